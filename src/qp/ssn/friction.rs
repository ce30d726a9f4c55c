//! `ssn` with friction (docs/methods.md §9.2): the primal–dual active set
//! method of Hüeber, Stadler & Wohlmuth (SISC 30, 2008) for the Tresca
//! problem, and Coulomb as successive Tresca problems (§9.1, the report's
//! outer loop).
//!
//! One Newton step predicts, with v = T x − t0 and a constant per row,
//! cᵢ = 1 / Σ_k a_ik² / c_kk (the stiffness the row meets, set by its
//! softer side; c_tᵢ = 10⁻² × the same sum over the row of T),
//! * the normal set N = {i : λ_nᵢ + cᵢ(Ax − g)ᵢ > 0};
//! * the stick set S = {i : sᵢ > 0, |λ_tᵢ + c_tᵢ vᵢ| ≤ sᵢ}; every other row
//!   slips with the known force λ_tᵢ = sᵢ·sign(λ_tᵢ + c_tᵢ vᵢ);
//!
//! (one c for all rows, the mean of diag C, let a soft body's rows be
//! judged at a stiff body's scale: a soft keystone between abutments
//! 10²–10⁷ times stiffer cycled for 10 000 steps, docs/methods.md §9.2);
//!
//! and solves the equality-constrained problem `Cx + Bᵀμ = d − T_Lᵀλ_L,
//! Bx = b` with B = [A_N; T_S], b = [g_N; t0_S]: in the dual space on one
//! bordered factor of C ([`Dual`], docs/methods.md §9.2), or, when the
//! border of [A; T] is too large for a dense block (or `ssn_path` says
//! augmented/refactor), through K = C + ρBᵀB (augmented Lagrangian steps
//! μ ← μ + ρ(Bx − b); the multiplier is taken after the step, so
//! Cx − d + Bᵀμ + T_Lᵀλ_L = 0 holds to the solve's backward error).
//! The step is repeated until the sets no longer change
//! (a KKT point of the Tresca problem); a set seen before, or one that
//! frees a rigid motion friction can hold, is entered one row at a time.
//! Coulomb starts glued (S = N); on the dual path it then runs the same
//! Newton steps on Coulomb's problem itself, s = μλ_n of the current
//! iterate and λ_t = μσλ_n on the slipping rows ([`Dual::solve_coulomb`]);
//! otherwise (or if that does not settle) it moves s towards μλ_n of the
//! last solution until s is stationary: the outer loop of §9.1 shared with
//! the dual ([`crate::qp::coulomb`]); each Tresca solve starts from the
//! working sets the new bound predicts at the last answer.
//!
//! A working set that leaves a rigid motion z free (B z = 0 for some z in
//! ker C) is tested: if the loads do more work along ±z than friction can
//! dissipate (dᵀz > Σ sᵢ|(Tz)ᵢ|, Az ≤ 0), the problem is unbounded — the
//! block slides down the plane (§9.3); otherwise K is regularised along z
//! for that step only.

use crate::linalg::cholesky::{Cholesky, Forward};
use crate::linalg::dense::{sym_eigen, SpdFactor};
use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::rotation::RowBorder;
use crate::linalg::sparse::{dot, norm_inf, Csr};
use crate::qp::coulomb::{self, Bound, Tresca, TrescaStep};
use crate::qp::executor::{Iterative, Step};
use crate::qp::settings::SsnPath;
use crate::qp::Failure;
use faer::Mat;
use std::collections::HashSet;

use crate::qp::{Context, Friction, IterRecord, Output, QpError, QpProblem, Status};

/// ρᵢ = RHO · (the row's stiffness) in K = C + Bᵀ diag(ρ) B.
const RHO: f64 = super::RHO_FACTOR;
/// Augmented Lagrangian steps per Newton step, at most.
const AL_MAX: usize = 200;
/// c_tᵢ = CT_FACTOR · cᵢ in the slip prediction |λ_t + c_t v| ≤ s: any
/// c_t > 0 has the same fixed points; a small one lets the forces lead.
/// With c_t = c the block of tests/friction.rs at tan θ = 0.9μ under
/// Tresca cycled between stick zones; with 10⁻² it settles in 7 steps.
const CT_FACTOR: f64 = 1e-2;

/// Solve the frictional `qp` (qp.friction is Some).
pub(super) fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let Some(fr) = qp.friction.as_ref() else {
        return Err(QpError::BadParameter(
            "ssn::friction called without friction".into(),
        ));
    };
    let r = orthonormal_kernel(&qp.c, &qp.kernel)?;
    let dual = match ctx.settings.ssn.path {
        SsnPath::Auto | SsnPath::Schur => Dual::new(qp, fr, &r, ctx.ws)?,
        _ => None,
    };
    let mut st = State::new(qp, fr, r, ctx);
    if let Some(d) = dual {
        st.inner += d.solves;
        st.dual = Some(d);
    }
    let mut step = SsnTresca {
        st,
        ctx,
        steps: 0,
        counted: 0,
    };
    coulomb::solve(fr, &mut step, "ssn")
}

/// The Tresca solve of ssn: Newton steps from the working sets of the last
/// solve (the start's for the first) until they settle. The steps of all
/// solves share one MAXIT.
struct SsnTresca<'c, 'a> {
    st: State<'a>,
    ctx: &'c Context<'a>,
    /// Newton steps of the solves so far.
    steps: usize,
    /// Sparse solves reported so far (the dual form's own go with the first solve).
    counted: usize,
}

impl TrescaStep for SsnTresca<'_, '_> {
    fn resolution(&self) -> f64 {
        self.st.tol
    }

    fn solve(&mut self, bound: Bound<'_>) -> Result<Tresca, QpError> {
        let st = &mut self.st;
        let m = st.qp.m();
        st.coulomb = None;
        match bound {
            Bound::Glued => {
                st.s = vec![0.0; m];
                st.glued = true;
            }
            Bound::Given(s) => {
                st.s = s.to_vec();
                st.glued = false;
            }
        }
        if st.last.is_none() {
            st.start_sets();
        } else {
            st.fresh = true;
        }
        self.run()
    }

    fn coulomb(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        let st = &mut self.st;
        st.dual.as_ref()?;
        st.coulomb = Some(mu.to_vec());
        st.s = st.fr.slip_bound(&st.ln);
        st.glued = false;
        st.fresh = true;
        st.visited.clear();
        Some(self.run())
    }

    fn complete(&mut self, r: &mut Tresca) -> Result<(), QpError> {
        self.st.ensure_x()?;
        r.inner_iterations += self.st.inner - self.counted;
        self.counted = self.st.inner;
        if r.x.is_empty() {
            r.x = self.st.x.clone();
        }
        Ok(())
    }
}

