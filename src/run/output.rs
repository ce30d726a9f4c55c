//! The outputs of a run (docs/problem-format.md §6) as observers, and the
//! transaction that moves them into place: files are written into a staging
//! directory ([`Stage`]) under the output directory's lock ([`OutputLock`])
//! and committed per load step (VTU pair, PVD, the checkpoint's step file and
//! its index, renamed last), the JSON summary last; an error drops the
//! transaction, which puts back what the directory held before. SIGTERM and SIGINT become such an error
//! ([`catch_signals`]).

use super::observe::StepObserver;
use super::prepare::{fingerprint, Prepared};
use super::restart::Restart;
use super::steps::Step;
use super::summary::Summary;
use super::RunError;
use crate::io::atomic::{self, OutputLock, Stage};
use crate::io::{self, IoError};
use crate::output::OutMesh;
use std::path::{Path, PathBuf};

/// The signal `signorini solve` received (SIGTERM, SIGINT; 0: none), set
/// by the handler of [`catch_signals`]: a process has one set of signal
/// handlers, so this is the one process-wide flag.
pub static SIGNAL: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);

/// Makes SIGTERM and SIGINT stop the run instead of the process: the
/// handler only stores the signal's number (an atomic store is
/// async-signal-safe); the iterative solvers end at their next iteration
/// (`SIGNAL`, which every solve of a [`Run`](super::Run) watches through `SolveOptions::stop`) and [`Run`](super::Run) returns
/// [`RunError::Interrupted`] at its next check (before and after each
/// step's solve, before each commit, after the last), so the dropped
/// [`Transaction`] puts back what the output directory held. Later signals
/// change nothing (the first one is kept); `kill -9` cannot be caught
/// (docs/problem-format.md §6 says what it leaves).
pub fn catch_signals() {
    extern "C" fn on_signal(sig: libc::c_int) {
        let _ = SIGNAL.compare_exchange(
            0,
            sig,
            std::sync::atomic::Ordering::SeqCst,
            std::sync::atomic::Ordering::SeqCst,
        );
    }
    for sig in [libc::SIGTERM, libc::SIGINT] {
        // SAFETY: a zeroed sigaction with a handler that only does an
        // atomic store; SA_RESTART keeps the file writes in flight going.
        unsafe {
            let mut sa: libc::sigaction = std::mem::zeroed();
            sa.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            sa.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut sa.sa_mask);
            libc::sigaction(sig, &sa, std::ptr::null_mut());
        }
    }
}

/// The signal that asked the run to stop ([`catch_signals`]), if any.
pub fn interrupted() -> Option<i32> {
    match SIGNAL.load(std::sync::atomic::Ordering::SeqCst) {
        0 => None,
        sig => Some(sig),
    }
}

/// `Err(Interrupted)` once a signal asked the run to stop.
pub(crate) fn check_interrupt() -> Result<(), RunError> {
    interrupted().map_or(Ok(()), |sig| Err(RunError::Interrupted(sig)))
}

/// The name of a signal number (for the message).
pub(crate) fn signal_name(sig: i32) -> String {
    match sig {
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGINT => "SIGINT".into(),
        _ => format!("signal {sig}"),
    }
}

/// Output file paths of one solve.
#[derive(Debug, Clone)]
pub struct Outputs {
    pub vtu: PathBuf,
    pub contact_vtu: PathBuf,
    pub h5: PathBuf,
    pub json: PathBuf,
}

/// Output paths; `step` = Some(k) names the VTU pair of load step k (1-based).
pub fn output_paths(dir: &Path, name: &str, step: Option<usize>) -> Outputs {
    let stem = match step {
        Some(k) => format!("{name}_{k:04}"),
        None => name.to_string(),
    };
    Outputs {
        vtu: dir.join(format!("{stem}.vtu")),
        contact_vtu: dir.join(format!("{stem}_contact.vtu")),
        h5: dir.join(format!("{name}.h5")),
        json: dir.join(format!("{name}.json")),
    }
}

