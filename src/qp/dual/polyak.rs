//! The `dual` method (docs/methods.md §4.6): the report's CGC on the bound
//! constraints of the dual, i.e. Polyak's CG with constraints: CG on the
//! free face; a step that would cross a bound stops on it and restarts CG;
//! when the face is minimised the bounds with negative multipliers are
//! released (all at once, or the most negative with `multiple_release =
//! false`; the rows −eᵢ are orthonormal, so releasing all is safe).
//!
//! Coercive C: `DualCgc`, one executor iteration per face, stopping at
//! ‖projected θ'‖ ≤ tol·max(‖Ax(λ)‖, ‖g‖) with the scale taken at the start
//! of each face (A x(λ) = g − θ'(λ) is free), x = C⁻¹(d − Aᵀλ) at the end.
//! Semicoercive C: `Polyak` as the bound step of the SMALBE host of
//! [`crate::qp::dual`], the face minimised to the precision the current
//! SMALBE step asks for, max(tol·‖h‖, ½min(M‖G̃λ̂‖, η)), the release by an
//! exact line search along the chopped gradient.

use crate::linalg::sparse::{axpy, dot, norm};
use crate::qp::dual::{solve_with, BoundStep, DualOp, DualState, StepKind};
use crate::qp::executor::{Iterative, Step};
use crate::qp::method::{Capabilities, MethodId};
use crate::qp::Failure;
use crate::qp::{Context, IterRecord, Method, Output, QpError, QpProblem, Status};
use std::time::Instant;

/// CGC on the dual functional (docs/methods.md §4.6).
pub struct DualMethod;

impl Method for DualMethod {
    fn id(&self) -> MethodId {
        MethodId::Dual
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "CGC on the dual functional, H applied through a Cholesky factor (§4.6)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let opts = ctx.settings;
    if !qp.kernel.is_empty() {
        let step = Polyak {
            multiple: opts.dual.multiple_release,
            p: vec![],
        };
        return solve_with(qp, ctx, step, "dual");
    }
    let t0 = Instant::now();
    let chol = ctx.ws.cholesky(&qp.c, &[])?;
    let mut op = DualOp::new(qp, chol, vec![], "dual")?;
    let t_f = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let m = qp.m();
    let mut x0 = qp.d.clone();
    op.solve_k(&mut x0);
    let ax0 = qp.a.mul(&x0);
    let h: Vec<f64> = ax0.iter().zip(&qp.g).map(|(a, g)| a - g).collect();
    let ref_norm = norm(&ax0).max(norm(&qp.g)).max(1e-300);
    let mut st = DualCgc {
        qp,
        op,
        tol: opts.tol,
        multiple: opts.dual.multiple_release,
        lam: vec![0.0; m],
        grad: h.iter().map(|v| -v).collect(),
        h,
        in_j: vec![true; m],
        ref_norm,
        response: ref_norm,
        cg_steps: 0,
    };
    let mut exec = ctx.executor("dual");
    let (status, iters) = exec.run(&mut st);
    // x = C⁻¹(d − Aᵀλ)
    let mut x = qp.d.clone();
    let atl = qp.a.mul_t(&st.lam);
    for (xi, a) in x.iter_mut().zip(&atl) {
        *xi -= a;
    }
    st.op.solve_k(&mut x);
    let t_it = t1.elapsed().as_secs_f64();
    let active: Vec<bool> = st.lam.iter().map(|&l| l > 0.0).collect();
    Ok(Output {
        x,
        lambda: st.lam,
        lambda_t: vec![],
        active,
        status,
        iterations: iters,
        inner_iterations: st.cg_steps,
        log: exec.log,
        timings: vec![("factor".into(), t_f), ("iterate".into(), t_it)],
    })
}

/// Polyak's CG with constraints on θ for a coercive C (no row scaling, no
/// SMALBE), one face per executor iteration.
pub(crate) struct DualCgc<'a> {
    qp: &'a QpProblem,
    /// H = A C⁻¹ Aᵀ through the factor of C.
    op: DualOp<'a>,
    tol: f64,
    multiple: bool,
    lam: Vec<f64>,
    /// θ'(λ) = Hλ − h
    grad: Vec<f64>,
    h: Vec<f64>,
    /// Bound λ_i = 0 in the working set.
    in_j: Vec<bool>,
    /// Scale of the stopping test, max(‖A x(λ)‖, ‖g‖, `response`) at the
    /// face start.
    ref_norm: f64,
    /// The loads' response at the rows, max(‖A C⁻¹d‖, ‖g‖): the floor of
    /// `ref_norm`. At an answer whose rows are all closed with g = 0 (a
    /// punch pressed by a prescribed displacement) A x(λ) = g = 0, and a
    /// scale taken there alone made rounding over rounding the residual:
    /// 1.0 at the exact answer, 10 000 iterations to stagnation.
    response: f64,
    /// CG steps (reported as inner iterations).
    cg_steps: usize,
}

