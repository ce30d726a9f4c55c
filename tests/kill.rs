//! Signals (issue 34, at the end): SIGTERM and SIGINT after a commit roll
//! the run back, the directory byte for byte as before.
//!
//! A multi-step run killed with SIGKILL at several moments never leaves a
//! half-written output under its final name, its checkpoint is complete for
//! every step it lists, and `--restart` from it ends where an uninterrupted
//! run ends (10⁻⁸ relative).
//!
//! The kill points are a few fixed delays (which land wherever the run
//! happens to be on this machine) and two that poll the checkpoint and kill
//! as soon as it holds one, resp. two, steps, so at least two kills land
//! after a checkpoint exists. Whatever a kill hits, the assertions are the
//! same.

use signorini::io::hdf5::read_checkpoint;
use signorini::output::Checkpoint;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

mod common;

use common::{command, joined, meshes};

const NAME: &str = "three_bodies_steps";
const NSTEPS: usize = 4;

fn problem() -> PathBuf {
    meshes().join(format!("{NAME}.toml"))
}

fn solve(out: &Path, extra: &[&str]) -> (i32, String) {
    let o = command()
        .arg("solve")
        .arg(problem())
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    joined(&o)
}

/// What a killed run may leave besides its outputs: a staging directory
/// (`.signorini-stage-…`) and its lock file (`.NAME.lock`, whose lock died
/// with the process).
fn is_temporary(name: &str) -> bool {
    name.starts_with(".signorini-stage-") || name == format!(".{NAME}.lock")
}

/// The names a run may leave under their final name.
fn is_output_name(name: &str) -> bool {
    let step_file = |suffix: &str| {
        name.strip_prefix(&format!("{NAME}_"))
            .and_then(|r| r.strip_suffix(suffix))
            .is_some_and(|k| k.len() == 4 && k.bytes().all(|c| c.is_ascii_digit()))
    };
    // The checkpoint of a run with load steps is split (NAME.h5 the index,
    // NAME_mesh.h5, NAME_NNNN.h5 one per step; docs/problem-format.md §6).
    name == format!("{NAME}.h5")
        || name == format!("{NAME}_mesh.h5")
        || step_file(".h5")
        || name == format!("{NAME}.pvd")
        || name == format!("{NAME}.json")
        || step_file(".vtu")
        || step_file("_contact.vtu")
}

/// Every file under its final name in `dir` is complete; returns the
/// checkpoint, if there is one. Temporary files are ignored (they may
/// remain after a kill).
fn check_outputs(dir: &Path, when: &str) -> Option<Checkpoint> {
    let mut ck = None;
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().into_owned();
        let path = e.path();
        if is_temporary(&name) {
            continue;
        }
        assert!(
            is_output_name(&name),
            "{when}: unexpected file {name} in the output directory"
        );
        if name.ends_with(".vtu") {
            let v = signorini::io::vtu::read_vtu_arrays(&path)
                .unwrap_or_else(|e| panic!("{when}: {name} is not a complete VTU: {e}"));
            assert!(v.num_points > 0, "{when}: {name} has no points");
        } else if name.ends_with(".pvd") {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                text.trim_end().ends_with("</VTKFile>"),
                "{when}: {name} is cut short"
            );
            let entries = signorini::io::vtu::read_pvd(&path)
                .unwrap_or_else(|e| panic!("{when}: {name}: {e}"));
            assert!(!entries.is_empty(), "{when}: {name} lists nothing");
            for (_, f) in entries {
                assert!(
                    !is_temporary(&f) && is_output_name(&f),
                    "{when}: {name} lists {f}"
                );
            }
        } else if name.ends_with(".json") {
            let text = std::fs::read_to_string(&path).unwrap();
            let j: serde_json::Value = serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("{when}: {name} is not complete JSON: {e}"));
            assert!(j.get("converged").is_some(), "{when}: {name}");
        } else if name == format!("{NAME}.h5") {
            let c = read_checkpoint(&path)
                .unwrap_or_else(|e| panic!("{when}: checkpoint does not open: {e}"));
            assert!(!c.mesh.points.is_empty(), "{when}: checkpoint without mesh");
            assert!(c.steps.len() <= NSTEPS, "{when}: {} steps", c.steps.len());
            // Steps 1..=k, each complete (read_checkpoint checks every
            // dataset's length against the mesh) and solved.
            for (k, s) in c.steps.iter().enumerate() {
                assert_eq!(s.time, (k + 1) as f64, "{when}: step {} time", k + 1);
                assert_eq!(s.displacement.len(), c.mesh.points.len());
                assert!(
                    s.displacement
                        .iter()
                        .all(|u| u[0].is_finite() && u[1].is_finite()),
                    "{when}: step {} has non-finite displacements",
                    k + 1
                );
                assert!(s.info.converged, "{when}: step {} not converged", k + 1);
            }
            ck = Some(c);
        }
    }
    ck
}