impl SsnTresca<'_, '_> {
    /// Newton steps from the current state until the sets settle.
    fn run(&mut self) -> Result<Tresca, QpError> {
        let st = &mut self.st;
        st.best = (f64::INFINITY, 0);
        let mut exec = self.ctx.executor("ssn");
        exec.max_iter = exec.max_iter.saturating_sub(self.steps);
        let (status, iters) = exec.run(st);
        self.steps += iters;
        let counted = std::mem::replace(&mut self.counted, st.inner);
        if let Some(e) = st.error.take() {
            return Err(e);
        }
        Ok(Tresca {
            // Formed by `complete` when the loop returns this answer.
            x: if st.x_stale { vec![] } else { st.x.clone() },
            lambda_n: st.ln.clone(),
            lambda_t: st.lt.clone(),
            active: st.in_n.clone(),
            status,
            iterations: iters,
            inner_iterations: st.inner - counted,
            log: exec.log,
        })
    }
}

/// factor / Σ_k b_ik² / c_kk for each row of `b`: the stiffness the row
/// meets, dominated by its softer side (`fallback` for a row with no
/// finite positive sum).
fn row_stiffness(b: &Csr, diag: &[f64], fallback: f64, factor: f64) -> Vec<f64> {
    (0..b.nrows)
        .map(|i| {
            let (cols, vals) = b.row(i);
            let flex: f64 = cols
                .iter()
                .zip(vals)
                .filter(|(&k, _)| diag[k] > 0.0)
                .map(|(&k, &v)| v * v / diag[k])
                .sum();
            let c = if flex > 0.0 && flex.is_finite() {
                1.0 / flex
            } else {
                fallback
            };
            factor * c
        })
        .collect()
}

/// The most rows of B = [A; T] whose dense H = B K⁻¹Bᵀ is formed (8·8192²
/// bytes, 512 MiB); more take the sparse path.
const DUAL_ROWS_MAX: usize = 8192;

/// A row of B with H_jj ≤ NULL_ROW · max H holds nothing ([`Dual`]).
const NULL_ROW: f64 = 1e-14;

/// The working-set solves in the dual space (docs/methods.md §9.2): one
/// bordered factor of C (+ springs on a floating body's fixing unknowns,
/// K) with every unknown B = [A; T] touches eliminated last, whose trailing
/// block gives all of H = B K⁻¹Bᵀ at once (§7). A working set's
/// equality-constrained problem is then a dense system on its rows, with
/// the FETI coarse problem for the rigid motions; x is one backward pass
/// (`Cholesky::finish`), formed only for an answer that is returned. The
/// factor does not change between Newton steps, Tresca solves or load
/// steps (the workspace keeps it), where K = C + ρBᵀB was refactored at
/// every Newton step and solved by augmented Lagrangian sweeps.
struct Dual {
    /// B = [A; T], 2m × n.
    b: Csr,
    fac: Cholesky,
    /// The forward half of K⁻¹d.
    fwd: Forward,
    /// H = B K⁻¹Bᵀ, 2m × 2m.
    h: Mat<f64>,
    /// B K⁻¹d.
    bk0: Vec<f64>,
    /// (B R)ᵢₗ by rows, 2m × k.
    br: Vec<Vec<f64>>,
    /// e = Rᵀd.
    e: Vec<f64>,
    /// Rows of B that hold nothing (H_jj = 0: a tangential row on a line
    /// of symmetry, whose unknown is eliminated): left out of every
    /// working set's system, their multiplier 0.
    null: Vec<bool>,
    /// Sparse solves it took (counted as inner iterations).
    solves: usize,
}

impl Dual {
    /// The dual form of `qp`, or None when the border of B is too large for
    /// a dense trailing block (the limits of the frictionless path,
    /// [`super::small_border`]) or H would be.
    fn new(
        qp: &QpProblem,
        fr: &Friction,
        r: &[Vec<f64>],
        ws: &crate::linalg::cholesky::Workspace,
    ) -> Result<Option<Dual>, QpError> {
        let (n, m) = (qp.n(), qp.m());
        if m == 0 || 2 * m > DUAL_ROWS_MAX {
            return Ok(None);
        }
        let mut trip = Vec::with_capacity(qp.a.nnz() + fr.t.nnz());
        for (off, mat) in [(0, &qp.a), (m, &fr.t)] {
            for i in 0..m {
                let (cols, vals) = mat.row(i);
                trip.extend(cols.iter().zip(vals).map(|(&j, &v)| (off + i, j, v)));
            }
        }
        let b = Csr::from_triplets(2 * m, n, &trip);
        let rb = RowBorder::new(&qp.c, &qp.kernel, &b);
        let nb = rb.len();
        log::debug!("ssn: friction: border of B = [A; T]: {nb} unknowns");
        if nb as f64 > super::BORDER_RATIO * (n as f64).sqrt() || nb > super::BORDER_MAX {
            return Ok(None);
        }
        let fac = ws.cholesky_rows(&qp.c, &qp.kernel, &rb)?;
        let Some(h) = fac.border_inverse(&b) else {
            return Ok(None);
        };
        let Some(fwd) = fac.forward(&qp.d) else {
            return Ok(None);
        };
        let Some(bk0) = fac.border_product(&fwd, &b) else {
            return Ok(None);
        };
        let br = (0..2 * m)
            .map(|i| r.iter().map(|rl| b.row_dot(i, rl)).collect())
            .collect();
        let e = r.iter().map(|rl| dot(rl, &qp.d)).collect();
        let hmax = (0..2 * m).fold(0.0f64, |a, j| a.max(h[(j, j)]));
        let null = (0..2 * m).map(|j| !(h[(j, j)] > NULL_ROW * hmax)).collect();
        Ok(Some(Dual {
            b,
            fac,
            fwd,
            h,
            bk0,
            br,
            e,
            null,
            solves: 1,
        }))
    }

