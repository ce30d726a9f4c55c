//! Restart (docs/problem-format.md §6): a checkpoint `NAME.h5` is read and
//! checked before its steps are trusted (the same problem by fingerprint,
//! the same mesh sizes, step groups `0001`…`000k` by name and time, finite
//! and plausible displacements, change fields that agree with `[output]
//! reference_step` and a finite reference step); the run then continues
//! after its last step, warm-started from it (docs/methods.md §8.3).

use super::prepare::{
    fingerprint, fingerprint_before_mortar, fingerprint_diff, has_default_discretization, Prepared,
};
use super::RunError;
use crate::io::hdf5::{read_checkpoint, step_name};
use crate::output::Checkpoint;
use crate::output::StepOutput;
use std::path::{Path, PathBuf};

/// A checkpoint to continue from.
#[derive(Debug, Clone)]
pub struct Restart {
    /// The checkpoint file: its steps are kept (in place, or copied once
    /// from another folder) and the next steps are added beside them
    /// (docs/problem-format.md §6, the split layout).
    pub path: PathBuf,
    /// Load steps it holds (the run continues with the next one).
    pub steps_done: usize,
    /// Displacements of its last step (per output point): the warm start.
    pub displacement: Option<Vec<[f64; 2]>>,
    /// Active flags of its last step (per contact row): the state the next
    /// step's opened/closed counts refer to.
    pub active: Option<Vec<u8>>,
    /// λ_n and λ_t of its last step (per contact row), if frictional: the
    /// next step's multiplier warm start (`SolveOptions::lambda0`).
    pub lambda: Option<(Vec<f64>, Vec<f64>)>,
    /// The step `[output] reference_step` names, if the checkpoint holds it.
    pub reference: Option<StepOutput>,
}

impl Restart {
    /// Reads the checkpoint at `path` and checks that it belongs to `prep`.
    pub fn read(path: &Path, prep: &Prepared) -> Result<Restart, RunError> {
        let ck = read_checkpoint(path).map_err(|e| RunError::Restart(format!("--restart: {e}")))?;
        check(path, &ck, &fingerprint(prep, prep.no_contact), prep).map_err(RunError::Restart)?;
        let reference = prep
            .problem
            .file
            .output
            .reference_step
            .and_then(|k| ck.steps.get(k.wrapping_sub(1)))
            .map(|s| StepOutput {
                change: None,
                ..s.clone()
            });
        Ok(Restart {
            path: path.to_path_buf(),
            steps_done: ck.steps.len(),
            displacement: ck.steps.last().map(|s| s.displacement.clone()),
            active: ck.steps.last().map(|s| s.active.clone()),
            lambda: ck
                .steps
                .last()
                .zip(ck.friction.last().and_then(|f| f.as_ref()))
                .map(|(s, f)| (s.multipliers.clone(), f.multipliers_t.clone())),
            reference,
        })
    }
}

/// The checks of [`Restart::read`]; the message names the checkpoint.
fn check(rp: &Path, ck: &Checkpoint, fingerprint: &str, prep: &Prepared) -> Result<(), String> {
    let shown = rp.display();
    let problem = prep.problem.path.display();
    let Some((_, theirs)) = ck.attrs.iter().find(|(k, _)| k == "fingerprint") else {
        return Err(format!(
            "{shown}: the checkpoint has no problem fingerprint (written by another program or an older signorini), so it cannot be matched to {problem}; solve from the start"
        ));
    };
    let mut diff = fingerprint_diff(theirs, fingerprint);
    // A checkpoint written when a pair without `discretization` had
    // node-to-segment rows, of a pair that runs them now.
    if fingerprint_before_mortar(prep, prep.no_contact).is_some_and(|b| b == *theirs) {
        diff.clear();
    }
    if !diff.is_empty() {
        // A checkpoint of node-to-segment rows written when they were the
        // default of a non-matching pair: say how to continue it.
        let hint = if diff.iter().any(|d| d == "contact") && has_default_discretization(prep) {
            "; a non-matching pair without discretization now has mortar rows: if the checkpoint was written with node-to-segment rows (the default before), add discretization = \"nts\" to the pair"
        } else {
            ""
        };
        return Err(format!(
            "{shown}: the checkpoint does not match {problem}: it was written for a different {} (restart needs the same mesh and the same loads, materials, contacts and steps){hint}",
            diff.join(", ")
        ));
    }
    // The output mesh has the model's points and triangles (post::out_mesh).
    let topo = &prep.model.topo;
    if ck.mesh.points.len() != topo.points.len() || ck.mesh.triangles.len() != topo.triangles.len()
    {
        return Err(format!(
            "{shown}: checkpoint mesh ({} points, {} triangles) does not match {problem} ({} points, {} triangles)",
            ck.mesh.points.len(),
            ck.mesh.triangles.len(),
            topo.points.len(),
            topo.triangles.len()
        ));
    }
    check_groups(rp, ck, prep)?;
    // A warm start beyond 10³ mesh diagonals is no displacement this
    // problem produced: refuse it rather than start the solver from it.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &topo.points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    for (k, st) in ck.steps.iter().enumerate() {
        let umax = st
            .displacement
            .iter()
            .fold(0.0f64, |m, u| m.max(u[0].abs().max(u[1].abs())));
        let finite = st
            .displacement
            .iter()
            .all(|u| u[0].is_finite() && u[1].is_finite());
        let plausible = umax <= 1e3 * diag;
        if !finite || !plausible {
            return Err(format!(
                "{shown}: /steps/{}/displacement: step {} holds displacements that are not finite or implausibly large (max |u| = {umax:e}, mesh size {diag:e}); it cannot be a warm start",
                step_name(k + 1),
                k + 1
            ));
        }
    }
    check_reference(rp, ck, prep)
}

