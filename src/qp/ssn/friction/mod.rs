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
//! On the dual path the first Newton step starts from the sets of coarser
//! contact discretisations ([`nested`]: rows summed in pairs, level by
//! level), so the count does not follow the number of rows a slip zone's
//! front must cross. There Coulomb runs the Newton steps on Coulomb's
//! problem itself, s = μλ_n of the current iterate and λ_t = μσλ_n on the
//! slipping rows ([`dual::DenseDual::solve_coulomb`]), from the coarse
//! start, or else from the glued answer (S = N);
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

mod dual;
mod motions;
mod nested;
mod plane;
mod sets;
mod update;
use dual::{unfinished, Dual, Law};
use sets::{start_tang, warm_sets, Rule, Tangential};

use crate::qp::{Context, Friction, IterRecord, Output, QpError, QpProblem, Status};

/// ρᵢ = RHO · (the row's stiffness) in K = C + Bᵀ diag(ρ) B.
const RHO: f64 = super::RHO_FACTOR;
/// Augmented Lagrangian steps per Newton step, at most.
const AL_MAX: usize = 200;
/// Sweeps in a row that do not halve |Bx − b| after which the augmented
/// Lagrangian steps stop (docs/methods.md §9.2).
const AL_STALL: usize = 3;
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
    if fr.frame == crate::qp::Frame::Plane {
        return plane::solve(qp, fr, ctx);
    }
    if ctx.settings.ssn.path == SsnPath::Iterative {
        return Err(QpError::Unsupported(
            "ssn_path = \"iterative\" solves friction on solid models (discs) only; \
             use ssn_path = \"auto\" for plane friction (docs/methods.md §12.3)"
                .into(),
        ));
    }
    let r = orthonormal_kernel(&qp.c, &qp.kernel)?;
    let dual = match ctx.settings.ssn.path {
        SsnPath::Auto | SsnPath::Schur => Dual::new(qp, fr, &r, ctx.ws)?,
        path => {
            log::debug!("ssn: friction: the sparse path (ssn_path = {path:?}); no coarse start, the glued start");
            None
        }
    };
    let mut st = State::new(qp, fr, r, ctx);
    st.hold_free_bodies();
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
    let target = ctx.settings.kkt_target;
    let proven = coulomb::certificate(qp);
    coulomb::solve(fr, &mut step, "ssn", &proven, target)
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
            // The coarse start where the dual form has one (it finds the
            // slip zone's front in a few steps, where the last step's sets
            // walk it a few rows a step), else the last step's sets.
            let started = !st.glued && (st.coarse_start() || st.dual.is_none() && st.warm_start());
            if !started {
                st.start_sets();
            }
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

    fn coulomb_first(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        let st = &mut self.st;
        st.dual.as_ref()?;
        st.coulomb = Some(mu.to_vec());
        st.s = vec![0.0; mu.len()];
        st.glued = false;
        st.visited.clear();
        if !st.coarse_start() {
            st.coulomb = None;
            return None;
        }
        let r = self.run();
        if !matches!(&r, Ok(t) if t.status.converged()) {
            // The glued start that follows starts afresh, as without this try.
            let st = &mut self.st;
            st.in_n = st.in_n0.clone();
            st.last = None;
            st.predicted = None;
            st.fresh = false;
            st.visited.clear();
        }
        Some(r)
    }

    fn warm_bound(&mut self, _mu: &[f64]) -> Option<Vec<f64>> {
        // The sparse path (no coarse start, no direct iteration): the last
        // load step's sets and its bound μλ_n instead of the glued start.
        let st = &self.st;
        if st.dual.is_some() {
            return None;
        }
        let s = st
            .warm
            .as_ref()
            .map(|(_, _, l)| st.fr.slip_bound(&l.normal))?;
        log::debug!(
            "ssn: friction: the fixed point starts from the last step's bound μλ_n and sets"
        );
        Some(s)
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
    /// The normal set of the start ([`State::hold_free_bodies`]).
    in_n0: Vec<bool>,
    tang: Vec<Tangential>,
    /// The sets of the last solve (None before the first).
    last: Option<(Vec<bool>, Vec<Tangential>)>,
    /// The sets of the last solve that gave an iterate (a failed one
    /// leaves the iterate before it).
    solved: Option<(Vec<bool>, Vec<Tangential>)>,
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
    /// The multiplier warm start, until the first solve takes it: its sets
    /// and its λ.
    warm: Option<(Vec<bool>, Vec<Tangential>, crate::qp::Multipliers)>,
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
            in_n0: in_n.clone(),
            in_n,
            last: None,
            solved: None,
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
            warm: ctx.lambda0.map(|l| {
                let (n_set, tang) = warm_sets(fr, l);
                (n_set, tang, l.clone())
            }),
        }
    }

    /// Start from the multiplier warm start if there is one (and it is not
    /// taken yet): its sets and λ. Returns whether it did.
    fn warm_start(&mut self) -> bool {
        let Some((n_set, tang, l)) = self.warm.take() else {
            return false;
        };
        let stick = tang
            .iter()
            .zip(&n_set)
            .filter(|(t, n)| **n && **t == Tangential::Stick)
            .count();
        let closed = n_set.iter().filter(|n| **n).count();
        log::debug!(
            "ssn: friction: the last step's sets: stick {stick}, slip {}, open {}",
            closed - stick,
            n_set.len() - closed
        );
        self.in_n = n_set;
        self.tang = tang;
        self.ln = l.normal;
        self.lt = l.tangential;
        self.last = None;
        self.predicted = None;
        self.fresh = false;
        true
    }

    /// Form x from the last dual-space answer if it is not yet (one
    /// backward pass on the bordered factor).
    fn ensure_x(&mut self) -> Result<(), QpError> {
        if !self.x_stale {
            return Ok(());
        }
        // A stale x comes from the dual path only.
        let Some(d) = self.dual.as_ref() else {
            return Err(unfinished());
        };
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
        self.tang = start_tang(&self.in_n, &self.s, self.glued);
    }

    /// Start the next Newton steps from the sets of the coarse levels
    /// ([`nested`]) on the dual path: Coulomb's direct iteration before any
    /// glued solve, or a Tresca problem's first solve. Returns whether it did.
    fn coarse_start(&mut self) -> bool {
        let Some(d) = self.dual.as_ref() else {
            return false;
        };
        let (coulomb, bound) = match &self.coulomb {
            Some(mu) => (true, mu.as_slice()),
            None => (false, self.s.as_slice()),
        };
        let t = std::time::Instant::now();
        let Some(cs) = nested::coarse_start(&nested::Fine {
            dense: d,
            g: &self.qp.g,
            t0: &self.fr.t0,
            cn: &self.cn,
            ct: &self.ct,
            coulomb,
            bound,
            in_n: &self.in_n,
        }) else {
            log::debug!("ssn: friction: no coarse start (too few rows to coarsen, or a coarse system is singular): the method's own start");
            return false;
        };
        log::debug!(
            "ssn: friction: coarse start: (rows, Newton steps) per level {:?}, {:.3} s",
            cs.levels,
            t.elapsed().as_secs_f64()
        );
        self.in_n = cs.in_n;
        self.tang = cs.tang;
        self.last = None;
        self.predicted = None;
        self.fresh = false;
        true
    }

    /// Ax and the slip v = T x − t0 of the current iterate.
    fn ax_v(&self) -> (&[f64], Vec<f64>) {
        let (ax, tx) = self.bx.split_at(self.qp.m());
        let v = tx.iter().zip(&self.fr.t0).map(|(t, t0)| t - t0).collect();
        (ax, v)
    }

    /// The sets predicted at the current (x, λ_n, λ_t).
    fn predict(&self) -> (Vec<bool>, Vec<Tangential>) {
        let m = self.qp.m();
        let rule = Rule {
            g: &self.qp.g,
            t0: &self.fr.t0,
            cn: &self.cn,
            ct: &self.ct,
            forced: self.dual.as_ref().map(|d| &d.null[m..]),
        };
        rule.predict(&self.bx, &self.ln, &self.lt, &self.s, self.glued)
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
        // Rigid motions left free by B. Under Coulomb's law inside the
        // iteration the slipping rows' forces μσλ_n enter the system with
        // λ_n unknown, so B's rows alone do not tell what holds a body: that
        // system is singular when nothing does (a breakdown, which sends
        // the loop to the glued start and then to Tresca problems, whose
        // bounds make the test below exact).
        let free = self.free_motions(&brows);
        if !(free.is_empty() || self.coulomb.is_some() && self.dual.is_some()) {
            if let Some(z) = self.unbounded_along(&free) {
                return Ok(Some(Status::Unbounded { direction: z }));
            }
        }
        if let Some(d) = &self.dual {
            let law = match &self.coulomb {
                Some(mu_c) => Law::Coulomb(mu_c),
                None => Law::Tresca {
                    s: &self.s,
                    glued: self.glued,
                },
            };
            let mut c = qp.g.clone();
            c.extend_from_slice(&self.fr.t0);
            if let Some(sol) = d.set_solve(&self.in_n, &self.tang, law, &c) {
                self.bx = d.bx(&sol.mu, &sol.alpha);
                self.ln = sol.mu[..m].to_vec();
                self.lt = sol.mu[m..].to_vec();
                if self.coulomb.is_some() {
                    self.s = self.fr.slip_bound(&self.ln);
                }
                self.rows = sol.rows;
                self.mu = sol.mu;
                self.alpha = sol.alpha;
                self.x_stale = true;
                return Ok(None);
            }
            if self.coulomb.is_some() {
                log::debug!("ssn: friction: the Coulomb system of the working set is singular");
                return Ok(Some(Status::Failed(Failure::Breakdown(
                    "ssn: the Coulomb system of a working set is singular".into(),
                ))));
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
        let (mut sweeps, mut last_res, mut stalled) = (0, f64::INFINITY, 0);
        for _ in 0..AL_MAX {
            sweeps += 1;
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
            // Done at rounding, or when three sweeps in a row no longer
            // halve |Bx − b| (its floor: rounding at 1.4·10⁻¹³, or rows that
            // contradict each other, where more sweeps only grow μ).
            stalled = if res > 0.5 * last_res * xs {
                stalled + 1
            } else {
                0
            };
            last_res = res / xs;
            if res <= 1e-14 * xs || stalled >= AL_STALL {
                break;
            }
        }
        log::debug!(
            "ssn: friction: sparse step: {sweeps} augmented Lagrangian sweeps, |Bx − b| {last_res:.2e} of max(|x|, |b|)"
        );
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
                self.solved = Some((self.in_n.clone(), self.tang.clone()));
                let rec = self.record(it);
                log::debug!("ssn: friction step {it}: residual {:.3e}", rec.residual);
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
                // A set seen before predicted at an answer already exact to
                // `tol`: the sets flip on a degenerate row (rows that depend
                // on each other, where three faults meet) and the answer is
                // a KKT point of the Tresca problem whichever way it falls;
                // going on only walks the cycle (432 Newton steps on the
                // geodynamic faults at μ = 0.1 before it was taken).
                let cycled = !settled && rec.residual <= self.tol && self.visited.contains(&next);
                self.predicted = Some(next);
                if settled || cycled {
                    Step::Done(Status::Converged, rec)
                } else {
                    Step::Continue(rec)
                }
            }
            Ok(Some(status)) => {
                if matches!(status, Status::Failed(_)) {
                    // The iterate is the last solved one: its sets with it
                    // (the loop may still take it if it passes the
                    // certificate, [`coulomb::solve`]).
                    if let Some((n_set, tang)) = self.solved.clone() {
                        self.in_n = n_set;
                        self.tang = tang;
                    }
                }
                Step::Done(status, self.record(it))
            }
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
mod tests;
