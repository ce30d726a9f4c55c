//! What the unit tests of every method share, so that no method's tests
//! import another's: a generator of two-body lattice problems
//! ([`two_blocks`]), the reference solution ([`reference`]: CGC with the
//! Cholesky preconditioner through the driver, certified), the comparison of
//! a result with it ([`compare`]) and a shipped example, assembled
//! ([`example`]). `tests_methods.rs` keeps its truss generator (its
//! V-shaped contact and weakly active rows are what its checks are about).

use crate::linalg::sparse::{norm, Csr};
use crate::qp::{kkt, registry, Output, QpProblem, QpResult, SolveOptions, Status};

/// Read access to a solution: a method's [`Output`] or the driver's
/// [`QpResult`] (tests compare both kinds).
pub(crate) trait Solution {
    fn x(&self) -> &[f64];
    fn lambda(&self) -> &[f64];
    fn active(&self) -> &[bool];
    fn status(&self) -> &Status;
}

impl Solution for Output {
    fn x(&self) -> &[f64] {
        &self.x
    }
    fn lambda(&self) -> &[f64] {
        &self.lambda
    }
    fn active(&self) -> &[bool] {
        &self.active
    }
    fn status(&self) -> &Status {
        &self.status
    }
}

impl Solution for QpResult {
    fn x(&self) -> &[f64] {
        &self.x
    }
    fn lambda(&self) -> &[f64] {
        &self.lambda
    }
    fn active(&self) -> &[bool] {
        &self.active
    }
    fn status(&self) -> &Status {
        &self.status
    }
}

/// Two square spring lattices (bars along the grid lines and both
/// diagonals, 2 DOFs per node), the lower one clamped at its bottom row,
/// stacked with a small vertical offset; node-to-node contact rows between
/// the lower block's top row and the upper block's bottom row
/// (n = (0, 1), the outward normal of the lower body). Gaps: 0 on the left
/// part of the interface, growing on the right.
///
/// * `floating = false`: the upper block is clamped at its top row; the load
///   pushes its left part down and pulls its right part up.
/// * `floating = true`: the upper block only has u_x = 0 on its left column,
///   so its vertical translation is held by contact alone (kernel vector
///   in `qp.kernel`); the load presses it down with an uplift at the right.
pub(crate) fn two_blocks(nx: usize, ny: usize, floating: bool) -> QpProblem {
    let nn = nx * ny;
    // global node p: block b ∈ {0 (lower), 1 (upper)}, (i, j)
    let node = |b: usize, i: usize, j: usize| b * nn + j * nx + i;
    let mut trip_full: Vec<(usize, usize, f64)> = vec![];
    let mut bar = |p: usize, q: usize, dir: [f64; 2], k: f64| {
        let l = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
        let e = [dir[0] / l, dir[1] / l];
        for a in 0..2 {
            for b in 0..2 {
                let v = k * e[a] * e[b];
                trip_full.push((2 * p + a, 2 * p + b, v));
                trip_full.push((2 * q + a, 2 * q + b, v));
                trip_full.push((2 * p + a, 2 * q + b, -v));
                trip_full.push((2 * q + a, 2 * p + b, -v));
            }
        }
    };
    for b in 0..2 {
        let kk = if b == 0 { 1.0 } else { 2.5 };
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx {
                    bar(node(b, i, j), node(b, i + 1, j), [1.0, 0.0], kk);
                }
                if j + 1 < ny {
                    bar(node(b, i, j), node(b, i, j + 1), [0.0, 1.0], kk);
                }
                if i + 1 < nx && j + 1 < ny {
                    bar(node(b, i, j), node(b, i + 1, j + 1), [1.0, 1.0], 0.5 * kk);
                    bar(node(b, i + 1, j), node(b, i, j + 1), [-1.0, 1.0], 0.5 * kk);
                }
            }
        }
    }
    // Fixed DOFs.
    let mut fixed = vec![false; 4 * nn];
    for i in 0..nx {
        fixed[2 * node(0, i, 0)] = true;
        fixed[2 * node(0, i, 0) + 1] = true;
        if !floating {
            fixed[2 * node(1, i, ny - 1)] = true;
            fixed[2 * node(1, i, ny - 1) + 1] = true;
        }
    }
    if floating {
        for j in 0..ny {
            fixed[2 * node(1, 0, j)] = true;
        }
    }
    let mut map = vec![usize::MAX; 4 * nn];
    let mut n = 0;
    for (dof, f) in fixed.iter().enumerate() {
        if !f {
            map[dof] = n;
            n += 1;
        }
    }
    let trip: Vec<(usize, usize, f64)> = trip_full
        .iter()
        .filter(|(i, j, _)| map[*i] != usize::MAX && map[*j] != usize::MAX)
        .map(|&(i, j, v)| (map[i], map[j], v))
        .collect();
    let c = Csr::from_triplets(n, n, &trip);
    // Loads on the upper block.
    let mut d = vec![0.0; n];
    for j in 0..ny {
        for i in 0..nx {
            let dy = map[2 * node(1, i, j) + 1];
            let dx = map[2 * node(1, i, j)];
            let t = i as f64 / (nx - 1) as f64;
            let fy = if floating {
                -1.0 + 1.6 * t * t
            } else {
                -1.0 + 2.2 * t
            };
            if dy != usize::MAX {
                d[dy] += 0.05 * fy;
            }
            if dx != usize::MAX {
                d[dx] += 0.01 * (j as f64 - 1.0);
            }
        }
    }
    // gravity-like load on the lower block
    for j in 1..ny {
        for i in 0..nx {
            d[map[2 * node(0, i, j) + 1]] -= 0.01;
        }
    }
    let mut at = vec![];
    let mut g = vec![];
    for i in 0..nx {
        let lo = map[2 * node(0, i, ny - 1) + 1];
        let up = map[2 * node(1, i, 0) + 1];
        let r = g.len();
        at.push((r, lo, 1.0));
        at.push((r, up, -1.0));
        let t = i as f64 / (nx - 1) as f64;
        g.push(if t < 0.4 { 0.0 } else { 0.02 * (t - 0.4) });
    }
    let a = Csr::from_triplets(g.len(), n, &at);
    let mut kernel = vec![];
    if floating {
        let mut z = vec![0.0; n];
        for j in 0..ny {
            for i in 0..nx {
                z[map[2 * node(1, i, j) + 1]] = 1.0;
            }
        }
        kernel.push(z);
    }
    QpProblem {
        c,
        d,
        a,
        g,
        kernel,
        friction: None,
        near: None,
    }
}

