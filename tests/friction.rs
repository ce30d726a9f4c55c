//! Friction (docs/methods.md §9): a block on an inclined plane sticks below
//! the friction angle and is refused as sliding above it; Cattaneo–Mindlin
//! partial slip; μ = 0 is the frictionless model bit for bit and a huge μ is
//! the tangentially glued interface.

mod common;

use common::{meshes, root, run, sheared_blocks};
use signorini::fem::Model;
use signorini::post::friction::{friction_output, FrictionOutput};
use signorini::qp::{QpResult, SolverSection};
use signorini::run::{self, Prepared};
use std::path::{Path, PathBuf};

/// Write `toml` next to a copy of the mesh `msh` in `dir`.
fn model_file(dir: &Path, name: &str, msh: &Path, toml: &str) -> PathBuf {
    let mname = msh.file_name().unwrap();
    std::fs::copy(msh, dir.join(mname)).unwrap();
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, toml.replace("MESH", mname.to_str().unwrap())).unwrap();
    p
}

/// Every load step of `path` by `method` through the library; the last
/// step's model (None: the prepared one) and result.
fn solve(path: &Path, method: &str) -> (Prepared, Option<Model>, QpResult) {
    let prep = run::prepare(path, false).unwrap_or_else(|e| panic!("{e}"));
    let flags = SolverSection {
        method: Some(method.parse().unwrap()),
        ..Default::default()
    };
    let (m, opts) = run::options(&prep.problem, &flags).unwrap();
    let out = run::Run::new(&prep, m, &opts)
        .solve(&mut [], None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(out.certified, "{}: not certified", path.display());
    let last = out.last.unwrap();
    (prep, last.model, last.result)
}

/// Every load step of `prep` by `method` on `ssn_path` (None: the default).
fn run_path(
    prep: &Prepared,
    method: &str,
    path: Option<&str>,
) -> Result<run::Outcome, run::RunError> {
    let flags = SolverSection {
        method: Some(method.parse().unwrap()),
        ssn_path: path.map(|p| p.parse().unwrap()),
        ..Default::default()
    };
    let (m, opts) = run::options(&prep.problem, &flags).unwrap();
    run::Run::new(prep, m, &opts).solve(&mut [], None)
}

/// The floating block of meshes/floating_block.msh (no support but the
/// contact) on its foundation, under gravity g = 9.81 turned by θ: the
/// inclined plane. Both bodies plane strain, the foundation held.
fn inclined(theta: f64, law: &str) -> String {
    let g = 9.81;
    format!(
        r#"[mesh]
file = "MESH"
[model]
plane = "strain"
gravity = [{}, {}]
[materials.foundation]
E = 3.0e10
nu = 0.2
rho = 2400.0
[materials.block]
E = 1.0e10
nu = 0.25
rho = 2500.0
[[dirichlet]]
on = "found_bottom"
u = [0.0, 0.0]
[[slip]]
on = "found_left"
[[slip]]
on = "found_right"
[[contact]]
on = "interface"
{law}
"#,
        g * theta.sin(),
        -g * theta.cos()
    )
}

#[test]
fn a_block_on_an_inclined_plane_sticks_below_the_friction_angle() {
    let d = tempfile::tempdir().unwrap();
    let msh = meshes().join("floating_block.msh");
    let mu = 0.5;
    // The block's weight per unit thickness (1 m × 1 m, ρ = 2500).
    let w = 2500.0 * 9.81;
    for (k, tan) in [0.1, 0.3, 0.45].into_iter().enumerate() {
        let theta = f64::atan(tan);
        for law in [format!("friction = {mu}"), format!("tresca = {}", 0.5 * w)] {
            let p = model_file(d.path(), &format!("stick{k}"), &msh, &inclined(theta, &law));
            let (prep, _, res) = solve(&p, "ssn");
            let fo = friction_output(&prep.model, &res).expect("friction outputs");
            let ln: f64 = res.lambda.iter().sum();
            let lt: f64 = res.lambda_t.iter().sum();
            // The contact holds the block's weight: λ_n = W cos θ, λ_t = W sin θ.
            assert!(
                (ln - w * theta.cos()).abs() < 1e-8 * w,
                "{law}: Σλ_n = {ln}"
            );
            assert!(
                (lt.abs() / ln - tan).abs() < 1e-9,
                "{law}: Σλ_t/Σλ_n = {} for tan θ = {tan}",
                lt.abs() / ln
            );
            // The block does not slide: a stick zone holds it (rows near the
            // corners may slip where the shear traction concentrates, more
            // under Tresca's uniform bound as tan θ nears μ) and the stick
            // rows do not move.
            assert!(fo.stick_count > 0, "{law}: {fo:?}");
            if tan <= 0.3 {
                assert!(2 * fo.stick_count >= fo.state.len(), "{law}: {fo:?}");
            }
            let umax = res.x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (s, v) in fo.state.iter().zip(&fo.slip) {
                if *s == 1 {
                    assert!(v.abs() <= 1e-9 * umax, "{law}: stick row slips {v}");
                }
            }
        }
    }
}

#[test]
fn a_block_above_the_friction_angle_is_refused_as_sliding() {
    let d = tempfile::tempdir().unwrap();
    let msh = meshes().join("floating_block.msh");
    for (law, tan) in [("friction = 0.5", 0.55), ("friction = 0.2", 0.3)] {
        let p = model_file(d.path(), "slide", &msh, &inclined(f64::atan(tan), law));
        let (code, log) = run(&[
            "solve",
            p.to_str().unwrap(),
            "--method",
            "ssn",
            "--out",
            d.path().join("out").to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{log}");
        assert!(log.contains("unbounded") && log.contains("slides"), "{log}");
        assert!(log.contains("translation along (1, 0)"), "{log}");
    }
}

#[test]
fn methods_without_friction_are_refused_and_bad_keys_are_named() {
    let d = tempfile::tempdir().unwrap();
    let msh = meshes().join("floating_block.msh");
    let p = model_file(d.path(), "m", &msh, &inclined(0.1, "friction = 0.5"));
    let out = d.path().join("out");
    let (code, log) = run(&[
        "solve",
        p.to_str().unwrap(),
        "--method",
        "cgc",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{log}");
    assert!(
        log.contains("does not solve contact with friction") && log.contains("ssn"),
        "{log}"
    );
    for (law, want) in [
        ("friction = 0.5\ntresca = 1.0", "not both"),
        ("friction = -0.1", "friction = -0.1 must be"),
        ("tresca = nan", "tresca = NaN must be"),
    ] {
        let p = model_file(d.path(), "bad", &msh, &inclined(0.1, law));
        let (code, log) = run(&["solve", p.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert_eq!(code, 2, "{law}: {log}");
        assert!(
            log.contains(want) && log.contains("bad.toml"),
            "{law}: {log}"
        );
    }
}

/// The Cattaneo–Mindlin mesh, made by gmsh from tests/data/friction/cattaneo.geo.
fn cattaneo_mesh(dir: &Path) -> PathBuf {
    let geo = root().join("tests/data/friction/cattaneo.geo");
    std::fs::create_dir_all(dir.join("gmsh")).unwrap();
    let out = dir.join("gmsh/cattaneo.msh");
    let (code, log) = run(&["mesh", geo.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    out
}

/// x of each contact row's slave point and the half-width of the set of
/// rows with `pick(state)`: the mean over both sides of the midpoint
/// between the outermost picked row and the next row beyond it.
fn half_width(prep: &Prepared, fo: &FrictionOutput, pick: impl Fn(u8) -> bool) -> f64 {
    let t = &prep.model.topo;
    let mut rows: Vec<(f64, bool)> = t
        .contact
        .iter()
        .zip(&fo.state)
        .map(|(r, &s)| (t.points[r.first][0], pick(s)))
        .collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let first = rows.iter().position(|r| r.1).unwrap();
    let last = rows.iter().rposition(|r| r.1).unwrap();
    assert!(
        first > 0 && last + 1 < rows.len(),
        "the set reaches the end of the curve"
    );
    let left = 0.5 * (rows[first].0 + rows[first - 1].0);
    let right = 0.5 * (rows[last].0 + rows[last + 1].0);
    0.5 * (right - left)
}

/// The Cattaneo–Mindlin model: the cylinder's top lowered by 12 mm in step
/// 1, then moved sideways by 3 mm in step 2.
fn cattaneo_toml(mu: f64) -> String {
    format!(
        r#"[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.cylinder]
E = 2.0e11
nu = 0.3
[materials.block]
E = 2.0e11
nu = 0.3
[[dirichlet]]
on = "block_bottom"
u = [0.0, 0.0]
[[dirichlet]]
on = "cyl_top"
u = [0.0, 0.0]
[[contact]]
slave = "cyl_contact"
master = "block_top"
friction = {mu}
[[steps]]
dirichlet = {{ cyl_top = [0.0, -0.012] }}
[[steps]]
dirichlet = {{ cyl_top = [0.003, -0.012] }}
[solver]
method = "ssn"
"#
    )
}

#[test]
fn cattaneo_mindlin_stick_zone() {
    // A cylinder pressed by P (its top lowered by 12 mm), then pulled by
    // Q < μP (its top moved sideways by 3 mm) in a second load step; the
    // two bodies are elastically similar, so normal and tangential problems
    // uncouple and the stick zone is |x| ≤ c = a·√(1 − Q/(μP)) (Johnson,
    // Contact Mechanics, 1985, §7.1), with a, P, Q measured on the solution.
    let d = tempfile::tempdir().unwrap();
    let msh = cattaneo_mesh(d.path());
    let mu = 0.3;
    let p = model_file(d.path(), "cattaneo", &msh, &cattaneo_toml(mu));
    let (prep, model, res) = solve(&p, "ssn");
    let fo = friction_output(model.as_ref().unwrap(), &res).unwrap();
    let pn: f64 = res.lambda.iter().sum();
    let q: f64 = res.lambda_t.iter().sum::<f64>().abs();
    let ratio = q / (mu * pn);
    assert!(ratio > 0.3 && ratio < 0.8, "Q/(μP) = {ratio}");
    let a = half_width(&prep, &fo, |s| s > 0);
    let c = half_width(&prep, &fo, |s| s == 1);
    let want = (1.0 - ratio).sqrt();
    eprintln!(
        "P = {pn:.4e}, Q = {q:.4e}, Q/(μP) = {ratio:.4}, a = {a:.5}, c = {c:.5}, c/a = {:.4}, want {want:.4}",
        c / a
    );
    assert!(
        fo.slip_count > 4 && fo.stick_count > 4,
        "{} {}",
        fo.stick_count,
        fo.slip_count
    );
    assert!(
        ((c / a) / want - 1.0).abs() < 0.04,
        "c/a = {} want {want}",
        c / a
    );
    // The slip zones slip the same way, along λ_t (the certificate's rule).
    for (s, (v, l)) in fo.state.iter().zip(fo.slip.iter().zip(&fo.lambda_t)) {
        if *s == 2 {
            assert!(v * l >= 0.0, "slip {v} against λ_t {l}");
        }
    }
}

#[test]
fn zero_friction_is_frictionless_bit_for_bit() {
    let d = tempfile::tempdir().unwrap();
    for (name, toml) in [
        ("floating_block", "floating_block.toml"),
        ("hertz", "hertz.toml"),
    ] {
        let src = std::fs::read_to_string(meshes().join(toml)).unwrap();
        let with = src.replace("[[contact]]", "[[contact]]\nfriction = 0.0");
        assert_ne!(src, with);
        let mut outs = vec![];
        for (k, text) in [src, with].iter().enumerate() {
            let p = model_file(
                d.path(),
                &format!("{name}{k}"),
                &meshes().join(format!("{name}.msh")),
                text,
            );
            let out = d.path().join(format!("out{name}{k}"));
            let (code, log) = run(&[
                "solve",
                p.to_str().unwrap(),
                "--method",
                "ssn",
                "--out",
                out.to_str().unwrap(),
            ]);
            assert_eq!(code, 0, "{log}");
            outs.push((out, format!("{name}{k}")));
        }
        for ext in [".vtu", "_contact.vtu"] {
            let a = std::fs::read(outs[0].0.join(format!("{}{ext}", outs[0].1))).unwrap();
            let b = std::fs::read(outs[1].0.join(format!("{}{ext}", outs[1].1))).unwrap();
            assert!(a == b, "{name}{ext} differs with friction = 0");
        }
    }
}

#[test]
fn huge_friction_is_the_glued_interface() {
    let d = tempfile::tempdir().unwrap();
    let msh = meshes().join("two_blocks.msh");
    let glued = model_file(d.path(), "glued", &msh, &sheared_blocks("", false));
    let (gprep, _, gres) = solve(&glued, "cgc");
    let ug = gprep.model.displacements(&gres.x);
    for law in ["friction = 1.0e6", "tresca = 1.0e12"] {
        let p = model_file(d.path(), "rough", &msh, &sheared_blocks(law, true));
        let (prep, _, res) = solve(&p, "ssn");
        let fo = friction_output(&prep.model, &res).unwrap();
        assert_eq!(fo.slip_count, 0, "{law}");
        assert_eq!(
            fo.stick_count,
            fo.state.len(),
            "{law}: the interface stays closed"
        );
        // Same points (an interface node has a copy per body): compare by position.
        let u = prep.model.displacements(&res.x);
        let umax = ug
            .iter()
            .fold(0.0f64, |m, v| m.max(v[0].abs()).max(v[1].abs()));
        let gp = &gprep.model.topo.points;
        let mut worst = 0.0f64;
        for (p, x) in prep.model.topo.points.iter().enumerate() {
            let q = signorini::post::nearest_point(gp, *x);
            assert!((gp[q][0] - x[0]).abs() + (gp[q][1] - x[1]).abs() < 1e-12);
            worst = worst
                .max((u[p][0] - ug[q][0]).abs())
                .max((u[p][1] - ug[q][1]).abs());
        }
        assert!(
            worst <= 1e-8 * umax,
            "{law}: max |u − u_glued| = {worst:.3e} of {umax:.3e}"
        );
        // The shear is carried: Σλ_t = the top traction's x resultant.
        let lt: f64 = res.lambda_t.iter().sum();
        assert!(
            (lt.abs() - 1.0e5).abs() < 1e-6 * 1.0e5,
            "{law}: Σλ_t = {lt}"
        );
    }
}

#[test]
fn a_restart_after_the_first_step_slips_as_the_uninterrupted_run() {
    // The slip of step 2 is measured from step 1's displacements, which a
    // restart reads back from the checkpoint.
    let d = tempfile::tempdir().unwrap();
    let msh = cattaneo_mesh(d.path());
    let p = model_file(d.path(), "cm", &msh, &cattaneo_toml(0.3));
    let p = p.to_str().unwrap();
    let full = d.path().join("full");
    let part = d.path().join("part");
    let (code, log) = run(&[
        "solve",
        p,
        "--method",
        "ssn",
        "--out",
        full.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    let (code, log) = run(&[
        "solve",
        p,
        "--out",
        part.to_str().unwrap(),
        "--max-steps",
        "1",
    ]);
    assert_eq!(code, 0, "{log}");
    let ck = part.join("cm.h5");
    let (code, log) = run(&[
        "solve",
        p,
        "--method",
        "ssn",
        "--out",
        part.to_str().unwrap(),
        "--restart",
        ck.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    let a = signorini::io::vtu::read_vtu_arrays(&full.join("cm_0002_contact.vtu")).unwrap();
    let b = signorini::io::vtu::read_vtu_arrays(&part.join("cm_0002_contact.vtu")).unwrap();
    for name in ["slip", "state", "tangential_traction"] {
        let (x, y) = (a.point_array(name).unwrap(), b.point_array(name).unwrap());
        assert_eq!(x.values, y.values, "{name}");
    }
    // Step 2 slips (the zones at the edges of the contact).
    let slip = &a.point_array("slip").unwrap().values;
    assert!(slip.iter().any(|v| v.abs() > 1e-7), "{slip:?}");
}

/// [`solve`] with the relative tolerance `tol`.
fn solve_tol(path: &Path, method: &str, tol: f64) -> (Prepared, QpResult) {
    let prep = run::prepare(path, false).unwrap_or_else(|e| panic!("{e}"));
    let flags = SolverSection {
        method: Some(method.parse().unwrap()),
        tol: Some(tol),
        ..Default::default()
    };
    let (m, opts) = run::options(&prep.problem, &flags).unwrap();
    let out = run::Run::new(&prep, m, &opts)
        .solve(&mut [], None)
        .unwrap_or_else(|e| panic!("{method}: {e}"));
    assert!(out.certified, "{}: not certified", path.display());
    let res = out.last.unwrap().result;
    assert!(res.kkt.within(1e-8), "{method}: {:?}", res.kkt);
    (prep, res)
}

/// max |a − b| / max |a|
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    d / scale.max(f64::MIN_POSITIVE)
}

#[test]
fn ssn_and_mprgp_agree_on_the_frictional_models() {
    // Verification (4) of issue 16: the primal active set method and the
    // box-constrained dual (docs/methods.md §9.2) are independent solvers of
    // the same Tresca/Coulomb problems; they agree to 1e-6 in x, λ_n, λ_t.
    let d = tempfile::tempdir().unwrap();
    let w = 2500.0 * 9.81;
    let block = meshes().join("floating_block.msh");
    let blocks = meshes().join("two_blocks.msh");
    let cat = cattaneo_mesh(d.path());
    let cases = [
        ("incl_c", &block, inclined(f64::atan(0.3), "friction = 0.5")),
        (
            "incl_t",
            &block,
            inclined(f64::atan(0.45), &format!("tresca = {}", 0.5 * w)),
        ),
        ("shear_c", &blocks, sheared_blocks("friction = 0.12", true)),
        ("shear_t", &blocks, sheared_blocks("tresca = 1.1e5", true)),
        ("cattaneo", &cat, cattaneo_toml(0.3)),
    ];
    for (name, msh, toml) in cases {
        let p = model_file(d.path(), name, msh, &toml);
        let (_, rs) = solve_tol(&p, "ssn", 1e-10);
        let (_, rm) = solve_tol(&p, "mprgp", 1e-10);
        let (dx, dn, dt) = (
            rel_diff(&rs.x, &rm.x),
            rel_diff(&rs.lambda, &rm.lambda),
            rel_diff(&rs.lambda_t, &rm.lambda_t),
        );
        eprintln!(
            "{name}: x {dx:.2e}, λ_n {dn:.2e}, λ_t {dt:.2e}; mprgp {} steps, {} solves with K",
            rm.iterations, rm.inner_iterations
        );
        assert!(
            dx <= 1e-6 && dn <= 1e-6 && dt <= 1e-6,
            "{name}: x {dx:e}, λ_n {dn:e}, λ_t {dt:e}"
        );
        // The dual Hessian of these few rows is formed once (docs/methods.md
        // §9.2): its steps are products with it, not solves with K (each
        // step was one or two solves before).
        assert!(
            2 * rm.inner_iterations <= rm.iterations,
            "{name}: mprgp took {} solves with K in {} steps",
            rm.inner_iterations,
            rm.iterations
        );
    }
}

/// Issue 34: the friction residual is unitless in μ and s (docs/methods.md
/// §9.4). The sheared two_blocks is certified by every friction-capable
/// method at μ = 0.12 (14 of 21 rows slip), 0.3, 10³ and 10⁶ and under a
/// Tresca bound of 10¹² (glued). Before, the residual grew like s × the
/// slip a solve leaves: mprgp's glued answers had 3.6·10⁻⁵ at μ = 10⁶ and
/// at s = 10¹² (exit 3). A tangential force flipped on the slipping row of
/// most dissipation still fails the friction residual.
#[test]
fn the_certificate_does_not_depend_on_mu_or_the_bound() {
    use signorini::qp::{kkt, MethodId};
    let d = tempfile::tempdir().unwrap();
    let msh = meshes().join("two_blocks.msh");
    let able: Vec<MethodId> = MethodId::ALL
        .into_iter()
        .filter(|m| m.capabilities().friction.any())
        .collect();
    assert!(able.contains(&MethodId::Ssn) && able.contains(&MethodId::Mprgp));
    for law in [
        "friction = 0.12",
        "friction = 0.3",
        "friction = 1.0e3",
        "friction = 1.0e6",
        "tresca = 1.0e12",
    ] {
        let p = model_file(d.path(), "scan", &msh, &sheared_blocks(law, true));
        for m in &able {
            // `solve` asserts that the run is certified (exit 0).
            let (prep, _, res) = solve(&p, m.name());
            let target = signorini::qp::settings::DEFAULT_KKT_TARGET;
            assert!(
                res.status.converged() && res.kkt.within(target),
                "{law}, {m}: {:?}",
                res.kkt
            );
            if law != "friction = 0.12" {
                continue;
            }
            let qp = &prep.model.qp;
            let fr = qp.friction.as_ref().unwrap();
            let s = fr.slip_bound(&res.lambda);
            let v = fr.slip(&res.x);
            let (row, _) = (0..qp.m())
                .filter(|&i| res.lambda_t[i].abs() >= (1.0 - 1e-6) * s[i] && s[i] > 0.0)
                .map(|i| (i, s[i] * v[i].abs()))
                .fold((usize::MAX, 0.0f64), |b, c| if c.1 > b.1 { c } else { b });
            assert!(row < qp.m(), "{m}: no slipping row");
            let mut lt = res.lambda_t.clone();
            lt[row] = -lt[row];
            let k = kkt::residuals_with_friction(qp, &res.x, &res.lambda, &lt);
            assert!(k.friction > target && !k.within(target), "{m}: {k:?}");
        }
    }
}

#[test]
fn the_checkpoint_holds_the_friction_arrays() {
    // docs/problem-format.md §6: a frictional step group has multipliers_t,
    // tangential_traction, slip and state; a frictionless one has none.
    let d = tempfile::tempdir().unwrap();
    let msh = meshes().join("floating_block.msh");
    let tan = 0.3;
    let theta = f64::atan(tan);
    let w = 2500.0 * 9.81;
    let shipped = std::fs::read_to_string(meshes().join("floating_block.toml")).unwrap();
    for (name, law) in [("rough", "friction = 0.5"), ("smooth", "")] {
        // Without friction: the shipped (frictionless) floating block.
        let toml = if law.is_empty() {
            shipped.clone()
        } else {
            inclined(theta, law)
        };
        let p = model_file(d.path(), name, &msh, &toml);
        let out = d.path().join(format!("out_{name}"));
        let method = if law.is_empty() { "cgc" } else { "mprgp" };
        let (code, log) = run(&[
            "solve",
            p.to_str().unwrap(),
            "--method",
            method,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{log}");
        let ck = signorini::io::hdf5::read_checkpoint(&out.join(format!("{name}.h5"))).unwrap();
        assert_eq!(ck.friction.len(), 1);
        let rows = ck.mesh.contact.points.len();
        match &ck.friction[0] {
            None => assert!(law.is_empty(), "{name}: no friction arrays"),
            Some(f) => {
                assert!(!law.is_empty(), "{name}: friction arrays without friction");
                assert_eq!(f.state.len(), rows);
                let lt: f64 = f.multipliers_t.iter().sum();
                assert!((lt.abs() - w * theta.sin()).abs() < 1e-6 * w, "Σλ_t = {lt}");
                assert!(f.state.iter().all(|&s| s == 1 || s == 2), "{:?}", f.state);
                assert!(f.state.iter().filter(|&&s| s == 1).count() * 2 >= rows);
                let ratio: Vec<f64> = f
                    .tangential_traction
                    .iter()
                    .zip(&f.multipliers_t)
                    .zip(&ck.steps[0].contact_pressure)
                    .zip(&ck.steps[0].multipliers)
                    .filter(|(_, &ln)| ln > 0.0)
                    .map(|(((tt, lt), p), ln)| (tt / lt) / (p / ln))
                    .collect();
                // Traction and pressure share the tributary length.
                assert!(
                    ratio
                        .iter()
                        .all(|r| (r - 1.0).abs() < 1e-9 || !r.is_finite()),
                    "{ratio:?}"
                );
            }
        }
    }
}

/// tests/data/friction/floating_punch.geo meshed by gmsh with element size
/// `h` (2.2 k nodes and 21 contact rows at its h = 0.05).
fn punch_mesh(dir: &Path, h: f64) -> PathBuf {
    let text =
        std::fs::read_to_string(root().join("tests/data/friction/floating_punch.geo")).unwrap();
    assert!(text.contains("h = 0.05;"));
    std::fs::create_dir_all(dir.join("gmsh")).unwrap();
    let geo = dir.join(format!("gmsh/punch_{h}.geo"));
    std::fs::write(&geo, text.replace("h = 0.05;", &format!("h = {h};"))).unwrap();
    let out = dir.join(format!("gmsh/punch_{h}.msh"));
    let (code, log) = run(&["mesh", geo.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    out
}

/// The punch of issue 36: a steel punch on a softer foundation, pressed by
/// 1 MPa and pushed sideways by a third of μN, held tangentially by
/// Coulomb friction (μ = 0.3) alone: no Dirichlet condition touches it.
const PUNCH: &str = r#"[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.foundation]
E = 2.0e10
nu = 0.3
[materials.punch]
E = 2.0e11
nu = 0.3
[[dirichlet]]
on = "found_bottom"
u = [0.0, 0.0]
[[dirichlet]]
on = "found_sides"
ux = 0.0
[[traction]]
on = "punch_top"
pn = -1.0e6
[[traction]]
on = "punch_left"
p = [2.0e5, 0.0]
[[contact]]
slave = "punch_bottom"
master = "found_top"
friction = 0.3
"#;

/// Issue 36: ssn solves Coulomb's problem on one bordered factor, in the
/// dual space, with the slip bound inside the Newton iteration
/// (docs/methods.md §9.2). On the floating punch: certified, Coulomb's
/// law met to rounding (friction residual 2·10⁻¹⁷; the fixed point of
/// Tresca problems left 1.9·10⁻¹²), in 2 Newton steps (8, then 3 from the
/// glued start, before the coarse start) and 2
/// sparse solves (40 before: a factor of C + ρBᵀB per Newton step and
/// augmented Lagrangian sweeps); the sparse path (`ssn_path =
/// "augmented"`) and mprgp agree with it to 10⁻⁶. The load balances: the
/// interface carries the side load and the pressure.
#[test]
fn a_punch_held_by_friction_alone_is_solved_on_one_factor() {
    let d = tempfile::tempdir().unwrap();
    let msh = punch_mesh(d.path(), 0.05);
    let p = model_file(d.path(), "punch", &msh, PUNCH);
    let prep = run::prepare(&p, false).unwrap_or_else(|e| panic!("{e}"));
    let mut results = vec![];
    for (method, path) in [("ssn", None), ("ssn", Some("augmented")), ("mprgp", None)] {
        let out =
            run_path(&prep, method, path).unwrap_or_else(|e| panic!("{method} {path:?}: {e}"));
        assert!(out.certified, "{method} {path:?}: not certified");
        let r = out.last.unwrap().result;
        let s = &r.solution;
        eprintln!(
            "{method} {path:?}: {} Newton, {} inner, friction residual {:.2e}",
            s.iterations, s.inner_iterations, r.kkt.friction
        );
        results.push(r);
    }
    let ssn = &results[0];
    assert!(
        ssn.solution.iterations <= 4 && ssn.solution.inner_iterations <= 3,
        "{} Newton steps, {} sparse solves",
        ssn.solution.iterations,
        ssn.solution.inner_iterations
    );
    assert!(ssn.kkt.friction < 1e-14, "{:?}", ssn.kkt);
    let pn: f64 = ssn.lambda.iter().sum();
    let pt: f64 = ssn.lambda_t.iter().sum();
    assert!(
        (pn.abs() - 1.0e6).abs() < 1e-6 * 1.0e6 && (pt.abs() - 1.0e5).abs() < 1e-6 * 1.0e6,
        "normal {pn:e}, tangential {pt:e}"
    );
    assert!(
        ssn.lambda_t
            .iter()
            .zip(&ssn.lambda)
            .any(|(t, n)| t.abs() >= 0.3 * n * (1.0 - 1e-9) && *n > 0.0),
        "no row slips"
    );
    for (other, r) in ["ssn (augmented)", "mprgp"].iter().zip(&results[1..]) {
        let (dx, dn, dt) = (
            rel_diff(&ssn.x, &r.x),
            rel_diff(&ssn.lambda, &r.lambda),
            rel_diff(&ssn.lambda_t, &r.lambda_t),
        );
        assert!(
            dx <= 1e-6 && dn <= 1e-6 && dt <= 1e-6,
            "{other}: x {dx:e}, λ_n {dn:e}, λ_t {dt:e}"
        );
    }
}

/// Issue 36: ssn's Newton count on the floating punch does not grow with
/// the mesh. From the glued start the front of the slip zone moved one or
/// two rows per Newton step (3 / 5 / 7 steps at 21 / 46 / 101 rows); the
/// coarse levels (docs/methods.md §9.2) place it, and the problem's own
/// steps correct it by a few rows. At each size: certified, at most 3
/// Newton steps, the answer of the sparse path (which has no coarse
/// levels: the glued start and the fixed point of Tresca problems) to
/// 10⁻⁶, and a slip zone as wide as the finest mesh's to within two rows.
#[test]
fn the_punchs_newton_count_does_not_grow_with_the_mesh() {
    let d = tempfile::tempdir().unwrap();
    let mut widths = vec![];
    for h in [0.05, 0.0225, 0.01] {
        let msh = punch_mesh(d.path(), h);
        let p = model_file(d.path(), &format!("punch_{h}"), &msh, PUNCH);
        let prep = run::prepare(&p, false).unwrap_or_else(|e| panic!("{e}"));
        let mut results = vec![];
        for path in [None, Some("augmented")] {
            let out =
                run_path(&prep, "ssn", path).unwrap_or_else(|e| panic!("h = {h} {path:?}: {e}"));
            assert!(out.certified, "h = {h} {path:?}: not certified");
            results.push(out.last.unwrap().result);
        }
        let (ssn, sparse) = (&results[0], &results[1]);
        let rows = ssn.lambda.len();
        eprintln!(
            "h = {h}: {rows} rows, {} Newton steps (sparse path {})",
            ssn.solution.iterations, sparse.solution.iterations
        );
        assert!(
            ssn.solution.iterations <= 3,
            "h = {h}: {} Newton steps",
            ssn.solution.iterations
        );
        let (dx, dt) = (
            rel_diff(&ssn.x, &sparse.x),
            rel_diff(&ssn.lambda_t, &sparse.lambda_t),
        );
        assert!(dx <= 1e-6 && dt <= 1e-6, "h = {h}: x {dx:e}, λ_t {dt:e}");
        let slipping = ssn
            .lambda_t
            .iter()
            .zip(&ssn.lambda)
            .filter(|(t, n)| **n > 0.0 && t.abs() >= 0.3 * **n * (1.0 - 1e-9))
            .count();
        widths.push((h, slipping as f64 * h));
    }
    let finest = widths.last().unwrap().1;
    assert!(finest > 0.0, "no row slips: {widths:?}");
    for &(h, w) in &widths {
        assert!((w - finest).abs() <= 2.0 * h, "slip zone widths {widths:?}");
    }
}

/// A stiff half-disc 5·10⁻⁴ above a block 10⁴ times softer, pressed by P
/// and pushed sideways by Q = μP/2: friction holds it once the load closes
/// the gap. It was refused as sliding along the push: no row was closed at
/// the start, so the glued solve kept N empty (its free motions solved as if
/// held) and the bound μλ_n was zero everywhere (docs/methods.md §9.3). Now
/// every row starts in N when the closed ones leave a motion free, and only
/// a Tresca problem's bound decides that a body slides. Certified, the
/// interface carries P and Q, and some rows stick.
#[test]
fn a_disc_pressed_across_a_gap_and_pushed_sideways_is_held() {
    let d = tempfile::tempdir().unwrap();
    let geo = root().join("tests/data/friction/disc_gap.geo");
    std::fs::create_dir_all(d.path().join("gmsh")).unwrap();
    let msh = d.path().join("gmsh/disc_gap.msh");
    let (code, log) = run(&["mesh", geo.to_str().unwrap(), "-o", msh.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    let toml = r#"[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.block]
E = 2.0e7
nu = 0.45
[materials.disc]
E = 2.0e11
nu = 0.3
[[dirichlet]]
on = "bottom"
u = [0.0, 0.0]
[[dirichlet]]
on = "sides"
ux = 0.0
[[traction]]
on = "disc_top"
p = [3.0e4, -2.0e5]
[[contact]]
slave = "disc_arc"
master = "block_top"
friction = 0.3
"#;
    let p = model_file(d.path(), "disc", &msh, toml);
    let (_, _, r) = solve(&p, "ssn");
    // disc_top is 2 m long: P = 4·10⁵ N/m, Q = 6·10⁴ N/m.
    let pn: f64 = r.lambda.iter().sum();
    let pt: f64 = r.lambda_t.iter().sum();
    assert!(
        (pn.abs() - 4.0e5).abs() < 1e-6 * 4.0e5 && (pt.abs() - 6.0e4).abs() < 1e-6 * 4.0e5,
        "normal {pn:e}, tangential {pt:e}"
    );
    let sticking = r
        .lambda_t
        .iter()
        .zip(&r.lambda)
        .filter(|(t, n)| **n > 0.0 && t.abs() < 0.3 * **n * (1.0 - 1e-6))
        .count();
    assert!(sticking > 0, "no row sticks");
    eprintln!(
        "{} Newton steps, {sticking} rows stick",
        r.solution.iterations
    );
}

/// `ssn_path = "iterative"` (AMG-PCG on K) solves friction on solid
/// models' discs only (docs/methods.md §12.3); on a plane model's lines it
/// is refused by name, not solved as if frictionless, and the same model
/// on `ssn_path = "auto"` is certified.
#[test]
fn plane_friction_on_the_iterative_path_is_refused_by_name() {
    let d = tempfile::tempdir().unwrap();
    let msh = punch_mesh(d.path(), 0.1);
    let p = model_file(d.path(), "punch", &msh, PUNCH);
    let prep = run::prepare(&p, false).unwrap_or_else(|e| panic!("{e}"));
    match run_path(&prep, "ssn", Some("iterative")) {
        Ok(out) => panic!("solved on the iterative path: certified {}", out.certified),
        Err(e) => {
            let text = format!("{e:#}");
            assert!(
                text.contains("solid models") && text.contains("§12.3"),
                "{text}"
            );
        }
    }
    let out = run_path(&prep, "ssn", Some("auto")).unwrap_or_else(|e| panic!("{e}"));
    assert!(out.certified);
}
