//! Semismooth Newton / primal–dual active set method (Hintermüller, Ito &
//! Kunisch 2002, SIAM J. Optim. 13; methods.md §7): Newton's method on the
//! complementarity function λ − max(0, λ + c(Ax − g)) = 0.
//!
//! One iteration (one [`Executor`] step):
//!
//! 1. solve the KKT system of the working set J: `Cx + A_Jᵀλ_J = d`,
//!    `A_J x = g_J`, `λ_{J^c} = 0`;
//! 2. predict `J ← {i : λᵢ + c(Ax − g)ᵢ > τ}`;
//! 3. stop when J did not change (then λ_J > τ ≥ 0 and (Ax − g)_{J^c} ≤ τ/c:
//!    the KKT conditions hold to the tolerance).
//!
//! The start is the glued set `J = {i : gᵢ = 0}` with λ = 0.
//!
//! **Parameters.** `c` = mean of diag(C) (a stiffness: λ is a force and Ax − g a
//! length, so c·(Ax − g) is a force too). With exact solves of the KKT system,
//! (Ax − g)_J and λ_{J^c} vanish, so c only weighs rounding-level terms and the
//! ordering in the fallback below. The threshold is
//! `τ = tol·(‖λ‖∞ + c·max(‖x‖∞, ‖g‖∞))` (relative, unit-free).
//!
//! **Linear algebra.** One sparse Cholesky factor K of C (of C + springs for a
//! semicoercive C, [`Cholesky::new`]) is computed once. The columns
//! hⱼ = A K⁻¹aⱼ of the dual Hessian are computed only for rows that ever
//! enter J, in blocks of [`BLOCK`] right-hand sides per multi-column solve
//! (BLAS-3 in the supernodal factor, several times cheaper per column than
//! one-at-a-time), and cached as m-vectors: O(m·|J|) memory, never an n×|J|
//! block. The Schur complement S_J = A_J K⁻¹ A_Jᵀ (|J|×|J|, SPD) is formed
//! densely from them and factored by a dense Cholesky in every iteration:
//! this method is *defined* with a dense |J|×|J| step (O(|J|³) flops,
//! O(|J|²) memory), which is cheap while |J| is a few thousand (contact
//! rows grow like √N in 2D). x = K⁻¹(d − A_Jᵀλ_J) + Rα costs one solve per
//! iteration.
//!
//! **Default linear algebra: augmented KKT factor.** The KKT system of J is
//! solved with K_J = C + ρA_JᵀA_J (ρ = [`RHO_FACTOR`]·max diag C), which is SPD
//! as soon as J holds every floating body, and has the same sparsity
//! pattern for every J (C + AᵀA, rows outside J with weight 0): each Newton
//! step is one *numeric* refactorization on the symbolic analysis of the
//! first ([`crate::linalg::cholesky`] cache), plus a few solves. The system
//! `K_J x + A_Jᵀλ = d + ρA_Jᵀg_J, A_J x = g_J` has the same solution as the
//! KKT system; its Schur complement S_ρ = A_J K_J⁻¹ A_Jᵀ = (H_J⁻¹ + ρI)⁻¹
//! (H_J = A_J C⁻¹A_Jᵀ on range C) has condition number ≤ 1 + 1/(ρ·λ_min(H_J)),
//! close to 1 because λ_min(H_J) ≳ ‖a‖²/λ_max(C) and ρ ≫ λ_max(C)/‖a‖², so
//! CG on it (warm-started from the last λ) needs a handful of solves. No
//! |J|×|J| matrix and no n×|J| block is formed. If K_J is not positive
//! definite (J leaves a floating body free) or CG stalls, the step falls back
//! to the Schur-complement path below.
//!
//! **Choosing the path per step** (counts only: the same input takes the
//! same path on every run, whatever the machine load). Before any numeric
//! work, the symbolic analyses of C and of C + AᵀA ([`factor_cost`], on the
//! AMD ordering the factors use) give for each factor L its entry count
//! nnz(L) and its multiply–adds Σⱼcⱼ² (cⱼ = column counts of L). In units of
//! one entry of L read by a solve:
//!
//! * a factorization costs Σⱼcⱼ² / [`FLOPS_PER_ENTRY`] (dense supernodal
//!   kernels run many multiply–adds in the time a solve reads one entry);
//! * a solve costs nnz(L); one column of a blocked solve ([`BLOCK`] right-hand
//!   sides) costs [`COL_FRACTION`]·nnz(L).
//!
//! The first step takes the Schur path when fac(C) + |J|·col(C) ≤ fac(K) +
//! 6·solve(K). Later, the Schur path costs [C not yet factored]·fac(C) +
//! (rows entering J for the first time)·col(C), the augmented path
//! min(fac(K), (changed rows)·col(K)) + 6·solve(K) (a refactor, or a
//! low-rank update of K'), and the Schur path is taken when it is at most
//! k times the augmented one, k = 1 in the second step and 3 later (J still
//! moving after two Newton steps: more steps will follow, and the Schur
//! path's columns are paid once). A large J that is nearly settled (the
//! three-body faults) stays on the augmented path; a small growing J (Hertz)
//! moves to the Schur path. `SolveOptions::ssn_path` forces a path.
//!
//! **Certificate and refinement.** When J has settled, the KKT residual of
//! (x, λ) is measured ([`certificate`]: stationarity also relative to ‖Aᵀλ‖ on
//! the contact unknowns, so that force errors cannot hide behind ‖d‖). If it
//! exceeds tol, the KKT system of J is refined with the same factor (solve
//! for the correction of the residual, at most [`REFINE_MAX`] times while it
//! halves), then, if it is still above min(CERT_TARGET, 100·tol) after the
//! augmented path, recomputed once on the Schur path and refined there (the
//! certificate has a rounding floor near ε × the stiffness contrast). An answer whose certificate still exceeds [`CERT_TARGET`] is
//! returned as [`Status::Failed`], never as converged.
//!
//! **Why the augmented path lost accuracy under stiffness contrast.** The
//! first block row of the augmented system is Cx − d + A_Jᵀ(μ + ρ(A_J x −
//! g_J)) = 0, so the multiplier of the original KKT system is μ + ρ(A_J x −
//! g_J), not μ: λ = μ is paid for every gap error δ = A_J x − g_J at the
//! rate ρ. ρ = 100·max diag C is set by the stiffest body, and the forward
//! error of K_J⁻¹ (condition number ∝ ρ / the soft body's smallest
//! stiffness) leaves δ ≈ ε·κ(K_J)·|x| however long CG runs; on a steel punch
//! (E = 2.1e11) on a soft foundation (E = 5e7) ρ is 4e5 times the
//! foundation's stiffness, and ρδ came to 1e-3 of the contact forces
//! (stationarity 1.3e-3 on a 35k-node mesh). The multiplier is therefore
//! taken as λ_J = μ + ρ(A_J x − g_J): then Cx − d + A_Jᵀλ = 0 holds to the
//! backward error of the K_J solve, and δ stays a gap error of ε·κ relative
//! size (1e-8 there), which the refinement above removes. (A smaller ρ per
//! row, set by the softest body the row touches, was tried: it only slows CG
//! on S_ρ, whose condition number 1 + 1/(ρλ_min(H_J)) grows, and leaves the
//! first residual larger.)
//!
//! **Semicoercive C** (floating bodies; `qp.kernel` = basis R of ker C,
//! orthonormalised here). With the springs at the fixing DOFs, K⁻¹ is a
//! generalised inverse of C on range C: for b ⟂ ker C, (C + S)y = b gives
//! Rᵀ S y = 0, hence y at the fixing DOFs is 0 and C y = b (tested below). As in
//! TFETI, x = K⁻¹(d − A_Jᵀλ_J) + Rα, and the solvability condition
//! Rᵀ(d − A_Jᵀλ_J) = 0 is added to `A_J x = g_J`:
//!
//! ```text
//!   [ S_J   −G_Jᵀ ] [λ_J]   [A_J K⁻¹d − g_J]        G_J = Rᵀ A_Jᵀ  (k×|J|)
//!   [ −G_J    0   ] [ α ] = [     −Rᵀd      ]
//! ```
//!
//! solved by the Schur complement F = G_J S_J⁻¹ G_Jᵀ (k×k, k = dim ker C).
//! It is nonsingular iff no rigid motion leaves all rows of J unchanged
//! (A_J R injective). If J leaves a rigid motion free, J is enlarged: first by
//! the last J that could be solved (J ∪ J_prev), then to all rows; if even that
//! is singular the method stops with [`Status::Failed`].
//!
//! **Growth limit** (not in Hintermüller–Ito–Kunisch). From the glued start
//! of a Hertz-type contact (one zero-gap row), the first solve holds the body
//! at one point and penetrates about twice the rows that end in contact; PDAS
//! then peels the surplus off a band per step, and on the Schur path every
//! row that ever entered J has cost a column (612 rows entered at the second
//! step on the 1 M-node Hertz mesh). So at most max([`GROW_MIN`], |J|) rows enter
//! per step, the most violated first: J at most doubles, and on a 170k-node
//! Hertz mesh the column solves drop from 269 to 139 (9 steps instead of 12).
//! The stopping test is unchanged (J is final only when the full prediction
//! equals it), so the limit can only delay, never change, the answer.
//!
//! **Cycling.** PDAS converges locally superlinearly but may cycle on
//! non-M-matrix problems. If a working set repeats, the method switches for
//! good to single changes (drop the most negative multiplier or add the most
//! violated constraint, whichever is larger in the units of c), a classical
//! primal active-set step; MAXIT (the executor) is the last guard.
//!
//! Counts: `iterations` = KKT solves; `inner_iterations` = solves with the
//! sparse factor (one per cached column plus one for K⁻¹d).

use crate::linalg::cholesky::{factor_cost, Cholesky, Workspace};
use crate::linalg::sparse::{dot, norm, norm_inf, Csr};
use crate::qp::executor::{Iterative, Step};
use crate::qp::settings::SsnPath;
use crate::qp::{Context, IterRecord, Method, Output, QpError, QpProblem, Status};
use std::collections::{HashMap, HashSet};
use std::rc::Rc;
use std::time::Instant;

