//! Tests of the hierarchy and its PCG through their public interface.

use super::*;
use crate::linalg::sparse::{dot, norm};

fn identity(r: &[f64], z: &mut [f64]) {
    z.copy_from_slice(r);
}

/// 5-point Laplacian on an m × m interior grid (Dirichlet boundary).
fn laplacian(m: usize) -> Csr {
    let id = |i: usize, j: usize| j * m + i;
    let mut t = Vec::new();
    for j in 0..m {
        for i in 0..m {
            let r = id(i, j);
            t.push((r, r, 4.0));
            if i > 0 {
                t.push((r, id(i - 1, j), -1.0));
            }
            if i + 1 < m {
                t.push((r, id(i + 1, j), -1.0));
            }
            if j > 0 {
                t.push((r, id(i, j - 1), -1.0));
            }
            if j + 1 < m {
                t.push((r, id(i, j + 1), -1.0));
            }
        }
    }
    Csr::from_triplets(m * m, m * m, &t)
}

/// Plane-strain P1 elasticity on the unit square (nx × ny squares, two
/// triangles each), left edge clamped, ν = 0.3, Young's modulus
/// `young(x, y)` at the element centroid. Returns K, the per-node block
/// pointers and the 3 rigid motions on the free DOFs.
fn elasticity(
    nx: usize,
    ny: usize,
    young: impl Fn(f64, f64) -> f64,
) -> (Csr, Vec<usize>, Vec<Vec<f64>>) {
    let nu = 0.3;
    let node = |i: usize, j: usize| j * (nx + 1) + i;
    let xy = |v: usize| {
        let (i, j) = (v % (nx + 1), v / (nx + 1));
        (i as f64 / nx as f64, j as f64 / ny as f64)
    };
    // Free nodes (i > 0) numbered in node order, 2 DOFs each.
    let nn = (nx + 1) * (ny + 1);
    let mut dof = vec![NONE; nn];
    let mut nfree = 0;
    for v in 0..nn {
        if v % (nx + 1) > 0 {
            dof[v] = 2 * nfree;
            nfree += 1;
        }
    }
    let mut trip = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            for tri in [[a, b, c], [a, c, d]] {
                let p: Vec<(f64, f64)> = tri.iter().map(|&v| xy(v)).collect();
                let area2 =
                    (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
                let area = 0.5 * area2;
                let bb = [p[1].1 - p[2].1, p[2].1 - p[0].1, p[0].1 - p[1].1];
                let cc = [p[2].0 - p[1].0, p[0].0 - p[2].0, p[1].0 - p[0].0];
                let (cx, cy) = (
                    (p[0].0 + p[1].0 + p[2].0) / 3.0,
                    (p[0].1 + p[1].1 + p[2].1) / 3.0,
                );
                let e = young(cx, cy);
                let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
                let mu = e / (2.0 * (1.0 + nu));
                let dm = [
                    [lam + 2.0 * mu, lam, 0.0],
                    [lam, lam + 2.0 * mu, 0.0],
                    [0.0, 0.0, mu],
                ];
                let mut bm = [[0.0; 6]; 3];
                for k in 0..3 {
                    bm[0][2 * k] = bb[k] / area2;
                    bm[1][2 * k + 1] = cc[k] / area2;
                    bm[2][2 * k] = cc[k] / area2;
                    bm[2][2 * k + 1] = bb[k] / area2;
                }
                for r in 0..6 {
                    for s in 0..6 {
                        let mut v = 0.0;
                        for u in 0..3 {
                            for w in 0..3 {
                                v += bm[u][r] * dm[u][w] * bm[w][s];
                            }
                        }
                        let (gr, gs) = (dof[tri[r / 2]], dof[tri[s / 2]]);
                        if gr != NONE && gs != NONE {
                            trip.push((gr + r % 2, gs + s % 2, area * v));
                        }
                    }
                }
            }
        }
    }
    let n = 2 * nfree;
    let k = Csr::from_triplets(n, n, &trip);
    let bp: Vec<usize> = (0..=nfree).map(|v| 2 * v).collect();
    let mut modes = vec![vec![0.0; n]; 3];
    for v in 0..nn {
        if dof[v] != NONE {
            let (x, y) = xy(v);
            let d = dof[v];
            modes[0][d] = 1.0;
            modes[1][d + 1] = 1.0;
            modes[2][d] = -y;
            modes[2][d + 1] = x;
        }
    }
    (k, bp, modes)
}

