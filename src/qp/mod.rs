//! The quadratic programme of contact (with or without friction) and the methods that solve it.
//!
//! Names (docs/methods.md §0, §2.8), used everywhere in this module tree:
//!
//! * `x ∈ ℝᴺ` — the unknowns (displacement DOFs left after Dirichlet and slip elimination);
//! * `C` — the N×N stiffness matrix, symmetric positive *semi*definite (a floating body
//!   gives a kernel of rigid motions);
//! * `d` — the load vector; the energy is `J(x) = f(x) = ½xᵀCx − xᵀd`, gradient `Cx − d`;
//! * `A` — the M×N contact matrix, one row per contact constraint; `g` — the initial gaps:
//!   the constraints are `Ax ≤ g` (conforming pairs have g = 0);
//! * `λ ∈ ℝᴹ`, `λ ≥ 0` — the multipliers = nodal normal contact forces (compression positive);
//! * KKT: `Cx − d + Aᵀλ = 0, λ ≥ 0, Ax ≤ g, λᵀ(Ax − g) = 0`;
//! * the active set `J = {i : (Ax − g)ᵢ = 0}`.
//!
//! This layer knows nothing of meshes: `fem` builds a [`QpProblem`], every method
//! returns an [`Output`] that the [`driver`] certifies into a [`QpResult`]. A
//! method is one type implementing [`Method`], named by one [`MethodId`].

pub mod active_set;
pub mod coulomb;
pub mod driver;
pub mod dual;
pub mod executor;
mod factor_advice;
pub mod kkt;
pub mod method;
pub mod precond;
pub mod primal;
pub mod recession;
pub mod recession_tresca;
pub mod registry;
pub mod settings;
pub mod ssn;
#[cfg(test)]
pub(crate) mod testing;
#[cfg(test)]
mod tests_methods;

pub use crate::linalg::sparse::{self, Csr};
pub use coulomb::CoulombRelaxation;
pub use driver::{Context, Note, Output};
pub use executor::{Observer, ProgressDisplay};
pub use method::{Capabilities, FallbackCause, FrictionSupport, Method, MethodChoice, MethodId};
pub use settings::{ByteSize, Release, Settings, SolverSection};

/// min ½xᵀCx − xᵀd subject to Ax ≤ g  (methods.md §2.8 with b = g).
#[derive(Debug, Clone, Default)]
pub struct QpProblem {
    pub c: Csr,
    pub d: Vec<f64>,
    pub a: Csr,
    pub g: Vec<f64>,
    /// A basis of ker C (rigid motions of floating bodies), if known. Methods
    /// that need C⁻¹ use it to regularise; CGC does not need it.
    pub kernel: Vec<Vec<f64>>,
    /// Tangential rows and slip bounds (docs/methods.md §9); `None` is
    /// frictionless contact, solved exactly as without this field.
    pub friction: Option<Friction>,
    /// The unknowns grouped by mesh point and the rigid motions sampled on
    /// them, for the algebraic multigrid of the iterative ssn path
    /// (docs/methods.md §7.2); `None`: unknowns taken one by one.
    pub near: Option<NearKernel>,
}

/// What an algebraic multigrid needs to know of the mesh and no more (PETSc's
/// block size and near-null space): the unknowns of block b are
/// `block_ptr[b]..block_ptr[b + 1]` (one mesh point), and `modes` are the
/// rigid motions of every body (two translations and a rotation in 2D,
/// Dirichlet conditions ignored) in the unknowns: the motions C barely
/// resists, which coarse levels must represent (docs/methods.md §7.2).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NearKernel {
    pub block_ptr: Vec<usize>,
    pub modes: Vec<Vec<f64>>,
}

impl QpProblem {
    /// A near-null space of the six rigid motions of 3D elasticity: the
    /// iterative ssn path's settings for solid models are chosen by this,
    /// so that plane models (three motions) keep theirs and their bits
    /// (docs/methods.md §7.2).
    pub fn has_solid_modes(&self) -> bool {
        self.near.as_ref().is_some_and(|nk| nk.modes.len() >= 6)
    }
}