    /// The multipliers of the working set `rows` (indices into B's rows)
    /// with the known forces `f` (2m; zero on `rows`): μ_J and α from
    /// H_JJ μ_J − (BR)_J α = (BK⁻¹b − c − H f)_J and (BR)_Jᵀμ_J = Rᵀb −
    /// (BR)ᵀf, given `bkb` = BK⁻¹b and `e` = Rᵀb (b = d and c = [g; t0]
    /// for a step; the residuals for a refinement). A rigid motion the rows
    /// leave free (a singular coarse matrix) gets no α: the step is solved
    /// as if it were held, as the sparse path regularises K along it. None
    /// if H_JJ is singular.
    fn solve(
        &self,
        rows: &[usize],
        f: &[f64],
        bkb: &[f64],
        c: &[f64],
        e: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let nj = rows.len();
        let k = e.len();
        let h = &self.h;
        let fl: Vec<(usize, f64)> = f
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(l, &v)| (l, v))
            .collect();
        let hjj = Mat::from_fn(
            nj,
            nj,
            |a, b| {
                if b <= a {
                    h[(rows[a], rows[b])]
                } else {
                    0.0
                }
            },
        );
        let fac = SpdFactor::new(hjj.as_ref())?;
        let mut rhs = Mat::from_fn(nj, 1 + k, |t, col| {
            let j = rows[t];
            if col == 0 {
                // H is symmetric: read column j.
                bkb[j] - c[j] - fl.iter().map(|&(l, v)| h[(l, j)] * v).sum::<f64>()
            } else {
                self.br[j][col - 1]
            }
        });
        fac.solve_mat_in_place(rhs.as_mut());
        let mut w: Vec<f64> = rhs.col(0).iter().copied().collect();
        let mut alpha = vec![0.0; k];
        if k > 0 {
            // F = (BR)_Jᵀ Y, Y = H_JJ⁻¹(BR)_J; F α = e − (BR)ᵀf − (BR)_Jᵀw.
            let mut fm = vec![vec![0.0; k]; k];
            for (a, row) in fm.iter_mut().enumerate() {
                for (b, v) in row.iter_mut().enumerate() {
                    *v = rows
                        .iter()
                        .enumerate()
                        .map(|(t, &j)| self.br[j][a] * rhs[(t, 1 + b)])
                        .sum();
                }
            }
            for a in 0..k {
                for b in 0..a {
                    let v = 0.5 * (fm[a][b] + fm[b][a]);
                    fm[a][b] = v;
                    fm[b][a] = v;
                }
            }
            let mut q: Vec<f64> = (0..k)
                .map(|l| {
                    let known: f64 = fl.iter().map(|&(j, v)| self.br[j][l] * v).sum();
                    let bw: f64 = rows.iter().zip(&w).map(|(&j, wt)| self.br[j][l] * wt).sum();
                    e[l] - known - bw
                })
                .collect();
            // α = F⁺q: the motions null F leaves free get none.
            let (vals, vecs) = sym_eigen(&fm);
            let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let mut out = vec![0.0; k];
            for (lam, v) in vals.iter().zip(&vecs) {
                if !(lam.abs() > 1e-12 * top) {
                    continue;
                }
                let p = dot(v, &q) / lam;
                for (o, vi) in out.iter_mut().zip(v) {
                    *o += p * vi;
                }
            }
            q = out;
            for (t, wt) in w.iter_mut().enumerate() {
                *wt += (0..k).map(|l| rhs[(t, 1 + l)] * q[l]).sum::<f64>();
            }
            alpha = q;
        }
        if !w.iter().chain(&alpha).all(|v| v.is_finite()) {
            return None;
        }
        Some((w, alpha))
    }

    /// The multipliers of a working set of Coulomb's problem with the slip
    /// bound inside (docs/methods.md §9.2): the normal rows `normal` (row
    /// i of A with κᵢ = μᵢσᵢ when its tangential row slips along σᵢ, else
    /// 0: λ_tᵢ = κᵢλ_nᵢ, a force the unknown λ_nᵢ sets), the stick rows
    /// `stick` (indices into B) and the rigid motions: (B x)_E = c_E on the
    /// rows E = normal ∪ stick and the equilibrium Rᵀ(d − Bᵀμ) = 0, a
    /// nonsymmetric system (the slip forces' columns) solved by LU with
    /// the coarse unknowns scaled to H's size. Returns μ over every row and
    /// α; None if the system is singular to working precision.
    fn solve_coulomb(
        &self,
        normal: &[(usize, f64)],
        stick: &[usize],
        c: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let m = self.bk0.len() / 2;
        let k = self.e.len();
        let (nn, q) = (normal.len(), normal.len() + stick.len());
        let size = q + k;
        let h = &self.h;
        let hs = (0..2 * m)
            .fold(0.0f64, |a, j| a.max(h[(j, j)]))
            .max(f64::MIN_POSITIVE);
        let erow = |e: usize| if e < nn { normal[e].0 } else { stick[e - nn] };
        // Column p of H P (P: unknowns to multipliers), read by rows.
        let col = |re: usize, p: usize| -> f64 {
            if p < nn {
                let (i, kappa) = normal[p];
                let mut v = h[(i, re)];
                if kappa != 0.0 {
                    v += kappa * h[(m + i, re)];
                }
                v
            } else {
                h[(stick[p - nn], re)]
            }
        };
        let brp = |p: usize, l: usize| -> f64 {
            if p < nn {
                let (i, kappa) = normal[p];
                self.br[i][l] + kappa * self.br[m + i][l]
            } else {
                self.br[stick[p - nn]][l]
            }
        };
        let mut w = vec![0.0; size * size];
        let mut rhs = vec![0.0; size];
        for e in 0..q {
            let re = erow(e);
            for p in 0..q {
                w[e * size + p] = col(re, p);
            }
            for l in 0..k {
                w[e * size + q + l] = -self.br[re][l] * hs;
            }
            rhs[e] = self.bk0[re] - c[re];
        }
        for l in 0..k {
            for p in 0..q {
                w[(q + l) * size + p] = brp(p, l) * hs;
            }
            rhs[q + l] = self.e[l] * hs;
        }
        let lu = crate::linalg::dense::Lu::from_row_major(&w, size)?;
        lu.solve_in_place(&mut rhs);
        if !rhs.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut mu = vec![0.0; 2 * m];
        for (p, &(i, kappa)) in normal.iter().enumerate() {
            mu[i] = rhs[p];
            mu[m + i] = kappa * rhs[p];
        }
        for (p, &t) in stick.iter().enumerate() {
            mu[t] = rhs[nn + p];
        }
        let alpha = rhs[q..].iter().map(|a| a * hs).collect();
        Some((mu, alpha))
    }

    /// B x for the multipliers `mu` (2m) and α: B K⁻¹(d − Bᵀμ) + BRα.
    fn bx(&self, mu: &[f64], alpha: &[f64]) -> Vec<f64> {
        let mut out = self.bk0.clone();
        for (l, &v) in mu.iter().enumerate().filter(|(_, v)| **v != 0.0) {
            for (o, hv) in out.iter_mut().zip(self.h.col(l).iter()) {
                *o -= v * hv;
            }
        }
        for (o, row) in out.iter_mut().zip(&self.br) {
            *o += row.iter().zip(alpha).map(|(a, b)| a * b).sum::<f64>();
        }
        out
    }

    /// x = K⁻¹(d − Bᵀμ) + Rα: one backward pass.
    fn x(&self, mu: &[f64], alpha: &[f64], r: &[Vec<f64>]) -> Option<Vec<f64>> {
        let mut x = self.fac.finish(&self.fwd, &self.b, mu)?;
        for (rl, &al) in r.iter().zip(alpha) {
            for (xi, ri) in x.iter_mut().zip(rl) {
                *xi += al * ri;
            }
        }
        Some(x)
    }
}

/// A bordered factor that cannot finish a solve (it always can: B is its border).
fn unfinished() -> QpError {
    QpError::BadParameter("ssn: the bordered factor of B = [A; T] cannot finish a solve".into())
}

/// How each row is held in a working set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Tangential {
    Stick,
    /// Slips with λ_t = s·sign (the sign as a bool: true = positive).
    Slip(bool),
}

