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
        assert_eq!(l.contains("[friction yes"), friction, "{l}");
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