fn steps_in(h5: &Path) -> usize {
    if !h5.is_file() {
        return 0;
    }
    read_checkpoint(h5).map(|c| c.steps.len()).unwrap_or(0)
}

/// When to kill the run.
#[derive(Debug, Clone, Copy)]
enum KillAt {
    After(Duration),
    /// As soon as the checkpoint holds this many steps (or the run ends).
    Steps(usize),
    /// While a step is being appended to an existing checkpoint (its staged
    /// copy exists), or when the run ends.
    WhileAppending,
}

/// Starts the run in `dir`, kills it at `at`; returns the number of steps the
/// checkpoint held at the moment of the kill (for `Steps`).
fn run_and_kill(dir: &Path, at: KillAt) -> usize {
    let mut child = command()
        .arg("solve")
        .arg(problem())
        .arg("--out")
        .arg(dir)
        .arg("--quiet")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let h5 = dir.join(format!("{NAME}.h5"));
    let mut seen = 0;
    match at {
        KillAt::After(d) => std::thread::sleep(d),
        KillAt::Steps(k) => {
            let t0 = Instant::now();
            loop {
                // Exit first, then the count: the last step's files appear
                // only in the final commit, just before the process exits,
                // so a count taken before the exit check could miss them.
                let exited = child.try_wait().unwrap().is_some();
                seen = steps_in(&h5);
                if seen >= k || exited {
                    break;
                }
                assert!(
                    t0.elapsed() < Duration::from_secs(300),
                    "the run never wrote step {k}"
                );
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        KillAt::WhileAppending => {
            let t0 = Instant::now();
            let stage = format!(".signorini-stage-{NAME}-");
            loop {
                let appending = h5.is_file()
                    && std::fs::read_dir(dir).unwrap().flatten().any(|e| {
                        e.file_name().to_string_lossy().starts_with(&stage)
                            && e.path().join(format!("{NAME}.h5")).is_file()
                    });
                if appending || child.try_wait().unwrap().is_some() {
                    break;
                }
                assert!(
                    t0.elapsed() < Duration::from_secs(300),
                    "the run never appended a step"
                );
                std::thread::sleep(Duration::from_micros(200));
            }
        }
    }
    // SIGKILL on unix; an error only means the child has already been reaped.
    let _ = child.kill();
    let _ = child.wait();
    seen
}

fn max_abs(u: &[[f64; 2]]) -> f64 {
    u.iter()
        .fold(0.0f64, |m, v| m.max(v[0].abs()).max(v[1].abs()))
}

#[test]
fn killed_runs_leave_complete_files_and_restart_to_the_same_result() {
    // The uninterrupted reference.
    let full = tempfile::tempdir().unwrap();
    let (code, log) = solve(full.path(), &["--quiet"]);
    assert_eq!(code, 0, "{log}");
    let reference = check_outputs(full.path(), "uninterrupted run").expect("a checkpoint");
    assert_eq!(reference.steps.len(), NSTEPS);
    let u_ref = &reference.steps[NSTEPS - 1].displacement;
    let scale = max_abs(u_ref);
    assert!(scale > 0.0);

    let points = [
        KillAt::After(Duration::ZERO),
        KillAt::After(Duration::from_millis(30)),
        KillAt::After(Duration::from_millis(300)),
        KillAt::After(Duration::from_millis(1000)),
        KillAt::Steps(1),
        KillAt::Steps(2),
        KillAt::Steps(NSTEPS),
        KillAt::WhileAppending,
    ];
    let mut after_checkpoint = 0;
    for at in points {
        let when = format!("killed at {at:?}");
        let dir = tempfile::tempdir().unwrap();
        let seen = run_and_kill(dir.path(), at);
        if let KillAt::Steps(k) = at {
            assert!(seen >= k, "{when}: the run ended before step {k}");
        }
        let ck = check_outputs(dir.path(), &when);
        let have = ck.as_ref().map_or(0, |c| c.steps.len());
        assert!(have >= seen, "{when}: the checkpoint lost steps");
        // A finished checkpoint comes with its summary: the last commit
        // renames the JSON before the checkpoint (a restart that finds all
        // steps done has nothing to write it from).
        if have == NSTEPS {
            assert!(
                dir.path().join(format!("{NAME}.json")).is_file(),
                "{when}: all {NSTEPS} steps in the checkpoint but no summary"
            );
        }
        if have > 0 {
            after_checkpoint += 1;
        }
        let left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| is_temporary(n))
            .collect();
        eprintln!(
            "{when}: checkpoint {}, {have} step(s); staging and lock files left: {left:?}",
            if ck.is_some() { "present" } else { "absent" }
        );
        let h5 = dir.path().join(format!("{NAME}.h5"));
        // Continue: from the checkpoint when there is one, else from scratch.
        let (code, log) = if h5.is_file() {
            solve(dir.path(), &["--quiet", "--restart", h5.to_str().unwrap()])
        } else {
            solve(dir.path(), &["--quiet"])
        };
        assert_eq!(code, 0, "{when}: the continued run failed: {log}");
        let done = check_outputs(dir.path(), &format!("{when}, then continued"))
            .expect("a checkpoint after the continued run");
        assert_eq!(done.steps.len(), NSTEPS, "{when}");
        // The continued run removed what the killed one left behind.
        let hidden: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(
            hidden.is_empty(),
            "{when}: left after the continued run: {hidden:?}"
        );
        for (k, (a, b)) in reference.steps.iter().zip(&done.steps).enumerate() {
            let err = a
                .displacement
                .iter()
                .zip(&b.displacement)
                .fold(0.0f64, |m, (p, q)| {
                    m.max((p[0] - q[0]).abs()).max((p[1] - q[1]).abs())
                });
            assert!(
                err <= 1e-8 * scale,
                "{when}: step {} differs from the uninterrupted run by {err:e} (scale {scale:e})",
                k + 1
            );
        }
        for f in [
            format!("{NAME}_{NSTEPS:04}.vtu"),
            format!("{NAME}_{NSTEPS:04}_contact.vtu"),
        ] {
            assert!(dir.path().join(&f).is_file(), "{when}: {f} missing");
        }
        assert!(dir.path().join(format!("{NAME}.json")).is_file(), "{when}");
    }
    assert!(
        after_checkpoint >= 2,
        "only {after_checkpoint} kills landed after a checkpoint step existed"
    );
}

// ---------------------------------------------------------------- signals
//
// SIGTERM and SIGINT (issue 34): the run stops, rolls back the commits it
// made, and the output directory holds exactly what it held before (byte for
// byte), without its staging directory or lock; exit code 128 + the signal
// and one `error:` line. The signal is sent as soon as the first step's
// commit is seen (the checkpoint's inode changes, a rename), while later
// steps remain: each test asserts the run was still going.

/// Every entry of `dir` (hidden ones included) with its bytes (directories: empty).
fn snapshot(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut m = std::collections::BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let bytes = if e.file_type().unwrap().is_file() {
            std::fs::read(e.path()).unwrap()
        } else {
            vec![]
        };
        m.insert(name, bytes);
    }
    m
}

