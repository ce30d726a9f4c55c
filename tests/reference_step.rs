//! The geodynamic load-step sequence (meshes/geodynamic_steps.toml) and
//! `[output] reference_step` (docs/problem-format.md §2, §6): the change
//! fields are the step's fields minus the reference step's (zero on the
//! reference step itself), they do not touch the absolute fields, a restart
//! from any step reproduces the uninterrupted run, and the per-step table
//! of the JSON agrees with the checkpoint.

mod common;

use common::{meshes, run};
use signorini::io::hdf5::read_checkpoint;
use signorini::output::Checkpoint;
use std::path::{Path, PathBuf};

const NAME: &str = "geodynamic_steps";

/// The shipped sequence with `reference_step` replaced (None: the key
/// removed), written next to a copy-free mesh reference in `dir`.
fn variant(dir: &Path, reference: Option<usize>) -> PathBuf {
    let text = std::fs::read_to_string(meshes().join(format!("{NAME}.toml"))).unwrap();
    assert!(
        text.contains("reference_step = 1\n"),
        "the shipped file sets reference_step = 1"
    );
    let mesh = meshes().join("geodynamic.msh");
    let text = text
        .replace(
            "file = \"geodynamic.msh\"",
            &format!("file = {:?}", mesh.to_str().unwrap()),
        )
        .replace(
            "reference_step = 1\n",
            &reference.map_or(String::new(), |k| format!("reference_step = {k}\n")),
        );
    let path = dir.join(format!("{NAME}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn solve(toml: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (code, log) = run(&args);
    assert_eq!(code, 0, "{log}");
    log
}

fn checkpoint(out: &Path) -> Checkpoint {
    read_checkpoint(&out.join(format!("{NAME}.h5"))).unwrap()
}

#[test]
fn the_shipped_sequence_has_zero_change_on_its_reference_and_exact_differences_after() {
    let out = tempfile::tempdir().unwrap();
    let log = solve(&meshes().join(format!("{NAME}.toml")), out.path(), &[]);
    assert!(
        log.contains("reference   step 1: displacement_change"),
        "the report names the reference step:\n{log}"
    );
    let ck = checkpoint(out.path());
    assert_eq!(ck.steps.len(), 5);
    let reference = &ck.steps[0];
    for (k, st) in ck.steps.iter().enumerate() {
        let c = st
            .change
            .as_ref()
            .expect("every step from the reference on has change fields");
        assert_eq!(c.reference_step, 1);
        for (i, d) in c.displacement.iter().enumerate() {
            let want = [
                st.displacement[i][0] - reference.displacement[i][0],
                st.displacement[i][1] - reference.displacement[i][1],
            ];
            assert_eq!(*d, want, "step {} point {i}", k + 1);
            if k == 0 {
                assert_eq!(*d, [0.0, 0.0]);
            }
        }
        for (d, (a, b)) in c.stress.iter().zip(st.stress.iter().zip(&reference.stress)) {
            let want = [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]];
            assert_eq!(*d, want, "step {}", k + 1);
            if k == 0 {
                assert_eq!(*d, [0.0; 4]);
            }
        }
        for (i, d) in c.contact_pressure.iter().enumerate() {
            assert_eq!(*d, st.contact_pressure[i] - reference.contact_pressure[i]);
            if k == 0 {
                assert_eq!(*d, 0.0);
            }
        }
    }
    // The plates converge: 2000 m on each side in the last step, relative to
    // the gravity state; horizontal only (the plate sides are free vertically).
    let last = ck.steps[4].change.as_ref().unwrap();
    let xs: Vec<f64> = ck.mesh.points.iter().map(|p| p[0]).collect();
    let (xmin, xmax) = xs
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let mut seen = (0, 0);
    for (i, p) in ck.mesh.points.iter().enumerate() {
        // The plate sides are the parts of x = xmin / xmax above the mantle (y > -60 km).
        if p[1] > -60_000.0 + 1.0 {
            if p[0] == xmin {
                assert_eq!(last.displacement[i][0], 2000.0);
                seen.0 += 1;
            } else if p[0] == xmax {
                assert_eq!(last.displacement[i][0], -2000.0);
                seen.1 += 1;
            }
        }
    }
    assert!(
        seen.0 > 2 && seen.1 > 2,
        "plate side points found: {seen:?}"
    );

    // The VTU files carry the change fields; the contact VTU the pressure change.
    let v =
        signorini::io::vtu::read_vtu_arrays(&out.path().join(format!("{NAME}_0003.vtu"))).unwrap();
    let du = v
        .point_array("displacement_change")
        .expect("displacement_change in the VTU");
    assert_eq!(du.num_comp, 3);
    assert!(v.cell_array("stress_change").is_some());
    let vc =
        signorini::io::vtu::read_vtu_arrays(&out.path().join(format!("{NAME}_0003_contact.vtu")))
            .unwrap();
    assert!(vc.point_array("contact_pressure_change").is_some());

    // The per-step table: JSON rows agree with the checkpoint.
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.path().join(format!("{NAME}.json"))).unwrap(),
    )
    .unwrap();
    assert_eq!(json["reference_step"], 1);
    let rows = json["steps"].as_array().unwrap();
    assert_eq!(rows.len(), 5);
    let mut changed_somewhere = false;
    for (k, r) in rows.iter().enumerate() {
        let st = &ck.steps[k];
        assert_eq!(r["step"], k + 1);
        assert_eq!(r["t"].as_f64().unwrap(), st.time);
        assert_eq!(r["nodes"].as_u64().unwrap() as usize, ck.mesh.points.len());
        assert_eq!(
            r["triangles"].as_u64().unwrap() as usize,
            ck.mesh.triangles.len()
        );
        assert_eq!(r["dofs"], json["dofs"]);
        assert_eq!(r["constraints"].as_u64().unwrap() as usize, st.active.len());
        let active = st.active.iter().filter(|a| **a == 1).count();
        assert_eq!(r["active"].as_u64().unwrap() as usize, active);
        assert_eq!(
            r["iterations"].as_u64().unwrap() as usize,
            st.info.iterations
        );
        if k == 0 {
            assert!(r["opened"].is_null() && r["closed"].is_null());
        } else {
            let prev = &ck.steps[k - 1].active;
            let opened = prev
                .iter()
                .zip(&st.active)
                .filter(|(a, b)| **a == 1 && **b == 0)
                .count();
            let closed = prev
                .iter()
                .zip(&st.active)
                .filter(|(a, b)| **a == 0 && **b == 1)
                .count();
            assert_eq!(
                r["opened"].as_u64().unwrap() as usize,
                opened,
                "step {}",
                k + 1
            );
            assert_eq!(
                r["closed"].as_u64().unwrap() as usize,
                closed,
                "step {}",
                k + 1
            );
            changed_somewhere |= opened + closed > 0;
        }
    }
    assert!(changed_somewhere, "the faults open or close between steps");
    // And the table is printed.
    let header = log
        .lines()
        .find(|l| l.starts_with("steps "))
        .expect("a step table");
    for col in [
        "nodes", "DOFs", "rows", "active", "opened", "closed", "iter",
    ] {
        assert!(header.contains(col), "{header}");
    }
}

