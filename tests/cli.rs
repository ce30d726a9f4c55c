//! The `signorini` binary: outputs read back, JSON schema, exit codes, and
//! bad input that must give exit 2 with one clear line and no output file.

mod common;

use common::{example, root, signorini};

#[test]
fn solve_writes_all_four_outputs_with_the_contract_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (code, stdout, stderr) =
        signorini(&["solve", &example("two_blocks_eccentric"), "--out", out]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("certified"), "{stdout}");
    let base = dir.path().join("two_blocks_eccentric");
    // VTU: point and cell arrays of the contract.
    let v = signorini::io::vtu::read_vtu_arrays(&base.with_extension("vtu")).unwrap();
    let names: Vec<&str> = v
        .point_data
        .iter()
        .chain(&v.cell_data)
        .map(|a| a.name.as_str())
        .collect();
    for n in [
        "displacement",
        "body",
        "stress",
        "von_mises",
        "principal_stress",
        "material",
    ] {
        assert!(names.contains(&n), "{n} missing in {names:?}");
    }
    let disp = v.point_array("displacement").unwrap();
    assert_eq!(disp.num_comp, 3);
    assert_eq!(disp.values.len(), 3 * v.num_points);
    assert_eq!(
        v.cell_array("stress").unwrap().num_comp,
        4,
        "plane strain writes σzz"
    );
    assert!(disp.values.iter().all(|x| x.is_finite()));
    // Contact VTU.
    let c =
        signorini::io::vtu::read_vtu_arrays(&dir.path().join("two_blocks_eccentric_contact.vtu"))
            .unwrap();
    for n in ["contact_pressure", "gap", "active", "normal"] {
        assert!(c.point_array(n).is_some(), "{n} missing in contact VTU");
    }
    assert!(c.num_cells > 0);
    // HDF5 checkpoint.
    let ck = signorini::io::hdf5::read_checkpoint(&base.with_extension("h5")).unwrap();
    assert_eq!(ck.steps.len(), 1);
    assert_eq!(ck.mesh.points.len(), v.num_points);
    assert_eq!(ck.steps[0].displacement.len(), v.num_points);
    assert!(ck.steps[0].info.converged);
    assert_eq!(ck.steps[0].info.method, "ssn");
    assert!(ck.steps[0].active.contains(&0) && ck.steps[0].active.contains(&1));
    // The VTU displacement equals the checkpoint's.
    for (i, u) in ck.steps[0].displacement.iter().enumerate() {
        assert_eq!(disp.values[3 * i], u[0]);
        assert_eq!(disp.values[3 * i + 1], u[1]);
    }
    // JSON summary schema of the contract.
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(base.with_extension("json")).unwrap())
            .unwrap();
    for k in [
        "problem",
        "method",
        "preconditioner",
        "ordering",
        "converged",
        "iterations",
        "nodes",
        "triangles",
        "dofs",
        "constraints",
        "active",
        "energy",
        "kkt",
        "contact",
        "probes",
        "timings_s",
    ] {
        assert!(j.get(k).is_some(), "JSON lacks {k}");
    }
    for k in ["primal", "dual", "complementarity", "stationarity"] {
        assert!(j["kkt"][k].as_f64().unwrap() <= 1e-8, "kkt.{k}");
    }
    for k in ["read", "assemble", "solve", "write", "total"] {
        assert!(j["timings_s"][k].as_f64().is_some(), "timings_s.{k}");
    }
    assert!(j["contact"]["max_pressure"].as_f64().unwrap() > 0.0);
    let probe = &j["probes"]["top_left"];
    assert!(probe["node"].as_u64().is_some() && probe["u"].as_array().unwrap().len() == 2);
    assert_eq!(j["converged"], true);
    // No temporary files left behind.
    for e in std::fs::read_dir(dir.path()).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!n.contains(".tmp"), "leftover {n}");
    }
}

