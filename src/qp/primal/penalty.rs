//! Exterior penalty with relaxation (docs/methods.md §4.4): minimise
//! h_ε(x, t) = f(x) + Σ_j ((a_j, x) − g_j + t_j)² / (2ε_j), t ≥ 0, by sweeps
//! of Gauss–Seidel/SOR over x (ω = `omega`; C and Aᵀ by rows, no
//! allocation) followed by the exact t_j = max(0, g_j − (a_j, x)).
//!
//! ε: the setting `penalty` for every row (the report's), else one per row,
//! ε_j = 1/([`PENALTY_FACTOR`] · min c_kk over the row's unknowns), so a
//! soft body under a stiff one is penalised in its own scale (§8.4).
//! Stop when ‖x^{k+1} − x^k‖ ≤ tol·‖x^k‖; λ = (Ax − g)⁺/ε, exact
//! stationarity for the penalised problem, feasibility to O(ε).
//!
//! `accelerate` (default): every [`CORRECTION_EVERY`] sweeps, minimise the
//! penalised energy exactly on the current penalty set (one sparse
//! Cholesky of C + A_JᵀW A_J on the fixed pattern of C + AᵀA, then an exact
//! line search): a descent step on the same function, so x_ε is unchanged.
//! Measurements behind these choices: BENCHMARKS.md, "Notes".

use crate::linalg::augmented::AugPattern;
use crate::linalg::cholesky::Workspace;
use crate::linalg::sparse::{norm, Csr};
use crate::qp::executor::{Iterative, Step};
use crate::qp::method::{Capabilities, Certificate, Factor, MethodId};
use crate::qp::Failure;
use crate::qp::{Context, IterRecord, Method, Output, QpError, QpProblem, Status};

/// Default ε_p = 1/(PENALTY_FACTOR · max diag C).
pub const PENALTY_FACTOR: f64 = 1e3;
/// Sweeps between two subspace corrections.
pub const CORRECTION_EVERY: usize = 10;
/// Newton steps per correction at most.
pub const NEWTON_STEPS: usize = 30;

/// Exterior penalty with relaxation (docs/methods.md §4.4).
pub struct PenaltyMethod;

impl Method for PenaltyMethod {
    fn id(&self) -> MethodId {
        MethodId::Penalty
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            factor: Factor::BySettings,
            certificate: Certificate::Penalised,
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "exterior penalty with Gauss–Seidel/SOR relaxation (§4.4)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let ps = &ctx.settings.penalty;
    let mut st = ctx.phase("setup", |ctx| setup(qp, ctx))?;
    let mut exec = ctx.executor("penalty");
    let (status, iters) = ctx.phase("iterate", |_| exec.run(&mut st));
    if let Some(e) = st.error.take() {
        return Err(e);
    }
    let ax = qp.a.mul(&st.x);
    let viol: Vec<f64> = ax
        .iter()
        .zip(&qp.g)
        .map(|(a, g)| (a - g).max(0.0))
        .collect();
    let vmax = viol.iter().fold(0.0f64, |a, &b| a.max(b));
    let eps: Vec<f64> = st.inv_eps.iter().map(|v| 1.0 / v).collect();
    let (emin, emax) = eps
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &e| (a.min(e), b.max(e)));
    log::info!(
        "penalty: ε_p from {emin:.3e} to {emax:.3e}, ω = {}, {iters} sweeps, {} of {} subspace corrections accepted, \
         max constraint violation {vmax:.3e}",
        ps.omega,
        st.corrections,
        st.factorizations
    );
    let lambda: Vec<f64> = viol.iter().zip(&eps).map(|(v, e)| v / e).collect();
    let active = lambda.iter().map(|&l| l > 0.0).collect();
    Ok(Output {
        x: st.x,
        lambda,
        lambda_t: vec![],
        active,
        status,
        iterations: iters,
        inner_iterations: st.factorizations,
        log: exec.log,
        timings: vec![],
    })
}

