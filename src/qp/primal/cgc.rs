//! CGC: conjugate gradients with constraints (methods.md §4.1), preconditioned
//! as in §4.2. f is minimised by (P)CG on faces {A_J x = g_J} of the feasible
//! polyhedron; a face is left when a new constraint blocks the step or when
//! constraints with negative multiplier estimates are released.
//!
//! Written in the original variables with z = W⁻¹r only: the projected
//! preconditioned gradient is z = W⁻¹(∇f + A_Jᵀλ) with
//! (A_J W⁻¹ A_Jᵀ) λ = −A_J W⁻¹ ∇f (the report's PROJECT_W), so one trait
//! method serves every preconditioner. Works for semidefinite C: a descent
//! direction with zero curvature that no constraint blocks proves f
//! unbounded below (§4.1, notes).
//!
//! One executor iteration = one visit of a face (FACE_CG until a face minimum,
//! a new constraint, or KMAX steps); the CG steps are the inner iterations.

use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::sparse::{axpy, dot, norm, norm_inf};
use crate::qp::executor::{Iterative, Step};
use crate::qp::method::{Capabilities, Factor, MethodId};
use crate::qp::precond::{self, Preconditioner};
use crate::qp::{Context, IterRecord, Method, Output, QpError, QpProblem, Status, MAXVAL};

/// CGC: conjugate gradients with constraints (docs/methods.md §4.1),
/// preconditioned (§4.2) as the settings say.
pub struct CgcMethod;

impl Method for CgcMethod {
    fn id(&self) -> MethodId {
        MethodId::Cgc
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            preconditioned: true,
            factor: Factor::BySettings,
            warm_start: true,
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "conjugate gradients with constraints (§4.1), preconditioned (§4.2)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

/// Solve `qp` by CGC with the preconditioner of the settings.
pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let s = ctx.settings;
    let pc = ctx.phase("precondition", |ctx| {
        precond::build_in(s.cgc.preconditioner, &qp.c, &qp.kernel, s.cgc.omega, ctx.ws)
    })?;
    let x0 = ctx.x0.filter(|x| x.len() == qp.n() && is_feasible(qp, x));
    let mut state = Cgc::new(qp, pc.as_ref(), s.tol, s.cgc.multiple_release, x0)?;
    state.kmax_cap = s.max_iter.max(1);
    let mut exec = ctx.executor("cgc");
    let (status, iters) = ctx.phase("iterate", |_| exec.run(&mut state));
    Ok(state.into_result(status, iters, exec.log, vec![]))
}

/// The CGC state: iterate, gradient, working set.
pub struct Cgc<'a> {
    qp: &'a QpProblem,
    pc: &'a dyn Preconditioner,
    tol: f64,
    multiple: bool,
    pub x: Vec<f64>,
    grad: Vec<f64>,
    /// s = A x
    s: Vec<f64>,
    in_j: Vec<bool>,
    /// Multiplier estimates (valid on J; warm start for the inner solves).
    lam: Vec<f64>,
    /// Scale of the projected gradient (W⁻¹-norm of d, or of the first one).
    ref_norm: f64,
    /// Rounding level of the projected gradient at the current x, relative
    /// to `ref_norm` ([`Cgc::rounding_floor`]): a residual below it ends a
    /// face only once FACE_CG has stalled there (`stalled`, `resolved`).
    floor: f64,
    /// The last FACE_CG ended because the residual, already below `floor`,
    /// stopped decreasing ([`FACE_STALL`] steps without halving): the face
    /// minimum is resolved to rounding. `floor` is a worst-case bound (10³
    /// above the noise actually reached on a floating plate at a contrast of
    /// 10⁸), so it only licenses the stop; the stall decides it.
    stalled: bool,
    /// The last FACE_CG ended at a face minimum (tolerance met or stalled);
    /// restoring the face after it may lift the residual again, up to `floor`.
    resolved: bool,
    /// The energy-norm tolerance in force: `tol`, divided by 10 (at most
    /// [`TIGHTEN`] times) while a face minimum misses the Euclidean test.
    tol_eff: f64,
    tightened: usize,
    /// ‖∇f + A_Jᵀλ_J‖₂ of the last projection, and the scale it is
    /// measured against, max(‖d‖, ‖Cx‖).
    gp_norm: f64,
    /// Orthonormal basis of ker C (empty: C is positive definite).
    kernel: Vec<Vec<f64>>,
    /// diag(C): the weights of the zero-curvature test without a kernel.
    cdiag: Vec<f64>,
    /// Every column of A occurs in at most one row and W = I: λ_J is explicit.
    direct: bool,
    row_norm2: Vec<f64>,
    pub inner: usize,
    /// At most this many CG steps per face (MAXIT bounds every loop).
    pub kmax_cap: usize,
}