/// The reference: CGC + Cholesky at tol 1e-11 (its residual floor on the
/// semicoercive lattices is ≈ 1e-13) through the driver, converged and
/// certified to 1e-9.
pub(crate) fn reference(qp: &QpProblem) -> QpResult {
    let mut o = SolveOptions::default();
    o.settings.tol = 1e-11;
    o.settings.max_iter = 1_000_000;
    o.settings.cgc.preconditioner = crate::qp::precond::PrecondKind::Cholesky;
    let r = registry::solve("cgc", qp, &o).expect("cgc");
    assert!(r.status.converged(), "reference: {}", r.status.describe());
    assert!(r.kkt.within(1e-9), "reference KKT {:?}", r.kkt);
    r
}

/// x agrees to `rel`, active sets equal, KKT ≤ 1e-8, λ ≥ 0, λ to 1e-6.
pub(crate) fn compare(qp: &QpProblem, r: &impl Solution, refr: &impl Solution, rel: f64) {
    assert!(r.status().converged(), "{:?}", r.status());
    let diff: Vec<f64> = r.x().iter().zip(refr.x()).map(|(a, b)| a - b).collect();
    let e = norm(&diff) / norm(refr.x()).max(1e-300);
    assert!(e <= rel, "x differs: {e:e}");
    assert_eq!(r.active(), refr.active(), "active sets differ");
    let k = kkt::residuals(qp, r.x(), r.lambda());
    assert!(k.max() <= 1e-8, "{k:?}");
    assert!(r.lambda().iter().all(|&l| l >= 0.0), "λ < 0");
    let ldiff: Vec<f64> = r
        .lambda()
        .iter()
        .zip(refr.lambda())
        .map(|(a, b)| a - b)
        .collect();
    assert!(
        norm(&ldiff) <= 1e-6 * norm(refr.lambda()).max(1e-300),
        "λ differs"
    );
}

/// The shipped example `meshes/NAME.toml`, read and assembled.
pub(crate) fn example(name: &str) -> crate::run::Prepared {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("meshes/{name}.toml"));
    crate::run::prepare(&path, false).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A point on a rigid floor (−u_y ≤ 0) held by springs kx (none: floating
/// along x) and 3 (along y), loaded by (fx, fy), with friction `bound`:
/// λ_n = −fy, and it sticks (u_x = 0, λ_t = fx) while |fx| ≤ s, else slips
/// with λ_t = s·sign fx, u_x = (fx − λ_t)/kx (s = μλ_n or the Tresca bound).
pub(crate) fn friction_point(kx: f64, fx: f64, fy: f64, bound: crate::qp::SlipBound) -> QpProblem {
    let mut trip = vec![(1, 1, 3.0)];
    if kx > 0.0 {
        trip.push((0, 0, kx));
    }
    QpProblem {
        c: Csr::from_triplets(2, 2, &trip),
        d: vec![fx, fy],
        a: Csr::from_triplets(1, 2, &[(0, 1, -1.0)]),
        g: vec![0.0],
        kernel: if kx > 0.0 {
            vec![]
        } else {
            vec![vec![1.0, 0.0]]
        },
        friction: Some(crate::qp::Friction {
            t: Csr::from_triplets(1, 2, &[(0, 0, 1.0)]),
            t0: vec![0.0],
            bound,
            frame: crate::qp::Frame::Line,
        }),
        near: None,
    }
}

/// A point on a rigid floor (−u_z ≤ 0) in 3D, held by springs k (none:
/// floating along x and y) in x and y and 3 along z, loaded by (fx, fy,
/// fz), with a disc or cone `bound` (`Frame::Plane`, tangents e_x, e_y):
/// λ_n = −fz; it sticks (u = 0 in the plane, λ_t = (fx, fy)) while
/// ‖(fx, fy)‖ ≤ s, else slips along the load with λ_t = s·(fx, fy)/‖(fx, fy)‖,
/// u_t = ((fx, fy) − λ_t)/k.
pub(crate) fn friction_point3(k: f64, f: [f64; 3], bound: crate::qp::SlipBound) -> QpProblem {
    let mut trip = vec![(2, 2, 3.0)];
    if k > 0.0 {
        trip.extend([(0, 0, k), (1, 1, k)]);
    }
    QpProblem {
        c: Csr::from_triplets(3, 3, &trip),
        d: f.to_vec(),
        a: Csr::from_triplets(1, 3, &[(0, 2, -1.0)]),
        g: vec![0.0],
        kernel: if k > 0.0 {
            vec![]
        } else {
            vec![vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0]]
        },
        friction: Some(crate::qp::Friction {
            t: Csr::from_triplets(2, 3, &[(0, 0, 1.0), (1, 1, 1.0)]),
            t0: vec![0.0; 2],
            bound,
            frame: crate::qp::Frame::Plane,
        }),
        near: None,
    }
}
