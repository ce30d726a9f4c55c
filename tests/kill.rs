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

use signorini::io::hdf5::{read_checkpoint, Checkpoint};
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
    name == format!("{NAME}.h5")
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
        } else if name.ends_with(".h5") {
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
