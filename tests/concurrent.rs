//! `run::Concurrent`: two observers run side by side on each step give what
//! they give one after the other: the same files (bytes), the names in the
//! order first, second, and of two errors the first's.

use signorini::io::hdf5::read_checkpoint;
use signorini::post;
use signorini::run::{
    self, CheckpointWriter, Concurrent, Prepared, Run, RunError, Step, StepObserver, VtuWriter,
};
use std::path::{Path, PathBuf};

fn prepared() -> (
    Prepared,
    signorini::qp::MethodId,
    signorini::qp::SolveOptions,
) {
    let toml = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/three_bodies_steps.toml");
    let prep = run::prepare(&toml, false).unwrap_or_else(|e| panic!("{e}"));
    let (method, opts) =
        run::options(&prep.problem, &signorini::qp::SolverSection::default()).unwrap();
    (prep, method, opts)
}

/// Names one file per step (`TAG_k`), and fails at step `fail_at` (0-based).
struct Named {
    tag: &'static str,
    fail_at: Option<usize>,
    seen: Vec<usize>,
}

impl Named {
    fn new(tag: &'static str, fail_at: Option<usize>) -> Named {
        Named {
            tag,
            fail_at,
            seen: vec![],
        }
    }
}

impl StepObserver for Named {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        self.seen.push(step.index);
        if self.fail_at == Some(step.index) {
            return Err(RunError::Output(format!("{} refused", self.tag)));
        }
        Ok(vec![format!("{}_{}", self.tag, step.index + 1)])
    }
}

/// Records the names an observer returns.
struct Spy<O>(O, Vec<Vec<String>>);

impl<O: StepObserver> StepObserver for Spy<O> {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        let names = self.0.on_step(step)?;
        self.1.push(names.clone());
        Ok(names)
    }
}

#[test]
fn names_come_back_first_then_second_on_every_step() {
    let (prep, method, opts) = prepared();
    let nsteps = prep.problem.file.nsteps();
    let mut spy = Spy(
        Concurrent(Named::new("a", None), Named::new("b", None)),
        vec![],
    );
    Run::new(&prep, method, &opts)
        .solve(&mut [&mut spy], None)
        .unwrap_or_else(|e| panic!("{e}"));
    let want: Vec<Vec<String>> = (1..=nsteps)
        .map(|k| vec![format!("a_{k}"), format!("b_{k}")])
        .collect();
    assert_eq!(spy.1, want);
}

#[test]
fn of_two_errors_the_first_is_returned_and_one_error_stops_the_run() {
    let (prep, method, opts) = prepared();
    let mut both = Concurrent(Named::new("a", Some(1)), Named::new("b", Some(1)));
    let err = match Run::new(&prep, method, &opts).solve(&mut [&mut both], None) {
        Ok(_) => panic!("the run went on after both observers failed"),
        Err(e) => e,
    };
    assert_eq!(err.to_string(), "a refused");

    let mut second = Concurrent(Named::new("a", None), Named::new("b", Some(0)));
    let err = match Run::new(&prep, method, &opts).solve(&mut [&mut second], None) {
        Ok(_) => panic!("the run went on after the second observer failed"),
        Err(e) => e,
    };
    assert_eq!(err.to_string(), "b refused");
    assert_eq!((second.0.seen, second.1.seen), (vec![0], vec![0]));
}

fn solve_into(dir: &Path, concurrent: bool) {
    let (prep, method, opts) = prepared();
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let vtu = VtuWriter::new(&prep, &om, dir, dir, false);
    let ck = CheckpointWriter::new(&prep, &om, dir, dir, None);
    let run = Run::new(&prep, method, &opts);
    let out = if concurrent {
        run.solve(&mut [&mut Concurrent(vtu, ck)], None)
    } else {
        let (mut vtu, mut ck) = (vtu, ck);
        run.solve(&mut [&mut vtu, &mut ck], None)
    };
    out.unwrap_or_else(|e| panic!("{e}"));
}

/// The VTU files and PVD are the same bytes, the checkpoint holds the same
/// arrays (its timing attributes differ from run to run).
#[test]
fn the_files_are_those_of_the_sequential_writers() {
    let (seq, par) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    solve_into(seq.path(), false);
    solve_into(par.path(), true);
    let mut names: Vec<String> = std::fs::read_dir(seq.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.iter().filter(|n| n.ends_with(".vtu")).count() >= 4);
    for n in names.iter().filter(|n| !n.ends_with(".h5")) {
        let (a, b) = (
            std::fs::read(seq.path().join(n)).unwrap(),
            std::fs::read(par.path().join(n)).unwrap(),
        );
        assert!(a == b, "{n} differs");
    }
    let h5 = names
        .iter()
        .find(|n| n.ends_with(".h5"))
        .expect("a checkpoint");
    let (a, b) = (
        read_checkpoint(&seq.path().join(h5)).unwrap(),
        read_checkpoint(&par.path().join(h5)).unwrap(),
    );
    assert_eq!(a.steps.len(), b.steps.len());
    for (x, y) in a.steps.iter().zip(&b.steps) {
        let bits =
            |v: &[[f64; 4]]| -> Vec<u64> { v.iter().flatten().map(|z| z.to_bits()).collect() };
        assert_eq!(bits(&x.stress), bits(&y.stress));
        let d = |v: &[[f64; 2]]| -> Vec<u64> { v.iter().flatten().map(|z| z.to_bits()).collect() };
        assert_eq!(d(&x.displacement), d(&y.displacement));
        let m = |v: &[f64]| -> Vec<u64> { v.iter().map(|z| z.to_bits()).collect() };
        assert_eq!(m(&x.multipliers), m(&y.multipliers));
    }
}
