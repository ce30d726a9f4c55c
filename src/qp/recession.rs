//! Is f(x) = ½xᵀCx − xᵀd bounded below on {Ax ≤ g}? (docs/methods.md §1.7)
//!
//! For a convex QP with a feasible point, f is unbounded below iff there is a
//! *recession direction* r with Cr = 0, Ar ≤ 0 and dᵀr > 0: a rigid motion
//! that no contact blocks and on which the loads do positive work. This module
//! decides that question exactly, before any method runs, and checks a
//! direction a method claims, so that "unbounded" is never the verdict of a
//! threshold on a curvature (a soft body under a stiff one has tiny but
//! positive curvature).
//!
//! **Decision** ([`boundedness`]). With R a basis of ker C (the rigid motions
//! the FEM layer computes from the geometry, each scaled to unit norm but not
//! orthogonalised, so that a translation stays a translation), r = Rα and the
//! question is a cone problem in α ∈ ℝᵏ (k = 3 per floating body at most):
//! with B = (AR)ᵀ and w = Rᵀd, solve the non-negative least-squares problem
//! min ‖Bμ − w‖, μ ≥ 0 (Lawson–Hanson). Its optimality conditions give
//! ρ = w − Bμ with Bᵀρ ≤ 0 and wᵀρ = ‖ρ‖². So either ρ = 0 — the loads on
//! the rigid motions are balanced by non-negative contact forces μ (Farkas),
//! and f is bounded — or α = ρ is a recession direction with dᵀr = ‖ρ‖² > 0.
//!
//! **Certificate** ([`certify`]). A direction is accepted only if, checked
//! independently of whoever produced it: every uncoupled block of C (a body:
//! C has no entries between bodies) has ‖C_b r_b‖ ≤ 10⁻⁸·max diag(C_b)·‖r_b‖,
//! in that body's own stiffness scale, so a stiffness contrast cannot fake a
//! zero curvature; (Ar)ᵢ ≤ 10⁻⁹·Σⱼ|Aᵢⱼrⱼ| for every row; and
//! dᵀr > 10⁻⁹·Σⱼ|dⱼrⱼ|.

use crate::linalg::sparse::{dot, norm, Csr};
use crate::qp::QpProblem;

/// Relative tolerance of Cr = 0 per block (in the block's stiffness scale).
const CURVATURE_TOL: f64 = 1e-8;
/// Relative tolerance of Ar ≤ 0 (per row) and dᵀr > 0.
const SIGN_TOL: f64 = 1e-9;
/// ‖ρ‖ ≤ BALANCE_TOL·‖w‖: the loads on the rigid motions are balanced.
const BALANCE_TOL: f64 = 1e-9;

/// A verified recession direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Recession {
    /// r, scaled so that its largest component is 1.
    pub direction: Vec<f64>,
    /// dᵀr for that scaling: the work the loads do along it.
    pub work: f64,
}

/// The verdict of [`boundedness`].
#[derive(Debug, Clone, PartialEq)]
pub enum Boundedness {
    /// The loads on every rigid motion are balanced by non-negative contact
    /// forces (or C has no kernel).
    Bounded,
    /// A verified recession direction.
    Unbounded(Recession),
    /// The decision found a candidate direction that failed the certificate
    /// (a borderline case): the methods decide, and their claims are checked.
    Undecided(String),
}

