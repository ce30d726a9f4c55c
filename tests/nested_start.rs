//! `solve --start-from COARSE.h5` (docs/methods.md §7.2, "The nested
//! start"), through the binary: Hertz's ball on a block
//! (tests/data/solid_contact) solved on a coarse mesh (`hertz_coarse.msh`,
//! hc = 0.045) and then on the finer `hertz.msh` (hc = 0.02) from the
//! coarse answer interpolated.
//!
//! Required: on the iterative path the nested solve takes fewer Newton
//! steps than the cold one and both end on the same working set and the
//! same displacements (to 10⁻⁸ of the largest); on the default path the
//! answer is the same; load steps take the coarse step at their pseudo-time;
//! a start that is not of this model (another geometry's checkpoint, a 2D
//! model, a missing file, with `--restart`) or a model with friction exits
//! 2 naming the file, and the output directory is not created.

mod common;

use serde_json::Value;
use signorini::io::hdf5::{read_solid_checkpoint, SolidSteps};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    common::root().join("tests/data/solid_contact").join(name)
}

/// Hertz on `msh` (the TOML of scripts/bench_solid.py), `tail` appended.
fn hertz_toml(msh: &Path, tail: &str) -> String {
    common::hertz_toml(msh, -4.6629e7, "nts", tail)
}

/// `signorini solve TOML --out DIR ARGS…` with `toml` written as
/// `dir/NAME.toml`: exit code, stdout + stderr.
fn solve(dir: &Path, name: &str, toml: &str, args: &[&str]) -> (i32, String) {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, toml).unwrap();
    let o = common::command()
        .arg("solve")
        .arg(&path)
        .arg("--out")
        .arg(dir.join(name))
        .args(args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code().unwrap_or(-1), text)
}

/// Hertz on the coarse mesh (`tail` appended to its TOML) solved in
/// `dir/coarse`: its checkpoint.
fn solve_coarse(dir: &Path, tail: &str) -> PathBuf {
    let (code, text) = solve(
        dir,
        "coarse",
        &hertz_toml(&data("hertz_coarse.msh"), tail),
        &[],
    );
    assert_eq!(code, 0, "{text}");
    dir.join("coarse/coarse.h5")
}

fn summary(dir: &Path, name: &str) -> Value {
    let s = std::fs::read_to_string(dir.join(name).join(format!("{name}.json"))).unwrap();
    serde_json::from_str(&s).unwrap()
}

/// The last step's displacements and active flags of run `name`.
fn answer(dir: &Path, name: &str) -> (Vec<[f64; 3]>, Vec<u8>) {
    let ck = read_solid_checkpoint(&dir.join(name).join(format!("{name}.h5")), SolidSteps::Last)
        .unwrap();
    let st = ck.steps.last().unwrap();
    (st.displacement.clone(), st.active.clone())
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> (f64, f64) {
    let d = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0f64, f64::max);
    let m = a.iter().flatten().fold(0.0f64, |x, v| x.max(v.abs()));
    (d, m)
}

#[test]
fn a_nested_start_gives_the_cold_answer_in_fewer_newton_steps() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let coarse = solve_coarse(dir, "");
    let fine = hertz_toml(&data("hertz.msh"), "");
    for path in ["iterative", "auto"] {
        let cold = format!("cold_{path}");
        let nested = format!("nested_{path}");
        let (code, text) = solve(dir, &cold, &fine, &["--ssn-path", path]);
        assert_eq!(code, 0, "{text}");
        let (code, text) = solve(
            dir,
            &nested,
            &fine,
            &["--ssn-path", path, "--start-from", coarse.to_str().unwrap()],
        );
        assert_eq!(code, 0, "{text}");
        assert!(text.contains("certified"), "{text}");
        let (jc, jn) = (summary(dir, &cold), summary(dir, &nested));
        assert!(jc.get("start_from").is_none());
        assert_eq!(jn["start_from"].as_str(), coarse.to_str(), "{jn}");
        let (ic, inn) = (
            jc["iterations"].as_u64().unwrap(),
            jn["iterations"].as_u64().unwrap(),
        );
        if path == "iterative" {
            assert!(
                inn < ic,
                "{path}: {inn} Newton steps from the nested start, {ic} cold"
            );
        } else {
            assert!(
                inn <= ic,
                "{path}: {inn} Newton steps from the nested start, {ic} cold"
            );
        }
        let ((uc, ac), (un, an)) = (answer(dir, &cold), answer(dir, &nested));
        assert_eq!(ac, an, "{path}: the working sets differ");
        let (d, m) = max_diff(&uc, &un);
        assert!(m > 0.0 && d <= 1e-8 * m, "{path}: |Δu| = {d:e} of {m:e}");
    }
}

