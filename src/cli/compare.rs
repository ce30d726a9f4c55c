//! `signorini compare`: every method (each CGC preconditioner a variant) on
//! one problem, and the report's table: probe displacements, iterations,
//! time per phase, KKT residuals, energy, agreement with the most accurate
//! result. A failing variant shows that in its row; the others go on.

use super::solve::{bad_input, choice, EXIT_BAD_INPUT};
use super::SolverFlags;
use crate::pipeline::{self, Prepared};
use crate::qp::{precond::PrecondKind, registry, QpResult};
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Comma-separated variants: a method name (`cgc` = all six
    /// preconditioners) or `cgc:PRECONDITIONER`. Default: all.
    #[arg(long)]
    pub methods: Option<String>,
    /// Write the table as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the table as CSV.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Ignore every [[contact]].
    #[arg(long)]
    pub no_contact: bool,
    /// Wall-clock budget per variant [s]; a variant that reaches it is
    /// stopped and its row says so.
    #[arg(long)]
    pub time_limit: Option<f64>,
    #[command(flatten)]
    pub solver: SolverFlags,
}

/// One row of the table.
pub struct Row {
    pub method: String,
    pub preconditioner: String,
    pub outcome: Result<(QpResult, f64), String>,
}

/// The variants named by `spec` (None: all).
pub fn variants(spec: Option<&str>) -> Result<Vec<(String, Option<PrecondKind>)>, String> {
    let mut out = vec![];
    let all: Vec<String> = registry::names().iter().map(|s| s.to_string()).collect();
    let items: Vec<String> = match spec {
        None => all.clone(),
        Some(s) => s
            .split(',')
            .map(|x| x.trim().to_string())
            .filter(|x| !x.is_empty())
            .collect(),
    };
    for it in items {
        let (name, pc) = match it.split_once(':') {
            Some((n, p)) => (n.to_string(), Some(p.to_string())),
            None => (it.clone(), None),
        };
        let m = registry::find(&name)
            .ok_or_else(|| format!("unknown method \"{name}\"; known: {}", all.join(", ")))?;
        if m.preconditioned {
            match pc {
                Some(p) => out.push((
                    name,
                    Some(
                        PrecondKind::parse(&p)
                            .ok_or_else(|| format!("unknown preconditioner \"{p}\""))?,
                    ),
                )),
                None => out.extend(PrecondKind::ALL.iter().map(|k| (name.clone(), Some(*k)))),
            }
        } else {
            out.push((name, None));
        }
    }
    Ok(out)
}

pub fn run(a: &CompareArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let prep = match pipeline::prepare_with(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let list = match variants(a.methods.as_deref()) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: {}: {e}", a.problem.display());
            return EXIT_BAD_INPUT;
        }
    };
    if let Some(t) = a.time_limit {
        if !(t > 0.0 && t.is_finite()) {
            eprintln!(
                "error: {}: --time-limit {t} must be a positive number of seconds",
                a.problem.display()
            );
            return EXIT_BAD_INPUT;
        }
    }
    // Frictionless elastic contact does not depend on the loading path: the
    // last load step (full load) is the answer of a multi-step problem.
    let nsteps = prep.problem.file.nsteps();
    let step_model;
    let model = if nsteps > 1 {
        step_model = match pipeline::step_model(&prep, nsteps - 1) {
            Ok(m) => m,
            Err(e) => return bad_input(&e),
        };
        if !quiet {
            eprintln!(
                "compare: {} has {nsteps} load steps; every variant solves the last one (step {nsteps}, t = {}) from a cold start",
                prep.problem.name,
                prep.problem.file.step_time(nsteps - 1)
            );
        }
        &step_model
    } else {
        &prep.model
    };
    let base = choice(&a.solver);
    let mut rows = vec![];
    let total = list.len();
    for (k, (method, pc)) in list.into_iter().enumerate() {
        let mut c = base.clone();
        c.method = Some(method.clone());
        c.preconditioner = pc.map(|k| k.name().to_string());
        let label = match pc {
            Some(p) => format!("[{}/{total}] {method}:{}", k + 1, p.name()),
            None => format!("[{}/{total}] {method}", k + 1),
        };
        if !quiet {
            eprintln!("compare: {label} …");
        }
        let t = Instant::now();
        let outcome = match pipeline::options(&prep.problem, &c) {
            Err(e) => Err(e.to_string()),
            Ok((m, mut opts)) => {
                // Each method pays for its own factorization.
                crate::linalg::cholesky::clear_cache();
                opts.progress = !quiet;
                opts.label = Some(label.clone());
                opts.deadline = a
                    .time_limit
                    .map(|s| t + std::time::Duration::from_secs_f64(s));
                pipeline::solve_model(&prep, model, &m, &opts)
                    .map(|r| (r, t.elapsed().as_secs_f64()))
                    .map_err(|e| e.to_string())
            }
        };
        if !quiet {
            let how = match &outcome {
                Ok((r, _)) => r.status.describe(),
                Err(e) => format!("error: {e}"),
            };
            eprintln!(
                "compare: {label} {how} ({:.3} s)",
                t.elapsed().as_secs_f64()
            );
        }
        rows.push(Row {
            method,
            preconditioner: pc
                .map(|k| k.name().to_string())
                .unwrap_or_else(|| "-".into()),
            outcome,
        });
    }
    let penalty_eps = pipeline::options(&prep.problem, &base)
        .ok()
        .and_then(|(_, o)| o.penalty);
    let mut table = table_json(&prep, model, &rows, a.solver.kkt_target, penalty_eps);
    table["steps"] = json!({ "count": nsteps, "compared": nsteps });
    if let Some(t) = a.time_limit {
        table["time_limit_s"] = json!(t);
    }
    if !quiet {
        print_table(&prep, &table);
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&table).unwrap_or_default();
        if let Err(e) = crate::io::atomic::write_atomic_bytes(p, text.as_bytes()) {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    }
    if let Some(p) = &a.csv {
        if let Err(e) = crate::io::atomic::write_atomic_bytes(p, to_csv(&table).as_bytes()) {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    }
    0
}