/// A face minimum must also have ‖∇f + A_Jᵀλ_J‖₂ ≤ EUCLID·tol·max(‖d‖, ‖Cx‖).
const EUCLID: f64 = 1e3;
/// At most this many tenfold tightenings of the energy-norm tolerance.
const TIGHTEN: usize = 6;
/// FACE_CG steps without halving the projected gradient after which a
/// residual below the rounding floor counts as resolved (see `Cgc::stalled`).
const FACE_STALL: usize = 20;

enum FaceEnd {
    Min,
    NewFace,
    Kmax,
    Unbounded(Vec<f64>),
}

impl<'a> Cgc<'a> {
    /// Start from `x0` (must be feasible) or from a feasible point built from g.
    pub fn new(
        qp: &'a QpProblem,
        pc: &'a dyn Preconditioner,
        tol: f64,
        multiple: bool,
        x0: Option<&[f64]>,
    ) -> Result<Cgc<'a>, QpError> {
        let n = qp.n();
        let m = qp.m();
        let x = match x0 {
            Some(v) => v.to_vec(),
            None => feasible_start(qp),
        };
        let cx = qp.c.mul(&x);
        let grad: Vec<f64> = cx.iter().zip(&qp.d).map(|(a, b)| a - b).collect();
        let s = qp.a.mul(&x);
        let gscale = norm_inf(&qp.g).max(norm_inf(&x)).max(1e-300);
        let in_j: Vec<bool> = (0..m).map(|i| s[i] - qp.g[i] >= -1e-12 * gscale).collect();
        let mut seen = vec![false; n];
        let mut disjoint = true;
        for i in 0..m {
            for &c in qp.a.row(i).0 {
                if seen[c] {
                    disjoint = false;
                }
                seen[c] = true;
            }
        }
        let row_norm2 = (0..m)
            .map(|i| qp.a.row(i).1.iter().map(|v| v * v).sum())
            .collect();
        let mut wd = vec![0.0; n];
        pc.apply(&qp.d, &mut wd);
        let kernel = orthonormal_kernel(&qp.c, &qp.kernel)?;
        let mut st = Cgc {
            qp,
            pc,
            tol,
            multiple,
            x,
            grad,
            s,
            in_j,
            lam: vec![0.0; m],
            ref_norm: dot(&qp.d, &wd).max(0.0).sqrt(),
            floor: 0.0,
            stalled: false,
            resolved: false,
            tol_eff: tol,
            tightened: 0,
            gp_norm: f64::INFINITY,
            kernel,
            cdiag: qp.c.diag(),
            direct: disjoint && pc.is_identity(),
            row_norm2,
            inner: 0,
            kmax_cap: usize::MAX,
        };
        let (_, r) = st.project();
        st.ref_norm = st.ref_norm.max(r.sqrt()).max(1e-300);
        Ok(st)
    }

    fn working_set(&self) -> Vec<usize> {
        (0..self.qp.m()).filter(|&i| self.in_j[i]).collect()
    }

    /// PROJECT_W: λ_J for the current gradient, z = W⁻¹(∇f + A_Jᵀλ_J), r = (∇f + A_Jᵀλ)ᵀz.
    fn project(&mut self) -> (Vec<f64>, f64) {
        let qp = self.qp;
        let n = qp.n();
        let jset = self.working_set();
        let mut gp = self.grad.clone();
        if !jset.is_empty() {
            if self.direct {
                for &j in &jset {
                    let l = -qp.a.row_dot(j, &self.grad) / self.row_norm2[j];
                    self.lam[j] = l;
                    let (c, v) = qp.a.row(j);
                    for (&k, &a) in c.iter().zip(v) {
                        gp[k] += a * l;
                    }
                }
            } else {
                let mut h = vec![0.0; n];
                self.pc.apply(&self.grad, &mut h);
                let rhs: Vec<f64> = jset.iter().map(|&j| -qp.a.row_dot(j, &h)).collect();
                let mut mu: Vec<f64> = jset.iter().map(|&j| self.lam[j]).collect();
                self.inner += schur_cg(qp, self.pc, &jset, &rhs, &mut mu);
                for (&j, &l) in jset.iter().zip(&mu) {
                    self.lam[j] = l;
                    let (c, v) = qp.a.row(j);
                    for (&k, &a) in c.iter().zip(v) {
                        gp[k] += a * l;
                    }
                }
            }
        }
        let mut z = vec![0.0; n];
        self.pc.apply(&gp, &mut z);
        let r = dot(&gp, &z);
        self.gp_norm = norm(&gp);
        (z, r)
    }

    /// Pull x back onto its face {A_J x = g_J} after rounding drift:
    /// x ← x − W⁻¹A_Jᵀ (A_J W⁻¹ A_Jᵀ)⁻¹ (A_J x − g_J).
    fn restore_face(&mut self) {
        let qp = self.qp;
        let jset = self.working_set();
        if jset.is_empty() {
            return;
        }
        let viol: Vec<f64> = jset.iter().map(|&j| self.s[j] - qp.g[j]).collect();
        let scale = norm_inf(&self.x).max(norm_inf(&qp.g)).max(1e-300);
        if norm_inf(&viol) <= 1e-14 * scale {
            return;
        }
        let mut mu = vec![0.0; jset.len()];
        self.inner += schur_cg(qp, self.pc, &jset, &viol, &mut mu);
        let mut t = vec![0.0; qp.n()];
        for (&j, &m) in jset.iter().zip(&mu) {
            let (c, v) = qp.a.row(j);
            for (&k, &a) in c.iter().zip(v) {
                t[k] += a * m;
            }
        }
        let mut dx = vec![0.0; qp.n()];
        self.pc.apply(&t, &mut dx);
        axpy(-1.0, &dx, &mut self.x);
        self.refresh();
    }

    /// Recompute ∇f and Ax from x (no drift across faces).
    fn refresh(&mut self) {
        let cx = self.qp.c.mul(&self.x);
        for ((g, c), d) in self.grad.iter_mut().zip(&cx).zip(&self.qp.d) {
            *g = c - d;
        }
        self.s = self.qp.a.mul(&self.x);
    }

    /// FACE_CG (preconditioned): CG on the current face from x.
    fn face_cg(&mut self) -> FaceEnd {
        let qp = self.qp;
        let n = qp.n();
        let nj = self.in_j.iter().filter(|b| **b).count();
        let kmax = (2 * n.saturating_sub(nj) + 10).min(self.kmax_cap);
        let mut p = vec![0.0; n];
        let mut w = vec![0.0; n];
        let mut r_old = 0.0;
        self.stalled = false;
        self.resolved = false;
        // The last residual that halved its predecessor anchor, and the steps since.
        let (mut anchor, mut since) = (f64::INFINITY, 0usize);
        for k in 0..kmax {
            let (z, r) = self.project();
            if !r.is_finite() {
                return FaceEnd::Unbounded(vec![f64::NAN]);
            }
            let rs = r.max(0.0).sqrt();
            if rs <= self.tol_eff * self.ref_norm {
                self.resolved = true;
                return FaceEnd::Min;
            }
            if rs < 0.5 * anchor {
                (anchor, since) = (rs, 0);
            } else {
                since += 1;
            }
            if since >= FACE_STALL && rs <= self.floor * self.ref_norm {
                (self.stalled, self.resolved) = (true, true);
                return FaceEnd::Min;
            }
            if k == 0 {
                for (pi, zi) in p.iter_mut().zip(&z) {
                    *pi = -zi;
                }
            } else {
                let beta = r / r_old;
                for (pi, zi) in p.iter_mut().zip(&z) {
                    *pi = -zi + beta * *pi;
                }
            }
            r_old = r;
            self.inner += 1;
            qp.c.mul_vec(&p, &mut w);
            let a2 = dot(&p, &w);
            let ap = qp.a.mul(&p);
            let pp = dot(&p, &p);
            if a2.is_nan() {
                return FaceEnd::Unbounded(vec![f64::NAN]);
            }
            let zero = self.zero_curvature(&p, a2, pp);
            if !zero && !(a2 > 0.0) {
                // pᵀCp ≤ 0 off ker C: rounding, C being semidefinite. The
                // face is resolved as far as f64 goes; the certificate
                // judges. (A steel deck on rubber at a contrast of 1e8: CG
                // went on below its floor to ‖p‖ = 2e-16, pᵀCp came out
                // −2e-38, and the step was taken for a rigid motion:
                // a false unbounded claim.)
                (self.stalled, self.resolved) = (true, true);
                return FaceEnd::Min;
            }
            // (g,p) = −r; a step of length r/a2 is the exact line search.
            let alpha = if !zero && r < a2 * MAXVAL {
                r / a2
            } else {
                MAXVAL
            };
            let mut abar = MAXVAL;
            let mut istar = usize::MAX;
            for i in 0..qp.m() {
                if !self.in_j[i] && ap[i] > 0.0 {
                    let t = ((qp.g[i] - self.s[i]) / ap[i]).max(0.0);
                    if t < abar {
                        abar = t;
                        istar = i;
                    }
                }
            }
            if istar != usize::MAX && abar < alpha {
                axpy(abar, &p, &mut self.x);
                axpy(abar, &w, &mut self.grad);
                axpy(abar, &ap, &mut self.s);
                self.in_j[istar] = true;
                self.lam[istar] = 0.0;
                return FaceEnd::NewFace;
            }
            if alpha >= MAXVAL {
                return FaceEnd::Unbounded(p);
            }
            axpy(alpha, &p, &mut self.x);
            axpy(alpha, &w, &mut self.grad);
            axpy(alpha, &ap, &mut self.s);
        }
        FaceEnd::Kmax
    }

    fn record(&self, residual: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual,
            active: self.in_j.iter().filter(|b| **b).count(),
            inner: self.inner,
        }
    }

    /// Package the state as an [`Output`] (the driver certifies it).
    pub fn into_result(
        self,
        status: Status,
        iterations: usize,
        log: Vec<IterRecord>,
        timings: Vec<(String, f64)>,
    ) -> Output {
        let m = self.qp.m();
        let lambda: Vec<f64> = (0..m)
            .map(|i| if self.in_j[i] { self.lam[i] } else { 0.0 })
            .collect();
        Output {
            active: self.in_j.clone(),
            x: self.x,
            lambda,
            lambda_t: vec![],
            status,
            iterations,
            inner_iterations: self.inner,
            log,
            timings,
        }
    }
}