/// ρ = RHO_FACTOR · max diag C in K_J = C + ρA_JᵀA_J (one ρ_j = ρ per row;
/// the code keeps a weight per row, Ρ = diag(ρ_j)).
pub(crate) const RHO_FACTOR: f64 = 1e2;
/// CG on the Schur complement of K_J: at most this many steps.
const AL_MAX_CG: usize = 200;
/// Low-rank updates of K': at most this many changed rows, and at most
/// this many bytes for the n×r block K'⁻¹Uᵀ.
const LOWRANK_MAX: usize = 256;
const LOWRANK_BYTES: f64 = 1.0e9;
/// Cost of one column in a blocked solve of BLOCK right-hand sides, as a
/// fraction of one single solve (32 columns took ≈ 5.6 single solves on the
/// 43k-node three-body model).
const COL_FRACTION: f64 = 0.2;
/// Multiply–adds of a supernodal factorization done in the time a solve
/// reads one entry of L (dense BLAS-3 kernels against a memory-bound
/// triangular solve: on a 69k-DOF punch model, 9.6e8 multiply–adds took
/// 0.56 s and a solve over 5.3e6 entries ≈ 0.05 s, a ratio of ≈ 17; 10 is
/// used, between that and the smaller shipped models).
const FLOPS_PER_ENTRY: f64 = 10.0;
/// Right-hand sides per multi-column solve when columns of H are computed.
const BLOCK: usize = 32;
/// Growth limit of J per step: at most max(GROW_MIN, |J|) rows enter.
const GROW_MIN: usize = BLOCK;
/// Relative pivot threshold of the dense Cholesky of S_J.
const PIVOT_S: f64 = 1e-12;
/// Relative pivot threshold of the coarse matrix F = G_J S_J⁻¹ G_Jᵀ
/// (a rigid motion left free by J gives a pivot at rounding level).
const PIVOT_F: f64 = 1e-10;
/// Refinement steps of the final KKT solve (module doc).
const REFINE_MAX: usize = 3;
/// The certificate an answer must meet to be returned as converged.
pub(crate) const CERT_TARGET: f64 = 1e-6;

/// Semismooth Newton / primal–dual active set (docs/methods.md §7).
pub struct SsnMethod;

impl Method for SsnMethod {
    fn name(&self) -> &'static str {
        "ssn"
    }
    fn summary(&self) -> &'static str {
        "semismooth Newton / primal–dual active set, Schur complement with one Cholesky factor (§7)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

/// Solve `qp` by the semismooth Newton (primal–dual active set) method.
pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let path = match ctx.settings.ssn.path {
        SsnPath::Auto => Path::Auto,
        SsnPath::Augmented => Path::Augmented,
        SsnPath::Refactor => Path::Refactor,
        SsnPath::Schur => Path::Schur,
    };
    solve_traced(qp, ctx, path).map(|(r, _)| r)
}

/// Which linear algebra the KKT solves use (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Path {
    /// Chosen per step by the count-based cost model.
    Auto,
    /// Always K_J = C + A_JᵀΡA_J (falls back to Schur only when it fails).
    Augmented,
    /// Augmented, refactoring K_J at every step (no low-rank updates).
    Refactor,
    /// Always the Schur complement on one factor of C.
    Schur,
}

/// [`solve`] with the linear-algebra path fixed (tests).
#[cfg(test)]
pub(crate) fn solve_with(
    qp: &QpProblem,
    opts: &crate::qp::SolveOptions,
    path: Path,
) -> Result<Output, QpError> {
    let ws = Workspace::new();
    solve_traced(qp, &mut Context::new(opts, &ws), path).map(|(r, _)| r)
}

/// [`solve`] with the path fixed, also returning the path of every KKT
/// solve (true = augmented), refinements included.
pub(crate) fn solve_traced(
    qp: &QpProblem,
    ctx: &mut Context,
    path: Path,
) -> Result<(Output, Vec<bool>), QpError> {
    let augmented = path != Path::Schur;
    let t0 = Instant::now();
    let r = orthonormal_kernel(&qp.c, &qp.kernel)?;
    let mut st = Ssn::new(qp, r, ctx.settings.tol, augmented, ctx.ws);
    st.auto = path == Path::Auto;
    st.lowrank = path != Path::Refactor;
    if st.aug.is_some() {
        st.costs = Costs::new(qp, st.aug.as_ref())?;
    }
    if !augmented {
        st.ensure_dense()?;
    }
    let mut exec = ctx.executor("ssn");
    let (status, iters) = exec.run(&mut st);
    if let Some(e) = st.error.take() {
        return Err(e);
    }
    let t_all = t0.elapsed().as_secs_f64();
    let t_factor = st.t_factor;
    let trace = std::mem::take(&mut st.trace);
    Ok((
        st.into_result(
            status,
            iters,
            exec.log,
            vec![
                ("factor".into(), t_factor),
                ("iterate".into(), t_all - t_factor),
            ],
        ),
        trace,
    ))
}

/// Counted costs of the two paths (module doc), in entries of L read by a solve.
#[derive(Debug, Clone, Copy)]
struct Costs {
    fac_c: f64,
    solve_c: f64,
    fac_k: f64,
    solve_k: f64,
}

impl Costs {
    fn new(qp: &QpProblem, aug: Option<&AugPattern>) -> Result<Costs, QpError> {
        let c = factor_cost(&qp.c)?;
        let k = match aug {
            Some(a) => factor_cost(&a.k)?,
            None => c,
        };
        log::debug!(
            "ssn: counts: C: nnz(L) {:.3e}, Σc² {:.3e}; C + AᵀA: nnz(L) {:.3e}, Σc² {:.3e}",
            c.nnz,
            c.flops,
            k.nnz,
            k.flops
        );
        Ok(Costs {
            fac_c: c.flops / FLOPS_PER_ENTRY,
            solve_c: c.nnz,
            fac_k: k.flops / FLOPS_PER_ENTRY,
            solve_k: k.nnz,
        })
    }
    fn col_c(&self) -> f64 {
        COL_FRACTION * self.solve_c
    }
    fn col_k(&self) -> f64 {
        COL_FRACTION * self.solve_k
    }
}

/// The largest KKT residual of (x, λ) as the driver computes it
/// ([`crate::qp::kkt::residuals`], docs/methods.md §8.4); +∞ if anything is not finite.
pub(crate) fn certificate(qp: &QpProblem, x: &[f64], lam: &[f64]) -> f64 {
    // ssn refines until its answer passes the test the driver applies.
    crate::qp::kkt::residuals(qp, x, lam).max()
}

/// K = C + AᵀA on one pattern: the values of C, and for every row j of A the
/// positions in K.data of its products a_k·a_l.
struct AugPattern {
    k: Csr,
    base: Vec<f64>,
    rows: Vec<Vec<(usize, f64)>>,
}

impl AugPattern {
    fn new(qp: &QpProblem) -> AugPattern {
        let n = qp.n();
        // Columns that AᵀA adds to each row, merged row by row into C's
        // (sorted) pattern: O(nnz) with no global sort.
        let mut extra: Vec<Vec<usize>> = vec![vec![]; n];
        for j in 0..qp.m() {
            let (c, _) = qp.a.row(j);
            for &k in c {
                extra[k].extend_from_slice(c);
            }
        }
        let mut indptr = Vec::with_capacity(n + 1);
        let mut indices = Vec::with_capacity(qp.c.nnz() + 4 * qp.a.nnz());
        let mut data = Vec::with_capacity(qp.c.nnz() + 4 * qp.a.nnz());
        indptr.push(0);
        for (i, ex) in extra.iter_mut().enumerate() {
            let (c, v) = qp.c.row(i);
            ex.sort_unstable();
            ex.dedup();
            let (mut a, mut b) = (0, 0);
            while a < c.len() || b < ex.len() {
                if b == ex.len() || (a < c.len() && c[a] <= ex[b]) {
                    if b < ex.len() && c[a] == ex[b] {
                        b += 1;
                    }
                    indices.push(c[a]);
                    data.push(v[a]);
                    a += 1;
                } else {
                    indices.push(ex[b]);
                    data.push(0.0);
                    b += 1;
                }
            }
            indptr.push(indices.len());
        }
        drop(extra);
        let k = Csr {
            nrows: n,
            ncols: n,
            indptr,
            indices,
            data,
        };
        let rows = (0..qp.m())
            .map(|j| {
                let (c, v) = qp.a.row(j);
                let mut out = Vec::with_capacity(c.len() * c.len());
                for (&kk, &ak) in c.iter().zip(v) {
                    let (cols, _) = k.row(kk);
                    for (&l, &al) in c.iter().zip(v) {
                        let pos = k.indptr[kk] + cols.binary_search(&l).expect("in pattern");
                        out.push((pos, ak * al));
                    }
                }
                out
            })
            .collect();
        AugPattern {
            base: k.data.clone(),
            k,
            rows,
        }
    }
}

/// K_J = K' + UᵀΣU for the rows whose membership changed since K' was
/// factored (σ = +ρ_j entering, −ρ_j leaving): Sherman–Morrison–Woodbury,
/// K_J⁻¹ = K'⁻¹ − Z W⁻¹ Zᵀ with Z = K'⁻¹Uᵀ (n×r, kept) and the small
/// capacitance W = Σ⁻¹ + U Z (r×r, LU with partial pivoting; indefinite
/// when rows leave).
struct LowRank {
    /// (row of A, σ/ρ ∈ {+1, −1}).
    rows: Vec<(usize, f64)>,
    /// Columns of Z = K'⁻¹Uᵀ, shared with the cache of the current K'.
    z: Vec<Rc<Vec<f64>>>,
    /// LU of W (row-major) and its pivots.
    lu: Vec<f64>,
    piv: Vec<usize>,
}

impl LowRank {
    /// The update for `rows`; columns K'⁻¹a_j missing from `cache` are
    /// computed (BLOCK per solve) and added. Returns the update and the
    /// number of new columns.
    fn new(
        qp: &QpProblem,
        fac: &Cholesky,
        rows: Vec<(usize, f64)>,
        rho: &[f64],
        cache: &mut HashMap<usize, Rc<Vec<f64>>>,
    ) -> (Option<LowRank>, usize) {
        let n = qp.n();
        let missing: Vec<usize> = rows
            .iter()
            .map(|&(j, _)| j)
            .filter(|j| !cache.contains_key(j))
            .collect();
        let mut buf = vec![];
        for chunk in missing.chunks(BLOCK) {
            buf.clear();
            buf.resize(n * chunk.len(), 0.0);
            for (c, &j) in chunk.iter().enumerate() {
                let (cols, v) = qp.a.row(j);
                for (&k, &a) in cols.iter().zip(v) {
                    buf[c * n + k] = a;
                }
            }
            fac.solve_many_in_place(&mut buf, chunk.len());
            for (c, &j) in chunk.iter().enumerate() {
                cache.insert(j, Rc::new(buf[c * n..(c + 1) * n].to_vec()));
            }
        }
        let z: Vec<Rc<Vec<f64>>> = rows.iter().map(|(j, _)| cache[j].clone()).collect();
        (Self::with_columns(qp, rows, z, rho), missing.len())
    }

