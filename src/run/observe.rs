//! What a [`Run`](super::Run) tells the outside: each solved step, then the
//! summary. Observers write the outputs (checkpoint, VTU/PVD, JSON) into
//! the run's staging directory and name the files they wrote; the run
//! commits them ([`Transaction`](super::Transaction)). The progress printer
//! is an observer that writes nothing.

use super::restart::Restart;
use super::steps::{Step, Verdict};
use super::summary::Summary;
use super::RunError;

/// Receives the steps of a run in order, then its summary. Each method
/// returns the names of the files it staged (committed by the run).
pub trait StepObserver {
    /// Step `step.index` is solved and post-processed.
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError>;
    /// Every step is done; `summary` is the run's result.
    fn on_finish(&mut self, _summary: &Summary) -> Result<Vec<String>, RunError> {
        Ok(vec![])
    }
    /// Nothing was left to solve after `restart` (it holds the steps asked for).
    fn on_nothing_to_do(&mut self, _restart: &Restart) -> Result<Vec<String>, RunError> {
        Ok(vec![])
    }
}

/// The step lines on stdout (with load steps, unless `quiet`) and the
/// warning of a step that is not converged or not certified on stderr
/// (unless `warnings` is false: `-qq`, `--log-level error`).
pub struct Progress {
    /// No step lines on stdout.
    pub quiet: bool,
    /// The warning of a step not converged or not certified on stderr.
    pub warnings: bool,
}

impl StepObserver for Progress {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        let res = step.result;
        if step.multi && !self.quiet {
            crate::outln!(
                "step {:>4}/{}  t = {:<10} {} in {} iterations, KKT {:.2e}, {} active, {:.3} s",
                step.index + 1,
                step.nsteps,
                step.time,
                if res.status.converged() {
                    "converged"
                } else {
                    "NOT CONVERGED"
                },
                res.iterations,
                res.kkt.max(),
                res.active.iter().filter(|a| **a).count(),
                step.started.elapsed().as_secs_f64()
            );
        }
        let s = step.index + 1;
        let method = step.method;
        if !self.warnings {
            return Ok(vec![]);
        }
        match step.verdict {
            Verdict::Certified => {}
            Verdict::NotConverged => crate::errln!(
                "warning: step {s}: {method} did not converge: {} (outputs written and flagged converged = false)",
                res.status.describe()
            ),
            Verdict::NotCertified => crate::errln!(
                "warning: step {s}: not certified: KKT residual {:.2e} above the target {:.0e} (outputs written and flagged certified = false; docs/methods.md §8)",
                res.kkt.max(),
                step.kkt_target
            ),
            Verdict::Penalised => crate::errln!(
                "warning: step {s}: {method} violates the contact conditions by O(ε_p) (KKT of the unpenalised problem {:.2e}; --strict certifies against it)",
                res.kkt.max()
            ),
        }
        Ok(vec![])
    }
}