/// The slip bound of each tangential row (docs/methods.md §9.1).
#[derive(Debug, Clone, PartialEq)]
pub enum SlipBound {
    /// Tresca: a given bound sᵢ ≥ 0 (N, the row's force).
    Tresca(Vec<f64>),
    /// Coulomb: sᵢ = μᵢ·λ_nᵢ, the coefficient per row.
    Coulomb(Vec<f64>),
}

/// A row slips when |λ_t| ≥ (1 − STICK_MARGIN)·s (the bound is reached to
/// the accuracy the certificate asks of it): the outputs' stick / slip
/// state and a load step's warm-start sets read it alike.
pub const STICK_MARGIN: f64 = 1e-6;

/// How many tangential rows a contact row has, and so the shape of its
/// friction law (docs/methods.md §9, §12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Frame {
    /// One tangent (plane and axisymmetric models): the bound is on |λ_t|,
    /// an interval.
    #[default]
    Line,
    /// Two orthonormal tangents t1, t2 (solid models): the bound is on the
    /// Euclidean norm of the pair (λ_t1, λ_t2), a disc (Tresca) or a cone
    /// (Coulomb); never a polygon, which would make friction anisotropic.
    Plane,
}

impl Frame {
    /// Tangential rows per contact row.
    pub fn rows(self) -> usize {
        match self {
            Frame::Line => 1,
            Frame::Plane => 2,
        }
    }
}

/// Friction on the contact rows (docs/methods.md §9, §12): `frame.rows()`
/// tangential rows of `t` per row of A (same order: contact row i owns rows
/// k·i .. k·i + k), the slip v = T x − t0 (t0: the tangential relative
/// displacement of the previous load step) and its bound, one per contact
/// row. The Tresca problem adds Σ sᵢ‖vᵢ‖ to the energy (vᵢ the row's k
/// slips); KKT: Cx − d + Aᵀλ_n + Tᵀλ_t = 0, ‖λ_tᵢ‖ ≤ sᵢ, and vᵢ ≠ 0 only
/// where λ_tᵢ = sᵢ·vᵢ/‖vᵢ‖.
#[derive(Debug, Clone, PartialEq)]
pub struct Friction {
    pub t: Csr,
    pub t0: Vec<f64>,
    pub bound: SlipBound,
    pub frame: Frame,
}

/// ‖v‖ of one contact row's tangential slice: |v| on a line (the same bits
/// as `abs`), the Euclidean norm in a plane (`hypot`: no overflow).
pub fn tangential_norm(v: &[f64]) -> f64 {
    match v {
        [a] => a.abs(),
        [a, b] => a.hypot(*b),
        _ => v.iter().map(|e| e * e).sum::<f64>().sqrt(),
    }
}

/// Coulomb's slip bound sᵢ = μᵢ max(λ_nᵢ, 0), an overflow kept at the largest
/// finite number ([`Friction::slip_bound`]; also ssn's coarse levels).
pub fn coulomb_bound(mu: &[f64], lambda_n: &[f64]) -> Vec<f64> {
    mu.iter()
        .zip(lambda_n)
        .map(|(m, l)| (m * l.max(0.0)).min(f64::MAX))
        .collect()
}

impl Friction {
    /// The slip bound s of each row at the normal forces `lambda_n`; a
    /// Coulomb bound μλ_n that overflows is the largest finite number (a
    /// glued row either way; an infinite s would make the certificate and
    /// the Coulomb loop NaN).
    pub fn slip_bound(&self, lambda_n: &[f64]) -> Vec<f64> {
        match &self.bound {
            SlipBound::Tresca(s) => s.clone(),
            SlipBound::Coulomb(mu) => coulomb_bound(mu, lambda_n),
        }
    }
    /// The slip v = T x − t0.
    pub fn slip(&self, x: &[f64]) -> Vec<f64> {
        let mut v = self.t.mul(x);
        for (vi, t0) in v.iter_mut().zip(&self.t0) {
            *vi -= t0;
        }
        v
    }
}