    fn with_columns(
        qp: &QpProblem,
        rows: Vec<(usize, f64)>,
        z: Vec<Rc<Vec<f64>>>,
        rho: &[f64],
    ) -> Option<LowRank> {
        let r = rows.len();
        // W = Σ⁻¹ + U Z
        let mut w = vec![0.0; r * r];
        for (a, &(ja, sa)) in rows.iter().enumerate() {
            for b in 0..r {
                w[a * r + b] = qp.a.row_dot(ja, &z[b]);
            }
            w[a * r + a] += sa / rho[ja];
        }
        // symmetrise, then LU with partial pivoting
        for a in 0..r {
            for b in 0..a {
                let v = 0.5 * (w[a * r + b] + w[b * r + a]);
                w[a * r + b] = v;
                w[b * r + a] = v;
            }
        }
        let scale = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut piv: Vec<usize> = (0..r).collect();
        for k in 0..r {
            let p = (k..r).max_by(|&i, &j| w[i * r + k].abs().total_cmp(&w[j * r + k].abs()))?;
            if !(w[p * r + k].abs() > 1e-13 * scale) {
                return None; // K_J singular to working precision: refactor instead
            }
            if p != k {
                for c in 0..r {
                    w.swap(k * r + c, p * r + c);
                }
                piv.swap(k, p);
            }
            for i in k + 1..r {
                let f = w[i * r + k] / w[k * r + k];
                w[i * r + k] = f;
                for c in k + 1..r {
                    w[i * r + c] -= f * w[k * r + c];
                }
            }
        }
        Some(LowRank {
            rows,
            z,
            lu: w,
            piv,
        })
    }

    /// y ← y − Z W⁻¹ (U y), turning K'⁻¹b into K_J⁻¹b.
    fn correct(&self, qp: &QpProblem, y: &mut [f64]) {
        let n = y.len();
        let r = self.rows.len();
        let uy: Vec<f64> = self.rows.iter().map(|&(j, _)| qp.a.row_dot(j, y)).collect();
        let mut t: Vec<f64> = self.piv.iter().map(|&p| uy[p]).collect();
        for i in 0..r {
            for k in 0..i {
                t[i] -= self.lu[i * r + k] * t[k];
            }
        }
        for i in (0..r).rev() {
            for k in i + 1..r {
                t[i] -= self.lu[i * r + k] * t[k];
            }
            t[i] /= self.lu[i * r + i];
        }
        debug_assert!(self.z.iter().all(|z| z.len() == n));
        for (c, &tc) in t.iter().enumerate() {
            if tc != 0.0 {
                for (yi, zi) in y.iter_mut().zip(self.z[c].iter()) {
                    *yi -= tc * zi;
                }
            }
        }
    }
}

/// The state of the iteration.
struct Ssn<'a> {
    qp: &'a QpProblem,
    /// Where factorizations reuse the symbolic analysis of the same pattern.
    ws: &'a Workspace,
    /// Factor of C (+ springs) for the Schur-complement path, made on demand.
    fac: Option<Cholesky>,
    /// The augmented path: pattern of C + AᵀA, ρ_j per row, the factor of K_J.
    aug: Option<AugPattern>,
    rho: Vec<f64>,
    kfac: Option<Cholesky>,
    /// The working set J' that `kfac` was built for.
    kfac_set: Option<Vec<bool>>,
    /// Columns K'⁻¹a_j of the current K' (low-rank updates); looked up by
    /// row only, never iterated (the order of a HashMap is not deterministic).
    zcache: HashMap<usize, Rc<Vec<f64>>>,
    /// Time spent in sparse factorizations (reported, never used to decide).
    t_factor: f64,
    /// Counted costs of the two paths (module doc).
    costs: Costs,
    /// KKT solves done (Newton steps).
    steps_done: usize,
    /// Choose the path per step (else: augmented whenever it is available).
    auto: bool,
    /// Allow low-rank updates of K'.
    lowrank: bool,
    error: Option<QpError>,
    /// Orthonormal basis of ker C (k vectors of length n).
    r: Vec<Vec<f64>>,
    /// (A R)[i][l] = (A r_l)_i, m×k.
    ar: Vec<Vec<f64>>,
    /// e = Rᵀd.
    e: Vec<f64>,
    /// K⁻¹d.
    x0: Vec<f64>,
    /// Cached columns hⱼ = A K⁻¹aⱼ (length m) of the dual Hessian.
    h: Vec<Option<Vec<f64>>>,
    tol: f64,
    /// The stiffness scale c.
    cpar: f64,
    in_j: Vec<bool>,
    /// The last working set whose KKT system was solved.
    last_ok: Option<Vec<bool>>,
    history: HashSet<Vec<bool>>,
    single: bool,
    x: Vec<f64>,
    lam: Vec<f64>,
    solves: usize,
    /// Path of every KKT solve (true = augmented), refinements included.
    trace: Vec<bool>,
    /// Whether the last solve of the current J used the augmented path.
    last_aug: bool,
}

