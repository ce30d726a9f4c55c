//! The load steps of a 3D model (docs/problem-format.md §2 `[[steps]]`, §6):
//! each step's model on the same mesh, points and rows; a warm start from
//! the previous step (docs/methods.md §8.3) and one workspace, so the
//! factor of C is computed once for every step (§8.5); the verdict of 2D
//! on each step's certificate. The files are those of 2D: a single solve
//! writes `NAME.vtu` (+ `_contact`), `NAME.h5` in one piece and
//! `NAME.json`; a run with `[[steps]]` writes per step `NAME_NNNN.vtu`
//! (+ `_contact`) and `NAME_NNNN.h5`, the mesh file and the index
//! `NAME.h5` of the split layout and `NAME.pvd`, committed step by step,
//! then `NAME.json`.

use super::forces::{contact_output, forces, probes, Forces3};
use super::{
    solve_in, step_model, NestedStart, SolidOutcome, SolidPrepared, SolidRestart, SolidSummary,
    MOMENT_POINT,
};
use crate::fem::element::{ElementKind, Vector3};
use crate::fem::solid::SolidModel;
use crate::io;
use crate::output::{SolidChange, SolidContactOutput, SolidOutput, StepInfo};
use crate::qp::{MethodId, QpResult, SolveOptions};
use crate::run::output::{check_interrupt, output_paths, same_dir, Transaction, SIGNAL};
use crate::run::steps::{preconditioner_label, Verdict};
use crate::run::summary::{Cells, KktSummary, StepRow, Timings};
use crate::run::RunError;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How a 3D run solves: the method and its options, `--strict`
/// ([`Verdict::of`]), `--max-steps`, compressed VTU, when the run began.
pub struct SolidRun<'a> {
    pub method: MethodId,
    pub opts: &'a SolveOptions,
    pub strict: bool,
    /// Stop after this many load steps (None: all).
    pub max_steps: Option<usize>,
    /// Continue this checkpoint (`--restart`): its steps are kept and the
    /// run starts after them.
    pub restart: Option<&'a SolidRestart>,
    /// Start each step from the coarser mesh's answer at its pseudo-time
    /// (`--start-from`, docs/methods.md §7.2 "The nested start").
    pub nested: Option<&'a NestedStart>,
    pub compress: bool,
    pub started: Instant,
}

