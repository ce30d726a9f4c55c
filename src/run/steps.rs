//! The load-step driver (docs/problem-format.md §2 `[[steps]]`, §8): for
//! each step, the step's model (same mesh and DOFs, the step's loads and
//! prescribed displacements), a warm start from the previous step
//! (docs/methods.md §8.3), the solve, the post-processing, the verdict on
//! the KKT certificate; then the observers and, with a [`Transaction`], one
//! commit per load step. The summary of the last step ends the run.

use super::observe::StepObserver;
use super::output::{check_interrupt, Transaction};
use super::prepare::{
    reduce, reduce_active, reduce_rows, solve_model_in, step_model_reusing, Prepared,
};
use super::restart::Restart;
use super::summary::{Cells, StepRow, Summary, Timings};
use super::RunError;
use crate::fem::Model;
use crate::linalg::cholesky::Workspace;
use crate::output::{Change, StepOutput};
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
    ///
    /// A load step's files are written and committed on a second thread
    /// while the next step is assembled and solved (docs/performance.md,
    /// "Load steps"): the observers see the steps in order, one at a time,
    /// and step k's commit is complete before step k + 1's files are
    /// written; an error of a write is returned after the step being solved
    /// meanwhile, and the run stops there (its transaction rolls back to
    /// the last commit, as before). The last step is written with the
    /// summary, on the calling thread.
    pub fn solve(
        self,
        observers: &mut [&mut (dyn StepObserver + Send)],
        mut tx: Option<&mut Transaction>,
    ) -> Result<Outcome, RunError> {
        self.check()?;
        let steps = self.steps();
        if let Some(t) = tx.as_deref_mut() {
            self.plan(t, !steps.is_empty());
        }
        if steps.is_empty() {
            return self.nothing_to_do(observers, tx);
        }
        let mut carry = Carry::from_restart(self.restart.as_ref());
        // One workspace for every step: C is the same, its factor is reused.
        let ws = self.opts.settings.workspace();
        let multi = !self.prep.problem.file.steps.is_empty();
        std::thread::scope(|sc| {
            let mut writing: Option<std::thread::ScopedJoinHandle<'_, Written<'_, '_, '_>>> = None;
            let mut observers = Some(observers);
            for s in steps.clone() {
                let solving = self.one_step(s, &ws, &mut carry)?;
                // The last step's files are committed, and its fields
                // freed, before this step's are made (peak memory: one
                // step's fields at a time) and written.
                if let Some(h) = writing.take() {
                    let w = match h.join() {
                        Ok(w) => w,
                        Err(panic) => std::panic::resume_unwind(panic),
                    };
                    tx = w.tx;
                    observers = Some(w.observers);
                    w.result?;
                    release_freed_memory();
                }
                let done = self.finish_step(s, solving, &mut carry);
                let Some(obs) = observers.take() else {
                    unreachable!("the observers are back from the last writer");
                };
                let prep = self.prep;
                if multi && s + 1 < steps.end {
                    let mut t = tx.take();
                    writing = Some(sc.spawn(move || {
                        let result =
                            write_step(prep, &done, &mut *obs, t.as_deref_mut(), &mut vec![]);
                        // The step's fields are freed on this thread.
                        drop(done);
                        Written {
                            observers: obs,
                            tx: t,
                            result: result.map(|_| ()),
                        }
                    }));
                    continue;
                }
                // The last step (or a single solve): its files wait for
                // the summary, in the last commit.
                let write = write_step(
                    prep,
                    &done,
                    &mut *obs,
                    tx.as_deref_mut(),
                    &mut carry.pending,
                )?;
                carry.last = Some((
                    done.solved,
                    done.view.verdict,
                    Timings {
                        write,
                        ..done.timings
                    },
                ));
                observers = Some(obs);
            }
            let Some(obs) = observers.take() else {
                unreachable!("the last step is written on this thread");
            };
            self.finish(carry, obs, tx)
        })
    }

    /// Tells the transaction which files of the output name this run
    /// leaves, so that its first commit removes an older run's others: the
    /// restart's steps are kept in place when its checkpoint is the output
    /// directory's (else they are copied, [`super::CheckpointWriter`] and
    /// [`super::VtuWriter`]).
    fn plan(&self, t: &mut Transaction, summary: bool) {
        let multi = !self.prep.problem.file.steps.is_empty();
        let kept = match &self.restart {
            Some(r) if super::output::same_dir(&r.path, t.dir()) => r.steps_done,
            _ => 0,
        };
        t.plan(multi, kept, summary);
    }

    /// The settings and the step count, before anything is solved.
    fn check(&self) -> Result<(), RunError> {
        self.opts.settings.validate().map_err(RunError::Settings)?;
        if self.max_steps == Some(0) {
            return Err(RunError::Settings(
                "max_steps = 0: load steps count from 1".into(),
            ));
        }
        // A SIGTERM/SIGINT (output::catch_signals) ends the run at the next
        // of these checks with an error: the dropped transaction rolls back.
        check_interrupt()
    }

    /// A restart that left no step to solve: the observers' files of it
    /// (a checkpoint copied into place) are the one commit.
    fn nothing_to_do(
        &self,
        observers: &mut [&mut (dyn StepObserver + Send)],
        tx: Option<&mut Transaction>,
    ) -> Result<Outcome, RunError> {
        let mut names = vec![];
        if let Some(r) = &self.restart {
            for ob in observers.iter_mut() {
                names.extend(ob.on_nothing_to_do(r).map_err(|e| unstage(&tx, e))?);
            }
        }
        if let Some(t) = tx {
            check_interrupt()?;
            if !names.is_empty() {
                t.commit(&names)?;
            }
        }
        check_interrupt()?;
        Ok(Outcome {
            steps: self.steps(),
            nsteps: self.prep.problem.file.nsteps(),
            last: None,
            summary: None,
            certified: true,
        })
    }

    /// Load step `s`: its model and the solve warm-started from the
    /// previous step ([`Run::finish_step`] post-processes it; the caller
    /// writes the files).
    fn one_step(&self, s: usize, ws: &Workspace, carry: &mut Carry) -> Result<Solving, RunError> {
        check_interrupt()?;
        let (prep, method) = (self.prep, self.method);
        let file = &prep.problem.file;
        let multi = !file.steps.is_empty();
        // The last step's model, unless its files are being written (then
        // the prepared model's copy: C and the topology are shared, not copied).
        let prev = carry.last.take().and_then(|(solved, _, _)| solved.model);
        let ts = Instant::now();
        // Without [[steps]] the prepared model is the problem; with steps
        // every step (the first included) gets its own loads.
        let mut model = if multi {
            Some(step_model_reusing(prep, s, prev)?)
        } else {
            None
        };
        // Friction: the slip of this step is measured from the last
        // step's displacements (docs/methods.md §9.5).
        if let (Some(m), Some(u)) = (model.as_mut(), carry.u_prev.as_deref()) {
            crate::fem::Discrete::start_step(m, Some(u));
        }
        let model_ref = model.as_ref().unwrap_or(&prep.model);
        let t_assemble = match model {
            None => prep.t_assemble,
            Some(_) => ts.elapsed().as_secs_f64(),
        };
        let mut o = self.opts.clone();
        o.x0 = carry.u_prev.as_ref().map(|u| reduce(model_ref, u));
        o.active0 = carry
            .active_prev
            .as_deref()
            .and_then(|a| reduce_active(model_ref, a));
        o.lambda0 = carry
            .lambda_prev
            .as_ref()
            .filter(|_| model_ref.qp.friction.is_some())
            .and_then(|(n, t)| {
                Some(crate::qp::Multipliers {
                    normal: reduce_rows(model_ref, n)?,
                    tangential: reduce_rows(model_ref, t)?,
                })
            });
        o.stop = Some(&super::output::SIGNAL);
        let t_solve0 = Instant::now();
        let res = solve_model_in(prep, model_ref, method, &o, ws);
        // An interrupted solve is no result to write, nor an error of
        // the problem.
        check_interrupt()?;
        // A refused step of several (an unbounded load) names the step.
        let res = res.map_err(|e| e.in_step(file, s))?;
        let t_solve = t_solve0.elapsed().as_secs_f64();
        log::debug!(
            "step {}: assembly {t_assemble:.3} s, solve {t_solve:.3} s",
            s + 1
        );
        Ok(Solving {
            model,
            res,
            t_assemble,
            t_solve,
            started: ts,
        })
    }

    /// Step `s` after its solve: the post-processing, the verdict and the
    /// step's row.
    fn finish_step(&self, s: usize, solving: Solving, carry: &mut Carry) -> Done {
        let (prep, method) = (self.prep, self.method);
        let file = &prep.problem.file;
        let multi = !file.steps.is_empty();
        let Solving {
            model,
            res,
            t_assemble,
            t_solve,
            started: ts,
        } = solving;
        let model_ref = model.as_ref().unwrap_or(&prep.model);
        let t_p = Instant::now();
        let (output, forces) =
            self.post_process(s, model_ref, &res, carry, [t_assemble, t_solve], ts);
        let verdict = Verdict::of(method, &res, self.opts.settings.kkt_target, self.strict);
        let solved = Solved {
            model,
            result: res,
            output,
            forces,
        };
        let view = View {
            index: s,
            end: self.steps().end,
            nsteps: file.nsteps(),
            multi,
            time: file.step_time(s),
            method,
            kkt_target: self.opts.settings.kkt_target,
            verdict,
            started: ts,
        };
        let step = view.step(solved.model(prep), &solved);
        carry
            .rows
            .push(step_row(&step, carry.active_prev.as_deref(), t_solve));
        carry.active_prev = Some(solved.output.active.clone());
        carry.lambda_prev =
            crate::post::friction::friction_output(solved.model(prep), &solved.result)
                .map(|f| (solved.output.multipliers.clone(), f.lambda_t));
        carry.certified &= verdict.certified();
        carry.u_prev = Some(solved.output.displacement.clone());
        let timings = Timings {
            read: prep.t_read,
            assemble: t_assemble,
            solve: t_solve,
            write: t_p.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Done {
            solved,
            timings,
            view,
        }
    }

    /// The step's fields, forces and change from the reference step, with
    /// the step's assembly and solve times.
    fn post_process(
        &self,
        s: usize,
        model: &Model,
        res: &QpResult,
        carry: &mut Carry,
        [t_assemble, t_solve]: [f64; 2],
        ts: Instant,
    ) -> (StepOutput, Forces) {
        let file = &self.prep.problem.file;
        let t_p = Instant::now();
        // A step changes loads and prescribed values, not the materials.
        let (mut output, forces) =
            post::step_output_with_forces(model, &file.materials, res, file.step_time(s));
        log::debug!(
            "step {}: post-processing {:.3} s",
            s + 1,
            t_p.elapsed().as_secs_f64()
        );
        output.info.method = self.method.name().to_string();
        output.info.preconditioner = preconditioner_label(self.method, self.opts);
        output.info.time_assemble = t_assemble;
        output.info.time_solve = t_solve;
        output.info.time_total = ts.elapsed().as_secs_f64();
        // The state the `*_change` fields refer to (docs/problem-format.md §6).
        let kref = file.output.reference_step;
        if kref == Some(s + 1) {
            carry.reference = Some(output.clone());
        }
        if let (Some(k), Some(r)) = (kref, &carry.reference) {
            if s + 1 >= k {
                output.change = Some(Change::between(&output, r, k));
            }
        }
        (output, forces)
    }

    /// The summary of the last step, the observers' last files and the
    /// last commit.
    fn finish(
        &self,
        carry: Carry,
        observers: &mut [&mut (dyn StepObserver + Send)],
        tx: Option<&mut Transaction>,
    ) -> Result<Outcome, RunError> {
        let prep = self.prep;
        let Some((last, verdict, timings)) = carry.last else {
            return Err(RunError::Settings("no load step was solved".into()));
        };
        // The iterative ssn path orders nothing (docs/methods.md §7.2).
        let ordering = match self.opts.settings.factor_free(self.method) {
            Some(why) => format!("none ({why})"),
            None => self.opts.settings.ordering.name().to_string(),
        };
        let multi = !prep.problem.file.steps.is_empty();
        let mut summary = Summary::new(
            prep,
            last.model(prep),
            self.method,
            &ordering,
            &last.result,
            &last.output,
            &last.forces,
            self.opts.settings.kkt_target,
            verdict.certified(),
            Timings {
                total: self.started.elapsed().as_secs_f64(),
                ..timings
            },
            None,
        );
        summary.judge_steps(&carry.rows);
        summary.steps = multi.then_some(carry.rows);
        let mut last_commit = vec![];
        for ob in observers.iter_mut() {
            last_commit.extend(ob.on_finish(&summary).map_err(|e| unstage(&tx, e))?);
        }
        // The last commit: the JSON summary first, then the last step's
        // files (for a single solve, every file), the checkpoint among them.
        // A run killed inside it leaves either a checkpoint without its last
        // step (a restart solves that step again and writes the summary) or
        // both; never a finished checkpoint without its summary.
        last_commit.extend(carry.pending);
        check_interrupt()?;
        if let Some(t) = tx {
            t.commit(&last_commit)?;
        }
        // A signal during the last commit still rolls the run back.
        check_interrupt()?;
        Ok(Outcome {
            steps: self.steps(),
            nsteps: prep.problem.file.nsteps(),
            last: Some(last),
            summary: Some(summary),
            certified: carry.certified,
        })
    }
}