impl<'a> Ssn<'a> {
    fn new(
        qp: &'a QpProblem,
        r: Vec<Vec<f64>>,
        tol: f64,
        augmented: bool,
        ws: &'a Workspace,
    ) -> Ssn<'a> {
        let m = qp.m();
        let ar: Vec<Vec<f64>> = (0..m)
            .map(|i| r.iter().map(|rl| qp.a.row_dot(i, rl)).collect())
            .collect();
        let e: Vec<f64> = r.iter().map(|rl| dot(rl, &qp.d)).collect();
        let diag = qp.c.diag();
        let pos: Vec<f64> = diag.iter().copied().filter(|v| *v > 0.0).collect();
        let cpar = if pos.is_empty() {
            1.0
        } else {
            pos.iter().sum::<f64>() / pos.len() as f64
        };
        let aug = (augmented && m > 0).then(|| {
            let t = Instant::now();
            let p = AugPattern::new(qp);
            log::debug!(
                "ssn: pattern of C + AᵀA in {:.3} s",
                t.elapsed().as_secs_f64()
            );
            p
        });
        Ssn {
            qp,
            ws,
            fac: None,
            rho: if aug.is_some() {
                let cmax = norm_inf(&diag);
                vec![RHO_FACTOR * if cmax > 0.0 { cmax } else { 1.0 }; m]
            } else {
                vec![]
            },
            aug,
            kfac: None,
            kfac_set: None,
            zcache: HashMap::new(),
            t_factor: 0.0,
            // Until counted (Schur-only runs never need it): equal costs.
            costs: Costs {
                fac_c: 1.0,
                solve_c: 1.0,
                fac_k: 1.0,
                solve_k: 1.0,
            },
            steps_done: 0,
            auto: true,
            lowrank: true,
            error: None,
            r,
            ar,
            e,
            x: vec![0.0; qp.n()],
            x0: vec![],
            h: vec![None; m],
            tol,
            cpar,
            in_j: qp.g.iter().map(|&g| g <= 0.0).collect(),
            last_ok: None,
            history: HashSet::new(),
            single: false,
            lam: vec![0.0; m],
            solves: 0,
            trace: vec![],
            last_aug: false,
        }
    }

    /// Factor C (+ springs) and x0 = K⁻¹d for the Schur-complement path.
    fn ensure_dense(&mut self) -> Result<(), QpError> {
        if self.fac.is_none() {
            let t = Instant::now();
            let fac = self.ws.cholesky(&self.qp.c, &self.qp.kernel)?;
            self.t_factor += t.elapsed().as_secs_f64();
            self.x0 = fac.solve(&self.qp.d);
            self.solves += 1;
            self.fac = Some(fac);
        }
        Ok(())
    }

    /// The KKT system of `in_j` through K_J (module doc), warm-started from
    /// the last λ.
    fn kkt_solve_aug(&mut self, in_j: &[bool]) -> Option<(Vec<f64>, Vec<f64>)> {
        let mu0: Vec<f64> = (0..self.qp.m())
            .filter(|&i| in_j[i])
            .map(|j| self.lam[j])
            .collect();
        let (d, g) = (&self.qp.d, &self.qp.g);
        self.aug_solve(in_j, d, g, mu0)
    }

    /// The KKT system `Cx + A_Jᵀλ_J = d, A_J x = g_J` through
    /// K_J = C + A_JᵀΡA_J, CG on its Schur complement started from `mu0`
    /// (one value per row of J); None if K_J is not positive definite or CG
    /// does not converge. Returns (λ over all rows, x).
    fn aug_solve(
        &mut self,
        in_j: &[bool],
        d: &[f64],
        g: &[f64],
        mu0: Vec<f64>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let qp = self.qp;
        let jset: Vec<usize> = (0..qp.m()).filter(|&i| in_j[i]).collect();
        let n = qp.n();
        // Reuse K' = C + A_{J'}ᵀΡA_{J'} with a low-rank correction, or refactor.
        let mut update = None;
        if let (Some(fac), Some(jb), true) = (&self.kfac, &self.kfac_set, self.lowrank) {
            let changed: Vec<(usize, f64)> = (0..qp.m())
                .filter(|&i| jb[i] != in_j[i])
                .map(|i| (i, if in_j[i] { 1.0 } else { -1.0 }))
                .collect();
            let r = changed.len();
            let r_max = ((LOWRANK_BYTES / (8.0 * n.max(1) as f64)) as usize).min(LOWRANK_MAX);
            if r == 0 {
                update = Some(None);
            } else if r <= r_max && {
                let new_cols = changed
                    .iter()
                    .filter(|(j, _)| !self.zcache.contains_key(j))
                    .count();
                new_cols as f64 * self.costs.col_k() <= 0.5 * self.costs.fac_k
            } {
                let (lr, new_cols) = LowRank::new(qp, fac, changed, &self.rho, &mut self.zcache);
                self.solves += new_cols;
                update = lr.map(Some);
            }
        }
        let update = match update {
            Some(u) => u,
            None => {
                let aug = self.aug.as_mut()?;
                aug.k.data.copy_from_slice(&aug.base);
                for &j in &jset {
                    for &(pos, v) in &aug.rows[j] {
                        aug.k.data[pos] += self.rho[j] * v;
                    }
                }
                self.kfac = None; // free the old factor first
                self.kfac_set = None;
                self.zcache.clear();
                let t = Instant::now();
                let fac = self.ws.cholesky(&aug.k, &[]).ok();
                self.t_factor += t.elapsed().as_secs_f64();
                self.kfac = Some(fac?);
                self.kfac_set = Some(in_j.to_vec());
                None
            }
        };
        let fac = self.kfac.as_ref().expect("factor of K'");
        // x ← K_J⁻¹x: the factor of K', then the Woodbury correction.
        let kinv = |x: &mut Vec<f64>| {
            fac.solve_in_place(x);
            if let Some(lr) = &update {
                lr.correct(qp, x);
            }
        };
        // y0 = K⁻¹(d + A_JᵀΡg_J − A_Jᵀμ0): then A_J y0 − g_J is the residual
        // of S μ = A_J K⁻¹(d + A_JᵀΡg_J) − g_J at μ0.
        let mut y0 = d.to_vec();
        for (&j, &m0) in jset.iter().zip(&mu0) {
            let (c, v) = qp.a.row(j);
            for (&k, &a) in c.iter().zip(v) {
                y0[k] += a * (self.rho[j] * g[j] - m0);
            }
        }
        kinv(&mut y0);
        self.solves += 1;
        // s(μ) = K⁻¹A_Jᵀμ (n-vector), S μ = A_J s(μ).
        let mut solves = 0usize;
        let mut apply = |mu: &[f64]| -> Vec<f64> {
            let mut t = vec![0.0; n];
            for (&j, &m) in jset.iter().zip(mu) {
                let (c, v) = qp.a.row(j);
                for (&k, &a) in c.iter().zip(v) {
                    t[k] += a * m;
                }
            }
            kinv(&mut t);
            solves += 1;
            t
        };
        let aj = |t: &[f64]| -> Vec<f64> { jset.iter().map(|&j| qp.a.row_dot(j, t)).collect() };
        // CG on S δ = r0 = A_J y0 − g_J; μ = μ0 + δ, x = y0 − K⁻¹A_Jᵀδ.
        let ay0 = aj(&y0);
        let mut r: Vec<f64> = ay0.iter().zip(&jset).map(|(v, &j)| v - g[j]).collect();
        // Scale of the terms that cancel in A_J x − g_J: ‖|A_J||y0|‖ + ‖g_J‖.
        let abs_ay: Vec<f64> = jset
            .iter()
            .map(|&j| {
                let (c, v) = qp.a.row(j);
                c.iter()
                    .zip(v)
                    .map(|(&k, &a)| (a * y0[k]).abs())
                    .sum::<f64>()
            })
            .collect();
        let gj: Vec<f64> = jset.iter().map(|&j| g[j]).collect();
        let bnorm = norm(&abs_ay) + norm(&gj);
        let mut mu = mu0;
        let mut z = vec![0.0; n];
        let goal = (1e-2 * self.tol).min(1e-12) * bnorm.max(f64::MIN_POSITIVE);
        let mut p = r.clone();
        let mut rr = dot(&r, &r);
        let mut ok = rr.sqrt() <= goal || jset.is_empty();
        for _ in 0..AL_MAX_CG {
            if ok {
                break;
            }
            let sp_full = apply(&p);
            let sp = aj(&sp_full);
            let psp = dot(&p, &sp);
            if !(psp > 0.0) {
                break;
            }
            let alpha = rr / psp;
            for i in 0..mu.len() {
                mu[i] += alpha * p[i];
                r[i] -= alpha * sp[i];
            }
            for (zi, si) in z.iter_mut().zip(&sp_full) {
                *zi += alpha * si;
            }
            let rr_new = dot(&r, &r);
            let beta = rr_new / rr;
            rr = rr_new;
            if rr.sqrt() <= goal {
                ok = true;
                break;
            }
            for (pi, ri) in p.iter_mut().zip(&r) {
                *pi = ri + beta * *pi;
            }
        }
        self.solves += solves;
        log::debug!(
            "ssn: |J| = {}, K' {}, CG {} solves, ‖r‖/‖b‖ = {:.2e}",
            jset.len(),
            match &update {
                Some(u) => format!("+ rank-{} update", u.rows.len()),
                None => "factored".into(),
            },
            solves,
            rr.sqrt() / bnorm.max(f64::MIN_POSITIVE)
        );
        if !ok {
            log::debug!("ssn: CG on the augmented Schur complement did not converge; falling back");
            return None;
        }
        // x = y0 − K⁻¹A_Jᵀμ
        let x: Vec<f64> = y0.iter().zip(&z).map(|(y, z)| y - z).collect();
        // λ_J = μ + Ρ(A_J x − g_J): the first block row K_J x + A_Jᵀμ =
        // d + A_JᵀΡg_J is Cx − d + A_Jᵀλ = 0 exactly for this λ, whatever
        // gap error CG and the rounding in K_J⁻¹ left (module doc).
        let mut lam = vec![0.0; qp.m()];
        for (&j, &m) in jset.iter().zip(&mu) {
            lam[j] = m + self.rho[j] * (qp.a.row_dot(j, &x) - g[j]);
        }
        if lam.iter().chain(&x).any(|v| !v.is_finite()) {
            return None;
        }
        Some((lam, x))
    }

    /// Compute the missing columns hⱼ, j ∈ `js`, BLOCK right-hand sides at a time.
    fn columns(&mut self, js: &[usize]) {
        let n = self.qp.n();
        let missing: Vec<usize> = js
            .iter()
            .copied()
            .filter(|&j| self.h[j].is_none())
            .collect();
        let mut buf = vec![];
        for chunk in missing.chunks(BLOCK) {
            buf.clear();
            buf.resize(n * chunk.len(), 0.0);
            for (c, &j) in chunk.iter().enumerate() {
                let (cols, v) = self.qp.a.row(j);
                for (&k, &a) in cols.iter().zip(v) {
                    buf[c * n + k] = a;
                }
            }
            self.fac
                .as_ref()
                .expect("ensure_dense before columns")
                .solve_many_in_place(&mut buf, chunk.len());
            self.solves += chunk.len();
            for (c, &j) in chunk.iter().enumerate() {
                self.h[j] = Some(self.qp.a.mul(&buf[c * n..(c + 1) * n]));
            }
        }
    }

    /// The cost model of the module doc (counts only): true to take the
    /// Schur path for `in_j`.
    fn prefer_schur(&self, in_j: &[bool]) -> bool {
        if !self.auto {
            return false;
        }
        let c = &self.costs;
        let nj = in_j.iter().filter(|b| **b).count() as f64;
        if self.fac.is_none() && self.kfac.is_none() {
            // Nothing factored yet: both paths need one factorization.
            return c.fac_c + nj * c.col_c() <= c.fac_k + 6.0 * c.solve_k;
        }
        let new_rows = in_j
            .iter()
            .zip(&self.h)
            .filter(|(j, h)| **j && h.is_none())
            .count();
        let schur = if self.fac.is_some() { 0.0 } else { c.fac_c } + new_rows as f64 * c.col_c();
        // The augmented step: a refactor, or a low-rank update of K' when few
        // rows changed since it was factored.
        let changed = self.kfac_set.as_ref().map_or(usize::MAX, |jb| {
            (0..jb.len())
                .filter(|&i| jb[i] != in_j[i] && !self.zcache.contains_key(&i))
                .count()
        });
        let aug_fac = if changed <= LOWRANK_MAX {
            c.fac_k.min(changed as f64 * c.col_k())
        } else {
            c.fac_k
        };
        // steps_done counts this step: k = 1 in the second, 3 from the third.
        let k = if self.steps_done >= 3 { 3.0 } else { 1.0 };
        schur <= k * (aug_fac + 6.0 * c.solve_k)
    }

    /// Solve the KKT system on `in_j` (the path by the cost model); None if
    /// it is singular. Returns (λ over all rows, x).
    fn kkt_solve(&mut self, in_j: &[bool]) -> Option<(Vec<f64>, Vec<f64>)> {
        self.steps_done += 1;
        if self.aug.is_some() && !self.prefer_schur(in_j) {
            if let Some(s) = self.kkt_solve_aug(in_j) {
                self.trace.push(true);
                self.last_aug = true;
                return Some(s);
            }
        }
        self.kfac = None;
        self.kfac_set = None;
        self.zcache.clear();
        let (d, g) = (&self.qp.d, &self.qp.g);
        let s = self.schur_solve(in_j, d, g);
        if s.is_some() {
            self.trace.push(false);
            self.last_aug = false;
        }
        s
    }

    /// The KKT system `Cx + A_Jᵀλ_J = d, A_J x = g_J` by the Schur complement
    /// on the factor of C; None if it is singular (or C cannot be factored:
    /// then `error` is set).
    fn schur_solve(&mut self, in_j: &[bool], d: &[f64], g: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        if let Err(e) = self.ensure_dense() {
            self.error = Some(e);
            return None;
        }
        let qp = self.qp;
        // K⁻¹d and e = Rᵀd: cached for the problem's own d.
        let own = std::ptr::eq(d.as_ptr(), qp.d.as_ptr());
        let x0 = if own {
            self.x0.clone()
        } else {
            self.solves += 1;
            self.fac.as_ref().expect("factored").solve(d)
        };
        let e: Vec<f64> = if own {
            self.e.clone()
        } else {
            self.r.iter().map(|rl| dot(rl, d)).collect()
        };
        let jset: Vec<usize> = (0..qp.m()).filter(|&i| in_j[i]).collect();
        self.columns(&jset);
        let nj = jset.len();
        let k = self.r.len();
        let hs: Vec<&Vec<f64>> = jset
            .iter()
            .map(|&j| self.h[j].as_ref().expect("column cached"))
            .collect();
        // S_J (symmetrised) and its factor.
        let mut s = vec![0.0; nj * nj];
        for (a, &ja) in jset.iter().enumerate() {
            for b in 0..=a {
                let v = 0.5 * (hs[b][ja] + hs[a][jset[b]]);
                s[a * nj + b] = v;
                s[b * nj + a] = v;
            }
        }
        if !chol_factor(&mut s, nj, PIVOT_S) {
            return None;
        }
        // w = S⁻¹(A_J K⁻¹ d − g_J)
        let mut w: Vec<f64> = jset.iter().map(|&j| qp.a.row_dot(j, &x0) - g[j]).collect();
        chol_solve(&s, nj, &mut w);
        let mut alpha = vec![0.0; k];
        if k > 0 {
            // Y = S⁻¹ G_Jᵀ (columns l), F = G_J Y.
            let mut y: Vec<Vec<f64>> = Vec::with_capacity(k);
            for l in 0..k {
                let mut col: Vec<f64> = jset.iter().map(|&j| self.ar[j][l]).collect();
                chol_solve(&s, nj, &mut col);
                y.push(col);
            }
            let mut f = vec![0.0; k * k];
            for a in 0..k {
                for b in 0..k {
                    let v: f64 = jset
                        .iter()
                        .enumerate()
                        .map(|(t, &j)| self.ar[j][a] * y[b][t])
                        .sum();
                    f[a * k + b] = v;
                }
            }
            for a in 0..k {
                for b in 0..a {
                    let v = 0.5 * (f[a * k + b] + f[b * k + a]);
                    f[a * k + b] = v;
                    f[b * k + a] = v;
                }
            }
            if !chol_factor(&mut f, k, PIVOT_F) {
                return None;
            }
            // F α = e − G_J w
            for (l, al) in alpha.iter_mut().enumerate() {
                let gw: f64 = jset
                    .iter()
                    .enumerate()
                    .map(|(t, &j)| self.ar[j][l] * w[t])
                    .sum();
                *al = e[l] - gw;
            }
            chol_solve(&f, k, &mut alpha);
            for (l, yl) in y.iter().enumerate() {
                for (wt, yt) in w.iter_mut().zip(yl) {
                    *wt += alpha[l] * yt;
                }
            }
        }
        let mut lam = vec![0.0; qp.m()];
        for (t, &j) in jset.iter().enumerate() {
            lam[j] = w[t];
        }
        // x = K⁻¹(d − A_Jᵀλ_J) + Rα: one solve.
        let mut x = d.to_vec();
        for (t, &j) in jset.iter().enumerate() {
            let (cols, v) = qp.a.row(j);
            for (&c, &a) in cols.iter().zip(v) {
                x[c] -= w[t] * a;
            }
        }
        self.fac
            .as_ref()
            .expect("ensure_dense before kkt_solve")
            .solve_in_place(&mut x);
        self.solves += 1;
        for (rl, &al) in self.r.iter().zip(&alpha) {
            for (xi, ri) in x.iter_mut().zip(rl) {
                *xi += al * ri;
            }
        }
        if lam.iter().chain(&x).any(|v| !v.is_finite()) {
            return None;
        }
        Some((lam, x))
    }

    /// The correction of (x, λ) on J = `in_j` for the residuals
    /// (d − Cx − A_Jᵀλ_J, g_J − A_J x), on the path of the last solve.
    fn correction(&mut self, aug: bool) -> Option<(Vec<f64>, Vec<f64>)> {
        let qp = self.qp;
        let mut r1 = qp.c.mul(&self.x);
        for (ri, di) in r1.iter_mut().zip(&qp.d) {
            *ri = di - *ri;
        }
        let lam_j: Vec<f64> = (0..qp.m())
            .map(|i| if self.in_j[i] { self.lam[i] } else { 0.0 })
            .collect();
        let mut atl = vec![0.0; qp.n()];
        qp.a.mul_t_add(&lam_j, &mut atl);
        for (ri, ai) in r1.iter_mut().zip(&atl) {
            *ri -= ai;
        }
        let r2: Vec<f64> = (0..qp.m())
            .map(|i| {
                if self.in_j[i] {
                    qp.g[i] - qp.a.row_dot(i, &self.x)
                } else {
                    0.0
                }
            })
            .collect();
        let in_j = self.in_j.clone();
        let nj = in_j.iter().filter(|b| **b).count();
        let s = if aug {
            self.aug_solve(&in_j, &r1, &r2, vec![0.0; nj])
        } else {
            self.schur_solve(&in_j, &r1, &r2)
        };
        if s.is_some() {
            self.trace.push(aug);
        }
        s
    }

    /// Measure the certificate of (x, λ) and refine the KKT solve of J until
    /// it meets tol (module doc). Returns the final certificate.
    fn refine(&mut self) -> f64 {
        let qp = self.qp;
        let mut cert = certificate(qp, &self.x, &self.lam);
        let mut fresh_schur = false;
        loop {
            let mut steps = 0;
            while cert > self.tol && steps < REFINE_MAX {
                steps += 1;
                let Some((dl, dx)) = self.correction(self.last_aug) else {
                    break;
                };
                let x: Vec<f64> = self.x.iter().zip(&dx).map(|(a, b)| a + b).collect();
                let lam: Vec<f64> = self.lam.iter().zip(&dl).map(|(a, b)| a + b).collect();
                let c = certificate(qp, &x, &lam);
                log::debug!("ssn: refinement: KKT residual {cert:.2e} → {c:.2e}");
                if c.is_nan() || c >= cert {
                    break;
                }
                let improved = c < 0.5 * cert;
                (self.x, self.lam, cert) = (x, lam, c);
                if !improved {
                    break;
                }
            }
            // Still far from tol on the augmented path: recompute on the
            // Schur path (one factor of C, exact elimination), once.
            if cert <= CERT_TARGET.min(1e2 * self.tol) || !self.last_aug || fresh_schur {
                return cert;
            }
            fresh_schur = true;
            log::debug!(
                "ssn: KKT residual {cert:.2e} on the augmented path; recomputing on the Schur path"
            );
            let in_j = self.in_j.clone();
            let (d, g) = (&qp.d, &qp.g);
            match self.schur_solve(&in_j, d, g) {
                Some((lam, x)) => {
                    self.trace.push(false);
                    self.last_aug = false;
                    let c = certificate(qp, &x, &lam);
                    if c < cert {
                        (self.x, self.lam, cert) = (x, lam, c);
                    }
                }
                None => return cert,
            }
        }
    }

    /// The complementarity function F = λ + c(Ax − g), the threshold τ and
    /// the relative residual of the complementarity equation.
    fn predict(&self) -> (Vec<f64>, f64, f64) {
        let qp = self.qp;
        let m = qp.m();
        let c = self.cpar;
        let s: Vec<f64> = (0..m).map(|i| qp.a.row_dot(i, &self.x) - qp.g[i]).collect();
        let scale = norm_inf(&self.lam) + c * norm_inf(&self.x).max(norm_inf(&qp.g));
        let scale = if scale > 0.0 { scale } else { 1.0 };
        let tau = self.tol * scale;
        let fval: Vec<f64> = (0..m).map(|i| self.lam[i] + c * s[i]).collect();
        let residual = (0..m)
            .map(|i| (self.lam[i] - fval[i].max(0.0)).abs())
            .fold(0.0f64, f64::max)
            / scale;
        (fval, tau, residual)
    }

    fn n_active(&self) -> usize {
        self.in_j.iter().filter(|b| **b).count()
    }

    fn record(&self, residual: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual,
            active: self.n_active(),
            inner: self.solves,
        }
    }

    fn into_result(
        self,
        status: Status,
        iterations: usize,
        log: Vec<IterRecord>,
        timings: Vec<(String, f64)>,
    ) -> Output {
        Output {
            x: self.x,
            lambda: self.lam,
            active: self.in_j,
            status,
            iterations,
            inner_iterations: self.solves,
            log,
            timings,
        }
    }
}

