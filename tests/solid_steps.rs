//! Load steps, `--max-steps`, `compare` and an unbounded load on 3D models
//! (issue 45), through the binary: the stacked cubes of
//! tests/data/solid_contact (steel under aluminium, non-matching meshes,
//! mortar rows, the upper cube held along z by the contact alone) under a
//! pressure p on top.
//!
//! Required: with `[[steps]]` factors 0.25, 0.5, 1 every step is certified
//! and its contact force Σλ is its factor × p·1 m² (the HDF5 steps read
//! through the split layout's index); the later steps start from the
//! previous answer (one Newton step: the active set does not change); the
//! last step is the single solve's answer bit for bit; `--max-steps 2`
//! stops after two steps; `compare` runs every method of the report on the
//! model and they agree, with 3-component probes equal to `solve`'s; a
//! pressure that pulls the upper cube off is refused as unbounded, naming
//! its volume; `--restart` continues a 3D run bit for bit.

mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};

const P: f64 = 1.0e6;

/// The stacked cubes meshed apart, mortar rows, probes; `extra` follows
/// the `[output]` table's probes.
fn stack_toml(extra: &str, pn: f64) -> String {
    let msh = common::root().join("tests/data/solid_contact/stack_nm.msh");
    let contact = "slave = \"upper_bottom\"\nmaster = \"lower_top\"";
    let tail = format!(
        "\n[output]\nprobes = {{ corner = [1.0, 1.0, 2.0], mid = [0.5, 0.5, 1.0] }}\n{extra}\n"
    );
    common::solid_stack_toml(&msh, contact, pn, &tail)
}

const STEPS: &str = "
[[steps]]
factor = 0.25

[[steps]]
factor = 0.5

[[steps]]
factor = 1.0
";

/// `signorini ARGS… TOML` on `toml` written in `dir` as `stack.toml`:
/// exit code and stdout + stderr.
fn run(dir: &Path, toml: &str, args: &[&str]) -> (i32, String, PathBuf) {
    let path = dir.join("stack.toml");
    std::fs::write(&path, toml).unwrap();
    let o = common::command()
        .args(&args[..1])
        .arg(&path)
        .args(&args[1..])
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code().unwrap_or(-1), text, path)
}

