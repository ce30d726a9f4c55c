//! Active set methods (docs/methods.md §4.7 ASM-E, §4.8 ASM-CGH): the loop
//! both share (`ActiveSet`) and ASM-E's entry. A working set J of
//! constraints is held as equalities; each step solves the face problem
//! `C δ + A_Jᵀλ_J = d − Cx, A_J δ = g_J − A_J x` (a `FaceSolver`; the lower
//! right-hand side is 0 up to rounding drift, carrying it keeps x on its
//! face), then steps to the nearest blocking constraint (adding it to J) or,
//! after a full step, drops the constraint with the most negative multiplier.
//!
//! Semicoercive C (ker C = span R, `qp.kernel`): the loop does the
//! rigid-motion bookkeeping. A motion v = Rβ that J does not fix (A_J v = 0)
//! makes the face problem unbounded along ±v when rᵀv ≠ 0 (a ray step to the
//! first blocking constraint, or `Status::Unbounded`), or leaves v free when
//! rᵀv = 0 (the face minimiser without a v-component is taken). Face
//! solvers: ASM-E's `SchurSolver` (`schur`), ASM-CGH's in [`cgh`].

pub mod cgh;
mod schur;

use crate::linalg::dense::sym_eigen;
use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::sparse::{axpy, dot, norm, norm_inf};
use crate::qp::executor::{Iterative, Step};
use crate::qp::method::{Capabilities, MethodId};
use crate::qp::Failure;
use crate::qp::{
    primal::cgc, Context, IterRecord, Method, Output, QpError, QpProblem, Settings, Status,
};
pub(crate) use schur::SchurSolver;

/// Refuse problems with more constraints: the dense factor of S_J needs |J|²/2 numbers.
pub const MAX_DENSE_ROWS: usize = 10_000;

/// ASM-E: the active set method, KKT systems by Schur-complement
/// elimination (docs/methods.md §4.7).
pub struct AsmMethod;

impl Method for AsmMethod {
    fn id(&self) -> MethodId {
        MethodId::Asm
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "active set method, KKT systems by Schur-complement elimination (ASM-E, §4.7)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

/// Solve `qp` by ASM-E.
pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    if qp.m() > MAX_DENSE_ROWS {
        return Err(QpError::Unsupported(format!(
            "asm: {} constraints > {MAX_DENSE_ROWS}; the dense Cholesky factor of A_J C⁻¹ A_Jᵀ would need \
             up to {:.1} GB (use asm-cgh or cgc)",
            qp.m(),
            (qp.m() as f64).powi(2) * 4.0 / 1e9
        )));
    }
    let chol = ctx.phase("factor", |ctx| ctx.ws.cholesky(&qp.c, &qp.kernel))?;
    let solver = SchurSolver::new(qp, chol);
    let mut state = ActiveSet::new(qp, solver, ctx.settings)?;
    let mut exec = ctx.executor("asm");
    let (status, iters) = ctx.phase("iterate", |_| exec.run(&mut state));
    Ok(state.into_result(status, iters, exec.log, vec![]))
}

// ---------------------------------------------------------------------------
// The active-set loop shared by ASM-E and ASM-CGH
// ---------------------------------------------------------------------------

/// Rigid motions relative to the current working set.
pub(crate) struct FaceKernel {
    /// Orthonormal k-vectors β spanning range(Gᵀ), G = A_J R (the motions J fixes).
    pub range: Vec<Vec<f64>>,
    /// The corresponding N-vectors Rβ.
    pub range_vecs: Vec<Vec<f64>>,
    /// Unit N-vectors v = Rβ with Gβ = 0 and rᵀv ≈ 0 (free, force-free motions).
    pub free: Vec<Vec<f64>>,
}

/// Solves the face systems B_J (δ, λ_J) = (r, e) for the active-set loop.
pub(crate) trait FaceSolver {
    /// Working set grows by constraint `j` (appended after `jl`). Returns false
    /// if the row is numerically dependent on the rows of `jl` (not added).
    fn push(&mut self, j: usize, jl: &[usize]) -> bool;
    /// Working set loses its entry at position `pos`.
    fn remove(&mut self, pos: usize);
    /// Solve the face problem: C δ + A_Jᵀλ = r, A_J δ = e, δ ⟂ `fk.free`
    /// directions' component left free. Returns (δ, λ_J).
    fn solve(
        &mut self,
        r: &[f64],
        e: &[f64],
        jl: &[usize],
        fk: &FaceKernel,
    ) -> Result<(Vec<f64>, Vec<f64>), String>;
    /// Inner iterations so far (solves with C, CGH steps).
    fn inner(&self) -> usize;
}

pub(crate) struct ActiveSet<'a, S: FaceSolver> {
    qp: &'a QpProblem,
    solver: S,
    tol: f64,
    pub x: Vec<f64>,
    /// Working list (order = order of the solver's factor).
    jl: Vec<usize>,
    in_j: Vec<bool>,
    /// Multipliers of the last face solve (indexed by constraint).
    lam: Vec<f64>,
    /// Orthonormal basis of ker C and its images A R (row i = k-vector).
    rker: Vec<Vec<f64>>,
    ar: Vec<Vec<f64>>,
    row_norm: Vec<f64>,
    amax: f64,
    dnorm: f64,
    failed: Option<String>,
}