/// The step groups are `/steps/0001` … in order, one per step, within the
/// problem's steps and at their pseudo-times: a restart continues after the
/// last by its name, so a gap, a `0000`, a duplicate or a renamed group
/// would put the next step under a wrong number.
fn check_groups(rp: &Path, ck: &Checkpoint, prep: &Prepared) -> Result<(), String> {
    let shown = rp.display();
    let problem = prep.problem.path.display();
    let file = &prep.problem.file;
    let nsteps = file.nsteps();
    for (k, (name, st)) in ck.step_groups.iter().zip(&ck.steps).enumerate() {
        let want = step_name(k + 1);
        if *name != want {
            let index = name.parse::<usize>().ok();
            let why = match index {
                Some(0) => "load steps are numbered from 1, a group 0000 is no step".to_string(),
                Some(i) if i == k + 1 => format!("step {i} is named /steps/{want}"),
                Some(i) if i < k + 1 => format!("a second group for step {i}"),
                _ => format!("/steps/{want} is missing before it"),
            };
            return Err(format!(
                "{shown}: group /steps/{name}: {why}; the checkpoint cannot be continued (solve from the start)"
            ));
        }
        if k >= nsteps {
            return Err(format!(
                "{shown}: group /steps/{name}: {problem} has {nsteps} load step(s); the checkpoint cannot be continued"
            ));
        }
        let t = file.step_time(k);
        if st.time.to_bits() != t.to_bits() {
            return Err(format!(
                "{shown}: group /steps/{name} is at t = {}, step {} of {problem} at t = {t}; the checkpoint cannot be continued",
                st.time,
                k + 1
            ));
        }
    }
    Ok(())
}

/// `[output] reference_step` between a run and its restart: the change
/// fields the checkpoint holds must be those an uninterrupted run with the
/// problem's reference step writes (from step K on, against step K; none
/// before K or without a reference). A reference added after the steps
/// held, or removed or changed while none of them has change fields, gives
/// the same checkpoint and is continued; anything else would mix two
/// references in one checkpoint and is refused, naming the key. The
/// reference step itself must be finite: the next steps subtract it.
fn check_reference(rp: &Path, ck: &Checkpoint, prep: &Prepared) -> Result<(), String> {
    let shown = rp.display();
    let problem = prep.problem.path.display();
    let kref = prep.problem.file.output.reference_step;
    // The reference of the first step with change fields, and that step.
    let mut theirs: Option<(usize, usize)> = None;
    for (k, st) in ck.steps.iter().enumerate() {
        let group = step_name(k + 1);
        match (&st.change, theirs) {
            (Some(c), None) => {
                if c.reference_step != k + 1 {
                    return Err(format!(
                        "{shown}: group /steps/{group}: the first change fields are relative to step {}, so they should start at step {} (the checkpoint is inconsistent)",
                        c.reference_step, c.reference_step
                    ));
                }
                theirs = Some((c.reference_step, k + 1));
            }
            (Some(c), Some((r, _))) if c.reference_step != r => {
                return Err(format!(
                    "{shown}: group /steps/{group}: change fields relative to step {}, the earlier steps' to step {r}: the checkpoint mixes two reference steps",
                    c.reference_step
                ));
            }
            (None, Some((r, _))) => {
                return Err(format!(
                    "{shown}: group /steps/{group}: no change fields, the earlier steps have them relative to step {r}: the checkpoint mixes runs with and without a reference step"
                ));
            }
            _ => {}
        }
    }
    let done = ck.steps.len();
    match (theirs.map(|t| t.0), kref) {
        (Some(r), Some(k)) if r == k => {}
        (Some(r), Some(k)) => {
            return Err(format!(
                "{shown}: its steps hold changes relative to step {r} ([output] reference_step = {r}), {problem} sets [output] reference_step = {k}: continuing would mix two references in one checkpoint; set reference_step = {r} or solve from the start"
            ))
        }
        (Some(r), None) => {
            return Err(format!(
                "{shown}: its steps hold changes relative to step {r} ([output] reference_step = {r}), {problem} has no [output] reference_step: continuing would leave the next steps without them; set reference_step = {r} or solve from the start"
            ))
        }
        (None, Some(k)) if k <= done => {
            return Err(format!(
                "{shown}: group /steps/{}: no change fields (the checkpoint was written without [output] reference_step = {k}), {problem} sets [output] reference_step = {k}: the steps it holds would lack them; remove reference_step, or solve from the start",
                step_name(k)
            ))
        }
        _ => {}
    }
    if let Some(st) = kref.and_then(|k| ck.steps.get(k.wrapping_sub(1))) {
        let group = step_name(kref.unwrap_or(0));
        let fields: [(&str, bool); 3] = [
            (
                "displacement",
                st.displacement.iter().flatten().all(|v| v.is_finite()),
            ),
            ("stress", st.stress.iter().flatten().all(|v| v.is_finite())),
            (
                "contact_pressure",
                st.contact_pressure.iter().all(|v| v.is_finite()),
            ),
        ];
        if let Some((what, _)) = fields.iter().find(|(_, ok)| !ok) {
            return Err(format!(
                "{shown}: /steps/{group}/{what}: values that are not finite (NaN or Inf) in the reference step ([output] reference_step = {}); the changes of the next steps cannot be taken from it",
                kref.unwrap_or(0)
            ));
        }
    }
    Ok(())
}
