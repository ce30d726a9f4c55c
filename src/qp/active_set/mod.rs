//! ASM-E: active set method with elimination (methods.md §4.7).
//!
//! Working set J of constraints held as equalities. Each iteration solves the
//! equality-constrained problem on the face J for the correction δ,
//!
//! ```text
//!   B_J (δ, λ_J) = (d − Cx, g_J − A_J x),   B_J = [[C, A_Jᵀ], [A_J, 0]]
//! ```
//!
//! (the lower right-hand side is 0 up to rounding drift; carrying it keeps x on
//! its face), then steps to the nearest blocking constraint (adding it to J) or,
//! after a full step, drops the constraint with the most negative multiplier.
//!
//! Here B_J is solved by exact elimination through the Schur complement on the
//! constraints: with Z = C⁻¹ (one sparse Cholesky factor of C, reused),
//! `S_J λ_J = A_J Z r − e_J`, `S_J = A_J Z A_Jᵀ` (dense |J|×|J|, SPD), then
//! `δ = Z (r − A_Jᵀλ_J)`. The dense Cholesky factor of S_J is updated when J
//! changes (append a row: one solve with C; delete a row: Givens rotations).
//!
//! **Semicoercive C** (a basis R of ker C in `qp.kernel`): Z = (C + springs at
//! fixing DOFs)⁻¹ is then a generalised inverse of C (`linalg::cholesky`), and the
//! face problem is solved in the FETI way: δ = Z(r − A_Jᵀλ) + Rα with the
//! solvability condition Rᵀ(r − A_Jᵀλ) = 0, i.e. the small saddle system
//! `[[S, −G], [−Gᵀ, 0]] (λ, α) = (A_J Z r − e, −Rᵀr)`, G = A_J R. If a rigid
//! motion v = Rβ is not fixed by the working set (Gβ = 0), the face problem is
//! either unbounded along ±v (when rᵀv ≠ 0: a *ray step* to the first blocking
//! constraint, or `Status::Unbounded` if none blocks) or has a free component
//! along v (when rᵀv = 0: any solution is a face minimiser; the one without a
//! v-component is taken). This loop (shared with ASM-CGH, `asm_cgh.rs`) does the
//! rigid-motion bookkeeping; the [`FaceSolver`] only solves the face systems.

pub mod cgh;

use crate::linalg::cholesky::Cholesky;
use crate::linalg::sparse::{axpy, dot, norm, norm_inf};
use crate::qp::executor::{Iterative, Step};
use crate::qp::{
    primal::cgc, Context, IterRecord, Method, Output, QpError, QpProblem, Settings, Status,
};

/// Refuse problems with more constraints: the dense factor of S_J needs |J|²/2 numbers.
pub const MAX_DENSE_ROWS: usize = 10_000;

/// ASM-E: the active set method, KKT systems by Schur-complement
/// elimination (docs/methods.md §4.7).
pub struct AsmMethod;

impl Method for AsmMethod {
    fn name(&self) -> &'static str {
        "asm"
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
    let mut state = ActiveSet::new(qp, solver, ctx.settings);
    let mut exec = ctx.executor("asm");
    let (status, iters) = ctx.phase("iterate", |_| exec.run(&mut state));
    Ok(state.into_result(status, iters, exec.log, vec![]))
}

// ---------------------------------------------------------------------------
// Small dense linear algebra
// ---------------------------------------------------------------------------

/// Dense lower Cholesky factor S = LLᵀ in packed rows (row i has i+1 entries),
/// with O(n²) append and delete of a row/column.
#[derive(Debug, Default, Clone)]
pub(crate) struct PackedChol {
    rows: Vec<Vec<f64>>,
}