impl Iterative for Ssn<'_> {
    fn step(&mut self) -> Step {
        let m = self.qp.m();
        // Candidate working sets: J, J ∪ J_prev, all rows.
        let mut cands = vec![self.in_j.clone()];
        if let Some(prev) = &self.last_ok {
            cands.push(self.in_j.iter().zip(prev).map(|(a, b)| *a || *b).collect());
        }
        cands.push(vec![true; m]);
        cands.dedup();
        let mut solved = None;
        for cand in cands {
            if let Some(s) = self.kkt_solve(&cand) {
                solved = Some((cand, s));
                break;
            }
        }
        let Some((jused, (lam, x))) = solved else {
            return Step::Done(
                Status::Failed(
                    "ssn: the KKT system is singular even with every contact row active: a rigid motion of a \
                     floating body is not restrained by the contact rows (A·R rank deficient) or the contact \
                     rows are linearly dependent"
                        .into(),
                ),
                self.record(f64::NAN),
            );
        };
        self.in_j = jused.clone();
        self.last_ok = Some(jused.clone());
        self.history.insert(jused.clone());
        self.lam = lam;
        self.x = x;

        let (mut fval, mut tau, mut residual) = self.predict();
        let mut new_j: Vec<bool> = fval.iter().map(|&f| f > tau).collect();
        if new_j == self.in_j {
            // J has settled: certify (x, λ), refining the solve if needed.
            let cert = self.refine();
            if cert.is_nan() || cert > CERT_TARGET.max(self.tol) {
                return Step::Done(
                    Status::Failed(format!(
                        "ssn: KKT residual {cert:.2e} after refinement (target {CERT_TARGET:e})"
                    )),
                    self.record(residual),
                );
            }
            (fval, tau, residual) = self.predict();
            new_j = fval.iter().map(|&f| f > tau).collect();
            if new_j == self.in_j {
                return Step::Done(Status::Converged, self.record(residual));
            }
            log::debug!("ssn: the refined solution moves J; continuing");
        }
        // Growth limit: at most max(BLOCK, |J|) rows enter, the most violated.
        let size = self.in_j.iter().filter(|&&b| b).count();
        let mut entering: Vec<usize> = (0..m).filter(|&i| new_j[i] && !self.in_j[i]).collect();
        let cap = GROW_MIN.max(size);
        if entering.len() > cap {
            entering.sort_unstable_by(|&a, &b| fval[b].total_cmp(&fval[a]).then(a.cmp(&b)));
            for &i in &entering[cap..] {
                new_j[i] = false;
            }
        }
        if !self.single && self.history.contains(&new_j) {
            log::debug!("ssn: a working set repeats; switching to single changes");
            self.single = true;
        }
        if self.single {
            // One change: the most negative λ in J or the most violated row outside J.
            let mut drop = (0.0f64, usize::MAX);
            let mut add = (0.0f64, usize::MAX);
            for (i, (&f, &inj)) in fval.iter().zip(&self.in_j).enumerate() {
                if inj && f <= tau && -f >= drop.0 {
                    drop = (-f, i);
                }
                if !inj && f > tau && f > add.0 {
                    add = (f, i);
                }
            }
            new_j = self.in_j.clone();
            if drop.1 != usize::MAX && (add.1 == usize::MAX || drop.0 >= add.0) {
                new_j[drop.1] = false;
            } else if add.1 != usize::MAX {
                new_j[add.1] = true;
            }
        }
        log::debug!(
            "ssn: step {}: |J| = {}, next |J| = {} ({} enter, {} leave), residual {:.2e}",
            self.history.len(),
            self.in_j.iter().filter(|&&b| b).count(),
            new_j.iter().filter(|&&b| b).count(),
            new_j
                .iter()
                .zip(&self.in_j)
                .filter(|(n, o)| **n && !**o)
                .count(),
            new_j
                .iter()
                .zip(&self.in_j)
                .filter(|(n, o)| !**n && **o)
                .count(),
            residual
        );
        self.in_j = new_j;
        Step::Continue(self.record(residual))
    }
}