/// A load that is neither smooth nor aligned with the grid.
fn rhs(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.3)
        .collect()
}

fn solve_amg(k: &Csr, near: Option<NearNull<'_>>, max_iter: usize) -> (PcgReport, Vec<f64>, Amg) {
    let amg = Amg::new(k, near, &AmgSettings::default()).expect("hierarchy");
    let b = rhs(k.nrows);
    let mut x = vec![0.0; k.nrows];
    let rep = pcg(k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, max_iter);
    (rep, x, amg)
}

#[test]
fn amg_laplacian_beats_cg() {
    let k = laplacian(100);
    let (rep, _, amg) = solve_amg(&k, None, 500);
    let b = rhs(k.nrows);
    let mut x = vec![0.0; k.nrows];
    let plain = pcg(&k, &b, &mut x, &identity, 1e-10, 10_000);
    eprintln!(
        "laplacian 100²: amg {} its (levels {:?}, oc {:.2}), cg {} its",
        rep.iterations,
        amg.sizes(),
        amg.operator_complexity(),
        plain.iterations
    );
    assert!(rep.converged && rep.iterations <= 30, "{rep:?}");
    assert!(plain.converged, "{plain:?}");
    assert!(plain.iterations >= 3 * rep.iterations, "{plain:?} {rep:?}");
}

#[test]
fn amg_elasticity_mesh_independent() {
    let mut its = Vec::new();
    for m in [64, 128] {
        let (k, bp, modes) = elasticity(m, m, |_, _| 1.0);
        let amg = Amg::new(
            &k,
            Some(NearNull {
                block_ptr: &bp,
                modes: &modes,
            }),
            &AmgSettings::default(),
        )
        .expect("hierarchy");
        let b = rhs(k.nrows);
        let mut x = vec![0.0; k.nrows];
        let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 500);
        let mut x0 = vec![0.0; k.nrows];
        let plain = pcg(&k, &b, &mut x0, &identity, 1e-10, 100_000);
        let (scalar, _, samg) = solve_amg(&k, None, 2000);
        eprintln!(
            "elasticity {m}²: n {} amg {} its (levels {:?}, oc {:.2}), \
             scalar amg {} its (levels {:?}), cg {} its",
            k.nrows,
            rep.iterations,
            amg.sizes(),
            amg.operator_complexity(),
            scalar.iterations,
            samg.sizes(),
            plain.iterations
        );
        assert!(rep.converged, "{rep:?}");
        assert!(scalar.converged, "{scalar:?}");
        assert!(plain.converged, "{plain:?}");
        assert!(plain.iterations >= 5 * rep.iterations, "{plain:?} {rep:?}");
        its.push(rep.iterations);
    }
    assert!(
        its[1] as f64 <= 1.5 * its[0] as f64 + 5.0,
        "iterations grow: {its:?}"
    );
}

/// 1 : 1e6 halves. The load is b = K x★ for a rough x★: with a nodal load
/// of O(1) the displacement of the soft half is so large that
/// ε‖K‖‖x‖/‖b‖ ≈ 1e-6, and no solver can get ‖b − Kx‖/‖b‖ below that in
/// double precision; b = K x★ keeps the attainable residual at rounding.
#[test]
fn amg_stiffness_contrast() {
    let (k, bp, modes) = elasticity(64, 64, |x, _| if x < 0.5 { 1.0 } else { 1e6 });
    let near = NearNull {
        block_ptr: &bp,
        modes: &modes,
    };
    let amg = Amg::new(&k, Some(near), &AmgSettings::default()).expect("hierarchy");
    let xs = rhs(k.nrows);
    let b = k.mul(&xs);
    let mut x = vec![0.0; k.nrows];
    let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 500);
    let err: Vec<f64> = x.iter().zip(&xs).map(|(a, b)| a - b).collect();
    let rel_err = norm(&err) / norm(&xs);
    eprintln!(
        "contrast 1:1e6 64²: {} its, relative error {rel_err:.1e}",
        rep.iterations
    );
    assert!(rep.converged && rep.iterations <= 60, "{rep:?}");
    assert!(rel_err < 1e-4, "{rel_err}");
}

