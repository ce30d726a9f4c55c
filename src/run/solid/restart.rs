//! `--restart` of a 3D run (docs/problem-format.md §6): the checkpoint is
//! read and checked before its steps are trusted, with 2D's rules — the
//! same problem by fingerprint (each differing part named), the same mesh
//! sizes, step groups `0001`…`000k` in order at the problem's pseudo-times,
//! a finite and plausible last displacement; the run then continues after
//! its last step, warm-started from it (docs/methods.md §8.3).

use super::SolidPrepared;
use crate::fem::element::Vector3;
use crate::io::hdf5::{read_solid_restart, step_name};
use crate::run::prepare::fingerprint_diff;
use crate::run::RunError;
use std::path::{Path, PathBuf};

/// A 3D checkpoint to continue from.
#[derive(Debug, Clone)]
pub struct SolidRestart {
    /// The checkpoint (`NAME.h5`: the index of the split layout, or a
    /// single solve's file).
    pub path: PathBuf,
    /// Load steps it holds; the run continues with the next one.
    pub steps_done: usize,
    /// The last step's point displacements: the warm start.
    pub displacement: Vec<Vector3>,
    /// The last step's active flag per contact row.
    pub active: Vec<bool>,
    /// The fields of `[output] reference_step` when the checkpoint holds
    /// that step.
    pub reference: Option<super::Reference>,
    /// The last step's λ_n and λ_t (frame) per contact row, with friction:
    /// the next step's multiplier warm start, as in an uninterrupted run.
    pub multipliers: Option<(Vec<f64>, Vec<[f64; 2]>)>,
}

impl SolidRestart {
    /// Reads the checkpoint at `path` and checks that it belongs to `prep`.
    pub fn read(path: &Path, prep: &SolidPrepared) -> Result<SolidRestart, RunError> {
        let m = &prep.model;
        let (n, r) = (m.points.len(), m.contact.len());
        let fail = |msg: String| RunError::Restart(format!("--restart: {msg}"));
        let shown = path.display();
        let problem = prep.problem.path.display();
        let kref = prep.problem.file.output.reference_step;
        let ck =
            read_solid_restart(path, n, m.tets.len(), r, kref).map_err(|e| fail(e.to_string()))?;
        if ck.model.as_deref() != Some("solid") {
            return Err(fail(format!(
                "{shown}: a checkpoint of a 2D model ({}), and {problem} is 3D (its mesh holds tetrahedra); restart needs the checkpoint of the same problem",
                ck.model.as_deref().unwrap_or("no model attribute")
            )));
        }
        let Some(theirs) = &ck.fingerprint else {
            return Err(fail(format!(
                "{shown}: the checkpoint has no problem fingerprint, so it cannot be matched to {problem}; solve from the start"
            )));
        };
        let diff = fingerprint_diff(theirs, &prep.fingerprint());
        if !diff.is_empty() {
            return Err(fail(format!(
                "{shown}: the checkpoint does not match {problem}: it was written for a different {} (restart needs the same mesh and the same loads, materials, contacts and steps)",
                diff.join(", ")
            )));
        }
        if (ck.points, ck.tets, ck.rows) != (n, m.tets.len(), r) {
            return Err(fail(format!(
                "{shown}: checkpoint mesh ({} points, {} tetrahedra, {} contact rows) does not match {problem} ({n} points, {} tetrahedra, {r} contact rows)",
                ck.points,
                ck.tets,
                ck.rows,
                m.tets.len()
            )));
        }
        let file = &prep.problem.file;
        let nsteps = file.nsteps();
        for (k, (name, t, theirs)) in ck.steps.iter().enumerate() {
            // Change fields from step K on, against K, as this problem's
            // `[output] reference_step` writes them; else two references
            // would mix in one checkpoint.
            let want = kref.filter(|&r| k + 1 >= r).map(|r| r as u64);
            if *theirs != want {
                let said = |v: Option<u64>| {
                    v.map_or_else(
                        || "no change fields".to_string(),
                        |v| format!("change fields against step {v}"),
                    )
                };
                return Err(fail(format!(
                    "{shown}: group /steps/{name} has {}, and {problem}'s [output] reference_step asks for {}: the checkpoint cannot be continued with this reference_step; set it as the checkpoint was written or solve from the start",
                    said(*theirs),
                    said(want)
                )));
            }
            let want = step_name(k + 1);
            if *name != want {
                return Err(fail(format!(
                    "{shown}: group /steps/{name} where /steps/{want} belongs: the step groups must be 0001, 0002, … in order; the checkpoint cannot be continued (solve from the start)"
                )));
            }
            if k >= nsteps {
                return Err(fail(format!(
                    "{shown}: group /steps/{name}: {problem} has {nsteps} load step(s); the checkpoint cannot be continued"
                )));
            }
            let ts = file.step_time(k);
            if t.to_bits() != ts.to_bits() {
                return Err(fail(format!(
                    "{shown}: group /steps/{name} is at t = {t}, step {} of {problem} at t = {ts}; the checkpoint cannot be continued",
                    k + 1
                )));
            }
        }
        let (Some(u), Some(active)) = (ck.displacement, ck.active) else {
            return Err(fail(format!(
                "{shown}: the checkpoint holds no step to continue from; solve from the start"
            )));
        };
        // A warm start beyond 10³ mesh diagonals is no displacement this
        // problem produced (as 2D).
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &m.points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        let umax = u.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        if !u.iter().flatten().all(|v| v.is_finite()) || umax > 1e3 * diag {
            return Err(fail(format!(
                "{shown}: /steps/{}/displacement holds displacements that are not finite or implausibly large (max |u| = {umax:e}, mesh size {diag:e}); it cannot be a warm start",
                step_name(ck.steps.len())
            )));
        }
        // λ_n with λ_t in the row frames: both, finite, or no warm start.
        let multipliers = match (ck.multipliers, ck.multipliers_t) {
            (Some(n), Some(t)) => {
                if !n.iter().chain(t.iter().flatten()).all(|v| v.is_finite()) {
                    return Err(fail(format!(
                        "{shown}: /steps/{}/multipliers or multipliers_t_frame hold values that are not finite; they cannot be a warm start",
                        step_name(ck.steps.len())
                    )));
                }
                Some((n, t))
            }
            _ => None,
        };
        Ok(SolidRestart {
            multipliers,
            path: path.to_path_buf(),
            steps_done: ck.steps.len(),
            displacement: u,
            active: active.iter().map(|&a| a != 0).collect(),
            reference: ck
                .reference
                .map(|(displacement, stress, pressure)| super::Reference {
                    displacement,
                    stress,
                    pressure,
                }),
        })
    }
}
