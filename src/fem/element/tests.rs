//! The elements against closed forms: rigid motions, patch tests, body
//! loads, equivalent and principal stresses.

use super::*;

#[test]
fn rigid_motions_have_zero_energy_and_stiffness_is_symmetric() {
    let p = [[0.0, 0.0], [2.0, 0.3], [0.4, 1.5]];
    let m = Material {
        e: 1e9,
        nu: 0.3,
        rho: 0.0,
    };
    let d = d_plane_strain(&m);
    let k = stiffness(&p, &d, 1.0);
    for i in 0..6 {
        for j in 0..6 {
            assert!((k[i][j] - k[j][i]).abs() < 1e-6 * k[0][0].abs());
        }
    }
    // translations and the infinitesimal rotation (−y, x)
    let modes = [
        [1.0, 0.0, 1.0, 0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
        [-p[0][1], p[0][0], -p[1][1], p[1][0], -p[2][1], p[2][0]],
    ];
    for z in modes {
        for row in k.iter() {
            let f: f64 = row.iter().zip(&z).map(|(a, b)| a * b).sum();
            assert!(f.abs() < 1e-6 * k[0][0].abs(), "{f}");
        }
    }
}

#[test]
fn stiffness_rows_equal_stiffness_bit_for_bit() {
    let p = [[0.1, -0.2], [2.3, 0.35], [0.45, 1.7]];
    let m = Material {
        e: 3.1e10,
        nu: 0.27,
        rho: 0.0,
    };
    for d in [d_plane_strain(&m), d_plane_stress(&m)] {
        let k = stiffness(&p, &d, 0.7);
        for a in 0..3 {
            let r = stiffness_rows(&p, &d, 0.7, a);
            assert_eq!(r[0], k[2 * a]);
            assert_eq!(r[1], k[2 * a + 1]);
        }
    }
}

/// The axisymmetric element: symmetric, zero energy for the axial
/// translation only, and exact for the uniform state u_r = εr, u_z = 0
/// (σ_rr = σ_θθ = (a + b)ε, σ_zz = 2bε), also with vertices on the axis.
#[test]
fn axisymmetric_element_modes_and_uniform_expansion() {
    let m = Material {
        e: 2e11,
        nu: 0.3,
        rho: 0.0,
    };
    let d4 = d_axi(&m);
    for p in [
        [[0.0, 0.0], [1.0, 0.2], [0.0, 1.0]],
        [[1.0, 0.0], [2.0, 0.3], [1.2, 1.5]],
    ] {
        let k = axi_stiffness(&p, &d4);
        for i in 0..6 {
            for j in 0..6 {
                assert!((k[i][j] - k[j][i]).abs() < 1e-9 * k[1][1].abs());
            }
        }
        let axial = [0.0, 1.0, 0.0, 1.0, 0.0, 1.0];
        let radial = [1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        let f = |z: &[f64; 6]| -> f64 {
            k.iter()
                .map(|row| row.iter().zip(z).map(|(a, b)| a * b).sum::<f64>().abs())
                .fold(0.0, f64::max)
        };
        assert!(f(&axial) < 1e-6 * k[1][1]);
        assert!(f(&radial) > 1e-3 * k[0][0]);
        let eps = 1e-3;
        let u = [eps * p[0][0], 0.0, eps * p[1][0], 0.0, eps * p[2][0], 0.0];
        let kind = ElementKind::Axisymmetric;
        let s = kind.stress(&p, &kind.material(&m), &u);
        let want = (d4[0][0] + d4[0][1]) * eps;
        assert!((s[0] - want).abs() < 1e-9 * want, "{s:?}");
        assert!((s[3] - want).abs() < 1e-9 * want, "{s:?}");
        assert!((s[1] - 2.0 * d4[0][1] * eps).abs() < 1e-9 * want);
        assert!(s[2].abs() < 1e-9 * want);
    }
}

/// The exact load integrals: Σ_a ∫N_a r = ∫r = |T| r̄ and
/// Σ_a ∫N_a r² = ∫r² = |T|/6 (Σr_i² + Σ_{i<j} r_i r_j)·… checked on
/// a unit right triangle by a fine midpoint sum.
#[test]
fn axisymmetric_body_load_integrals() {
    let p = [[0.5, 0.0], [1.5, 0.0], [0.5, 1.0]];
    let (mut s1, mut s2) = (0.0, 0.0);
    for a in 0..3 {
        let f = axi_body_load(&p, a, [0.0, 1.0], 1.0);
        s1 += f[1];
        s2 += f[0];
    }
    let n = 400;
    let (mut q1, mut q2) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n - i {
            let x = 0.5 + (i as f64 + 1.0 / 3.0) / n as f64;
            let w = 0.5 / (n * n) as f64;
            q1 += x * w;
            q2 += x * x * w;
            if j + i + 1 < n {
                let x2 = 0.5 + (i as f64 + 2.0 / 3.0) / n as f64;
                q1 += x2 * w;
                q2 += x2 * x2 * w;
            }
        }
    }
    assert!((s1 - q1).abs() < 1e-3 * q1, "{s1} {q1}");
    assert!((s2 - q2).abs() < 1e-3 * q2, "{s2} {q2}");
    assert!((s1 - 0.5 * centroid_r(&p)).abs() < 1e-14);
}

#[test]
fn uniaxial_stress_state() {
    // u = (εx, 0): plane stress σxx = E/(1−ν²) ε, σyy = ν σxx
    let p = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let m = Material {
        e: 200.0,
        nu: 0.25,
        rho: 0.0,
    };
    let kind = ElementKind::PlaneStress { thickness: 1.0 };
    let eps = 1e-3;
    let u = [0.0, 0.0, eps, 0.0, 0.0, 0.0];
    let s = kind.stress(&p, &kind.material(&m), &u);
    let sxx = 200.0 / (1.0 - 0.0625) * eps;
    assert!((s[0] - sxx).abs() < 1e-12);
    assert!((s[1] - 0.25 * sxx).abs() < 1e-12);
    assert_eq!(s[3], 0.0);
    let pr = principal(&s);
    assert!((pr[0] - sxx).abs() < 1e-12 && (pr[1] - 0.25 * sxx).abs() < 1e-12);
}

fn steel() -> Material {
    Material {
        e: 2.1e11,
        nu: 0.3,
        rho: 7800.0,
    }
}

/// An irregular tetrahedron, scaled by `s`.
fn tet(s: f64) -> [Point3; 4] {
    [
        [0.1, -0.2, 0.05],
        [1.3, 0.1, -0.1],
        [0.2, 0.9, 0.3],
        [0.4, 0.35, 1.1],
    ]
    .map(|x| x.map(|c| s * c))
}

/// The solid element: symmetric, and its kernel is exactly the six
/// rigid motions at every scale: six eigenvalues below 1e-12 of the
/// largest, the seventh above 1e-3 of it, and K z = 0 for each motion.
#[test]
fn solid_stiffness_kernel_is_the_six_rigid_motions() {
    let kind = ElementKind::Solid;
    let d = kind.material(&steel());
    for s in [1e-3, 1.0, 1e3] {
        let p = tet(s);
        let k = kind.tet_stiffness(&p, &d);
        let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..12 {
            for j in 0..12 {
                assert!((k[i][j] - k[j][i]).abs() <= 1e-13 * kmax);
            }
        }
        let rows: Vec<Vec<f64>> = k.iter().map(|r| r.to_vec()).collect();
        let (vals, _) = crate::linalg::dense::sym_eigen(&rows);
        let mut ev: Vec<f64> = vals.iter().map(|v| v.abs()).collect();
        ev.sort_by(|a, b| a.total_cmp(b));
        let top = ev[11];
        assert!(ev[5] < 1e-12 * top, "{ev:?}");
        assert!(ev[6] > 1e-3 * top, "{ev:?}");
        let c = p[0];
        for m in kind.rigid_modes() {
            let z: Vec<f64> = p.iter().flat_map(|&x| m.at(x, c, s)).collect();
            let kz = k
                .iter()
                .map(|r| r.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>().abs())
                .fold(0.0, f64::max);
            assert!(kz < 1e-12 * top, "{m:?}: {kz}");
        }
    }
    assert_eq!(kind.n_rigid_modes(), 6);
}

/// The unit cube cut into 12 tetrahedra about an off-centre interior
/// node (node 8): corners 0..8, each face two triangles.
fn cube_patch() -> (Vec<Point3>, Vec<[usize; 4]>) {
    let mut x: Vec<Point3> = (0..8)
        .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
        .collect();
    x.push([0.37, 0.58, 0.44]);
    let faces = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    let mut tets = vec![];
    for f in faces {
        for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            let mut c = [t[0], t[1], t[2], 8];
            if crate::mesh::gmsh::volume6(&c.map(|v| x[v])) < 0.0 {
                c.swap(1, 2);
            }
            tets.push(c);
        }
    }
    (x, tets)
}

