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

use crate::linalg::sparse::{dot, norm, norm_inf, Csr};
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
    let (block, nb) = qp.c.components();
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
    // Ar ≤ 0, row by row, against the row's size times the motion's
    // (r is scaled to max|r| = 1): a motion along the contact plane gives
    // round-off of either sign on every term, so Σ|a r| is no yardstick.
    for i in 0..qp.m() {
        let (cols, vals) = qp.a.row(i);
        let (mut s, mut abs) = (0.0, 0.0);
        for (&c, &a) in cols.iter().zip(vals) {
            s += a * r[c];
            abs += a.abs();
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

/// An eigenvalue of (BR)ᵀ(BR) at most this share of the largest is zero
/// (B the contact and friction rows, R the unit-norm rigid motions).
const FREE_TOL: f64 = 1e-12;

/// The rigid motions along which the solution is not unique (docs/methods.md
/// §1.7): an orthonormal basis of the r = Rα with Ar = 0 (every contact row
/// slides without opening or closing), Tr = 0 (no slip on a friction row)
/// and dᵀr = 0 (the loads do no work). Adding such an r to a solution gives
/// another solution with the same λ: a ring pressed between two flat
/// plates may sit anywhere along them. Each vector is checked row by row in
/// the row's scale: |(Br)ᵢ| ≤ 10⁻⁹·Σⱼ|Bᵢⱼ|·‖r‖_∞.
pub fn free_motions(qp: &QpProblem) -> Vec<Vec<f64>> {
    free_on(qp, None)
}

/// [`free_motions`] with only the contact rows of `rows` (all if None), and
/// the friction rows that go with them, required not to move.
fn free_on(qp: &QpProblem, rows: Option<&[bool]>) -> Vec<Vec<f64>> {
    let r = normalized(&qp.kernel);
    let k = r.len();
    if k == 0 {
        return vec![];
    }
    let sel = rows;
    // Br with the rows outside the selection zeroed.
    let moved = |z: &[f64]| {
        let mut v = masked(qp.a.mul(z), sel);
        if let Some(f) = &qp.friction {
            v.extend(masked(f.t.mul(z), sel));
        }
        v
    };
    let br: Vec<Vec<f64>> = r.iter().map(|z| moved(z)).collect();
    let gram: Vec<Vec<f64>> = (0..k)
        .map(|i| (0..k).map(|j| dot(&br[i], &br[j])).collect())
        .collect();
    let (vals, vecs) = crate::linalg::dense::sym_eigen(&gram);
    let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let w: Vec<f64> = r.iter().map(|z| dot(z, &qp.d)).collect();
    let d1: f64 = qp.d.iter().map(|v| v.abs()).sum();
    let mut free: Vec<Vec<f64>> = vec![];
    for (lam, alpha) in vals.iter().zip(&vecs) {
        if !(lam.abs() <= FREE_TOL * top) && top > 0.0 {
            continue;
        }
        let mut z = vec![0.0; qp.n()];
        for (a, rv) in alpha.iter().zip(&r) {
            for (zi, ri) in z.iter_mut().zip(rv) {
                *zi += a * ri;
            }
        }
        if !slides_freely(qp, &z, sel) {
            continue;
        }
        // The loads must do no work (else the problem is unbounded, which
        // `boundedness` decides; a borderline case is left to the method).
        // Scale: ‖d‖₁‖z‖_∞, as the eigenvector carries rounding-sized
        // components on every other motion.
        let work: f64 = alpha.iter().zip(&w).map(|(a, b)| a * b).sum();
        if work.abs() > SIGN_TOL * d1 * norm_inf(&z) {
            continue;
        }
        // Orthonormalise against the ones kept.
        for f in &free {
            let p = dot(f, &z);
            for (zi, fi) in z.iter_mut().zip(f) {
                *zi -= p * fi;
            }
        }
        let nz = norm(&z);
        if nz > 0.5 {
            free.push(z.iter().map(|v| v / nz).collect());
        }
    }
    free
}

/// `v` with the entries outside `mask` zeroed (a mask of another length,
/// or none, keeps every entry).
fn masked(mut v: Vec<f64>, mask: Option<&[bool]>) -> Vec<f64> {
    if let Some(m) = mask.filter(|m| m.len() == v.len()) {
        for (vi, &keep) in v.iter_mut().zip(m) {
            if !keep {
                *vi = 0.0;
            }
        }
    }
    v
}

/// |(Br)ᵢ| ≤ 10⁻⁹·Σⱼ|Bᵢⱼ|·‖r‖_∞ on every contact and friction row (the
/// row's own scale: a row that r does not move has only rounding in it).
fn slides_freely(qp: &QpProblem, r: &[f64], rows: Option<&[bool]>) -> bool {
    let rmax = norm_inf(r);
    let ok = |b: &Csr, mask: Option<&[bool]>| {
        (0..b.nrows)
            .filter(|&i| mask.is_none_or(|m| m[i]))
            .all(|i| row_moves(b, i, r, rmax) == 0.0)
    };
    // A friction row goes with its contact row (one each, in order): a
    // motion may slip where the contact is open.
    ok(&qp.a, rows)
        && qp
            .friction
            .as_ref()
            .is_none_or(|f| ok(&f.t, rows.filter(|m| m.len() == f.t.nrows)))
}

/// (Br)ᵢ, or 0 if it is within 10⁻⁹·Σⱼ|Bᵢⱼ|·‖r‖_∞ of 0 (`rmax` = ‖r‖_∞).
fn row_moves(b: &Csr, i: usize, r: &[f64], rmax: f64) -> f64 {
    let (cols, vals) = b.row(i);
    let (mut s, mut abs) = (0.0, 0.0);
    for (&c, &a) in cols.iter().zip(vals) {
        s += a * r[c];
        abs += a.abs();
    }
    if s.abs() <= SIGN_TOL * abs * rmax {
        0.0
    } else {
        s
    }
}

/// The rigid motions free on the rows that carry a force (λᵢ > 0) but not
/// on all rows (docs/methods.md §1.7, "free on the active rows"): a ring
/// touching each plate at one node may roll until a neighbouring node
/// touches. Every point of that segment is a solution with the same λ;
/// `x` is moved to the one with the least component along each such motion
/// that keeps every other row closed (a clamp to its gaps), one motion
/// after the other. With friction the motion must not slip on the
/// friction rows of those contacts either (rolling about the contact
/// point), so λ_t and the stick/slip state are unchanged too. `lambda` =
/// λ of the contact rows. Returns the number of such motions (the ones free
/// on every row, `free`, are not counted: x has no component along them).
pub fn settle_on_active(qp: &QpProblem, x: &mut [f64], lambda: &[f64], free: &[Vec<f64>]) -> usize {
    if qp.kernel.is_empty() || lambda.len() != qp.m() {
        return 0;
    }
    // A row holds the motions if it carries a force and is closed (a
    // small λ left on an open row by an inexact method does not hold).
    let active: Vec<bool> = (0..qp.m())
        .map(|i| {
            let (cols, vals) = qp.a.row(i);
            let (mut ax, mut abs) = (0.0, qp.g[i].abs());
            for (&c, &a) in cols.iter().zip(vals) {
                ax += a * x[c];
                abs += (a * x[c]).abs();
            }
            lambda[i] > 0.0 && qp.g[i] - ax <= SIGN_TOL * abs
        })
        .collect();
    let motions = free_on(qp, Some(&active));
    if motions.len() <= free.len() {
        return 0;
    }
    for f in &motions {
        let fmax = norm_inf(f);
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for i in (0..qp.m()).filter(|&i| !active[i]) {
            let af = row_moves(&qp.a, i, f, fmax);
            if af == 0.0 {
                continue;
            }
            // A_i(x + t f) ≤ g_i, from a slack of at least 0.
            let slack = (qp.g[i] - qp.a.row_dot(i, x)).max(0.0);
            if af > 0.0 {
                hi = hi.min(slack / af);
            } else {
                lo = lo.max(slack / af);
            }
        }
        let t = (-dot(f, x)).clamp(lo.min(0.0), hi.max(0.0));
        if t.is_finite() && t != 0.0 {
            for (xi, fi) in x.iter_mut().zip(f) {
                *xi += t * fi;
            }
        }
    }
    motions.len() - free.len()
}

/// The problem with the `free` motions ([`free_motions`]) held: a spring
/// c_ii on one DOF per free motion (DOFs on which the free motions are
/// independent, [`fixing_dofs`](crate::linalg::cholesky::fixing_dofs)), and
/// the kernel cut down to the rigid motions that leave those DOFs at rest.
/// Its solution is a solution of `qp` (a free motion moves it to the pinned
/// DOFs' rest at no cost in energy or feasibility), and unique where `qp`'s
/// is unique up to the free motions.
pub fn pinned(qp: &QpProblem, free: &[Vec<f64>]) -> QpProblem {
    let n = qp.n();
    let pins = crate::linalg::cholesky::fixing_dofs(free, n);
    let diag = qp.c.diag();
    // The spring: the DOF's own stiffness (its body's scale), 1 if none.
    let springs: Vec<(usize, usize, f64)> = pins
        .iter()
        .map(|&i| (i, i, if diag[i] > 0.0 { diag[i] } else { 1.0 }))
        .collect();
    // The springs go on the diagonal entries in place; a pattern without one
    // (no FEM stiffness has that) is rebuilt with them.
    let diag_at = |i: usize| {
        let (a, b) = (qp.c.indptr[i], qp.c.indptr[i + 1]);
        qp.c.indices[a..b].binary_search(&i).ok().map(|p| a + p)
    };
    let c = match pins
        .iter()
        .map(|&i| diag_at(i))
        .collect::<Option<Vec<usize>>>()
    {
        Some(at) => {
            let mut c = qp.c.clone();
            for (p, &(_, _, v)) in at.into_iter().zip(&springs) {
                c.data[p] += v;
            }
            c
        }
        None => {
            let mut t: Vec<(usize, usize, f64)> = (0..n)
                .flat_map(|row| {
                    let (cols, vals) = qp.c.row(row);
                    cols.iter().zip(vals).map(move |(&j, &v)| (row, j, v))
                })
                .collect();
            t.extend(springs);
            Csr::from_triplets(n, n, &t)
        }
    };
    // ker of the pinned C: z = Rβ with z = 0 on the pins, β ∈ null(R_pins).
    let k = qp.kernel.len();
    let rp: Vec<Vec<f64>> = pins
        .iter()
        .map(|&i| qp.kernel.iter().map(|z| z[i]).collect())
        .collect();
    let gram: Vec<Vec<f64>> = (0..k)
        .map(|a| {
            (0..k)
                .map(|b| rp.iter().map(|row| row[a] * row[b]).sum())
                .collect()
        })
        .collect();
    let (vals, vecs) = crate::linalg::dense::sym_eigen(&gram);
    let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let kernel: Vec<Vec<f64>> = vals
        .iter()
        .zip(&vecs)
        .filter(|(l, _)| l.abs() <= FREE_TOL * top)
        .map(|(_, beta)| {
            let mut z = vec![0.0; n];
            for (b, rv) in beta.iter().zip(&qp.kernel) {
                if *b != 0.0 {
                    for (zi, ri) in z.iter_mut().zip(rv) {
                        *zi += b * ri;
                    }
                }
            }
            z
        })
        .collect();
    QpProblem {
        c,
        d: qp.d.clone(),
        a: qp.a.clone(),
        g: qp.g.clone(),
        kernel,
        friction: qp.friction.clone(),
        near: qp.near.clone(),
    }
}

/// x with no component along the orthonormal `free` motions: the solution
/// of least norm among those a free motion connects (same Cx, Ax, dᵀx).
pub fn without_free(x: &mut [f64], free: &[Vec<f64>]) {
    for f in free {
        let p = dot(f, x);
        for (xi, fi) in x.iter_mut().zip(f) {
            *xi -= p * fi;
        }
    }
}

/// The kernel vectors scaled to unit norm. The NNLS argument needs no
/// orthogonality (r = Rρ satisfies Ar ≤ 0 and dᵀr = ‖ρ‖² for any R), and
/// keeping the FEM's modes (a translation, a rotation about a fixed point)
/// makes the direction found the one a user recognises.
pub(crate) fn normalized(kernel: &[Vec<f64>]) -> Vec<Vec<f64>> {
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
            near: None,
        }
    }

    /// Two floating two-unknown "bodies", springs 1 and 2: (x0, x1) under
    /// the rows x0 ≤ 0, x1 ≤ 0 and the loads d0, d1; (x2, x3) with the loads
    /// d2, d3 and the rows given (numbered from 2).
    fn two_bodies(d: [f64; 4], rows: &[(usize, usize, f64)]) -> QpProblem {
        let m = 2.max(1 + rows.iter().map(|r| r.0).max().unwrap_or(0));
        let mut a = vec![(0, 0, 1.0), (1, 1, 1.0)];
        a.extend_from_slice(rows);
        let spring =
            |i: usize, k: f64| [(i, i, k), (i + 1, i + 1, k), (i, i + 1, -k), (i + 1, i, -k)];
        let c: Vec<_> = spring(0, 1.0).into_iter().chain(spring(2, 2.0)).collect();
        QpProblem {
            c: Csr::from_triplets(4, 4, &c),
            d: d.to_vec(),
            a: Csr::from_triplets(m, 4, &a),
            g: vec![0.0; m],
            kernel: vec![vec![1.0, 1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0, 1.0]],
            friction: None,
            near: None,
        }
    }

    #[test]
    fn a_motion_no_row_sees_and_no_load_works_on_is_free_and_held() {
        // The second body: no row, no net load: free.
        let q = two_bodies([1.0, 0.5, 0.25, -0.25], &[]);
        let free = free_motions(&q);
        assert_eq!(free.len(), 1);
        let h = 0.5f64.sqrt();
        assert!(free[0][0] == 0.0 && free[0][1] == 0.0, "{free:?}");
        assert!((free[0][2].abs() - h).abs() < 1e-15 && (free[0][3] - free[0][2]).abs() < 1e-15);
        // Held: one spring on the second body, the first one's motion left
        // in the kernel.
        let p = pinned(&q, &free);
        assert_eq!(p.kernel.len(), 1);
        assert!(p.kernel[0][2].abs() < 1e-15 && p.kernel[0][0].abs() > 0.5);
        // Every method returns the one solution whose second body has no
        // mean displacement: x = (0, 0, 0.0625, −0.0625), λ = (1, 0.5),
        // certified against the problem as given, and says so; a warm start
        // far along the free motion changes nothing.
        let x = [0.0, 0.0, 0.0625, -0.0625];
        for method in ["ssn", "asm", "mprgp", "dual", "cgc", "uzawa"] {
            let opts = crate::qp::SolveOptions {
                x0: Some(vec![0.0, 0.0, 5.0, 5.0]),
                ..Default::default()
            };
            let r = crate::qp::registry::solve(method, &q, &opts).expect(method);
            assert!(
                r.status.converged() && r.kkt.within(1e-6),
                "{method}: {:?} {:?}",
                r.status,
                r.kkt
            );
            for (a, b) in r.x.iter().zip(&x) {
                assert!((a - b).abs() <= 1e-8, "{method}: {:?}", r.x);
            }
            assert!(
                (r.lambda[0] - 1.0).abs() <= 1e-8 && (r.lambda[1] - 0.5).abs() <= 1e-8,
                "{method}: {:?}",
                r.lambda
            );
            assert!(
                r.notes
                    .iter()
                    .any(|n| n.to_string().contains("unique only up to 1 rigid motion")),
                "{method}: {:?}",
                r.notes
            );
        }
        // A row on the second body (either sign) or a net load on it: not free.
        let q = two_bodies([1.0, 0.5, 0.25, -0.25], &[(2, 2, 1.0), (3, 3, -1.0)]);
        assert!(free_motions(&q).is_empty());
        let q = two_bodies([1.0, 0.5, 0.25, 0.25], &[]);
        assert!(free_motions(&q).is_empty());
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
            near: None,
        };
        assert!(certify(&q, &[0.0, 1.0]).is_err());
        assert_eq!(q.c.components().1, 2);
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