/// Two load steps on both meshes: each fine step starts from the coarse
/// step at its pseudo-time, and the last is the cold run's answer.
#[test]
fn each_load_step_starts_from_the_coarse_step_at_its_time() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let steps = "\n[[steps]]\nfactor = 0.5\n\n[[steps]]\nfactor = 1.0\n";
    let coarse = solve_coarse(dir, steps);
    let fine = hertz_toml(&data("hertz.msh"), steps);
    let args = ["--ssn-path", "iterative"];
    let (code, text) = solve(dir, "cold", &fine, &args);
    assert_eq!(code, 0, "{text}");
    let (code, text) = solve(
        dir,
        "nested",
        &fine,
        &[args[0], args[1], "--start-from", coarse.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{text}");
    let (uc, ac) = answer(dir, "cold");
    let (un, an) = answer(dir, "nested");
    assert_eq!(ac, an);
    let (d, m) = max_diff(&uc, &un);
    assert!(d <= 1e-8 * m, "|Δu| = {d:e} of {m:e}");
    // Fewer Newton steps in all.
    let count = |name: &str| -> u64 {
        let ck = read_solid_checkpoint(&dir.join(name).join(format!("{name}.h5")), SolidSteps::All)
            .unwrap();
        assert_eq!(ck.steps.len(), 2);
        ck.steps.iter().map(|s| s.info.iterations as u64).sum()
    };
    let (c, n) = (count("cold"), count("nested"));
    assert!(n < c, "{n} Newton steps from the nested starts, {c} cold");
}

#[test]
fn a_start_that_is_not_of_this_model_is_refused_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let fine = hertz_toml(&data("hertz.msh"), "");
    // Another geometry: the stacked cubes (other materials).
    let stack = common::solid_stack_toml(
        &data("stack_nm.msh"),
        "slave = \"upper_bottom\"\nmaster = \"lower_top\"",
        -1e6,
        "",
    );
    let (code, text) = solve(dir, "stack", &stack, &[]);
    assert_eq!(code, 0, "{text}");
    let stack_h5 = dir.join("stack/stack.h5");
    let missing = dir.join("nowhere.h5");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["--start-from".into(), stack_h5.display().to_string()],
            "stack.h5",
        ),
        (
            vec!["--start-from".into(), missing.display().to_string()],
            "nowhere.h5",
        ),
        (
            vec![
                "--start-from".into(),
                stack_h5.display().to_string(),
                "--restart".into(),
                stack_h5.display().to_string(),
            ],
            "--restart",
        ),
    ];
    // A frictional model (its steps start from the last multipliers).
    let coarse = solve_coarse(dir, "");
    let (code, text) = solve(
        dir,
        "frictional",
        &format!("{fine}friction = 0.3\n"),
        &["--start-from", coarse.to_str().unwrap()],
    );
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("coarse.h5") && text.contains("friction"),
        "{text}"
    );
    assert!(!dir.join("frictional").exists());
    for (k, (args, named)) in cases.iter().enumerate() {
        let name = format!("bad{k}");
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, text) = solve(dir, &name, &fine, &args);
        assert_eq!(code, 2, "case {k}: {text}");
        assert!(text.contains(named), "case {k}: {text}");
        assert!(!text.contains("panicked"), "case {k}: {text}");
        assert!(
            !dir.join(&name).exists(),
            "case {k}: an output directory was made"
        );
    }
    // A 2D model (the shipped plane column).
    let toml = common::example("column");
    let o = common::command()
        .arg("solve")
        .arg(&toml)
        .arg("--out")
        .arg(dir.join("plane"))
        .arg("--start-from")
        .arg(&stack_h5)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(
        text.contains("--start-from") && text.contains("2D"),
        "{text}"
    );
    assert!(!dir.join("plane").exists());
}