/// Decide boundedness from `qp.kernel` (module doc). Without a kernel, C is
/// taken as the FEM layer built it: positive definite.
pub fn boundedness(qp: &QpProblem) -> Boundedness {
    let r = normalized(&qp.kernel);
    let k = r.len();
    if k == 0 {
        return Boundedness::Bounded;
    }
    let m = qp.m();
    let w: Vec<f64> = r.iter().map(|z| dot(z, &qp.d)).collect();
    let wn = norm(&w);
    if !(wn > 0.0) {
        return Boundedness::Bounded;
    }
    // Columns of B: b_i = (A_i R)ᵀ ∈ ℝᵏ, one per contact row.
    let ar: Vec<Vec<f64>> = r.iter().map(|z| qp.a.mul(z)).collect();
    let b: Vec<Vec<f64>> = (0..m).map(|i| ar.iter().map(|c| c[i]).collect()).collect();
    let rho = nnls_residual(&b, &w);
    if norm(&rho) <= BALANCE_TOL * wn {
        return Boundedness::Bounded;
    }
    let mut dir = vec![0.0; qp.n()];
    for (a, z) in rho.iter().zip(&r) {
        for (di, zi) in dir.iter_mut().zip(z) {
            *di += a * zi;
        }
    }
    match certify(qp, &dir) {
        Ok(c) => Boundedness::Unbounded(c),
        Err(why) => Boundedness::Undecided(why),
    }
}

/// Check a claimed recession direction `r` (module doc); the reason if it fails.
pub fn certify(qp: &QpProblem, r: &[f64]) -> Result<Recession, String> {
    if r.len() != qp.n() || !r.iter().all(|v| v.is_finite()) {
        return Err("the direction is not a finite vector of the problem's size".into());
    }
    let rmax = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if !(rmax > 0.0) {
        return Err("the direction is zero".into());
    }
    let r: Vec<f64> = r.iter().map(|v| v / rmax).collect();
    // Cr = 0, block by block in each block's own scale.
    let (block, nb) = blocks(&qp.c);
    let cr = qp.c.mul(&r);
    let diag = qp.c.diag();
    let mut cr2 = vec![0.0; nb];
    let mut r2 = vec![0.0; nb];
    let mut dmax = vec![0.0f64; nb];
    for i in 0..qp.n() {
        let b = block[i];
        cr2[b] += cr[i] * cr[i];
        r2[b] += r[i] * r[i];
        dmax[b] = dmax[b].max(diag[i].abs());
    }
    for b in 0..nb {
        if r2[b] > 0.0 && cr2[b].sqrt() > CURVATURE_TOL * dmax[b] * r2[b].sqrt() {
            return Err(format!(
                "it deforms a body: ‖Cr‖ = {:.3e} × max diag(C)·‖r‖ on that body",
                cr2[b].sqrt() / (dmax[b] * r2[b].sqrt())
            ));
        }
    }
    // Ar ≤ 0, row by row.
    for i in 0..qp.m() {
        let (cols, vals) = qp.a.row(i);
        let (mut s, mut abs) = (0.0, 0.0);
        for (&c, &a) in cols.iter().zip(vals) {
            s += a * r[c];
            abs += (a * r[c]).abs();
        }
        if s > SIGN_TOL * abs {
            return Err(format!("it closes contact row {i}"));
        }
    }
    let work = dot(&qp.d, &r);
    let abs: f64 = qp.d.iter().zip(&r).map(|(d, r)| (d * r).abs()).sum();
    if !(work > SIGN_TOL * abs) {
        return Err(format!(
            "the loads do no positive work on it (dᵀr = {work:.3e})"
        ));
    }
    Ok(Recession { direction: r, work })
}