fn inode(p: &Path) -> Option<u64> {
    use std::os::unix::fs::MetadataExt;
    std::fs::symlink_metadata(p).ok().map(|m| m.ino())
}

fn send(child: &std::process::Child, sig: i32) {
    // SAFETY: kill(2) on the PID of a child not yet reaped.
    let r = unsafe { libc::kill(child.id() as libc::pid_t, sig) };
    assert_eq!(r, 0, "kill({}, {sig})", child.id());
}

/// How a signalled run ended: exit code (None: killed by a signal) and stderr.
struct Stopped {
    code: Option<i32>,
    stderr: String,
}

/// Runs `solve NAME.toml --out dir extra…`, and once the checkpoint in `dir`
/// is a new file (the first step committed) sends `signals` in order;
/// waits at most 300 s for the end.
fn signal_after_first_commit(name: &str, dir: &Path, extra: &[&str], signals: &[i32]) -> Stopped {
    signal_after_first_commit_of(&meshes().join(format!("{name}.toml")), dir, extra, signals)
}

/// [`signal_after_first_commit`] of the problem file `toml` (its stem the
/// output name).
fn signal_after_first_commit_of(
    toml: &Path,
    dir: &Path,
    extra: &[&str],
    signals: &[i32],
) -> Stopped {
    let name = toml.file_stem().unwrap().to_string_lossy().into_owned();
    let h5 = dir.join(format!("{name}.h5"));
    let before = inode(&h5);
    let err = dir.with_extension("stderr");
    let mut child = command()
        .arg("solve")
        .arg(toml)
        .arg("--out")
        .arg(dir)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        let now = inode(&h5);
        if now.is_some() && now != before {
            break;
        }
        if let Some(s) = child.try_wait().unwrap() {
            panic!("the run ended ({s}) before its first commit was seen");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "no commit within 300 s"
        );
        std::thread::sleep(Duration::from_micros(200));
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "the run ended before the signal: nothing left to interrupt"
    );
    for (k, &s) in signals.iter().enumerate() {
        if k > 0 {
            // Two signals pending at once are delivered lowest number
            // first (SIGINT before SIGTERM), whatever order they were
            // sent in: let the first be taken before the next is sent.
            std::thread::sleep(Duration::from_millis(50));
        }
        send(&child, s);
    }
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(300) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the run did not stop within 300 s of the signal");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Stopped {
        code: status.code(),
        stderr: std::fs::read_to_string(&err).unwrap(),
    }
}