impl QpProblem {
    pub fn n(&self) -> usize {
        self.d.len()
    }
    pub fn m(&self) -> usize {
        self.g.len()
    }
    /// f(x) = ½xᵀCx − xᵀd
    pub fn energy(&self, x: &[f64]) -> f64 {
        let cx = self.c.mul(x);
        0.5 * sparse::dot(x, &cx) - sparse::dot(x, &self.d)
    }
    /// The energy with the friction dissipation Σ sᵢ|vᵢ| at the normal forces
    /// `lambda_n` (the Tresca functional; [`QpProblem::energy`] without friction).
    pub fn energy_with_friction(&self, x: &[f64], lambda_n: &[f64]) -> f64 {
        self.energy_with_friction_cx(x, &self.c.mul(x), lambda_n)
    }
    /// [`QpProblem::energy_with_friction`] with `cx` = Cx already formed.
    pub fn energy_with_friction_cx(&self, x: &[f64], cx: &[f64], lambda_n: &[f64]) -> f64 {
        let e = 0.5 * sparse::dot(x, cx) - sparse::dot(x, &self.d);
        match &self.friction {
            None => e,
            Some(f) => {
                let s = f.slip_bound(lambda_n);
                e + f
                    .slip(x)
                    .chunks(f.frame.rows())
                    .zip(&s)
                    .map(|(v, s)| s * tangential_norm(v))
                    .sum::<f64>()
            }
        }
    }
}

/// How a solve ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    Converged,
    /// MAXIT reached.
    MaxIter,
    /// f is unbounded below on the feasible set; `direction` is a descent
    /// direction with zero curvature along which no constraint blocks.
    Unbounded {
        direction: Vec<f64>,
    },
    /// The method stopped without an answer it stands by.
    Failed(Failure),
}

/// Why a method stopped without converging. The driver's rules match on
/// the variant (a stagnated answer is judged by the certificate, a cycling
/// one falls back, docs/methods.md §8); the text is made only at the edge
/// ([`std::fmt::Display`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// The residual has not gone below its best (`best`, at iteration
    /// `best_at`) in `window` iterations; the last was `residual`
    /// ([`executor::STALL_WINDOW`]).
    Stagnation {
        residual: f64,
        best: f64,
        best_at: usize,
        window: usize,
    },
    /// A NaN or Inf residual in iteration `iteration`.
    NotFinite { iteration: usize },
    /// The caller's time budget ran out after `iterations` iterations
    /// (`compare --time-limit`; never a decision of a method).
    TimeLimit { iterations: usize },
    /// The caller's stop flag ([`SolveOptions::stop`]) was raised with
    /// `signal` after `iterations` iterations.
    Interrupted { signal: i32, iterations: usize },
    /// The working sets cycle: no KKT residual below `best` in `steps`
    /// Newton steps (frictional ssn, docs/methods.md §9.2).
    Cycling { best: f64, steps: usize },
    /// The Coulomb fixed point s = μλ_n did not settle in `outer` Tresca solves
    /// (last relative change `change`, docs/methods.md §9.1).
    CoulombUnsettled { outer: usize, change: f64 },
    /// The method's own check of its settled answer missed the
    /// certificate's target.
    Uncertified { residual: f64, target: f64 },
    /// An unbounded direction that fails the certificate, where no other
    /// method can take over (`why`: the failed test, docs/methods.md §8.2).
    RefusedClaim { method: MethodId, why: String },
    /// The method cannot go on: a singular system, a failed factor, a
    /// breakdown; the text says what, in the method's words.
    Breakdown(String),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Stagnation {
                residual,
                best,
                best_at,
                window,
            } => write!(
                f,
                "stagnation: the residual ({residual:.3e}) has not gone below its best {best:.3e} \
                 (iteration {best_at}) in {window} iterations"
            ),
            Failure::NotFinite { iteration } => write!(f, "NaN or Inf in iteration {iteration}"),
            Failure::TimeLimit { iterations } => {
                write!(f, "time limit reached after {iterations} iterations")
            }
            Failure::Interrupted { signal, iterations } => {
                write!(f, "interrupted by signal {signal} after {iterations} iterations")
            }
            Failure::Cycling { best, steps } => write!(
                f,
                "cycling: the working sets of the Tresca problem cycle: no KKT residual below {best:.3e} in {steps} Newton steps"
            ),
            Failure::CoulombUnsettled { outer, change } => write!(
                f,
                "the Coulomb fixed point (s = μλ_n) did not settle in {outer} Tresca solves (last change {change:.3e} of max s)"
            ),
            Failure::Uncertified { residual, target } => write!(
                f,
                "KKT residual {residual:.2e} after refinement (target {target:e})"
            ),
            Failure::RefusedClaim { method, why } => write!(
                f,
                "{method} reported an unbounded direction that fails the certificate ({why})"
            ),
            Failure::Breakdown(m) => f.write_str(m),
        }
    }
}