/// Solve the load steps of a 3D model and write the outputs in `dir`, one
/// commit per step and the JSON summary last (the transaction of 2D: an
/// error or a signal leaves the directory as it was). None: a restart
/// whose checkpoint holds every step asked for; nothing is solved, and a
/// checkpoint in another directory is copied into `dir` with its files
/// (docs/problem-format.md §6).
pub fn solve_solid(
    prep: &SolidPrepared,
    run: &SolidRun<'_>,
    dir: &Path,
) -> Result<Option<SolidOutcome>, RunError> {
    let (method, opts, strict, compress, started) =
        (run.method, run.opts, run.strict, run.compress, run.started);
    check_interrupt()?;
    let file = &prep.problem.file;
    let multi = !file.steps.is_empty();
    let nsteps = file.nsteps().min(run.max_steps.unwrap_or(usize::MAX));
    let first = run.restart.map_or(0, |r| r.steps_done);
    if first >= nsteps {
        if let Some(r) = run.restart.filter(|r| !same_dir(&r.path, dir)) {
            copy_finished(prep, r, dir, multi, compress)?;
        }
        return Ok(None);
    }
    let name = &prep.problem.name;
    let mut tx = Transaction::open(dir, name)?;
    let mut files = Files::new(prep, tx.stage_dir(), dir, multi, compress);
    let mut carried = vec![];
    if let Some(r) = run.restart {
        carried = files.start_from(r)?;
    }
    tx.plan(multi, files.kept, true);
    let target = opts.settings.kkt_target;
    let mut rows: Vec<StepRow> = vec![];
    let mut failed: Vec<usize> = vec![];
    // The last answer: point displacements and the QP rows' active flags,
    // and λ_n, λ_t per contact row (frictional steps).
    let carry = Carry {
        prev: run.restart.map(|r| {
            let active = prep.model.qp_rows.iter().map(|&k| r.active[k]).collect();
            (r.displacement.clone(), active)
        }),
        lambda: run
            .restart
            .and_then(|r| r.multipliers.clone())
            .map(|(normal, tangential)| RowMultipliers { normal, tangential }),
    };
    // The fields of `[output] reference_step` once it is solved (or read
    // from the checkpoint a restart continues).
    let mut reference = run.restart.and_then(|r| r.reference.clone());
    let mut posted = None;
    let (mut t_assemble_all, mut t_solve_all, mut t_write_all) = (0.0, 0.0, 0.0);
    let last = march(
        prep,
        method,
        opts,
        first..nsteps,
        carry,
        run.nested,
        |st, was| {
            let (s, model, res) = (st.index, &*st.model, &st.result);
            let time_solve = st.time_solve;
            let verdict = Verdict::of(method, res, target, strict);
            let certified = verdict.certified() && res.status.converged();
            if !certified {
                failed.push(s + 1);
            }
            let mut out = crate::post::solid_output(model, &file.materials, &res.x);
            let mut contact =
                contact_output(prep, model, &out.displacement, &res.lambda, &res.active);
            let stick_slip =
                crate::post::solid_friction::solid_friction_output(model, res, &mut contact);
            let mut f3 = forces(prep, model, &out.displacement, &contact);
            super::forces::add_stick_slip(model, &mut f3, &stick_slip);
            out.reaction = f3.reaction.clone();
            // [output] reference_step: from step K on, the change since K.
            if let Some(k) = file.output.reference_step {
                if s + 1 == k {
                    reference = Some(Reference {
                        displacement: out.displacement.clone(),
                        stress: out.stress.clone(),
                        pressure: contact.pressure.clone(),
                    });
                }
                if let Some(r) = reference.as_ref().filter(|_| s + 1 >= k) {
                    let change = r.change(k, &out, &contact);
                    contact.pressure_change = change.contact_pressure.clone();
                    out.change = Some(change);
                }
            }
            let info = StepInfo {
                method: method.name().to_string(),
                preconditioner: preconditioner_label(method, opts),
                converged: res.status.converged(),
                iterations: res.iterations,
                energy: res.energy,
                kkt: res.kkt,
                time_assemble: st.t_assemble,
                time_solve,
                time_total: started.elapsed().as_secs_f64(),
            };
            let tw = Instant::now();
            let mut names = files.step(s, file.step_time(s), &out, &contact, &info)?;
            // A restart's copied files go with its first commit.
            names.append(&mut carried);
            tx.commit(&names)?;
            t_write_all += tw.elapsed().as_secs_f64();
            let active = contact.active.iter().filter(|&&a| a).count();
            let (opened, closed) = match was {
                Some(was) if was.len() == res.active.len() => (
                    Some(
                        was.iter()
                            .zip(&res.active)
                            .filter(|(a, b)| **a && !**b)
                            .count(),
                    ),
                    Some(
                        was.iter()
                            .zip(&res.active)
                            .filter(|(a, b)| !**a && **b)
                            .count(),
                    ),
                ),
                _ => (None, None),
            };
            rows.push(StepRow {
                step: s + 1,
                t: file.step_time(s),
                converged: res.status.converged(),
                certified,
                iterations: res.iterations,
                inner_iterations: res.inner_iterations,
                kkt_max: res.kkt.max(),
                energy: res.energy,
                nodes: model.points.len(),
                cells: Cells::Tetrahedra(model.tets.len()),
                dofs: model.qp.n(),
                constraints: model.qp.m(),
                active,
                opened,
                closed,
                time_solve,
                time_step: st.started.elapsed().as_secs_f64(),
            });
            log::debug!(
                "step {}: assembly {:.3} s, solve {time_solve:.3} s",
                s + 1,
                st.t_assemble
            );
            t_assemble_all += st.t_assemble;
            t_solve_all += time_solve;
            posted = Some((out, contact, verdict, f3));
            Ok(())
        },
    )?;
    let (Some(last), Some((out, contact, verdict, f3))) = (last, posted) else {
        return Err(RunError::Settings(format!(
            "{}: no load step to solve",
            prep.problem.path.display()
        )));
    };
    let (model, res) = (&*last.model, &last.result);
    let t_write = Instant::now();
    let mut summary = summary(prep, model, method, opts, res, &out, &contact, verdict, f3);
    summary.reference_step = file.output.reference_step;
    summary.start_from = run.nested.map(|n| n.path.display().to_string());
    summary.failed_steps = failed;
    if multi {
        summary.steps = rows;
    }
    summary.timings.assemble = t_assemble_all;
    summary.timings.solve = t_solve_all;
    let json_path = output_paths(dir, name, None).json;
    // The steps' VTU and HDF5 files and the summary (as assemble and
    // solve, summed over the steps).
    summary.timings.write = t_write_all + t_write.elapsed().as_secs_f64();
    summary.timings.total = started.elapsed().as_secs_f64();
    let json = summary
        .to_json()
        .map_err(|e| RunError::Output(format!("{}: {e}", json_path.display())))?;
    let staged = files.stage.join(file_name(&json_path));
    io::atomic::write_atomic_bytes(&staged, json.as_bytes())?;
    check_interrupt()?;
    tx.commit(&[file_name(&json_path)])?;
    tx.finish();
    let certified = summary.failed_steps.is_empty();
    let mut written = files.written;
    written.push(json_path);
    Ok(Some(SolidOutcome {
        summary,
        output: out,
        certified,
        files: written,
        contact,
    }))
}