/// The run stopped by `sig` with its exit code and one `error:` line.
fn assert_stopped(s: &Stopped, sig: i32, what: &str) {
    assert_eq!(
        s.code,
        Some(128 + sig),
        "{what}: exit code; stderr:\n{}",
        s.stderr
    );
    let errors: Vec<&str> = s
        .stderr
        .lines()
        .filter(|l| l.starts_with("error"))
        .collect();
    assert_eq!(errors.len(), 1, "{what}: {}", s.stderr);
    let want = if sig == libc::SIGTERM {
        "SIGTERM"
    } else {
        "SIGINT"
    };
    assert!(
        errors[0].contains("interrupted") && errors[0].contains(want),
        "{what}: {}",
        errors[0]
    );
    assert!(!s.stderr.contains("panicked"), "{what}: {}", s.stderr);
}

/// A complete set of `name` in `dir`; returns its snapshot.
fn previous_set(
    name: &str,
    dir: &Path,
    extra: &[&str],
) -> std::collections::BTreeMap<String, Vec<u8>> {
    let o = command()
        .arg("solve")
        .arg(meshes().join(format!("{name}.toml")))
        .arg("--out")
        .arg(dir)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap();
    let (code, log) = joined(&o);
    assert_eq!(code, 0, "{log}");
    let s = snapshot(dir);
    assert!(s.contains_key(&format!("{name}.json")), "{s:?}");
    assert!(!s.keys().any(|k| k.starts_with('.')), "{:?}", s.keys());
    s
}

