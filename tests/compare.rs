//! `signorini compare`: every variant on a small example; the rows agree.

use std::process::Command;

#[test]
fn compare_rows_agree_on_the_eccentric_blocks() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("t.json");
    let csv = dir.path().join("t.csv");
    let toml = format!(
        "{}/meshes/two_blocks_eccentric.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args([
            "compare",
            &toml,
            "--json",
            json.to_str().unwrap(),
            "--csv",
            csv.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = t["rows"].as_array().unwrap();
    // Six CGC preconditioners at least, one line each in the CSV.
    assert!(rows.len() >= 6);
    assert_eq!(
        std::fs::read_to_string(&csv).unwrap().lines().count(),
        rows.len() + 1
    );
    for r in rows {
        let name = format!("{} {}", r["method"], r["preconditioner"]);
        if r["method"] == "penalty" {
            // O(ε) accurate only; checked against ε in the method's own tests.
            continue;
        }
        if let Some(e) = r["error"].as_str() {
            // A method may refuse a semicoercive problem, with a reason.
            assert!(
                e.contains("floating") || e.contains("singular") || e.contains("semicoercive"),
                "{name}: {e}"
            );
            continue;
        }
        assert_eq!(r["converged"], true, "{name}");
        assert_eq!(r["agrees"], true, "{name}: rel diff {}", r["rel_diff"]);
        assert!(
            r["kkt_max"].as_f64().unwrap() <= 1e-8,
            "{name}: KKT {}",
            r["kkt_max"]
        );
    }
    assert!(stdout.contains("agrees"));
}
