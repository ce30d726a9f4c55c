//! `signorini compare`: every method (each CGC preconditioner a variant) on
//! one problem, and the report's table: probe displacements, iterations,
//! time per phase, KKT residuals, energy, agreement with the most accurate
//! result. A failing variant shows that in its row; the others go on.

use super::solve::{bad_input, EXIT_BAD_INPUT};
use super::SolverFlags;
use crate::qp::{precond::PrecondKind, registry, QpResult};
use crate::run::{self, Prepared};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
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
    /// Ignore every `[[contact]]`.
    #[arg(long)]
    pub no_contact: bool,
    /// Wall-clock budget per variant (s); a variant that reaches it is
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
        if m.capabilities().preconditioned {
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
    let prep = match run::prepare_with(&a.problem, a.no_contact, build) {
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
        step_model = match run::step_model(&prep, nsteps - 1) {
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
    // With friction only the methods that solve it are run (unless named):
    // the others would all be refused (docs/methods.md §9.2).
    let list: Vec<_> = if model.qp.friction.is_some() && a.methods.is_none() {
        let kept: Vec<_> = list
            .into_iter()
            .filter(|(m, _)| registry::find(m).is_some_and(|m| m.capabilities().friction))
            .collect();
        if !quiet {
            let names: Vec<&str> = kept.iter().map(|(m, _)| m.as_str()).collect();
            eprintln!(
                "compare: {} has friction; only the methods that solve it are run: {}",
                prep.problem.name,
                names.join(", ")
            );
        }
        kept
    } else {
        list
    };
    let base = a.solver.section.clone();
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
        let outcome = match run::options(&prep.problem, &c) {
            Err(e) => Err(e.to_string()),
            Ok((m, mut opts)) => {
                // Each method pays for its own factorization: every solve
                // gets a fresh workspace.
                opts.progress = !quiet;
                opts.label = Some(label.clone());
                opts.deadline = a
                    .time_limit
                    .map(|s| t + std::time::Duration::from_secs_f64(s));
                run::solve_model(&prep, model, m, &opts)
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
    let penalty_eps = run::options(&prep.problem, &base)
        .ok()
        .and_then(|(_, o)| o.settings.penalty.eps);
    let kkt_target = run::options(&prep.problem, &base)
        .map_or(crate::qp::settings::DEFAULT_KKT_TARGET, |(_, o)| {
            o.settings.kkt_target
        });
    let mut table = table_json(&prep, model, &rows, kkt_target, penalty_eps);
    table.steps = TableSteps {
        count: nsteps,
        compared: nsteps,
    };
    table.time_limit_s = a.time_limit;
    if !quiet {
        print_table(&prep, &table);
    }
    if let Some(p) = &a.json {
        let text = table.to_json();
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
/// ≤ its tolerance and the same active set. Both tolerances are 1e-6 (or the
/// rounding floor of the row's or the reference's stationarity, if larger:
/// docs/methods.md §8.4), except for `penalty`, whose minimiser x_ε is
/// O(ε_p) away from x: its x tolerance (`agree_tol`) is max(that, 10·its
/// relative constraint violation), the
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
) -> Table {
    let penalty_lambda_tol = match penalty_eps {
        Some(e) => 100.0 * e * model.qp.c.diag().iter().fold(0.0f64, |a, b| a.max(*b)),
        None => 100.0 / crate::qp::primal::penalty::PENALTY_FACTOR,
    };
    let certified = |r: &Row, q: &QpResult| {
        q.status.converged()
            && crate::qp::MethodId::parse(&r.method)
                .is_some_and(|m| registry::certified(m, &q.kkt, kkt_target, false))
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
        let row = match &r.outcome {
            Err(e) => TableRow {
                method: r.method.clone(),
                preconditioner: r.preconditioner.clone(),
                error: Some(e.clone()),
                converged: false,
                certified: false,
                agrees: false,
                solved: None,
            },
            Ok((q, t)) => {
                let u = model.displacements(&q.x);
                let probes = run::probes(prep, &u)
                    .into_iter()
                    .map(|(n, _, _, v)| (n, v))
                    .collect();
                // Two answers at the rounding floor differ by about the
                // floor, relative (docs/methods.md §8.4).
                let base = reference
                    .map_or(0.0, |rf| rf.kkt.stationarity_floor)
                    .max(q.kkt.stationarity_floor)
                    .clamp(1e-6, crate::qp::kkt::FLOOR_CAP);
                let (agree_tol, agree_tol_lambda) = if r.method == "penalty" {
                    (
                        (10.0 * q.kkt.primal).max(base),
                        penalty_lambda_tol.max(base),
                    )
                } else {
                    (base, base)
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
                                && rel_l <= agree_tol_lambda
                                && q.active == rf.active,
                        )
                    }
                    None => (f64::NAN, f64::NAN, false),
                };
                TableRow {
                    method: r.method.clone(),
                    preconditioner: r.preconditioner.clone(),
                    error: None,
                    converged: q.status.converged(),
                    certified: cert,
                    agrees,
                    solved: Some(SolvedRow {
                        status: q.status.describe(),
                        iterations: q.iterations,
                        inner_iterations: q.inner_iterations,
                        time_s: *t,
                        phases: q.timings.iter().cloned().collect(),
                        kkt: q.kkt,
                        kkt_max: q.kkt.max(),
                        energy: q.energy,
                        active: q.active.iter().filter(|a| **a).count(),
                        probes,
                        rel_diff: rel,
                        rel_diff_lambda: rel_l,
                        agree_tol,
                        agree_tol_lambda,
                        notes: q.notes.iter().map(ToString::to_string).collect(),
                    }),
                }
            }
        };
        out.push(row);
    }
    Table {
        problem: prep.problem.name.clone(),
        dofs: model.qp.n(),
        constraints: model.qp.m(),
        kkt_target,
        rows: out,
        steps: TableSteps {
            count: 1,
            compared: 1,
        },
        time_limit_s: None,
    }
}

/// The comparison table (`--json`; keys in alphabetical order).
#[derive(Debug, Clone, Serialize)]
pub struct Table {
    pub problem: String,
    pub dofs: usize,
    pub constraints: usize,
    pub kkt_target: f64,
    pub rows: Vec<TableRow>,
    /// Load steps of the problem; the last is compared.
    pub steps: TableSteps,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_limit_s: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct TableSteps {
    pub count: usize,
    pub compared: usize,
}

/// One variant: its error, or its result ([`SolvedRow`]).
#[derive(Debug, Clone, Serialize)]
pub struct TableRow {
    pub method: String,
    pub preconditioner: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub converged: bool,
    pub certified: bool,
    pub agrees: bool,
    #[serde(flatten)]
    pub solved: Option<SolvedRow>,
}

#[derive(Debug, Clone, Serialize)]
pub struct SolvedRow {
    pub status: String,
    pub iterations: usize,
    pub inner_iterations: usize,
    pub time_s: f64,
    pub phases: BTreeMap<String, f64>,
    pub kkt: crate::qp::Kkt,
    pub kkt_max: f64,
    pub energy: f64,
    pub active: usize,
    pub probes: BTreeMap<String, [f64; 2]>,
    pub rel_diff: f64,
    pub rel_diff_lambda: f64,
    pub agree_tol: f64,
    pub agree_tol_lambda: f64,
    pub notes: Vec<String>,
}

impl Table {
    /// The JSON text, keys in alphabetical order at every level.
    pub fn to_json(&self) -> String {
        serde_json::to_value(self)
            .and_then(|v| serde_json::to_string_pretty(&v))
            .unwrap_or_default()
    }
}

fn print_table(prep: &Prepared, t: &Table) {
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
    for r in &t.rows {
        let mut line = format!("{:<8} {:<9}", r.method, r.preconditioner);
        if let Some(e) = &r.error {
            println!("{line} FAILED: {e}");
            continue;
        }
        let Some(s) = &r.solved else {
            continue;
        };
        if !r.converged {
            println!("{line} {}", s.status);
            continue;
        }
        for n in &names {
            let u = s.probes.get(n).copied().unwrap_or([f64::NAN; 2]);
            line += &format!(" {:>12.5e} {:>12.5e}", u[0], u[1]);
        }
        line += &format!(
            " {:>7} {:>8} {:>9.4} {:>9.2e} {:>15.8e} {:>9.2e} {:>9.2e}  {}",
            s.iterations,
            s.inner_iterations,
            s.time_s,
            s.kkt_max,
            s.energy,
            s.rel_diff,
            s.rel_diff_lambda,
            if !r.certified {
                "NOT CERTIFIED"
            } else if r.agrees {
                "yes"
            } else {
                "no"
            }
        );
        println!("{line}");
        // A row solved by another method (a fallback) says so under it:
        // its numbers are that method's.
        for note in s.notes.iter().filter(|n| n.contains(" instead")) {
            println!("{:<8} └ {note}", "");
        }
    }
}

/// A value as in the JSON (`null` for a missing or non-finite number).
fn js<T: Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_else(|_| "null".into())
}

fn to_csv(t: &Table) -> String {
    let mut s = String::from("method,preconditioner,converged,certified,iterations,inner_iterations,time_s,kkt_max,energy,rel_diff,rel_diff_lambda,agrees,probes,error\n");
    for r in &t.rows {
        let o = r.solved.as_ref();
        let probes = o
            .map(|o| {
                o.probes
                    .iter()
                    .map(|(k, v)| format!("{k}={}:{}", js(&v[0]), js(&v[1])))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .unwrap_or_default();
        s += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"\n",
            r.method,
            r.preconditioner,
            r.converged,
            r.certified,
            js(&o.map(|o| o.iterations)),
            js(&o.map(|o| o.inner_iterations)),
            js(&o.map(|o| o.time_s)),
            js(&o.map(|o| o.kkt_max)),
            js(&o.map(|o| o.energy)),
            js(&o.map(|o| o.rel_diff)),
            js(&o.map(|o| o.rel_diff_lambda)),
            r.agrees,
            probes,
            r.error.as_deref().unwrap_or("").replace('"', "'")
        );
    }
    s
}