#[test]
fn not_converged_gives_exit_3_and_flagged_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (code, _, stderr) = signorini(&[
        "solve",
        &example("two_blocks_eccentric"),
        "--out",
        out,
        "--method",
        "cgc",
        "--max-iter",
        "1",
        "--quiet",
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("did not converge"), "{stderr}");
    let j: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("two_blocks_eccentric.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(j["converged"], false);
    let ck =
        signorini::io::hdf5::read_checkpoint(&dir.path().join("two_blocks_eccentric.h5")).unwrap();
    assert!(!ck.steps[0].info.converged);
}

/// A bad case: the TOML text (with MESH replaced by the square fixture's path)
/// and words that the error line must contain.
/// `signorini solve TOML --out OUT --quiet`: (exit code, stderr).
fn solve_quiet(toml: &std::path::Path, out: &std::path::Path) -> (i32, String) {
    let (code, _, stderr) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    (code, stderr)
}

/// Solve `base` + each of `extras` (a problem file on the square mesh; MESH
/// stands for its path) and return each run's JSON; every run must exit 0.
fn solve_square_variants(base: &str, extras: &[&str]) -> Vec<serde_json::Value> {
    let dir = tempfile::tempdir().unwrap();
    let mesh = root().join("tests/data/msh/square_ascii41.msh");
    let mut jsons = vec![];
    for (i, extra) in extras.iter().enumerate() {
        let p = dir.path().join(format!("m{i}.toml"));
        std::fs::write(
            &p,
            format!("{base}{extra}").replace("MESH", &mesh.display().to_string()),
        )
        .unwrap();
        let out = dir.path().join(format!("out{i}"));
        let (code, stderr) = solve_quiet(&p, &out);
        assert_eq!(code, 0, "{extra}: {stderr}");
        let text = std::fs::read_to_string(out.join(format!("m{i}.json"))).unwrap();
        jsons.push(serde_json::from_str(&text).unwrap());
    }
    jsons
}

fn bad(toml: &str, words: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let mesh = root()
        .join("tests/data/msh/square_ascii41.msh")
        .display()
        .to_string();
    let p = dir.path().join("bad.toml");
    std::fs::write(&p, toml.replace("MESH", &mesh)).unwrap();
    let out = dir.path().join("out");
    let (code, stderr) = solve_quiet(&p, &out);
    assert_eq!(code, 2, "expected exit 2 for {words:?}, stderr: {stderr}");
    for w in words {
        assert!(stderr.contains(w), "message lacks {w:?}: {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    let written: Vec<_> = std::fs::read_dir(&out)
        .map(|d| d.filter_map(|e| e.ok()).collect())
        .unwrap_or_default();
    assert!(
        written.is_empty(),
        "no output may be written on bad input: {written:?}"
    );
}

const GOOD: &str = "[mesh]\nfile = \"MESH\"\n[materials.body_left]\nE = 1e9\nnu = 0.3\n[materials.body_right]\nE = 1e9\nnu = 0.3\n[[dirichlet]]\non = \"bottom\"\nu = [0.0, 0.0]\n[[traction]]\non = \"top\"\npn = -1e6\n[[contact]]\non = \"interface\"\n";

#[test]
fn good_square_problem_solves() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = root()
        .join("tests/data/msh/square_ascii41.msh")
        .display()
        .to_string();
    let p = dir.path().join("good.toml");
    std::fs::write(&p, GOOD.replace("MESH", &mesh)).unwrap();
    let (code, _, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        dir.path().join("o").to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn bad_unknown_key_names_key_and_table() {
    bad(
        &GOOD.replace(
            "nu = 0.3\n[materials.body_right]",
            "nu = 0.3\nyoung = 3\n[materials.body_right]",
        ),
        &["bad.toml", "young", "materials.body_left"],
    );
}

#[test]
fn bad_poisson_ratio() {
    bad(
        &GOOD.replacen("nu = 0.3", "nu = 0.5", 1),
        &["nu", "0.5", "body_left"],
    );
    bad(
        &GOOD.replacen("nu = 0.3", "nu = -1.0", 1),
        &["nu", "(-1, 0.5)"],
    );
}

#[test]
fn bad_young_modulus_and_density() {
    bad(&GOOD.replacen("E = 1e9", "E = 0.0", 1), &["E", "positive"]);
    bad(
        &GOOD.replacen("nu = 0.3", "nu = 0.3\nrho = -1.0", 1),
        &["rho", "non-negative"],
    );
}

#[test]
fn bad_unknown_physical_name() {
    bad(
        &GOOD.replace("on = \"top\"", "on = \"roof\""),
        &["roof", "no physical group", "square_ascii41.msh"],
    );
}

#[test]
fn bad_missing_material() {
    bad(
        &GOOD.replace("[materials.body_right]\nE = 1e9\nnu = 0.3\n", ""),
        &["body_right", "no material"],
    );
}

#[test]
fn bad_material_for_missing_surface() {
    bad(
        &GOOD.replace("[materials.body_right]", "[materials.granite]"),
        &["granite", "no physical surface"],
    );
}

#[test]
fn bad_contact_curve_on_boundary() {
    bad(
        &GOOD.replace("on = \"interface\"", "on = \"left\""),
        &["left", "not between two bodies"],
    );
}

#[test]
fn bad_surface_used_as_dirichlet_curve() {
    bad(
        &GOOD.replace("on = \"bottom\"", "on = \"body_left\""),
        &["body_left", "surface"],
    );
}

#[test]
fn bad_toml_syntax_gives_line_and_column() {
    bad(
        &GOOD.replace(
            "nu = 0.3\n[materials.body_right]",
            "nu = = 0.3\n[materials.body_right]",
        ),
        &["bad.toml", "line 5"],
    );
}

#[test]
fn bad_wrong_type() {
    bad(
        &GOOD.replacen("E = 1e9", "E = \"stiff\"", 1),
        &["key `E`", "line 4", "materials.body_left"],
    );
}

#[test]
fn bad_missing_mesh_file() {
    bad(
        &GOOD.replace("MESH", "/nonexistent/none.msh"),
        &["none.msh", "cannot read"],
    );
}

#[test]
fn bad_unknown_method_and_parameters() {
    bad(
        &format!("{GOOD}[solver]\nmethod = \"magic\"\n"),
        &["magic", "unknown method"],
    );
    bad(&format!("{GOOD}[solver]\nomega = 2.5\n"), &["omega"]);
    bad(&format!("{GOOD}[solver]\nrho = -1.0\n"), &["rho"]);
    bad(
        &format!("{GOOD}[solver]\npreconditioner = \"amg\"\n"),
        &["amg", "preconditioner"],
    );
    bad(
        &format!("{GOOD}[solver]\nordering = \"metis\"\n"),
        &["ordering = \"metis\"", "\"nested-dissection\""],
    );
    bad(
        &format!("{GOOD}[solver]\nmemory_limit = \"8 GB\"\n"),
        &["memory_limit = \"8 GB\"", "GiB"],
    );
}

/// `[solver] memory_limit`: a factor larger than it is refused before it
/// starts (exit 2, nothing written, the message names the size, the limit
/// and how to raise it); a limit it fits under changes nothing.
#[test]
fn memory_limit_refuses_a_larger_factor_and_changes_nothing_else() {
    bad(
        &format!("{GOOD}[solver]\nmethod = \"ssn\"\nmemory_limit = \"1 KiB\"\n"),
        &[
            "needs",
            "the limit set for the factors (1.0 KiB)",
            "raise [solver] memory_limit",
        ],
    );
    let jsons = solve_square_variants(
        &format!("{GOOD}[solver]\nmethod = \"ssn\"\n"),
        &["", "memory_limit = \"1 GiB\"\n"],
    );
    assert_eq!(jsons[0]["probes"], jsons[1]["probes"]);
    assert_eq!(jsons[0]["kkt"], jsons[1]["kkt"]);
}

/// `ssn_path = "iterative"` factors nothing of C's size: under a memory
/// limit of 1 KiB, which refuses the direct path, it solves the model and
/// its probes are the direct path's (to 1e-5 of the largest: both are
/// certified to 1e-10 in residual, not in error), same active set.
#[test]
fn the_iterative_path_solves_under_a_limit_no_factor_fits() {
    let jsons = solve_square_variants(
        &format!(
            "{GOOD}[output]\nprobes = {{ top = [0.5, 1.0], mid = [0.5, 0.5], low = [0.2, 0.3] }}\n[solver]\nmethod = \"ssn\"\n"
        ),
        &["", "ssn_path = \"iterative\"\nmemory_limit = \"1 KiB\"\n"],
    );
    assert!(
        jsons[1]["timings_s"]
            .to_string()
            .contains("multigrid setup"),
        "{}",
        jsons[1]["timings_s"]
    );
    let probes = |j: &serde_json::Value| -> Vec<f64> {
        let mut v = vec![];
        for (_, p) in j["probes"].as_object().unwrap() {
            v.extend(
                p["u"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap()),
            );
        }
        v
    };
    let (a, b) = (probes(&jsons[0]), probes(&jsons[1]));
    assert!(!a.is_empty());
    let big = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-5 * big, "{a:?} vs {b:?}");
    }
    assert_eq!(jsons[0]["active"], jsons[1]["active"]);
}

/// Issue 34: at a stiffness contrast of 10¹⁵ (a floating block of 1 PPa on
/// one of 1 kPa) the iterative path claimed that a body was free although
/// contact holds it (its multigrid's coarsest factor failed). At 10¹⁵ the
/// rounding of the stiff body's C is the soft body's stiffness, so no path
/// need certify the answer (exit 3 is honest), but none may blame the
/// bodies, and the iterative path says what failed.
#[test]
fn the_iterative_path_never_blames_a_held_body() {
    let dir = tempfile::tempdir().unwrap();
    let toml = std::fs::read_to_string(root().join("meshes/two_blocks.toml"))
        .unwrap()
        .replace(
            "file = \"two_blocks.msh\"",
            &format!("file = {:?}", root().join("meshes/two_blocks.msh")),
        )
        .replace("method = \"cgc\"", "method = \"ssn\"");
    let mut k = 0;
    let toml: String = toml
        .lines()
        .map(|l| {
            if l.starts_with("E = ") {
                k += 1;
                if k == 1 { "E = 1.0e3" } else { "E = 1.0e18" }.to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert_eq!(k, 2, "two materials in two_blocks.toml");
    for (name, extra) in [("auto", ""), ("iterative", "ssn_path = \"iterative\"\n")] {
        let p = dir.path().join(format!("{name}.toml"));
        std::fs::write(
            &p,
            toml.replace("[solver]\n", &format!("[solver]\n{extra}")),
        )
        .unwrap();
        let outdir = dir.path().join(name);
        let (rc, stdout, stderr) = signorini(&[
            "solve",
            p.to_str().unwrap(),
            "--out",
            outdir.to_str().unwrap(),
        ]);
        let log = stderr + &stdout;
        assert!(!log.contains("is free"), "{name}: {log}");
        assert!(rc == 0 || rc == 3, "{name}: {log}");
        if rc == 3 && name == "iterative" {
            assert!(log.contains("stiffness contrast"), "{name}: {log}");
        }
    }
}

/// `signorini methods`: one line per method, its name first (the benchmark
/// parses that), then what it declares; ssn is marked as the default
/// (`auto`); the last line lists cgc's preconditioners.
#[test]
fn methods_lists_every_method_with_its_capabilities() {
    let (rc, out, err) = signorini(&["methods"]);
    assert_eq!(rc, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    let (last, methods) = lines.split_last().unwrap();
    assert!(
        last.starts_with("preconditioners (cgc): none, jacobi"),
        "{last}"
    );
    let names: Vec<&str> = methods
        .iter()
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    assert_eq!(
        names,
        ["cgc", "preelim", "penalty", "uzawa", "dual", "asm", "asm-cgh", "mprgp", "ssn"]
    );
    for l in methods {
        let friction = l.starts_with("mprgp") || l.starts_with("ssn");
        assert_eq!(l.contains("[friction 2D"), friction, "{l}");
        assert_eq!(l.contains("the default"), l.starts_with("ssn"), "{l}");
    }
}

#[test]
fn bad_body_without_support() {
    // No Dirichlet at all and no contact: both halves are free.
    bad(
        &GOOD
            .replace("[[dirichlet]]\non = \"bottom\"\nu = [0.0, 0.0]\n", "")
            .replace("[[contact]]\non = \"interface\"\n", ""),
        &["not supported", "body 'body_left+body_right'"],
    );
}

#[test]
fn bad_floating_body_with_sliding_load_is_unbounded() {
    // Right half held only by contact on a vertical interface; a vertical
    // load on it slides it along the interface: unbounded.
    let t = "[mesh]\nfile = \"MESH\"\n[materials.body_left]\nE = 1e9\nnu = 0.3\n[materials.body_right]\nE = 1e9\nnu = 0.3\n[[dirichlet]]\non = \"left\"\nu = [0.0, 0.0]\n[[traction]]\non = \"right\"\np = [-1e5, -1e5]\n[[contact]]\non = \"interface\"\n";
    bad(t, &["unbounded", "body 'body_right'"]);
}

#[test]
fn bad_floating_body_pulled_away_is_unbounded() {
    // Pulled away from its only support: the contact opens and nothing holds it.
    let t = "[mesh]\nfile = \"MESH\"\n[materials.body_left]\nE = 1e9\nnu = 0.3\n[materials.body_right]\nE = 1e9\nnu = 0.3\n[[dirichlet]]\non = \"left\"\nu = [0.0, 0.0]\n[[dirichlet]]\non = \"corner\"\nu = [0.0, 0.0]\n[[slip]]\non = \"bottom\"\n[[traction]]\non = \"right\"\np = [1e5, 0.0]\n[[contact]]\non = \"interface\"\n";
    bad(t, &["unbounded", "body 'body_right'"]);
}

#[test]
fn bad_output_directory_not_writable() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plainfile");
    std::fs::write(&file, "x").unwrap();
    let (code, _, stderr) = signorini(&[
        "solve",
        &example("column"),
        "--out",
        file.join("sub").to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("plainfile"), "{stderr}");
}

#[test]
fn truncated_mesh_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let src = std::fs::read_to_string(root().join("tests/data/msh/square_ascii41.msh")).unwrap();
    let cut = &src[..src.find("$Elements").unwrap() + 40];
    let m = dir.path().join("cut.msh");
    std::fs::write(&m, cut).unwrap();
    let p = dir.path().join("cut.toml");
    std::fs::write(&p, GOOD.replace("MESH", m.to_str().unwrap())).unwrap();
    let (code, _, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        dir.path().join("o").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("cut.msh") && stderr.contains("$Elements"),
        "{stderr}"
    );
}

/// Penalty is certified against its own penalised problem: its O(ε)
/// violation of the contact conditions is a warning and exit 0; `--strict`
/// certifies against the unpenalised problem: exit 3.
#[test]
fn strict_turns_the_penalty_violation_into_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let ex = example("two_blocks_eccentric");
    let (code, _, err) = signorini(&["solve", &ex, "--method", "penalty", "--out", out, "-q"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("O(ε_p)"), "{err}");
    let (code, _, err) = signorini(&[
        "solve", &ex, "--method", "penalty", "--out", out, "-q", "--strict",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("above the target"), "{err}");
}

/// A divergent Uzawa (ρ far above 2/‖H‖) ends in NaN/Inf: exit 3, outputs
/// written and flagged, one line naming the failure.
#[test]
fn nan_in_an_iteration_gives_exit_3_and_flagged_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let src = std::fs::read_to_string(example("two_blocks_eccentric")).unwrap();
    let mesh = root().join("meshes/two_blocks_eccentric.msh");
    let toml = src.replace("[solver]", "[solver]\nrho = 1e30").replace(
        "file = \"two_blocks_eccentric.msh\"",
        &format!("file = \"{}\"", mesh.display()),
    );
    let p = dir.path().join("div.toml");
    std::fs::write(&p, toml).unwrap();
    let out = dir.path().join("out");
    let (code, _, err) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--method",
        "uzawa",
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("NaN or Inf"), "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("div.json")).unwrap()).unwrap();
    assert_eq!(json["converged"], false);
}

// ---- Issue 43, round four: a broken or full stdout, flags that must be
// refused, verdicts of every step, quiet that is not silent. ----

use std::process::{Command, Stdio};

/// How a child's stdout (or stderr) is broken.
#[derive(Clone, Copy, Debug)]
enum Broken {
    /// /dev/full: every write fails with ENOSPC.
    Full,
    /// A pipe whose reader is gone before the child starts: EPIPE.
    Closed,
}

/// A `Stdio` that is broken in the way `how` says.
fn broken(how: Broken) -> Stdio {
    match how {
        Broken::Full => std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full")
            .into(),
        Broken::Closed => {
            let (r, w) = std::io::pipe().expect("pipe");
            drop(r);
            w.into()
        }
    }
}

/// Runs `signorini ARGS` with its stdout broken as `how`: (exit code, stderr).
fn with_broken_stdout(args: &[&str], how: Broken) -> (i32, String) {
    let o = common::command()
        .args(args)
        .stdin(Stdio::null())
        .stdout(broken(how))
        .stderr(Stdio::piped())
        .output()
        .expect("run signorini");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The stdout failure's verdict: exit 4 (or `code` when the command failed
/// on its own), one `error:` line naming standard output, no panic.
fn assert_stdout_error(what: &str, how: Broken, code: i32, want: i32, stderr: &str) {
    assert_eq!(code, want, "{what} {how:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{what} {how:?}: {stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{what} {how:?}: {stderr}");
    assert!(
        errors[0].contains("standard output"),
        "{what} {how:?}: {stderr}"
    );
}

/// Every subcommand whose report fails to reach stdout (/dev/full, a pipe
/// whose reader is gone) exits 4 with one line, and the files it wrote
/// stay written. Before: a panic, exit 101 (clap's --help: exit 0).
#[test]
fn a_full_or_closed_stdout_is_exit_4_on_every_subcommand() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let toml = example("two_blocks_eccentric");
    // One checkpoint to plot.
    let ck = d.join("ck");
    let (code, _, stderr) = signorini(&["solve", &toml, "--out", ck.to_str().unwrap(), "-q"]);
    assert_eq!(code, 0, "{stderr}");
    let h5 = ck.join("two_blocks_eccentric.h5");
    for how in [Broken::Full, Broken::Closed] {
        let tag = format!("{how:?}");
        let (code, stderr) = with_broken_stdout(&["methods"], how);
        assert_stdout_error("methods", how, code, 4, &stderr);
        for flag in ["--help", "--version"] {
            let (code, stderr) = with_broken_stdout(&[flag], how);
            assert_stdout_error(flag, how, code, 4, &stderr);
        }
        let (code, stderr) = with_broken_stdout(&["solve", "--help"], how);
        assert_stdout_error("solve --help", how, code, 4, &stderr);
        // solve: the outputs are committed, then the report fails.
        let out = d.join(format!("solve_{tag}"));
        let (code, stderr) =
            with_broken_stdout(&["solve", &toml, "--out", out.to_str().unwrap()], how);
        assert_stdout_error("solve", how, code, 4, &stderr);
        let j: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("two_blocks_eccentric.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(j["converged"], true);
        assert!(out.join("two_blocks_eccentric.h5").is_file());
        // A run that failed keeps its own code (3), with the stdout line.
        let out3 = d.join(format!("solve3_{tag}"));
        let (code, stderr) = with_broken_stdout(
            &[
                "solve",
                &toml,
                "--out",
                out3.to_str().unwrap(),
                "--method",
                "cgc",
                "--max-iter",
                "1",
            ],
            how,
        );
        assert_stdout_error("solve (not converged)", how, code, 3, &stderr);
        assert!(stderr.contains("did not converge"), "{stderr}");
        // -q prints nothing on stdout: nothing fails.
        let outq = d.join(format!("solveq_{tag}"));
        let (code, stderr) = with_broken_stdout(
            &["solve", &toml, "--out", outq.to_str().unwrap(), "-q"],
            how,
        );
        assert_eq!(code, 0, "solve -q {how:?}: {stderr}");
        // compare: the table fails, the JSON is still written.
        let cj = d.join(format!("compare_{tag}.json"));
        let (code, stderr) = with_broken_stdout(
            &[
                "compare",
                &toml,
                "--methods",
                "ssn,asm",
                "--json",
                cj.to_str().unwrap(),
            ],
            how,
        );
        assert_stdout_error("compare", how, code, 4, &stderr);
        assert!(cj.is_file(), "compare {how:?}: no JSON");
        // plot: the figure is written.
        let png = d.join(format!("plot_{tag}.png"));
        let (code, stderr) = with_broken_stdout(
            &["plot", h5.to_str().unwrap(), "-o", png.to_str().unwrap()],
            how,
        );
        assert_stdout_error("plot", how, code, 4, &stderr);
        assert!(png.is_file());
        // export: the QP is written.
        let qp = d.join(format!("qp_{tag}"));
        let (code, stderr) =
            with_broken_stdout(&["export", &toml, "--qp", qp.to_str().unwrap()], how);
        assert_stdout_error("export", how, code, 4, &stderr);
        assert!(qp.join("meta.json").is_file());
        // limit: its one JSON line.
        let (code, stderr) = with_broken_stdout(&["limit", &toml], how);
        assert_stdout_error("limit", how, code, 4, &stderr);
        // mesh (with Gmsh installed): the mesh is written.
        if Command::new("gmsh").arg("--version").output().is_ok() {
            let msh = d.join(format!("mesh_{tag}.msh"));
            let geo = common::meshes().join("two_blocks.geo");
            let (code, stderr) = with_broken_stdout(
                &["mesh", geo.to_str().unwrap(), "-o", msh.to_str().unwrap()],
                how,
            );
            assert_stdout_error("mesh", how, code, 4, &stderr);
            assert!(msh.is_file());
        }
    }
}

/// stderr full or closed as well: no panic (exit 101), the exit code
/// still tells: 4 for a lost report, 2 for bad input.
#[test]
fn a_full_or_closed_stderr_never_panics() {
    for how in [Broken::Full, Broken::Closed] {
        let run = |args: &[&str], out: Broken| {
            common::command()
                .args(args)
                .stdin(Stdio::null())
                .stdout(broken(out))
                .stderr(broken(how))
                .status()
                .unwrap()
                .code()
        };
        assert_eq!(run(&["methods"], how), Some(4), "{how:?}");
        assert_eq!(
            run(&["solve", "/nonexistent/problem.toml"], Broken::Full),
            Some(2),
            "{how:?}"
        );
        assert_eq!(run(&["--log-level", "bogus", "methods"], how), Some(2));
    }
}

/// A plot, a compare table or a mesh written to a FIFO (or a device node)
/// is refused, and the node is left as it was: the atomic rename would
/// replace it by a regular file (as root, `-o /dev/full` would unlink the
/// device). Before: the FIFO was replaced by a file, exit 0.
#[test]
fn an_output_file_that_is_a_fifo_or_a_device_is_refused_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let toml = example("two_blocks_eccentric");
    let ck = d.join("ck");
    let (code, _, stderr) = signorini(&["solve", &toml, "--out", ck.to_str().unwrap(), "-q"]);
    assert_eq!(code, 0, "{stderr}");
    let h5 = ck.join("two_blocks_eccentric.h5");
    let mkfifo = |p: &std::path::Path| {
        let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    };
    let is_fifo = |p: &std::path::Path| {
        use std::os::unix::fs::FileTypeExt;
        std::fs::symlink_metadata(p)
            .map(|m| m.file_type().is_fifo())
            .unwrap_or(false)
    };
    let png = d.join("fig.png");
    mkfifo(&png);
    let (code, _, stderr) = signorini(&[
        "plot",
        h5.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 2, "plot into a FIFO: {stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
    assert!(is_fifo(&png), "the FIFO was replaced");
    for flag in ["--json", "--csv"] {
        let p = d.join(format!("table{flag}"));
        mkfifo(&p);
        let (code, _, stderr) = signorini(&[
            "compare",
            &toml,
            "--methods",
            "ssn",
            flag,
            p.to_str().unwrap(),
            "-q",
        ]);
        assert_eq!(code, 2, "compare {flag} FIFO: {stderr}");
        assert!(stderr.contains("not a regular file"), "{stderr}");
        assert!(is_fifo(&p), "compare {flag}: the FIFO was replaced");
    }
    // mesh -o FIFO (with Gmsh installed).
    if Command::new("gmsh").arg("--version").output().is_ok() {
        let msh = d.join("m.msh");
        mkfifo(&msh);
        let geo = common::meshes().join("two_blocks.geo");
        let (code, _, stderr) =
            signorini(&["mesh", geo.to_str().unwrap(), "-o", msh.to_str().unwrap()]);
        assert_eq!(code, 2, "mesh -o FIFO: {stderr}");
        assert!(is_fifo(&msh), "mesh: the FIFO was replaced");
    }
    // A character device (root only: mknod); /dev/full's own numbers.
    let dev = d.join("full");
    let c = std::ffi::CString::new(dev.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    let made = unsafe { libc::mknod(c.as_ptr(), libc::S_IFCHR | 0o600, libc::makedev(1, 7)) } == 0;
    if made {
        let (code, _, stderr) = signorini(&[
            "compare",
            &toml,
            "--methods",
            "ssn",
            "--json",
            dev.to_str().unwrap(),
            "-q",
        ]);
        assert_eq!(code, 2, "compare --json DEVICE: {stderr}");
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::symlink_metadata(&dev)
            .unwrap()
            .file_type()
            .is_char_device());
    } else {
        eprintln!("mknod refused (not root): the device case is skipped");
    }
}

/// `--log-level bogus` is refused with the valid values (it was accepted
/// and hid every warning); `limit --repeat 0` is refused.
#[test]
fn a_bogus_log_level_and_repeat_0_are_refused() {
    let (code, _, stderr) = signorini(&["--log-level", "bogus", "methods"]);
    assert_eq!(code, 2, "{stderr}");
    for w in ["bogus", "error", "warn", "info", "debug", "trace"] {
        assert!(stderr.contains(w), "{w}: {stderr}");
    }
    let (code, _, stderr) = signorini(&["limit", &example("two_blocks"), "--repeat", "0"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--repeat"), "{stderr}");
}

/// `compare --json X --csv X` (also spelled `./X`) is refused naming both
/// flags, before anything runs; nothing is written.
#[test]
fn compare_refuses_one_path_for_json_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let x = dir.path().join("t.out");
    let xs = x.to_str().unwrap();
    let dotted = format!("{}/./t.out", dir.path().display());
    for (j, c) in [(xs, xs), (xs, dotted.as_str())] {
        let (code, _, stderr) = signorini(&[
            "compare",
            &example("two_blocks"),
            "--methods",
            "ssn",
            "--json",
            j,
            "--csv",
            c,
        ]);
        assert_eq!(code, 2, "{stderr}");
        assert!(
            stderr.contains("--json") && stderr.contains("--csv"),
            "{stderr}"
        );
        assert!(!stderr.contains("compare: "), "it ran: {stderr}");
        assert!(!x.exists());
    }
}

/// An export whose solution is not converged exits 3 (it exited 0 while
/// meta.json said converged = false), and meta.json says certified = false.
#[test]
fn export_of_an_uncertified_solution_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    let qp = dir.path().join("qp");
    let (code, _, stderr) = signorini(&[
        "export",
        &example("two_blocks_eccentric"),
        "--qp",
        qp.to_str().unwrap(),
        "--solution",
        "--method",
        "cgc",
        "--preconditioner",
        "none",
        "--max-iter",
        "1",
        "-q",
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("not converged"), "{stderr}");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(qp.join("meta.json")).unwrap()).unwrap();
    assert_eq!(meta["converged"], false);
    assert_eq!(meta["certified"], false);
    // A certified export still exits 0 and says so.
    let qp2 = dir.path().join("qp2");
    let (code, _, stderr) = signorini(&[
        "export",
        &example("two_blocks_eccentric"),
        "--qp",
        qp2.to_str().unwrap(),
        "--solution",
        "-q",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(qp2.join("meta.json")).unwrap()).unwrap();
    assert_eq!(meta["certified"], true);
}

/// The three-body model in three steps: step 1 the full load, steps 2 and
/// 3 less of it (step 3 starts from step 2's answer); `small_first`
/// reverses the order (steps 1 and 2 the small load, step 3 the full one).
fn three_steps(dir: &std::path::Path) -> std::path::PathBuf {
    three_steps_as(dir, false)
}

fn three_steps_as(dir: &std::path::Path, small_first: bool) -> std::path::PathBuf {
    let text = std::fs::read_to_string(common::meshes().join("three_bodies_steps.toml")).unwrap();
    let head = &text[..text.find("[[steps]]").unwrap()];
    let mesh = common::meshes().join("three_bodies.msh");
    let head = head.replace(
        "\"three_bodies.msh\"",
        &format!("{:?}", mesh.display().to_string()),
    );
    let p = dir.join("s3.toml");
    let (full, small) = (
        "displacement = 1.0\nload = 1.0",
        "displacement = 0.2\nload = 0.3",
    );
    let [a, b, c] = if small_first {
        [small, small, full]
    } else {
        [full, small, small]
    };
    std::fs::write(
        &p,
        format!(
            "{head}[[steps]]\nt = 1.0\n{a}\n\n[[steps]]\nt = 2.0\n{b}\n\n[[steps]]\nt = 3.0\n{c}\n"
        ),
    )
    .unwrap();
    p
}

/// Step 1 of 3 not converged (cgc stopped at 60 iterations; steps 2 and 3
/// converge and certify): the top level's `converged` is false (it was
/// the last step's, true), `failed_steps` = [1], the HDF5 step 1 is
/// flagged, and the report's KKT line (of the last step) still says
/// certified while the failed line names step 1.
#[test]
fn a_failed_first_step_makes_the_run_not_converged() {
    let dir = tempfile::tempdir().unwrap();
    let p = three_steps_as(dir.path(), true);
    let out = dir.path().join("out");
    let (code, stdout, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--method",
        "cgc",
        "--preconditioner",
        "none",
        "--tol",
        "1e-7",
        "--max-iter",
        "60",
    ]);
    assert_eq!(code, 3, "{stdout}\n{stderr}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("s3.json")).unwrap()).unwrap();
    let conv: Vec<bool> = j["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["converged"] == true)
        .collect();
    assert_eq!(conv, [false, true, true]);
    assert_eq!(j["converged"], false);
    assert_eq!(j["kkt"]["certified"], false);
    assert_eq!(j["failed_steps"], serde_json::json!([1]));
    let ck = signorini::io::hdf5::read_checkpoint(&out.join("s3.h5")).unwrap();
    let flags: Vec<bool> = ck.steps.iter().map(|s| s.info.converged).collect();
    assert_eq!(flags, [false, true, true]);
    assert!(
        stdout.contains("failed      step 1 of 3 (not converged)"),
        "{stdout}"
    );
    let kkt = stdout.lines().find(|l| l.starts_with("KKT")).unwrap();
    assert!(kkt.contains("certified (≤"), "{kkt}");
    assert!(stderr.contains("warning: step 1:"), "{stderr}");
}

/// Step 2 of 3 not certified (cgc without preconditioner stopped early;
/// steps 1 and 3 certified): exit 3, and the JSON's top level says so
/// (`kkt.certified` false, `failed_steps` = [2], the step row certified =
/// false) where it said certified; the report names the step.
#[test]
fn a_failed_middle_step_is_in_the_top_level_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let p = three_steps(dir.path());
    let out = dir.path().join("out");
    let (code, stdout, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--method",
        "cgc",
        "--preconditioner",
        "none",
        "--tol",
        "1e-7",
        "--max-iter",
        "70",
    ]);
    assert_eq!(code, 3, "{stdout}\n{stderr}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("s3.json")).unwrap()).unwrap();
    let rows = j["steps"].as_array().unwrap();
    let certified: Vec<bool> = rows.iter().map(|r| r["certified"] == true).collect();
    assert_eq!(certified, [true, false, true], "{rows:?}");
    assert_eq!(j["kkt"]["certified"], false, "{}", j["kkt"]);
    assert_eq!(j["failed_steps"], serde_json::json!([2]));
    assert_eq!(
        j["converged"],
        rows.iter().all(|r| r["converged"] == true),
        "converged is the conjunction of the steps"
    );
    assert!(
        stdout.contains("failed      step 2 of 3 (not certified)"),
        "{stdout}"
    );
    assert!(stdout.contains("NOT CERTIFIED"), "{stdout}");
    assert!(
        stderr.contains("warning: step 2: not certified"),
        "{stderr}"
    );
}

/// A run whose every step is certified lists no failed step.
#[test]
fn a_certified_run_has_no_failed_steps() {
    let dir = tempfile::tempdir().unwrap();
    let p = three_steps(dir.path());
    let out = dir.path().join("out");
    let (code, _, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("s3.json")).unwrap()).unwrap();
    assert_eq!(j["failed_steps"], serde_json::json!([]));
    assert_eq!(j["kkt"]["certified"], true);
    assert_eq!(j["converged"], true);
}

/// The floating block pulled off its support in step 3: the unbounded
/// error names step 3 (it did not say which step).
#[test]
fn the_unbounded_error_of_a_step_names_the_step() {
    let dir = tempfile::tempdir().unwrap();
    let p = common::model_variant(
        &common::meshes(),
        "floating_block.toml",
        &[],
        &dir.path().join("fb.toml"),
    );
    let mut text = std::fs::read_to_string(&p).unwrap();
    text.push_str("[[steps]]\nt = 1.0\nload = 1.0\n[[steps]]\nt = 2.0\nload = 0.5\n[[steps]]\nt = 3.0\nload = -1.0\n");
    std::fs::write(&p, text).unwrap();
    let out = dir.path().join("out");
    let (code, _, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("unbounded"), "{stderr}");
    assert!(stderr.contains("step 3 of 3"), "{stderr}");
    assert!(stderr.contains("fb.toml"), "{stderr}");
}

/// `-q` hides the report, not the warnings (a key for another method);
/// `-qq` and `--log-level error` hide them. Before: `-q` hid them.
#[test]
fn quiet_hides_the_report_and_qq_the_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let toml = example("two_blocks_eccentric");
    let run = |extra: &[&str], sub: &str| {
        let out = dir.path().join(sub);
        let mut args = vec![
            "solve",
            toml.as_str(),
            "--out",
            out.to_str().unwrap(),
            "--method",
            "ssn",
            "--preconditioner",
            "jacobi",
        ];
        args.extend_from_slice(extra);
        let (code, stdout, stderr) = signorini(&args);
        assert_eq!(code, 0, "{extra:?}: {stderr}");
        (stdout, stderr)
    };
    let (stdout, stderr) = run(&[], "a");
    assert!(stdout.contains("KKT"), "{stdout}");
    assert!(stderr.contains("does not apply"), "{stderr}");
    let (stdout, stderr) = run(&["-q"], "b");
    assert!(stdout.is_empty(), "-q: {stdout}");
    assert!(
        stderr.contains("does not apply"),
        "-q hid the warning: {stderr}"
    );
    for flags in [&["-qq"][..], &["--log-level", "error"], &["-q", "--quiet"]] {
        let (_, stderr) = run(flags, "c");
        assert!(!stderr.contains("does not apply"), "{flags:?}: {stderr}");
    }
    // -qq hides a step's warning too; the exit code still says 3.
    let out = dir.path().join("d");
    let (code, _, stderr) = signorini(&[
        "solve",
        &toml,
        "--out",
        out.to_str().unwrap(),
        "--method",
        "cgc",
        "--max-iter",
        "1",
        "-qq",
    ]);
    assert_eq!(code, 3);
    assert!(stderr.is_empty(), "{stderr}");
}

/// The report's time line has no empty `()` when the method reports no
/// phases, and the compare table's penalty row says "yes (O(ε))" as the
/// guide's table does.
#[test]
fn small_things_of_the_report_and_the_table() {
    let dir = tempfile::tempdir().unwrap();
    for method in ["cgc", "ssn", "asm", "penalty", "uzawa"] {
        let out = dir.path().join(method);
        let (code, stdout, stderr) = signorini(&[
            "solve",
            &example("two_blocks"),
            "--out",
            out.to_str().unwrap(),
            "--method",
            method,
        ]);
        assert_eq!(code, 0, "{method}: {stderr}");
        let line = stdout.lines().find(|l| l.starts_with("time [s]")).unwrap();
        assert!(!line.contains("()"), "{method}: {line}");
    }
    let (code, stdout, stderr) = signorini(&[
        "compare",
        &example("two_blocks"),
        "--methods",
        "ssn,penalty",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let row = stdout.lines().find(|l| l.starts_with("penalty")).unwrap();
    assert!(row.ends_with("yes (O(ε))"), "{row}");
    let row = stdout.lines().find(|l| l.starts_with("ssn")).unwrap();
    assert!(row.ends_with("yes"), "{row}");
    assert!(!stdout.contains("-0.00000e0"), "{stdout}");
}

/// `scripts/verify` (verify.py): a usage error is one line and exit 2,
/// whether or not h5py and numpy are there (run with the system's
/// python3): `--work` naming a regular file, an unknown option, an unknown
/// case. Before: a traceback and exit 1, which means "outside tolerance".
#[test]
fn verify_script_usage_errors_are_exit_2_and_one_line() {
    if Command::new("python3").arg("--version").output().is_err() {
        eprintln!("python3 not found: skipped");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("afile");
    std::fs::write(&file, "x").unwrap();
    let script = root().join("scripts/verify.py");
    for args in [
        vec!["--work", file.to_str().unwrap()],
        vec!["--bogus"],
        vec!["--only", "nosuchcase"],
    ] {
        let o = Command::new("python3")
            .arg(&script)
            .args(&args)
            .current_dir(dir.path())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("verify: "), "{args:?}: {stderr}");
        assert!(!stderr.contains("Traceback"), "{args:?}: {stderr}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}