/// ‖a − b‖ / ‖b‖ (0 when both vanish).
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let den = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    if den > 0.0 {
        num / den
    } else {
        num
    }
}

/// The table as JSON. `reference` = the converged, certified row with the
/// smallest KKT residual; each row's `rel_diff` = ‖x − x_ref‖/‖x_ref‖ and
/// `rel_diff_lambda` = ‖λ − λ_ref‖/‖λ_ref‖ (the contact forces), and
/// `agrees` = converged, certified (KKT ≤ `kkt_target`), both differences
/// ≤ its tolerance and the same active set. Both tolerances are 1e-6, except
/// for `penalty`, whose minimiser x_ε is O(ε_p) away from x: its x tolerance
/// (`agree_tol`) is max(1e-6, 10·its relative constraint violation), the
/// violation being the observable O(ε_p) scale of that run; its contact
/// forces are those of contact springs of compliance ε_j, off by about
/// ε_j·c_kk relative per row (10⁻³ by default, methods.md §4.4) and by more
/// at the edge of a contact zone (2.4·10⁻² measured on the floating punch of
/// tests/hard), so its λ tolerance (`agree_tol_lambda`) is 100·ε_p·max diag C
/// for a given ε_p, or 100/PENALTY_FACTOR for the default one.
pub fn table_json(
    prep: &Prepared,
    model: &crate::fem::Model,
    rows: &[Row],
    kkt_target: f64,
    penalty_eps: Option<f64>,
) -> serde_json::Value {
    let penalty_lambda_tol = match penalty_eps {
        Some(e) => 100.0 * e * model.qp.c.diag().iter().fold(0.0f64, |a, b| a.max(*b)),
        None => 100.0 / crate::qp::primal::penalty::PENALTY_FACTOR,
    };
    let certified = |r: &Row, q: &QpResult| {
        q.status.converged() && registry::certified(&r.method, &q.kkt, kkt_target, false)
    };
    let best = rows
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            r.outcome
                .as_ref()
                .ok()
                .filter(|(q, _)| certified(r, q) && r.method != "penalty")
                .map(|(q, _)| (i, q.kkt.max()))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|x| x.0);
    let reference = best
        .and_then(|i| rows[i].outcome.as_ref().ok())
        .map(|(q, _)| q);
    let mut out = vec![];
    for r in rows {
        let mut o = json!({ "method": r.method, "preconditioner": r.preconditioner });
        match &r.outcome {
            Err(e) => {
                o["error"] = json!(e);
                o["converged"] = json!(false);
                o["certified"] = json!(false);
                o["agrees"] = json!(false);
            }
            Ok((q, t)) => {
                let u = model.displacements(&q.x);
                let probes: serde_json::Map<String, serde_json::Value> = pipeline::probes(prep, &u)
                    .into_iter()
                    .map(|(n, _, _, v)| (n, json!(v)))
                    .collect();
                let (agree_tol, agree_tol_l) = if r.method == "penalty" {
                    (
                        (10.0 * q.kkt.primal).max(1e-6),
                        penalty_lambda_tol.max(1e-6),
                    )
                } else {
                    (1e-6, 1e-6)
                };
                let cert = certified(r, q);
                let (rel, rel_l, agrees) = match reference {
                    Some(rf) => {
                        let rel = rel_diff(&q.x, &rf.x);
                        let rel_l = rel_diff(&q.lambda, &rf.lambda);
                        (
                            rel,
                            rel_l,
                            cert && rel <= agree_tol
                                && rel_l <= agree_tol_l
                                && q.active == rf.active,
                        )
                    }
                    None => (f64::NAN, f64::NAN, false),
                };
                o["converged"] = json!(q.status.converged());
                o["certified"] = json!(cert);
                o["status"] = json!(q.status.describe());
                o["iterations"] = json!(q.iterations);
                o["inner_iterations"] = json!(q.inner_iterations);
                o["time_s"] = json!(t);
                o["phases"] = json!(q
                    .timings
                    .iter()
                    .map(|(k, v)| (k.clone(), json!(v)))
                    .collect::<serde_json::Map<_, _>>());
                o["kkt"] = json!(q.kkt);
                o["kkt_max"] = json!(q.kkt.max());
                o["energy"] = json!(q.energy);
                o["active"] = json!(q.active.iter().filter(|a| **a).count());
                o["probes"] = json!(probes);
                o["rel_diff"] = json!(rel);
                o["rel_diff_lambda"] = json!(rel_l);
                o["agrees"] = json!(agrees);
                o["agree_tol"] = json!(agree_tol);
                o["agree_tol_lambda"] = json!(agree_tol_l);
                o["notes"] = json!(q.notes);
            }
        }
        out.push(o);
    }
    json!({ "problem": prep.problem.name, "dofs": model.qp.n(), "constraints": model.qp.m(), "kkt_target": kkt_target, "rows": out })
}