#[test]
fn amg_deterministic() {
    let (k, bp, modes) = elasticity(40, 30, |_, _| 1.0);
    let run = || {
        let near = NearNull {
            block_ptr: &bp,
            modes: &modes,
        };
        solve_amg(&k, Some(near), 500).1
    };
    let (x1, x2) = (run(), run());
    assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn amg_vcycle_symmetric() {
    let (k, bp, modes) = elasticity(48, 48, |_, _| 1.0);
    let s = AmgSettings {
        coarse_max: 200,
        smooth_sweeps: 2,
        ..AmgSettings::default()
    };
    let near = NearNull {
        block_ptr: &bp,
        modes: &modes,
    };
    let amg = Amg::new(&k, Some(near), &s).expect("hierarchy");
    assert!(amg.levels() >= 3, "{:?}", amg.sizes());
    let n = k.nrows;
    let u: Vec<f64> = (0..n).map(|i| ((i * 31 + 7) % 101) as f64 - 50.0).collect();
    let v: Vec<f64> = (0..n).map(|i| ((i * 17 + 3) % 89) as f64 - 44.0).collect();
    let (mut mu, mut mv) = (vec![0.0; n], vec![0.0; n]);
    amg.apply(&u, &mut mu);
    amg.apply(&v, &mut mv);
    let (umv, vmu) = (dot(&u, &mv), dot(&v, &mu));
    assert!((umv - vmu).abs() <= 1e-10 * umv.abs(), "{umv} {vmu}");
    // Positive definite on these vectors, too.
    assert!(dot(&u, &mu) > 0.0 && dot(&v, &mv) > 0.0);
}

#[test]
fn amg_small_matrix_is_exact_and_bad_input_refused() {
    let k = laplacian(10);
    let amg = Amg::new(&k, None, &AmgSettings::default()).expect("dense");
    assert_eq!(amg.levels(), 1);
    let b = rhs(k.nrows);
    let mut x = vec![0.0; k.nrows];
    let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-12, 5);
    assert!(rep.converged && rep.iterations <= 2, "{rep:?}");
    let bad = NearNull {
        block_ptr: &[0, 3],
        modes: &[],
    };
    assert!(matches!(
        Amg::new(&k, Some(bad), &AmgSettings::default()),
        Err(AmgError::BadInput(_))
    ));
    // A singular matrix (zero Neumann Laplacian row sums) is refused at
    // the coarse factor.
    let sing = Csr::from_triplets(
        2,
        2,
        &[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)],
    );
    assert!(matches!(
        Amg::new(&sing, None, &AmgSettings::default()),
        Err(AmgError::CoarseSingular { n: 2 })
    ));
}

/// Empty blocks (mesh points without free unknowns) are skipped, and
/// the hierarchy may be shared between threads.
#[test]
fn amg_empty_blocks_and_sync() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Amg>();
    let k = laplacian(60);
    let n = k.nrows;
    // Blocks of one unknown with an empty block after every 7th.
    let mut bp = vec![0];
    for i in 1..=n {
        bp.push(i);
        if i % 7 == 0 {
            bp.push(i);
        }
    }
    let ones = vec![vec![1.0; n]];
    let near = NearNull {
        block_ptr: &bp,
        modes: &ones,
    };
    let (rep, _, amg) = solve_amg(&k, Some(near), 100);
    assert!(
        amg.levels() >= 2 && rep.converged && rep.iterations <= 30,
        "{rep:?}"
    );
}

/// The parallel residual, transfers, K·p and reductions give the same
/// bits on any number of threads (n above the parallel threshold).
#[test]
fn amg_pcg_thread_count_independent() {
    let (k, bp, modes) = elasticity(200, 200, |_, _| 1.0);
    assert!(k.nrows > 2 * PAR_MIN);
    let solve = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let near = NearNull {
                block_ptr: &bp,
                modes: &modes,
            };
            solve_amg(&k, Some(near), 500)
        })
    };
    let (r1, x1, _) = solve(1);
    let (r2, x2, _) = solve(2);
    assert!(
        r1.converged && r1.iterations == r2.iterations,
        "{r1:?} {r2:?}"
    );
    assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
}