impl<'a, S: FaceSolver> ActiveSet<'a, S> {
    pub fn new(qp: &'a QpProblem, solver: S, opts: &Settings) -> Result<Self, QpError> {
        let m = qp.m();
        let x = cgc::feasible_start(qp);
        let rker = orthonormal_kernel(&qp.c, &qp.kernel)?;
        let ar: Vec<Vec<f64>> = (0..m)
            .map(|i| rker.iter().map(|z| qp.a.row_dot(i, z)).collect())
            .collect();
        let row_norm: Vec<f64> = (0..m).map(|i| norm(qp.a.row(i).1)).collect();
        let amax = row_norm
            .iter()
            .fold(0.0f64, |a, &b| a.max(b))
            .max(f64::MIN_POSITIVE);
        let mut st = ActiveSet {
            qp,
            solver,
            tol: opts.tol,
            x,
            jl: vec![],
            in_j: vec![false; m],
            lam: vec![0.0; m],
            rker,
            ar,
            row_norm,
            amax,
            dnorm: norm(&qp.d),
            failed: None,
        };
        let ax = qp.a.mul(&st.x);
        let scale = norm_inf(&qp.g).max(norm_inf(&st.x)).max(1e-300);
        for (i, (&axi, &gi)) in ax.iter().zip(&qp.g).enumerate() {
            if axi - gi >= -1e-12 * scale && st.row_norm[i] > 0.0 {
                st.add(i);
            }
        }
        Ok(st)
    }

    /// The face solver (to report how it solved).
    pub(crate) fn solver(&self) -> &S {
        &self.solver
    }

    /// Add constraint i to the working set if it is independent of it.
    fn add(&mut self, i: usize) -> bool {
        if self.solver.push(i, &self.jl) {
            self.jl.push(i);
            self.in_j[i] = true;
            true
        } else {
            false
        }
    }

    fn drop_at(&mut self, pos: usize) {
        let j = self.jl.remove(pos);
        self.in_j[j] = false;
        self.lam[j] = 0.0;
        self.solver.remove(pos);
    }

    /// Split ker C into the motions fixed by J and the free ones; a free motion
    /// with rᵀv ≠ 0 is returned as a descent ray.
    fn face_kernel(&self, r: &[f64]) -> (FaceKernel, Option<Vec<f64>>) {
        let k = self.rker.len();
        let mut fk = FaceKernel {
            range: vec![],
            range_vecs: vec![],
            free: vec![],
        };
        if k == 0 {
            return (fk, None);
        }
        let mut gtg = vec![vec![0.0; k]; k];
        for &j in &self.jl {
            let gj = &self.ar[j];
            for a in 0..k {
                for b in 0..k {
                    gtg[a][b] += gj[a] * gj[b];
                }
            }
        }
        let (vals, vecs) = sym_eigen(&gtg);
        let thr = 1e-10 * self.amax * self.amax;
        let rn = norm(r).max(self.dnorm);
        let mut ray: Option<(f64, Vec<f64>)> = None;
        for (val, beta) in vals.into_iter().zip(vecs) {
            let mut v = vec![0.0; self.qp.n()];
            for (b, z) in beta.iter().zip(&self.rker) {
                axpy(*b, z, &mut v);
            }
            if val > thr {
                fk.range.push(beta);
                fk.range_vecs.push(v);
            } else {
                let t = dot(r, &v);
                if t.abs() > 1e-10 * rn {
                    if ray.as_ref().is_none_or(|(s, _)| t.abs() > *s) {
                        if t < 0.0 {
                            v.iter_mut().for_each(|e| *e = -*e);
                        }
                        ray = Some((t.abs(), v));
                    }
                } else {
                    fk.free.push(v);
                }
            }
        }
        (fk, ray.map(|(_, v)| v))
    }