impl Status {
    pub fn converged(&self) -> bool {
        matches!(self, Status::Converged)
    }
    pub fn describe(&self) -> String {
        match self {
            Status::Converged => "converged".into(),
            Status::MaxIter => "not converged: maximum number of iterations reached".into(),
            Status::Unbounded { .. } => {
                "unbounded: the energy decreases without limit along a rigid motion".into()
            }
            Status::Failed(m) => format!("failed: {m}"),
        }
    }
}

/// One line of the iteration log.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct IterRecord {
    pub iter: usize,
    /// Method-specific convergence measure (relative).
    pub residual: f64,
    pub active: usize,
    pub inner: usize,
}

/// KKT residuals, relative as defined in problem-format.md.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct Kkt {
    pub primal: f64,
    pub dual: f64,
    pub complementarity: f64,
    pub stationarity: f64,
    /// Force balance at the contact unknowns relative to the contact forces
    /// ([`kkt::residuals`]).
    #[serde(default)]
    pub contact_balance: f64,
    /// The equilibrium of each rigid motion of ker C (a floating body):
    /// |zᵀ(Aᵀλ − d)| over the gross forces along z ([`kkt::residuals`],
    /// docs/methods.md §8.4); 0 without a kernel (and then left out of
    /// the JSON).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rigid_balance: f64,
    /// The friction conditions (docs/methods.md §9.4): |λ_t| ≤ s and slip
    /// only where the bound is reached, along λ_t; 0 without friction (and
    /// then left out of the JSON, which stays as it was).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub friction: f64,
    /// The rounding level of `stationarity`: what computing r = Cx − d + Aᵀλ
    /// in f64 may leave of an exact answer, on the same scale
    /// ([`kkt::residuals`], docs/methods.md §8.4).
    #[serde(default)]
    pub stationarity_floor: f64,
    /// The rounding level of `contact_balance`, on its scale.
    #[serde(default)]
    pub balance_floor: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// What the driver returns: a method's [`Output`] (its solution, read
/// through `Deref`: `r.x`, `r.lambda`, …) with the certificate, the energy
/// and the driver's notes.
#[derive(Debug, Clone)]
pub struct QpResult {
    pub solution: Output,
    pub kkt: Kkt,
    pub energy: f64,
    /// What the driver did beyond the method: a fallback, a refused claim
    /// ([`driver::run`]). Printed as warnings and written to the JSON.
    pub notes: Vec<driver::Note>,
}

impl std::ops::Deref for QpResult {
    type Target = Output;
    fn deref(&self) -> &Output {
        &self.solution
    }
}

impl std::ops::DerefMut for QpResult {
    fn deref_mut(&mut self) -> &mut Output {
        &mut self.solution
    }
}

/// Run a method's solve function directly (no driver checks, no
/// certificate) with a fresh workspace: the unit tests of one method.
#[cfg(test)]
pub(crate) fn run_direct(
    f: fn(&QpProblem, &mut Context) -> Result<Output, QpError>,
    qp: &QpProblem,
    opts: &SolveOptions,
) -> Result<Output, QpError> {
    let ws = crate::linalg::cholesky::Workspace::new();
    f(qp, &mut Context::new(opts, &ws))
}

/// An observer the caller keeps (to read what it saw after the solve) and
/// hands to the driver, which shows it every iteration of every executor.
pub type SharedObserver = std::rc::Rc<std::cell::RefCell<dyn executor::Observer>>;