fn signal_restores(name: &str, sig: i32, signals: &[i32]) {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let before = previous_set(name, &out, &[]);
    let s = signal_after_first_commit(name, &out, &["--quiet"], signals);
    let after = snapshot(&out);
    assert_eq!(
        after.keys().collect::<Vec<_>>(),
        before.keys().collect::<Vec<_>>(),
        "{name}: the files in the directory changed (staging folder or lock left?)"
    );
    for (k, v) in &before {
        assert!(after[k] == *v, "{name}: {k} is not the previous run's");
    }
    assert_stopped(&s, sig, name);
}

#[test]
fn sigterm_after_the_first_commit_leaves_the_previous_set_byte_for_byte() {
    signal_restores("geodynamic_steps", libc::SIGTERM, &[libc::SIGTERM]);
}

#[test]
fn sigint_after_the_first_commit_leaves_the_previous_set_byte_for_byte() {
    signal_restores("geodynamic_steps", libc::SIGINT, &[libc::SIGINT]);
}

#[test]
fn sigterm_on_three_bodies_steps_leaves_the_previous_set_byte_for_byte() {
    signal_restores(NAME, libc::SIGTERM, &[libc::SIGTERM]);
}

#[test]
fn sigterm_then_sigint_still_roll_back_once_with_the_first_signal() {
    signal_restores(
        "geodynamic_steps",
        libc::SIGTERM,
        &[libc::SIGTERM, libc::SIGINT, libc::SIGTERM],
    );
}

#[test]
fn a_signal_in_a_fresh_directory_leaves_no_output() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let s = signal_after_first_commit("geodynamic_steps", &out, &["--quiet"], &[libc::SIGINT]);
    let left: Vec<String> = snapshot(&out).into_keys().collect();
    assert!(left.is_empty(), "left behind: {left:?}");
    assert_stopped(&s, libc::SIGINT, "fresh directory");
}

#[test]
fn a_signal_during_a_restart_leaves_the_partial_set_and_a_restart_then_completes() {
    let name = "geodynamic_steps";
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let before = previous_set(name, &out, &["--max-steps", "2"]);
    let h5 = out.join(format!("{name}.h5"));
    let h5s = h5.to_str().unwrap().to_string();
    let s = signal_after_first_commit(
        name,
        &out,
        &["--quiet", "--restart", &h5s],
        &[libc::SIGTERM],
    );
    assert!(snapshot(&out) == before, "the partial set changed");
    assert_eq!(read_checkpoint(&h5).unwrap().steps.len(), 2);
    assert_stopped(&s, libc::SIGTERM, "restart");
    // The restart, not interrupted, completes the sequence.
    let o = command()
        .arg("solve")
        .arg(meshes().join(format!("{name}.toml")))
        .args(["--out", out.to_str().unwrap(), "--quiet", "--restart", &h5s])
        .output()
        .unwrap();
    let (code, log) = joined(&o);
    assert_eq!(code, 0, "{log}");
    assert_eq!(read_checkpoint(&h5).unwrap().steps.len(), 5);
}

#[test]
fn a_signal_at_the_start_leaves_the_directory_as_it_was() {
    // Sent at once: before the handler is installed the signal's default
    // action ends the process; after, the run stops at its first check.
    // Either way nothing of this run is left.
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let before = previous_set(NAME, &out, &[]);
    for sig in [libc::SIGTERM, libc::SIGINT] {
        let mut child = command()
            .arg("solve")
            .arg(problem())
            .args(["--out", out.to_str().unwrap(), "--quiet"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(20));
        send(&child, sig);
        let t0 = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            assert!(t0.elapsed() < Duration::from_secs(300), "no stop");
            std::thread::sleep(Duration::from_millis(5));
        };
        assert!(
            status.code().is_none_or(|c| c == 128 + sig),
            "{sig}: {status}"
        );
        assert!(
            snapshot(&out) == before,
            "signal {sig}: the directory changed"
        );
    }
}

