//! Uzawa's method (docs/methods.md §4.5): projected gradient ascent on the
//! dual, x_new = C⁻¹(d − Aᵀλ), λ ← max(0, λ + ρ(A x_new − g)), one Cholesky
//! factor of C reused. ρ = the setting `rho`, or 1/‖H‖_est by power iteration
//! ([`crate::linalg::power`]; convergence needs 0 < ρ < 2/‖H‖).
//!
//! `accelerate = false` with a coercive C runs the report's plain iteration
//! (`Uzawa`): stop when ‖x_new − x‖ ≤ tol·‖x_new‖ and the relative primal
//! violation max((A x_new − g)⁺)/max|x_new| ≤ tol; the pair returned is
//! (x_new, the λ that produced it). Its rate is 1 − O(1/κ(H)). Otherwise
//! (`UzawaStep` in the SMALBE host of [`crate::qp::dual`], which enforces
//! Gλ = e for a semicoercive C with ρ_SMALBE = ‖PHP‖) the update is applied
//! at the Nesterov/FISTA point y = λ + β_k(λ − λ_prev) with the gradient
//! restart of O'Donoghue & Candès (rate 1 − O(1/√κ)), stopping at
//! ‖θ'ᴾ‖ ≤ [`UZAWA_MARGIN`]·tol·‖h‖.

use crate::linalg::sparse::norm;
use crate::linalg::sparse::norm_inf;
use crate::qp::dual::{solve_with, BoundStep, DualOp, DualState, StepKind};
use crate::qp::executor::{Iterative, Step};
use crate::qp::method::{Capabilities, MethodId};
use crate::qp::{Context, IterRecord, Method, Output, QpError, QpProblem, Settings, Status};
use std::time::Instant;

/// The accelerated (SMALBE-hosted) Uzawa stops at UZAWA_MARGIN·tol.
pub const UZAWA_MARGIN: f64 = 0.1;

/// Uzawa's method (docs/methods.md §4.5).
pub struct UzawaMethod;

impl Method for UzawaMethod {
    fn id(&self) -> MethodId {
        MethodId::Uzawa
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "Uzawa's method with Cholesky inner solves (§4.5)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let opts = ctx.settings;
    if opts.uzawa.accelerate || !qp.kernel.is_empty() {
        let step = UzawaStep {
            rho: opts.uzawa.rho,
            momentum: opts.uzawa.accelerate,
            ..Default::default()
        };
        // Gradient steps approach λ along the weakly determined directions
        // of H last, so the dual gradient is driven UZAWA_MARGIN further
        // than `tol` (not below the rounding level).
        let tight = Settings {
            tol: (opts.tol * UZAWA_MARGIN).max(f64::EPSILON).min(opts.tol),
            ..opts.clone()
        };
        return solve_with(qp, &mut ctx.sub(&tight), step, "uzawa");
    }
    let t0 = Instant::now();
    let chol = ctx.ws.cholesky(&qp.c, &[])?;
    let mut op = DualOp::new(qp, chol, vec![], "uzawa")?;
    let t_f = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let rho = match opts.uzawa.rho {
        Some(r) => r,
        None => {
            let mu = op.norm_estimate();
            if mu > 0.0 && mu.is_finite() {
                1.0 / mu
            } else {
                1.0
            }
        }
    };
    log::info!("uzawa: ρ = {rho:.4e}");
    let t_rho = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let mut st = Uzawa {
        qp,
        op,
        rho,
        tol: opts.tol,
        x: vec![0.0; qp.n()],
        lam: vec![0.0; qp.m()],
        lam_x: vec![0.0; qp.m()],
        solves: 0,
    };
    let mut exec = ctx.executor("uzawa");
    let (status, iters) = exec.run(&mut st);
    let t_it = t2.elapsed().as_secs_f64();
    let active: Vec<bool> = st.lam_x.iter().map(|&l| l > 0.0).collect();
    Ok(Output {
        x: st.x,
        lambda: st.lam_x,
        lambda_t: vec![],
        active,
        status,
        iterations: iters,
        inner_iterations: st.solves,
        log: exec.log,
        timings: vec![
            ("factor".into(), t_f),
            ("rho".into(), t_rho),
            ("iterate".into(), t_it),
        ],
    })
}

/// The report's plain Uzawa iteration for a coercive C (no row scaling, no
/// momentum), one solve with the factor per executor iteration.
pub(crate) struct Uzawa<'a> {
    qp: &'a QpProblem,
    /// x(λ) through the factor of C.
    op: DualOp<'a>,
    /// Step length ρ.
    rho: f64,
    tol: f64,
    /// The last x_new.
    x: Vec<f64>,
    /// λ for the next solve.
    lam: Vec<f64>,
    /// The λ that produced x.
    lam_x: Vec<f64>,
    /// Solves in the iteration (reported as inner iterations).
    solves: usize,
}