/// P1 elasticity on the unit cube (m³ cubes, six Kuhn tetrahedra each),
/// the face x = 0 clamped, E = 1, ν = 0.3, `young(x, y, z)` scaling E at
/// the tetrahedron's centroid. Returns K, the per-node block pointers and
/// the six rigid motions on the free DOFs.
fn elasticity3d(m: usize, young: impl Fn([f64; 3]) -> f64) -> (Csr, Vec<usize>, Vec<Vec<f64>>) {
    let nu = 0.3;
    let np = m + 1;
    let node = |i: usize, j: usize, k: usize| (k * np + j) * np + i;
    let xyz = |v: usize| {
        let (i, j, k) = (v % np, (v / np) % np, v / (np * np));
        [i, j, k].map(|t| t as f64 / m as f64)
    };
    let nn = np * np * np;
    let mut dof = vec![NONE; nn];
    let mut nfree = 0;
    for (v, d) in dof.iter_mut().enumerate() {
        if v % np > 0 {
            *d = 3 * nfree;
            nfree += 1;
        }
    }
    let lam = nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = 1.0 / (2.0 * (1.0 + nu));
    let mut dmat = [[0.0f64; 6]; 6];
    for a in 0..3 {
        for b in 0..3 {
            dmat[a][b] = lam + if a == b { 2.0 * mu } else { 0.0 };
        }
        dmat[a + 3][a + 3] = mu;
    }
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut trip = Vec::new();
    for k in 0..m {
        for j in 0..m {
            for i in 0..m {
                for p in perms {
                    let mut c = [i, j, k];
                    let mut tet = [node(i, j, k); 4];
                    for (s, &ax) in p.iter().enumerate() {
                        c[ax] += 1;
                        tet[s + 1] = node(c[0], c[1], c[2]);
                    }
                    let x: Vec<[f64; 3]> = tet.iter().map(|&v| xyz(v)).collect();
                    // Jacobian columns x_s − x_0; gradients of λ_1..λ_3 are the rows of J⁻¹.
                    let jm: [[f64; 3]; 3] =
                        std::array::from_fn(|r| std::array::from_fn(|s| x[s + 1][r] - x[0][r]));
                    let det = jm[0][0] * (jm[1][1] * jm[2][2] - jm[1][2] * jm[2][1])
                        - jm[0][1] * (jm[1][0] * jm[2][2] - jm[1][2] * jm[2][0])
                        + jm[0][2] * (jm[1][0] * jm[2][1] - jm[1][1] * jm[2][0]);
                    let cof = |r: usize, s: usize| {
                        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
                        let (s1, s2) = ((s + 1) % 3, (s + 2) % 3);
                        jm[r1][s1] * jm[r2][s2] - jm[r1][s2] * jm[r2][s1]
                    };
                    let mut g = [[0.0f64; 3]; 4];
                    for a in 0..3 {
                        for r in 0..3 {
                            g[a + 1][r] = cof(r, a) / det; // (J⁻¹)_{a r}
                        }
                    }
                    for r in 0..3 {
                        g[0][r] = -(g[1][r] + g[2][r] + g[3][r]);
                    }
                    let vol = det.abs() / 6.0;
                    let cen = [0, 1, 2].map(|r| x.iter().map(|p| p[r]).sum::<f64>() / 4.0);
                    let e = young(cen);
                    // B (6 × 12), strains xx, yy, zz, yz, xz, xy.
                    let mut bm = [[0.0f64; 12]; 6];
                    for a in 0..4 {
                        let [gx, gy, gz] = g[a];
                        bm[0][3 * a] = gx;
                        bm[1][3 * a + 1] = gy;
                        bm[2][3 * a + 2] = gz;
                        bm[3][3 * a + 1] = gz;
                        bm[3][3 * a + 2] = gy;
                        bm[4][3 * a] = gz;
                        bm[4][3 * a + 2] = gx;
                        bm[5][3 * a] = gy;
                        bm[5][3 * a + 1] = gx;
                    }
                    for r in 0..12 {
                        let dr = dof[tet[r / 3]];
                        if dr == NONE {
                            continue;
                        }
                        for s in 0..12 {
                            let ds = dof[tet[s / 3]];
                            if ds == NONE {
                                continue;
                            }
                            let mut v = 0.0;
                            for a in 0..6 {
                                for b in 0..6 {
                                    v += bm[a][r] * dmat[a][b] * bm[b][s];
                                }
                            }
                            trip.push((dr + r % 3, ds + s % 3, e * vol * v));
                        }
                    }
                }
            }
        }
    }
    let n = 3 * nfree;
    let k = Csr::from_triplets(n, n, &trip);
    let bp: Vec<usize> = (0..=nfree).map(|b| 3 * b).collect();
    let mut modes = vec![vec![0.0; n]; 6];
    for (v, &d) in dof.iter().enumerate() {
        if d == NONE {
            continue;
        }
        let [x, y, z] = xyz(v);
        let u = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -z, y],
            [z, 0.0, -x],
            [-y, x, 0.0],
        ];
        for (mode, ui) in modes.iter_mut().zip(u) {
            mode[d..d + 3].copy_from_slice(&ui);
        }
    }
    (k, bp, modes)
}

