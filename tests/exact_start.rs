//! No method stalls on an exact start (issue 42 §3, docs/methods.md §8.4):
//! a flat punch pressed by a prescribed displacement (tests/data/
//! pressed_punch) closes every row with g = 0, so A x = g = 0 at the
//! answer. The dual method took ‖A x(λ)‖ there as the scale of its
//! residual and ran 10 000 iterations (MAXIT with --max-iter) on an answer
//! whose every KKT residual was at rounding, exiting 3.

mod common;

use common::{root, run};

fn model() -> String {
    root()
        .join("tests/data/pressed_punch/pressed_punch.toml")
        .display()
        .to_string()
}

/// The number after `status      converged after`.
fn iterations(out: &str) -> usize {
    let line = out
        .lines()
        .find(|l| l.starts_with("status"))
        .unwrap_or_else(|| panic!("no status line:\n{out}"));
    line.split_whitespace()
        .skip_while(|w| *w != "after")
        .nth(1)
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no count in {line}"))
}

#[test]
fn the_dual_method_stops_on_a_pressed_punch() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().display().to_string();
    let (code, text) = run(&[
        "solve",
        &model(),
        "--method",
        "dual",
        "--max-iter",
        "30",
        "--out",
        &out,
    ]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("certified (≤"), "{text}");
    assert!(
        !text.contains("note "),
        "a note where the method stops on its own:\n{text}"
    );
    let n = iterations(&text);
    assert!(n <= 10, "dual: {n} iterations\n{text}");
}

#[test]
fn every_method_is_certified_on_a_pressed_punch() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().display().to_string();
    for m in [
        "ssn", "mprgp", "dual", "uzawa", "penalty", "preelim", "asm", "asm-cgh", "cgc",
    ] {
        let (code, text) = run(&["solve", &model(), "--method", m, "--out", &out]);
        assert_eq!(code, 0, "{m}:\n{text}");
        assert!(text.contains("certified (≤"), "{m}:\n{text}");
    }
}