impl Iterative for Cgc<'_> {
    fn step(&mut self) -> Step {
        self.restore_face();
        self.floor = self.rounding_floor();
        let (_, r) = self.project();
        let res = r.max(0.0).sqrt() / self.ref_norm;
        if res <= self.tol_eff || (self.resolved && res <= self.floor) {
            // Face minimum: λ_J are the KKT multipliers of this face.
            let jset = self.working_set();
            let lbar = jset.iter().fold(0.0f64, |m, &j| m.max(self.lam[j].abs()));
            let lbar = if lbar > 0.0 { lbar } else { 1.0 };
            let thr = -100.0 * self.tol * lbar;
            let neg: Vec<usize> = jset
                .iter()
                .copied()
                .filter(|&j| self.lam[j] < thr)
                .collect();
            if neg.is_empty() {
                // The W⁻¹-norm weighs a residual on a stiff body by
                // 1/stiffness: at a contrast of 10⁸ it hid a Euclidean
                // stationarity of 10⁻⁵. Tighten until the Euclidean
                // residual meets EUCLID·tol too (or the rounding floor).
                let cx = self.qp.c.mul(&self.x);
                let scale = norm(&self.qp.d).max(norm(&cx)).max(f64::MIN_POSITIVE);
                if self.gp_norm / scale <= EUCLID * self.tol
                    || self.tightened >= TIGHTEN
                    || self.stalled
                {
                    log::debug!(
                        "cgc: face minimum accepted: energy-norm residual {res:.2e} (tol {:.1e}, \
                         floor {:.1e}, stalled {}), Euclidean {:.2e}, {} tightenings",
                        self.tol_eff,
                        self.floor,
                        self.stalled,
                        self.gp_norm / scale,
                        self.tightened
                    );
                    return Step::Done(Status::Converged, self.record(res));
                }
                self.tol_eff /= 10.0;
                self.tightened += 1;
            } else {
                let worst = *neg
                    .iter()
                    .min_by(|&&a, &&b| self.lam[a].total_cmp(&self.lam[b]))
                    .unwrap_or(&neg[0]);
                let released = if self.multiple { neg } else { vec![worst] };
                for &j in &released {
                    self.in_j[j] = false;
                }
                // Multiple release is safe only if the first direction moves
                // every released row inward; otherwise release the worst only.
                if released.len() > 1 && !self.release_moves_inward(&released) {
                    for &j in &released {
                        self.in_j[j] = true;
                    }
                    self.in_j[worst] = false;
                }
            }
        }
        match self.face_cg() {
            FaceEnd::Unbounded(p) => {
                Step::Done(Status::Unbounded { direction: p }, self.record(res))
            }
            FaceEnd::Min | FaceEnd::NewFace | FaceEnd::Kmax => {
                self.refresh();
                Step::Continue(self.record(res))
            }
        }
    }
}

