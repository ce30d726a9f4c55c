//! A solve as a library call: read and assemble ([`prepare`]), solve every
//! load step with a warm start from the previous one ([`Run`]), continue a
//! run from its checkpoint ([`Restart`]), and hand each step to observers
//! ([`StepObserver`]): the HDF5 checkpoint, the VTU/PVD writer, the JSON
//! summary and the progress printer. The files of a run are staged and
//! moved into place by commits of one [`Transaction`] (one per load step,
//! the JSON last), so an interrupted run leaves complete files only.
//! The `signorini solve` command is this API plus flag parsing and printing.
//!
//! Contract: docs/problem-format.md §6 (outputs), §7 (the JSON
//! [`Summary`]), §8 (certificate and exit codes); warm starts:
//! docs/methods.md §8.3.

pub mod compare;
pub mod export;
pub mod limit;
mod observe;
mod output;
mod plot;
mod prepare;
mod restart;
pub mod solid;
mod steps;
mod summary;

pub use compare::{compare, CompareSpec};
pub use export::{export, ExportReport, ExportSpec};
pub use limit::{limit, Assembled, LimitPath, LimitReport, LimitSpec};
pub use observe::{Progress, StepObserver};
pub use output::{
    catch_signals, create_checkpoint, interrupted, output_paths, CheckpointWriter, Concurrent,
    Outputs, SummaryWriter, Transaction, VtuWriter,
};
pub use plot::{plot_file, plot_solid_file};
pub use prepare::{
    fingerprint, fingerprint_before_mortar, fingerprint_diff, fnv1a, load, options, prepare,
    prepare_with, probes, reduce, reduce_active, solve, solve_model, solve_model_in, step_model,
    step_model_reusing, Loaded, Prepared,
};
pub use restart::Restart;
pub use solid::{solve_solid, SolidOutcome, SolidPrepared, SolidSummary};
pub use steps::{preconditioner_label, Outcome, Run, Solved, Step, Verdict};
pub use summary::{Cells, KktSummary, Probe, StepRow, Summary, Timings};

use std::path::PathBuf;

/// Why a run stopped without a result: bad input in the wide sense of
/// docs/problem-format.md §8 (exit code 2), each message naming the file,
/// line or group at fault. A step that does not converge or certify is no
/// error: its outputs are written and flagged ([`Outcome::certified`]).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Model(#[from] crate::problem::ModelError),
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    #[error(transparent)]
    Fem(#[from] crate::fem::FemError),
    /// The problem or the solver settings, as given in `path`.
    #[error("{path}: {msg}")]
    Solver { path: PathBuf, msg: String },
    /// A checkpoint that cannot be continued.
    #[error("{0}")]
    Restart(String),
    /// An output that cannot be written (the message names the final file).
    #[error("{0}")]
    Output(String),
    /// A setting of the run itself (a step count, a KKT target).
    #[error("{0}")]
    Settings(String),
    /// SIGTERM or SIGINT (the number) arrived before the run was complete:
    /// its outputs were rolled back ([`interrupted`]).
    #[error("interrupted by {}: the run stopped and its outputs were rolled back (the output directory holds what it held before)", output::signal_name(*.0))]
    Interrupted(i32),
}

impl From<crate::io::IoError> for RunError {
    fn from(e: crate::io::IoError) -> Self {
        RunError::Output(e.to_string())
    }
}

impl RunError {
    /// The process exit code of this error (docs/problem-format.md §8).
    pub fn exit_code(&self) -> i32 {
        match self {
            // The shell's convention for a process ended by a signal.
            RunError::Interrupted(sig) => 128 + sig,
            _ => EXIT_BAD_INPUT,
        }
    }

    /// A solver's refusal in load step `s` (0-based) of `file`'s steps,
    /// named by the step when there are several (an unbounded load): plane,
    /// axisymmetric and solid runs alike.
    pub(crate) fn in_step(self, file: &crate::problem::ProblemFile, s: usize) -> RunError {
        match self {
            RunError::Solver { path, msg } if !file.steps.is_empty() => RunError::Solver {
                path,
                msg: format!(
                    "step {} of {} (t = {}): {msg}",
                    s + 1,
                    file.nsteps(),
                    file.step_time(s)
                ),
            },
            e => e,
        }
    }
}

/// Exit code: bad input, an unbounded problem, an unwritable output.
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit code: a step not converged or not certified (outputs written).
pub const EXIT_NOT_CONVERGED: i32 = 3;
/// Exit code: standard output could not be written (a closed pipe, a full
/// disk) by a command that would otherwise have exited 0: its report is
/// lost, the files it wrote are complete and committed.
pub const EXIT_STDOUT: i32 = 4;

/// Whether the recession direction `r` (Ar ≤ 0) opens a contact row: a
/// lift-off, not a slide. Measured per row against the row's own scale,
/// |a_i|·|r| (max norms), so that neither the mesh's units nor a stiff
/// row's weights decide it: a slide along the interface keeps (Ar)_i at
/// rounding, a lift of the body opens its rows by the motion itself.
pub(crate) fn opens_contact(qp: &crate::qp::QpProblem, r: &[f64]) -> bool {
    let rmax = crate::linalg::sparse::norm_inf(r);
    let ar = qp.a.mul(r);
    ar.iter().enumerate().any(|(i, v)| {
        let amax = qp.a.row(i).1.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        *v < -1e-6 * amax * rmax
    })
}

/// The error text of an unbounded problem (a certified recession direction
/// `r`, docs/methods.md §1.7): `who` moves as a rigid body, the loads doing
/// `work` on a motion of 1 m; with friction and a motion that keeps every
/// contact row closed, the slide friction cannot hold (`section`: the
/// methods section of the dimension's test). A motion that opens a row is
/// a body pulled away from its support, friction or not: friction holds
/// nothing on an open row.
pub(crate) fn unbounded_message(
    qp: &crate::qp::QpProblem,
    r: &[f64],
    who: &str,
    work: f64,
    section: &str,
) -> String {
    if qp.friction.is_some() && !opens_contact(qp, r) {
        format!(
            "the problem is unbounded: {who} slides as a rigid body, its friction cannot hold the loads (dᵀr = {work:.4e} J for a motion of 1 m exceeds what friction dissipates, methods.md {section})"
        )
    } else {
        format!(
            "the problem is unbounded: {who} can move as a rigid body without closing any contact, and the loads do positive work on it (dᵀr = {work:.4e} J for a motion of 1 m; a body pulled away from its support, methods.md §1.7)"
        )
    }
}