#[test]
fn a_signal_stops_a_long_solve_at_its_next_iteration() {
    // Uzawa with a tiny step takes many thousands of iterations on
    // three_bodies (about 10 s here); the signal lands inside the solve and
    // the executor stops at its next iteration: the run ends within a few
    // seconds, not when the solve would have (the bound is generous; it is
    // no decision of the product).
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let mut child = command()
        .arg("solve")
        .arg(meshes().join("three_bodies.toml"))
        .args(["--out", out.to_str().unwrap(), "--quiet"])
        .args(["--method", "uzawa", "--rho", "1e-6", "--tol", "1e-14"])
        .args(["--max-iter", "100000000"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    if child.try_wait().unwrap().is_some() {
        eprintln!("SKIPPED: the solve ended within 1.5 s; nothing to interrupt");
        return;
    }
    send(&child, libc::SIGINT);
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(300) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("no stop within 300 s");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let waited = t0.elapsed();
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted by SIGINT"), "{stderr}");
    assert!(
        waited < Duration::from_secs(5),
        "the solve went on for {waited:?} after the signal"
    );
    // The run created `out`; it leaves nothing, the directory included.
    assert!(!out.exists(), "left behind: {:?}", snapshot(&out));
}

/// `signorini solve … | head -1`: the reader of stdout goes away after the
/// first step's line, while the run goes on. The run completes every step,
/// commits its files (the checkpoint holds all four steps, the JSON is
/// there and converged) and exits 4 with one line on stderr. Before: the
/// second step's line panicked (EPIPE), exit 101, and the run stopped.
#[test]
fn a_reader_that_goes_away_mid_run_loses_the_report_not_the_run() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = command()
        .args(["solve", problem().to_str().unwrap(), "--out"])
        .arg(&out)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(child.stdout.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    assert!(first.starts_with("step    1/4"), "{first}");
    // `head -1` exits: the pipe's only reader is gone.
    drop(lines);
    let o = child.wait_with_output().unwrap();
    let (code, stderr) = (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert_eq!(code, 4, "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains("error: cannot write to standard output"),
        "{stderr}"
    );
    let ck = read_checkpoint(&out.join(format!("{NAME}.h5"))).unwrap();
    assert_eq!(ck.steps.len(), 4);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join(format!("{NAME}.json"))).unwrap())
            .unwrap();
    assert_eq!(j["converged"], true);
    assert_eq!(j["failed_steps"], serde_json::json!([]));
}

// ------------------------------------------------- files from another run
//
// Issue 43: a run's first commit removes the files of its name that an
// older run left and it will not write (later steps of a longer run),
// keeping them in its staging directory until the end: a signal puts them
// back with the rest, and a SIGKILL leaves no older step file beside the
// new checkpoint.

/// `dir/NAME.toml`: three_bodies_steps with `nsteps` load steps, the mesh
/// path made absolute.
fn steps_variant(dir: &Path, nsteps: usize) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(problem()).unwrap();
    let head = &text[..text.find("[[steps]]").unwrap()];
    let mesh = meshes().join("three_bodies.msh");
    let mut out = head.replace(
        "file = \"three_bodies.msh\"",
        &format!("file = {:?}", mesh.to_str().unwrap()),
    );
    for k in 1..=nsteps {
        out.push_str(&format!(
            "[[steps]]\nt = {k}.0\ndisplacement = {}\nload = 1.0\n\n",
            k as f64 / nsteps as f64
        ));
    }
    let p = dir.join(format!("{NAME}.toml"));
    std::fs::write(&p, out).unwrap();
    p
}