impl Cgc<'_> {
    /// The level below which the projected gradient is rounding noise, relative
    /// to `ref_norm`: ∇f = Cx − d is computed with an error of about
    /// ε·(|C||x| + |d|) entry by entry, which is ‖·‖_{W⁻¹} = sqrt(eᵀW⁻¹e) for
    /// e = 64ε(|C||x| + |d|). With a stiff body resting on a soft one, |C||x|
    /// (a large rigid motion of the stiff body) can put this floor above a
    /// requested tol of 1e-10: the face minimum then cannot be resolved
    /// further, and the KKT certificate judges the answer.
    fn rounding_floor(&self) -> f64 {
        let c = &self.qp.c;
        let e: Vec<f64> = (0..self.qp.n())
            .map(|i| {
                let (cols, vals) = c.row(i);
                let s: f64 = cols
                    .iter()
                    .zip(vals)
                    .map(|(&j, v)| (v * self.x[j]).abs())
                    .sum();
                64.0 * f64::EPSILON * (s + self.qp.d[i].abs())
            })
            .collect();
        let mut z = vec![0.0; e.len()];
        self.pc.apply(&e, &mut z);
        let f = dot(&e, &z).max(0.0).sqrt() / self.ref_norm;
        if f.is_finite() {
            f
        } else {
            0.0
        }
    }

    /// Is pᵀCp = `a2` a zero curvature? Scale-invariant (methods.md §4.1):
    /// with a kernel basis R, only a direction in span R (‖p − RRᵀp‖ ≤ 10⁻⁸‖p‖,
    /// pure geometry) counts (a non-positive a2 off span R is rounding, and
    /// `face_cg` ends the face there); without one, a non-positive a2 counts
    /// and a2 is compared with pᵀdiag(C)p, each entry in its own body's scale.
    /// A stiff body on a soft one gives small but positive curvatures that
    /// must be stepped along, not taken for a rigid motion. Any unbounded
    /// claim is checked again by the driver (recession::certify).
    fn zero_curvature(&self, p: &[f64], a2: f64, pp: f64) -> bool {
        if self.kernel.is_empty() {
            if !(a2 > 0.0) {
                return true;
            }
            let pdp: f64 = p.iter().zip(&self.cdiag).map(|(v, c)| v * v * c).sum();
            return a2 <= 1e-14 * pdp;
        }
        // ‖p − RRᵀp‖² = ‖p‖² − Σ(zᵀp)² (R orthonormal): enough to rule out
        // span R without an n-vector per CG step; the explicit projection only
        // when that difference is too small to trust.
        let coef: Vec<f64> = self.kernel.iter().map(|z| dot(z, p)).collect();
        if pp - coef.iter().map(|c| c * c).sum::<f64>() > 1e-8 * pp {
            return false;
        }
        let mut rest = p.to_vec();
        for (z, c) in self.kernel.iter().zip(&coef) {
            axpy(-c, z, &mut rest);
        }
        dot(&rest, &rest) <= 1e-16 * pp
    }

    /// Does the first FACE_CG direction after releasing `released` move every
    /// released row inward? (the non-cycling condition of §4.1).
    fn release_moves_inward(&mut self, released: &[usize]) -> bool {
        let (z, _) = self.project();
        let ap = self.qp.a.mul(&z); // p = −z
        let pn = norm(&z);
        !released
            .iter()
            .any(|&j| -ap[j] > -1e-12 * pn * self.row_norm2[j].sqrt())
    }
}

