//! Restart (docs/problem-format.md §6): a checkpoint `NAME.h5` is read and
//! checked before its steps are trusted (the same problem by fingerprint,
//! the same mesh sizes, finite and plausible displacements); the run then
//! continues after its last step, warm-started from it (docs/methods.md §8.3).

use super::prepare::{fingerprint, fingerprint_diff, Prepared};
use super::RunError;
use crate::io::hdf5::{read_checkpoint, Checkpoint};
use crate::io::StepOutput;
use std::path::{Path, PathBuf};

/// A checkpoint to continue from.
#[derive(Debug, Clone)]
pub struct Restart {
    /// The checkpoint file (copied, then extended, by the next steps).
    pub path: PathBuf,
    /// Load steps it holds (the run continues with the next one).
    pub steps_done: usize,
    /// Displacements of its last step (per output point): the warm start.
    pub displacement: Option<Vec<[f64; 2]>>,
    /// Active flags of its last step (per contact row): the state the next
    /// step's opened/closed counts refer to.
    pub active: Option<Vec<u8>>,
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
    let diff = fingerprint_diff(theirs, fingerprint);
    if !diff.is_empty() {
        return Err(format!(
            "{shown}: the checkpoint does not match {problem}: it was written for a different {} (restart needs the same mesh and the same loads, materials, contacts and steps)",
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
                "{shown}: step {} holds displacements that are not finite or implausibly large (max |u| = {umax:e}, mesh size {diag:e}); it cannot be a warm start",
                k + 1
            ));
        }
    }
    Ok(())
}
