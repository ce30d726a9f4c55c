//! The quadratic programme of frictionless contact and the methods that solve it.
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
//! returns a [`QpResult`]. A method is one file and one line in [`registry`].

pub mod active_set;
pub mod dual;
pub mod executor;
pub mod kkt;
pub mod precond;
pub mod primal;
pub mod recession;
pub mod registry;
pub mod ssn;
#[cfg(test)]
mod tests_methods;

pub use crate::linalg::sparse::{self, Csr};

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
    /// NaN/Inf, stagnation or a failed factorization.
    Failed(String),
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
}

/// What every method returns.
#[derive(Debug, Clone)]
pub struct QpResult {
    pub x: Vec<f64>,
    pub lambda: Vec<f64>,
    pub active: Vec<bool>,
    pub status: Status,
    /// Outer iterations (faces, active-set changes, Uzawa steps, …).
    pub iterations: usize,
    /// Inner iterations (CG steps, inner solves).
    pub inner_iterations: usize,
    pub log: Vec<IterRecord>,
    /// Wall time per phase [s], e.g. ("factor", 0.1), ("iterate", 0.5).
    pub timings: Vec<(String, f64)>,
    pub kkt: Kkt,
    pub energy: f64,
    /// What the driver did beyond the method: a fallback, a refused claim
    /// (registry::solve). Printed as warnings and written to the JSON.
    pub notes: Vec<String>,
}

/// Options shared by all methods.
#[derive(Debug, Clone)]
pub struct SolveOptions {
    /// Relative tolerance of the method's own stopping test.
    pub tol: f64,
    pub max_iter: usize,
    pub preconditioner: precond::PrecondKind,
    /// SSOR ω.
    pub omega: f64,
    /// CGC: release all constraints with negative multipliers at once.
    pub multiple_release: bool,
    /// Penalty ε_p (None: automatic).
    pub penalty: Option<f64>,
    /// Uzawa ρ (None: estimated).
    pub rho: Option<f64>,
    /// Uzawa: Nesterov momentum with gradient restart; penalty: exact solve
    /// on the penalty active set between relaxation sweeps. `false`: the
    /// report's plain iterations (§4.4, §4.5).
    pub accelerate: bool,
    /// Print progress to stderr for long solves.
    pub progress: bool,
    /// Prefix of the progress line (e.g. the variant in `compare`).
    pub label: Option<String>,
    /// Stop with `Status::Failed("time limit …")` after this instant
    /// (`compare --time-limit`; a budget the user sets, never a decision
    /// of a method).
    pub deadline: Option<std::time::Instant>,
    /// Warm start (load steps, restart): used by methods that can, when feasible.
    pub x0: Option<Vec<f64>>,
    /// ssn: the linear-algebra path ("auto", "augmented", "refactor",
    /// "schur"); None = "auto" (the count-based cost model).
    pub ssn_path: Option<String>,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            tol: 1e-10,
            max_iter: 100_000,
            preconditioner: precond::PrecondKind::Cholesky,
            omega: 1.0,
            multiple_release: true,
            penalty: None,
            rho: None,
            accelerate: true,
            progress: false,
            label: None,
            deadline: None,
            x0: None,
            ssn_path: None,
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
}

/// The large number of §5 (overflow guard, step for zero curvature).
pub const MAXVAL: f64 = 1e30;
