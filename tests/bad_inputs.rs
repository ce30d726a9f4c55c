//! The catalogue of bad inputs (`tests/bad_inputs/CASE/`): every case must
//! give exit code 2 and one `error:` line on stderr that contains the words of
//! its `expect.toml`, never a panic, and no output file at all.
//!
//! A case is a directory with `problem.toml` (and `mesh.msh` when the mesh is
//! the bad part) and `expect.toml`:
//!
//! ```toml
//! exit = 2
//! words = ["problem.toml", "roof", "no physical group"]
//! out = "problem.toml/out"   # optional: --out relative to the case directory
//! args = ["--max-steps", "0"] # optional: more flags; `{case}` = the case directory
//! ```

use serde::Deserialize;
use std::path::{Path, PathBuf};

mod common;

/// Fewer cases than this means cases were deleted.
const MIN_CASES: usize = 131;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Expect {
    exit: i32,
    words: Vec<String>,
    /// Output directory relative to the case directory (default: a fresh
    /// temporary directory).
    out: Option<String>,
    /// More command-line flags (`{case}` is replaced by the case directory).
    #[serde(default)]
    args: Vec<String>,
}

fn cases_dir() -> PathBuf {
    common::root().join("tests/bad_inputs")
}

fn cases() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(cases_dir())
        .expect("tests/bad_inputs exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    v.sort();
    v
}

/// Every file under `dir` (relative paths, sorted); empty if `dir` does not exist.
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            out.push(p.strip_prefix(dir).unwrap_or(&p).to_path_buf());
        }
    }
    out.sort();
    out
}

/// Runs one case; `Err` describes every way it failed.
fn run_case(case: &Path) -> Result<(), String> {
    let name = case.file_name().unwrap().to_string_lossy().into_owned();
    let text = std::fs::read_to_string(case.join("expect.toml"))
        .map_err(|e| format!("{name}: cannot read expect.toml: {e}"))?;
    let expect: Expect =
        toml::from_str(&text).map_err(|e| format!("{name}: bad expect.toml: {e}"))?;
    if expect.words.is_empty() {
        return Err(format!("{name}: expect.toml lists no words"));
    }
    let problem = case.join("problem.toml");
    if !problem.is_file() {
        return Err(format!("{name}: no problem.toml"));
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = match &expect.out {
        Some(o) => case.join(o),
        None => tmp.path().join("out"),
    };
    let before = files_under(case);
    let o = common::command()
        .args(["solve", problem.to_str().unwrap(), "--out"])
        .arg(&out)
        .args(
            expect
                .args
                .iter()
                .map(|a| a.replace("{case}", &case.display().to_string())),
        )
        .arg("--quiet")
        // Write nothing relative to the working directory by accident.
        .current_dir(tmp.path())
        .output()
        .map_err(|e| format!("{name}: cannot run signorini: {e}"))?;
    let code = o.status.code().unwrap_or(-1);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let mut errs = vec![];
    if code != expect.exit {
        errs.push(format!("exit code {code}, expected {}", expect.exit));
    }
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
        errs.push("a panic".to_string());
    }
    let error_lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.trim_start().starts_with("error"))
        .collect();
    if error_lines.len() != 1 {
        errs.push(format!(
            "{} `error:` lines on stderr, expected one",
            error_lines.len()
        ));
    }
    let line = error_lines.first().copied().unwrap_or("").to_lowercase();
    // Numbers in short form: 1e200, not its 201 digits (issue 43).
    let longest_digits = line
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0);
    if longest_digits > 24 {
        errs.push(format!(
            "the error line has a number of {longest_digits} digits (print it in short form)"
        ));
    }
    for w in &expect.words {
        if !line.contains(&w.to_lowercase()) {
            errs.push(format!("the error line lacks {w:?}"));
        }
    }
    let written = files_under(&out);
    if !written.is_empty() {
        errs.push(format!(
            "files written to the output directory: {written:?}"
        ));
    }
    let after = files_under(case);
    if after != before {
        errs.push(format!(
            "the case directory changed: {:?}",
            after
                .iter()
                .filter(|p| !before.contains(p))
                .collect::<Vec<_>>()
        ));
    }
    let stray = files_under(tmp.path())
        .into_iter()
        .filter(|p| !p.starts_with("out"))
        .collect::<Vec<_>>();
    if !stray.is_empty() {
        errs.push(format!("files written to the working directory: {stray:?}"));
    }
    if errs.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{name}: {}\n    stderr: {}\n    stdout: {}",
            errs.join("; "),
            stderr.trim_end().replace('\n', "\n            "),
            stdout.trim_end()
        ))
    }
}

#[test]
fn every_bad_input_exits_2_with_one_clear_line_and_no_output() {
    let cases = cases();
    assert!(
        cases.len() >= MIN_CASES,
        "only {} cases in tests/bad_inputs (at least {MIN_CASES} expected)",
        cases.len()
    );
    let failures: Vec<String> = cases.iter().filter_map(|c| run_case(c).err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {} bad-input cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

#[test]
fn every_case_directory_is_complete() {
    for c in cases() {
        for f in ["problem.toml", "expect.toml"] {
            assert!(c.join(f).is_file(), "{}: no {f}", c.display());
        }
        let e: Expect = toml::from_str(&std::fs::read_to_string(c.join("expect.toml")).unwrap())
            .unwrap_or_else(|e| panic!("{}: {e}", c.display()));
        assert_eq!(e.exit, 2, "{}: bad input means exit 2", c.display());
    }
}
