//! The load-step driver (docs/problem-format.md §2 `[[steps]]`, §8): for
//! each step, the step's model (same mesh and DOFs, the step's loads and
//! prescribed displacements), a warm start from the previous step
//! (docs/methods.md §8.3), the solve, the post-processing, the verdict on
//! the KKT certificate; then the observers and, with a [`Transaction`], one
//! commit per load step. The summary of the last step ends the run.

use super::observe::StepObserver;
use super::output::{check_interrupt, Transaction};
use super::prepare::{reduce, solve_model_in, step_model, Prepared};
use super::restart::Restart;
use super::summary::{StepRow, Summary, Timings};
use super::RunError;
use crate::fem::Model;
use crate::io::{Change, StepOutput};
use crate::post::{self, forces::Forces};
use crate::qp::{registry, MethodId, QpResult, SolveOptions};
use std::ops::Range;
use std::time::Instant;

/// The run's verdict on one step (docs/methods.md §8.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Converged, KKT residual within the target.
    Certified,
    /// Certified against its own penalised problem only (penalty without
    /// `strict`): the contact conditions hold to O(ε_p).
    Penalised,
    /// The method did not converge.
    NotConverged,
    /// Converged, KKT residual above the target.
    NotCertified,
}

impl Verdict {
    pub fn of(method: MethodId, res: &QpResult, kkt_target: f64, strict: bool) -> Verdict {
        if !res.status.converged() {
            Verdict::NotConverged
        } else if !registry::certified(method, &res.kkt, kkt_target, strict) {
            Verdict::NotCertified
        } else if !res.kkt.within(kkt_target) {
            Verdict::Penalised
        } else {
            Verdict::Certified
        }
    }

    /// The step's `kkt.certified` in the summary.
    pub fn certified(self) -> bool {
        matches!(self, Verdict::Certified | Verdict::Penalised)
    }
}

/// One solved step, as the observers see it.
pub struct Step<'a> {
    /// 0-based step number (`index + 1` in file names and messages).
    pub index: usize,
    pub nsteps: usize,
    /// The problem has `[[steps]]` (outputs per step, a time series).
    pub multi: bool,
    /// Pseudo-time of the step.
    pub time: f64,
    pub method: MethodId,
    pub kkt_target: f64,
    pub model: &'a Model,
    pub result: &'a QpResult,
    pub output: &'a StepOutput,
    pub forces: &'a Forces,
    pub verdict: Verdict,
    /// When the step began (assembly).
    pub started: Instant,
}

/// The last step solved.
pub struct Solved {
    /// The step's model (None: the prepared model, a problem without steps).
    pub model: Option<Model>,
    pub result: QpResult,
    pub output: StepOutput,
    pub forces: Forces,
}

impl Solved {
    /// The model the step was solved on.
    pub fn model<'a>(&'a self, prep: &'a Prepared) -> &'a Model {
        self.model.as_ref().unwrap_or(&prep.model)
    }
}

/// What a run did.
pub struct Outcome {
    /// The steps solved (0-based; empty when a restart left nothing to do).
    pub steps: Range<usize>,
    /// Steps of the problem.
    pub nsteps: usize,
    /// The last step (None when nothing was solved).
    pub last: Option<Solved>,
    pub summary: Option<Summary>,
    /// Every step solved converged and is certified (else exit code 3).
    pub certified: bool,
}

/// A solve of the load steps of a prepared problem by one method.
pub struct Run<'a> {
    prep: &'a Prepared,
    method: MethodId,
    opts: &'a SolveOptions,
    strict: bool,
    max_steps: Option<usize>,
    restart: Option<Restart>,
    started: Instant,
}

impl<'a> Run<'a> {
    /// Every load step of `prep` by `method` (see [`super::options`]),
    /// certified against the settings' KKT target (`opts.settings.kkt_target`).
    pub fn new(prep: &'a Prepared, method: MethodId, opts: &'a SolveOptions) -> Self {
        Run {
            prep,
            method,
            opts,
            strict: false,
            max_steps: None,
            restart: None,
            started: Instant::now(),
        }
    }

    /// `strict` certifies a penalised method against the unpenalised
    /// problem ([`crate::qp::method::Certificate::Penalised`]).
    pub fn strict(mut self, strict: bool) -> Self {
        self.strict = strict;
        self
    }

    /// Stop after load step `n` (1-based); a restart continues later.
    pub fn max_steps(mut self, n: Option<usize>) -> Self {
        self.max_steps = n;
        self
    }

    /// Continue after the last step of a checkpoint.
    pub fn restart(mut self, r: Option<Restart>) -> Self {
        self.restart = r;
        self
    }

