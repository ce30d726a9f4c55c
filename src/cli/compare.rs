//! `signorini compare`: the flags, the progress lines and the printed table
//! of [`crate::run::compare()`], which runs every method (each CGC
//! preconditioner a variant) on one problem and holds the agreement rules.

use super::solve::{bad_input, EXIT_BAD_INPUT};
use super::SolverFlags;
use crate::run::compare::{compare, label, CompareSpec, Event, Table};
use crate::run::{self, Prepared};
use clap::Args;
use std::path::PathBuf;

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

pub fn run(a: &CompareArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let prep = match run::prepare_with(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
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
    let spec = CompareSpec {
        methods: a.methods.clone(),
        solver: a.solver.section.clone(),
        time_limit: a.time_limit,
        progress: !quiet,
    };
    let name = &prep.problem.name;
    let mut report = |e: Event<'_>| {
        if quiet {
            return;
        }
        match e {
            Event::Plan {
                steps,
                time,
                friction_only,
            } => {
                let n = steps.count;
                if steps.path {
                    eprintln!(
                        "compare: {name} has {n} load steps and friction; every variant follows the load path as solve does (each step warm-started from the previous) and the last one (step {n}, t = {time}) is compared"
                    );
                } else if prep.problem.file.steps.len() > 1 {
                    eprintln!(
                        "compare: {name} has {n} load steps; every variant solves the last one (step {n}, t = {time}) from a cold start"
                    );
                }
                if let Some(kept) = friction_only {
                    let names: Vec<&str> = kept.iter().map(|v| v.method.name()).collect();
                    eprintln!(
                        "compare: {name} has friction; only the methods that solve it are run: {}",
                        names.join(", ")
                    );
                }
            }
            Event::Start {
                index,
                total,
                variant,
            } => eprintln!("compare: {} …", label(index, total, variant)),
            Event::Done {
                index,
                total,
                variant,
                outcome,
                seconds,
            } => {
                let how = match outcome {
                    Ok(r) => r.result.status.describe(),
                    Err(e) => format!("error: {e}"),
                };
                eprintln!(
                    "compare: {} {how} ({seconds:.3} s)",
                    label(index, total, variant)
                );
            }
        }
    };
    let table = match compare(&prep, &spec, &mut report) {
        Ok(t) => t,
        Err(e) => return bad_input(&e),
    };
    if !quiet {
        print_table(&prep, &table);
    }
    if let Some(p) = &a.json {
        if let Err(e) = crate::io::atomic::write_atomic_bytes(p, table.to_json().as_bytes()) {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    }
    if let Some(p) = &a.csv {
        if let Err(e) = crate::io::atomic::write_atomic_bytes(p, table.to_csv().as_bytes()) {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    }
    0
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
        if let Some(note) = &s.fallback {
            println!("{:<8} └ {note}", "");
        }
    }
}