struct State<'a> {
    qp: &'a QpProblem,
    fr: &'a Friction,
    ws: &'a crate::linalg::cholesky::Workspace,
    /// Orthonormal basis of ker C.
    r: Vec<Vec<f64>>,
    /// cᵢ of the normal prediction, per row of A.
    cn: Vec<f64>,
    /// c_tᵢ of the slip prediction, per row of T.
    ct: Vec<f64>,
    /// ρᵢ of K = C + Bᵀ diag(ρ) B for a normal row (index 0) and a
    /// tangential row (index 1): RHO × the row's stiffness, so that a soft
    /// body's rows are not weighted at a stiff body's scale (with one ρ =
    /// RHO·max diag C, λ = μ + ρ(Bx − b) lost all but ~6 digits on a soft
    /// keystone 10⁷ times softer than its abutments).
    rho: Vec<[f64; 2]>,
    tol: f64,
    x: Vec<f64>,
    ln: Vec<f64>,
    lt: Vec<f64>,
    /// The current slip bound.
    s: Vec<f64>,
    /// Coulomb's glued start: S = N.
    glued: bool,
    /// A new bound: the next step takes the sets it predicts as they are.
    fresh: bool,
    /// The sets the last answer predicts (at the current bound).
    predicted: Option<(Vec<bool>, Vec<Tangential>)>,
    in_n: Vec<bool>,
    tang: Vec<Tangential>,
    /// The sets of the last solve (None before the first).
    last: Option<(Vec<bool>, Vec<Tangential>)>,
    outer: usize,
    inner: usize,
    /// Working sets solved so far (anti-cycling; looked up, never iterated).
    visited: HashSet<(Vec<bool>, Vec<Tangential>)>,
    /// The best KKT residual of the current Tresca problem and the steps
    /// since it was reached ([`cycle_budget`]).
    best: (f64, usize),
    error: Option<QpError>,
    /// The dual-space solves (None: the sparse path, K = C + ρBᵀB).
    dual: Option<Dual>,
    /// [A x; T x] of the current iterate (both paths).
    bx: Vec<f64>,
    /// The multipliers [λ_n; λ_t] and α of the last dual-space solve.
    mu: Vec<f64>,
    alpha: Vec<f64>,
    /// x is not yet formed from (μ, α) (the dual path forms it on demand).
    x_stale: bool,
    /// The rows of B in the last dual-space solve's working set.
    rows: Vec<usize>,
    /// Coulomb's coefficients while the direct iteration runs (the bound
    /// s = μλ_n of the current iterate, [`TrescaStep::coulomb`]).
    coulomb: Option<Vec<f64>>,
}

/// Newton steps without a better residual after which the sets of one
/// Tresca problem are judged to cycle: two single-change walks over every
/// row, and 100 more.
fn cycle_budget(m: usize) -> usize {
    2 * m + 100
}

impl<'a> State<'a> {
    fn new(qp: &'a QpProblem, fr: &'a Friction, r: Vec<Vec<f64>>, ctx: &Context<'a>) -> Self {
        let (n, m) = (qp.n(), qp.m());
        let diag = qp.c.diag();
        let cmean = (diag.iter().sum::<f64>() / n.max(1) as f64).max(f64::MIN_POSITIVE);
        let cn = row_stiffness(&qp.a, &diag, cmean, 1.0);
        let kt = row_stiffness(&fr.t, &diag, cmean, 1.0);
        let rho = cn
            .iter()
            .zip(&kt)
            .map(|(a, b)| [RHO * a, RHO * b])
            .collect();
        let ct = kt.iter().map(|k| CT_FACTOR * k).collect();
        let x = ctx.x0.map_or_else(|| vec![0.0; n], |x0| x0.to_vec());
        let ax = qp.a.mul(&x);
        let scale = norm_inf(&x).max(norm_inf(&qp.g)).max(f64::MIN_POSITIVE);
        let in_n: Vec<bool> = (0..m).map(|i| ax[i] - qp.g[i] >= -1e-12 * scale).collect();
        let mut bx = ax;
        bx.extend(fr.t.mul(&x));
        State {
            qp,
            fr,
            ws: ctx.ws,
            r,
            cn,
            ct,
            rho,
            tol: ctx.settings.tol,
            x,
            ln: vec![0.0; m],
            lt: vec![0.0; m],
            s: vec![0.0; m],
            glued: true,
            fresh: false,
            predicted: None,
            tang: vec![Tangential::Stick; m],
            in_n,
            last: None,
            outer: 0,
            inner: 0,
            visited: HashSet::new(),
            best: (f64::INFINITY, 0),
            error: None,
            dual: None,
            bx,
            mu: vec![],
            alpha: vec![],
            x_stale: false,
            rows: vec![],
            coulomb: None,
        }
    }

    /// Form x from the last dual-space answer if it is not yet (one
    /// backward pass on the bordered factor).
    fn ensure_x(&mut self) -> Result<(), QpError> {
        if !self.x_stale {
            return Ok(());
        }
        let d = self
            .dual
            .as_ref()
            .expect("a stale x comes from the dual path");
        self.x = d.x(&self.mu, &self.alpha, &self.r).ok_or_else(unfinished)?;
        self.inner += 1;
        self.x_stale = false;
        self.refine()
    }

    /// Iterative refinement of a dual-space answer on its working set, as
    /// the frictionless path refines (at most [`super::REFINE_MAX`] steps,
    /// while the certificate exceeds `tol` and falls): with the residuals
    /// r₁ = d − Cx − Bᵀμ and r₂ = c − Bx, the correction (δμ_J, δα) solves
    /// the step's system with BK⁻¹r₁ − r₂ and Rᵀr₁ on the right, and δx =
    /// K⁻¹(r₁ − B_Jᵀδμ_J) + Rδα: one sparse solve each. The slip forces
    /// stay. On a point at rest (x = 0), the rounding of λ_n alone left
    /// Ax = 10⁻¹⁶, which the certificate judges against |x| = 10⁻¹⁶.
    fn refine(&mut self) -> Result<(), QpError> {
        let Some(d) = self.dual.as_ref() else {
            return Ok(());
        };
        let qp = self.qp;
        let m = qp.m();
        let cert = |x: &[f64], ln: &[f64], lt: &[f64]| {
            crate::qp::kkt::residuals_with_friction(qp, x, ln, lt).judged()
        };
        let mut best = cert(&self.x, &self.ln, &self.lt);
        for _ in 0..super::REFINE_MAX {
            if !(best > self.tol) {
                break;
            }
            let mut r1 = qp.c.mul(&self.x);
            d.b.mul_t_add(&self.mu, &mut r1);
            for (ri, di) in r1.iter_mut().zip(&qp.d) {
                *ri = di - *ri;
            }
            let bx = d.b.mul(&self.x);
            let mut r2 = qp.g.clone();
            r2.extend_from_slice(&self.fr.t0);
            for (ri, bi) in r2.iter_mut().zip(&bx) {
                *ri -= bi;
            }
            let fwd = d.fac.forward(&r1).ok_or_else(unfinished)?;
            let bkr = d.fac.border_product(&fwd, &d.b).ok_or_else(unfinished)?;
            let e: Vec<f64> = self.r.iter().map(|rl| dot(rl, &r1)).collect();
            let zero = vec![0.0; 2 * m];
            let Some((dmu, dalpha)) = d.solve(&self.rows, &zero, &bkr, &r2, &e) else {
                break;
            };
            let mut dmu_all = zero;
            for (&j, v) in self.rows.iter().zip(&dmu) {
                dmu_all[j] = *v;
            }
            let mut dx = d.fac.finish(&fwd, &d.b, &dmu_all).ok_or_else(unfinished)?;
            self.inner += 1;
            for (rl, &al) in self.r.iter().zip(&dalpha) {
                for (xi, ri) in dx.iter_mut().zip(rl) {
                    *xi += al * ri;
                }
            }
            let x: Vec<f64> = self.x.iter().zip(&dx).map(|(a, b)| a + b).collect();
            let mu: Vec<f64> = self.mu.iter().zip(&dmu_all).map(|(a, b)| a + b).collect();
            let c = cert(&x, &mu[..m], &mu[m..]);
            log::debug!("ssn: friction: refinement: KKT residual {best:.2e} → {c:.2e}");
            if !(c < best) {
                break;
            }
            best = c;
            self.ln = mu[..m].to_vec();
            self.lt = mu[m..].to_vec();
            self.bx = d.b.mul(&x);
            self.x = x;
            self.mu = mu;
        }
        Ok(())
    }