/// What the observers see of a step besides its [`Solved`] (the scalars
/// of a [`Step`]).
#[derive(Clone, Copy)]
struct View {
    index: usize,
    /// One past the last step this run solves.
    end: usize,
    nsteps: usize,
    multi: bool,
    time: f64,
    method: MethodId,
    kkt_target: f64,
    verdict: Verdict,
    started: Instant,
}

impl View {
    fn step<'a>(&self, model: &'a Model, solved: &'a Solved) -> Step<'a> {
        Step {
            index: self.index,
            nsteps: self.nsteps,
            multi: self.multi,
            time: self.time,
            method: self.method,
            kkt_target: self.kkt_target,
            model,
            result: &solved.result,
            output: &solved.output,
            forces: &solved.forces,
            verdict: self.verdict,
            started: self.started,
        }
    }
}

/// A solved step before its post-processing.
struct Solving {
    model: Option<Model>,
    res: QpResult,
    t_assemble: f64,
    t_solve: f64,
    started: Instant,
}

/// A solved, post-processed step whose files are not yet written.
struct Done {
    solved: Solved,
    timings: Timings,
    view: View,
}

/// What a step's writer hands back: the observers and the transaction it
/// borrowed, and its outcome (the step's fields are freed when written).
struct Written<'a, 'b, 't> {
    observers: &'a mut [&'b mut (dyn StepObserver + Send)],
    tx: Option<&'t mut Transaction>,
    result: Result<(), RunError>,
}