/// 3D elasticity with the six rigid motions (the settings of
/// `AmgSettings::for_modes(6)`, a small coarse level so that every size
/// has several levels): PCG converges, the hierarchy coarsens to the
/// dense level, and the iterations do not grow much over refinements.
#[test]
fn amg_elasticity3d_mesh_independent() {
    let mut its = Vec::new();
    for m in [6, 10, 16] {
        let (k, bp, modes) = elasticity3d(m, |_| 1.0);
        let s = AmgSettings {
            coarse_max: 200,
            ..AmgSettings::for_modes(6)
        };
        let near = NearNull {
            block_ptr: &bp,
            modes: &modes,
        };
        let amg = Amg::new(&k, Some(near), &s).expect("hierarchy");
        let b = rhs(k.nrows);
        let mut x = vec![0.0; k.nrows];
        let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 500);
        eprintln!(
            "elasticity3d {m}³: n {} amg {} its (levels {:?}, oc {:.2})",
            k.nrows,
            rep.iterations,
            amg.sizes(),
            amg.operator_complexity()
        );
        assert!(rep.converged, "{rep:?}");
        assert!(amg.levels() >= 2 && *amg.sizes().last().unwrap() <= 200);
        assert!(
            amg.operator_complexity() < 3.0,
            "{}",
            amg.operator_complexity()
        );
        its.push(rep.iterations);
    }
    assert!(
        its[2] as f64 <= 1.5 * its[0] as f64 + 5.0,
        "iterations grow: {its:?}"
    );
}

/// 3D with a 1 : 1e4 contrast between two halves of the cube (b = K x★ as
/// in `amg_stiffness_contrast`): the six-mode hierarchy still converges.
#[test]
fn amg_elasticity3d_contrast() {
    let (k, bp, modes) = elasticity3d(10, |p| if p[0] < 0.5 { 1.0 } else { 1e4 });
    let s = AmgSettings {
        coarse_max: 200,
        ..AmgSettings::for_modes(6)
    };
    let near = NearNull {
        block_ptr: &bp,
        modes: &modes,
    };
    let amg = Amg::new(&k, Some(near), &s).expect("hierarchy");
    let xs = rhs(k.nrows);
    let b = k.mul(&xs);
    let mut x = vec![0.0; k.nrows];
    let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 500);
    eprintln!("elasticity3d contrast: {rep:?}, levels {:?}", amg.sizes());
    assert!(rep.converged && rep.iterations <= 100, "{rep:?}");
}