/// A restart with nothing left to solve whose checkpoint lies in another
/// directory: `dir` gets what a run that solved those steps there would
/// have left (as 2D, docs/problem-format.md §6), in one commit: with load
/// steps the mesh and step files, their VTU pairs, the index and the time
/// series; a single solve's checkpoint; and the summary beside the
/// checkpoint, if there is one.
fn copy_finished(
    prep: &SolidPrepared,
    r: &SolidRestart,
    dir: &Path,
    multi: bool,
    compress: bool,
) -> Result<(), RunError> {
    let name = &prep.problem.name;
    let mut tx = Transaction::open(dir, name)?;
    let mut files = Files::new(prep, tx.stage_dir(), dir, multi, compress);
    let index = output_paths(dir, name, None).h5;
    let mut names = if multi {
        let mut names = files.start_from(r)?;
        names.extend(files.series_and_index()?);
        names
    } else {
        let f = file_name(&index);
        copy(&r.path, &files.stage.join(&f))?;
        vec![f]
    };
    let json = output_paths(dir, name, None).json;
    let src = r.path.with_file_name(file_name(&json));
    let summary = src.is_file();
    if summary {
        let f = file_name(&json);
        std::fs::copy(&src, files.stage.join(&f)).map_err(|e| {
            RunError::Output(format!(
                "{}: cannot copy the restart's summary: {e}",
                src.display()
            ))
        })?;
        names.push(f);
    }
    check_interrupt()?;
    tx.plan(multi, files.kept, summary);
    tx.commit(&names)?;
    tx.finish();
    Ok(())
}

/// What one load step hands on to the next (docs/methods.md §8.3): the
/// point displacements and the QP rows' active flags of its answer, and
/// with friction its λ_n, λ_t per contact row.
#[derive(Default)]
pub(super) struct Carry {
    prev: Option<(Vec<Vector3>, Vec<bool>)>,
    lambda: Option<RowMultipliers>,
}

/// One solved load step of a 3D model.
pub(super) struct Marched<'p> {
    /// The step (0-based).
    pub index: usize,
    pub model: Cow<'p, SolidModel>,
    pub result: QpResult,
    /// Seconds to build the step's model (the prepared one's for step 1).
    pub t_assemble: f64,
    pub time_solve: f64,
    /// When the step began.
    pub started: Instant,
}