/// `signorini solve TOML ARGS…` as [`run`], asserting exit 0: its output.
fn solve_ok(dir: &Path, toml: &str, args: &[&str]) -> String {
    let mut a = vec!["solve"];
    a.extend_from_slice(args);
    let (code, text, _) = run(dir, toml, &a);
    assert_eq!(code, 0, "{args:?}: {text}");
    text
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn read(f: &hdf5::File, name: &str) -> Vec<f64> {
    f.dataset(name).unwrap().read_raw().unwrap()
}

#[test]
fn load_steps_in_3d_scale_the_contact_force_and_end_at_the_single_solve() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    let (code, text, _) = run(tmp.path(), &stack_toml(STEPS, -P), &["solve", "--out", o]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("steps "), "no step table: {text}");
    for f in [
        "stack.h5",
        "stack_mesh.h5",
        "stack.pvd",
        "stack.json",
        "stack_0001.vtu",
        "stack_0002_contact.vtu",
        "stack_0003.h5",
    ] {
        assert!(out.join(f).is_file(), "no {f}");
    }
    assert!(!out.join("stack.vtu").exists(), "a single solve's VTU");
    let j = json(&out.join("stack.json"));
    let rows = j["steps"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert!(j["failed_steps"].as_array().unwrap().is_empty());
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r["certified"], Value::Bool(true), "step {}", k + 1);
        if k > 0 {
            // Warm-started from the previous step, same active set.
            assert_eq!(r["iterations"].as_u64(), Some(1), "step {}: {r}", k + 1);
            assert_eq!(
                (r["opened"].as_u64(), r["closed"].as_u64()),
                (Some(0), Some(0))
            );
        }
    }
    // Every step through the index: Σλ = factor · p · 1 m².
    let f = hdf5::File::open(out.join("stack.h5")).unwrap();
    assert_eq!(
        f.attr("last_step").unwrap().read_scalar::<u64>().unwrap(),
        3
    );
    for (k, factor) in [0.25, 0.5, 1.0].into_iter().enumerate() {
        let lam = read(&f, &format!("steps/{:04}/multipliers", k + 1));
        let sum: f64 = lam.iter().sum();
        assert!(
            (sum - factor * P).abs() <= 1e-9 * P,
            "step {}: Σλ = {sum:e}",
            k + 1
        );
    }
    let u3 = read(&f, "steps/0003/displacement");

    // The single solve of the full load: the last step's answer.
    let single = tmp.path().join("single");
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml("", -P),
        &["solve", "--out", single.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{text}");
    let g = hdf5::File::open(single.join("stack.h5")).unwrap();
    let u = read(&g, "steps/0001/displacement");
    let scale = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = u
        .iter()
        .zip(&u3)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(d <= 1e-12 * scale, "last step vs single solve: {d:e}");

    // --max-steps 2: two steps written, the index ends there.
    let two = tmp.path().join("two");
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml(STEPS, -P),
        &["solve", "--out", two.to_str().unwrap(), "--max-steps", "2"],
    );
    assert_eq!(code, 0, "{text}");
    assert!(!two.join("stack_0003.h5").exists());
    let f = hdf5::File::open(two.join("stack.h5")).unwrap();
    assert_eq!(
        f.attr("last_step").unwrap().read_scalar::<u64>().unwrap(),
        2
    );
    assert_eq!(
        json(&two.join("stack.json"))["steps"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
}

#[test]
fn compare_runs_every_method_on_a_3d_model() {
    let tmp = tempfile::tempdir().unwrap();
    let table = tmp.path().join("t.json");
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml("", -P),
        &["compare", "--json", table.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("u3(corner)"), "{text}");
    let t = json(&table);
    let rows = t["rows"].as_array().unwrap();
    // Six CGC preconditioners and eight other methods.
    assert_eq!(rows.len(), 14, "{t}");
    for r in rows {
        assert_eq!(r["agrees"], Value::Bool(true), "{r}");
        assert_eq!(r["probes"]["corner"].as_array().unwrap().len(), 3);
    }
    // The probes of `solve`.
    let out = tmp.path().join("out");
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml("", -P),
        &["solve", "--out", out.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{text}");
    let s = json(&out.join("stack.json"));
    let ssn = rows.iter().find(|r| r["method"] == "ssn").unwrap();
    for name in ["corner", "mid"] {
        let a = s["probes"][name]["u"].as_array().unwrap();
        let b = ssn["probes"][name].as_array().unwrap();
        for k in 0..3 {
            let (a, b) = (a[k].as_f64().unwrap(), b[k].as_f64().unwrap());
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1e-9),
                "{name}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn a_3d_load_pulling_a_body_off_is_refused_as_unbounded() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    // The pressure pulls the upper cube up, away from its only support.
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml("", P),
        &["solve", "--out", out.to_str().unwrap()],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("unbounded"), "{text}");
    assert!(
        text.contains("\"upper\""),
        "the moving volume is not named: {text}"
    );
    assert!(
        !text.contains("\"lower\""),
        "the fixed volume is named: {text}"
    );
    assert!(text.contains("stack.toml"), "{text}");
    assert!(!out.join("stack.h5").exists(), "an output was written");

    // In load steps, the step that pulls it off is named (as in 2D,
    // tests/cli.rs): pressing (factor 1 of −P), less, then pulling.
    let steps =
        "\n[[steps]]\nfactor = 1.0\n\n[[steps]]\nfactor = 0.5\n\n[[steps]]\nfactor = -1.0\n";
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml(steps, -P),
        &["solve", "--out", out.to_str().unwrap()],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("unbounded"), "{text}");
    assert!(
        text.contains("step 3 of 3 (t = 3)"),
        "the step is not named: {text}"
    );
}

/// `--restart` in 3D: a run stopped after two of three steps and continued
/// (in place, and into another directory) gives the uninterrupted run's
/// steps bit for bit; nothing to do when every step is there; a checkpoint
/// of another load is refused naming the part that differs.
#[test]
fn a_3d_run_continues_from_its_checkpoint_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack_toml(STEPS, -P);
    let dir = |d: &str| tmp.path().join(d).to_str().unwrap().to_string();
    let (full, part, other) = (dir("full"), dir("part"), dir("other"));
    let solve = |args: &[&str]| solve_ok(tmp.path(), &toml, args);
    solve(&["--out", &full]);
    solve(&["--out", &part, "--max-steps", "2"]);
    let h5 = format!("{part}/stack.h5");
    solve(&["--out", &other, "--restart", &h5]);
    solve(&["--out", &part, "--restart", &h5]);
    let text = solve(&["--out", &part, "--restart", &h5]);
    assert!(text.contains("nothing to do"), "{text}");
    // Nothing to do into another directory: the finished run's files are
    // copied there (as 2D), its summary byte for byte, and the copy is a
    // checkpoint that restarts (nothing to do again).
    let done = dir("done");
    let text = solve(&["--out", &done, "--restart", &format!("{full}/stack.h5")]);
    assert!(text.contains("nothing to do"), "{text}");
    let listing = |d: &str| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(listing(&done), listing(&full));
    assert_eq!(
        std::fs::read(format!("{done}/stack.json")).unwrap(),
        std::fs::read(format!("{full}/stack.json")).unwrap()
    );
    let text = solve(&[
        "--out",
        &dir("again"),
        "--restart",
        &format!("{done}/stack.h5"),
    ]);
    assert!(text.contains("nothing to do"), "{text}");
    let f = hdf5::File::open(format!("{full}/stack.h5")).unwrap();
    for d in [&part, &other, &done] {
        let g = hdf5::File::open(format!("{d}/stack.h5")).unwrap();
        assert_eq!(
            g.attr("last_step").unwrap().read_scalar::<u64>().unwrap(),
            3
        );
        for s in ["0001", "0002", "0003"] {
            let name = format!("steps/{s}/displacement");
            let (a, b) = (read(&f, &name), read(&g, &name));
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{d} {s}"
            );
        }
        // This run's summary has the step it solved (the copy: all three).
        let j = json(&Path::new(d).join("stack.json"));
        let solved = if *d == done { 3 } else { 1 };
        assert_eq!(j["steps"].as_array().unwrap().len(), solved, "{d}");
    }
    // Another load: refused, naming the part; nothing written.
    let (code, text, _) = run(
        tmp.path(),
        &stack_toml(STEPS, -2.0 * P),
        &["solve", "--out", &dir("bad"), "--restart", &h5],
    );
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("traction") && text.contains("does not match"),
        "{text}"
    );
    assert!(!tmp.path().join("bad").exists());
}