    /// A KKT residual of the current iterate from B x and the multipliers
    /// alone (no x needed; stationarity holds by construction): the normal
    /// conditions and the friction rules of docs/methods.md §9.4, forces
    /// relative to the largest multiplier and bound, lengths to the largest
    /// of |Bx|, g and t0. Orders the iterates for the cycling budget.
    fn dual_residual(&self) -> f64 {
        let qp = self.qp;
        let m = qp.m();
        let (ax, tx) = self.bx.split_at(m);
        let fs = norm_inf(&self.ln)
            .max(norm_inf(&self.lt))
            .max(if self.glued { 0.0 } else { norm_inf(&self.s) })
            .max(f64::MIN_POSITIVE);
        let xs = norm_inf(&self.bx)
            .max(norm_inf(&qp.g))
            .max(norm_inf(&self.fr.t0))
            .max(f64::MIN_POSITIVE);
        let mut r = 0.0f64;
        for i in 0..m {
            let gap = ax[i] - qp.g[i];
            let ln = self.ln[i];
            r = r
                .max(gap.max(0.0) / xs)
                .max((-ln).max(0.0) / fs)
                .max((ln * gap).abs() / (fs * xs));
            let v = tx[i] - self.fr.t0[i];
            let lt = self.lt[i];
            if self.glued {
                // Glued: the closed rows stick, the open ones are free.
                r = r.max(if self.in_n[i] {
                    v.abs() / xs
                } else {
                    lt.abs() / fs
                });
            } else {
                let si = self.s[i];
                r = r.max((lt.abs() - si).max(0.0) / fs);
                if v != 0.0 {
                    r = r.max(v.abs() / xs * (si - lt * v.signum()).abs() / fs);
                }
            }
        }
        r
    }

    /// The tangential sets of the first solve: Tresca starts glued, every
    /// row with a bound sticks (docs/methods.md §9.2); Coulomb's glued
    /// start sticks the rows in contact.
    fn start_sets(&mut self) {
        self.tang = self
            .in_n
            .iter()
            .zip(&self.s)
            .map(|(&a, &si)| {
                if a || (!self.glued && si > 0.0) {
                    Tangential::Stick
                } else {
                    Tangential::Slip(true)
                }
            })
            .collect();
    }

    /// Ax and the slip v = T x − t0 of the current iterate.
    fn ax_v(&self) -> (&[f64], Vec<f64>) {
        let (ax, tx) = self.bx.split_at(self.qp.m());
        let v = tx.iter().zip(&self.fr.t0).map(|(t, t0)| t - t0).collect();
        (ax, v)
    }

    /// The sets predicted at the current (x, λ_n, λ_t).
    fn predict(&self) -> (Vec<bool>, Vec<Tangential>) {
        let qp = self.qp;
        let (ax, v) = self.ax_v();
        let n_set: Vec<bool> = (0..qp.m())
            .map(|i| self.ln[i] + self.cn[i] * (ax[i] - qp.g[i]) > 0.0)
            .collect();
        let m = qp.m();
        // A tangential row the dual path leaves out (no free unknown: both
        // sides' tangential motion prescribed, or a line of symmetry) cannot
        // respond: its slip v = −t0 is given, so it sticks only where that
        // is zero and otherwise slips with it (at the end of a tube pushed
        // through a fit, its forced slip was taken for a stick).
        let forced = |i: usize| self.dual.as_ref().is_some_and(|d| d.null[m + i]);
        let tang = (0..m)
            .map(|i| {
                let z = self.lt[i] + self.ct[i] * v[i];
                if self.glued {
                    if n_set[i] {
                        Tangential::Stick
                    } else {
                        Tangential::Slip(true)
                    }
                } else if forced(i) {
                    if self.fr.t0[i] == 0.0 {
                        Tangential::Stick
                    } else {
                        Tangential::Slip(v[i] > 0.0)
                    }
                } else if self.s[i] > 0.0 && z.abs() <= self.s[i] {
                    Tangential::Stick
                } else {
                    Tangential::Slip(z > 0.0)
                }
            })
            .collect();
        (n_set, tang)
    }

    /// Whether the working set `(n_set, tang)` leaves a rigid motion free
    /// along which the problem is bounded.
    fn frees_a_bounded_motion(&self, n_set: &[bool], tang: &[Tangential]) -> bool {
        let m = self.qp.m();
        let brows: Vec<(bool, usize)> = (0..m)
            .filter(|&i| n_set[i])
            .map(|i| (false, i))
            .chain(
                (0..m)
                    .filter(|&i| tang[i] == Tangential::Stick)
                    .map(|i| (true, i)),
            )
            .collect();
        let free = self.free_motions(&brows);
        !free.is_empty() && self.unbounded_along(&free).is_none()
    }