/// Solve the load steps `steps` of `prep` in order, each warm-started
/// from the last (its x, active set and, with friction, its multipliers
/// and the slip measured from its displacements, docs/methods.md §8.3,
/// §12.2), with one workspace for all (§8.5). `each` sees every solved
/// step and the active flags of the step before (None for the first);
/// the last step is returned. This is the loop of `solve` (which writes
/// the files in `each`) and of `compare` along a frictional load path
/// (which sums the work); a refused step's error names it.
pub(super) fn march<'p>(
    prep: &'p SolidPrepared,
    method: MethodId,
    opts: &SolveOptions,
    steps: std::ops::Range<usize>,
    mut carry: Carry,
    nested: Option<&NestedStart>,
    mut each: impl FnMut(&Marched<'p>, Option<&[bool]>) -> Result<(), RunError>,
) -> Result<Option<Marched<'p>>, RunError> {
    let file = &prep.problem.file;
    let ws = opts.settings.workspace();
    let mut last = None;
    for s in steps {
        check_interrupt()?;
        let started = Instant::now();
        let mut model = step_model(prep, s)?;
        // Friction: the slip of this step is measured from the last step's
        // displacements (docs/methods.md §12.2).
        if let (Some(_), Some((u, _))) = (&model.qp.friction, &carry.prev) {
            crate::fem::Discrete::start_step(model.to_mut(), Some(u));
        }
        let t_assemble = if s == 0 {
            prep.t_assemble
        } else {
            started.elapsed().as_secs_f64()
        };
        let mut o = opts.clone();
        if let Some((u, active)) = &carry.prev {
            o.x0 = Some(crate::fem::Discrete::reduce(&*model, u));
            o.active0 = (active.len() == model.qp.m()).then(|| active.clone());
        }
        o.lambda0 = carry
            .lambda
            .as_ref()
            .filter(|_| model.qp.friction.is_some())
            .map(|l| l.reduce(&model));
        // A nested start replaces the last step's x and working set.
        if let Some((u, lam)) = nested.and_then(|n| n.at(prep.problem.file.step_time(s))) {
            o.x0 = Some(crate::fem::Discrete::reduce(&*model, u));
            o.active0 = None;
            o.nested_lambda = Some(model.qp_rows.iter().map(|&k| lam[k]).collect());
        }
        o.stop = Some(&SIGNAL);
        let t0 = Instant::now();
        let res = solve_in(prep, &model, method, &o, &ws);
        // An interrupted solve is no result to hand on, nor an error of the
        // problem.
        check_interrupt()?;
        let result = res.map_err(|e| e.in_step(file, s))?;
        let step = Marched {
            index: s,
            model,
            result,
            t_assemble,
            time_solve: t0.elapsed().as_secs_f64(),
            started,
        };
        each(&step, carry.prev.as_ref().map(|(_, a)| a.as_slice()))?;
        carry = Carry {
            prev: Some((
                step.model.displacements(&step.result.x),
                step.result.active.clone(),
            )),
            lambda: RowMultipliers::of(&step.model, &step.result),
        };
        last = Some(step);
    }
    Ok(last)
}

/// λ_n (one) and λ_t (two, in the row's friction frame) per contact row
/// of a frictional answer: the multiplier warm start of the next step
/// (docs/methods.md §8.3), carried by contact row since each step's model
/// is built anew.
struct RowMultipliers {
    normal: Vec<f64>,
    tangential: Vec<[f64; 2]>,
}

impl RowMultipliers {
    /// Those of `res` on `model` (None: frictionless, or no λ_t).
    fn of(model: &SolidModel, res: &QpResult) -> Option<Self> {
        model.qp.friction.as_ref()?;
        let m = model.qp.m();
        if res.lambda.len() != m || res.lambda_t.len() != 2 * m {
            return None;
        }
        let r = model.contact.len();
        let mut out = RowMultipliers {
            normal: vec![0.0; r],
            tangential: vec![[0.0; 2]; r],
        };
        for (qi, &k) in model.qp_rows.iter().enumerate() {
            out.normal[k] = res.lambda[qi];
            out.tangential[k] = [res.lambda_t[2 * qi], res.lambda_t[2 * qi + 1]];
        }
        Some(out)
    }

