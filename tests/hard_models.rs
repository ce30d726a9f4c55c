//! Issue 11's contract on the hard models of `tests/hard/` (see its README):
//! every method variant on every model either exits 0 with a certified KKT
//! and x and λ within 1e-6 relative of a verified reference, or exits 3 (an
//! honest failure, printed in the table). Exit 2 (these problems are bounded
//! and well posed), a run killed after its time budget ("hung"), a crash, and
//! an exit 0 that is not certified or disagrees with the reference fail.
//!
//! The reference of a model is the certified exit-0 run with the smallest KKT
//! residual (penalty excluded: it solves its own O(ε_p) problem) that passes
//! checks independent of signorini's certificate: the QP exported by `signorini
//! export --qp DIR --solution` with the same variant meets the KKT conditions
//! as evaluated here (stationarity scaled by the contact forces AᵀΛ, so an
//! error in λ cannot hide behind ‖d‖), the export reproduces the run's λ, and
//! the closed form (uniaxial strain) or the equilibrium of the contact forces
//! holds where the model has one. Environment variables: on the test function.

mod common;

use common::{norm, read_mtx, read_vec, rel_diff, root, run_signorini, tomls_in, Run};
use signorini::io::hdf5::read_checkpoint;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

/// Agreement required of every exit-0 run (issue 11).
const AGREE: f64 = 1e-6;
/// KKT residuals (as evaluated here) the reference must meet.
const REF_KKT: f64 = 1e-7;
/// The export must reproduce the run's λ to this (the same input, the same method).
const REPRODUCE: f64 = 1e-9;

/// The 14 variants `signorini methods` lists: each CGC preconditioner and the other methods.
const VARIANTS: [(&str, Option<&str>); 14] = [
    ("cgc", Some("none")),
    ("cgc", Some("jacobi")),
    ("cgc", Some("ssor")),
    ("cgc", Some("ic0")),
    ("cgc", Some("mic0")),
    ("cgc", Some("cholesky")),
    ("preelim", None),
    ("penalty", None),
    ("uzawa", None),
    ("dual", None),
    ("asm", None),
    ("asm-cgh", None),
    ("mprgp", None),
    ("ssn", None),
];

fn variant_name(v: &(&str, Option<&str>)) -> String {
    match v.1 {
        Some(pc) => format!("{}:{pc}", v.0),
        None => v.0.to_string(),
    }
}

fn variant_args(v: &(&str, Option<&str>)) -> Vec<String> {
    let mut a = vec!["--method".to_string(), v.0.to_string()];
    if let Some(pc) = v.1 {
        a.extend(["--preconditioner".to_string(), pc.to_string()]);
    }
    a
}

/// A check of the reference that does not rely on signorini's certificate.
#[derive(Clone, Debug)]
enum Known {
    None,
    /// Two stacked blocks, interface at `y_if`, sides on slip lines, bottom
    /// fixed, pressure `p` on the top: u_x = 0, u_y linear in each block.
    Uniaxial {
        p: f64,
        m_lower: f64,
        m_upper: f64,
        y_if: f64,
    },
    /// The contact normal is vertical and all vertical load goes through the
    /// contact: Σλ = this.
    TotalForce(f64),
}

#[derive(Clone, Debug)]
struct Model {
    name: String,
    toml: PathBuf,
    extra: Vec<String>,
    known: Known,
}

/// Oedometric modulus M = E(1 − ν)/((1 + ν)(1 − 2ν)) of `materials.NAME`.
fn oedometric(t: &toml::Value, name: &str) -> f64 {
    let m = &t["materials"][name];
    let e = m["E"].as_float().unwrap();
    let nu = m["nu"].as_float().unwrap();
    e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
}

/// The top pressure p > 0 of the one `[[traction]]` (pn < 0).
fn top_pressure(t: &toml::Value) -> f64 {
    -t["traction"][0]["pn"].as_float().unwrap()
}

