//! `signorini solve` on a 3D frictional model through the binary (issue
//! 46): a soft cube (E = 2e7 Pa, ν = 0.45) on a steel one, non-matching
//! mortar rows with Coulomb μ = 0.3, the upper cube held tangentially by
//! friction alone, a pressure 1e6 Pa and a tangential traction on its top
//! (1 m²). Under 0.6 μN the answer is certified and the interface carries
//! the tangential load exactly (statics of the upper cube); under 1.03 μN
//! no equilibrium exists: the run is refused as unbounded, naming the body
//! that slides, exit 2, nothing written. (Before the fix the second run
//! ended in "C is not positive definite": the springs across the slip of
//! a body sliding away vanish and the Newton matrix with them.)

mod common;

use serde_json::Value;
use std::path::Path;

/// `signorini solve` of the problem `text` written in `dir`, with `flags`,
/// to dir/out: (exit code, stdout + stderr).
fn run(dir: &Path, text: &str, flags: &[&str]) -> (i32, String) {
    let path = dir.join("cube.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out");
    let mut args = vec!["solve", path.to_str().unwrap()];
    args.extend_from_slice(flags);
    args.extend(["--out", out.to_str().unwrap()]);
    common::run(&args)
}

/// `signorini solve TOML -q --ssn-path PATH --out OUT`, which must exit 0,
/// and its JSON report.
fn solve_on_path(toml: &Path, ssn_path: &str, out: &Path) -> Value {
    let o = common::command()
        .args([
            "solve",
            toml.to_str().unwrap(),
            "-q",
            "--ssn-path",
            ssn_path,
            "--out",
        ])
        .arg(out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{} on {ssn_path}: {o:?}",
        toml.display()
    );
    let stem = toml.file_stem().unwrap().to_str().unwrap();
    let text = std::fs::read_to_string(out.join(format!("{stem}.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The soft cube on the steel one, pushed by `pt` on its top.
/// The resultant of the interface `name` in a run's JSON, as [fx, fy, fz].
fn interface_force(json: &Value, name: &str) -> Vec<f64> {
    json["contact"][name]["force"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

fn cube(pt: [f64; 2]) -> String {
    common::soft_cube_toml(["lower_x0", "lower_y0"], pt, "")
}

/// A run refused as unbounded: exit 2, the sliding body and friction
/// named, nothing written to dir/out.
fn assert_refused_as_sliding(dir: &Path, code: i32, text: &str) {
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("unbounded"), "{text}");
    assert!(text.contains("\"upper\""), "{text}");
    assert!(text.contains("friction"), "{text}");
    assert!(!text.contains("positive definite"), "{text}");
    let written = std::fs::read_dir(dir.join("out"))
        .map(|d| d.count())
        .unwrap_or(0);
    assert_eq!(written, 0, "an unbounded run writes nothing");
}

#[test]
fn a_soft_cube_held_by_friction_carries_a_tangential_load_below_mu_n() {
    let dir = tempfile::tempdir().unwrap();
    let pt = [1.5e5, 1.0e5]; // ‖pt‖ = 1.80e5 = 0.6 μN
    let (code, text) = run(dir.path(), &cube(pt), &[]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("certified"), "{text}");
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("out/cube.json")).unwrap())
            .unwrap();
    let it = &json["contact"]["upper_bottom/lower_top"];
    let f = interface_force(&json, "upper_bottom/lower_top");
    // The slave side's resultant balances the loads on the upper cube.
    let want = [-pt[0], -pt[1], 1.0e6];
    for k in 0..3 {
        assert!(
            (f[k] - want[k]).abs() <= 1e-6 * 1.0e6,
            "component {k}: {} vs {}",
            f[k],
            want[k]
        );
    }
    assert!(f[0].hypot(f[1]) <= 0.3 * f[2] * (1.0 + 1e-9));

    // The multigrid path (docs/methods.md §12.3), on the body that friction
    // alone holds: certified, the same interface force.
    let multigrid = dir.path().join("multigrid");
    std::fs::create_dir(&multigrid).unwrap();
    let (code, text) = run(&multigrid, &cube(pt), &["--ssn-path", "iterative"]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("certified"), "{text}");
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(multigrid.join("out/cube.json")).unwrap())
            .unwrap();
    let g = &json["contact"]["upper_bottom/lower_top"]["force"];
    for k in 0..3 {
        assert!(
            (g[k].as_f64().unwrap() - f[k]).abs() <= 1e-6 * 1.0e6,
            "component {k}: {g} vs {f:?}"
        );
    }

    // The footprint names the stick/slip border only where both zones
    // exist (with every row slipping it would trace the open zone's edge).
    let svg = dir.path().join("fp.svg");
    let o = common::command()
        .args(["plot", "--contact", "-o"])
        .arg(&svg)
        .arg(dir.path().join("out/cube.h5"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let text = std::fs::read_to_string(&svg).unwrap();
    let at = text
        .find(" stick, ")
        .expect("stick/slip counts in the title");
    let head = &text[..at];
    let stick: usize = head[head.rfind(|c: char| !c.is_ascii_digit()).unwrap() + 1..]
        .parse()
        .unwrap();
    let tail = &text[at + " stick, ".len()..];
    let slip: usize = tail[..tail.find(' ').unwrap()].parse().unwrap();
    let active = it["active"].as_u64().unwrap() as usize;
    assert_eq!(stick + slip, active, "{stick} stick, {slip} slip");
    assert_eq!(
        text.contains("white line"),
        stick > 0 && slip > 0,
        "{stick} stick, {slip} slip"
    );
}

#[test]
fn a_soft_cube_pushed_past_mu_n_is_refused_as_unbounded() {
    let dir = tempfile::tempdir().unwrap();
    let pt = [2.5e5, 1.8e5]; // ‖pt‖ = 3.08e5 = 1.03 μN
    let (code, text) = run(dir.path(), &cube(pt), &[]);
    assert_refused_as_sliding(dir.path(), code, &text);
}

/// The same cube under Tresca friction (s = 3·10⁵ Pa, below the push's
/// 3.08·10⁵) solved by mprgp: its SMALBE stagnates (exit 3 and a written,
/// uncertified answer before), and the driver decides the Tresca problem
/// unbounded from the rigid motions (docs/methods.md §9.3): exit 2, the
/// sliding body named, nothing written. With s = 3.2·10⁵ the run is not
/// refused as unbounded.
#[test]
fn mprgp_pushed_past_a_tresca_bound_is_refused_as_unbounded() {
    for (s, unbounded) in [("3.0e5", true), ("3.2e5", false)] {
        let dir = tempfile::tempdir().unwrap();
        let text = cube([2.5e5, 1.8e5]).replace("friction = 0.3", &format!("tresca = {s}"));
        let (code, text) = run(dir.path(), &text, &["--method", "mprgp"]);
        if unbounded {
            assert_refused_as_sliding(dir.path(), code, &text);
        } else {
            assert!(!text.contains("unbounded"), "s = {s}: {text}");
        }
    }
}

/// The quarter of two stacked cubes (conforming interface, aluminium on
/// steel, 1e8 Pa on the top, Coulomb μ = 0.3): the glued start's
/// interface has Ax = g = 0 and T x = t₀ = 0, and on the dual path (no x
/// until the solve ends) the residual's length scale was rounding, so the
/// glued solve ran its whole cycling budget (198 Newton steps here, 2m +
/// 100) before Coulomb's loop began. Now the scale is floored as the
/// certificate's is (docs/methods.md §8.4) and it takes a few steps; the
/// sparse path (`--ssn-path augmented`) and the multigrid one
/// (`--ssn-path iterative`, AMG-PCG on K, §12.3) give the same interface
/// forces and the same stick zone.
#[test]
fn the_dual_path_does_not_cycle_on_a_glued_conforming_interface() {
    let dir = tempfile::tempdir().unwrap();
    let msh = common::root().join("tests/data/solid_contact/stack.msh");
    let path = dir.path().join("stack.toml");
    // Aluminium's ν = 0.33: with the helper's 0.25 the two expansions are
    // close enough that every row sticks, and the test wants both zones.
    let toml = common::solid_stack_toml(&msh, "on = \"interface\"\nfriction = 0.3", -1.0e8, "")
        .replace("nu = 0.25", "nu = 0.33");
    assert!(toml.contains("nu = 0.33"), "{toml}");
    std::fs::write(&path, toml).unwrap();
    let solve = |path_arg: &str, out: &str| solve_on_path(&path, path_arg, &dir.path().join(out));
    let dual = solve("schur", "dual");
    let sparse = solve("augmented", "sparse");
    let multigrid = solve("iterative", "multigrid");
    for j in [&dual, &sparse, &multigrid] {
        assert_eq!(j["kkt"]["certified"], Value::Bool(true), "{j}");
    }
    let it = dual["iterations"].as_u64().unwrap();
    assert!(it <= 20, "{it} Newton steps on the dual path");
    let c = &dual["contact"]["interface"];
    let stick = c["stick"].as_u64().unwrap();
    let slip = c["slip"].as_u64().unwrap();
    assert!(stick > 0 && slip > 0, "{stick} stick, {slip} slip");
    let a = interface_force(&dual, "interface");
    for other in [&sparse, &multigrid] {
        let b = interface_force(other, "interface");
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-7 * a[2].abs(), "{a:?} vs {b:?}");
        }
        assert_eq!(c["stick"], other["contact"]["interface"]["stick"]);
    }
}

/// The same stack under Tresca (s = 2·10⁷ Pa, both zones) and Coulomb, at
/// `--tol 1e-15`, below the rounding floor of the dense dual (its residual
/// wanders near 10⁻¹³ on one set): ssn stops when its sets repeat without
/// halving the residual (docs/methods.md §12.3). Before, each Tresca solve
/// ran its cycling budget (511 Newton steps here; 84 577 on the 42 k-DOF
/// stack of BENCHMARKS.md). The answer is the one at the default tol.
#[test]
fn a_tol_below_the_rounding_floor_ends_at_the_floor() {
    let dir = tempfile::tempdir().unwrap();
    let msh = common::root().join("tests/data/solid_contact/stack.msh");
    for (law, name) in [("tresca = 2.0e7", "tresca"), ("friction = 0.3", "coulomb")] {
        let path = dir.path().join(format!("{name}.toml"));
        let contact = format!("on = \"interface\"\n{law}");
        let toml =
            common::solid_stack_toml(&msh, &contact, -1.0e8, "").replace("nu = 0.25", "nu = 0.33");
        std::fs::write(&path, toml).unwrap();
        let solve = |tol: &str| -> Value {
            let out = dir.path().join(format!("{name}_{tol}"));
            let o = common::command()
                .args(["solve", path.to_str().unwrap(), "-q", "--tol", tol, "--out"])
                .arg(&out)
                .output()
                .unwrap();
            assert_eq!(o.status.code(), Some(0), "{o:?}");
            let text = std::fs::read_to_string(out.join(format!("{name}.json"))).unwrap();
            serde_json::from_str(&text).unwrap()
        };
        let (tight, usual) = (solve("1e-15"), solve("1e-10"));
        // Coulomb's direct iteration holds s = μλ_n inside the step (the
        // dual path's coupled rows, docs/methods.md §12.3): 5 Newton steps
        // at the default tol, 7 with the last iterate's bound.
        let usual_it = usual["iterations"].as_u64().unwrap();
        assert!(
            name == "tresca" || usual_it <= 5,
            "{name}: {usual_it} Newton steps at tol 1e-10"
        );
        assert_eq!(tight["kkt"]["certified"], Value::Bool(true), "{tight}");
        // Coulomb's glued start ends as soon as its sets repeat, without
        // the floor's three steps (docs/methods.md §12.3): 8 Newton steps,
        // 11 before; Tresca (no glued start) 10.
        let it = tight["iterations"].as_u64().unwrap();
        let most = if name == "coulomb" { 8 } else { 20 };
        assert!(it <= most, "{name}: {it} Newton steps at tol 1e-15");
        let (a, b) = (
            &tight["contact"]["interface"],
            &usual["contact"]["interface"],
        );
        assert!(a["slip"].as_u64().unwrap() > 0, "{name}: {a}");
        assert_eq!(a["stick"], b["stick"], "{name}");
        assert_eq!(a["slip"], b["slip"], "{name}");
        let fz = |c: &Value| c["force"][2].as_f64().unwrap();
        let fx = |c: &Value| c["force"][0].as_f64().unwrap();
        assert!((fz(a) - fz(b)).abs() <= 1e-9 * fz(b).abs(), "{name}");
        assert!((fx(a) - fx(b)).abs() <= 1e-9 * fz(b).abs(), "{name}");
    }
}

/// At zero load no row carries a force, so every row is open, whatever the
/// method (post::friction::row_state): mprgp keeps the closed gaps of a
/// conforming interface active and, with s = μ·0 = 0, counted all 45 rows
/// as slipping where ssn counted none.
#[test]
fn at_zero_load_every_row_is_open_whatever_the_method() {
    let dir = tempfile::tempdir().unwrap();
    let msh = common::root().join("tests/data/solid_contact/stack.msh");
    for contact in [
        "on = \"interface\"\nfriction = 0.3",
        "on = \"interface\"\ntresca = 1e6",
    ] {
        let text = common::solid_stack_toml(&msh, contact, 0.0, "");
        for method in ["ssn", "mprgp"] {
            let (code, out) = run(dir.path(), &text, &["--method", method]);
            assert_eq!(code, 0, "{method} {contact}: {out}");
            assert!(
                out.contains("'interface': 0 rows stick, 0 slip"),
                "{method} {contact}: {out}"
            );
        }
    }
}

/// Tresca on the multigrid path (docs/methods.md §12.3): its one problem is
/// the answer, so it is solved to `tol`, not to the Coulomb loop's inexact
/// δ² (which ended it at a friction residual of 6·10⁻³, not certified,
/// before). The soft cube under s = 2·10⁵ Pa slips everywhere; both paths
/// certify it with the same interface force.
#[test]
fn tresca_on_the_multigrid_path_is_solved_to_tol() {
    let dir = tempfile::tempdir().unwrap();
    let text = cube([1.5e5, 1.0e5]).replace("friction = 0.3", "tresca = 2.0e5");
    assert!(text.contains("tresca = 2.0e5"), "{text}");
    let mut forces = vec![];
    for path in ["auto", "iterative"] {
        let sub = dir.path().join(path);
        std::fs::create_dir(&sub).unwrap();
        let (code, out) = run(&sub, &text, &["--ssn-path", path]);
        assert_eq!(code, 0, "{path}: {out}");
        assert!(
            out.contains("certified") && !out.contains("NOT certified"),
            "{path}: {out}"
        );
        let json: Value =
            serde_json::from_str(&std::fs::read_to_string(sub.join("out/cube.json")).unwrap())
                .unwrap();
        assert!(
            json["kkt"]["friction"].as_f64().unwrap() < 1e-9,
            "{path}: {}",
            json["kkt"]
        );
        forces.push(interface_force(&json, "upper_bottom/lower_top"));
    }
    for k in 0..3 {
        assert!(
            (forces[0][k] - forces[1][k]).abs() <= 1e-6 * 1.0e6,
            "{forces:?}"
        );
    }
}

/// A soft cube (E = 2·10⁷ Pa, ν = 0.49, on steel: a contrast of 10⁴)
/// sheared obliquely under Tresca friction, almost every row slipping.
/// The coarse start (docs/methods.md §12.3) classed a row as slipping
/// that the answer has on the disc's rim, and Newton's steps on its
/// direction gained ×0.7 a step: the solve ended at a residual of 3·10⁻³
/// as if at a rounding floor and was not certified. Now a floor lies below
/// the certificate's target, and a solve from the coarse kinds that has not
/// ended in 12 steps gives way to the method's own start. Certified, with
/// the sparse path's interface force, under Coulomb too.
#[test]
fn a_soft_cube_sheared_under_tresca_is_certified_from_the_coarse_start() {
    let dir = tempfile::tempdir().unwrap();
    let msh = common::root().join("tests/data/solid_contact/stack.msh");
    for law in ["tresca = 2.0e5", "friction = 0.4"] {
        let toml = format!(
            "[mesh]\nfile = {msh:?}\n\n[materials.lower]\nE = 2.0e11\nnu = 0.3\n\n\
             [materials.upper]\nE = 2.0e7\nnu = 0.49\n\n[[slip]]\non = \"x0\"\n\n\
             [[slip]]\non = \"y0\"\n\n[[slip]]\non = \"bottom\"\n\n[[traction]]\n\
             on = \"top\"\np = [2.0e5, 1.0e5, -1.0e6]\n\n[[contact]]\non = \"interface\"\n{law}\n"
        );
        let path = dir.path().join("soft.toml");
        std::fs::write(&path, toml).unwrap();
        let force = |path_arg: &str| -> Vec<f64> {
            let j = solve_on_path(&path, path_arg, &dir.path().join(path_arg));
            assert_eq!(j["kkt"]["certified"], Value::Bool(true), "{law}: {j}");
            interface_force(&j, "interface")
        };
        let (a, b) = (force("auto"), force("augmented"));
        for k in 0..3 {
            assert!(
                (a[k] - b[k]).abs() <= 1e-6 * a[2].abs(),
                "{law}: {a:?} vs {b:?}"
            );
        }
    }
}