fn print_table(prep: &Prepared, t: &serde_json::Value) {
    let names: Vec<String> = prep.problem.file.output.probes.keys().cloned().collect();
    println!(
        "{} — {} DOFs, {} contact constraints",
        prep.problem.name,
        prep.model.qp.n(),
        prep.model.qp.m()
    );
    let mut head = format!("{:<8} {:<9}", "method", "precond");
    for n in &names {
        head += &format!(" {:>12} {:>12}", format!("u1({n})"), format!("u2({n})"));
    }
    head += &format!(
        " {:>7} {:>8} {:>9} {:>9} {:>15} {:>9} {:>9}  agrees",
        "outer", "inner", "time[s]", "KKT", "energy", "diff(x)", "diff(λ)"
    );
    println!("{head}");
    for r in t["rows"].as_array().into_iter().flatten() {
        let mut line = format!(
            "{:<8} {:<9}",
            r["method"].as_str().unwrap_or(""),
            r["preconditioner"].as_str().unwrap_or("")
        );
        if let Some(e) = r["error"].as_str() {
            println!("{line} FAILED: {e}");
            continue;
        }
        if r["converged"] == false {
            println!("{line} {}", r["status"].as_str().unwrap_or("NOT CONVERGED"));
            continue;
        }
        for n in &names {
            let u = &r["probes"][n];
            line += &format!(
                " {:>12.5e} {:>12.5e}",
                u[0].as_f64().unwrap_or(f64::NAN),
                u[1].as_f64().unwrap_or(f64::NAN)
            );
        }
        line += &format!(
            " {:>7} {:>8} {:>9.4} {:>9.2e} {:>15.8e} {:>9.2e} {:>9.2e}  {}",
            r["iterations"].as_u64().unwrap_or(0),
            r["inner_iterations"].as_u64().unwrap_or(0),
            r["time_s"].as_f64().unwrap_or(f64::NAN),
            r["kkt_max"].as_f64().unwrap_or(f64::NAN),
            r["energy"].as_f64().unwrap_or(f64::NAN),
            r["rel_diff"].as_f64().unwrap_or(f64::NAN),
            r["rel_diff_lambda"].as_f64().unwrap_or(f64::NAN),
            if r["converged"] == false {
                "NOT CONVERGED"
            } else if r["certified"] == false {
                "NOT CERTIFIED"
            } else if r["agrees"] == true {
                "yes"
            } else {
                "no"
            }
        );
        println!("{line}");
    }
}

fn to_csv(t: &serde_json::Value) -> String {
    let mut s = String::from("method,preconditioner,converged,certified,iterations,inner_iterations,time_s,kkt_max,energy,rel_diff,rel_diff_lambda,agrees,probes,error\n");
    for r in t["rows"].as_array().into_iter().flatten() {
        let probes = r["probes"]
            .as_object()
            .map(|m| {
                m.iter()
                    .map(|(k, v)| format!("{k}={}:{}", v[0], v[1]))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .unwrap_or_default();
        s += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"\n",
            r["method"].as_str().unwrap_or(""),
            r["preconditioner"].as_str().unwrap_or(""),
            r["converged"],
            r["certified"],
            r["iterations"],
            r["inner_iterations"],
            r["time_s"],
            r["kkt_max"],
            r["energy"],
            r["rel_diff"],
            r["rel_diff_lambda"],
            r["agrees"],
            probes,
            r["error"].as_str().unwrap_or("").replace('"', "'")
        );
    }
    s
}