/// `--restart` of a frictional 3D run (Coulomb μ = 0.3 on the mortar rows,
/// the steps of the test above): the checkpoint's `multipliers` and
/// `multipliers_t_frame` are the continued step's warm start, as the last
/// step's λ is in the uninterrupted run, so the continued steps are the
/// same bit for bit (displacement, λ_n, λ_t, state).
#[test]
fn a_frictional_3d_run_continues_from_its_checkpoint_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let msh = common::root().join("tests/data/solid_contact/stack_nm.msh");
    let contact = "slave = \"upper_bottom\"\nmaster = \"lower_top\"\nfriction = 0.3";
    // Aluminium's ν = 0.33 on steel: both stick and slip zones.
    let toml = common::solid_stack_toml(&msh, contact, -P, STEPS).replace("nu = 0.25", "nu = 0.33");
    let dir = |d: &str| tmp.path().join(d).to_str().unwrap().to_string();
    // The direct paths, and the multigrid one (docs/methods.md §12.3): its
    // CG starts from the step's own iterate, never from the last step's x.
    for path in ["auto", "iterative"] {
        let (full, part) = (dir(&format!("full_{path}")), dir(&format!("part_{path}")));
        let solve = |args: &[&str]| {
            let mut all = args.to_vec();
            all.extend(["--ssn-path", path]);
            solve_ok(tmp.path(), &toml, &all)
        };
        let text = solve(&["--out", &full]);
        assert!(text.contains("slip;"), "{text}");
        solve(&["--out", &part, "--max-steps", "1"]);
        solve(&["--out", &part, "--restart", &format!("{part}/stack.h5")]);
        let f = hdf5::File::open(format!("{full}/stack.h5")).unwrap();
        let g = hdf5::File::open(format!("{part}/stack.h5")).unwrap();
        let state = |h: &hdf5::File, name: &str| -> Vec<u8> {
            h.dataset(name).unwrap().read_raw::<u8>().unwrap()
        };
        for s in ["0002", "0003"] {
            for ds in [
                "displacement",
                "multipliers",
                "multipliers_t",
                "multipliers_t_frame",
            ] {
                let name = format!("steps/{s}/{ds}");
                let (a, b) = (read(&f, &name), read(&g, &name));
                assert_eq!(a.len(), b.len(), "{name}");
                assert!(
                    a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{path}: {name}"
                );
            }
            let name = format!("steps/{s}/state");
            assert_eq!(state(&f, &name), state(&g, &name), "{path}: {name}");
        }
    }
}

