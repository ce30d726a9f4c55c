//! Friction that the certificate decides (issue 42 §1, docs/methods.md
//! §9.1 "When the loop stops"): the report's geodynamic load-step model
//! (meshes/geodynamic_steps.toml) with Coulomb friction μ on its three
//! faults. At μ = 0.05–0.2 the Coulomb fixed point used to stop on its own
//! rule (a relative change of s ≤ 10⁻¹⁰, which the rounding of λ_n in the
//! Tresca solves kept at 5.7·10⁻⁹) after 200 Tresca solves, and the run
//! exited 3 "not converged" on answers whose KKT residuals, Coulomb's
//! included, were at 10⁻¹³.

mod common;

use common::{meshes, model_variant, run, sheared_blocks};

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

/// mprgp certifies every step at μ = 0.1 and 0.2, where its Tresca
/// solves used to stagnate at a projected gradient of 2–7·10⁻¹⁰ (tol
/// 10⁻¹⁰): the tangential rows where fault_cont_base and fault_ocean_base
/// end on the moving plates have all their unknowns prescribed, so their
/// slip is prescribed and their dual gradient a constant no multiplier
/// could cancel (docs/methods.md §9.1). Then the Coulomb loop stopped
/// after three stagnated solves (step 5 at μ = 0.1, steps 3–4 at 0.2).
#[test]
fn mprgp_certifies_every_step_at_mu_0_1_and_0_2() {
    let d = tempfile::tempdir().unwrap();
    for mu in [0.1, 0.2] {
        let model = frictional(mu, d.path());
        let out = d.path().join(format!("out_{mu}"));
        let (code, text) = run(&[
            "solve",
            &model,
            "--method",
            "mprgp",
            "--out",
            &out.display().to_string(),
        ]);
        assert_eq!(code, 0, "μ = {mu}:\n{text}");
        let steps: Vec<&str> = text.lines().filter(|l| l.starts_with("step ")).collect();
        assert_eq!(steps.len(), 5, "μ = {mu}:\n{text}");
        for s in &steps {
            assert!(s.contains(" converged in "), "μ = {mu}: {s}");
        }
        assert!(text.contains("→ certified"), "μ = {mu}:\n{text}");
        assert!(!text.contains("NOT certified"), "μ = {mu}:\n{text}");
    }
}