impl Iterative for Uzawa<'_> {
    fn step(&mut self) -> Step {
        let qp = self.qp;
        let xn = self.op.x_of(&self.lam);
        self.solves += 1;
        let diff: f64 = xn
            .iter()
            .zip(&self.x)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        let xnorm = norm(&xn);
        let err = if xnorm > 0.0 { diff / xnorm } else { diff };
        let ax = qp.a.mul(&xn);
        let mut pmax = 0.0f64;
        self.lam_x.copy_from_slice(&self.lam);
        for ((l, a), g) in self.lam.iter_mut().zip(&ax).zip(&qp.g) {
            let v = a - g;
            pmax = pmax.max(v);
            *l = (*l + self.rho * v).max(0.0);
        }
        let xinf = norm_inf(&xn);
        let primal = if xinf > 0.0 { pmax / xinf } else { pmax };
        self.x = xn;
        let rec = IterRecord {
            iter: 0,
            residual: err,
            active: self.lam_x.iter().filter(|&&l| l > 0.0).count(),
            inner: self.solves,
        };
        if err <= self.tol && primal <= self.tol {
            Step::Done(Status::Converged, rec)
        } else {
            Step::Continue(rec)
        }
    }
}

/// Uzawa as the bound step of the dual host: λ̂ ← max(ℓ, y − ρθ'(y)), y = λ̂
/// without momentum, the Nesterov extrapolation with it; then θ' at the new
/// λ̂ (one solve with the factor; θ' is affine, so θ'(y) is extrapolated
/// from the last two gradients).
#[derive(Default)]
pub(crate) struct UzawaStep {
    /// The caller's ρ (else 1/‖PHP + ρQ‖_est).
    rho: Option<f64>,
    /// Nesterov momentum with gradient restart.
    momentum: bool,
    /// The step length in use.
    abar: f64,
    /// Previous iterate and gradient (empty until the first step).
    lam_prev: Vec<f64>,
    g_prev: Vec<f64>,
    /// FISTA's t_k.
    t_mom: f64,
}

impl BoundStep for UzawaStep {
    /// A larger SMALBE ρ would shorten the fixed step on the PHP part.
    fn rho_factor(&self) -> f64 {
        1.0
    }

    fn start(&mut self, _s: &DualState, h_norm: f64) {
        self.abar = self.rho.unwrap_or(1.0 / h_norm);
        self.t_mom = 1.0;
    }

    /// The gradient changed discontinuously: restart the momentum.
    fn restart(&mut self, s: &DualState) {
        self.t_mom = 1.0;
        self.lam_prev = s.lam.clone();
        self.g_prev = s.g.clone();
    }

    fn step(&mut self, s: &mut DualState) -> Result<StepKind, String> {
        let m = s.lam.len();
        let (y, gy) = if self.momentum && self.lam_prev.len() == m {
            let t_new = 0.5 * (1.0 + (1.0 + 4.0 * self.t_mom * self.t_mom).sqrt());
            let b = (self.t_mom - 1.0) / t_new;
            self.t_mom = t_new;
            let y: Vec<f64> = (0..m)
                .map(|i| s.lam[i] + b * (s.lam[i] - self.lam_prev[i]))
                .collect();
            let gy: Vec<f64> = (0..m)
                .map(|i| s.g[i] + b * (s.g[i] - self.g_prev[i]))
                .collect();
            (y, gy)
        } else {
            (s.lam.clone(), s.g.clone())
        };
        let xn: Vec<f64> = (0..m)
            .map(|i| (y[i] - self.abar * gy[i]).max(s.lb[i]))
            .collect();
        if self.momentum {
            let restart: f64 = (0..m).map(|i| (y[i] - xn[i]) * (xn[i] - s.lam[i])).sum();
            if restart > 0.0 {
                self.t_mom = 1.0;
            }
        }
        self.lam_prev = std::mem::replace(&mut s.lam, xn);
        self.g_prev = s.g.clone();
        s.refresh();
        if s.g.iter().any(|v| !v.is_finite()) {
            return Err("uzawa: the iteration produced NaN or Inf".into());
        }
        Ok(StepKind::Gradient)
    }
}
