//! The run API (`signorini::run`) without the binary: load steps, restart
//! from a checkpoint written by the library's own observer, observers that
//! count and that fail, and the run's own settings refused as bad input.

use signorini::post;
use signorini::run::{
    self, CheckpointWriter, Prepared, Restart, Run, RunError, Step, StepObserver, Summary, Verdict,
};
use std::path::PathBuf;

fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/three_bodies_steps.toml")
}

fn prepared() -> (
    Prepared,
    signorini::qp::MethodId,
    signorini::qp::SolveOptions,
) {
    let prep = run::prepare(&example(), false).unwrap_or_else(|e| panic!("{e}"));
    let (method, opts) =
        run::options(&prep.problem, &signorini::qp::SolverSection::default()).unwrap();
    (prep, method, opts)
}

/// Counts the steps it is shown (their 0-based numbers) and the finishes.
#[derive(Default)]
struct Count {
    steps: Vec<usize>,
    times: Vec<f64>,
    finished: usize,
    /// Fail at this step (0-based).
    fail_at: Option<usize>,
}

impl StepObserver for Count {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        if self.fail_at == Some(step.index) {
            return Err(RunError::Output(format!("refused step {}", step.index + 1)));
        }
        self.steps.push(step.index);
        self.times.push(step.time);
        assert_eq!(step.output.displacement.len(), step.model.topo.points.len());
        Ok(vec![])
    }
    fn on_finish(&mut self, _summary: &Summary) -> Result<Vec<String>, RunError> {
        self.finished += 1;
        Ok(vec![])
    }
}

/// A transaction on the output name `name` in `out`, a new directory of a
/// temporary one (kept alive by the first value).
fn transaction(name: &str) -> (tempfile::TempDir, PathBuf, signorini::run::Transaction) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let tx = signorini::run::Transaction::open(&out, name).unwrap_or_else(|e| panic!("{e}"));
    (dir, out, tx)
}

fn bits(v: &[[f64; 2]]) -> Vec<[u64; 2]> {
    v.iter().map(|p| [p[0].to_bits(), p[1].to_bits()]).collect()
}