    /// Nearest blocking constraint along p from x: (step, index), or None.
    fn ratio_test(&self, p: &[f64], ax: &[f64]) -> Option<(f64, usize)> {
        let pn = norm(p);
        let mut best: Option<(f64, usize)> = None;
        for (i, &axi) in ax.iter().enumerate() {
            if self.in_j[i] {
                continue;
            }
            let ap = self.qp.a.row_dot(i, p);
            if ap > 1e-13 * self.row_norm[i] * pn {
                let t = ((self.qp.g[i] - axi) / ap).max(0.0);
                if best.is_none_or(|(b, _)| t < b) {
                    best = Some((t, i));
                }
            }
        }
        best
    }

    fn record(&self, residual: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual,
            active: self.jl.len(),
            inner: self.solver.inner(),
        }
    }

    pub fn into_result(
        self,
        status: Status,
        iterations: usize,
        log: Vec<IterRecord>,
        timings: Vec<(String, f64)>,
    ) -> Output {
        let m = self.qp.m();
        let status = match (status, self.failed) {
            (Status::Converged, _) => Status::Converged,
            (_, Some(msg)) => Status::Failed(Failure::Breakdown(msg)),
            (s, None) => s,
        };
        // Multipliers within the release tolerance of 0 are reported as 0.
        let lambda: Vec<f64> = (0..m)
            .map(|i| {
                if self.in_j[i] {
                    self.lam[i].max(0.0)
                } else {
                    0.0
                }
            })
            .collect();
        Output {
            active: self.in_j,
            x: self.x,
            lambda,
            lambda_t: vec![],
            status,
            iterations,
            inner_iterations: self.solver.inner(),
            log,
            timings,
        }
    }

    fn fail(&mut self, msg: String) -> Step {
        self.failed = Some(msg.clone());
        Step::Done(
            Status::Failed(Failure::Breakdown(msg)),
            self.record(f64::NAN),
        )
    }
}

impl<S: FaceSolver> Iterative for ActiveSet<'_, S> {
    fn step(&mut self) -> Step {
        let qp = self.qp;
        let cx = qp.c.mul(&self.x);
        let r: Vec<f64> = qp.d.iter().zip(&cx).map(|(d, c)| d - c).collect();
        let ax = qp.a.mul(&self.x);
        let e: Vec<f64> = self.jl.iter().map(|&j| qp.g[j] - ax[j]).collect();
        let (fk, ray) = self.face_kernel(&r);
        if let Some(p) = ray {
            // f is linear and decreasing along the rigid motion p on this face.
            return match self.ratio_test(&p, &ax) {
                None => Step::Done(
                    Status::Unbounded { direction: p },
                    self.record(f64::INFINITY),
                ),
                Some((t, i)) => {
                    axpy(t, &p, &mut self.x);
                    if !self.add(i) {
                        return self.fail(format!(
                            "constraint {i} blocks a rigid motion but depends on the working set"
                        ));
                    }
                    Step::Continue(self.record(1.0))
                }
            };
        }
        let (delta, lam_j) = match self.solver.solve(&r, &e, &self.jl, &fk) {
            Ok(v) => v,
            Err(msg) => return self.fail(msg),
        };
        if delta.iter().chain(&lam_j).any(|v| !v.is_finite()) {
            return self.fail("NaN or Inf in the face solution".into());
        }
        // Relative size of the correction, in [0, 1]. ‖δ‖ in the denominator
        // keeps it finite when x = 0 and g = 0 (the first face of a problem
        // with large displacements: ‖δ‖/1e-300 overflowed to Inf, which the
        // executor took for a NaN/Inf failure).
        let dn = norm(&delta);
        let den = norm(&self.x).max(norm_inf(&qp.g)).max(dn);
        let res = if den > 0.0 { dn / den } else { 0.0 };
        for (&j, &l) in self.jl.iter().zip(&lam_j) {
            self.lam[j] = l;
        }
        match self.ratio_test(&delta, &ax) {
            Some((t, i)) if t < 1.0 => {
                axpy(t, &delta, &mut self.x);
                if !self.add(i) {
                    return self.fail(format!(
                        "constraint {i} blocks the step but depends on the working set"
                    ));
                }
                Step::Continue(self.record(res))
            }
            _ => {
                // Full step: x is the minimiser on the face and λ_J its multipliers.
                axpy(1.0, &delta, &mut self.x);
                let lbar = lam_j.iter().fold(0.0f64, |a, l| a.max(l.abs()));
                let lbar = if lbar > 0.0 { lbar } else { 1.0 };
                let thr = -100.0 * self.tol * lbar;
                let worst = lam_j
                    .iter()
                    .enumerate()
                    .filter(|(_, &l)| l < thr)
                    .min_by(|a, b| a.1.total_cmp(b.1))
                    .map(|(p, _)| p);
                match worst {
                    None => Step::Done(Status::Converged, self.record(res)),
                    Some(pos) => {
                        self.drop_at(pos);
                        Step::Continue(self.record(res))
                    }
                }
            }
        }
    }
}