    /// Move the current sets one row towards the prediction `(n_set, tang)`:
    /// the row whose prediction is violated most (normal: |λ_n + c(Ax − g)|,
    /// tangential: ||λ_t + c v| − s|).
    fn single_change(&mut self, n_set: &[bool], tang: &[Tangential]) {
        let qp = self.qp;
        let (ax, v) = self.ax_v();
        let mut best: Option<(f64, usize, bool)> = None;
        for i in 0..qp.m() {
            if n_set[i] != self.in_n[i] {
                let sc = (self.ln[i] + self.cn[i] * (ax[i] - qp.g[i])).abs();
                if best.is_none_or(|b| sc > b.0) {
                    best = Some((sc, i, false));
                }
            }
            if tang[i] != self.tang[i] {
                let sc = ((self.lt[i] + self.ct[i] * v[i]).abs() - self.s[i]).abs();
                if best.is_none_or(|b| sc > b.0) {
                    best = Some((sc, i, true));
                }
            }
        }
        match best {
            Some((_, i, false)) => self.in_n[i] = n_set[i],
            Some((_, i, true)) => self.tang[i] = tang[i],
            None => {}
        }
    }

    /// The known force of a slipping row.
    fn slip_force(&self, i: usize, t: Tangential) -> f64 {
        match t {
            Tangential::Slip(pos) if !self.glued => {
                if pos {
                    self.s[i]
                } else {
                    -self.s[i]
                }
            }
            _ => 0.0,
        }
    }

    /// Solve the equality-constrained problem of the working set; Ok(None)
    /// when it is unbounded along a rigid motion (returned as the status).
    fn solve_set(&mut self) -> Result<Option<Status>, QpError> {
        let qp = self.qp;
        let (n, m) = (qp.n(), qp.m());
        // B's rows: (is tangential, row index).
        let mut brows: Vec<(bool, usize)> = vec![];
        for i in 0..m {
            if self.in_n[i] {
                brows.push((false, i));
            }
        }
        for i in 0..m {
            if self.tang[i] == Tangential::Stick {
                brows.push((true, i));
            }
        }
        let row = |&(t, i): &(bool, usize)| if t { self.fr.t.row(i) } else { qp.a.row(i) };
        let b: Vec<f64> = brows
            .iter()
            .map(|&(t, i)| if t { self.fr.t0[i] } else { qp.g[i] })
            .collect();
        // d' = d − T_Lᵀ λ_L.
        let mut dp = qp.d.clone();
        let fl: Vec<f64> = (0..m).map(|i| -self.slip_force(i, self.tang[i])).collect();
        self.fr.t.mul_t_add(&fl, &mut dp);
        // Rigid motions left free by B.
        let free = self.free_motions(&brows);
        if !free.is_empty() {
            if let Some(z) = self.unbounded_along(&free) {
                return Ok(Some(Status::Unbounded { direction: z }));
            }
        }
        if let (Some(d), Some(mu_c)) = (&self.dual, &self.coulomb) {
            let normal: Vec<(usize, f64)> = (0..m)
                .filter(|&i| self.in_n[i] && !d.null[i])
                .map(|i| match self.tang[i] {
                    Tangential::Slip(pos) => (i, if pos { mu_c[i] } else { -mu_c[i] }),
                    Tangential::Stick => (i, 0.0),
                })
                .collect();
            let stick: Vec<usize> = (0..m)
                .filter(|&i| self.tang[i] == Tangential::Stick && !d.null[m + i])
                .map(|i| m + i)
                .collect();
            let mut c = qp.g.clone();
            c.extend_from_slice(&self.fr.t0);
            if let Some((mu, alpha)) = d.solve_coulomb(&normal, &stick, &c) {
                self.bx = d.bx(&mu, &alpha);
                self.ln = mu[..m].to_vec();
                self.lt = mu[m..].to_vec();
                self.s = self.fr.slip_bound(&self.ln);
                self.rows = normal.iter().map(|&(i, _)| i).chain(stick).collect();
                self.mu = mu;
                self.alpha = alpha;
                self.x_stale = true;
                return Ok(None);
            }
            log::debug!("ssn: friction: the Coulomb system of the working set is singular");
            return Ok(Some(Status::Failed(Failure::Breakdown(
                "ssn: the Coulomb system of a working set is singular".into(),
            ))));
        }
        if let Some(d) = &self.dual {
            let rows: Vec<usize> = brows
                .iter()
                .map(|&(t, i)| if t { m + i } else { i })
                .filter(|&j| !d.null[j])
                .collect();
            let mut f = vec![0.0; 2 * m];
            for i in 0..m {
                f[m + i] = self.slip_force(i, self.tang[i]);
            }
            let mut c = qp.g.clone();
            c.extend_from_slice(&self.fr.t0);
            if let Some((w, alpha)) = d.solve(&rows, &f, &d.bk0, &c, &d.e) {
                let mut mu = f;
                for (&j, wj) in rows.iter().zip(w) {
                    mu[j] = wj;
                }
                self.bx = d.bx(&mu, &alpha);
                self.ln = mu[..m].to_vec();
                self.lt = mu[m..].to_vec();
                self.mu = mu;
                self.alpha = alpha;
                self.x_stale = true;
                self.rows = rows;
                return Ok(None);
            }
            log::debug!("ssn: friction: H_JJ of the working set is singular: a sparse step");
        }
        // K = C + ρBᵀB on the pattern of C + AᵀA + TᵀT (same pattern every step).
        let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(qp.c.nnz());
        for i in 0..n {
            let (cols, vals) = qp.c.row(i);
            for (&j, &v) in cols.iter().zip(vals) {
                trip.push((i, j, v));
            }
        }
        let mut in_b = vec![[false; 2]; m];
        for &(t, i) in &brows {
            in_b[i][t as usize] = true;
        }
        for (mat, t) in [(&qp.a, false), (&self.fr.t, true)] {
            for i in 0..m {
                let w = if in_b[i][t as usize] {
                    self.rho[i][t as usize]
                } else {
                    0.0
                };
                let (cols, vals) = mat.row(i);
                for (&j, &a) in cols.iter().zip(vals) {
                    for (&k, &c) in cols.iter().zip(vals) {
                        trip.push((j, k, w * a * c));
                    }
                }
            }
        }
        let kmat = Csr::from_triplets(n, n, &trip);
        let fac = self.ws.cholesky(&kmat, &free)?;
        // Augmented Lagrangian steps from the last multipliers.
        let mut mu: Vec<f64> = brows
            .iter()
            .map(|&(t, i)| if t { self.lt[i] } else { self.ln[i] })
            .collect();
        let bscale = norm_inf(&b);
        let mut x = vec![0.0; n];
        for _ in 0..AL_MAX {
            // x = K⁻¹(d' + Bᵀ(ρb − μ))
            let mut rhs = dp.clone();
            for (k, br) in brows.iter().enumerate() {
                let (cols, vals) = row(br);
                let w = self.rho[br.1][br.0 as usize] * b[k] - mu[k];
                for (&j, &a) in cols.iter().zip(vals) {
                    rhs[j] += w * a;
                }
            }
            x = fac.solve(&rhs);
            self.inner += 1;
            let mut res = 0.0f64;
            for (k, br) in brows.iter().enumerate() {
                let (cols, vals) = row(br);
                let bx: f64 = cols.iter().zip(vals).map(|(&j, &a)| a * x[j]).sum();
                mu[k] += self.rho[br.1][br.0 as usize] * (bx - b[k]);
                res = res.max((bx - b[k]).abs());
            }
            let xs = norm_inf(&x).max(bscale).max(f64::MIN_POSITIVE);
            if res <= 1e-14 * xs {
                break;
            }
        }
        if !x.iter().all(|v| v.is_finite()) {
            return Ok(Some(Status::Failed(Failure::Breakdown(
                "the KKT solve of a working set gave a non-finite iterate".into(),
            ))));
        }
        self.bx = qp.a.mul(&x);
        self.bx.extend(self.fr.t.mul(&x));
        self.x = x;
        self.x_stale = false;
        self.ln = vec![0.0; m];
        self.lt = (0..m).map(|i| self.slip_force(i, self.tang[i])).collect();
        for (k, &(t, i)) in brows.iter().enumerate() {
            if t {
                self.lt[i] = mu[k];
            } else {
                self.ln[i] = mu[k];
            }
        }
        Ok(None)
    }