fn bits1(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Solve to step k writing a checkpoint, restart from it to the end: the
/// last step equals (bits) the one of an uninterrupted run.
#[test]
fn restart_from_the_checkpoint_equals_the_uninterrupted_run() {
    let (prep, method, opts) = prepared();
    let nsteps = prep.problem.file.nsteps();
    assert!(nsteps >= 3, "{nsteps} steps");
    let mut all = Count::default();
    let full = Run::new(&prep, method, &opts)
        .solve(&mut [&mut all], None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(all.steps, (0..nsteps).collect::<Vec<_>>());
    let times: Vec<f64> = (0..nsteps)
        .map(|s| prep.problem.file.step_time(s))
        .collect();
    assert_eq!(all.times, times);
    assert_eq!(all.finished, 1);
    assert!(full.certified);
    assert_eq!(full.steps, 0..nsteps);

    let k = 2;
    let dir = tempfile::tempdir().unwrap();
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let mut ck = CheckpointWriter::new(&prep, &om, dir.path(), dir.path(), None);
    let mut first = Count::default();
    let part = Run::new(&prep, method, &opts)
        .max_steps(Some(k))
        .solve(&mut [&mut ck, &mut first], None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first.steps, (0..k).collect::<Vec<_>>());
    assert_eq!(part.steps, 0..k);

    let h5 = dir.path().join(format!("{}.h5", prep.problem.name));
    let restart = Restart::read(&h5, &prep).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(restart.steps_done, k);
    let mut rest = Count::default();
    let second = Run::new(&prep, method, &opts)
        .restart(Some(restart))
        .solve(&mut [&mut rest], None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rest.steps, (k..nsteps).collect::<Vec<_>>());
    assert_eq!(second.steps, k..nsteps);

    let (a, b) = (full.last.unwrap(), second.last.unwrap());
    assert_eq!(bits(&a.output.displacement), bits(&b.output.displacement));
    assert_eq!(bits1(&a.output.multipliers), bits1(&b.output.multipliers));
    assert_eq!(bits1(&a.result.x), bits1(&b.result.x));
    assert_eq!(a.result.energy.to_bits(), b.result.energy.to_bits());
    // The summaries agree but for the timings and the rows of the steps
    // the restart did not solve.
    let (sa, sb) = (full.summary.unwrap(), second.summary.unwrap());
    let (ra, rb) = (sa.steps.clone().unwrap(), sb.steps.clone().unwrap());
    assert_eq!(ra.len(), nsteps);
    assert_eq!(rb.len(), nsteps - k);
    let json = |s: &Summary| {
        let mut v = serde_json::to_value(s).unwrap();
        let o = v.as_object_mut().unwrap();
        o.remove("timings_s").expect("timings_s");
        o.remove("steps").expect("steps");
        v
    };
    assert_eq!(json(&sa), json(&sb));
    // Each row agrees but for its wall-clock times (time_solve, time_step).
    let row = |r: &signorini::run::StepRow| {
        let mut v = serde_json::to_value(r).unwrap();
        let o = v.as_object_mut().unwrap();
        o.remove("time_solve").expect("time_solve");
        o.remove("time_step").expect("time_step");
        v
    };
    for (x, y) in ra[k..].iter().zip(&rb) {
        assert_eq!(row(x), row(y));
    }
}

/// A restart that already holds the steps asked for solves nothing.
#[test]
fn a_restart_past_max_steps_has_nothing_to_do() {
    let (prep, method, opts) = prepared();
    let dir = tempfile::tempdir().unwrap();
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let mut ck = CheckpointWriter::new(&prep, &om, dir.path(), dir.path(), None);
    Run::new(&prep, method, &opts)
        .max_steps(Some(2))
        .solve(&mut [&mut ck], None)
        .unwrap_or_else(|e| panic!("{e}"));
    let h5 = dir.path().join(format!("{}.h5", prep.problem.name));
    let restart = Restart::read(&h5, &prep).unwrap_or_else(|e| panic!("{e}"));
    let mut count = Count::default();
    let out = Run::new(&prep, method, &opts)
        .restart(Some(restart))
        .max_steps(Some(1))
        .solve(&mut [&mut count], None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(out.steps.is_empty(), "{:?}", out.steps);
    assert!(out.last.is_none() && out.summary.is_none());
    assert!(count.steps.is_empty() && count.finished == 0);
}

/// An observer's error ends the run at that step, and is returned.
#[test]
fn an_observer_error_stops_the_run() {
    let (prep, method, opts) = prepared();
    let mut count = Count {
        fail_at: Some(1),
        ..Default::default()
    };
    let err = match Run::new(&prep, method, &opts).solve(&mut [&mut count], None) {
        Ok(_) => panic!("the run went on after the observer failed"),
        Err(e) => e,
    };
    assert_eq!(err.to_string(), "refused step 2");
    assert_eq!(err.exit_code(), run::EXIT_BAD_INPUT);
    assert_eq!(count.steps, vec![0]);
    assert_eq!(count.finished, 0);
}

/// The run's own settings are checked: a KKT target must be positive, and
/// steps count from 1; a checkpoint of another problem is refused.
#[test]
fn bad_run_settings_are_bad_input() {
    let (prep, method, opts) = prepared();
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut o = opts.clone();
        o.settings.kkt_target = t;
        let e = Run::new(&prep, method, &o)
            .solve(&mut [], None)
            .err()
            .unwrap_or_else(|| panic!("kkt_target {t} accepted"));
        assert!(e.to_string().contains("KKT target"), "{e}");
    }
    let e = Run::new(&prep, method, &opts)
        .max_steps(Some(0))
        .solve(&mut [], None)
        .err()
        .expect("max_steps 0 accepted");
    assert!(e.to_string().contains("count from 1"), "{e}");

    // A checkpoint of two_blocks is not one of three_bodies_steps.
    let other = run::prepare(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/two_blocks.toml"),
        false,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let om = post::out_mesh(&other.model, &other.mesh);
    let mut ck = CheckpointWriter::new(&other, &om, dir.path(), dir.path(), None);
    let (m2, o2) = run::options(&other.problem, &signorini::qp::SolverSection::default()).unwrap();
    Run::new(&other, m2, &o2)
        .solve(&mut [&mut ck], None)
        .unwrap_or_else(|e| panic!("{e}"));
    let e = Restart::read(&dir.path().join("two_blocks.h5"), &prep).expect_err("accepted");
    assert!(e.to_string().contains("does not match"), "{e}");
    assert_eq!(e.exit_code(), 2);
}

/// The CLI's outputs through the library: the writers observe the run and a
/// transaction commits each load step; the directory then holds the
/// complete files and no staging directory.
#[test]
fn the_writers_and_a_transaction_leave_every_output() {
    use signorini::run::{SummaryWriter, VtuWriter};
    let (prep, method, opts) = prepared();
    let nsteps = prep.problem.file.nsteps();
    let name = prep.problem.name.clone();
    let (_dir, out, mut tx) = transaction(&name);
    let (sdir, fdir) = (tx.stage_dir().to_path_buf(), tx.dir().to_path_buf());
    let om = post::out_mesh(&prep.model, &prep.mesh);
    assert_ne!(sdir, fdir);
    let mut vtu = VtuWriter::new(&prep, &om, &sdir, &fdir, false);
    let mut ck = CheckpointWriter::new(&prep, &om, &sdir, &fdir, None);
    let mut json = SummaryWriter::new(&prep, &sdir);
    let outcome = Run::new(&prep, method, &opts)
        .solve(&mut [&mut vtu, &mut ck, &mut json], Some(&mut tx))
        .unwrap_or_else(|e| panic!("{e}"));
    tx.finish();
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let mut want = vec![
        format!("{name}.h5"),
        format!("{name}.json"),
        format!("{name}.pvd"),
    ];
    // The checkpoint of a run with load steps is split (docs/problem-format.md §6).
    want.push(format!("{name}_mesh.h5"));
    for k in 1..=nsteps {
        want.push(format!("{name}_{k:04}.h5"));
        want.push(format!("{name}_{k:04}.vtu"));
        want.push(format!("{name}_{k:04}_contact.vtu"));
    }
    want.sort();
    assert_eq!(files, want);
    let text = std::fs::read_to_string(out.join(format!("{name}.json"))).unwrap();
    assert_eq!(text, outcome.summary.unwrap().to_json().unwrap());
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["steps"].as_array().map(Vec::len), Some(nsteps));
    let ck = signorini::io::hdf5::read_checkpoint(&out.join(format!("{name}.h5"))).unwrap();
    assert_eq!(ck.steps.len(), nsteps);
}

/// Sees each step after the writers and records where the committed files
/// stand: which steps' VTUs are in the output directory, and the thread.
struct Committed {
    out: std::path::PathBuf,
    name: String,
    /// Per step seen: (index, VTUs committed so far, on the caller's thread).
    seen: Vec<(usize, Vec<usize>, bool)>,
    caller: std::thread::ThreadId,
}

impl StepObserver for Committed {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        let committed = (1..=step.nsteps)
            .filter(|k| self.out.join(format!("{}_{k:04}.vtu", self.name)).exists())
            .collect();
        let here = std::thread::current().id() == self.caller;
        self.seen.push((step.index, committed, here));
        Ok(vec![])
    }
}

/// A load step's files are written beside the next step's solve
/// (`Run::solve`): every step but the last is handed to the observers on
/// the writer thread, in order; when step k + 1 is, step k's files are
/// committed and no later step's are; the last step is written on the
/// caller's thread with the summary. A write error of a middle step stops
/// the run with that error, and nothing after it is committed.
#[test]
fn a_step_is_written_beside_the_next_one_in_order_and_committed_first() {
    use signorini::run::{Transaction, VtuWriter};
    let (prep, method, opts) = prepared();
    let nsteps = prep.problem.file.nsteps();
    assert!(nsteps >= 3);
    let name = prep.problem.name.clone();
    let (dir, out, mut tx) = transaction(&name);
    let (sdir, fdir) = (tx.stage_dir().to_path_buf(), tx.dir().to_path_buf());
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let mut vtu = VtuWriter::new(&prep, &om, &sdir, &fdir, false);
    let mut spy = Committed {
        out: out.clone(),
        name: name.clone(),
        seen: vec![],
        caller: std::thread::current().id(),
    };
    Run::new(&prep, method, &opts)
        .solve(&mut [&mut vtu, &mut spy], Some(&mut tx))
        .unwrap_or_else(|e| panic!("{e}"));
    tx.finish();
    let order: Vec<usize> = spy.seen.iter().map(|s| s.0).collect();
    assert_eq!(order, (0..nsteps).collect::<Vec<_>>());
    for (k, committed, here) in &spy.seen {
        // Step k + 1 (1-based) is seen after the writer of this step
        // staged its VTU: the steps before it are committed, it is not.
        assert_eq!(committed, &(1..=*k).collect::<Vec<_>>(), "step {}", k + 1);
        assert_eq!(*here, k + 1 == nsteps, "step {}: thread", k + 1);
    }
    // A writer that fails at step 2 of the steps: the run returns its
    // error, step 1 was committed and rolled back with the run, nothing of
    // step 2 or later is left.
    let out2 = dir.path().join("out2");
    let mut tx2 = Transaction::open(&out2, &name).unwrap_or_else(|e| panic!("{e}"));
    let mut count = Count {
        fail_at: Some(1),
        ..Default::default()
    };
    let err = Run::new(&prep, method, &opts)
        .solve(&mut [&mut count], Some(&mut tx2))
        .err()
        .expect("the writer's error");
    assert!(err.to_string().contains("refused step 2"), "{err}");
    assert_eq!(count.steps, vec![0]);
    drop(tx2);
    let left: Vec<_> = std::fs::read_dir(&out2)
        .map(|d| d.filter_map(Result::ok).map(|e| e.file_name()).collect())
        .unwrap_or_default();
    assert!(left.is_empty(), "{left:?}");
}

/// `[solver] ordering = "nested-dissection"` (docs/methods.md §3) changes
/// the factor, not the answer: on a floating wedge (ssn's bordered factor,
/// springs on the rigid modes) and on non-matching rollers, every method
/// that factors C is certified and agrees with its AMD solve to rounding;
/// a second nested-dissection solve repeats the first bit for bit.
#[test]
fn the_nested_dissection_ordering_changes_the_factor_not_the_answer() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes");
    for (model, methods) in [
        (
            "three_bodies.toml",
            &["ssn", "asm", "dual", "mprgp", "preelim", "penalty", "cgc"][..],
        ),
        ("rollers.toml", &["ssn", "dual"][..]),
    ] {
        let prep = run::prepare(&dir.join(model), false).unwrap_or_else(|e| panic!("{e}"));
        for &m in methods {
            let solve = |ordering: &str| {
                let flags = signorini::qp::SolverSection {
                    method: Some(m.parse().unwrap()),
                    preconditioner: (m == "cgc").then(|| "cholesky".parse().unwrap()),
                    ordering: Some(ordering.parse().unwrap()),
                    ..Default::default()
                };
                let (method, opts) = run::options(&prep.problem, &flags).unwrap();
                let res = run::solve(&prep, method, &opts).unwrap_or_else(|e| panic!("{e}"));
                assert!(
                    Verdict::of(method, &res, 1e-6, false).certified(),
                    "{model} {m} {ordering}: {:?} {:?}",
                    res.status,
                    res.kkt
                );
                res
            };
            let (amd, nd) = (solve("amd"), solve("nested-dissection"));
            let scale = amd.x.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let diff = amd
                .x
                .iter()
                .zip(&nd.x)
                .fold(0.0f64, |s, (a, b)| s.max((a - b).abs()));
            assert!(
                diff <= 1e-8 * scale,
                "{model} {m}: max |x_amd − x_nd| = {diff:.3e} of {scale:.3e}"
            );
            assert_eq!(amd.active, nd.active, "{model} {m}");
            if m == "ssn" {
                assert_eq!(bits1(&nd.x), bits1(&solve("nested-dissection").x));
            }
        }
    }
}
