//! The P1 element of docs/methods.md §1.4 and §2.2: material matrix D, strain
//! matrix B, element stiffness C_e = t_h|T| BᵀDB, stresses τ̄ = D B x_e.

use crate::problem::{Material, Plane};

/// D for ē = (e11, e22, 2e12) (methods.md §1.4).
pub fn d_matrix(m: &Material, plane: Plane) -> [[f64; 3]; 3] {
    let (e, nu) = (m.e, m.nu);
    match plane {
        // The in-plane block of the axisymmetric D4 is that of plane strain.
        Plane::Strain | Plane::Axisymmetric => {
            let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            [
                [f * (1.0 - nu), f * nu, 0.0],
                [f * nu, f * (1.0 - nu), 0.0],
                [0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
            ]
        }
        Plane::Stress => {
            let f = e / (1.0 - nu * nu);
            [
                [f, f * nu, 0.0],
                [f * nu, f, 0.0],
                [0.0, 0.0, f * (1.0 - nu) / 2.0],
            ]
        }
    }
}

/// Twice the signed area: positive for counter-clockwise vertices.
pub fn area2(p: &[[f64; 2]; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
}

/// B (3×6) of §2.2 for counter-clockwise vertices, and |T|.
pub fn b_matrix(p: &[[f64; 2]; 3]) -> ([[f64; 6]; 3], f64) {
    let a2 = area2(p);
    let b = [p[1][1] - p[2][1], p[2][1] - p[0][1], p[0][1] - p[1][1]];
    let c = [p[2][0] - p[1][0], p[0][0] - p[2][0], p[1][0] - p[0][0]];
    let mut bm = [[0.0; 6]; 3];
    for a in 0..3 {
        bm[0][2 * a] = b[a] / a2;
        bm[1][2 * a + 1] = c[a] / a2;
        bm[2][2 * a] = c[a] / a2;
        bm[2][2 * a + 1] = b[a] / a2;
    }
    (bm, a2 / 2.0)
}

/// D B (3×6).
#[inline]
fn d_times_b(d: &[[f64; 3]; 3], b: &[[f64; 6]; 3]) -> [[f64; 6]; 3] {
    let mut db = [[0.0; 6]; 3];
    for i in 0..3 {
        for j in 0..6 {
            db[i][j] = (0..3).map(|k| d[i][k] * b[k][j]).sum();
        }
    }
    db
}

/// Entry (i, j) of C_e from B, |T| and D B: the one expression that both
/// [`stiffness`] and [`stiffness_rows`] use, so that they agree bit for bit.
#[inline]
fn ke_entry(b: &[[f64; 6]; 3], db: &[[f64; 6]; 3], th: f64, area: f64, i: usize, j: usize) -> f64 {
    th * area * (0..3).map(|l| b[l][i] * db[l][j]).sum::<f64>()
}

/// C_e = t_h |T| BᵀDB (6×6).
pub fn stiffness(p: &[[f64; 2]; 3], d: &[[f64; 3]; 3], th: f64) -> [[f64; 6]; 6] {
    let (b, area) = b_matrix(p);
    let db = d_times_b(d, &b);
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ke_entry(&b, &db, th, area, i, j);
        }
    }
    k
}

/// Rows 2a and 2a+1 of C_e (the two rows of vertex `a`), bit for bit equal
/// to those of [`stiffness`].
#[inline]
pub fn stiffness_rows(p: &[[f64; 2]; 3], d: &[[f64; 3]; 3], th: f64, a: usize) -> [[f64; 6]; 2] {
    let (b, area) = b_matrix(p);
    let db = d_times_b(d, &b);
    let mut k = [[0.0; 6]; 2];
    for (r, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ke_entry(&b, &db, th, area, 2 * a + r, j);
        }
    }
    k
}

/// Stresses (σxx, σyy, σxy, σzz) from the element displacements.
pub fn stress(
    p: &[[f64; 2]; 3],
    d: &[[f64; 3]; 3],
    m: &Material,
    plane: Plane,
    u: &[f64; 6],
) -> [f64; 4] {
    let (b, _) = b_matrix(p);
    let mut e = [0.0; 3];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..6).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 3];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..3).map(|k| d[i][k] * e[k]).sum();
    }
    let szz = match plane {
        Plane::Strain => m.nu * (s[0] + s[1]),
        Plane::Stress => 0.0,
        Plane::Axisymmetric => return axi_stress(p, m, u),
    };
    [s[0], s[1], s[2], szz]
}

/// D4 of an axisymmetric body for ε = (ε_rr, ε_zz, 2ε_rz, ε_θθ)
/// (docs/methods.md §10; Zienkiewicz & Taylor, The Finite Element Method,
/// vol. 1, ch. "Axisymmetric stress analysis").
pub fn d_axi(m: &Material) -> [[f64; 4]; 4] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let (a, b, g) = (f * (1.0 - nu), f * nu, f * (1.0 - 2.0 * nu) / 2.0);
    [
        [a, b, 0.0, b],
        [b, a, 0.0, b],
        [0.0, 0.0, g, 0.0],
        [b, b, 0.0, a],
    ]
}

/// The centroid radius r̄ = (r₁ + r₂ + r₃)/3 of a triangle (x = r).
pub fn centroid_r(p: &[[f64; 2]; 3]) -> f64 {
    (p[0][0] + p[1][0] + p[2][0]) / 3.0
}