enum Face {
    Min,
    Blocked,
    Kmax,
    Failed(String),
}

impl DualCgc<'_> {
    /// out = H v
    fn apply_h(&mut self, v: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&self.op.h(v));
    }

    /// Projected gradient norm (bound components zeroed).
    fn proj_norm(&self) -> f64 {
        self.grad
            .iter()
            .zip(&self.in_j)
            .filter(|(_, &b)| !b)
            .map(|(g, _)| g * g)
            .sum::<f64>()
            .sqrt()
    }

    fn refresh(&mut self) {
        let lam = self.lam.clone();
        let mut hl = vec![0.0; lam.len()];
        self.apply_h(&lam, &mut hl);
        for ((g, a), b) in self.grad.iter_mut().zip(&hl).zip(&self.h) {
            *g = a - b;
        }
    }

    fn face_cg(&mut self) -> Face {
        let m = self.qp.m();
        let nfree = self.in_j.iter().filter(|b| !**b).count();
        let kmax = 2 * nfree + 10;
        let mut p = vec![0.0; m];
        let mut w = vec![0.0; m];
        let mut r_old = 0.0;
        for k in 0..kmax {
            let r: f64 = self.proj_norm().powi(2);
            if r.sqrt() <= self.tol * self.ref_norm {
                return Face::Min;
            }
            let beta = if k == 0 { 0.0 } else { r / r_old };
            for ((pi, &bound), gi) in p.iter_mut().zip(&self.in_j).zip(&self.grad) {
                *pi = if bound { 0.0 } else { -gi + beta * *pi };
            }
            r_old = r;
            self.apply_h(&p, &mut w);
            self.cg_steps += 1;
            let a2 = dot(&p, &w);
            if a2.is_nan() || a2 <= 0.0 {
                return Face::Failed(format!(
                    "dual Hessian not positive on a search direction ((p,Hp) = {a2:e})"
                ));
            }
            let alpha = r / a2;
            let mut abar = f64::INFINITY;
            let mut istar = usize::MAX;
            for (i, &pi) in p.iter().enumerate() {
                if !self.in_j[i] && pi < 0.0 {
                    let t = (self.lam[i] / -pi).max(0.0);
                    if t < abar {
                        abar = t;
                        istar = i;
                    }
                }
            }
            if istar != usize::MAX && abar < alpha {
                axpy(abar, &p, &mut self.lam);
                axpy(abar, &w, &mut self.grad);
                self.lam[istar] = 0.0;
                self.in_j[istar] = true;
                for i in 0..m {
                    if self.lam[i] < 0.0 {
                        self.lam[i] = 0.0;
                    }
                }
                return Face::Blocked;
            }
            axpy(alpha, &p, &mut self.lam);
            axpy(alpha, &w, &mut self.grad);
        }
        Face::Kmax
    }

    fn record(&self, res: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual: res,
            active: self.in_j.iter().filter(|b| !**b).count(),
            inner: self.cg_steps,
        }
    }
}