/// CG on S μ = rhs with S = A_J W⁻¹ A_Jᵀ (matrix-free), from the given μ.
/// Returns the number of iterations.
pub fn schur_cg(
    qp: &QpProblem,
    pc: &dyn Preconditioner,
    jset: &[usize],
    rhs: &[f64],
    mu: &mut [f64],
) -> usize {
    let n = qp.n();
    let k = jset.len();
    let mut t = vec![0.0; n];
    let mut wt = vec![0.0; n];
    let mut apply = |v: &[f64], out: &mut [f64]| {
        t.iter_mut().for_each(|e| *e = 0.0);
        for (&j, &vj) in jset.iter().zip(v) {
            if vj != 0.0 {
                let (c, a) = qp.a.row(j);
                for (&col, &aa) in c.iter().zip(a) {
                    t[col] += aa * vj;
                }
            }
        }
        pc.apply(&t, &mut wt);
        for (o, &j) in out.iter_mut().zip(jset) {
            *o = qp.a.row_dot(j, &wt);
        }
    };
    let bnorm = norm(rhs);
    if bnorm == 0.0 {
        mu.iter_mut().for_each(|e| *e = 0.0);
        return 0;
    }
    let mut q = vec![0.0; k];
    apply(mu, &mut q);
    let mut res: Vec<f64> = rhs.iter().zip(&q).map(|(b, v)| b - v).collect();
    let mut p = res.clone();
    let mut rr = dot(&res, &res);
    let target = (1e-13 * bnorm).powi(2);
    let maxit = 2 * k + 50;
    let mut it = 0;
    while rr > target && it < maxit {
        apply(&p, &mut q);
        let pq = dot(&p, &q);
        if !(pq > 0.0) {
            break;
        }
        let a = rr / pq;
        axpy(a, &p, mu);
        axpy(-a, &q, &mut res);
        let rr_new = dot(&res, &res);
        let b = rr_new / rr;
        rr = rr_new;
        for (pi, ri) in p.iter_mut().zip(&res) {
            *pi = ri + b * *pi;
        }
        it += 1;
    }
    it
}

/// Ax ≤ g up to rounding (a warm start must be feasible, §4.1).
pub fn is_feasible(qp: &QpProblem, x: &[f64]) -> bool {
    let ax = qp.a.mul(x);
    let scale = norm_inf(x).max(norm_inf(&qp.g)).max(1e-300);
    x.iter().all(|v| v.is_finite()) && ax.iter().zip(&qp.g).all(|(a, g)| a - g <= 1e-12 * scale)
}

/// x⁰ = 0 when g ≥ 0 (the report's glued start); otherwise the least-norm
/// x⁰ = Aᵀ(AAᵀ)⁻¹ min(g, 0), which satisfies Ax⁰ = min(g, 0) ≤ g.
pub fn feasible_start(qp: &QpProblem) -> Vec<f64> {
    let n = qp.n();
    if qp.g.iter().all(|&v| v >= 0.0) {
        return vec![0.0; n];
    }
    let all: Vec<usize> = (0..qp.m()).collect();
    let rhs: Vec<f64> = qp.g.iter().map(|&v| v.min(0.0)).collect();
    let mut mu = vec![0.0; qp.m()];
    schur_cg(qp, &precond::Identity, &all, &rhs, &mut mu);
    qp.a.mul_t(&mu)
}
