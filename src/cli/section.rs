//! The `[solver]` entries as command-line flags: each value is parsed by
//! the `FromStr` of its type in `qp` (the one the problem file's `[solver]`
//! uses too), and the flags become a [`SolverSection`] laid over the
//! file's ([`SolverSection::overlay`]).

use crate::linalg::ordering::Ordering;
use crate::qp::precond::PrecondKind;
use crate::qp::settings::SsnPath;
use crate::qp::{ByteSize, MethodChoice, Release, SolverSection};
use clap::Args;

// clap prints these doc comments as `--help`: `[solver]` stays as written.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone, Default, PartialEq)]
pub struct SectionFlags {
    /// QP method: auto (default: ssn for every problem) or a name from
    /// `signorini methods`; overrides [solver] method.
    #[arg(long)]
    pub method: Option<MethodChoice>,
    /// none | jacobi | ssor | ic0 | mic0 | cholesky; overrides [solver] preconditioner.
    #[arg(long)]
    pub preconditioner: Option<PrecondKind>,
    /// Relative tolerance of the method's stopping test.
    #[arg(long)]
    pub tol: Option<f64>,
    /// Maximum number of (outer) iterations.
    #[arg(long)]
    pub max_iter: Option<usize>,
    /// SSOR / SOR relaxation parameter ω ∈ (0, 2) (cgc:ssor, penalty).
    #[arg(long)]
    pub omega: Option<f64>,
    /// Release strategy of cgc and dual: single | multiple.
    #[arg(long)]
    pub release: Option<Release>,
    /// Penalty parameter ε_p of the penalty method (default: one per contact
    /// row from the stiffness, docs/methods.md §4.4).
    #[arg(long)]
    pub penalty: Option<f64>,
    /// Uzawa step ρ (default: estimated from ‖H‖).
    #[arg(long)]
    pub rho: Option<f64>,
    /// Uzawa: Nesterov momentum; penalty: exact subspace correction between
    /// sweeps. `false` gives the report's plain iterations.
    #[arg(long)]
    pub accelerate: Option<bool>,
    /// ssn's linear algebra: auto (by counts) | augmented | refactor | schur | iterative (no factor of C's size, docs/methods.md §7.2).
    #[arg(long)]
    pub ssn_path: Option<SsnPath>,
    /// Fill-reducing ordering of every sparse Cholesky factor: amd (default)
    /// | nested-dissection (METIS: about a quarter less memory for the
    /// factor, a slower ordering; docs/methods.md §3).
    #[arg(long)]
    pub ordering: Option<Ordering>,
    /// Largest numeric Cholesky factor allowed, e.g. "8 GiB" (units B, KiB,
    /// MiB, GiB, TiB): a larger one is refused before it starts, as one
    /// beyond the machine's free memory is (docs/methods.md §3). For a
    /// machine shared with other jobs.
    #[arg(long)]
    pub memory_limit: Option<ByteSize>,
    /// Largest KKT residual accepted as a certificate (default 1e-6,
    /// docs/methods.md §8.4): the driver's rules and the run's verdict.
    #[arg(long)]
    pub kkt_target: Option<f64>,
}

impl From<&SectionFlags> for SolverSection {
    /// The flags as a `[solver]` section (the entries not given: None).
    fn from(f: &SectionFlags) -> SolverSection {
        SolverSection {
            method: f.method,
            preconditioner: f.preconditioner,
            tol: f.tol,
            max_iter: f.max_iter,
            omega: f.omega,
            release: f.release,
            penalty: f.penalty,
            rho: f.rho,
            accelerate: f.accelerate,
            ssn_path: f.ssn_path,
            ordering: f.ordering,
            memory_limit: f.memory_limit,
            kkt_target: f.kkt_target,
        }
    }
}