fn model(toml: PathBuf, name: &str, extra: &[&str]) -> Model {
    let text = std::fs::read_to_string(&toml).unwrap();
    let t: toml::Value = text.parse().unwrap();
    let stem = toml.file_stem().unwrap().to_string_lossy().into_owned();
    let known = if stem.starts_with("stack_clamped") || stem == "two_blocks" {
        Known::Uniaxial {
            p: top_pressure(&t),
            m_lower: oedometric(&t, "lower"),
            m_upper: oedometric(&t, "upper"),
            y_if: 0.5,
        }
    } else if stem.starts_with("stack_floating") {
        // Width 1 m.
        Known::TotalForce(top_pressure(&t))
    } else if stem.starts_with("punch") {
        // Width 2 m, flat master (normal (0, 1)).
        Known::TotalForce(2.0 * top_pressure(&t))
    } else {
        Known::None
    };
    Model {
        name: name.to_string(),
        toml,
        extra: extra.iter().map(|s| s.to_string()).collect(),
        known,
    }
}

/// Every model of tests/hard/ plus the extreme-tolerance cases.
fn models() -> Vec<Model> {
    let hard = root().join("tests/hard");
    let tomls = tomls_in(&hard);
    let mut v: Vec<Model> = tomls
        .into_iter()
        .map(|p| {
            let n = p.file_stem().unwrap().to_string_lossy().into_owned();
            model(p, &n, &[])
        })
        .collect();
    for tol in ["1e-15", "1e-16"] {
        v.push(model(
            root().join("meshes/two_blocks.toml"),
            &format!("two_blocks@tol{tol}"),
            &["--tol", tol],
        ));
        v.push(model(
            hard.join("stack_floating_soft_below_1e4.toml"),
            &format!("stack_floating_soft_below_1e4@tol{tol}"),
            &["--tol", tol],
        ));
    }
    v
}

