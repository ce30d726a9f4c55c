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

pub fn run(a: &CompareArgs, quiet: bool) -> i32 {
    let prep = match pipeline::prepare(&a.problem, a.no_contact) {
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
    let base = choice(&a.solver);
    let mut rows = vec![];
    for (method, pc) in list {
        let mut c = base.clone();
        c.method = Some(method.clone());
        c.preconditioner = pc.map(|k| k.name().to_string());
        let outcome = match pipeline::options(&prep.problem, &c) {
            Err(e) => Err(e.to_string()),
            Ok((m, opts)) => {
                // Each method pays for its own factorization.
                crate::qp::factor::clear_cache();
                let t = Instant::now();
                pipeline::solve(&prep, &m, &opts)
                    .map(|r| (r, t.elapsed().as_secs_f64()))
                    .map_err(|e| e.to_string())
            }
        };
        if !quiet {
            eprintln!(
                "compare: {method} {} done",
                pc.map(|k| k.name()).unwrap_or("-")
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
    let table = table_json(&prep, &rows);
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

/// The table as JSON: `reference` = the converged row with the smallest KKT
/// residual; each row's `rel_diff` = ‖x − x_ref‖/‖x_ref‖ and `agrees` =
/// converged, rel_diff ≤ `agree_tol` and the same active set. `agree_tol` =
/// 1e-6, except for `penalty`, whose minimiser x_ε is O(ε_p) away from x:
/// there it is max(1e-6, 10·its relative constraint violation), the
/// violation being the observable O(ε_p) scale of that run.
pub fn table_json(prep: &Prepared, rows: &[Row]) -> serde_json::Value {
    let best = rows
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            r.outcome
                .as_ref()
                .ok()
                .filter(|(q, _)| q.status.converged())
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
            }
            Ok((q, t)) => {
                let u = prep.model.displacements(&q.x);
                let probes: serde_json::Map<String, serde_json::Value> = pipeline::probes(prep, &u)
                    .into_iter()
                    .map(|(n, _, _, v)| (n, json!(v)))
                    .collect();
                let agree_tol = if r.method == "penalty" {
                    (10.0 * q.kkt.primal).max(1e-6)
                } else {
                    1e-6
                };
                let (rel, agrees) = match reference {
                    Some(rf) => {
                        let num: f64 =
                            q.x.iter()
                                .zip(&rf.x)
                                .map(|(a, b)| (a - b) * (a - b))
                                .sum::<f64>()
                                .sqrt();
                        let den: f64 =
                            rf.x.iter()
                                .map(|a| a * a)
                                .sum::<f64>()
                                .sqrt()
                                .max(f64::MIN_POSITIVE);
                        let rel = num / den;
                        (
                            rel,
                            q.status.converged() && rel <= agree_tol && q.active == rf.active,
                        )
                    }
                    None => (f64::NAN, false),
                };
                o["converged"] = json!(q.status.converged());
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
                o["agrees"] = json!(agrees);
                o["agree_tol"] = json!(agree_tol);
            }
        }
        out.push(o);
    }
    json!({ "problem": prep.problem.name, "dofs": prep.model.qp.n(), "constraints": prep.model.qp.m(), "rows": out })
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
        " {:>7} {:>8} {:>9} {:>9} {:>15} {:>9}  agrees",
        "outer", "inner", "time[s]", "KKT", "energy", "rel.diff"
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
        for n in &names {
            let u = &r["probes"][n];
            line += &format!(
                " {:>12.5e} {:>12.5e}",
                u[0].as_f64().unwrap_or(f64::NAN),
                u[1].as_f64().unwrap_or(f64::NAN)
            );
        }
        line += &format!(
            " {:>7} {:>8} {:>9.4} {:>9.2e} {:>15.8e} {:>9.2e}  {}",
            r["iterations"].as_u64().unwrap_or(0),
            r["inner_iterations"].as_u64().unwrap_or(0),
            r["time_s"].as_f64().unwrap_or(f64::NAN),
            r["kkt_max"].as_f64().unwrap_or(f64::NAN),
            r["energy"].as_f64().unwrap_or(f64::NAN),
            r["rel_diff"].as_f64().unwrap_or(f64::NAN),
            if r["converged"] == false {
                "NOT CONVERGED"
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
    let mut s = String::from("method,preconditioner,converged,iterations,inner_iterations,time_s,kkt_max,energy,rel_diff,agrees,probes,error\n");
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
            "{},{},{},{},{},{},{},{},{},{},{},\"{}\"\n",
            r["method"].as_str().unwrap_or(""),
            r["preconditioner"].as_str().unwrap_or(""),
            r["converged"],
            r["iterations"],
            r["inner_iterations"],
            r["time_s"],
            r["kkt_max"],
            r["energy"],
            r["rel_diff"],
            r["agrees"],
            probes,
            r["error"].as_str().unwrap_or("").replace('"', "'")
        );
    }
    s
}