/// ε per row, the relaxation diagonal and the start x = 0.
fn setup<'a>(qp: &'a QpProblem, ctx: &Context<'a>) -> Result<Relax<'a>, QpError> {
    let ps = &ctx.settings.penalty;
    let cdiag = qp.c.diag();
    let eps: Vec<f64> = match ps.eps {
        Some(e) => vec![e; qp.m()],
        None => (0..qp.m())
            .map(|j| {
                let kmin =
                    qp.a.row(j)
                        .0
                        .iter()
                        .map(|&k| cdiag[k])
                        .filter(|&c| c > 0.0)
                        .fold(f64::INFINITY, f64::min);
                if kmin > 0.0 && kmin.is_finite() {
                    Ok(1.0 / (PENALTY_FACTOR * kmin))
                } else {
                    Err(QpError::BadParameter(format!(
                        "penalty: contact row {j} touches no unknown with a positive stiffness"
                    )))
                }
            })
            .collect::<Result<_, _>>()?,
    };
    let n = qp.n();
    let m = qp.m();
    let at = qp.a.transpose();
    let mut diag = vec![0.0; n];
    for (i, di) in diag.iter_mut().enumerate() {
        let (rows, vals) = at.row(i);
        let s: f64 = rows.iter().zip(vals).map(|(&j, a)| a * a / eps[j]).sum();
        *di = cdiag[i] + s;
        if cdiag[i] <= 0.0 || cdiag[i].is_nan() {
            return Err(QpError::Unsupported(format!(
                "penalty: Gauss–Seidel needs c_ii > 0, but c_{i}{i} = {}",
                cdiag[i]
            )));
        }
    }
    let x = vec![0.0; n];
    let s: Vec<f64> = (0..m)
        .map(|j| (qp.a.row_dot(j, &x) - qp.g[j]).max(0.0))
        .collect();
    Ok(Relax {
        qp,
        at,
        diag,
        inv_eps: eps.iter().map(|e| 1.0 / e).collect(),
        omega: ps.omega,
        tol: ctx.settings.tol,
        x_old: x.clone(),
        x,
        s,
        correct: ps.accelerate,
        sweeps: 0,
        corrections: 0,
        factorizations: 0,
        ws: ctx.ws,
        aug: None,
        error: None,
    })
}

struct Relax<'a> {
    qp: &'a QpProblem,
    /// Aᵀ (row i = the constraints DOF i occurs in)
    at: Csr,
    /// c_ii + Σ_j a_ji² / ε_j
    diag: Vec<f64>,
    /// 1/ε_j per contact row.
    inv_eps: Vec<f64>,
    omega: f64,
    tol: f64,
    x: Vec<f64>,
    x_old: Vec<f64>,
    /// s_j = (a_j, x) − g_j + t_j
    s: Vec<f64>,
    /// Subspace corrections on.
    correct: bool,
    sweeps: usize,
    /// Accepted corrections / factorizations made.
    corrections: usize,
    factorizations: usize,
    /// Where the correction factors reuse their symbolic analysis.
    ws: &'a Workspace,
    /// The pattern of C + AᵀA, made at the first correction.
    aug: Option<AugPattern>,
    /// A factor refused for memory: the solve ends with it.
    error: Option<QpError>,
}

