//! Minimisation of the dual functional (methods.md §4.6):
//!
//! ```text
//!   min θ(λ) = ½λᵀHλ − λᵀh  s.t. λ ≥ 0,   H = A C⁻¹ Aᵀ,  h = A C⁻¹ d − g,
//!   θ'(λ) = Hλ − h = −(A x(λ) − g),        x(λ) = C⁻¹ (d − Aᵀλ),
//! ```
//!
//! by CGC on the bound constraints (rows −e_i: orthonormal, so the projection is
//! "zero the bound components" and releasing every negative multiplier at
//! once is safe; `opts.multiple_release = false` releases one). Hp is applied
//! through one Cholesky factor of C (w = Aᵀp, solve, A·): H is never formed.
//! The displacements are recovered as x = C⁻¹(d − Aᵀλ), so stationarity
//! Cx − d + Aᵀλ = 0 holds to rounding and the primal feasibility A x − g ≤ 0
//! is the dual optimality condition θ' ≥ 0 on the bounds.
//!
//! Stopping (§4.1 applied to θ): ‖projected θ'‖ ≤ tol·max(‖A x(λ)‖, ‖g‖), the
//! scale taken at the start of each face (A x(λ) = g − θ'(λ) is free; the
//! unconstrained ‖A C⁻¹ d‖ can exceed the final ‖Ax‖ by orders of magnitude).
//! With exact solves (a factor, not the report's inner CG) no stricter inner
//! tolerance is needed.
//!
//! One executor iteration = one face (CG on the free multipliers until the
//! face minimum or a new bound becomes active).
//!
//! Semicoercive C (non-empty `qp.kernel`) is refused: the dual then carries the
//! equality constraint Rᵀ(d − Aᵀλ) = 0 (FETI), which this bound-constrained CGC
//! does not handle.

use super::asm::check_common;
use super::executor::{Executor, Iterative, Step};
use super::factor::Cholesky;
use super::sparse::{axpy, dot, norm};
use super::{IterRecord, QpError, QpProblem, QpResult, SolveOptions, Status};
use std::time::Instant;

pub fn solve(qp: &QpProblem, opts: &SolveOptions) -> Result<QpResult, QpError> {
    check_common(qp, opts)?;
    if !qp.kernel.is_empty() {
        return Err(QpError::Unsupported(
            "dual needs an invertible C; this C is singular (floating bodies: the dual gains the \
             equality constraint Rᵀ(d − Aᵀλ) = 0, not implemented). Use cgc, preelim, asm or asm-cgh"
                .into(),
        ));
    }
    let t0 = Instant::now();
    let chol = Cholesky::new(&qp.c, &[])?;
    let t_f = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let m = qp.m();
    let x0 = chol.solve(&qp.d);
    let ax0 = qp.a.mul(&x0);
    let h: Vec<f64> = ax0.iter().zip(&qp.g).map(|(a, g)| a - g).collect();
    let ref_norm = norm(&ax0).max(norm(&qp.g)).max(1e-300);
    let mut st = DualCgc {
        qp,
        chol: &chol,
        tol: opts.tol,
        multiple: opts.multiple_release,
        lam: vec![0.0; m],
        grad: h.iter().map(|v| -v).collect(),
        h,
        in_j: vec![true; m],
        ref_norm,
        solves: 1,
        cg_steps: 0,
    };
    let mut exec = Executor::new(opts.max_iter, opts.progress.then_some("dual"));
    let (status, iters) = exec.run(&mut st);
    // x = C⁻¹(d − Aᵀλ)
    let mut x = qp.d.clone();
    let atl = qp.a.mul_t(&st.lam);
    for (xi, a) in x.iter_mut().zip(&atl) {
        *xi -= a;
    }
    chol.solve_in_place(&mut x);
    let t_it = t1.elapsed().as_secs_f64();
    let active: Vec<bool> = st.lam.iter().map(|&l| l > 0.0).collect();
    let energy = qp.energy(&x);
    Ok(QpResult {
        x,
        lambda: st.lam,
        active,
        status,
        iterations: iters,
        inner_iterations: st.cg_steps,
        log: exec.log,
        timings: vec![("factor".into(), t_f), ("iterate".into(), t_it)],
        kkt: Default::default(),
        energy,
    })
}

struct DualCgc<'a> {
    qp: &'a QpProblem,
    chol: &'a Cholesky,
    tol: f64,
    multiple: bool,
    lam: Vec<f64>,
    /// θ'(λ) = Hλ − h
    grad: Vec<f64>,
    h: Vec<f64>,
    /// Bound λ_i = 0 in the working set.
    in_j: Vec<bool>,
    ref_norm: f64,
    solves: usize,
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
        let mut w = self.qp.a.mul_t(v);
        self.chol.solve_in_place(&mut w);
        self.qp.a.mul_vec(&w, out);
        self.solves += 1;
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
            for i in 0..m {
                p[i] = if self.in_j[i] {
                    0.0
                } else {
                    -self.grad[i] + beta * p[i]
                };
            }
            r_old = r;
            self.apply_h(&p, &mut w);
            self.cg_steps += 1;
            let a2 = dot(&p, &w);
            if !(a2 > 0.0) {
                return Face::Failed(format!(
                    "dual Hessian not positive on a search direction ((p,Hp) = {a2:e})"
                ));
            }
            let alpha = r / a2;
            let mut abar = f64::INFINITY;
            let mut istar = usize::MAX;
            for i in 0..m {
                if !self.in_j[i] && p[i] < 0.0 {
                    let t = (self.lam[i] / -p[i]).max(0.0);
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
        self.ref_norm = ax.max(norm(&self.qp.g)).max(1e-300);
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
            Face::Failed(msg) => Step::Done(Status::Failed(msg), self.record(res)),
            Face::Min | Face::Blocked | Face::Kmax => {
                self.refresh();
                Step::Continue(self.record(res))
            }
        }
    }
}