/// Hands a step to the observers and, with `tx`, commits its files unless
/// it is the last of the run (whose files wait in `pending` for the
/// summary, [`Run::finish`]). Returns the step's write time (its
/// post-processing included). Runs on the writer thread of [`Run::solve`]
/// for every step but the last.
fn write_step(
    prep: &Prepared,
    done: &Done,
    observers: &mut [&mut (dyn StepObserver + Send)],
    tx: Option<&mut Transaction>,
    pending: &mut Vec<String>,
) -> Result<f64, RunError> {
    let t_w = Instant::now();
    let step = done.view.step(done.solved.model(prep), &done.solved);
    let commit = done.view.index + 1 < done.view.end;
    observe(&step, observers, tx, commit, pending)?;
    let write = done.timings.write + t_w.elapsed().as_secs_f64();
    log::debug!("step {}: writing {write:.3} s", done.view.index + 1);
    Ok(write)
}

/// Gives the pages of freed blocks back to the system (glibc `malloc_trim`):
/// a step's fields, freed by its writer thread, sit in that thread's malloc
/// arena otherwise, and each step's would add to the run's peak RSS.
fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free memory of the allocator to the
    // system; it reads and writes no memory of ours.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Hands the step to the observers; with `tx`, a load step that is not the
/// last (`commit`) is one commit: its VTU pair, the time series and the
/// checkpoint grown by this step. The last step's files wait for the
/// summary ([`Run::finish`]), as do all of a single solve's (`pending`).
fn observe(
    step: &Step<'_>,
    observers: &mut [&mut (dyn StepObserver + Send)],
    tx: Option<&mut Transaction>,
    commit: bool,
    pending: &mut Vec<String>,
) -> Result<(), RunError> {
    let mut names = vec![];
    for ob in observers.iter_mut() {
        let t = Instant::now();
        names.extend(ob.on_step(step).map_err(|e| unstage(&tx, e))?);
        log::debug!(
            "step {}: output {:?} {:.3} s",
            step.index + 1,
            names.last(),
            t.elapsed().as_secs_f64()
        );
    }
    check_interrupt()?;
    match tx {
        Some(t) if step.multi && commit => t.commit(&names)?,
        _ => pending.extend(names),
    }
    Ok(())
}

