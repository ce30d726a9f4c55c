//! Helpers shared by the integration tests: where the shipped files are, the
//! `signorini` binary run with or without a time budget, a seeded xorshift
//! generator, vector norms, and a Matrix Market reader independent of
//! `signorini::io::mtx` (so a test can check the exporter with other code).
//! Each test binary declares `mod common;` and uses the part it needs.
#![allow(dead_code)] // Each test binary compiles all of this and uses a part.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Prepare and solve a problem file in-process with the method `choice`
/// picks (default: the file's own), asserting that the method converged.
pub fn solve_file(
    path: &Path,
    choice: &signorini::qp::SolverSection,
) -> (signorini::run::Prepared, signorini::qp::QpResult) {
    use signorini::run;
    let prep = run::prepare(path, false).unwrap_or_else(|e| panic!("{e}"));
    let (method, opts) = run::options(&prep.problem, choice).unwrap();
    let res = run::solve(&prep, method, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        res.status.converged(),
        "{}: {:?}",
        path.display(),
        res.status
    );
    (prep, res)
}

/// The `signorini` binary Cargo built for these tests.
pub fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_signorini")
}

/// A command for the `signorini` binary, to add arguments to.
///
/// Without HDF5's file locks: a test that edits a checkpoint in this
/// process holds an flock on it while the file is open, and a child that
/// another test spawns in that moment inherits the descriptor (HDF5 does
/// not open with O_CLOEXEC) and keeps the lock while it runs; the restart
/// that reads the edited file then failed with "unable to lock file"
/// (tests/faults.rs, once in CI). The lock guards against concurrent
/// writers, which the tests do not have; the product keeps it.
pub fn command() -> Command {
    let mut c = Command::new(exe());
    c.env("HDF5_USE_FILE_LOCKING", "FALSE");
    c
}

/// The crate's root directory.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The shipped examples' directory, `meshes/`.
pub fn meshes() -> PathBuf {
    root().join("meshes")
}

/// The path of the shipped example `meshes/NAME.toml`, as a string argument.
pub fn example(name: &str) -> String {
    meshes().join(format!("{name}.toml")).display().to_string()
}

/// The Gmsh fixture `tests/data/msh/NAME`.
pub fn msh_fixture(name: &str) -> PathBuf {
    root().join("tests/data/msh").join(name)
}

/// The `*.toml` files of `dir`, sorted.
pub fn tomls_in(dir: &Path) -> Vec<PathBuf> {
    let mut tomls: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    tomls.sort();
    tomls
}