/// What a caller asks of the driver besides the problem: the settings
/// (validated by the driver) and the run control — progress, label,
/// deadline, warm start, observers — which belong to the caller, not to the
/// problem file.
#[derive(Clone, Default)]
pub struct SolveOptions {
    pub settings: Settings,
    /// The caller's display of the iterations (the command line's spinner
    /// on stderr for long solves); None: none.
    pub progress: Option<std::sync::Arc<dyn executor::ProgressDisplay>>,
    /// Label of the progress display (e.g. the variant in `compare`).
    pub label: Option<String>,
    /// Stop with [`Failure::TimeLimit`] after this instant
    /// (`compare --time-limit`; a budget the user sets, never a decision
    /// of a method).
    pub deadline: Option<std::time::Instant>,
    /// Stop with [`Failure::Interrupted`] at the next iteration once this
    /// flag is non-zero (its value, a signal number, is reported): the
    /// caller's cancel (`signorini solve` sets it on SIGTERM/SIGINT,
    /// `run::catch_signals`). A flag the caller owns, never a decision of
    /// a method.
    pub stop: Option<&'static std::sync::atomic::AtomicI32>,
    /// Warm start (load steps, restart): used by methods that can, when feasible.
    pub x0: Option<Vec<f64>>,
    /// Working-set warm start (load steps, restart): the rows expected in
    /// contact, e.g. the last step's active set; methods that start from a
    /// working set (ssn) start from it (docs/methods.md §8.3).
    pub active0: Option<Vec<bool>>,
    /// Multiplier warm start of a frictional problem (load steps, restart):
    /// the last step's λ_n and λ_t per row, from which ssn takes the
    /// stick / slip / open sets and the first slip bound μλ_n of its
    /// Coulomb loop (docs/methods.md §9.5).
    pub lambda0: Option<Multipliers>,
    /// λ_n per contact row of an answer on a coarser mesh of the same
    /// model, interpolated onto this one together with `x0` (nested
    /// iteration, `--start-from`; docs/methods.md §7.2, "The nested
    /// start"). Methods that start from a working set take it from the
    /// pair, J0 = {i : λ̂ᵢ + c(Ax0 − g)ᵢ > 0}, in place of their own start.
    pub nested_lambda: Option<Vec<f64>>,
    /// Observers of every iteration record, besides the progress display.
    pub observers: Vec<SharedObserver>,
}

impl std::fmt::Debug for SolveOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolveOptions")
            .field("settings", &self.settings)
            .field("progress", &self.progress)
            .field("label", &self.label)
            .field("deadline", &self.deadline)
            .field("stop", &self.stop.is_some())
            .field("x0", &self.x0.as_ref().map(|x| x.len()))
            .field("active0", &self.active0.as_ref().map(|a| a.len()))
            .field("lambda0", &self.lambda0.as_ref().map(|l| l.normal.len()))
            .field("nested_lambda", &self.nested_lambda.as_ref().map(Vec::len))
            .field("observers", &self.observers.len())
            .finish()
    }
}

/// The multipliers of a frictional answer per contact row: λ_n (normal)
/// and λ_t (tangential), as a warm start ([`SolveOptions::lambda0`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Multipliers {
    pub normal: Vec<f64>,
    pub tangential: Vec<f64>,
}

impl SolveOptions {
    /// Default run control with `settings`.
    pub fn new(settings: Settings) -> SolveOptions {
        SolveOptions {
            settings,
            ..Default::default()
        }
    }
}

/// Errors that make a method refuse a problem (bad parameters, a singular
/// C it cannot handle). Non-convergence is a [`Status`], not an error.
#[derive(Debug, thiserror::Error)]
pub enum QpError {
    #[error("{0}")]
    BadParameter(String),
    #[error("{0}")]
    Unsupported(String),
    #[error("factorization failed: {0}")]
    Factor(String),
    /// A factor that does not fit in memory: never a reason to try another
    /// path (the bits of an answer must not depend on free memory).
    #[error("{0}")]
    Memory(String),
}

/// The large number of §5 (overflow guard, step for zero curvature).
pub const MAXVAL: f64 = 1e30;