    /// An orthonormal basis (as vectors of ℝⁿ) of the rigid motions z with
    /// B z = 0.
    fn free_motions(&self, brows: &[(bool, usize)]) -> Vec<Vec<f64>> {
        let k = self.r.len();
        if k == 0 {
            return vec![];
        }
        let mut g = vec![vec![0.0; k]; k];
        let mut bnorm = 0.0;
        for &(t, i) in brows {
            let (cols, vals) = if t {
                self.fr.t.row(i)
            } else {
                self.qp.a.row(i)
            };
            bnorm += vals.iter().map(|v| v * v).sum::<f64>();
            let br: Vec<f64> = self
                .r
                .iter()
                .map(|rl| cols.iter().zip(vals).map(|(&j, &a)| a * rl[j]).sum())
                .collect();
            for a in 0..k {
                for c in 0..k {
                    g[a][c] += br[a] * br[c];
                }
            }
        }
        let (vals, vecs) = sym_eigen(&g);
        let tol = 1e-9 * bnorm.max(1.0) / self.qp.n().max(1) as f64;
        vals.iter()
            .zip(&vecs)
            .filter(|(e, _)| !(**e > tol))
            .map(|(_, v)| {
                let mut z = vec![0.0; self.qp.n()];
                for (c, rl) in v.iter().zip(&self.r) {
                    for (zj, rj) in z.iter_mut().zip(rl) {
                        *zj += c * rj;
                    }
                }
                z
            })
            .collect()
    }

    /// A free rigid motion ±z (z in span `free`) along which the loads do
    /// more work than friction dissipates and no contact row closes.
    fn unbounded_along(&self, free: &[Vec<f64>]) -> Option<Vec<f64>> {
        let qp = self.qp;
        // Steepest: the loads projected on the free motions, then each basis vector.
        let mut cands: Vec<Vec<f64>> = vec![];
        let mut p = vec![0.0; qp.n()];
        for z in free {
            let w = dot(&qp.d, z);
            for (pj, zj) in p.iter_mut().zip(z) {
                *pj += w * zj;
            }
        }
        cands.push(p);
        for z in free {
            cands.push(z.clone());
            cands.push(z.iter().map(|v| -v).collect());
        }
        for z in cands {
            let zmax = norm_inf(&z);
            if !(zmax > 0.0) {
                continue;
            }
            let az = qp.a.mul(&z);
            let arow: Vec<f64> = (0..qp.m())
                .map(|i| {
                    let (_, vals) = qp.a.row(i);
                    vals.iter().map(|v| v.abs()).sum::<f64>() * zmax
                })
                .collect();
            if az.iter().zip(&arow).any(|(a, s)| *a > 1e-10 * s) {
                continue;
            }
            let tz = self.fr.t.mul(&z);
            let work = dot(&qp.d, &z);
            let dissipation: f64 = tz.iter().zip(&self.s).map(|(t, s)| s * t.abs()).sum();
            let dscale: f64 = qp.d.iter().zip(&z).map(|(d, z)| (d * z).abs()).sum();
            if work - dissipation > 1e-10 * dscale {
                return Some(z);
            }
        }
        None
    }

    fn record(&self, iter: usize) -> IterRecord {
        IterRecord {
            iter,
            residual: self.dual_residual(),
            active: self.in_n.iter().filter(|a| **a).count(),
            inner: self.inner,
        }
    }
}