impl PackedChol {
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Append a row/column: `col` = S[old, new] (length len()), `diag` = S[new, new].
    /// Returns false (and leaves the factor unchanged) if the new matrix is not
    /// numerically positive definite (the new row depends on the old ones).
    pub fn push(&mut self, col: &[f64], diag: f64) -> bool {
        let n = self.len();
        debug_assert_eq!(col.len(), n);
        let mut w = Vec::with_capacity(n + 1);
        for i in 0..n {
            let r = &self.rows[i];
            let s: f64 = r[..i].iter().zip(&w).map(|(a, b)| a * b).sum();
            w.push((col[i] - s) / r[i]);
        }
        let d2 = diag - dot(&w, &w);
        if !(d2 > 1e-12 * diag.abs()) || !d2.is_finite() {
            return false;
        }
        w.push(d2.sqrt());
        self.rows.push(w);
        true
    }

    /// Delete row/column `k` (Givens rotations restore the triangle).
    pub fn remove(&mut self, k: usize) {
        self.rows.remove(k);
        let n = self.rows.len();
        for i in k..n {
            // Row i (old row i+1) has a superdiagonal entry (i, i+1): rotate
            // columns i and i+1 of rows i..n to annihilate it.
            let a = self.rows[i][i];
            let b = self.rows[i][i + 1];
            let h = a.hypot(b);
            let (c, s) = if h > 0.0 { (a / h, b / h) } else { (1.0, 0.0) };
            for r in self.rows[i..].iter_mut() {
                let (x, y) = (r[i], r[i + 1]);
                r[i] = c * x + s * y;
                r[i + 1] = -s * x + c * y;
            }
            self.rows[i][i] = self.rows[i][i].abs();
            self.rows[i].truncate(i + 1);
        }
    }

    /// Solve S x = b in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.len();
        for i in 0..n {
            let r = &self.rows[i];
            let s: f64 = r[..i].iter().zip(&b[..i]).map(|(a, x)| a * x).sum();
            b[i] = (b[i] - s) / r[i];
        }
        for i in (0..n).rev() {
            let bi = b[i] / self.rows[i][i];
            b[i] = bi;
            for (bj, &l) in b[..i].iter_mut().zip(&self.rows[i][..i]) {
                *bj -= l * bi;
            }
        }
    }
}