/// Patch test: a linear displacement u = G x + t on an irregular tet
/// patch gives each element the exact stress D ε(G), and the interior
/// node is in equilibrium without load (K u = 0 in its rows).
#[test]
fn solid_patch_test_linear_field_is_exact() {
    let kind = ElementKind::Solid;
    let m = steel();
    let d = kind.material(&m);
    let (x, tets) = cube_patch();
    let g = [
        [1e-3, 2e-4, -3e-4],
        [5e-4, -7e-4, 1e-4],
        [-2e-4, 3e-4, 4e-4],
    ];
    let u: Vec<Vector3> = x
        .iter()
        .map(|p| [0, 1, 2].map(|i| (0..3).map(|j| g[i][j] * p[j]).sum::<f64>() + 0.01 * i as f64))
        .collect();
    let eps = [
        g[0][0],
        g[1][1],
        g[2][2],
        g[0][1] + g[1][0],
        g[1][2] + g[2][1],
        g[0][2] + g[2][0],
    ];
    let d6 = d_solid(&m);
    let want: Vec<f64> = (0..6)
        .map(|i| (0..6).map(|k| d6[i][k] * eps[k]).sum())
        .collect();
    let smax = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut r = [0.0; 3];
    let mut kmax = 0.0f64;
    for t in &tets {
        let p = t.map(|v| x[v]);
        let ue: [f64; 12] = std::array::from_fn(|i| u[t[i / 3]][i % 3]);
        let s = kind.tet_stress(&p, &d, &ue);
        for i in 0..6 {
            assert!((s[i] - want[i]).abs() < 1e-12 * smax, "{s:?} {want:?}");
        }
        let k = kind.tet_stiffness(&p, &d);
        kmax = k.iter().flatten().fold(kmax, |a, v| a.max(v.abs()));
        let a = t.iter().position(|&v| v == 8).unwrap();
        for (c, rc) in r.iter_mut().enumerate() {
            *rc += (0..12).map(|j| k[3 * a + c][j] * ue[j]).sum::<f64>();
        }
    }
    let umax = u.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    for rc in r {
        assert!(rc.abs() < 1e-12 * kmax * umax, "{r:?}");
    }
}