/// Whether the file `path` lies in the directory `dir` (both resolved).
pub(crate) fn same_dir(path: &Path, dir: &Path) -> bool {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match (parent.canonicalize(), dir.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// The file name of an output path.
fn fname(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The outputs of one run in the directory `dir`: the lock of the name, the
/// staging directory, the commits. Dropped without [`Transaction::finish`]
/// (an error), it restores the files the directory held before.
pub struct Transaction {
    // Dropped in this order: the stage restores, then the lock is released.
    stage: Stage,
    _lock: OutputLock,
    dir: PathBuf,
    name: String,
    /// The files of the name this run keeps, until the first commit
    /// removes the others ([`Transaction::plan`]); None once done.
    sweep: Option<Sweep>,
    /// Last, so that it drops after the stage and the lock.
    _created: CreatedDir,
}

/// The output directory when this run created it: removed again if the run
/// leaves it empty (a run refused before its first commit, e.g. a bad
/// `--restart`), so that a failed run leaves nothing behind.
struct CreatedDir(Option<PathBuf>);

impl Drop for CreatedDir {
    fn drop(&mut self) {
        if let Some(dir) = self.0.take() {
            // Fails, as it should, when anything is in it.
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// What a run leaves of its output name (docs/problem-format.md §6): with
/// load steps (`multi`) the index, mesh file, time series and step files,
/// else the single files; the step files of steps `1..=kept` are those of
/// a restart in place (the checkpoint's own), the later ones this run's.
#[derive(Debug, Clone, Copy)]
struct Sweep {
    multi: bool,
    kept: usize,
    /// The run writes `NAME.json` (it solves a step); else (a restart with
    /// nothing left to solve) an older run's summary is removed unless
    /// one is copied in.
    summary: bool,
}

/// The kind of a file of the output name `name` (None: not of its pattern).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owned {
    /// `NAME.h5`, `NAME.json`: rewritten by every run's last commit.
    Record,
    /// `NAME.vtu`, `NAME_contact.vtu`: a single solve's.
    Single,
    /// `NAME.pvd`, `NAME_mesh.h5`: a run with load steps'.
    Series,
    /// `NAME_NNNN.vtu`, `NAME_NNNN_contact.vtu`, `NAME_NNNN.h5`: step NNNN's.
    Step(usize),
}

/// Classifies `file` against the output name `name`.
fn owned(name: &str, file: &str) -> Option<Owned> {
    if file == format!("{name}.h5") || file == format!("{name}.json") {
        return Some(Owned::Record);
    }
    if file == format!("{name}.vtu") || file == format!("{name}_contact.vtu") {
        return Some(Owned::Single);
    }
    if file == format!("{name}.pvd") || file == io::hdf5::mesh_file_name(name) {
        return Some(Owned::Series);
    }
    let rest = file.strip_prefix(name)?.strip_prefix('_')?;
    let digits = ["_contact.vtu", ".vtu", ".h5"]
        .iter()
        .find_map(|suffix| rest.strip_suffix(suffix))?;
    if digits.len() < 4 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().map(Owned::Step)
}

impl Transaction {
    /// Creates `dir` if needed, takes the lock of the output name `name`
    /// (one run per name at a time), removes the staging directories a
    /// killed run left, and opens a new one.
    pub fn open(dir: &Path, name: &str) -> Result<Transaction, RunError> {
        let created = CreatedDir((!dir.exists()).then(|| dir.to_path_buf()));
        std::fs::create_dir_all(dir).map_err(|e| {
            RunError::Output(format!(
                "{}: cannot create output directory: {e}",
                dir.display()
            ))
        })?;
        let lock = OutputLock::acquire(dir, name).map_err(RunError::Output)?;
        let prefix = format!("{}{name}-", atomic::STAGE_PREFIX);
        atomic::remove_stale_stages(dir, &prefix);
        let stage = Stage::new(dir, &prefix)?;
        Ok(Transaction {
            stage,
            _lock: lock,
            dir: dir.to_path_buf(),
            name: name.to_string(),
            sweep: None,
            _created: created,
        })
    }

    /// The files of the output name this run leaves: with load steps
    /// (`multi`) or not, a restart's steps `1..=kept` kept in place (the
    /// restart checkpoint is this directory's), and a summary written or
    /// not (`summary`: a step is solved). The first commit then
    /// removes every other file of the name's pattern (an older run's
    /// surplus: its later steps, or the files of the other layout), as part
    /// of the transaction: a rollback puts them back.
    pub fn plan(&mut self, multi: bool, kept: usize, summary: bool) {
        self.sweep = Some(Sweep {
            multi,
            kept,
            summary,
        });
    }

    /// Removes the files of the name this run does not leave ([`Transaction::plan`]),
    /// except `committed`.
    fn sweep(&mut self, plan: Sweep, committed: &[&str]) -> Result<(), IoError> {
        let Ok(rd) = std::fs::read_dir(&self.dir) else {
            return Ok(());
        };
        let mut surplus: Vec<String> = rd
            .flatten()
            .filter(|e| e.file_type().is_ok_and(|t| !t.is_dir()))
            .filter_map(|e| e.file_name().to_str().map(str::to_string))
            .filter(|f| !committed.contains(&f.as_str()))
            .filter(|f| match owned(&self.name, f) {
                None => false,
                // The checkpoint is in every run's last commit; the
                // summary in every run's that solves a step (a restart in
                // place with nothing to solve keeps its own).
                Some(Owned::Record) => !plan.summary && plan.kept == 0 && f.ends_with(".json"),
                Some(Owned::Single) => plan.multi,
                // With load steps, the mesh file of a restart in place is
                // the checkpoint's (the time series is in every commit).
                Some(Owned::Series) => !plan.multi || plan.kept == 0,
                Some(Owned::Step(i)) => !plan.multi || i == 0 || i > plan.kept,
            })
            .collect();
        // Directory order is the file system's: sorted, the same input
        // removes the same files in the same order.
        surplus.sort();
        for f in &surplus {
            self.stage.remove(f)?;
        }
        if !surplus.is_empty() {
            log::debug!("removed {} files of an older run", surplus.len());
        }
        Ok(())
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The staging directory, where the observers write.
    pub fn stage_dir(&self) -> &Path {
        self.stage.dir()
    }

    /// Moves the staged files `names` into place.
    pub fn commit(&mut self, names: &[String]) -> Result<(), RunError> {
        let t = std::time::Instant::now();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let mut r = self.stage.commit(&names);
        // After the commit's files (a new index first, then the older
        // run's step files it no longer links to).
        if let (Ok(()), Some(plan)) = (&r, self.sweep.take()) {
            r = self.sweep(plan, &names);
        }
        let r = r.map_err(|e| RunError::Output(self.unstage(&e.to_string())));
        log::debug!(
            "commit of {} files {:.3} s",
            names.len(),
            t.elapsed().as_secs_f64()
        );
        r
    }

    /// `msg` naming the final files instead of their staged copies.
    pub fn unstage(&self, msg: &str) -> String {
        msg.replace(
            &format!("{}/", self.stage.dir().display()),
            &format!("{}/", self.dir.display()),
        )
    }

    /// The run is complete: drop the backups and the staging directory, release the lock.
    pub fn finish(self) {
        self.stage.finish();
    }
}

/// A new checkpoint at `h5` holding the mesh and the problem's
/// [`fingerprint`] (steps are appended one by one).
pub fn create_checkpoint(
    prep: &Prepared,
    h5: &Path,
    om: &OutMesh,
    fingerprint: &str,
) -> Result<(), IoError> {
    let attrs = [
        ("problem", prep.problem.name.clone()),
        ("problem_toml", prep.problem.text.clone()),
        ("fingerprint", fingerprint.to_string()),
        (
            "program",
            format!("signorini {}", env!("CARGO_PKG_VERSION")),
        ),
    ];
    io::hdf5::create_checkpoint(h5, om, &attrs)
}

/// The checkpoint `NAME.h5`. A single solve writes one file (created at
/// the step, or copied from the checkpoint of a restart and extended). A
/// run with load steps writes the split layout of [`crate::io::hdf5`]:
/// the mesh file once, each step's own file, and the small index `NAME.h5`
/// rewritten at every step, which the commit renames last; so a step
/// writes its own data and the index, never the earlier steps again.
pub struct CheckpointWriter<'a> {
    prep: &'a Prepared,
    om: &'a OutMesh,
    fingerprint: String,
    stage_dir: PathBuf,
    dir: PathBuf,
    staged: PathBuf,
    target: PathBuf,
    /// The checkpoint the next step extends (None: a new one).
    base: Option<PathBuf>,
    /// Split layout: the step files the index lists, (index, file name in
    /// `dir`), once the mesh file is written or found (None before).
    split: Option<Vec<(usize, String)>>,
}

impl<'a> CheckpointWriter<'a> {
    /// Writes into `stage_dir` the checkpoint whose final place is in `dir`
    /// (the same directory without a [`Transaction`]).
    pub fn new(
        prep: &'a Prepared,
        om: &'a OutMesh,
        stage_dir: &Path,
        dir: &Path,
        restart: Option<&Restart>,
    ) -> Self {
        let name = &prep.problem.name;
        CheckpointWriter {
            prep,
            om,
            fingerprint: fingerprint(prep, prep.no_contact),
            stage_dir: stage_dir.to_path_buf(),
            dir: dir.to_path_buf(),
            staged: output_paths(stage_dir, name, None).h5,
            target: output_paths(dir, name, None).h5,
            base: restart.map(|r| r.path.clone()),
            split: None,
        }
    }

    fn copy_base(&self, base: &Path) -> Result<(), RunError> {
        std::fs::copy(base, &self.staged).map(|_| ()).map_err(|e| {
            RunError::Output(format!(
                "{}: cannot copy the checkpoint: {e}",
                base.display()
            ))
        })
    }

    fn name(&self) -> &str {
        &self.prep.problem.name
    }

    /// The root attributes of the checkpoint.
    fn attrs(&self) -> [(&'static str, String); 4] {
        [
            ("problem", self.prep.problem.name.clone()),
            ("problem_toml", self.prep.problem.text.clone()),
            ("fingerprint", self.fingerprint.clone()),
            (
                "program",
                format!("signorini {}", env!("CARGO_PKG_VERSION")),
            ),
        ]
    }

    /// Whether `found` (a file HDF5 opened) is `name` in the output directory.
    fn is_in_dir(&self, found: &Path, name: &str) -> bool {
        let here = self.dir.join(name);
        match (found.canonicalize(), here.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }

    /// The split layout's mesh and step files of the run's start, written
    /// into the stage as needed: new (no restart), or those of the restart
    /// checkpoint: kept where they already are the output directory's
    /// files of this name, copied from another directory, or taken out of
    /// a single-file checkpoint. Returns the staged file names.
    fn start_split(&mut self) -> Result<Vec<String>, RunError> {
        let name = self.name().to_string();
        let mesh_file = io::hdf5::mesh_file_name(&name);
        let mut staged = vec![];
        let mut steps = vec![];
        let files = match &self.base {
            Some(b) => Some((b.clone(), io::hdf5::checkpoint_files(b)?)),
            None => None,
        };
        let mesh_kept = files
            .as_ref()
            .is_some_and(|(_, f)| self.is_in_dir(&f.mesh, &mesh_file));
        if !mesh_kept {
            io::hdf5::write_mesh_file(&self.stage_dir.join(&mesh_file), self.om)?;
            staged.push(mesh_file);
        }
        if let Some((base, files)) = files {
            let single = base.canonicalize().ok();
            for (i, group, found) in &files.steps {
                let f = io::hdf5::step_file_name(&name, *i);
                if self.is_in_dir(found, &f) {
                    steps.push((*i, f));
                    continue;
                }
                let to = self.stage_dir.join(&f);
                if found.canonicalize().ok() == single {
                    // A single-file checkpoint: the step group taken out.
                    let (s, fr) = io::hdf5::read_step_of(&base, self.om, group)?;
                    io::hdf5::write_step_file(&to, self.om, *i, &s, fr.as_ref())?;
                } else {
                    std::fs::copy(found, &to).map_err(|e| {
                        RunError::Output(format!(
                            "{}: cannot copy the checkpoint's step file: {e}",
                            found.display()
                        ))
                    })?;
                }
                staged.push(f.clone());
                steps.push((*i, f));
            }
        }
        self.split = Some(steps);
        Ok(staged)
    }

    /// The index of the split layout, staged (its name).
    fn write_index(&self) -> Result<String, RunError> {
        let steps = self.split.as_deref().unwrap_or_default();
        let attrs = self.attrs();
        let attrs: Vec<(&str, String)> = attrs.iter().map(|(k, v)| (*k, v.clone())).collect();
        io::hdf5::write_index(
            &self.staged,
            self.om,
            &attrs,
            &io::hdf5::mesh_file_name(self.name()),
            steps,
        )?;
        Ok(fname(&self.staged))
    }
}

impl StepObserver for CheckpointWriter<'_> {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        let fo = crate::post::friction::friction_output(step.model, step.result);
        let friction = fo.map(|f| crate::output::StepFriction {
            multipliers_t: f.lambda_t,
            tangential_traction: f.tangential_traction,
            slip: f.slip,
            state: f.state,
        });
        let index = step.index + 1;
        let t = std::time::Instant::now();
        if step.multi {
            let mut names = match self.split {
                Some(_) => vec![],
                None => self.start_split()?,
            };
            let f = io::hdf5::step_file_name(self.name(), index);
            io::hdf5::write_step_file(
                &self.stage_dir.join(&f),
                self.om,
                index,
                step.output,
                friction.as_ref(),
            )?;
            // A restart from an earlier step rewrites the history after it.
            let steps = self.split.get_or_insert_with(Vec::new);
            steps.retain(|s| s.0 < index);
            steps.push((index, f.clone()));
            names.push(f);
            // The index last: committed after the files it links to.
            names.push(self.write_index()?);
            log::debug!("checkpoint step {:.3} s", t.elapsed().as_secs_f64());
            return Ok(names);
        }
        // The staged checkpoint: a copy of the one this step extends, or new.
        if !self.staged.exists() {
            match &self.base {
                Some(b) => self.copy_base(b)?,
                None => create_checkpoint(self.prep, &self.staged, self.om, &self.fingerprint)?,
            }
        }
        match &friction {
            Some(f) => {
                io::hdf5::append_step_with_friction_in_place(&self.staged, index, step.output, f)?
            }
            None => io::hdf5::append_step_in_place(&self.staged, index, step.output)?,
        }
        Ok(vec![fname(&self.staged)])
    }

    /// A checkpoint restarted from elsewhere is still copied to the output
    /// directory, as a run would have left it (a split one with its files).
    fn on_nothing_to_do(&mut self, restart: &Restart) -> Result<Vec<String>, RunError> {
        if restart.path.canonicalize().ok() == self.target.canonicalize().ok() {
            return Ok(vec![]);
        }
        let files = io::hdf5::checkpoint_files(&restart.path)?;
        let single = restart.path.canonicalize().ok();
        let is_single = files.mesh.canonicalize().ok() == single
            && files
                .steps
                .iter()
                .all(|s| s.2.canonicalize().ok() == single);
        if is_single {
            self.copy_base(&restart.path)?;
            return Ok(vec![fname(&self.staged)]);
        }
        let mut names = self.start_split()?;
        names.push(self.write_index()?);
        Ok(names)
    }
}

/// The VTU pair of each step (`NAME.vtu`, `NAME_contact.vtu`; with load
/// steps `NAME_NNNN.vtu`, … and the time series `NAME.pvd`).
pub struct VtuWriter<'a> {
    om: &'a OutMesh,
    name: String,
    stage_dir: PathBuf,
    dir: PathBuf,
    compress: bool,
    /// Pseudo-time of every load step (the PVD lists steps 1..=k).
    times: Vec<f64>,
    /// The mesh arrays of the bulk VTU, encoded at the first of several
    /// load steps (uncompressed files): the later steps encode their
    /// fields only.
    parts: Option<io::vtu::VtuMeshParts>,
    /// The checkpoint a restart continues and the steps it holds, until
    /// their VTU pairs are in the output directory (then None).
    restart: Option<(PathBuf, usize)>,
    /// The problem has load steps (a time series of step files).
    multi: bool,
}

impl<'a> VtuWriter<'a> {
    /// Writes into `stage_dir` the files whose final place is in `dir`.
    pub fn new(
        prep: &Prepared,
        om: &'a OutMesh,
        stage_dir: &Path,
        dir: &Path,
        compress: bool,
    ) -> Self {
        let file = &prep.problem.file;
        VtuWriter {
            om,
            name: prep.problem.name.clone(),
            stage_dir: stage_dir.to_path_buf(),
            dir: dir.to_path_buf(),
            compress,
            times: (0..file.nsteps()).map(|s| file.step_time(s)).collect(),
            parts: None,
            restart: None,
            multi: !file.steps.is_empty(),
        }
    }

    /// The run continues the checkpoint of `restart`: the time series
    /// lists its steps too, so their VTU pairs must lie beside it. Those of
    /// a restart in place are there already; for a checkpoint in another
    /// directory they are copied from beside it, and a pair found nowhere
    /// is written again from the checkpoint's step (every field but the
    /// reactions, which the checkpoint does not keep).
    pub fn restart(mut self, restart: Option<&Restart>) -> Self {
        self.restart = restart.map(|r| (r.path.clone(), r.steps_done));
        self
    }

    /// Stages the VTU pairs of the restart's steps that the output
    /// directory lacks (see [`VtuWriter::restart`]); their names.
    fn restart_pairs(&mut self) -> Result<Vec<String>, RunError> {
        let Some((path, k)) = self.restart.take() else {
            return Ok(vec![]);
        };
        let in_place = same_dir(&path, &self.dir);
        let mut names = vec![];
        for i in 1..=k {
            let fin = output_paths(&self.dir, &self.name, Some(i));
            if in_place && fin.vtu.is_file() && fin.contact_vtu.is_file() {
                continue;
            }
            let staged = output_paths(&self.stage_dir, &self.name, Some(i));
            names.push(fname(&staged.vtu));
            names.push(fname(&staged.contact_vtu));
            // The pair the run that wrote the checkpoint left beside it:
            // copied as it is (it has the reactions, which the checkpoint
            // does not keep).
            let src = output_paths(path.parent().unwrap_or(Path::new(".")), &self.name, Some(i));
            if !in_place && src.vtu.is_file() && src.contact_vtu.is_file() {
                for (from, to) in [
                    (&src.vtu, &staged.vtu),
                    (&src.contact_vtu, &staged.contact_vtu),
                ] {
                    std::fs::copy(from, to).map_err(|e| {
                        RunError::Output(format!(
                            "{}: cannot copy the restart's step file: {e}",
                            from.display()
                        ))
                    })?;
                }
                continue;
            }
            let (out, fr) = io::hdf5::read_step_of(&path, self.om, &io::hdf5::step_name(i))?;
            let arrays = fr.as_ref().map(|f| io::vtu::FrictionArrays {
                tangential_traction: &f.tangential_traction,
                slip: &f.slip,
                state: &f.state,
            });
            self.write_pair(&staged, &out, arrays.as_ref(), true)?;
        }
        Ok(names)
    }

    /// One step's VTU pair at `paths`: the bulk file (with the mesh arrays
    /// encoded once for a time series, `series`) and the contact file with
    /// the friction arrays, if any.
    fn write_pair(
        &mut self,
        paths: &Outputs,
        out: &crate::output::StepOutput,
        arrays: Option<&io::vtu::FrictionArrays<'_>>,
        series: bool,
    ) -> Result<(), RunError> {
        if series && !self.compress && self.parts.is_none() {
            self.parts = Some(io::vtu::VtuMeshParts::new(self.om));
        }
        io::vtu::write_vtu_with(&paths.vtu, self.om, out, self.compress, self.parts.as_ref())?;
        io::vtu::write_contact_vtu_with_friction(
            &paths.contact_vtu,
            self.om,
            out,
            arrays,
            self.compress,
        )?;
        Ok(())
    }

    /// The time series of steps `0..=s` (0-based), staged: every pair it
    /// names is in the output directory or staged beside it.
    fn write_pvd(&self, s: usize, time: f64) -> Result<String, RunError> {
        let entries: Vec<(f64, String)> = (0..=s)
            .filter_map(|k| {
                let o = output_paths(&self.dir, &self.name, Some(k + 1));
                let t = self.times.get(k).copied().unwrap_or(time);
                let staged = output_paths(&self.stage_dir, &self.name, Some(k + 1));
                let here = |fin: &Path, st: &Path| fin.is_file() || st.is_file();
                (here(&o.vtu, &staged.vtu) && here(&o.contact_vtu, &staged.contact_vtu))
                    .then(|| [(t, fname(&o.vtu)), (t, fname(&o.contact_vtu))])
            })
            .flatten()
            .collect();
        let pvd = format!("{}.pvd", self.name);
        io::vtu::write_pvd(&self.stage_dir.join(&pvd), &entries)?;
        Ok(pvd)
    }
}

impl StepObserver for VtuWriter<'_> {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        let s = step.index;
        let staged = output_paths(&self.stage_dir, &self.name, step.multi.then_some(s + 1));
        let t = std::time::Instant::now();
        let earlier = if step.multi {
            self.restart_pairs()?
        } else {
            vec![]
        };
        let fo = crate::post::friction::friction_output(step.model, step.result);
        let arrays = fo.as_ref().map(|f| io::vtu::FrictionArrays {
            tangential_traction: &f.tangential_traction,
            slip: &f.slip,
            state: &f.state,
        });
        self.write_pair(&staged, step.output, arrays.as_ref(), step.multi)?;
        log::debug!("VTU pair {:.3} s", t.elapsed().as_secs_f64());
        let mut names = earlier;
        names.extend([fname(&staged.vtu), fname(&staged.contact_vtu)]);
        if step.multi {
            names.push(self.write_pvd(s, step.time)?);
        }
        Ok(names)
    }

    /// A restart with nothing left to solve, into another directory: the
    /// checkpoint's VTU pairs and time series are written there too.
    fn on_nothing_to_do(&mut self, restart: &Restart) -> Result<Vec<String>, RunError> {
        // A single solve's VTU pair is no series (and nothing to continue).
        if !self.multi || restart.steps_done == 0 {
            return Ok(vec![]);
        }
        if self.restart.is_none() {
            self.restart = Some((restart.path.clone(), restart.steps_done));
        }
        let mut names = self.restart_pairs()?;
        if names.is_empty() && same_dir(&restart.path, &self.dir) {
            return Ok(names);
        }
        names.push(self.write_pvd(restart.steps_done - 1, 0.0)?);
        Ok(names)
    }
}

/// The JSON summary `NAME.json` (docs/problem-format.md §7): the run's last
/// file, its commit record.
pub struct SummaryWriter {
    path: PathBuf,
}

impl SummaryWriter {
    pub fn new(prep: &Prepared, stage_dir: &Path) -> Self {
        SummaryWriter {
            path: output_paths(stage_dir, &prep.problem.name, None).json,
        }
    }
}

impl StepObserver for SummaryWriter {
    fn on_step(&mut self, _step: &Step<'_>) -> Result<Vec<String>, RunError> {
        Ok(vec![])
    }

    /// A restart with nothing left to solve, from another directory: the
    /// summary beside its checkpoint (of the run that wrote it) comes
    /// along with the checkpoint, if there is one.
    fn on_nothing_to_do(&mut self, restart: &Restart) -> Result<Vec<String>, RunError> {
        let name = fname(&self.path);
        let Some(dir) = self.path.parent() else {
            return Ok(vec![]);
        };
        let src = restart.path.with_file_name(&name);
        // The staging directory lies in the output directory (or is it,
        // without a transaction).
        let out = dir.parent().unwrap_or(dir);
        if same_dir(&restart.path, dir) || same_dir(&restart.path, out) || !src.is_file() {
            return Ok(vec![]);
        }
        std::fs::copy(&src, &self.path).map_err(|e| {
            RunError::Output(format!(
                "{}: cannot copy the restart's summary: {e}",
                src.display()
            ))
        })?;
        Ok(vec![name])
    }

    fn on_finish(&mut self, summary: &Summary) -> Result<Vec<String>, RunError> {
        let text = summary
            .to_json()
            .map_err(|e| RunError::Output(format!("JSON summary: {e}")))?;
        atomic::write_atomic_bytes(&self.path, text.as_bytes())?;
        Ok(vec![fname(&self.path)])
    }
}

/// Two observers whose step files are independent (the VTU pair and the
/// checkpoint), run on two threads for each step: at 1–2 M DOFs each
/// writes hundreds of MB, so the write phase takes the longer of the two
/// rather than their sum. The files are the same as sequentially: each
/// observer writes only its own files, the names come back in the order
/// `first`, `second` (so the commit order is unchanged), and of two errors
/// the first's is reported, as if they had run one after the other.
pub struct Concurrent<A, B>(pub A, pub B);

impl<A, B> StepObserver for Concurrent<A, B>
where
    A: StepObserver + Send,
    B: StepObserver + Send,
{
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        let (a, b) = (&mut self.0, &mut self.1);
        let (ra, rb) = std::thread::scope(|s| {
            let hb = s.spawn(|| {
                let t = std::time::Instant::now();
                let r = b.on_step(step);
                log::debug!("output (second thread) {:.3} s", t.elapsed().as_secs_f64());
                r
            });
            let t = std::time::Instant::now();
            let ra = a.on_step(step);
            log::debug!("output (first thread) {:.3} s", t.elapsed().as_secs_f64());
            let rb = match hb.join() {
                Ok(r) => r,
                Err(panic) => std::panic::resume_unwind(panic),
            };
            (ra, rb)
        });
        let mut names = ra?;
        names.extend(rb?);
        Ok(names)
    }

    fn on_finish(&mut self, summary: &Summary) -> Result<Vec<String>, RunError> {
        let mut names = self.0.on_finish(summary)?;
        names.extend(self.1.on_finish(summary)?);
        Ok(names)
    }

    fn on_nothing_to_do(&mut self, restart: &Restart) -> Result<Vec<String>, RunError> {
        let mut names = self.0.on_nothing_to_do(restart)?;
        names.extend(self.1.on_nothing_to_do(restart)?);
        Ok(names)
    }
}