/// Exit code (-1 when a signal ended the process), stdout and stderr.
pub fn split(o: &Output) -> (i32, String, String) {
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Exit code (-1 when a signal ended the process) and stdout + stderr.
pub fn joined(o: &Output) -> (i32, String) {
    let (code, stdout, stderr) = split(o);
    (code, format!("{stdout}{stderr}"))
}

/// Runs `signorini ARGS`: (exit code, stdout, stderr).
pub fn signorini(args: &[&str]) -> (i32, String, String) {
    split(&command().args(args).output().expect("run signorini"))
}

/// Runs `signorini ARGS` in the directory `dir`: (exit code, stdout, stderr).
pub fn signorini_in(dir: &str, args: &[&str]) -> (i32, String, String) {
    split(
        &command()
            .args(args)
            .current_dir(dir)
            .output()
            .expect("run signorini"),
    )
}

/// Runs `signorini ARGS`: (exit code, stdout + stderr).
pub fn run(args: &[&str]) -> (i32, String) {
    joined(&command().args(args).output().expect("run signorini"))
}

/// Runs `signorini ARGS` and panics when it still runs after `deadline` (a
/// FIFO must not block a run forever): (exit code, stdout + stderr).
pub fn run_with_deadline(args: &[&str], deadline: Duration) -> (i32, String) {
    let mut child = command()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if t0.elapsed() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("signorini {args:?} still runs after {deadline:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    joined(&child.wait_with_output().unwrap())
}

/// How one run of the binary ended.
#[derive(Debug, Clone)]
pub struct Run {
    /// Exit code; `None` when the process was killed (budget) or died by a signal.
    pub code: Option<i32>,
    /// Killed because it outlived its budget.
    pub hung: bool,
    /// Wall time of the run (reported only; no decision depends on it but the kill).
    pub secs: f64,
    /// Standard output and error, concatenated.
    pub output: String,
}

/// Run `signorini ARGS` with a time budget: the child is killed when it
/// outlives `budget`, so a hanging method cannot hang the test. Output goes
/// to files in `scratch` (no pipe can fill up and block the child).
pub fn run_signorini(args: &[String], budget: Duration, scratch: &Path) -> Run {
    std::fs::create_dir_all(scratch).expect("scratch directory");
    let out_path = scratch.join("stdout.txt");
    let err_path = scratch.join("stderr.txt");
    let stdout = std::fs::File::create(&out_path).expect("stdout file");
    let stderr = std::fs::File::create(&err_path).expect("stderr file");
    let start = Instant::now();
    let mut child = command()
        .args(args)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .expect("start signorini");
    let mut hung = false;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for signorini") {
            break Some(s);
        }
        if start.elapsed() > budget {
            let _ = child.kill();
            let _ = child.wait();
            hung = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let output = format!(
        "{}{}",
        std::fs::read_to_string(&out_path).unwrap_or_default(),
        std::fs::read_to_string(&err_path).unwrap_or_default()
    );
    Run {
        code: status.and_then(|s| s.code()),
        hung,
        secs: start.elapsed().as_secs_f64(),
        output,
    }
}

/// xorshift64: a small reproducible generator for fuzzing and random data.
pub struct XorShift(pub u64);

impl XorShift {
    /// The generator started from splitmix64 of `seed`, so that nearby seeds
    /// give unrelated streams.
    pub fn seeded(seed: u64) -> XorShift {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        XorShift((z ^ (z >> 31)) | 1)
    }
    /// The next 64 bits.
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    /// A number in 0..n (0 when n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    /// An element of the non-empty `v`.
    pub fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// ‖a − b‖ / ‖b‖; 0 when both are zero, infinite when only `b` is zero or
/// the lengths differ.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let s = norm(b);
    if s == 0.0 {
        if norm(&d) == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    } else {
        norm(&d) / s
    }
}

/// A Matrix Market file written by `signorini export`, as (rows, cols,
/// triplets): coordinate files with the symmetric half expanded, array files
/// in their column-major order.
pub fn read_mtx(path: &Path) -> (usize, usize, Vec<(usize, usize, f64)>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_lowercase();
    let symmetric = header.contains("symmetric");
    let array = header.contains("array");
    let mut lines = lines.filter(|l| !l.starts_with('%') && !l.trim().is_empty());
    let size: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|s| s.parse().unwrap())
        .collect();
    let (nr, nc) = (size[0], size[1]);
    let mut t = Vec::new();
    if array {
        // Column-major dense.
        for (k, l) in lines.enumerate() {
            t.push((k % nr, k / nr, l.trim().parse::<f64>().unwrap()));
        }
    } else {
        for l in lines {
            let f: Vec<&str> = l.split_whitespace().collect();
            let (i, j) = (
                f[0].parse::<usize>().unwrap() - 1,
                f[1].parse::<usize>().unwrap() - 1,
            );
            let a: f64 = f[2].parse().unwrap();
            t.push((i, j, a));
            if symmetric && i != j {
                t.push((j, i, a));
            }
        }
    }
    (nr, nc, t)
}

/// A Matrix Market vector (one column) as a dense vector.
pub fn read_vec(path: &Path) -> Vec<f64> {
    let (nr, _, t) = read_mtx(path);
    let mut v = vec![0.0; nr];
    for (i, _, a) in t {
        v[i] = a;
    }
    v
}

/// A dense Matrix Market array as (rows, cols, values in column-major order);
/// asserts that it holds rows × cols values.
pub fn read_array(path: &Path) -> (usize, usize, Vec<f64>) {
    let (nr, nc, t) = read_mtx(path);
    let v: Vec<f64> = t.into_iter().map(|(_, _, a)| a).collect();
    assert_eq!(v.len(), nr * nc);
    (nr, nc, v)
}

/// A variant of the model `dir/toml` written to `out`: each (from, to) edit
/// applied (each `from` must occur), and the mesh file made absolute so the
/// variant can live anywhere.
pub fn model_variant(dir: &Path, toml: &str, edits: &[(&str, &str)], out: &Path) -> PathBuf {
    let mut text = std::fs::read_to_string(dir.join(toml)).expect("read the model");
    for (from, to) in edits {
        assert!(text.contains(from), "{toml}: no {from:?} to edit");
        text = text.replace(from, to);
    }
    let text: String = text
        .lines()
        .map(|l| match l.strip_prefix("file = \"") {
            Some(rest) => format!("file = {:?}\n", dir.join(rest.trim_end_matches('"'))),
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(out, text).expect("write the variant");
    out.to_path_buf()
}

/// meshes/two_blocks with the upper block held only by the contact and a
/// shear traction on top; `law` is the friction line of the interface.
pub fn sheared_blocks(law: &str, contact: bool) -> String {
    let c = if contact {
        format!("[[contact]]\non = \"interface\"\n{law}\n")
    } else {
        String::new()
    };
    format!(
        r#"[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.lower]
E = 2.0e9
nu = 0.25
[materials.upper]
E = 2.0e9
nu = 0.25
[[dirichlet]]
on = "bottom"
u = [0.0, 0.0]
[[slip]]
on = "left_lower"
[[slip]]
on = "right_lower"
[[traction]]
on = "top"
p = [1.0e5, -1.0e6]
{c}"#
    )
}

/// Hertz's ball on a block of tests/data/solid_contact (`msh`: hertz.msh or
/// hertz_coarse.msh; the TOML of scripts/bench_solid.py): steel on steel
/// between three slip planes, the pressure `pn` on "ball_top", the ball
/// held by the `[[contact]]` entry slave "ball", master "block_top",
/// `discretization`; `tail` is appended as it is (more keys of that entry
/// first, then tables).
pub fn hertz_toml(msh: &Path, pn: f64, discretization: &str, tail: &str) -> String {
    format!(
        r#"[mesh]
file = "{}"

[materials.ball]
E = 2.0e11
nu = 0.3

[materials.block]
E = 2.0e11
nu = 0.3

[[slip]]
on = "x0"

[[slip]]
on = "y0"

[[slip]]
on = "block_bottom"

[[traction]]
on = "ball_top"
pn = {pn:e}

[[contact]]
slave = "ball"
master = "block_top"
discretization = "{discretization}"
{tail}"#,
        msh.display()
    )
}

/// The stacked cubes of tests/data/solid_contact (`msh`: stack.msh,
/// conforming, or stack_nm.msh, meshed apart): steel (lower) under
/// aluminium (upper) on three slip planes, the pressure `pn` on "top", the
/// upper cube held along z by the contact entry `contact` alone; `tail` is
/// appended as it is (an `[output]` table, `[[steps]]`).
pub fn solid_stack_toml(msh: &Path, contact: &str, pn: f64, tail: &str) -> String {
    format!(
        r#"[mesh]
file = "{}"

[materials.lower]
E = 2.0e11
nu = 0.3

[materials.upper]
E = 7.0e10
nu = 0.25

[[slip]]
on = "x0"

[[slip]]
on = "y0"

[[slip]]
on = "bottom"

[[traction]]
on = "top"
pn = {pn}

[[contact]]
{contact}
{tail}"#,
        msh.display()
    )
}

/// A soft cube (E = 2·10⁷ Pa, ν = 0.45) on a steel one: the stacked cubes
/// meshed apart (tests/data/solid_contact/stack_nm.msh), the steel held at
/// its bottom, the planes `slip` slip planes, mortar rows with Coulomb
/// μ = 0.3, a pressure of 10⁶ Pa and the shear `pt` on top; `tail`
/// follows.
pub fn soft_cube_toml(slip: [&str; 2], pt: [f64; 2], tail: &str) -> String {
    format!(
        r#"[mesh]
file = "{}"

[materials.lower]
E = 2.0e11
nu = 0.3

[materials.upper]
E = 2.0e7
nu = 0.45

[[dirichlet]]
on = "bottom"
u = [0.0, 0.0, 0.0]

[[slip]]
on = "{}"

[[slip]]
on = "{}"

[[traction]]
on = "top"
p = [{:e}, {:e}, -1.0e6]

[[contact]]
slave = "upper_bottom"
master = "lower_top"
discretization = "mortar"
friction = 0.3
{tail}"#,
        root()
            .join("tests/data/solid_contact/stack_nm.msh")
            .display(),
        slip[0],
        slip[1],
        pt[0],
        pt[1]
    )
}