/// meshes/two_blocks with the upper block held only by friction μ = 0.12
/// ([`common::sheared_blocks`]) and sheared by a traction p = [1.1·10⁵,
/// −10⁶] Pa in three load steps.
fn sheared_steps(dir: &std::path::Path) -> String {
    let base = sheared_blocks("friction = 0.12", true);
    assert!(base.contains("p = [1.0e5, -1.0e6]"));
    let text = base
        .replace(
            "MESH",
            &meshes().join("two_blocks.msh").display().to_string(),
        )
        .replace("p = [1.0e5, -1.0e6]", "p = [1.1e5, -1.0e6]")
        + "[[steps]]\nfactor = 0.4\n[[steps]]\nfactor = 0.7\n[[steps]]\nfactor = 1.0\n";
    let p = dir.join("sheared_steps.toml");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

/// max |a − b| over every component, and max |b| (the scale it is judged by).
fn max_difference(a: &[[f64; 2]], b: &[[f64; 2]]) -> (f64, f64) {
    let scale = b
        .iter()
        .fold(0.0f64, |m, u| m.max(u[0].abs()).max(u[1].abs()));
    let diff = a.iter().zip(b).fold(0.0f64, |m, (p, q)| {
        m.max((p[0] - q[0]).abs()).max((p[1] - q[1]).abs())
    });
    (diff, scale)
}

/// The last step's displacements of a checkpoint.
fn last_displacement(h5: &std::path::Path) -> Vec<[f64; 2]> {
    let ck = signorini::io::hdf5::read_checkpoint(h5).unwrap();
    ck.steps.last().unwrap().displacement.clone()
}

/// Issue 42 §2: on ssn's sparse path (no coarse start there) a load step
/// starts from the last step's stick / slip / open sets and bound μλ_n,
/// says so in the debug log, gives the dual path's answer, and a restart
/// (which reads λ_n, λ_t from the checkpoint) gives the same bits as the
/// run it continues.
#[test]
fn sparse_path_load_steps_start_from_the_last_steps_sets() {
    let d = tempfile::tempdir().unwrap();
    let model = sheared_steps(d.path());
    let out = |k: &str| d.path().join(k).display().to_string();
    let (code, text) = run(&[
        "solve",
        &model,
        "--ssn-path",
        "augmented",
        "--log-level",
        "debug",
        "--out",
        &out("sparse"),
    ]);
    assert_eq!(code, 0, "{text}");
    assert_eq!(
        text.matches("the fixed point starts from the last step's bound")
            .count(),
        2,
        "{text}"
    );
    assert!(text.contains("the last step's sets: stick"), "{text}");
    let (code, text) = run(&["solve", &model, "--out", &out("dual")]);
    assert_eq!(code, 0, "{text}");
    let us = last_displacement(&d.path().join("sparse/sheared_steps.h5"));
    let ud = last_displacement(&d.path().join("dual/sheared_steps.h5"));
    let (diff, scale) = max_difference(&us, &ud);
    assert!(
        diff <= 1e-8 * scale,
        "sparse vs dual path: {diff:e} of {scale:e}"
    );
    // Two steps, then a restart for the third.
    let (code, text) = run(&[
        "solve",
        &model,
        "--ssn-path",
        "augmented",
        "--max-steps",
        "2",
        "--out",
        &out("part"),
    ]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = run(&[
        "solve",
        &model,
        "--ssn-path",
        "augmented",
        "--restart",
        &out("part/sheared_steps.h5"),
        "--out",
        &out("part"),
    ]);
    assert_eq!(code, 0, "{text}");
    let ur = last_displacement(&d.path().join("part/sheared_steps.h5"));
    assert!(
        ur == us,
        "the restart's last step differs from the whole run's"
    );
}

/// Issue 42 §2: mprgp with friction past 10 k unknowns says up front that
/// it will be slow and why (tests/data/ring, 11 k unknowns, with Coulomb
/// friction on its contacts); ssn does not.
#[test]
fn mprgp_with_friction_on_a_large_model_warns_up_front() {
    let d = tempfile::tempdir().unwrap();
    let dir = common::root().join("tests/data/ring");
    let model = model_variant(
        &dir,
        "ring.toml",
        &[("[[contact]]\n", "[[contact]]\nfriction = 0.2\n")],
        &d.path().join("ring_mu.toml"),
    );
    let m = model.display().to_string();
    let out = d.path().join("o").display().to_string();
    let (_, text) = run(&[
        "solve",
        &m,
        "--method",
        "mprgp",
        "--max-iter",
        "1",
        "--out",
        &out,
    ]);
    assert!(
        text.contains("whose steps grow in number with the mesh"),
        "{text}"
    );
    let (_, text) = run(&["solve", &m, "--max-iter", "1", "--out", &out]);
    assert!(!text.contains("grow in number with the mesh"), "{text}");
}

/// Issue 42 §2: the shrink fit pushed out (scripts/bench_models/
/// shrinkfit_push.{geo,toml}, here at nz = 200, nr = 6: 201 NTS rows)
/// takes a bounded number of Newton steps in every load step. Once the
/// push passes the sliding displacement, the friction forces of the whole
/// interface move the tube more than the push does: every row slipping
/// one way makes it slip the other. The coarse levels flipped all their
/// rows back and forth, stopped on a repeat with every row slipping, and
/// the problem's own steps then walked the stick zone in from there (93
/// Newton steps; 177 at nz = 400). A coarse level now sticks a row whose
/// prediction reverses its slip (docs/methods.md §9.2). The last step
/// slips everywhere: the axial force on the interface is μ times the
/// normal one.
/// scripts/bench_models/shrinkfit_push.{geo,toml} meshed at `nz`, `nr`
/// into `dir`: the model's path.
fn pushed_shrink_fit(dir: &std::path::Path, nz: usize, nr: usize) -> String {
    let models = common::root().join("scripts/bench_models");
    let geo = std::fs::read_to_string(models.join("shrinkfit_push.geo")).unwrap();
    assert!(geo.contains("nz = {400,") && geo.contains("nr = {12,"));
    let geo = geo
        .replace("nz = {400,", &format!("nz = {{{nz},"))
        .replace("nr = {12,", &format!("nr = {{{nr},"));
    std::fs::write(dir.join("sf.geo"), geo).unwrap();
    let msh = dir.join("sf.msh").display().to_string();
    let geo = dir.join("sf.geo").display().to_string();
    let (code, log) = run(&["mesh", &geo, "-o", &msh]);
    assert_eq!(code, 0, "{log}");
    let toml = std::fs::read_to_string(models.join("shrinkfit_push.toml")).unwrap();
    assert!(toml.contains("file = \"shrinkfit_push.msh\""));
    let model = dir.join("sf.toml");
    std::fs::write(&model, toml.replace("shrinkfit_push.msh", "sf.msh")).unwrap();
    model.display().to_string()
}

#[test]
fn the_pushed_shrink_fit_takes_few_newton_steps_a_load_step() {
    let d = tempfile::tempdir().unwrap();
    let model = pushed_shrink_fit(d.path(), 200, 6);
    let out = d.path().join("out").display().to_string();
    let (code, text) = run(&["solve", &model, "--log-level", "debug", "--out", &out]);
    assert_eq!(code, 0, "{text}");
    assert!(text.matches("coarse start: (rows").count() >= 5, "{text}");
    let newton = text.matches("|N| = ").count();
    assert!(newton <= 20, "{newton} Newton steps in six load steps");
    let steps: Vec<&str> = text.lines().filter(|l| l.starts_with("step ")).collect();
    assert_eq!(steps.len(), 6, "{text}");
    assert!(steps.iter().all(|s| s.contains(" converged in ")), "{text}");
    assert!(text.contains("→ certified"), "{text}");
    // Full slip in the last step: |F_t| = μ |F_n| over the interface.
    let ck = signorini::io::hdf5::read_checkpoint(&d.path().join("out/sf.h5")).unwrap();
    let ln = &ck.steps.last().unwrap().multipliers;
    let lt = &ck.friction.last().unwrap().as_ref().unwrap().multipliers_t;
    let (sn, st): (f64, f64) = (ln.iter().sum(), lt.iter().map(|v| v.abs()).sum());
    assert!(
        (st - 0.2 * sn).abs() <= 1e-9 * sn,
        "Σ|λ_t| {st:e} vs μ Σλ_n {:e}",
        0.2 * sn
    );
}

/// A shrink fit with walls four elements thick (nz = 640, nr = 4: 5.8 k
/// nodes, 641 rows) has a border of B = [A; T] of 2304 = 21·√n unknowns:
/// over the frictionless path's 12·√n, it took the sparse path (341
/// Newton steps, 7.3 times the frictionless run). The frictional dual
/// form allows 48·√n (docs/methods.md §9.2): a few Newton steps a load
/// step, the second one of a step a low-rank change of the first one's
/// LU, and the sparse path's answer to 1e-8.
#[test]
fn a_thin_walled_shrink_fit_takes_the_dual_form() {
    let d = tempfile::tempdir().unwrap();
    let model = pushed_shrink_fit(d.path(), 640, 4);
    let out = |k: &str| d.path().join(k).display().to_string();
    let (code, text) = run(&[
        "solve",
        &model,
        "--log-level",
        "debug",
        "--out",
        &out("dual"),
    ]);
    assert_eq!(code, 0, "{text}");
    assert!(!text.contains("the sparse path"), "{text}");
    assert!(text.contains("as a rank-"), "{text}");
    let newton = text.matches("|N| = ").count();
    assert!(newton <= 20, "{newton} Newton steps in six load steps");
    assert!(text.contains("→ certified"), "{text}");
    let (code, text) = run(&[
        "solve",
        &model,
        "--ssn-path",
        "augmented",
        "--out",
        &out("sparse"),
    ]);
    assert_eq!(code, 0, "{text}");
    let ud = last_displacement(&d.path().join("dual/sf.h5"));
    let us = last_displacement(&d.path().join("sparse/sf.h5"));
    let (diff, scale) = max_difference(&us, &ud);
    assert!(
        diff <= 1e-8 * scale,
        "dual vs sparse path: {diff:e} of {scale:e}"
    );
}

/// The certificate decides for the direct Coulomb iteration too (issue 42
/// §1): at μ = 0.15 the direct iteration of step 3 reaches an iterate
/// exact to 10⁻¹² (KKT residual), then predicts a working set whose
/// Coulomb system is singular (rows that depend on each other where the
/// faults meet) and stopped as failed, and the iterate was thrown away for
/// the glued start and the fixed point: 52 Newton steps over the five
/// steps. Now the stopped iteration's last iterate is taken when it passes
/// the certificate, as a stopped Tresca solve's is (docs/methods.md §9.1).
#[test]
fn a_stopped_direct_iteration_whose_iterate_passes_is_taken() {
    let d = tempfile::tempdir().unwrap();
    let model = frictional(0.15, d.path());
    let out = d.path().join("out").display().to_string();
    let (code, text) = run(&["solve", &model, "--log-level", "debug", "--out", &out]);
    assert_eq!(code, 0, "{text}");
    assert!(
        text.contains("but its last iterate passes the certificate"),
        "{text}"
    );
    let newton: usize = text
        .lines()
        .filter(|l| l.starts_with("step ") && l.contains(" converged in "))
        .map(|l| {
            l.split(" converged in ")
                .nth(1)
                .and_then(|r| r.split_whitespace().next())
                .and_then(|n| n.parse::<usize>().ok())
                .unwrap_or_else(|| panic!("{l}"))
        })
        .sum();
    assert!(newton <= 40, "{newton} Newton steps over the five steps");
    assert!(text.contains("→ certified"), "{text}");
}

/// The sparse augmented-Lagrangian steps that ssn takes where H_JJ is
/// singular (the dependent rows where the geodynamic faults meet) ran all
/// 200 sweeps: |Bx − b| stalls at 1.4·10⁻¹³ of max(|x|, |b|), above the
/// 10⁻¹⁴ they stopped at. They now stop when three sweeps in a row do not
/// halve it (docs/methods.md §9.2): μ = 0.05 in 0.55 s instead of 1.7 s,
/// the same Newton steps, certified.
#[test]
fn sparse_steps_stop_when_their_residual_stalls() {
    let d = tempfile::tempdir().unwrap();
    let model = frictional(0.05, d.path());
    let out = d.path().join("out").display().to_string();
    let (code, text) = run(&["solve", &model, "--log-level", "debug", "--out", &out]);
    assert_eq!(code, 0, "{text}");
    let sweeps: Vec<usize> = text
        .lines()
        .filter_map(|l| l.split("sparse step: ").nth(1))
        .map(|r| r.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    assert!(!sweeps.is_empty(), "{text}");
    assert!(sweeps.iter().all(|&s| s <= 20), "{sweeps:?}");
    assert!(text.contains("→ certified"), "{text}");
}