    /// In `model`'s QP rows.
    fn reduce(&self, model: &SolidModel) -> crate::qp::Multipliers {
        let get = |k: usize| self.normal.get(k).copied().unwrap_or(0.0);
        let get_t = |k: usize| self.tangential.get(k).copied().unwrap_or([0.0; 2]);
        crate::qp::Multipliers {
            normal: model.qp_rows.iter().map(|&k| get(k)).collect(),
            tangential: model.qp_rows.iter().flat_map(|&k| get_t(k)).collect(),
        }
    }
}

fn copy(from: &Path, to: &Path) -> Result<(), RunError> {
    std::fs::copy(from, to).map(|_| ()).map_err(|e| {
        RunError::Output(format!(
            "{}: cannot copy the checkpoint's file: {e}",
            from.display()
        ))
    })
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The files of a 3D run, staged step by step.
struct Files<'a> {
    prep: &'a SolidPrepared,
    stage: PathBuf,
    dir: PathBuf,
    multi: bool,
    compress: bool,
    /// Gmsh node tag of each point.
    tags: Vec<u64>,
    /// Split layout: the step files the index lists.
    steps: Vec<(usize, String)>,
    /// The time series: (t, VTU file) per step and file.
    series: Vec<(f64, String)>,
    /// Final paths of every file written.
    written: Vec<PathBuf>,
    /// A restart's step files kept where they are (the output directory's).
    kept: usize,
    /// The split layout's mesh file is there already (a restart).
    has_mesh: bool,
}

impl<'a> Files<'a> {
    fn new(prep: &'a SolidPrepared, stage: &Path, dir: &Path, multi: bool, compress: bool) -> Self {
        let tags = prep
            .model
            .point_node
            .iter()
            .map(|&v| prep.mesh.node_tags[v])
            .collect();
        Files {
            prep,
            stage: stage.to_path_buf(),
            dir: dir.to_path_buf(),
            multi,
            compress,
            tags,
            steps: vec![],
            series: vec![],
            written: vec![],
            kept: 0,
            has_mesh: false,
        }
    }

