//! Friction that the certificate decides (issue 42 §1, docs/methods.md
//! §9.1 "When the loop stops"): the report's geodynamic load-step model
//! (meshes/geodynamic_steps.toml) with Coulomb friction μ on its three
//! faults. At μ = 0.05–0.2 the Coulomb fixed point used to stop on its own
//! rule (a relative change of s ≤ 10⁻¹⁰, which the rounding of λ_n in the
//! Tresca solves kept at 5.7·10⁻⁹) after 200 Tresca solves, and the run
//! exited 3 "not converged" on answers whose KKT residuals, Coulomb's
//! included, were at 10⁻¹³.

mod common;

use common::{meshes, model_variant, run};

/// The faults of geodynamic_steps.toml with `friction = mu`.
fn frictional(mu: f64, dir: &std::path::Path) -> String {
    let edits: Vec<(String, String)> = ["fault_cont_base", "fault_subduction", "fault_ocean_base"]
        .iter()
        .map(|f| {
            (
                format!("on = \"{f}\"\n"),
                format!("on = \"{f}\"\nfriction = {mu}\n"),
            )
        })
        .collect();
    let edits: Vec<(&str, &str)> = edits
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    let out = dir.join(format!("geo_{mu}.toml"));
    model_variant(&meshes(), "geodynamic_steps.toml", &edits, &out)
        .display()
        .to_string()
}

/// Every step of every μ is certified by ssn (exit 0, five step lines
/// that say converged), and each whole run's Newton steps stay far below
/// the 200 Tresca solves the fixed point used to spend on one step.
#[test]
fn every_step_of_the_geodynamic_mu_scan_is_certified() {
    let d = tempfile::tempdir().unwrap();
    for mu in [0.05, 0.1, 0.15, 0.2, 0.3, 0.6] {
        let model = frictional(mu, d.path());
        let out = d.path().join(format!("out_{mu}"));
        let (code, text) = run(&["solve", &model, "--out", &out.display().to_string()]);
        assert_eq!(code, 0, "μ = {mu}:\n{text}");
        let steps: Vec<&str> = text.lines().filter(|l| l.starts_with("step ")).collect();
        assert_eq!(steps.len(), 5, "μ = {mu}:\n{text}");
        for s in &steps {
            assert!(s.contains(" converged in "), "μ = {mu}: {s}");
            let iters: usize = s
                .split(" converged in ")
                .nth(1)
                .and_then(|r| r.split_whitespace().next())
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("μ = {mu}: {s}"));
            assert!(iters <= 100, "μ = {mu}: {s}");
        }
        assert!(text.contains("→ certified"), "μ = {mu}:\n{text}");
        assert!(text.contains("friction residual"), "μ = {mu}:\n{text}");
    }
}