/// B4 (4×6) of the axisymmetric P1 triangle with the hoop row evaluated
/// at the centroid, N_a(r̄)/r̄ = 1/(3r̄): the one-point rule for the hoop
/// terms, finite whenever the triangle has area (r̄ > 0 even with two
/// vertices on the axis), with |T|, r̄. Zienkiewicz & Taylor (vol. 1,
/// "Axisymmetric stress analysis") give this centroid approximation; the
/// in-plane rows are constant, so r̄|T| BᵀD4B is the one-point rule of
/// ∫ BᵀD4B r dA (docs/methods.md §10).
pub fn axi_b(p: &[[f64; 2]; 3]) -> ([[f64; 6]; 4], f64, f64) {
    let (b3, area) = b_matrix(p);
    let rbar = centroid_r(p);
    let mut b = [[0.0; 6]; 4];
    b[..3].copy_from_slice(&b3);
    for a in 0..3 {
        b[3][2 * a] = 1.0 / (3.0 * rbar);
    }
    (b, area, rbar)
}

/// C_e = r̄ |T| B4ᵀ D4 B4 (6×6, per radian) of the axisymmetric triangle.
pub fn axi_stiffness(p: &[[f64; 2]; 3], d4: &[[f64; 4]; 4]) -> [[f64; 6]; 6] {
    let (b, area, rbar) = axi_b(p);
    let mut db = [[0.0; 6]; 4];
    for i in 0..4 {
        for j in 0..6 {
            db[i][j] = (0..4).map(|k| d4[i][k] * b[k][j]).sum();
        }
    }
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = rbar * area * (0..4).map(|l| b[l][i] * db[l][j]).sum::<f64>();
        }
    }
    k
}

/// The element stiffness of any `plane` (per radian when axisymmetric).
pub fn stiffness_in(
    p: &[[f64; 2]; 3],
    m: &Material,
    d: &[[f64; 3]; 3],
    plane: Plane,
    th: f64,
) -> [[f64; 6]; 6] {
    match plane {
        Plane::Axisymmetric => axi_stiffness(p, &d_axi(m)),
        _ => stiffness(p, d, th),
    }
}

/// ∫ N_a (f_b r + c r² e_r) dA over an axisymmetric triangle, exactly
/// (∫ λ₁^i λ₂^j λ₃^k dA = 2|T| i! j! k! / (i + j + k + 2)!): the nodal force
/// per radian of vertex `a` from a body force f_b (gravity, along z) and a
/// centrifugal load c r along r (c = ρω²).
pub fn axi_body_load(p: &[[f64; 2]; 3], a: usize, fb: [f64; 2], c: f64) -> [f64; 2] {
    let area = area2(p) / 2.0;
    let r = [p[0][0], p[1][0], p[2][0]];
    let w1 = area / 12.0 * (r[a] + r[0] + r[1] + r[2]);
    let fact = [1.0, 1.0, 2.0, 6.0];
    let mut w2 = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let mut k = [0usize; 3];
            k[a] += 1;
            k[i] += 1;
            k[j] += 1;
            w2 += r[i] * r[j] * 2.0 * area * fact[k[0]] * fact[k[1]] * fact[k[2]] / 120.0;
        }
    }
    [w1 * fb[0] + c * w2, w1 * fb[1]]
}

/// (σ_rr, σ_zz, σ_rz, σ_θθ) at the centroid of an axisymmetric triangle.
fn axi_stress(p: &[[f64; 2]; 3], m: &Material, u: &[f64; 6]) -> [f64; 4] {
    let (b, _, _) = axi_b(p);
    let d4 = d_axi(m);
    let mut e = [0.0; 4];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..6).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 4];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..4).map(|k| d4[i][k] * e[k]).sum();
    }
    s
}

/// von Mises from the four components (σ_rr, σ_zz, σ_rz, σ_θθ) of an
/// axisymmetric stress: sqrt(½[(σ1−σ2)² + (σ2−σ3)² + (σ3−σ1)²] + 3τ²).
pub fn von_mises_axi(s: &[f64; 4]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[3], s[3] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * s[2] * s[2])
        .max(0.0)
        .sqrt()
}

/// The report's equivalent stress τe = sqrt(σxx² + σyy² − σxxσyy + 3σxy²) (§1.4).
pub fn von_mises(s: &[f64; 4]) -> f64 {
    (s[0] * s[0] + s[1] * s[1] - s[0] * s[1] + 3.0 * s[2] * s[2])
        .max(0.0)
        .sqrt()
}

/// In-plane principal stresses, σ1 ≥ σ2.
pub fn principal(s: &[f64; 4]) -> [f64; 2] {
    let c = 0.5 * (s[0] + s[1]);
    let r = (0.25 * (s[0] - s[1]).powi(2) + s[2] * s[2]).sqrt();
    [c + r, c - r]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_motions_have_zero_energy_and_stiffness_is_symmetric() {
        let p = [[0.0, 0.0], [2.0, 0.3], [0.4, 1.5]];
        let m = Material {
            e: 1e9,
            nu: 0.3,
            rho: 0.0,
        };
        let d = d_matrix(&m, Plane::Strain);
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
        for plane in [Plane::Strain, Plane::Stress] {
            let d = d_matrix(&m, plane);
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
            let s = stress(
                &p,
                &d_matrix(&m, Plane::Axisymmetric),
                &m,
                Plane::Axisymmetric,
                &u,
            );
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
        let d = d_matrix(&m, Plane::Stress);
        let eps = 1e-3;
        let u = [0.0, 0.0, eps, 0.0, 0.0, 0.0];
        let s = stress(&p, &d, &m, Plane::Stress, &u);
        let sxx = 200.0 / (1.0 - 0.0625) * eps;
        assert!((s[0] - sxx).abs() < 1e-12);
        assert!((s[1] - 0.25 * sxx).abs() < 1e-12);
        assert_eq!(s[3], 0.0);
        let pr = principal(&s);
        assert!((pr[0] - sxx).abs() < 1e-12 && (pr[1] - 0.25 * sxx).abs() < 1e-12);
    }
}