/// `[output] reference_step` in 3D: from step K on, the `*_change` fields
/// are the step's minus step K's in the HDF5 and the VTU (and a restart
/// keeps them); the VTU's `reaction` point data balance the loads.
#[test]
fn reference_step_and_reactions_in_3d() {
    let tmp = tempfile::tempdir().unwrap();
    // `extra` follows the [output] table's probes.
    let toml = stack_toml(&format!("reference_step = 1\n{STEPS}"), -P);
    let out = tmp.path().join("out");
    let (code, text, _) = run(
        tmp.path(),
        &toml,
        &["solve", "--out", out.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{text}");
    let f = hdf5::File::open(out.join("stack.h5")).unwrap();
    let u1 = read(&f, "steps/0001/displacement");
    for s in ["0001", "0002", "0003"] {
        let u = read(&f, &format!("steps/{s}/displacement"));
        let du = read(&f, &format!("steps/{s}/displacement_change"));
        let d = u
            .iter()
            .zip(&u1)
            .zip(&du)
            .fold(0.0f64, |m, ((a, b), c)| m.max((a - b - c).abs()));
        assert!(d == 0.0, "step {s}: {d:e}");
        let g = f.group(&format!("steps/{s}")).unwrap();
        assert_eq!(
            g.attr("reference_step")
                .unwrap()
                .read_scalar::<u64>()
                .unwrap(),
            1
        );
        let dp = read(&f, &format!("steps/{s}/contact_pressure_change"));
        let p = read(&f, &format!("steps/{s}/contact_pressure"));
        let p1 = read(&f, "steps/0001/contact_pressure");
        assert!(dp.iter().zip(&p).zip(&p1).all(|((c, a), b)| *c == a - b));
    }
    let vtu = signorini::io::vtu::read_vtu_arrays(&out.join("stack_0003.vtu")).unwrap();
    for name in ["displacement_change", "reaction"] {
        assert!(vtu.point_data.iter().any(|a| a.name == name), "no {name}");
    }
    assert!(vtu.cell_data.iter().any(|a| a.name == "stress_change"));
    let c = signorini::io::vtu::read_vtu_arrays(&out.join("stack_0003_contact.vtu")).unwrap();
    assert!(c
        .point_data
        .iter()
        .any(|a| a.name == "contact_pressure_change"));
    // Σ reactions = −loads (the top's p · 1 m² along −z).
    let r = &vtu
        .point_data
        .iter()
        .find(|a| a.name == "reaction")
        .unwrap()
        .values;
    let sum = [0, 1, 2].map(|k| r.iter().skip(k).step_by(3).sum::<f64>());
    assert!(
        sum[0].abs() < 1e-8 * P && sum[1].abs() < 1e-8 * P,
        "{sum:?}"
    );
    assert!((sum[2] - P).abs() < 1e-8 * P, "{sum:?}");
    // A restart with another reference step is refused, naming the key.
    let part = tmp.path().join("part");
    let (code, text, _) = run(
        tmp.path(),
        &toml,
        &["solve", "--out", part.to_str().unwrap(), "--max-steps", "2"],
    );
    assert_eq!(code, 0, "{text}");
    let h5 = part.join("stack.h5");
    let other = toml.replace("reference_step = 1", "reference_step = 2");
    let (code, text, _) = run(
        tmp.path(),
        &other,
        &[
            "solve",
            "--out",
            part.to_str().unwrap(),
            "--restart",
            h5.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("reference_step"), "{text}");
    // With the same one: step 3's change fields as the uninterrupted run's.
    let (code, text, _) = run(
        tmp.path(),
        &toml,
        &[
            "solve",
            "--out",
            part.to_str().unwrap(),
            "--restart",
            h5.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{text}");
    let g = hdf5::File::open(&h5).unwrap();
    let (a, b) = (
        read(&f, "steps/0003/stress_change"),
        read(&g, "steps/0003/stress_change"),
    );
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// A 3D step that does not converge: exit 3, its outputs written and
/// flagged (the JSON's `failed_steps`, `converged` false and the step's
/// row), the later steps still solved.
#[test]
fn a_3d_step_that_does_not_converge_exits_3_with_its_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let toml = stack_toml(STEPS, -P).replace(
        "[output]\n",
        "[solver]\nmethod = \"uzawa\"\nmax_iter = 2\n\n[output]\n",
    );
    let (code, text, _) = run(
        tmp.path(),
        &toml,
        &["solve", "--out", out.to_str().unwrap()],
    );
    assert_eq!(code, 3, "{text}");
    let j = json(&out.join("stack.json"));
    assert_eq!(j["converged"], Value::Bool(false), "{j}");
    let failed: Vec<u64> = j["failed_steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(failed, vec![1, 2, 3], "{j}");
    let rows = j["steps"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| r["converged"] == Value::Bool(false)));
    assert!(text.contains("NOT CONVERGED"), "{text}");
    for f in ["stack_0003.vtu", "stack_0003.h5", "stack.h5"] {
        assert!(out.join(f).is_file(), "no {f}");
    }
}