/// Σ over the vertices of |T|/4 ρg is ρg·V; |F|/3 sums to |F| and the
/// facet normal is the right-handed unit one.
#[test]
fn solid_body_load_and_facet_measure() {
    let kind = ElementKind::Solid;
    let (x, tets) = cube_patch();
    let fb = [1.0, -2.0, 9.81];
    let mut tot = [0.0; 3];
    for t in &tets {
        let f = kind.tet_body_load(&t.map(|v| x[v]), fb);
        for c in 0..3 {
            tot[c] += 4.0 * f[c];
        }
    }
    for c in 0..3 {
        assert!((tot[c] - fb[c]).abs() < 1e-14 * 10.0, "{tot:?}");
    }
    let (w, n) = kind.facet_weight(&[[0.0, 0.0, 2.0], [3.0, 0.0, 2.0], [0.0, 4.0, 2.0]]);
    assert!((3.0 * w - 6.0).abs() < 1e-14);
    assert_eq!(n, [0.0, 0.0, 1.0]);
}

/// von Mises: σ for uniaxial σ, √3 τ for any pure shear; principal
/// stresses of R diag(3, −1, 2) Rᵀ are (3, 2, −1).
#[test]
fn solid_equivalent_and_principal_stresses() {
    assert!((von_mises_solid(&[5.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 5.0).abs() < 1e-14);
    for k in 3..6 {
        let mut s = [0.0; 6];
        s[k] = 2.0;
        assert!((von_mises_solid(&s) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
    }
    let (c, sn) = (0.3f64.cos(), 0.3f64.sin());
    let (c2, s2) = (1.1f64.cos(), 1.1f64.sin());
    let rz = [[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]];
    let rx = [[1.0, 0.0, 0.0], [0.0, c2, -s2], [0.0, s2, c2]];
    let r: Vec<[f64; 3]> = (0..3)
        .map(|i| [0, 1, 2].map(|j| (0..3).map(|k| rz[i][k] * rx[k][j]).sum()))
        .collect();
    let l = [3.0, -1.0, 2.0];
    let t = |i: usize, j: usize| (0..3).map(|k| r[i][k] * l[k] * r[j][k]).sum::<f64>();
    let s = [t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(1, 2), t(0, 2)];
    let p = principal_solid(&s);
    for (a, b) in p.iter().zip([3.0, 2.0, -1.0]) {
        assert!((a - b).abs() < 1e-12, "{p:?}");
    }
    assert_eq!(principal_solid(&[1.0, 1.0, 1.0, 0.0, 0.0, 0.0]), [1.0; 3]);
}