/// Eigen-decomposition of a small symmetric matrix (row-major k×k) by cyclic
/// Jacobi rotations: returns (eigenvalues, eigenvectors as rows).
pub(crate) fn sym_eigen(a: &[f64], k: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut m = a.to_vec();
    let mut v = vec![0.0; k * k];
    for i in 0..k {
        v[i * k + i] = 1.0;
    }
    for _sweep in 0..100 {
        let off: f64 = (0..k)
            .flat_map(|i| (0..k).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| m[i * k + j].powi(2))
            .sum();
        let total: f64 = m.iter().map(|x| x * x).sum();
        if off <= 1e-30 * total || total == 0.0 {
            break;
        }
        for p in 0..k {
            for q in p + 1..k {
                let apq = m[p * k + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (m[q * k + q] - m[p * k + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for r in 0..k {
                    let (x, y) = (m[r * k + p], m[r * k + q]);
                    m[r * k + p] = c * x - s * y;
                    m[r * k + q] = s * x + c * y;
                }
                for r in 0..k {
                    let (x, y) = (m[p * k + r], m[q * k + r]);
                    m[p * k + r] = c * x - s * y;
                    m[q * k + r] = s * x + c * y;
                }
                for r in 0..k {
                    let (x, y) = (v[r * k + p], v[r * k + q]);
                    v[r * k + p] = c * x - s * y;
                    v[r * k + q] = s * x + c * y;
                }
            }
        }
    }
    let vals = (0..k).map(|i| m[i * k + i]).collect();
    let vecs = (0..k)
        .map(|j| (0..k).map(|r| v[r * k + j]).collect())
        .collect();
    (vals, vecs)
}

/// Solve the small SPD system K x = b (row-major q×q) by Cholesky; None if not SPD.
pub(crate) fn small_spd_solve(k: &[f64], q: usize, b: &[f64]) -> Option<Vec<f64>> {
    let mut f = PackedChol::default();
    for j in 0..q {
        let col: Vec<f64> = (0..j).map(|i| k[i * q + j]).collect();
        if !f.push(&col, k[j * q + j]) {
            return None;
        }
    }
    let mut x = b.to_vec();
    f.solve_in_place(&mut x);
    Some(x)
}

/// Orthonormal basis of span(kernel) (modified Gram–Schmidt, dependent vectors dropped).
pub(crate) fn orthonormal_kernel(kernel: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = vec![];
    for z in kernel {
        let mut v = z.clone();
        let n0 = norm(&v);
        if !(n0 > 0.0) || !n0.is_finite() {
            continue;
        }
        for _ in 0..2 {
            for q in &out {
                let p = dot(&v, q);
                axpy(-p, q, &mut v);
            }
        }
        let nv = norm(&v);
        if nv > 1e-10 * n0 {
            v.iter_mut().for_each(|e| *e /= nv);
            out.push(v);
        }
    }
    out
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
    pub fn new(qp: &'a QpProblem, solver: S, opts: &Settings) -> Self {
        let m = qp.m();
        let x = cgc::feasible_start(qp);
        let rker = orthonormal_kernel(&qp.kernel);
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
        for i in 0..m {
            if ax[i] - qp.g[i] >= -1e-12 * scale && st.row_norm[i] > 0.0 {
                st.add(i);
            }
        }
        st
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
        let mut gtg = vec![0.0; k * k];
        for &j in &self.jl {
            let gj = &self.ar[j];
            for a in 0..k {
                for b in 0..k {
                    gtg[a * k + b] += gj[a] * gj[b];
                }
            }
        }
        let (vals, vecs) = sym_eigen(&gtg, k);
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
        for i in 0..self.qp.m() {
            if self.in_j[i] {
                continue;
            }
            let ap = self.qp.a.row_dot(i, p);
            if ap > 1e-13 * self.row_norm[i] * pn {
                let t = ((self.qp.g[i] - ax[i]) / ap).max(0.0);
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
            (_, Some(msg)) => Status::Failed(msg),
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
            status,
            iterations,
            inner_iterations: self.solver.inner(),
            log,
            timings,
        }
    }

    fn fail(&mut self, msg: String) -> Step {
        self.failed = Some(msg.clone());
        Step::Done(Status::Failed(msg), self.record(f64::NAN))
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

// ---------------------------------------------------------------------------
// ASM-E face solver: Schur complement with one Cholesky factor of C
// ---------------------------------------------------------------------------

pub(crate) struct SchurSolver<'a> {
    qp: &'a QpProblem,
    chol: Cholesky,
    s: PackedChol,
    solves: usize,
}

impl<'a> SchurSolver<'a> {
    pub(crate) fn new(qp: &'a QpProblem, chol: Cholesky) -> Self {
        SchurSolver {
            qp,
            chol,
            s: PackedChol::default(),
            solves: 0,
        }
    }

    /// Z v
    fn zsolve(&mut self, v: &mut [f64]) {
        self.solves += 1;
        self.chol.solve_in_place(v);
    }
}

impl FaceSolver for SchurSolver<'_> {
    fn push(&mut self, j: usize, jl: &[usize]) -> bool {
        let qp = self.qp;
        let mut z = vec![0.0; qp.n()];
        let (c, v) = qp.a.row(j);
        for (&k, &a) in c.iter().zip(v) {
            z[k] = a;
        }
        self.zsolve(&mut z);
        let col: Vec<f64> = jl.iter().map(|&i| qp.a.row_dot(i, &z)).collect();
        let diag = qp.a.row_dot(j, &z);
        self.s.push(&col, diag)
    }

    fn remove(&mut self, pos: usize) {
        self.s.remove(pos);
    }

    fn solve(
        &mut self,
        r: &[f64],
        e: &[f64],
        jl: &[usize],
        fk: &FaceKernel,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let qp = self.qp;
        let mut z = r.to_vec();
        self.zsolve(&mut z);
        // λ0 = S⁻¹ (A_J Z r − e)
        let mut lam: Vec<f64> = jl
            .iter()
            .zip(e)
            .map(|(&j, &ej)| qp.a.row_dot(j, &z) - ej)
            .collect();
        self.s.solve_in_place(&mut lam);
        // Rigid motions fixed by J: α on range(Gᵀ), Gr = A_J R Q_r.
        let q = fk.range.len();
        let mut alpha = vec![0.0; q];
        if q > 0 {
            let gr: Vec<Vec<f64>> = fk
                .range_vecs
                .iter()
                .map(|v| jl.iter().map(|&j| qp.a.row_dot(j, v)).collect())
                .collect();
            let w: Vec<Vec<f64>> = gr
                .iter()
                .map(|g| {
                    let mut t = g.clone();
                    self.s.solve_in_place(&mut t);
                    t
                })
                .collect();
            let mut kmat = vec![0.0; q * q];
            for a in 0..q {
                for b in 0..q {
                    kmat[a * q + b] = dot(&gr[a], &w[b]);
                }
            }
            let rhs: Vec<f64> = (0..q)
                .map(|a| dot(&fk.range_vecs[a], r) - dot(&gr[a], &lam))
                .collect();
            alpha = small_spd_solve(&kmat, q, &rhs)
                .ok_or("the rigid-motion system Gᵀ S⁻¹ G is singular")?;
            for (wa, &aa) in w.iter().zip(&alpha) {
                axpy(aa, wa, &mut lam);
            }
        }
        // δ = Z (r − A_Jᵀλ) + R Q_r α
        let mut delta = r.to_vec();
        for (&j, &l) in jl.iter().zip(&lam) {
            let (c, v) = qp.a.row(j);
            for (&k, &a) in c.iter().zip(v) {
                delta[k] -= a * l;
            }
        }
        self.zsolve(&mut delta);
        for (v, &aa) in fk.range_vecs.iter().zip(&alpha) {
            axpy(aa, v, &mut delta);
        }
        // Free force-free rigid motions: remove their component (any is optimal).
        for v in &fk.free {
            let t = dot(&delta, v);
            axpy(-t, v, &mut delta);
        }
        Ok((delta, lam))
    }

    fn inner(&self) -> usize {
        self.solves
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd(n: usize) -> Vec<f64> {
        // S = BᵀB + I with a deterministic B
        let b: Vec<f64> = (0..n * n)
            .map(|i| ((i * 7 + 3) % 11) as f64 / 5.0 - 1.0)
            .collect();
        let mut s = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                s[i * n + j] = (0..n).map(|k| b[k * n + i] * b[k * n + j]).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
        }
        s
    }

    #[test]
    fn packed_cholesky_append_delete_solve() {
        let n = 7;
        let s = spd(n);
        let mut idx: Vec<usize> = vec![];
        let mut f = PackedChol::default();
        for j in 0..n {
            let col: Vec<f64> = idx.iter().map(|&i| s[i * n + j]).collect();
            assert!(f.push(&col, s[j * n + j]));
            idx.push(j);
        }
        f.remove(2);
        idx.remove(2);
        f.remove(0);
        idx.remove(0);
        let col: Vec<f64> = idx.iter().map(|&i| s[i * n + 2]).collect();
        assert!(f.push(&col, s[2 * n + 2]));
        idx.push(2);
        let b: Vec<f64> = (0..idx.len()).map(|i| i as f64 - 1.5).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x);
        for (a, &i) in idx.iter().enumerate() {
            let sx: f64 = idx.iter().zip(&x).map(|(&j, xj)| s[i * n + j] * xj).sum();
            assert!((sx - b[a]).abs() < 1e-10, "{sx} {}", b[a]);
        }
        // A dependent row is refused.
        let mut g = PackedChol::default();
        assert!(g.push(&[], 2.0));
        assert!(!g.push(&[2.0], 2.0));
        assert_eq!(g.len(), 1);
    }

    #[test]
    fn jacobi_eigen() {
        let a = [2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0];
        let (vals, vecs) = sym_eigen(&a, 3);
        let mut v = vals.clone();
        v.sort_by(f64::total_cmp);
        assert!((v[0]).abs() < 1e-14 && (v[1] - 1.0).abs() < 1e-12 && (v[2] - 3.0).abs() < 1e-12);
        for (l, x) in vals.iter().zip(&vecs) {
            for i in 0..3 {
                let ax: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
                assert!((ax - l * x[i]).abs() < 1e-12);
            }
        }
    }
}