/// An orthonormal basis of span(kernel) (modified Gram–Schmidt, dependent
/// vectors dropped), after checking that every vector is in ker C.
pub(crate) fn orthonormal_kernel(c: &Csr, kernel: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, QpError> {
    let cmax = norm_inf(&c.diag()).max(f64::MIN_POSITIVE);
    let mut out: Vec<Vec<f64>> = vec![];
    for (i, z) in kernel.iter().enumerate() {
        let nz = norm(z);
        if !nz.is_finite() || nz <= 0.0 {
            return Err(QpError::BadParameter(format!(
                "kernel vector {i} is zero or not finite"
            )));
        }
        let cz = c.mul(z);
        if norm(&cz) > 1e-8 * cmax * nz {
            return Err(QpError::BadParameter(format!(
                "kernel vector {i} is not in ker C (‖Cz‖/(max diag C·‖z‖) = {:.3e})",
                norm(&cz) / (cmax * nz)
            )));
        }
        let mut v: Vec<f64> = z.iter().map(|a| a / nz).collect();
        for _ in 0..2 {
            for q in &out {
                let p = dot(&v, q);
                for (a, b) in v.iter_mut().zip(q) {
                    *a -= p * b;
                }
            }
        }
        let nv = norm(&v);
        if nv > 1e-10 {
            v.iter_mut().for_each(|a| *a /= nv);
            out.push(v);
        }
    }
    Ok(out)
}

/// In-place dense Cholesky A = LLᵀ of the n×n row-major SPD matrix `a` (the
/// lower triangle receives L). False if a pivot is ≤ `rel` times the original
/// diagonal entry of its row (singular to working precision) or not finite.
pub(crate) fn chol_factor(a: &mut [f64], n: usize, rel: f64) -> bool {
    for j in 0..n {
        let orig = a[j * n + j];
        let mut d = orig;
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !d.is_finite() || d <= rel * orig.abs() {
            return false;
        }
        let l = d.sqrt();
        a[j * n + j] = l;
        for i in j + 1..n {
            let mut v = a[i * n + j];
            for k in 0..j {
                v -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = v / l;
        }
    }
    true
}

/// b ← L⁻¹ b
pub(crate) fn chol_forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut v = b[i];
        for k in 0..i {
            v -= l[i * n + k] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
}

/// b ← L⁻ᵀ b
pub(crate) fn chol_backward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= l[k * n + i] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
}

/// b ← (LLᵀ)⁻¹ b
pub(crate) fn chol_solve(l: &[f64], n: usize, b: &mut [f64]) {
    chol_forward(l, n, b);
    chol_backward(l, n, b);
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::qp::executor::Executor;
    use crate::qp::{kkt, precond::PrecondKind, primal::cgc, run_direct, SolveOptions};

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
        QpProblem { c, d, a, g, kernel }
    }

    pub(crate) fn reference(qp: &QpProblem) -> Output {
        let opts = {
            let mut o = SolveOptions::default();
            o.settings.tol = 1e-12;
            o.settings.cgc.preconditioner = PrecondKind::Cholesky;
            o
        };
        let r = run_direct(cgc::solve, qp, &opts).expect("cgc");
        assert!(r.status.converged(), "cgc: {:?}", r.status);
        r
    }

    /// x agrees to `rel`, active sets equal, KKT ≤ 1e-8, λ ≥ 0.
    pub(crate) fn compare(qp: &QpProblem, r: &Output, refr: &Output, rel: f64) {
        assert!(r.status.converged(), "{:?}", r.status);
        let diff: Vec<f64> = r.x.iter().zip(&refr.x).map(|(a, b)| a - b).collect();
        let e = norm(&diff) / norm(&refr.x).max(1e-300);
        assert!(e <= rel, "x differs: {e:e}");
        assert_eq!(r.active, refr.active, "active sets differ");
        let k = kkt::residuals(qp, &r.x, &r.lambda);
        assert!(k.max() <= 1e-8, "{k:?}");
        assert!(r.lambda.iter().all(|&l| l >= 0.0), "λ < 0");
        let ldiff: Vec<f64> = r
            .lambda
            .iter()
            .zip(&refr.lambda)
            .map(|(a, b)| a - b)
            .collect();
        assert!(
            norm(&ldiff) <= 1e-6 * norm(&refr.lambda).max(1e-300),
            "λ differs"
        );
    }

    fn opts() -> SolveOptions {
        {
            let mut o = SolveOptions::default();
            o.settings.tol = 1e-12;
            o
        }
    }

    fn nontrivial(r: &Output) {
        let na = r.active.iter().filter(|b| **b).count();
        assert!(
            na > 0 && na < r.active.len(),
            "active {na} of {}",
            r.active.len()
        );
        // some active row with g > 0 would be nice but is not required
    }

    #[test]
    fn dense_cholesky() {
        let a0 = vec![4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let mut l = a0.clone();
        assert!(chol_factor(&mut l, 3, 1e-12));
        let mut b = vec![1.0, -2.0, 0.5];
        chol_solve(&l, 3, &mut b);
        for i in 0..3 {
            let v: f64 = (0..3).map(|j| a0[i * 3 + j] * b[j]).sum();
            assert!((v - [1.0, -2.0, 0.5][i]).abs() < 1e-14);
        }
        let mut sing = vec![1.0, 1.0, 1.0, 1.0];
        assert!(!chol_factor(&mut sing, 2, 1e-12));
    }

    #[test]
    fn coercive_agrees_with_cgc() {
        let qp = two_blocks(9, 5, false);
        let refr = reference(&qp);
        nontrivial(&refr);
        let r = run_direct(solve, &qp, &opts()).unwrap();
        compare(&qp, &r, &refr, 1e-6);
        assert!(r.iterations <= 15, "{} iterations", r.iterations);
        assert!(r.timings.iter().any(|(n, _)| n == "factor"));
    }

    #[test]
    fn semicoercive_agrees_with_cgc() {
        let qp = two_blocks(9, 5, true);
        assert_eq!(qp.kernel.len(), 1);
        let cz = qp.c.mul(&qp.kernel[0]);
        assert!(
            norm(&cz) <= 1e-12 * norm(&qp.kernel[0]),
            "the kernel vector should be in ker C"
        );
        let refr = reference(&qp);
        nontrivial(&refr);
        let r = run_direct(solve, &qp, &opts()).unwrap();
        compare(&qp, &r, &refr, 1e-6);
        assert!(r.iterations <= 15, "{} iterations", r.iterations);
    }

    /// All gaps open: the glued start J is empty, which leaves the floating
    /// block free; J is enlarged to all rows and the iteration proceeds.
    #[test]
    fn semicoercive_empty_start_is_enlarged() {
        let mut qp = two_blocks(9, 5, true);
        qp.g.iter_mut().for_each(|g| *g += 1e-3);
        let refr = reference(&qp);
        let r = run_direct(solve, &qp, &opts()).unwrap();
        compare(&qp, &r, &refr, 1e-6);
    }

    /// The anti-cycling fallback (single changes) on its own converges too.
    #[test]
    fn single_change_fallback_converges() {
        for (floating, augmented) in [(false, true), (true, true), (false, false), (true, false)] {
            let qp = two_blocks(9, 5, floating);
            let refr = reference(&qp);
            let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
            let ws_st = Workspace::new();
            let mut st = Ssn::new(&qp, r, 1e-12, augmented, &ws_st);
            st.single = true;
            let mut exec = Executor::new(200, None);
            let (status, iters) = exec.run(&mut st);
            let res = st.into_result(status, iters, exec.log, vec![]);
            compare(&qp, &res, &refr, 1e-6);
        }
    }

    /// The augmented-factor path and the Schur-complement path give the same
    /// answer, and the augmented path refactors on one symbolic analysis.
    #[test]
    fn augmented_and_schur_paths_agree() {
        for floating in [false, true] {
            let qp = two_blocks(12, 6, floating);
            let refr = reference(&qp);
            let ws = Workspace::new();
            let (_, s0) = ws.reuse_counts();
            let a = solve_traced(&qp, &mut Context::new(&opts(), &ws), Path::Refactor)
                .unwrap()
                .0;
            let (_, s1) = ws.reuse_counts();
            let u = solve_with(&qp, &opts(), Path::Augmented).unwrap();
            compare(&qp, &u, &refr, 1e-6);
            assert_eq!(a.active, u.active);
            let b = solve_with(&qp, &opts(), Path::Schur).unwrap();
            let c = solve_with(&qp, &opts(), Path::Auto).unwrap();
            compare(&qp, &c, &refr, 1e-6);
            assert_eq!(a.active, c.active);
            compare(&qp, &a, &refr, 1e-6);
            compare(&qp, &b, &refr, 1e-6);
            assert_eq!(a.active, b.active);
            let dx =
                a.x.iter()
                    .zip(&b.x)
                    .map(|(u, v)| (u - v).abs())
                    .fold(0.0, f64::max);
            assert!(dx <= 1e-8 * norm_inf(&b.x), "{dx}");
            if a.iterations > 1 {
                assert!(
                    s1 > s0,
                    "no symbolic reuse over {} iterations",
                    a.iterations
                );
            }
            // A handful of solves per Newton step, not one per active row.
            assert!(
                a.inner_iterations <= 12 * a.iterations,
                "{} solves",
                a.inner_iterations
            );
        }
    }

    /// The Woodbury update of K' (rows leaving and entering J) solves the
    /// KKT system of the new J exactly as a fresh factorization does.
    #[test]
    fn low_rank_update_matches_refactorization() {
        for floating in [false, true] {
            let qp = two_blocks(10, 6, floating);
            let m = qp.m();
            let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
            let j1: Vec<bool> = vec![true; m];
            let mut j2 = j1.clone();
            j2[0] = false;
            j2[m / 2] = false;
            let ws_st = Workspace::new();
            let mut st = Ssn::new(&qp, r.clone(), 1e-12, true, &ws_st);
            st.kkt_solve_aug(&j1).expect("J1");
            st.costs.fac_k = 1e300; // make the update look cheap
            let solves = st.solves;
            let (l_up, x_up) = st.kkt_solve_aug(&j2).expect("J2 by update");
            assert!(st.kfac_set.as_ref().unwrap() == &j1, "K' was refactored");
            assert!(st.solves > solves);
            let ws_fresh = Workspace::new();
            let mut fresh = Ssn::new(&qp, r, 1e-12, true, &ws_fresh);
            let (l_ref, x_ref) = fresh.kkt_solve_aug(&j2).expect("J2 fresh");
            let dx = x_up
                .iter()
                .zip(&x_ref)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let dl = l_up
                .iter()
                .zip(&l_ref)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(dx <= 1e-8 * norm_inf(&x_ref), "x: {dx}");
            assert!(dl <= 1e-6 * norm_inf(&l_ref), "λ: {dl}");
            assert_eq!(l_up[0], 0.0);
            // Now back to J1: the update is empty (r = 0), the factor is K' itself.
            let (_, x_back) = st.kkt_solve_aug(&j1).expect("J1 again");
            let ws1 = Workspace::new();
            let mut fresh1 = Ssn::new(
                &qp,
                orthonormal_kernel(&qp.c, &qp.kernel).unwrap(),
                1e-12,
                true,
                &ws1,
            );
            let (_, x1) = fresh1.kkt_solve_aug(&j1).unwrap();
            let d1 = x_back
                .iter()
                .zip(&x1)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(d1 <= 1e-8 * norm_inf(&x1), "{d1}");
        }
    }

    #[test]
    fn semicoercive_without_any_contact_row_fails_cleanly() {
        let mut qp = two_blocks(5, 3, true);
        qp.a = Csr::zeros(0, qp.n());
        qp.g.clear();
        let r = run_direct(solve, &qp, &opts()).unwrap();
        assert!(matches!(r.status, Status::Failed(_)), "{:?}", r.status);
    }

    #[test]
    fn no_contact_rows_coercive() {
        let mut qp = two_blocks(5, 3, false);
        qp.a = Csr::zeros(0, qp.n());
        qp.g.clear();
        let r = run_direct(solve, &qp, &opts()).unwrap();
        assert!(r.status.converged());
        let k = kkt::residuals(&qp, &r.x, &r.lambda);
        assert!(k.max() <= 1e-10, "{k:?}");
    }

    #[test]
    fn wrong_kernel_is_rejected() {
        let mut qp = two_blocks(5, 3, true);
        qp.kernel[0][0] += 1.0;
        assert!(matches!(
            run_direct(solve, &qp, &opts()),
            Err(QpError::BadParameter(_))
        ));
    }

    pub(crate) fn example(name: &str) -> crate::pipeline::Prepared {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("meshes/{name}.toml"));
        crate::pipeline::prepare(&path, false).unwrap_or_else(|e| panic!("{name}: {e}"))
    }

    /// A string (n interior nodes, both ends fixed) pressed by a uniform
    /// load onto a parabolic obstacle touching it at the middle node: the
    /// 1D analogue of Hertz. With only the middle row glued, the first
    /// solve penetrates far more rows than end in contact; the growth limit
    /// (at most max(GROW_MIN, |J|) rows enter per step) keeps the Schur
    /// path from computing a column for each of them.
    fn string_on_parabola(n: usize) -> QpProblem {
        let h = 1.0 / (n + 1) as f64;
        let mut trip = vec![];
        for i in 0..n {
            trip.push((i, i, 2.0 / h));
            if i > 0 {
                trip.push((i, i - 1, -1.0 / h));
                trip.push((i - 1, i, -1.0 / h));
            }
        }
        let c = Csr::from_triplets(n, n, &trip);
        let d = vec![-h; n];
        // −x_i ≤ g_i with g_i = κ(s_i − ½)², zero at the middle node.
        let mid = n / 2;
        let s_of = |i: usize| (i + 1) as f64 * h;
        let a = Csr::from_triplets(n, n, &(0..n).map(|i| (i, i, -1.0)).collect::<Vec<_>>());
        let g = (0..n)
            .map(|i| 4.0 * (s_of(i) - s_of(mid)).powi(2))
            .collect();
        QpProblem {
            c,
            d,
            a,
            g,
            kernel: vec![],
        }
    }

    #[test]
    fn growth_limit_computes_few_columns() {
        let qp = string_on_parabola(2001);
        let refr = run_direct(crate::qp::dual::mprgp::solve, &qp, &opts()).unwrap();
        assert!(refr.status.converged(), "mprgp: {:?}", refr.status);
        let r = solve_with(&qp, &opts(), Path::Schur).unwrap();
        compare(&qp, &r, &refr, 1e-6);
        let active = r.active.iter().filter(|&&b| b).count();
        // Penetrated after the first solve: every row where the string held
        // at its middle node (x_mid = 0) is below the obstacle.
        let x0 = {
            let k = Cholesky::new(&qp.c, &[]).unwrap();
            let y = k.solve(&qp.d);
            let mut e = vec![0.0; qp.n()];
            e[qp.n() / 2] = 1.0;
            let z = k.solve(&e);
            let t = y[qp.n() / 2] / z[qp.n() / 2];
            y.iter()
                .zip(&z)
                .map(|(a, b)| a - t * b)
                .collect::<Vec<f64>>()
        };
        let penetrated = (0..qp.m())
            .filter(|&i| qp.a.row_dot(i, &x0) > qp.g[i])
            .count();
        assert!(
            penetrated > active + 2 * GROW_MIN + 10,
            "test premise: {penetrated} penetrated, {active} active"
        );
        // One solve for K⁻¹d and one per row that ever entered J.
        assert!(
            r.inner_iterations <= active + 2 * GROW_MIN,
            "{} solves for {active} active rows ({penetrated} penetrated at first)",
            r.inner_iterations
        );
    }

    /// The shipped examples (floating bodies in all but cantilevers and
    /// geodynamic): ssn converges in few iterations and agrees with cgc (where
    /// cgc at tol 1e-12 is cheap) or with mprgp (the others).
    #[test]
    fn shipped_examples() {
        for name in [
            "floating_block",
            "two_blocks",
            "three_bodies",
            "hip",
            "cantilevers",
            "geodynamic",
            "hertz",
        ] {
            let prep = example(name);
            let qp = &prep.model.qp;
            let r = run_direct(solve, qp, &opts()).unwrap();
            // cantilevers: the glued start is far from the solution (half the
            // interface opens), PDAS releases it in 17 steps.
            let maxit = if name == "cantilevers" { 20 } else { 15 };
            assert!(r.iterations <= maxit, "{name}: {} iterations", r.iterations);
            let refr = if ["floating_block", "two_blocks", "three_bodies"].contains(&name) {
                reference(qp)
            } else {
                let m = run_direct(crate::qp::dual::mprgp::solve, qp, &opts()).unwrap();
                assert!(m.status.converged(), "{name}: mprgp {:?}", m.status);
                m
            };
            compare(qp, &r, &refr, 1e-6);
        }
    }

    #[test]
    fn floating_block_in_few_iterations() {
        let prep = example("floating_block");
        let qp = &prep.model.qp;
        assert_eq!(qp.kernel.len(), 1);
        let r = run_direct(solve, qp, &SolveOptions::default()).unwrap();
        assert!(r.status.converged(), "{:?}", r.status);
        assert!(r.iterations <= 15, "{} iterations", r.iterations);
        // total vertical contact force = 1e5 + 2500·9.81 N/m (meshes/floating_block.toml)
        let f: f64 = r.lambda.iter().sum();
        assert!(
            (f - 1.24525e5).abs() <= 1e-6 * 1.24525e5,
            "contact force {f}"
        );
        assert!(kkt::residuals(qp, &r.x, &r.lambda).max() <= 1e-8);
    }

    /// Two lattice blocks of unit width (bars along the grid lines and both
    /// diagonals, as in [`two_blocks`]): the lower one, stiffness 1, with
    /// `nx_lo` nodes per row, clamped at its bottom; the upper one, stiffness
    /// `contrast`, with `nx_up` nodes per row, held only by u_x = 0 at its top
    /// left node (kernel: its vertical translation and its rotation about that
    /// node, in `qp.kernel`). Non-matching contact rows: every bottom node of
    /// the upper block against the linear interpolation of the lower block's
    /// top row, n = (0, 1); the upper block's bottom is curved (gap
    /// 0.02(s − 0.45)²), the load presses it down off-centre.
    pub(crate) fn contrast_blocks(
        nx_lo: usize,
        nx_up: usize,
        ny: usize,
        contrast: f64,
    ) -> QpProblem {
        let h = 0.5 / (ny - 1) as f64;
        // global node numbers and coordinates
        let lo = |i: usize, j: usize| j * nx_lo + i;
        let up = |i: usize, j: usize| nx_lo * ny + j * nx_up + i;
        let nn = (nx_lo + nx_up) * ny;
        let mut xy = vec![[0.0; 2]; nn];
        for j in 0..ny {
            for i in 0..nx_lo {
                xy[lo(i, j)] = [i as f64 / (nx_lo - 1) as f64, j as f64 * h];
            }
            for i in 0..nx_up {
                xy[up(i, j)] = [i as f64 / (nx_up - 1) as f64, 0.5 + j as f64 * h];
            }
        }
        let mut trip_full: Vec<(usize, usize, f64)> = vec![];
        let mut bar = |p: usize, q: usize, k: f64| {
            let dir = [xy[q][0] - xy[p][0], xy[q][1] - xy[p][1]];
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
        for (nx, k, node) in [
            (nx_lo, 1.0, &lo as &dyn Fn(usize, usize) -> usize),
            (nx_up, contrast, &up),
        ] {
            for j in 0..ny {
                for i in 0..nx {
                    if i + 1 < nx {
                        bar(node(i, j), node(i + 1, j), k);
                    }
                    if j + 1 < ny {
                        bar(node(i, j), node(i, j + 1), k);
                    }
                    if i + 1 < nx && j + 1 < ny {
                        bar(node(i, j), node(i + 1, j + 1), 0.5 * k);
                        bar(node(i + 1, j), node(i, j + 1), 0.5 * k);
                    }
                }
            }
        }
        let mut fixed = vec![false; 2 * nn];
        for i in 0..nx_lo {
            fixed[2 * lo(i, 0)] = true;
            fixed[2 * lo(i, 0) + 1] = true;
        }
        fixed[2 * up(0, ny - 1)] = true;
        let mut map = vec![usize::MAX; 2 * nn];
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
        // Loads: the upper block's top row pressed down, more on the left;
        // gravity-like load on the lower block (in its own stiffness scale).
        let mut d = vec![0.0; n];
        for i in 0..nx_up {
            let s = i as f64 / (nx_up - 1) as f64;
            d[map[2 * up(i, ny - 1) + 1]] -= 0.02 * (1.5 - s) / nx_up as f64;
        }
        for j in 1..ny {
            for i in 0..nx_lo {
                d[map[2 * lo(i, j) + 1]] -= 1e-4;
            }
        }
        let mut at = vec![];
        let mut g = vec![];
        for i in 0..nx_up {
            let s = i as f64 / (nx_up - 1) as f64;
            let t = s * (nx_lo - 1) as f64;
            let k = (t.floor() as usize).min(nx_lo - 2);
            let w = t - k as f64;
            let r = g.len();
            at.push((r, map[2 * lo(k, ny - 1) + 1], 1.0 - w));
            at.push((r, map[2 * lo(k + 1, ny - 1) + 1], w));
            at.push((r, map[2 * up(i, 0) + 1], -1.0));
            g.push(0.02 * (s - 0.45) * (s - 0.45));
        }
        let a = Csr::from_triplets(g.len(), n, &at);
        // ker C: the upper block's vertical translation and its rotation
        // about the held node (x0, y0) = its top left corner.
        let (x0, y0) = (xy[up(0, ny - 1)][0], xy[up(0, ny - 1)][1]);
        let mut tz = vec![0.0; n];
        let mut rot = vec![0.0; n];
        for j in 0..ny {
            for i in 0..nx_up {
                let p = up(i, j);
                tz[map[2 * p + 1]] = 1.0;
                if map[2 * p] != usize::MAX {
                    rot[map[2 * p]] = -(xy[p][1] - y0);
                }
                rot[map[2 * p + 1]] = xy[p][0] - x0;
            }
        }
        QpProblem {
            c,
            d,
            a,
            g,
            kernel: vec![tz, rot],
        }
    }

    fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
        let d = a
            .iter()
            .zip(b)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max);
        d / norm_inf(b).max(f64::MIN_POSITIVE)
    }

    /// A floating stiff block on a soft clamped one, contrast 1e4 and 1e8,
    /// non-matching rows: every path is certified by the force-sensitive
    /// certificate and agrees with the Schur path and with `asm` on x and λ
    /// to 1e-8 (at 1e4; at 1e8 to the rounding floor 100·ε·1e8). (Before λ = μ + ρ(A_J x − g_J), the augmented path returned
    /// "converged" with stationarity far above 1e-6 here.)
    #[test]
    fn stiffness_contrast_is_certified() {
        for contrast in [1e4, 1e8] {
            let qp = contrast_blocks(17, 11, 6, contrast);
            assert_eq!(orthonormal_kernel(&qp.c, &qp.kernel).unwrap().len(), 2);
            let o = SolveOptions::default();
            let schur = solve_with(&qp, &o, Path::Schur).unwrap();
            assert!(schur.status.converged(), "{contrast:e}: {:?}", schur.status);
            nontrivial(&schur);
            let asm = run_direct(crate::qp::active_set::solve, &qp, &o).unwrap();
            assert!(asm.status.converged(), "asm {contrast:e}: {:?}", asm.status);
            // Rounding floor: C x of the stiff body (a rigid motion plus a
            // deformation 1/contrast as large) is known to ε·contrast only,
            // for every method (asm and the Schur path give 1.2e-7 and 1.4e-7
            // at 1e8): agreement to 1e-8, or to 100·ε·contrast above that.
            let agree = 1e-8f64.max(1e2 * f64::EPSILON * contrast);
            for path in [Path::Auto, Path::Augmented, Path::Refactor, Path::Schur] {
                let r = solve_with(&qp, &o, path).unwrap();
                assert!(
                    r.status.converged(),
                    "{contrast:e} {path:?}: {:?}",
                    r.status
                );
                let cert = certificate(&qp, &r.x, &r.lambda);
                assert!(
                    cert <= CERT_TARGET,
                    "{contrast:e} {path:?}: certificate {cert:e}"
                );
                assert_eq!(r.active, schur.active, "{contrast:e} {path:?}");
                for (name, refr) in [("schur", &schur), ("asm", &asm)] {
                    let dx = max_rel_diff(&r.x, &refr.x);
                    let dl = max_rel_diff(&r.lambda, &refr.lambda);
                    assert!(
                        dx <= agree && dl <= agree,
                        "{contrast:e} {path:?} vs {name}: x {dx:e}, λ {dl:e}"
                    );
                }
                // The floating block carries its load by contact alone.
                let load: f64 = -qp
                    .d
                    .iter()
                    .zip(&qp.kernel[0])
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
                let f: f64 = r.lambda.iter().sum();
                assert!(
                    (f - load).abs() <= agree * load,
                    "{contrast:e} {path:?}: Σλ = {f}, load {load}"
                );
            }
        }
    }

    /// Same input ⇒ the same path at every step and bit-identical x, λ,
    /// iterations, whatever else the machine does (a busy thread runs
    /// during the second solve), on problems whose sizes make the cost
    /// model choose differently (Schur from the start, augmented, switches).
    #[test]
    fn deterministic_paths_and_results() {
        let probs = [
            two_blocks(9, 5, false),
            two_blocks(40, 12, true),
            contrast_blocks(33, 21, 8, 1e6),
            string_on_parabola(3001),
            {
                // A wide interface glued from the start: |J| = 200 rows.
                let mut qp = two_blocks(200, 20, false);
                qp.g.iter_mut().for_each(|g| *g = 0.0);
                qp
            },
        ];
        let mut kinds = HashSet::new();
        for qp in &probs {
            let o = opts();
            let (a, ta) =
                solve_traced(qp, &mut Context::new(&o, &Workspace::new()), Path::Auto).unwrap();
            let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            let s2 = stop.clone();
            let busy = std::thread::spawn(move || {
                let mut v = 0u64;
                while !s2.load(std::sync::atomic::Ordering::Relaxed) {
                    v = v.wrapping_mul(6364136223846793005).wrapping_add(1);
                }
                v
            });
            let (b, tb) =
                solve_traced(qp, &mut Context::new(&o, &Workspace::new()), Path::Auto).unwrap();
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
            busy.join().unwrap();
            assert!(a.status.converged(), "{:?}", a.status);
            assert_eq!(ta, tb, "paths differ");
            assert_eq!(a.iterations, b.iterations);
            assert_eq!(a.inner_iterations, b.inner_iterations);
            assert_eq!(a.active, b.active);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
            assert_eq!(bits(&a.x), bits(&b.x), "x not bit-identical");
            assert_eq!(bits(&a.lambda), bits(&b.lambda), "λ not bit-identical");
            kinds.insert((ta.contains(&true), ta.contains(&false)));
        }
        // The sizes exercise both paths.
        assert!(kinds.iter().any(|k| k.0), "augmented path never taken");
        assert!(kinds.iter().any(|k| k.1), "Schur path never taken");
    }

    /// The cost model's inputs are counts: the same pattern gives the same
    /// counts, a larger one larger counts, and a factor costs more than a solve.
    #[test]
    fn cost_model_counts() {
        let small = two_blocks(9, 5, false);
        let big = two_blocks(30, 10, false);
        let cs = Costs::new(&small, Some(&AugPattern::new(&small))).unwrap();
        let cs2 = Costs::new(&small, Some(&AugPattern::new(&small))).unwrap();
        let cb = Costs::new(&big, Some(&AugPattern::new(&big))).unwrap();
        assert_eq!(
            (cs.fac_c, cs.solve_c, cs.fac_k, cs.solve_k),
            (cs2.fac_c, cs2.solve_c, cs2.fac_k, cs2.solve_k)
        );
        assert!(cb.fac_c > cs.fac_c && cb.solve_c > cs.solve_c);
        assert!(cs.solve_c >= small.n() as f64, "nnz(L) ≥ n");
        assert!(
            cs.fac_k >= cs.fac_c && cs.solve_k >= cs.solve_c,
            "C + AᵀA fills more"
        );
    }

    /// The path is a setting: an unknown name is refused when the settings
    /// are read, a known one is taken.
    #[test]
    fn path_option() {
        let qp = two_blocks(9, 5, false);
        let bad = crate::qp::SolverSection {
            ssn_path: Some("diagonal".into()),
            ..Default::default()
        };
        assert!(crate::qp::Settings::from_section(&bad).is_err());
        let o = {
            let mut o = opts();
            o.settings.ssn.path = crate::qp::settings::SsnPath::Schur;
            o
        };
        let (r, trace) =
            solve_traced(&qp, &mut Context::new(&o, &Workspace::new()), Path::Schur).unwrap();
        assert!(r.status.converged());
        assert!(trace.iter().all(|aug| !aug), "{trace:?}");
        let r = run_direct(solve, &qp, &o).unwrap();
        assert!(r.status.converged());
    }

    /// NaN anywhere is never certified.
    #[test]
    fn certificate_rejects_nan() {
        let qp = two_blocks(9, 5, false);
        let r = run_direct(solve, &qp, &opts()).unwrap();
        assert!(certificate(&qp, &r.x, &r.lambda) <= 1e-8);
        let mut x = r.x.clone();
        x[3] = f64::NAN;
        assert_eq!(certificate(&qp, &x, &r.lambda), f64::INFINITY);
        let mut l = r.lambda.clone();
        l[0] = f64::INFINITY;
        assert_eq!(certificate(&qp, &r.x, &l), f64::INFINITY);
    }
}