impl Iterative for DualCgc<'_> {
    fn step(&mut self) -> Step {
        // Scale of A x(λ) − g at the current λ: A x(λ) = g − θ'(λ).
        let ax = self
            .grad
            .iter()
            .zip(&self.qp.g)
            .map(|(d, g)| (g - d) * (g - d))
            .sum::<f64>()
            .sqrt();
        self.ref_norm = ax.max(norm(&self.qp.g)).max(self.response);
        let res = self.proj_norm() / self.ref_norm;
        if res <= self.tol {
            // Face minimum: the multiplier of bound i ∈ J is u_i = θ'_i.
            let m = self.qp.m();
            let ubar = (0..m)
                .filter(|&i| self.in_j[i])
                .fold(0.0f64, |a, i| a.max(self.grad[i].abs()));
            let ubar = if ubar > 0.0 { ubar } else { 1.0 };
            let thr = -self.tol * ubar;
            let neg: Vec<usize> = (0..m)
                .filter(|&i| self.in_j[i] && self.grad[i] < thr)
                .collect();
            if neg.is_empty() {
                return Step::Done(Status::Converged, self.record(res));
            }
            if self.multiple {
                for &i in &neg {
                    self.in_j[i] = false;
                }
            } else if let Some(&i) = neg
                .iter()
                .min_by(|&&a, &&b| self.grad[a].total_cmp(&self.grad[b]))
            {
                self.in_j[i] = false;
            }
        }
        match self.face_cg() {
            Face::Failed(msg) => {
                Step::Done(Status::Failed(Failure::Breakdown(msg)), self.record(res))
            }
            Face::Min | Face::Blocked | Face::Kmax => {
                self.refresh();
                Step::Continue(self.record(res))
            }
        }
    }
}

/// One step of the report's CGC on the bounds λ̂ ≥ ℓ for the SMALBE host:
/// release (line search along the chopped gradient β, restricted to its most
/// negative component unless `multiple`) when the face is minimised, else
/// one CG step on the face, stopped at the first blocking bound.
pub(crate) struct Polyak {
    /// Release every bound with a negative multiplier at once.
    multiple: bool,
    /// CG direction on the face.
    p: Vec<f64>,
}

impl BoundStep for Polyak {
    fn start(&mut self, s: &DualState, _h_norm: f64) {
        self.p = s.phi();
    }

    fn restart(&mut self, s: &DualState) {
        self.p = s.phi();
    }

    fn step(&mut self, s: &mut DualState) -> Result<StepKind, String> {
        let mdim = s.lam.len();
        let phi = s.phi();
        let mut beta = s.beta();
        s.fresh = false;
        let face_tol = (s.tol * s.ref_g).max(0.5 * s.smalbe_tol);
        if norm(&beta) > 0.0 && norm(&phi) <= face_tol {
            if !self.multiple {
                let imin = (0..mdim)
                    .min_by(|&a, &b| beta[a].total_cmp(&beta[b]))
                    .unwrap_or(0);
                for (i, b) in beta.iter_mut().enumerate() {
                    if i != imin {
                        *b = 0.0;
                    }
                }
            }
            let ad = s.op.apply(&beta);
            let dad = dot(&beta, &ad);
            if !dad.is_finite() || dad <= 0.0 {
                return Err(format!(
                    "dual: non-positive curvature βᵀHβ = {dad:e} (H should be SPD)"
                ));
            }
            let a = dot(&s.g, &beta) / dad;
            for i in 0..mdim {
                s.lam[i] = (s.lam[i] - a * beta[i]).max(s.lb[i]);
                s.g[i] -= a * ad[i];
            }
            self.p = s.phi();
            return Ok(StepKind::Release);
        }
        if dot(&self.p, &self.p) == 0.0 {
            self.p = phi;
        }
        let ap = s.op.apply(&self.p);
        let pap = dot(&self.p, &ap);
        if !pap.is_finite() || pap <= 0.0 {
            return Err(format!(
                "dual: non-positive curvature pᵀHp = {pap:e} (H should be SPD)"
            ));
        }
        let acg = dot(&s.g, &self.p) / pap;
        let mut af = f64::INFINITY;
        let mut block = usize::MAX;
        for i in 0..mdim {
            if self.p[i] > 0.0 {
                let t = ((s.lam[i] - s.lb[i]) / self.p[i]).max(0.0);
                if t < af {
                    af = t;
                    block = i;
                }
            }
        }
        if acg <= af {
            axpy(-acg, &self.p, &mut s.lam);
            axpy(-acg, &ap, &mut s.g);
            let phin = s.phi();
            let gamma = dot(&phin, &ap) / pap;
            for (pi, fi) in self.p.iter_mut().zip(&phin) {
                *pi = fi - gamma * *pi;
            }
            Ok(StepKind::Cg)
        } else {
            // Stop on the blocking bound; CG restarts on the smaller face.
            for ((xi, pi), li) in s.lam.iter_mut().zip(&self.p).zip(&s.lb) {
                *xi = (*xi - af * pi).max(*li);
            }
            s.lam[block] = s.lb[block];
            axpy(-af, &ap, &mut s.g);
            self.p = s.phi();
            Ok(StepKind::Blocked)
        }
    }
}