/// What one solve gave.
#[derive(Clone, Debug, Default)]
struct Cell {
    run: Option<Run>,
    certified: Option<bool>,
    iterations: Option<u64>,
    kkt: Option<f64>,
    rigid_modes: Option<u64>,
    constraints: Option<u64>,
    nodes: Option<u64>,
    /// Displacements of every output point, flattened; point coordinates.
    u: Option<Vec<f64>>,
    points: Vec<[f64; 2]>,
    lambda: Option<Vec<f64>>,
    /// The relative constraint violation (`kkt.primal`): penalty's O(ε_p) scale.
    primal: Option<f64>,
    /// Filled after the reference is known.
    rel_u: Option<f64>,
    rel_lambda: Option<f64>,
    verdict: String,
    ok: bool,
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The largest KKT residual of the JSON summary (NaN, null or missing → None).
fn json_kkt(j: &serde_json::Value) -> Option<f64> {
    let k = &j["kkt"];
    let mut m = 0.0f64;
    for key in ["primal", "dual", "complementarity", "stationarity"] {
        let v = k[key].as_f64()?;
        if !v.is_finite() {
            return None;
        }
        m = m.max(v);
    }
    Some(m)
}

fn solve_cell(m: &Model, v: &(&str, Option<&str>), budget: Duration, scratch: &Path) -> Cell {
    let out = scratch.join("out");
    let mut args = vec![
        "solve".to_string(),
        m.toml.to_string_lossy().into_owned(),
        "--out".to_string(),
        out.to_string_lossy().into_owned(),
        "--quiet".to_string(),
    ];
    args.extend(variant_args(v));
    args.extend(m.extra.iter().cloned());
    let run = run_signorini(&args, budget, scratch);
    let stem = m.toml.file_stem().unwrap().to_string_lossy().into_owned();
    let mut c = Cell::default();
    if let Ok(text) = std::fs::read_to_string(out.join(format!("{stem}.json"))) {
        if let Ok(j) = serde_json::from_str::<serde_json::Value>(&text) {
            c.certified = j["kkt"]["certified"].as_bool();
            c.iterations = j["iterations"].as_u64();
            c.kkt = json_kkt(&j);
            c.primal = j["kkt"]["primal"].as_f64();
            c.rigid_modes = j["rigid_modes"].as_u64();
            c.constraints = j["constraints"].as_u64();
            c.nodes = j["nodes"].as_u64();
        }
    }
    if let Ok(ck) = read_checkpoint(&out.join(format!("{stem}.h5"))) {
        if let Some(s) = ck.steps.last() {
            c.u = Some(s.displacement.iter().flat_map(|p| [p[0], p[1]]).collect());
            c.lambda = Some(s.multipliers.clone());
            c.points = ck.mesh.points.clone();
        }
    }
    c.run = Some(run);
    c
}

/// M·v for triplets (transposed when `t`).
fn mul(tr: &[(usize, usize, f64)], n_out: usize, v: &[f64], t: bool) -> Vec<f64> {
    let mut y = vec![0.0; n_out];
    for &(i, j, a) in tr {
        if t {
            y[j] += a * v[i];
        } else {
            y[i] += a * v[j];
        }
    }
    y
}

/// KKT residuals of an exported QP and its solution, evaluated here:
/// (stationarity, primal, dual, complementarity), all relative. Stationarity
/// ‖Cx − d + Aᵀλ‖ is divided by the smaller of max(‖d‖, ‖Cx‖) and ‖Aᵀλ‖
/// (when λ ≠ 0), so a small error in the contact forces shows.
fn independent_kkt(dir: &Path) -> Result<([f64; 4], f64, Vec<f64>), String> {
    let (n, _, c) = read_mtx(&dir.join("C.mtx"));
    let (m, na, a) = read_mtx(&dir.join("A.mtx"));
    let d = read_vec(&dir.join("d.mtx"));
    let g = read_vec(&dir.join("g.mtx"));
    let x = read_vec(&dir.join("x.mtx"));
    let lam = read_vec(&dir.join("lambda.mtx"));
    if na != n || d.len() != n || x.len() != n || g.len() != m || lam.len() != m {
        return Err(format!(
            "inconsistent export: n {n}, A {m}x{na}, |d| {}, |x| {}, |g| {}, |λ| {}",
            d.len(),
            x.len(),
            g.len(),
            lam.len()
        ));
    }
    if !finite(&x) || !finite(&lam) {
        return Err("NaN/Inf in the exported solution".into());
    }
    let cx = mul(&c, n, &x, false);
    let atl = mul(&a, n, &lam, true);
    let r: Vec<f64> = (0..n).map(|i| cx[i] - d[i] + atl[i]).collect();
    let level = norm(&d).max(norm(&cx));
    let forces = norm(&atl);
    let scale = if forces > 0.0 {
        level.min(forces)
    } else {
        level
    };
    let stat = if scale > 0.0 {
        norm(&r) / scale
    } else {
        norm(&r)
    };
    // What rounding alone leaves in r when it is evaluated in f64: ~√k ε per
    // row of k ≈ 18 terms, times |C||x| + |A|ᵀ|λ| + |d|. At contrast 1e8 the
    // exact solution's r is ~1e-6 of the contact forces (C x of the nearly
    // rigid stiff block cancels), so the reference is then held to this
    // floor, and to the closed form or the force balance where there is one.
    let abs_c: Vec<(usize, usize, f64)> = c.iter().map(|&(i, j, v)| (i, j, v.abs())).collect();
    let abs_a: Vec<(usize, usize, f64)> = a.iter().map(|&(i, j, v)| (i, j, v.abs())).collect();
    let xa: Vec<f64> = x.iter().map(|v| v.abs()).collect();
    let la: Vec<f64> = lam.iter().map(|v| v.abs()).collect();
    let cxa = mul(&abs_c, n, &xa, false);
    let ala = mul(&abs_a, n, &la, true);
    let bound: Vec<f64> = (0..n).map(|i| cxa[i] + ala[i] + d[i].abs()).collect();
    let floor = 4.0 * f64::EPSILON * norm(&bound) / if scale > 0.0 { scale } else { 1.0 };
    let ax = mul(&a, m, &x, false);
    let xs = x
        .iter()
        .fold(0.0f64, |s, v| s.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let ls = lam.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let primal = (0..m).fold(0.0f64, |s, i| s.max(ax[i] - g[i])) / xs;
    let dual = lam.iter().fold(0.0f64, |s, v| s.max(-v)) / ls.max(f64::MIN_POSITIVE);
    let compl = (0..m).fold(0.0f64, |s, i| s.max((lam[i] * (ax[i] - g[i])).abs()))
        / (ls * xs).max(f64::MIN_POSITIVE);
    Ok(([stat, primal, dual, compl], floor, lam))
}

/// The model's closed form or equilibrium, on a run's u and λ.
fn known_check(m: &Model, c: &Cell) -> Result<String, String> {
    let (u, lam) = (c.u.as_ref().unwrap(), c.lambda.as_ref().unwrap());
    match m.known {
        Known::None => Ok(String::new()),
        Known::TotalForce(f) => {
            let s: f64 = lam.iter().sum();
            let e = (s - f).abs() / f;
            if e <= AGREE {
                Ok(format!("Σλ = load to {e:.1e}"))
            } else {
                Err(format!("Σλ = {s:e}, load {f:e} (rel {e:.1e})"))
            }
        }
        Known::Uniaxial {
            p,
            m_lower,
            m_upper,
            y_if,
        } => {
            let mut err = 0.0f64;
            let mut scale = 0.0f64;
            for (k, x) in c.points.iter().enumerate() {
                let y = x[1];
                let uy = -p / m_lower * y.min(y_if) - p / m_upper * (y - y_if).max(0.0);
                err = err.max(u[2 * k].abs()).max((u[2 * k + 1] - uy).abs());
                scale = scale.max(uy.abs());
            }
            let e = err / scale;
            if e <= AGREE {
                Ok(format!("closed form to {e:.1e}"))
            } else {
                Err(format!("closed form off by {e:.1e}"))
            }
        }
    }
}

/// The verified reference of a model: (variant index, note) or why none.
fn reference(
    m: &Model,
    cells: &[Cell],
    budget: Duration,
    scratch: &Path,
) -> Result<(usize, String), String> {
    let mut cand: Vec<usize> = (0..cells.len())
        .filter(|&i| {
            let c = &cells[i];
            VARIANTS[i].0 != "penalty"
                && c.run.as_ref().is_some_and(|r| r.code == Some(0))
                && c.certified == Some(true)
                && c.kkt.is_some()
                && c.u.as_ref().is_some_and(|u| finite(u))
                && c.lambda.as_ref().is_some_and(|l| finite(l))
        })
        .collect();
    cand.sort_by(|&a, &b| cells[a].kkt.unwrap().total_cmp(&cells[b].kkt.unwrap()));
    let mut why = Vec::new();
    for &i in cand.iter().take(3) {
        let name = variant_name(&VARIANTS[i]);
        let dir = scratch.join(format!("ref-{i}"));
        let qp = dir.join("qp");
        let mut args = vec![
            "export".to_string(),
            "--qp".to_string(),
            qp.to_string_lossy().into_owned(),
            m.toml.to_string_lossy().into_owned(),
            "--solution".to_string(),
            "--quiet".to_string(),
        ];
        args.extend(variant_args(&VARIANTS[i]));
        args.extend(m.extra.iter().cloned());
        let run = run_signorini(&args, budget, &dir);
        if !qp.join("lambda.mtx").is_file() {
            why.push(format!(
                "{name}: export gave exit {:?}{}",
                run.code,
                if run.hung { " (hung)" } else { "" }
            ));
            continue;
        }
        let (k, floor, lam) = match independent_kkt(&qp) {
            Ok(v) => v,
            Err(e) => {
                why.push(format!("{name}: {e}"));
                continue;
            }
        };
        let kmax = k.iter().fold(0.0f64, |s, v| s.max(*v));
        let tol = REF_KKT.max(floor);
        if kmax.is_nan() || k[0] > tol || k[1..].iter().any(|v| *v > REF_KKT) {
            why.push(format!(
                "{name}: KKT evaluated here (stat {:.1e} [rounding floor {floor:.1e}], primal {:.1e}, dual {:.1e}, compl {:.1e}) > {REF_KKT:.0e}",
                k[0], k[1], k[2], k[3]
            ));
            continue;
        }
        let rep = rel_diff(&lam, cells[i].lambda.as_ref().unwrap());
        if rep > REPRODUCE {
            why.push(format!(
                "{name}: the export's λ differs from the run's by {rep:.1e} (not reproducible)"
            ));
            continue;
        }
        match known_check(m, &cells[i]) {
            Ok(note) => {
                return Ok((
                    i,
                    format!(
                        "reference {name}: KKT here {kmax:.1e} (rounding floor {floor:.1e}){}{}",
                        if note.is_empty() { "" } else { "; " },
                        note
                    ),
                ))
            }
            Err(e) => why.push(format!("{name}: {e}")),
        }
    }
    if cand.is_empty() {
        why.push("no certified exit-0 run".into());
    }
    Err(why.join("; "))
}

/// The agreement tolerances (u, λ) of a variant. 1e-6, except for penalty,
/// which solves its own problem (docs/methods.md §4.4, §8.4): its x is
/// O(ε_p) away, judged at 10× its observed relative violation, and its
/// contact forces are those of contact springs of compliance ε_j, judged at
/// 100/PENALTY_FACTOR (the same rule as `signorini compare`).
fn tolerances(method: &str, c: &Cell) -> (f64, f64) {
    if method == "penalty" {
        (
            (10.0 * c.primal.unwrap_or(f64::INFINITY)).max(AGREE),
            (100.0 / signorini::qp::primal::penalty::PENALTY_FACTOR).max(AGREE),
        )
    } else {
        (AGREE, AGREE)
    }
}

/// Judge one cell against the contract; fills rel_u, rel_lambda, verdict, ok.
fn judge(c: &mut Cell, refc: Option<&Cell>, method: &str) {
    let run = c.run.as_ref().unwrap();
    let (verdict, ok) = if run.hung {
        ("FAIL hung (killed after its budget)".to_string(), false)
    } else {
        match run.code {
            Some(3) => ("exit 3 (honest failure)".to_string(), true),
            Some(2) => (format!("FAIL exit 2: {}", first_error(&run.output)), false),
            Some(0) => {
                if c.certified != Some(true) {
                    ("FAIL exit 0 but not certified".to_string(), false)
                } else if c.kkt.is_none()
                    || !c.u.as_ref().is_some_and(|u| finite(u))
                    || !c.lambda.as_ref().is_some_and(|l| finite(l))
                {
                    (
                        "FAIL exit 0 with NaN/Inf/missing outputs".to_string(),
                        false,
                    )
                } else if let Some(r) = refc {
                    let du = rel_diff(c.u.as_ref().unwrap(), r.u.as_ref().unwrap());
                    let dl = rel_diff(c.lambda.as_ref().unwrap(), r.lambda.as_ref().unwrap());
                    c.rel_u = Some(du);
                    c.rel_lambda = Some(dl);
                    let (tu, tl) = tolerances(method, c);
                    if du <= tu && dl <= tl {
                        ("ok".to_string(), true)
                    } else {
                        (
                            format!("FAIL exit 0, certified, but wrong (u {du:.1e}, λ {dl:.1e})"),
                            false,
                        )
                    }
                } else {
                    (
                        "FAIL exit 0 but no verified reference to agree with".to_string(),
                        false,
                    )
                }
            }
            Some(k) => (format!("FAIL exit {k}"), false),
            None => ("FAIL killed by a signal".to_string(), false),
        }
    };
    c.verdict = verdict;
    c.ok = ok;
}

/// The first line starting with "error" (exit 2 messages), shortened.
fn first_error(out: &str) -> String {
    let l = out
        .lines()
        .find(|l| l.starts_with("error"))
        .or_else(|| out.lines().next())
        .unwrap_or("")
        .to_string();
    let mut s: String = l.chars().take(140).collect();
    if l.chars().count() > 140 {
        s.push('…');
    }
    s
}

fn env_list(key: &str) -> Option<Vec<String>> {
    std::env::var(key)
        .ok()
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.split(',').map(|t| t.trim().to_string()).collect())
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |x| format!("{x:.1e}"))
}