impl Relax<'_> {
    /// g_ε(x) = f(x) + Σ_j ((a_j,x) − g_j)⁺² / (2ε_j)
    fn g_eps(&self, x: &[f64]) -> f64 {
        let pen: f64 = (0..self.qp.m())
            .map(|j| (self.qp.a.row_dot(j, x) - self.qp.g[j]).max(0.0).powi(2) * self.inv_eps[j])
            .sum();
        self.qp.energy(x) + 0.5 * pen
    }

    /// Minimise g_ε exactly on the current penalty set (see the module doc).
    /// Semismooth Newton steps until the penalty set stops changing
    /// (at most [`NEWTON_STEPS`]).
    fn subspace_correction(&mut self) {
        for _ in 0..NEWTON_STEPS {
            let before: Vec<bool> = self.s.iter().map(|&v| v > 0.0).collect();
            if !self.newton_step() || self.error.is_some() {
                return;
            }
            if self.s.iter().map(|&v| v > 0.0).eq(before) {
                return;
            }
        }
    }

    /// One step; false if it was not taken.
    fn newton_step(&mut self) -> bool {
        let qp = self.qp;
        // K = C + A_JᵀA_J/ε on the fixed pattern of C + AᵀA (rows outside J
        // enter with weight 0), so every Newton step reuses the symbolic
        // analysis of the first ([`crate::linalg::cholesky`] cache).
        let jset: Vec<usize> = (0..qp.m()).filter(|&j| self.s[j] > 0.0).collect();
        let mut rhs = qp.d.clone();
        for &j in &jset {
            let w = self.inv_eps[j];
            let (c, v) = qp.a.row(j);
            for (&k, &ak) in c.iter().zip(v) {
                rhs[k] += w * ak * qp.g[j];
            }
        }
        let aug = self
            .aug
            .get_or_insert_with(|| AugPattern::new(&qp.c, &qp.a));
        let k = aug.assemble(jset, &self.inv_eps);
        self.factorizations += 1;
        // A floating body J does not hold yet makes K singular: then the
        // spring-regularised K + S (fixing DOFs, [`Cholesky::new`]) still
        // gives a descent direction −(K + S)⁻¹∇g_ε.
        // A factor refused for memory ends the solve (QpError::Memory):
        // going on without the correction would make the answer depend on
        // the machine's free memory.
        let fac = match self.ws.cholesky(k, &[]) {
            Ok(f) => f,
            Err(e) if e.is_memory() => {
                self.error = Some(e.into());
                return false;
            }
            Err(_) if !qp.kernel.is_empty() => match self.ws.cholesky(k, &qp.kernel) {
                Ok(f) => f,
                Err(e) => {
                    if e.is_memory() {
                        self.error = Some(e.into());
                    }
                    return false;
                }
            },
            Err(_) => return false,
        };
        let kx = k.mul(&self.x);
        let res: Vec<f64> = rhs.iter().zip(&kx).map(|(a, b)| a - b).collect();
        let step = fac.solve(&res);
        if !step.iter().all(|v| v.is_finite()) {
            return false;
        }
        let y: Vec<f64> = self.x.iter().zip(&step).map(|(a, b)| a + b).collect();
        // Exact line search on the convex piecewise quadratic
        // φ(t) = g_ε(x + t(y − x)), t ∈ [0, 1]: φ'(0) ≤ 0 because J is the
        // violated set at x; φ' is monotone, so bisect on its sign.
        let dir: Vec<f64> = y.iter().zip(&self.x).map(|(a, b)| a - b).collect();
        let cx = qp.c.mul(&self.x);
        let cd = qp.c.mul(&dir);
        let lin = crate::linalg::sparse::dot(&cx, &dir) - crate::linalg::sparse::dot(&qp.d, &dir);
        let quad = crate::linalg::sparse::dot(&cd, &dir);
        let ax: Vec<f64> = (0..qp.m())
            .map(|j| qp.a.row_dot(j, &self.x) - qp.g[j])
            .collect();
        let ad = qp.a.mul(&dir);
        let dphi = |t: f64| {
            lin + t * quad
                + ax.iter()
                    .zip(&ad)
                    .zip(&self.inv_eps)
                    .map(|((a, d), w)| (a + t * d).max(0.0) * d * w)
                    .sum::<f64>()
        };
        let t = if dphi(1.0) <= 0.0 {
            1.0
        } else {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if dphi(mid) <= 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let z: Vec<f64> = self.x.iter().zip(&dir).map(|(a, d)| a + t * d).collect();
        if t > 0.0 && self.g_eps(&z) <= self.g_eps(&self.x) {
            self.x = z;
            for (j, sj) in self.s.iter_mut().enumerate() {
                *sj = (qp.a.row_dot(j, &self.x) - qp.g[j]).max(0.0);
            }
            self.corrections += 1;
            return true;
        }
        false
    }
}

impl Iterative for Relax<'_> {
    fn step(&mut self) -> Step {
        let qp = self.qp;
        self.sweeps += 1;
        if self.correct && self.sweeps.is_multiple_of(CORRECTION_EVERY) {
            self.subspace_correction();
            if let Some(e) = &self.error {
                return Step::Done(
                    Status::Failed(Failure::Breakdown(e.to_string())),
                    IterRecord::default(),
                );
            }
        }
        self.x_old.copy_from_slice(&self.x);
        // Step 1: relaxation in x with the current s.
        for i in 0..self.x.len() {
            let (cc, cv) = qp.c.row(i);
            let cx: f64 = cc.iter().zip(cv).map(|(&k, &c)| c * self.x[k]).sum();
            let (ac, av) = self.at.row(i);
            let pen: f64 = ac
                .iter()
                .zip(av)
                .map(|(&j, &a)| a * self.s[j] * self.inv_eps[j])
                .sum();
            let grad = cx - qp.d[i] + pen;
            let delta = -self.omega * grad / self.diag[i];
            self.x[i] += delta;
            for (&j, &a) in ac.iter().zip(av) {
                self.s[j] += a * delta;
            }
        }
        // Step 2: projected minimisation in t: s_j = ((a_j,x) − g_j)⁺.
        for (j, sj) in self.s.iter_mut().enumerate() {
            *sj = (qp.a.row_dot(j, &self.x) - qp.g[j]).max(0.0);
        }
        let diff: f64 = self
            .x
            .iter()
            .zip(&self.x_old)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        let xo = norm(&self.x_old);
        let err = diff / xo.max(1e-300);
        let err = if diff == 0.0 { 0.0 } else { err };
        let active = self.s.iter().filter(|&&v| v > 0.0).count();
        let rec = IterRecord {
            iter: 0,
            residual: err,
            active,
            inner: 0,
        };
        if err < self.tol {
            Step::Done(Status::Converged, rec)
        } else {
            Step::Continue(rec)
        }
    }
}