    /// The files of the checkpoint `r` continues: its mesh and step files
    /// kept where they are the output directory's, or copied into the
    /// stage (returned: committed with the first step); the time series
    /// lists the kept steps' VTU pairs that are in the output directory.
    fn start_from(&mut self, r: &SolidRestart) -> Result<Vec<String>, RunError> {
        let name = self.prep.problem.name.clone();
        let found = io::hdf5::checkpoint_files(&r.path)?;
        let single = r.path.canonicalize().ok();
        let dir = self.dir.clone();
        let here = |f: &Path, want: &str| {
            let w = dir.join(want);
            matches!((f.canonicalize(), w.canonicalize()), (Ok(a), Ok(b)) if a == b)
        };
        if !self.multi {
            return Err(RunError::Restart(format!(
                "--restart: {}: a single solve's checkpoint; a 3D run with [[steps]] continues the checkpoint of a run with the same steps (docs/problem-format.md §6)",
                r.path.display()
            )));
        }
        // A packed checkpoint (`signorini pack`: one file, every step):
        // its parts are written out again as the split layout's files.
        let packed = found.mesh.canonicalize().ok() == single;
        let mut staged = vec![];
        let mesh_file = io::hdf5::mesh_file_name(&name);
        if packed {
            io::hdf5::unpack_part(&r.path, None, &self.stage.join(&mesh_file))?;
            staged.push(mesh_file.clone());
        } else if !here(&found.mesh, &mesh_file) {
            copy(&found.mesh, &self.stage.join(&mesh_file))?;
            staged.push(mesh_file.clone());
        }
        self.keep(&self.dir.join(&mesh_file));
        self.has_mesh = true;
        let mut kept = true;
        // The checkpoint's mesh, read once if a pair must be written again.
        let mut mesh = None;
        for (i, _, f) in found.steps.iter().take(r.steps_done) {
            let want = io::hdf5::step_file_name(&name, *i);
            if packed {
                kept = false;
                io::hdf5::unpack_part(&r.path, Some(*i), &self.stage.join(&want))?;
                staged.push(want.clone());
            } else if here(f, &want) {
                self.kept += usize::from(kept);
            } else {
                kept = false;
                copy(f, &self.stage.join(&want))?;
                staged.push(want.clone());
            }
            self.keep(&self.dir.join(&want));
            self.steps.push((*i, want));
            let t = self.prep.problem.file.step_time(i - 1);
            let pair = output_paths(&self.dir, &name, Some(*i));
            // The VTU pair the run that wrote the checkpoint left beside it
            // (a restart into another directory): copied as it is, as in
            // 2D; a pair found nowhere (a packed checkpoint moved alone) is
            // written again from the checkpoint's step, every field but the
            // reactions and the change fields, which it does not keep.
            let src = output_paths(r.path.parent().unwrap_or(Path::new(".")), &name, Some(*i));
            let has_contact = !self.prep.problem.file.contact.is_empty();
            let in_place = same_dir(&r.path, &self.dir);
            let files = 1 + usize::from(has_contact);
            let pairs = [(&src.vtu, &pair.vtu), (&src.contact_vtu, &pair.contact_vtu)];
            if in_place && pairs.iter().take(files).all(|(_, to)| to.is_file()) {
                // A restart in place: the pair is there.
            } else if !in_place && pairs.iter().take(files).all(|(from, _)| from.is_file()) {
                for (from, to) in pairs.iter().take(files) {
                    let f = file_name(to);
                    copy(from, &self.stage.join(&f))?;
                    staged.push(f);
                    self.keep(to);
                }
            } else {
                let names =
                    self.pair_from_checkpoint(&r.path, &mut mesh, *i, &pair, has_contact)?;
                staged.extend(names);
            }
            for v in [&pair.vtu, &pair.contact_vtu] {
                let f = file_name(v);
                if v.is_file() || staged.contains(&f) {
                    self.series.push((t, f));
                }
            }
        }
        Ok(staged)
    }