/// `SIGNORINI_HARD_REPORT=1` prints the table and does not fail (the before /
/// after tables of issue 11). `SIGNORINI_HARD_MODELS=punch,arch` (substrings
/// of model names) and `SIGNORINI_HARD_VARIANTS=ssn,cgc:cholesky` (variant
/// names; a bare method name selects all its variants) select a subset,
/// `SIGNORINI_HARD_BUDGET_S` sets the time budget of one run
/// (default 30 s) and `SIGNORINI_HARD_JOBS` the number of runs at a time
/// (default 2).
#[test]
fn every_variant_certifies_and_agrees_or_exits_3_on_every_hard_model() {
    let report_only = std::env::var("SIGNORINI_HARD_REPORT").is_ok_and(|v| v == "1");
    let budget = Duration::from_secs_f64(
        std::env::var("SIGNORINI_HARD_BUDGET_S")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(30.0),
    );
    let jobs: usize = std::env::var("SIGNORINI_HARD_JOBS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2)
        .max(1);
    let mut models = models();
    assert!(models.len() >= 17, "{} models", models.len());
    if let Some(sel) = env_list("SIGNORINI_HARD_MODELS") {
        models.retain(|m| sel.iter().any(|s| m.name.contains(s.as_str())));
    }
    let variants: Vec<usize> = match env_list("SIGNORINI_HARD_VARIANTS") {
        Some(sel) => (0..VARIANTS.len())
            .filter(|&i| {
                sel.iter()
                    .any(|s| variant_name(&VARIANTS[i]) == *s || VARIANTS[i].0 == s)
            })
            .collect(),
        None => (0..VARIANTS.len()).collect(),
    };
    let tmp = tempfile::tempdir().unwrap();

    // All solves, `jobs` at a time.
    let queue: Mutex<VecDeque<(usize, usize)>> = Mutex::new(
        (0..models.len())
            .flat_map(|mi| variants.iter().map(move |&vi| (mi, vi)))
            .collect(),
    );
    let results: Mutex<Vec<Vec<Cell>>> =
        Mutex::new(vec![vec![Cell::default(); VARIANTS.len()]; models.len()]);
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| loop {
                let Some((mi, vi)) = queue.lock().unwrap().pop_front() else {
                    break;
                };
                let scratch = tmp.path().join(format!("m{mi}-v{vi}"));
                let c = solve_cell(&models[mi], &VARIANTS[vi], budget, &scratch);
                let r = c.run.as_ref().unwrap();
                eprintln!(
                    "  {:<42} {:<16} exit {:>4} {:6.1} s",
                    models[mi].name,
                    variant_name(&VARIANTS[vi]),
                    if r.hung {
                        "hung".to_string()
                    } else {
                        format!("{:?}", r.code)
                    },
                    r.secs
                );
                results.lock().unwrap()[mi][vi] = c;
            });
        }
    });
    let mut results = results.into_inner().unwrap();

    // References, verdicts, table.
    let mut failures = Vec::new();
    let mut table = String::new();
    let mut summary: Vec<(String, Vec<String>)> = Vec::new();
    for (mi, m) in models.iter().enumerate() {
        let cells = &mut results[mi];
        let scratch = tmp.path().join(format!("ref-m{mi}"));
        let refr = reference(m, cells, budget, &scratch);
        let refc = refr.as_ref().ok().map(|(i, _)| cells[*i].clone());
        let any = variants
            .iter()
            .find_map(|&i| cells[i].nodes.map(|_| &cells[i]));
        table += &format!(
            "\n### {}{}\n\n{} nodes, {} contact rows, {} rigid modes. {}\n\n",
            m.name,
            if m.extra.is_empty() {
                String::new()
            } else {
                format!(" (`{}`)", m.extra.join(" "))
            },
            any.and_then(|c| c.nodes)
                .map_or("?".into(), |v| v.to_string()),
            any.and_then(|c| c.constraints)
                .map_or("?".into(), |v| v.to_string()),
            any.and_then(|c| c.rigid_modes)
                .map_or("?".into(), |v| v.to_string()),
            match &refr {
                Ok((_, note)) => note.clone(),
                Err(e) => format!("NO verified reference: {e}"),
            }
        );
        table += "| variant | exit | certified | iterations | KKT (JSON) | ‖u−u_ref‖/‖u_ref‖ | ‖λ−λ_ref‖/‖λ_ref‖ | time [s] | verdict |\n";
        table += "|---|---|---|---|---|---|---|---|---|\n";
        let mut row = Vec::new();
        for &vi in &variants {
            let c = &mut cells[vi];
            judge(c, refc.as_ref(), VARIANTS[vi].0);
            let r = c.run.as_ref().unwrap();
            table += &format!(
                "| {} | {} | {} | {} | {} | {} | {} | {:.2} | {} |\n",
                variant_name(&VARIANTS[vi]),
                if r.hung {
                    "killed".to_string()
                } else {
                    r.code.map_or("signal".into(), |k| k.to_string())
                },
                c.certified
                    .map_or("-".into(), |b| if b { "yes" } else { "no" }.to_string()),
                c.iterations.map_or("-".into(), |v| v.to_string()),
                fmt_opt(c.kkt),
                fmt_opt(c.rel_u),
                fmt_opt(c.rel_lambda),
                r.secs,
                c.verdict
            );
            row.push(if c.ok {
                if c.verdict == "ok" { "ok" } else { "3" }.to_string()
            } else if r.hung {
                "HUNG".to_string()
            } else {
                match r.code {
                    Some(0) => "BAD0",
                    Some(2) => "EX2",
                    _ => "FAIL",
                }
                .to_string()
            });
            if !c.ok {
                failures.push(format!(
                    "{} / {}: {}",
                    m.name,
                    variant_name(&VARIANTS[vi]),
                    c.verdict
                ));
            }
        }
        summary.push((m.name.clone(), row));
    }

    // Compact matrix: model × variant.
    let mut mat = String::from("| model |");
    for &vi in &variants {
        mat += &format!(" {} |", variant_name(&VARIANTS[vi]));
    }
    mat += "\n|---|";
    mat += &"---|".repeat(variants.len());
    mat += "\n";
    for (name, row) in &summary {
        mat += &format!("| {name} | {} |\n", row.join(" | "));
    }
    println!(
        "\n## Summary (ok = certified and agrees to {AGREE:.0e}; 3 = honest exit 3; \
         BAD0 = exit 0 uncertified or wrong; EX2 = exit 2; HUNG = killed after {:.0} s; FAIL = other)\n\n{mat}\n## Cells\n{table}",
        budget.as_secs_f64()
    );
    println!(
        "{} of {} cells break the contract",
        failures.len(),
        models.len() * variants.len()
    );
    if !report_only {
        assert!(
            failures.is_empty(),
            "{} cells break issue 11's contract:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }
}