/// `Amg::update` by a spring δ u uᵀ (u on two unknowns of one node, in
/// K's pattern): the updated hierarchy preconditions K + δ u uᵀ as well as
/// the first did K, and updating back by −δ gives the first cycle again.
#[test]
fn amg_update_follows_a_low_rank_change() {
    let (k, bp, modes) = elasticity3d(8, |_| 1.0);
    let s = AmgSettings {
        coarse_max: 100,
        ..AmgSettings::for_modes(6)
    };
    let near = || NearNull {
        block_ptr: &bp,
        modes: &modes,
    };
    let mut amg = Amg::new(&k, Some(near()), &s).expect("hierarchy");
    assert!(amg.levels() >= 3, "{:?}", amg.sizes());
    let b = rhs(k.nrows);
    let mut z0 = vec![0.0; k.nrows];
    amg.apply(&b, &mut z0);
    let (cols, vals) = ([0usize, 1], [1.0, -0.5]);
    let delta = 10.0 * k.diag()[0];
    let mut k2 = k.clone();
    let (c0, _) = k.row(0);
    let (c1, _) = k.row(1);
    let s0 = k.indptr[0];
    let s1 = k.indptr[1];
    for (a, &ca) in cols.iter().zip(&vals) {
        for (bcol, &cb) in cols.iter().zip(&vals) {
            let (row_cols, start) = if *a == 0 { (c0, s0) } else { (c1, s1) };
            let p = start + row_cols.binary_search(bcol).expect("in pattern");
            k2.data[p] += delta * ca * cb;
        }
    }
    amg.update(&k2, &[(delta, &cols, &vals)]).expect("update");
    let mut x = vec![0.0; k.nrows];
    let rep = pcg(&k2, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 200);
    assert!(rep.converged && rep.iterations <= 40, "{rep:?}");
    amg.update(&k, &[(-delta, &cols, &vals)])
        .expect("update back");
    let mut z1 = vec![0.0; k.nrows];
    amg.apply(&b, &mut z1);
    let diff: Vec<f64> = z0.iter().zip(&z1).map(|(a, b)| a - b).collect();
    assert!(
        norm(&diff) <= 1e-8 * norm(&z0),
        "{} {}",
        norm(&diff),
        norm(&z0)
    );
}

/// The coarse-space API of the coarse start (`coarse.rs`): on every level,
/// prolongation and restriction are transposes, the level's dense operator
/// is PᵀKP (K applied to prolonged unit vectors), and a sparse row
/// restricted is the dense restriction of that row.
#[test]
fn amg_level_spaces_are_galerkin() {
    let (k, bp, modes) = elasticity3d(6, |_| 1.0);
    let s = AmgSettings {
        coarse_max: 60,
        ..AmgSettings::for_modes(6)
    };
    let near = NearNull {
        block_ptr: &bp,
        modes: &modes,
    };
    let amg = Amg::new(&k, Some(near), &s).expect("hierarchy");
    let sizes = amg.sizes();
    assert!(sizes.len() >= 3, "{sizes:?}");
    let n = k.nrows;
    let r = rhs(n);
    for (l, &nl) in sizes.iter().enumerate().skip(1) {
        let dense = amg.level_dense(l);
        assert_eq!(dense.len(), nl * nl);
        let rc = amg.restrict_to_level(l, &r);
        let scale = dense.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // Column c of PᵀKP against the dense operator; (Pe_c)ᵀr = (Pᵀr)_c.
        for c in (0..nl).step_by((nl / 7).max(1)) {
            let mut e = vec![0.0; nl];
            e[c] = 1.0;
            let pe = amg.prolong_from_level(l, &e);
            assert!((dot(&pe, &r) - rc[c]).abs() <= 1e-12 * norm(&pe) * norm(&r));
            let kpe = k.mul(&pe);
            let col = amg.restrict_to_level(l, &kpe);
            for i in 0..nl {
                assert!(
                    (col[i] - dense[i * nl + c]).abs() <= 1e-10 * scale,
                    "level {l} entry ({i}, {c}): {} against {}",
                    col[i],
                    dense[i * nl + c]
                );
            }
        }
        // A sparse row (three unknowns of one point) restricted.
        let (cols, vals) = ([3usize, 4, 5], [0.3, -1.0, 0.7]);
        let mut u = vec![0.0; n];
        for (&c, &v) in cols.iter().zip(&vals) {
            u[c] = v;
        }
        let want = amg.restrict_to_level(l, &u);
        let got = amg.restrict_row_to_level(l, &cols, &vals);
        let mut full = vec![0.0; nl];
        for w in got.windows(2) {
            assert!(w[0].0 < w[1].0, "columns sorted");
        }
        for &(j, v) in &got {
            full[j] = v;
        }
        let d: Vec<f64> = full.iter().zip(&want).map(|(a, b)| a - b).collect();
        assert!(norm(&d) <= 1e-13 * norm(&want), "level {l}");
        assert!(norm(&want) > 0.0);
    }
}