/// What one step hands the next, and the run's end: the warm start, the
/// active set (for the flips), the reference state, the files waiting for
/// the last commit, the step table, the verdict so far, the last step.
struct Carry {
    u_prev: Option<Vec<[f64; 2]>>,
    active_prev: Option<Vec<u8>>,
    /// λ_n and λ_t of the last step per contact row (frictional steps).
    lambda_prev: Option<(Vec<f64>, Vec<f64>)>,
    reference: Option<StepOutput>,
    pending: Vec<String>,
    rows: Vec<StepRow>,
    certified: bool,
    last: Option<(Solved, Verdict, Timings)>,
}

impl Carry {
    fn from_restart(r: Option<&Restart>) -> Carry {
        Carry {
            u_prev: r.and_then(|r| r.displacement.clone()),
            active_prev: r.and_then(|r| r.active.clone()),
            lambda_prev: r.and_then(|r| r.lambda.clone()),
            reference: r.and_then(|r| r.reference.clone()),
            pending: vec![],
            rows: vec![],
            certified: true,
            last: None,
        }
    }
}

/// The step's row of the summary's step table; `active_prev` is the
/// previous step's active set (the rows that opened and closed).
fn step_row(step: &Step<'_>, active_prev: Option<&[u8]>, t_solve: f64) -> StepRow {
    let (res, model, output) = (step.result, step.model, step.output);
    let flips = |from: u8| {
        active_prev.map(|p| {
            p.iter()
                .zip(&output.active)
                .filter(|(a, b)| **a == from && **b != from)
                .count()
        })
    };
    StepRow {
        step: step.index + 1,
        t: step.time,
        converged: res.status.converged(),
        certified: step.verdict.certified(),
        iterations: res.iterations,
        inner_iterations: res.inner_iterations,
        kkt_max: res.kkt.max(),
        energy: res.energy,
        nodes: model.topo.points.len(),
        cells: Cells::Triangles(model.topo.triangles.len()),
        dofs: model.qp.n(),
        constraints: model.qp.m(),
        active: res.active.iter().filter(|a| **a).count(),
        opened: flips(1),
        closed: flips(0),
        time_solve: t_solve,
        time_step: step.started.elapsed().as_secs_f64(),
    }
}

/// An observer's or commit's error naming the final files, not the staged ones.
fn unstage(tx: &Option<&mut Transaction>, e: RunError) -> RunError {
    match tx {
        Some(t) => RunError::Output(t.unstage(&e.to_string())),
        None => e,
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