#[test]
fn the_reference_step_does_not_change_the_absolute_fields_and_restarts_reproduce_the_run() {
    let dir = tempfile::tempdir().unwrap();
    // Reference 3: steps 1 and 2 have no change fields, restarts before and
    // after the reference.
    let toml = variant(dir.path(), Some(3));
    let full = dir.path().join("full");
    solve(&toml, &full, &[]);
    let ck = checkpoint(&full);
    let plain_dir = tempfile::tempdir().unwrap();
    let plain_toml = variant(plain_dir.path(), None);
    let plain = plain_dir.path().join("out");
    solve(&plain_toml, &plain, &[]);
    let ck0 = checkpoint(&plain);
    assert_eq!(ck.steps.len(), ck0.steps.len());
    for (k, (a, b)) in ck.steps.iter().zip(&ck0.steps).enumerate() {
        assert_eq!(a.displacement, b.displacement, "step {}", k + 1);
        assert_eq!(a.stress, b.stress, "step {}", k + 1);
        assert_eq!(a.multipliers, b.multipliers, "step {}", k + 1);
        assert!(b.change.is_none());
        assert_eq!(a.change.is_some(), k + 1 >= 3, "step {}", k + 1);
    }
    assert_eq!(
        ck.steps[2]
            .change
            .as_ref()
            .unwrap()
            .displacement
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs())),
        0.0
    );

    // The figures: every step's contact pressure change in one plot; the
    // change of a step before the reference, or of a run without one, is
    // refused with a message that says why.
    let h5 = full.join(format!("{NAME}.h5"));
    let png = dir.path().join("contact.png");
    let (code, log) = run(&[
        "plot",
        h5.to_str().unwrap(),
        "--contact",
        "--all-steps",
        "--change",
        "--step",
        "4",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "--all-steps with --step: {log}");
    let (code, log) = run(&[
        "plot",
        h5.to_str().unwrap(),
        "--contact",
        "--all-steps",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    assert!(log.contains("steps 1 to 5"), "{log}");
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    let (code, log) = run(&[
        "plot",
        h5.to_str().unwrap(),
        "--change",
        "--field",
        "umag",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    // |Δu| of the last step since step 3 reaches the 2000 − 500 m of the
    // plate sides.
    let top: f64 = log
        .lines()
        .find_map(|l| l.strip_prefix("range: 0 to "))
        .and_then(|r| r.trim_end_matches(" m").parse().ok())
        .unwrap_or_else(|| panic!("{log}"));
    assert!((1500.0..1600.0).contains(&top), "{log}");
    for (file, extra) in [(&h5, "1"), (&plain.join(format!("{NAME}.h5")), "5")] {
        let (code, log) = run(&[
            "plot",
            file.to_str().unwrap(),
            "--change",
            "--step",
            extra,
            "-o",
            dir.path().join("x.png").to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{log}");
        assert!(
            log.contains("no change fields") && log.contains("reference_step"),
            "{log}"
        );
        assert!(!dir.path().join("x.png").exists());
    }
    let (code, log) = run(&[
        "plot",
        h5.to_str().unwrap(),
        "--all-steps",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{log}");
    assert!(log.contains("--contact"), "{log}");

    // Stopped after step j, restarted from the checkpoint: the same steps.
    for j in 1..ck.steps.len() {
        let out = dir.path().join(format!("part{j}"));
        solve(&toml, &out, &["--max-steps", &j.to_string()]);
        let h5 = out.join(format!("{NAME}.h5"));
        let log = solve(&toml, &out, &["--restart", h5.to_str().unwrap()]);
        assert!(log.contains("restart"), "{log}");
        let ckr = checkpoint(&out);
        assert_eq!(ckr.steps.len(), ck.steps.len());
        for (k, (a, b)) in ck.steps.iter().zip(&ckr.steps).enumerate() {
            assert_eq!(
                a.displacement,
                b.displacement,
                "restart after {j}: step {}",
                k + 1
            );
            assert_eq!(a.change, b.change, "restart after {j}: step {}", k + 1);
            assert_eq!(a.active, b.active, "restart after {j}: step {}", k + 1);
        }
    }
}

#[test]
fn a_reference_step_outside_the_steps_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    for k in [0, 6] {
        let toml = variant(dir.path(), Some(k));
        let (code, log) = run(&[
            "solve",
            toml.to_str().unwrap(),
            "--out",
            dir.path().join("o").to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{log}");
        assert!(
            log.contains("reference_step")
                && log.contains(&format!("{NAME}.toml"))
                && log.contains("5 steps"),
            "{log}"
        );
        assert!(!dir.path().join("o").join(format!("{NAME}.h5")).exists());
    }
}

// ------------------------------------------- restarts that change the question
//
// Issue 34. `[output] reference_step` between a run and its `--restart`: the
// checkpoint's change fields must be those an uninterrupted run with the
// new value writes; otherwise the restart is refused naming the key, and
// the output directory is left as it was. Step groups are continued by
// name; a reference step with non-finite fields is refused naming the file
// and the group.

/// Every entry of `dir` with its bytes (directories: empty).
fn snapshot(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut m = std::collections::BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let bytes = if e.file_type().unwrap().is_file() {
            std::fs::read(e.path()).unwrap()
        } else {
            vec![]
        };
        m.insert(e.file_name().to_string_lossy().into_owned(), bytes);
    }
    m
}

/// The first `k` steps with `reference`, in `dir/out`; (toml dir, out, h5).
fn partial(dir: &Path, reference: Option<usize>, k: usize) -> (PathBuf, PathBuf) {
    let a = dir.join("a");
    std::fs::create_dir_all(&a).unwrap();
    let toml = variant(&a, reference);
    let out = dir.join("out");
    solve(&toml, &out, &["--quiet", "--max-steps", &k.to_string()]);
    let h5 = out.join(format!("{NAME}.h5"));
    (out, h5)
}

/// `--restart h5` of the variant with `reference`, into `out`: (code, log).
fn restart(dir: &Path, reference: Option<usize>, out: &Path, h5: &Path) -> (i32, String) {
    let b = dir.join("b");
    std::fs::create_dir_all(&b).unwrap();
    let toml = variant(&b, reference);
    run(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--restart",
        h5.to_str().unwrap(),
    ])
}

/// Exit 2, one `error:` line naming the checkpoint and containing `want`;
/// the output directory as it was.
fn assert_refused(
    code: i32,
    log: &str,
    h5: &Path,
    want: &[&str],
    out: &Path,
    before: &std::collections::BTreeMap<String, Vec<u8>>,
) {
    assert_eq!(code, 2, "{log}");
    assert!(!log.contains("panicked"), "{log}");
    let errors: Vec<&str> = log.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{log}");
    assert!(errors[0].contains(h5.to_str().unwrap()), "{}", errors[0]);
    for w in want {
        assert!(errors[0].contains(w), "no {w:?} in: {}", errors[0]);
    }
    assert!(snapshot(out) == *before, "the output directory changed");
}

fn refused_reference_change(from: Option<usize>, to: Option<usize>, done: usize) {
    let d = tempfile::tempdir().unwrap();
    let (out, h5) = partial(d.path(), from, done);
    let before = snapshot(&out);
    let (code, log) = restart(d.path(), to, &out, &h5);
    assert_refused(code, &log, &h5, &["reference_step"], &out, &before);
}

#[test]
fn restart_adding_a_reference_step_the_checkpoint_holds_is_refused() {
    refused_reference_change(None, Some(1), 2);
}

#[test]
fn restart_adding_the_last_held_step_as_reference_is_refused() {
    refused_reference_change(None, Some(2), 2);
}

#[test]
fn restart_changing_the_reference_step_is_refused() {
    refused_reference_change(Some(1), Some(2), 2);
}

#[test]
fn restart_moving_the_reference_step_later_is_refused() {
    refused_reference_change(Some(2), Some(4), 3);
}

#[test]
fn restart_removing_the_reference_step_is_refused() {
    refused_reference_change(Some(1), None, 2);
}

/// A restart whose new reference step gives the same checkpoint as an
/// uninterrupted run with it: continued, and equal to that run.
fn consistent_reference_change(from: Option<usize>, to: Option<usize>, done: usize) {
    let d = tempfile::tempdir().unwrap();
    let (out, h5) = partial(d.path(), from, done);
    let (code, log) = restart(d.path(), to, &out, &h5);
    assert_eq!(code, 0, "{log}");
    let full_dir = d.path().join("full");
    std::fs::create_dir_all(&full_dir).unwrap();
    let toml = variant(&full_dir, to);
    solve(&toml, &full_dir.join("out"), &["--quiet"]);
    let (a, b) = (checkpoint(&out), checkpoint(&full_dir.join("out")));
    assert_eq!(a.steps.len(), b.steps.len());
    for (k, (x, y)) in a.steps.iter().zip(&b.steps).enumerate() {
        assert_eq!(x.displacement, y.displacement, "step {}", k + 1);
        assert_eq!(x.change, y.change, "step {}", k + 1);
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join(format!("{NAME}.json"))).unwrap())
            .unwrap();
    assert_eq!(json["reference_step"].as_u64().map(|v| v as usize), to);
}

#[test]
fn restart_adding_a_reference_step_after_the_held_steps_equals_the_uninterrupted_run() {
    consistent_reference_change(None, Some(3), 2);
}

#[test]
fn restart_removing_a_reference_step_not_yet_reached_equals_the_plain_run() {
    consistent_reference_change(Some(4), None, 2);
}

/// A checkpoint of the first `k` steps with reference step 1, edited by `edit`.
fn edited(dir: &Path, k: usize, edit: impl FnOnce(&hdf5::File)) -> (PathBuf, PathBuf) {
    let (out, h5) = partial(dir, Some(1), k);
    let f = hdf5::File::open_rw(&h5).unwrap();
    edit(&f);
    f.close().unwrap();
    (out, h5)
}

fn poison(f: &hdf5::File, ds: &str, at: usize, v: f64) {
    let ds = f.dataset(ds).unwrap();
    let mut x = ds.read_raw::<f64>().unwrap();
    x[at] = v;
    ds.write_raw(&x).unwrap();
}

fn refused_edit(k: usize, edit: impl FnOnce(&hdf5::File), want: &[&str]) {
    let d = tempfile::tempdir().unwrap();
    let (out, h5) = edited(d.path(), k, edit);
    let before = snapshot(&out);
    let (code, log) = restart(d.path(), Some(1), &out, &h5);
    assert_refused(code, &log, &h5, want, &out, &before);
}

#[test]
fn nan_stress_in_the_reference_step_is_refused_naming_the_group() {
    refused_edit(
        2,
        |f| poison(f, "steps/0001/stress", 5, f64::NAN),
        &["/steps/0001/stress", "not finite"],
    );
}

#[test]
fn inf_contact_pressure_in_the_reference_step_is_refused_naming_the_group() {
    refused_edit(
        2,
        |f| poison(f, "steps/0001/contact_pressure", 0, f64::INFINITY),
        &["/steps/0001/contact_pressure", "not finite"],
    );
}

#[test]
fn nan_displacement_in_the_reference_step_is_refused_naming_the_group() {
    refused_edit(
        3,
        |f| poison(f, "steps/0001/displacement", 3, f64::NAN),
        &["/steps/0001/displacement", "not finite"],
    );
}

#[test]
fn a_checkpoint_with_a_step_group_missing_is_refused_naming_it() {
    refused_edit(
        3,
        |f| f.group("steps").unwrap().unlink("0002").unwrap(),
        &["/steps/0003", "/steps/0002 is missing"],
    );
}

#[test]
fn a_checkpoint_with_an_extra_group_0000_is_refused_naming_it() {
    refused_edit(
        2,
        // A soft link: in the split layout of a run with load steps the
        // group lives in its own file, where no hard link can reach.
        |f| f.link_soft("/steps/0002", "steps/0000").unwrap(),
        &["/steps/0000"],
    );
}

#[test]
fn a_checkpoint_with_a_renamed_step_group_is_refused() {
    // 0001, 0003 (was 0002): the time of the group is not step 2's... and
    // the name is not the one a run gives step 2.
    refused_edit(
        2,
        |f| f.group("steps").unwrap().relink("0002", "0003").unwrap(),
        &["/steps/0003"],
    );
}

#[test]
fn a_checkpoint_with_more_steps_than_the_problem_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let (out, h5) = partial(d.path(), Some(1), 5);
    {
        let f = hdf5::File::open_rw(&h5).unwrap();
        f.link_soft("/steps/0005", "steps/0006").unwrap();
        f.close().unwrap();
    }
    let before = snapshot(&out);
    let (code, log) = restart(d.path(), Some(1), &out, &h5);
    assert_refused(
        code,
        &log,
        &h5,
        &["/steps/0006", "5 load step"],
        &out,
        &before,
    );
}

#[test]
fn a_checkpoint_mixing_two_reference_steps_is_refused() {
    refused_edit(
        3,
        |f| {
            f.group("steps/0003")
                .unwrap()
                .attr("reference_step")
                .unwrap()
                .write_scalar(&2u64)
                .unwrap()
        },
        &["/steps/0003", "mixes"],
    );
}