/// The step index of a step file of NAME (`NAME_NNNN.vtu`, `…_contact.vtu`, `….h5`).
fn step_of(name: &str) -> Option<usize> {
    let rest = name.strip_prefix(&format!("{NAME}_"))?;
    let digits = ["_contact.vtu", ".vtu", ".h5"]
        .iter()
        .find_map(|s| rest.strip_suffix(s))?;
    digits.parse().ok()
}

#[test]
fn sigterm_during_a_shorter_run_puts_back_the_longer_runs_files() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let long = steps_variant(&d.path().join("long"), 20);
    let short = steps_variant(&d.path().join("short"), 12);
    let (code, log) = solve_toml_in(&long, &out, &["--quiet"]);
    assert_eq!(code, 0, "{log}");
    let before = snapshot(&out);
    assert_eq!(before.keys().filter(|k| step_of(k) == Some(20)).count(), 3);
    let s = signal_after_first_commit_of(&short, &out, &["--quiet"], &[libc::SIGTERM]);
    let after = snapshot(&out);
    assert_eq!(
        after.keys().collect::<Vec<_>>(),
        before.keys().collect::<Vec<_>>(),
        "the older run's files were not all put back"
    );
    for (k, v) in &before {
        assert!(after[k] == *v, "{k} is not the older run's");
    }
    assert_stopped(&s, libc::SIGTERM, "shorter run");
}

#[test]
fn a_killed_shorter_run_leaves_no_older_step_file_and_restarts_to_its_own_set() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let long = steps_variant(&d.path().join("long"), 20);
    let short = steps_variant(&d.path().join("short"), 12);
    let (code, log) = solve_toml_in(&long, &out, &["--quiet"]);
    assert_eq!(code, 0, "{log}");
    let h5 = out.join(format!("{NAME}.h5"));
    let mut child = command()
        .arg("solve")
        .arg(&short)
        .args(["--out", out.to_str().unwrap(), "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Two steps in the new checkpoint: the first commit (and its removal
    // of the older files) is complete, the run goes on.
    let t0 = Instant::now();
    let mut seen = 0;
    loop {
        let exited = child.try_wait().unwrap().is_some();
        if let Ok(c) = read_checkpoint(&h5) {
            if c.steps.len() < 20 {
                seen = c.steps.len();
            }
        }
        if seen >= 2 || exited {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(300), "no second step");
        std::thread::sleep(Duration::from_micros(500));
    }
    let _ = child.kill();
    let _ = child.wait();
    let ck = read_checkpoint(&h5).expect("the checkpoint opens after the kill");
    let have = ck.steps.len();
    assert!((2..=12).contains(&have), "{have} steps");
    for name in snapshot(&out).keys() {
        if let Some(k) = step_of(name) {
            // The step being committed may have its pair in place before
            // its index; nothing beyond it.
            assert!(
                k <= have + 1,
                "{name} left beside a checkpoint of {have} steps"
            );
        }
    }
    let pvd = signorini::io::vtu::read_pvd(&out.join(format!("{NAME}.pvd"))).unwrap();
    for (_, f) in &pvd {
        assert!(out.join(f).is_file(), "the .pvd names {f}, absent");
    }
    // The restart completes the shorter run's set, and only it.
    let (code, log) = solve_toml_in(
        &short,
        &out,
        &["--quiet", "--restart", h5.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{log}");
    let names: Vec<String> = snapshot(&out).into_keys().collect();
    assert_eq!(names.len(), 4 + 3 * 12, "{names:?}");
    assert!(names
        .iter()
        .all(|n| step_of(n).is_none_or(|k| (1..=12).contains(&k))));
    assert_eq!(read_checkpoint(&h5).unwrap().steps.len(), 12);
}

fn solve_toml_in(toml: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let o = command()
        .arg("solve")
        .arg(toml)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    joined(&o)
}