/// Connected components of the graph of C: its uncoupled diagonal blocks
/// (the bodies). Returns the block of every unknown and the block count.
pub fn blocks(c: &Csr) -> (Vec<usize>, usize) {
    let n = c.nrows;
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for i in 0..n {
        for &j in c.row(i).0 {
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut id = vec![usize::MAX; n];
    let mut block = vec![0; n];
    let mut nb = 0;
    for i in 0..n {
        let r = root(&mut parent, i);
        if id[r] == usize::MAX {
            id[r] = nb;
            nb += 1;
        }
        block[i] = id[r];
    }
    (block, nb)
}

/// The kernel vectors scaled to unit norm. The NNLS argument needs no
/// orthogonality (r = Rρ satisfies Ar ≤ 0 and dᵀr = ‖ρ‖² for any R), and
/// keeping the FEM's modes (a translation, a rotation about a fixed point)
/// makes the direction found the one a user recognises.
fn normalized(kernel: &[Vec<f64>]) -> Vec<Vec<f64>> {
    kernel
        .iter()
        .filter_map(|z| {
            let nz = norm(z);
            (nz > 0.0 && nz.is_finite()).then(|| z.iter().map(|a| a / nz).collect())
        })
        .collect()
}

/// Lawson–Hanson NNLS for min ‖Bμ − w‖, μ ≥ 0, with the columns b_i of B
/// given as `cols` (each of length k = w.len()); returns ρ = w − Bμ.
/// A column enters only if its gradient bᵢᵀρ exceeds 10⁻¹²·‖bᵢ‖·‖w‖
/// (scale-free; a column in the span of the passive ones has gradient 0).
fn nnls_residual(cols: &[Vec<f64>], w: &[f64]) -> Vec<f64> {
    let m = cols.len();
    let wn = norm(w);
    let cn: Vec<f64> = cols.iter().map(|c| norm(c)).collect();
    let mut mu = vec![0.0; m];
    let mut passive: Vec<usize> = vec![];
    let residual = |mu: &[f64]| {
        let mut rho = w.to_vec();
        for (c, &u) in cols.iter().zip(mu) {
            if u != 0.0 {
                for (r, v) in rho.iter_mut().zip(c) {
                    *r -= u * v;
                }
            }
        }
        rho
    };
    for _outer in 0..3 * m.max(1) + 10 {
        let rho = residual(&mu);
        // The most positive relative gradient outside the passive set.
        let mut best = None;
        let mut gbest = 0.0;
        for i in 0..m {
            if passive.contains(&i) || !(cn[i] > 0.0) {
                continue;
            }
            let g = dot(&cols[i], &rho) / (cn[i] * wn);
            if g > 1e-12 && g > gbest {
                gbest = g;
                best = Some(i);
            }
        }
        let Some(t) = best else {
            return rho;
        };
        passive.push(t);
        // Inner loop: unconstrained least squares on the passive set, kept
        // feasible by interpolation (Lawson & Hanson 1974, ch. 23).
        for _inner in 0..3 * m.max(1) + 10 {
            let z = lstsq(cols, &passive, w);
            if z.iter().all(|&v| v > 0.0) {
                for (&i, &v) in passive.iter().zip(&z) {
                    mu[i] = v;
                }
                break;
            }
            let mut alpha = f64::INFINITY;
            for (&i, &v) in passive.iter().zip(&z) {
                if v <= 0.0 {
                    let a = mu[i] / (mu[i] - v);
                    if a < alpha {
                        alpha = a;
                    }
                }
            }
            let alpha = if alpha.is_finite() { alpha } else { 0.0 };
            for (&i, &v) in passive.iter().zip(&z) {
                mu[i] += alpha * (v - mu[i]);
            }
            passive.retain(|&i| mu[i] > 1e-14 * mu.iter().fold(0.0f64, |a, b| a.max(*b)));
            for i in 0..m {
                if !passive.contains(&i) {
                    mu[i] = 0.0;
                }
            }
            if passive.is_empty() {
                break;
            }
        }
    }
    residual(&mu)
}

/// Least-squares coefficients of w on the columns `idx` (column-pivoted QR).
fn lstsq(cols: &[Vec<f64>], idx: &[usize], w: &[f64]) -> Vec<f64> {
    use faer::linalg::solvers::SolveLstsq;
    let k = w.len();
    let b = faer::Mat::from_fn(k, idx.len(), |r, c| cols[idx[c]][r]);
    let rhs = faer::Mat::from_fn(k, 1, |r, _| w[r]);
    if idx.len() > k {
        // More columns than rows cannot all be independent: drop the last.
        let z = lstsq(cols, &idx[..k], w);
        return z
            .into_iter()
            .chain(std::iter::repeat(0.0))
            .take(idx.len())
            .collect();
    }
    let z = b.col_piv_qr().solve_lstsq(&rhs);
    (0..idx.len()).map(|i| z[(i, 0)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One floating "body" of two unknowns (x0, x1) with C = 0 and a soft
    /// spring x2 clamped: kernel e0, e1. Rows: −x0 ≤ 0 (a floor under x0).
    fn floating(d: [f64; 3], rows: &[(usize, usize, f64)]) -> QpProblem {
        let m = rows.iter().map(|r| r.0 + 1).max().unwrap_or(0);
        QpProblem {
            c: Csr::from_triplets(3, 3, &[(2, 2, 1e-6)]),
            d: d.to_vec(),
            a: Csr::from_triplets(m, 3, rows),
            g: vec![0.0; m],
            kernel: vec![vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0]],
            friction: None,
        }
    }

    #[test]
    fn a_load_pressing_on_a_support_is_bounded() {
        // Load −1 on x0 (towards the floor −x0 ≤ 0 … i.e. x0 ≥ 0? no: the
        // row is +x0 ≤ 0, the load pushes x0 up (+1): blocked). x1 blocked
        // both ways by two rows.
        let q = floating([1.0, 0.5, 3.0], &[(0, 0, 1.0), (1, 1, 1.0), (2, 1, -1.0)]);
        assert_eq!(boundedness(&q), Boundedness::Bounded);
    }

    #[test]
    fn a_load_pulling_away_is_unbounded_with_a_certificate() {
        // x0 ≤ 0 blocks motion up; the load pulls down (d0 = −2): unbounded.
        let q = floating([-2.0, 0.0, 3.0], &[(0, 0, 1.0), (1, 1, 1.0), (2, 1, -1.0)]);
        match boundedness(&q) {
            Boundedness::Unbounded(c) => {
                assert!((c.direction[0] + 1.0).abs() < 1e-12, "{c:?}");
                assert!(c.direction[1].abs() < 1e-12 && c.direction[2] == 0.0);
                assert!((c.work - 2.0).abs() < 1e-12);
            }
            v => panic!("{v:?}"),
        }
    }

    #[test]
    fn a_stiffness_contrast_cannot_fake_a_zero_curvature() {
        // Body 1: stiff spring 1e11 on x0; body 2: soft spring 1 on x1,
        // coupled by nothing. A motion of the soft body has tiny curvature
        // against the stiff scale but not against its own.
        let q = QpProblem {
            c: Csr::from_triplets(2, 2, &[(0, 0, 1e11), (1, 1, 1.0)]),
            d: vec![0.0, 1.0],
            a: Csr::zeros(0, 2),
            g: vec![],
            kernel: vec![],
            friction: None,
        };
        assert!(certify(&q, &[0.0, 1.0]).is_err());
        assert_eq!(blocks(&q.c).1, 2);
    }

    #[test]
    fn a_direction_that_closes_a_contact_is_refused() {
        let q = floating([-2.0, 0.0, 3.0], &[(0, 0, -1.0)]);
        assert!(certify(&q, &[1.0, 0.0, 0.0]).is_err());
        assert!(certify(&q, &[-1.0, 0.0, 0.0]).is_err(), "no positive work");
        assert!(certify(&q, &[0.0, 0.0, 0.0]).is_err());
        assert!(certify(&q, &[f64::NAN, 0.0, 0.0]).is_err());
    }

    #[test]
    fn partially_balanced_loads_leave_the_unbalanced_motion() {
        // x0 held both ways; x1 held only against +: a load −1 on x1 is free.
        let q = floating([5.0, -1.0, 0.0], &[(0, 0, 1.0), (1, 0, -1.0), (2, 1, 1.0)]);
        match boundedness(&q) {
            Boundedness::Unbounded(c) => {
                assert!(
                    c.direction[0].abs() < 1e-12 && (c.direction[1] + 1.0).abs() < 1e-12,
                    "{c:?}"
                )
            }
            v => panic!("{v:?}"),
        }
    }
}