impl Iterative for State<'_> {
    /// One Newton step: the sets predicted at the last answer (one row at
    /// a time if they were seen before or free a motion friction holds; as
    /// predicted after a new bound), their solve, and the end of the Tresca
    /// solve when the answer predicts the sets it was solved with.
    fn step(&mut self) -> Step {
        let it = self.outer + 1;
        self.outer += 1;
        if self.fresh {
            // A new bound (the Coulomb loop's update): its prediction.
            self.fresh = false;
            self.predicted = None;
            let (n_set, tang) = self.predict();
            self.in_n = n_set;
            self.tang = tang;
        } else if self.last.is_some() {
            let (n_set, tang) = self.predicted.take().unwrap_or_else(|| self.predict());
            if self.visited.contains(&(n_set.clone(), tang.clone()))
                || self.frees_a_bounded_motion(&n_set, &tang)
            {
                // A working set seen before (the full step cycles), or one
                // that would let a body slide although friction holds it
                // (an overshoot): change only the row that violates its
                // prediction most (as in ssn's single changes).
                self.single_change(&n_set, &tang);
            } else {
                self.in_n = n_set;
                self.tang = tang;
            }
        }
        self.visited.insert((self.in_n.clone(), self.tang.clone()));
        self.last = Some((self.in_n.clone(), self.tang.clone()));
        log::debug!(
            "ssn: friction step {it}: |N| = {}, stick {}, slip {}",
            self.in_n.iter().filter(|b| **b).count(),
            self.tang
                .iter()
                .filter(|t| **t == Tangential::Stick)
                .count(),
            self.tang
                .iter()
                .zip(&self.in_n)
                .filter(|(t, n)| **n && **t != Tangential::Stick)
                .count()
        );
        match self.solve_set() {
            Ok(None) => {
                let rec = self.record(it);
                // A Tresca problem whose sets cycle (single changes walking
                // back and forth) never settles: stop after a budget of
                // steps without a better residual, counted, never timed.
                if rec.residual < self.best.0 * (1.0 - 1e-9) {
                    self.best = (rec.residual, 0);
                } else {
                    self.best.1 += 1;
                }
                let budget = cycle_budget(self.qp.m());
                if self.best.1 > budget {
                    return Step::Done(
                        Status::Failed(Failure::Cycling {
                            best: self.best.0,
                            steps: budget,
                        }),
                        rec,
                    );
                }
                // The answer predicts the sets it was solved with: a KKT
                // point of the current Tresca problem.
                let next = self.predict();
                let settled = self.last.as_ref() == Some(&next);
                self.predicted = Some(next);
                if settled {
                    Step::Done(Status::Converged, rec)
                } else {
                    Step::Continue(rec)
                }
            }
            Ok(Some(status)) => Step::Done(status, self.record(it)),
            Err(e) => {
                let msg = e.to_string();
                self.error = Some(e);
                Step::Done(
                    Status::Failed(Failure::Breakdown(msg)),
                    IterRecord::default(),
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::qp::{registry, SlipBound, SolveOptions, Status};

    use crate::qp::testing::friction_point as point;

    #[test]
    fn a_point_sticks_and_slips_by_coulomb_and_tresca() {
        let opts = SolveOptions::default();
        for (fx, mu) in [(0.3, 0.5), (-0.3, 0.5), (0.7, 0.5), (-0.7, 0.5), (0.5, 0.0)] {
            for bound in [
                SlipBound::Coulomb(vec![mu]),
                SlipBound::Tresca(vec![mu * 1.0]),
            ] {
                let qp = point(2.0, fx, -1.0, bound.clone());
                let r = registry::solve("ssn", &qp, &opts).unwrap();
                assert!(r.status.converged(), "{fx} {mu}: {:?}", r.status);
                assert!(r.kkt.within(1e-10), "{:?}", r.kkt);
                assert!((r.lambda[0] - 1.0).abs() < 1e-12);
                let lt = if fx.abs() <= mu { fx } else { mu * fx.signum() };
                assert!(
                    (r.lambda_t[0] - lt).abs() < 1e-12,
                    "{fx} {mu}: {:?}",
                    r.lambda_t
                );
                assert!((r.x[0] - (fx - lt) / 2.0).abs() < 1e-12, "{:?}", r.x);
            }
        }
    }

    /// A point free along x (a floating body) held by friction alone: it
    /// sticks below the bound and is unbounded above it. At rest (x = 0,
    /// t0 = 0) the answer is checked to rounding: the certificate measures
    /// slips against max|x|, itself rounding there (the dual path leaves
    /// |x| ≈ 10⁻³³), so it is judged on the same point with a slip offset
    /// t0 = 0.2 (x = (0.2, 0)).
    #[test]
    fn a_floating_point_sticks_or_is_unbounded() {
        let opts = SolveOptions::default();
        let r = registry::solve(
            "ssn",
            &point(0.0, 0.3, -1.0, SlipBound::Coulomb(vec![0.5])),
            &opts,
        )
        .unwrap();
        assert!(r.status.converged(), "{:?}", r.status);
        assert!((r.lambda[0] - 1.0).abs() < 1e-12, "{:?}", r.lambda);
        assert!((r.lambda_t[0] - 0.3).abs() < 1e-12 && r.x[0].abs() < 1e-12);
        let mut qp = point(0.0, 0.3, -1.0, SlipBound::Coulomb(vec![0.5]));
        if let Some(f) = qp.friction.as_mut() {
            f.t0 = vec![0.2];
        }
        let r = registry::solve("ssn", &qp, &opts).unwrap();
        assert!(
            r.status.converged() && r.kkt.within(1e-10),
            "{:?} {:?}",
            r.status,
            r.kkt
        );
        assert!((r.lambda[0] - 1.0).abs() < 1e-12, "{:?}", r.lambda);
        assert!((r.lambda_t[0] - 0.3).abs() < 1e-12, "{:?}", r.lambda_t);
        assert!(
            (r.x[0] - 0.2).abs() < 1e-12 && r.x[1].abs() < 1e-12,
            "{:?}",
            r.x
        );
        let r = registry::solve(
            "ssn",
            &point(0.0, 0.7, -1.0, SlipBound::Coulomb(vec![0.5])),
            &opts,
        )
        .unwrap();
        assert!(
            matches!(r.status, Status::Unbounded { .. }),
            "{:?}",
            r.status
        );
    }

    /// Huge but finite bounds: the point, resting on a floor 0.5 below it,
    /// sticks (λ_t = fx, certified, finite energy) with ssn and mprgp, also
    /// where μλ_n overflows (μ = f64::MAX, λ_n = 1.5); a Tresca bound whose force on the unknowns
    /// overflows (f64::MAX on a tangential row of coefficient 10) is
    /// refused naming the slip bound s. Never a NaN or an infinity.
    #[test]
    fn a_huge_bound_sticks_or_is_refused_by_name() {
        for (bound, fy, tscale) in [
            (SlipBound::Tresca(vec![1e307]), -3.0, 1.0),
            (SlipBound::Tresca(vec![f64::MAX]), -3.0, 1.0),
            (SlipBound::Tresca(vec![1e307]), -3.0, 10.0),
            (SlipBound::Coulomb(vec![f64::MAX]), -3.0, 1.0),
            (SlipBound::Tresca(vec![f64::MAX]), -3.0, 10.0),
        ] {
            let mut qp = point(2.0, 0.3, fy, bound.clone());
            qp.g = vec![0.5];
            if let Some(f) = qp.friction.as_mut() {
                f.t.data.iter_mut().for_each(|v| *v *= tscale);
            }
            let refused = match &bound {
                SlipBound::Tresca(s) => !(s[0] * tscale).is_finite(),
                SlipBound::Coulomb(_) => false,
            };
            for m in ["ssn", "mprgp"] {
                let what = format!("{bound:?}, T × {tscale}, {m}");
                match registry::solve(m, &qp, &SolveOptions::default()) {
                    Ok(r) => {
                        assert!(!refused, "{what}: solved");
                        assert!(
                            r.status.converged() && r.kkt.within(1e-10),
                            "{what}: {:?}",
                            r.kkt
                        );
                        assert!(
                            (r.lambda_t[0] * tscale - 0.3).abs() < 1e-12,
                            "{what}: {:?}",
                            r.lambda_t
                        );
                        assert!(
                            r.x[0].abs() < 1e-12 && r.energy.is_finite(),
                            "{what}: {:?}",
                            r.x
                        );
                    }
                    Err(e) => {
                        assert!(refused, "{what}: {e}");
                        assert!(
                            e.to_string().contains("slip bound s of contact row 0"),
                            "{what}: {e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn other_methods_refuse_friction_and_nan_fails_the_certificate() {
        let qp = point(2.0, 0.3, -1.0, SlipBound::Coulomb(vec![0.5]));
        let e = registry::solve("cgc", &qp, &SolveOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .contains("does not solve contact with friction"),
            "{e}"
        );
        let k = crate::qp::kkt::residuals_with_friction(&qp, &[0.0, 0.0], &[1.0], &[f64::NAN]);
        assert!(!k.within(1e300));
        // A tangential force above the bound fails the friction residual.
        let k = crate::qp::kkt::residuals_with_friction(&qp, &[0.0, 0.0], &[1.0], &[0.6]);
        assert!(k.friction > 1e-3, "{k:?}");
        // A slip against λ_t fails it too.
        let k = crate::qp::kkt::residuals_with_friction(&qp, &[0.1, 0.0], &[1.0], &[-0.5]);
        assert!(k.friction > 1e-3, "{k:?}");
    }
}