    /// The start of the run's total time (default: [`Run::new`]).
    pub fn started(mut self, t0: Instant) -> Self {
        self.started = t0;
        self
    }

    /// The steps this run solves (0-based).
    pub fn steps(&self) -> Range<usize> {
        let nsteps = self.prep.problem.file.nsteps();
        let last = self.max_steps.unwrap_or(nsteps).min(nsteps);
        let first = self.restart.as_ref().map_or(0, |r| r.steps_done);
        first..last.max(first)
    }

    /// Solves the steps, each handed to `observers` in order; with `tx`,
    /// the files they stage are committed per load step (without steps,
    /// all at the end with the summary's).
    pub fn solve(
        self,
        observers: &mut [&mut dyn StepObserver],
        mut tx: Option<&mut Transaction>,
    ) -> Result<Outcome, RunError> {
        self.opts.settings.validate().map_err(RunError::Settings)?;
        let kkt_target = self.opts.settings.kkt_target;
        if self.max_steps == Some(0) {
            return Err(RunError::Settings(
                "max_steps = 0: load steps count from 1".into(),
            ));
        }
        // A SIGTERM/SIGINT (output::catch_signals) ends the run at the next
        // of these checks with an error: the dropped transaction rolls back.
        check_interrupt()?;
        let (prep, method) = (self.prep, self.method);
        let file = &prep.problem.file;
        let multi = !file.steps.is_empty();
        let nsteps = file.nsteps();
        let steps = self.steps();
        // Errors of the observers and commits name the final files.
        let unstage = |tx: &Option<&mut Transaction>, e: RunError| match tx {
            Some(t) => RunError::Output(t.unstage(&e.to_string())),
            None => e,
        };
        if steps.is_empty() {
            let mut names = vec![];
            if let Some(r) = &self.restart {
                for ob in observers.iter_mut() {
                    names.extend(ob.on_nothing_to_do(r).map_err(|e| unstage(&tx, e))?);
                }
            }
            if let Some(t) = tx.as_deref_mut() {
                check_interrupt()?;
                if !names.is_empty() {
                    t.commit(&names)?;
                }
            }
            check_interrupt()?;
            return Ok(Outcome {
                steps,
                nsteps,
                last: None,
                summary: None,
                certified: true,
            });
        }
        let mut u_prev = self.restart.as_ref().and_then(|r| r.displacement.clone());
        let mut active_prev = self.restart.as_ref().and_then(|r| r.active.clone());
        // The state the `*_change` fields refer to (docs/problem-format.md §6).
        let kref = file.output.reference_step;
        let mut reference = self.restart.as_ref().and_then(|r| r.reference.clone());
        let mut pending: Vec<String> = vec![];
        let mut rows = vec![];
        let mut certified = true;
        let mut last = None;
        // One workspace for every step: C is the same, its factor is reused.
        let ws = self.opts.settings.workspace();
        for s in steps.clone() {
            check_interrupt()?;
            let ts = Instant::now();
            // Without [[steps]] the prepared model is the problem; with steps
            // every step (the first included) gets its own loads.
            let mut model = if multi {
                Some(step_model(prep, s)?)
            } else {
                None
            };
            // Friction: the slip of this step is measured from the last
            // step's displacements (docs/methods.md §9.5).
            if let (Some(m), Some(u)) = (model.as_mut(), u_prev.as_deref()) {
                crate::fem::friction::start_step(m, Some(u));
            }
            let model_ref = model.as_ref().unwrap_or(&prep.model);
            let t_assemble = match model {
                None => prep.t_assemble,
                Some(_) => ts.elapsed().as_secs_f64(),
            };
            let mut o = self.opts.clone();
            o.x0 = u_prev.as_ref().map(|u| reduce(model_ref, u));
            o.stop = Some(&super::output::SIGNAL);
            let t_solve0 = Instant::now();
            let res = solve_model_in(prep, model_ref, method, &o, &ws);
            // An interrupted solve is no result to write, nor an error of
            // the problem.
            check_interrupt()?;
            let res = res?;
            let t_solve = t_solve0.elapsed().as_secs_f64();
            let t_w = Instant::now();
            let mut problem_s = prep.problem.clone();
            problem_s.file = file.at_step(s);
            let (mut output, forces) =
                post::step_output_with_forces(model_ref, &problem_s, &res, file.step_time(s));
            log::debug!(
                "step {}: post-processing {:.3} s",
                s + 1,
                t_w.elapsed().as_secs_f64()
            );
            output.info.method = method.name().to_string();
            output.info.preconditioner = preconditioner_label(method, self.opts);
            output.info.time_assemble = t_assemble;
            output.info.time_solve = t_solve;
            output.info.time_total = ts.elapsed().as_secs_f64();
            if kref == Some(s + 1) {
                reference = Some(output.clone());
            }
            if let (Some(k), Some(r)) = (kref, &reference) {
                if s + 1 >= k {
                    output.change = Some(Change::between(&output, r, k));
                }
            }
            let verdict = Verdict::of(method, &res, kkt_target, self.strict);
            let step = Step {
                index: s,
                nsteps,
                multi,
                time: file.step_time(s),
                method,
                kkt_target,
                model: model_ref,
                result: &res,
                output: &output,
                forces: &forces,
                verdict,
                started: ts,
            };
            let mut names = vec![];
            for ob in observers.iter_mut() {
                let t = Instant::now();
                names.extend(ob.on_step(&step).map_err(|e| unstage(&tx, e))?);
                log::debug!(
                    "step {}: output {:?} {:.3} s",
                    s + 1,
                    names.last(),
                    t.elapsed().as_secs_f64()
                );
            }
            // A load step is one commit: its VTU pair, the time series and
            // the checkpoint grown by this step. The last step's files wait
            // for the summary (below).
            check_interrupt()?;
            match tx.as_deref_mut() {
                Some(t) if multi && s + 1 < steps.end => t.commit(&names)?,
                _ => pending.extend(names),
            }
            let t_write = t_w.elapsed().as_secs_f64();
            let flips = |from: u8| {
                active_prev.as_ref().map(|p: &Vec<u8>| {
                    p.iter()
                        .zip(&output.active)
                        .filter(|(a, b)| **a == from && **b != from)
                        .count()
                })
            };
            rows.push(StepRow {
                step: s + 1,
                t: file.step_time(s),
                converged: res.status.converged(),
                iterations: res.iterations,
                inner_iterations: res.inner_iterations,
                kkt_max: res.kkt.max(),
                energy: res.energy,
                nodes: model_ref.topo.points.len(),
                triangles: model_ref.topo.triangles.len(),
                dofs: model_ref.qp.n(),
                constraints: model_ref.qp.m(),
                active: res.active.iter().filter(|a| **a).count(),
                opened: flips(1),
                closed: flips(0),
                time_solve: t_solve,
                time_step: ts.elapsed().as_secs_f64(),
            });
            active_prev = Some(output.active.clone());
            certified &= matches!(verdict, Verdict::Certified | Verdict::Penalised);
            u_prev = Some(output.displacement.clone());
            let timings = Timings {
                read: prep.t_read,
                assemble: t_assemble,
                solve: t_solve,
                write: t_write,
                ..Default::default()
            };
            last = Some((
                Solved {
                    model,
                    result: res,
                    output,
                    forces,
                },
                verdict,
                timings,
            ));
        }
        let Some((last, verdict, timings)) = last else {
            return Err(RunError::Settings("no load step was solved".into()));
        };
        // The iterative ssn path orders nothing (docs/methods.md §7.2).
        let ordering = match self.opts.settings.factor_free(method) {
            Some(why) => format!("none ({why})"),
            None => self.opts.settings.ordering.name().to_string(),
        };
        let summary = Summary::new(
            prep,
            last.model(prep),
            method,
            &ordering,
            &last.result,
            &last.output,
            &last.forces,
            kkt_target,
            verdict.certified(),
            Timings {
                total: self.started.elapsed().as_secs_f64(),
                ..timings
            },
            multi.then_some(rows),
        );
        let mut last_commit = vec![];
        for ob in observers.iter_mut() {
            last_commit.extend(ob.on_finish(&summary).map_err(|e| unstage(&tx, e))?);
        }
        // The last commit: the JSON summary first, then the last step's
        // files (for a single solve, every file), the checkpoint among them.
        // A run killed inside it leaves either a checkpoint without its last
        // step (a restart solves that step again and writes the summary) or
        // both; never a finished checkpoint without its summary.
        last_commit.extend(pending);
        check_interrupt()?;
        if let Some(t) = tx {
            t.commit(&last_commit)?;
        }
        // A signal during the last commit still rolls the run back.
        check_interrupt()?;
        Ok(Outcome {
            steps,
            nsteps,
            last: Some(last),
            summary: Some(summary),
            certified,
        })
    }
}

/// The preconditioner column of a method: its name, or `-` for a method
/// that takes none.
pub fn preconditioner_label(method: MethodId, opts: &SolveOptions) -> String {
    if method.capabilities().preconditioned {
        opts.settings.cgc.preconditioner.name().to_string()
    } else {
        "-".to_string()
    }
}