    fn attrs(&self) -> [(&'static str, String); 4] {
        let p = &self.prep;
        [
            ("problem", p.problem.name.clone()),
            ("toml", p.problem.text.clone()),
            ("version", env!("CARGO_PKG_VERSION").to_string()),
            ("fingerprint", p.fingerprint()),
        ]
    }

    /// Stage step `s`'s files; returns their names, the index last.
    fn step(
        &mut self,
        s: usize,
        time: f64,
        out: &SolidOutput,
        contact: &SolidContactOutput,
        info: &StepInfo,
    ) -> Result<Vec<String>, RunError> {
        let name = self.prep.problem.name.clone();
        let has_contact = !self.prep.problem.file.contact.is_empty();
        let paths = output_paths(&self.dir, &name, self.multi.then_some(s + 1));
        let mut names = vec![file_name(&paths.vtu)];
        io::vtu::write_solid_vtu(&self.stage.join(&names[0]), out, self.compress)?;
        self.keep(&paths.vtu);
        if has_contact {
            let f = file_name(&paths.contact_vtu);
            io::vtu::write_solid_contact_vtu(&self.stage.join(&f), contact, self.compress)?;
            self.keep(&paths.contact_vtu);
            names.push(f);
        }
        let attrs = self.attrs();
        let attrs: Vec<(&str, String)> = attrs.iter().map(|(k, v)| (*k, v.clone())).collect();
        if !self.multi {
            let f = file_name(&paths.h5);
            io::hdf5::write_solid_checkpoint(
                &self.stage.join(&f),
                out,
                contact,
                &self.tags,
                &attrs,
                time,
                info,
            )?;
            self.keep(&paths.h5);
            names.push(f);
            return Ok(names);
        }
        // The split layout: the mesh file at the first step, the step's
        // file, the index last (committed after the files it links to).
        let mesh_file = io::hdf5::mesh_file_name(&name);
        if !self.has_mesh {
            self.has_mesh = true;
            io::hdf5::write_solid_mesh_file(
                &self.stage.join(&mesh_file),
                out,
                contact,
                &self.tags,
            )?;
            self.keep(&self.dir.join(&mesh_file));
            names.push(mesh_file.clone());
        }
        let f = io::hdf5::step_file_name(&name, s + 1);
        io::hdf5::write_solid_step_file(&self.stage.join(&f), s + 1, out, contact, time, info)?;
        self.keep(&self.dir.join(&f));
        names.push(f.clone());
        self.steps.push((s + 1, f));
        self.series.push((time, file_name(&paths.vtu)));
        if has_contact {
            self.series.push((time, file_name(&paths.contact_vtu)));
        }
        names.extend(self.series_and_index()?);
        Ok(names)
    }

    /// Stage the time series and the split layout's index over the steps
    /// so far; their names, the index last (committed after the files it
    /// links to).
    fn series_and_index(&mut self) -> Result<Vec<String>, RunError> {
        let name = self.prep.problem.name.clone();
        let attrs = self.attrs();
        let attrs: Vec<(&str, String)> = attrs.iter().map(|(k, v)| (*k, v.clone())).collect();
        let pvd = format!("{name}.pvd");
        io::vtu::write_pvd(&self.stage.join(&pvd), &self.series)?;
        self.keep(&self.dir.join(&pvd));
        let index = output_paths(&self.dir, &name, None).h5;
        io::hdf5::write_solid_index(
            &self.stage.join(file_name(&index)),
            &attrs,
            &io::hdf5::mesh_file_name(&name),
            &self.steps,
        )?;
        self.keep(&index);
        Ok(vec![pvd, file_name(&index)])
    }

    /// Stage step `i`'s VTU pair (the bulk file, and the contact file
    /// when the problem has contact) written from the checkpoint at
    /// `path`, to be committed as `pair`; their names. `mesh` holds the
    /// checkpoint's mesh once read (it is read on the first call only).
    fn pair_from_checkpoint(
        &mut self,
        path: &Path,
        mesh: &mut Option<crate::output::SolidCheckpoint>,
        i: usize,
        pair: &crate::run::output::Outputs,
        has_contact: bool,
    ) -> Result<Vec<String>, RunError> {
        if mesh.is_none() {
            *mesh = Some(io::hdf5::read_solid_checkpoint(
                path,
                io::hdf5::SolidSteps::MeshOnly,
            )?);
        }
        let Some(ck) = mesh.as_ref() else {
            return Ok(vec![]);
        };
        let st = io::hdf5::read_solid_step(path, ck, i)?;
        let out = SolidOutput {
            points: ck.points.clone(),
            point_body: ck.point_body.clone(),
            tets: ck.tets.clone(),
            material: ck.material.clone(),
            material_names: ck.material_names.clone(),
            displacement: st.displacement,
            stress: st.stress,
            von_mises: st.von_mises,
            principal: st.principal,
            reaction: vec![],
            change: None,
        };
        let mut names = vec![file_name(&pair.vtu)];
        io::vtu::write_solid_vtu(&self.stage.join(&names[0]), &out, self.compress)?;
        self.keep(&pair.vtu);
        if has_contact {
            let c = &ck.contact;
            let contact = SolidContactOutput {
                points: c.slave.iter().map(|&p| ck.points[p]).collect(),
                slave: c.slave.clone(),
                triangles: c.triangles.clone(),
                normal: c.normal.clone(),
                interface: c.interface.clone(),
                gap0: c.gap0.clone(),
                gap: st.gap,
                multiplier: st.multipliers,
                pressure: st.contact_pressure,
                active: st.active.iter().map(|&a| a != 0).collect(),
                tangential_force: st.tangential_force,
                tangential_traction: st.tangential_traction,
                slip: st.slip,
                friction_state: st.friction_state,
                ..Default::default()
            };
            let f = file_name(&pair.contact_vtu);
            io::vtu::write_solid_contact_vtu(&self.stage.join(&f), &contact, self.compress)?;
            self.keep(&pair.contact_vtu);
            names.push(f);
        }
        Ok(names)
    }

    fn keep(&mut self, p: &Path) {
        if !self.written.iter().any(|w| w == p) {
            self.written.push(p.to_path_buf());
        }
    }
}

/// The fields of the reference step (`[output] reference_step`).
#[derive(Debug, Clone)]
pub struct Reference {
    pub displacement: Vec<Vector3>,
    pub stress: Vec<[f64; 6]>,
    /// Per contact row.
    pub pressure: Vec<f64>,
}

impl Reference {
    /// A step's fields minus these (reference step `k`, 1-based).
    fn change(&self, k: usize, out: &SolidOutput, c: &SolidContactOutput) -> SolidChange {
        let sub =
            |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
        SolidChange {
            reference_step: k,
            displacement: out
                .displacement
                .iter()
                .zip(&self.displacement)
                .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                .collect(),
            stress: out
                .stress
                .iter()
                .zip(&self.stress)
                .map(|(a, b)| std::array::from_fn(|i| a[i] - b[i]))
                .collect(),
            contact_pressure: sub(&c.pressure, &self.pressure),
        }
    }
}

/// The JSON summary of the last step solved.
#[allow(clippy::too_many_arguments)]
fn summary(
    prep: &SolidPrepared,
    m: &SolidModel,
    method: MethodId,
    opts: &SolveOptions,
    res: &QpResult,
    out: &SolidOutput,
    contact: &SolidContactOutput,
    verdict: Verdict,
    f: Forces3,
) -> SolidSummary {
    let certified = verdict.certified();
    SolidSummary {
        problem: prep.problem.name.clone(),
        model: ElementKind::Solid.model_name(),
        method: method.name().to_string(),
        preconditioner: preconditioner_label(method, opts),
        ordering: match opts.settings.factor_free(method) {
            Some(why) => format!("none ({why})"),
            // ssn_path = "auto" solves a large solid model on the multigrid
            // (docs/methods.md §7.2, §12.3).
            None if method == MethodId::Ssn
                && crate::qp::ssn::iterative_by_default(&m.qp, opts.settings.ssn.path) =>
            {
                format!(
                    "none (ssn_path = auto: the multigrid path from {} unknowns)",
                    crate::qp::ssn::ITERATIVE_3D_FROM
                )
            }
            None => opts.settings.ordering.name().to_string(),
        },
        converged: res.status.converged(),
        status: res.status.describe(),
        iterations: res.iterations,
        inner_iterations: res.inner_iterations,
        nodes: m.points.len(),
        mesh_nodes: prep.mesh.nodes.len(),
        tetrahedra: m.tets.len(),
        bodies: m.nbodies,
        rigid_modes: m.qp.kernel.len(),
        dofs: m.qp.n(),
        constraints: m.qp.m(),
        active: contact.active.iter().filter(|&&a| a).count(),
        contact: f.interfaces,
        failed_steps: vec![],
        energy: res.energy,
        strain_energy: f.strain_energy,
        load_work: f.load_work,
        kkt: KktSummary {
            residuals: res.kkt,
            friction_zero: (m.qp.friction.is_some() && res.kkt.friction == 0.0).then_some(0.0),
            target: opts.settings.kkt_target,
            certified,
        },
        moment_point: MOMENT_POINT,
        loads: f.loads,
        reactions: f.groups.into_iter().map(|g| (g.on.clone(), g)).collect(),
        notes: res.notes.iter().map(ToString::to_string).collect(),
        probes: probes(prep, &out.displacement),
        steps: vec![],
        reference_step: None,
        start_from: None,
        timings: Timings {
            read: prep.t_read,
            assemble: 0.0,
            solve: 0.0,
            write: 0.0,
            total: 0.0,
            phases: res.timings.iter().cloned().collect(),
        },
    }
}
