//! `signorini compare`: the flags, the progress lines and the printed table
//! of [`crate::run::compare()`], which runs every method (each CGC
//! preconditioner a variant) on one problem and holds the agreement rules.

use super::progress::progress;
use super::solve::{bad_input, EXIT_BAD_INPUT};
use super::SolverFlags;
use crate::problem::Problem;
use crate::run;
use crate::run::compare::{compare, label, CompareSpec, Event, Table};
use clap::Args;
use std::path::{Path, PathBuf};

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

/// Whether `a` and `b` name one file: the same path, or the same name in
/// one directory reached by two spellings (`x.json`, `./x.json`, a link).
fn same_file(a: &Path, b: &Path) -> bool {
    if a == b {
        return true;
    }
    let dir = |p: &Path| {
        let d = p.parent().filter(|d| !d.as_os_str().is_empty());
        d.unwrap_or(Path::new(".")).canonicalize().ok()
    };
    a.file_name().is_some()
        && a.file_name() == b.file_name()
        && dir(a).is_some()
        && dir(a) == dir(b)
}

pub fn run(a: &CompareArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    // Two outputs at one path: the second would overwrite the first.
    if let (Some(j), Some(c)) = (&a.json, &a.csv) {
        if same_file(j, c) {
            return bad_input(&format!(
                "--json {} and --csv {} name the same file: the CSV would overwrite the JSON; give two paths",
                j.display(),
                c.display()
            ));
        }
    }
    let loaded = match run::load(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let prep = loaded.comparable();
    if let Some(t) = a.time_limit {
        if !(t > 0.0 && t.is_finite()) {
            crate::errln!(
                "error: {}: --time-limit {t} must be a positive number of seconds",
                a.problem.display()
            );
            return EXIT_BAD_INPUT;
        }
    }
    let spec = CompareSpec {
        methods: a.methods.clone(),
        solver: a.solver.section(),
        time_limit: a.time_limit,
        progress: progress(quiet),
    };
    let problem = prep.problem();
    let name = &problem.name;
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
                    crate::errln!(
                        "compare: {name} has {n} load steps and friction; every variant follows the load path as solve does (each step warm-started from the previous) and the last one (step {n}, t = {time}) is compared"
                    );
                } else if problem.file.steps.len() > 1 {
                    crate::errln!(
                        "compare: {name} has {n} load steps; every variant solves the last one (step {n}, t = {time}) from a cold start"
                    );
                }
                if let Some(kept) = friction_only {
                    let names: Vec<&str> = kept.iter().map(|v| v.method.name()).collect();
                    crate::errln!(
                        "compare: {name} has friction; only the methods that solve it are run: {}",
                        names.join(", ")
                    );
                }
            }
            Event::Start {
                index,
                total,
                variant,
            } => crate::errln!("compare: {} …", label(index, total, variant)),
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
                crate::errln!(
                    "compare: {} {how} ({seconds:.3} s)",
                    label(index, total, variant)
                );
            }
        }
    };
    let table = match compare(prep, &spec, &mut report) {
        Ok(t) => t,
        Err(e) => return bad_input(&e),
    };
    if !quiet {
        print_table(problem, &table);
    }
    if let Some(p) = &a.json {
        if let Err(e) = crate::io::atomic::write_atomic_bytes(p, table.to_json().as_bytes()) {
            crate::errln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    }
    if let Some(p) = &a.csv {
        if let Err(e) = crate::io::atomic::write_atomic_bytes(p, table.to_csv().as_bytes()) {
            crate::errln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    }
    // A table without one certified row holds no answer: every variant
    // failed, timed out or was not certified, and there is nothing the
    // others were measured against (exit 3, as an uncertified solve).
    if !table.rows.iter().any(|r| r.certified) {
        crate::errln!(
            "warning: {}: no variant gave a certified answer; the table has no reference (docs/methods.md §8)",
            a.problem.display()
        );
        return crate::run::EXIT_NOT_CONVERGED;
    }
    0
}

/// Whether the row of method `name` is a penalised method's.
fn penalised_row(name: &str) -> bool {
    crate::qp::MethodId::ALL
        .iter()
        .any(|m| m.name() == name && crate::run::compare::penalised(*m))
}

fn print_table(problem: &Problem, t: &Table) {
    let names: Vec<String> = problem.file.output.probes.keys().cloned().collect();
    crate::outln!(
        "{} — {} DOFs, {} contact constraints",
        problem.name,
        t.dofs,
        t.constraints
    );
    // u1 u2 per probe, and u3 in 3D (the components the rows hold).
    let dim = t
        .rows
        .iter()
        .filter_map(|r| r.solved.as_ref())
        .find_map(|s| s.probes.values().next().map(Vec::len))
        .unwrap_or(2);
    let mut head = format!("{:<8} {:<9}", "method", "precond");
    for n in &names {
        for k in 1..=dim {
            head += &format!(" {:>12}", format!("u{k}({n})"));
        }
    }
    // With friction, the tangential forces' difference too.
    let friction = t
        .rows
        .iter()
        .filter_map(|r| r.solved.as_ref())
        .any(|s| s.rel_diff_lambda_t.is_some());
    head += &format!(
        " {:>7} {:>8} {:>9} {:>9} {:>15} {:>9} {:>9}",
        "outer", "inner", "time[s]", "KKT", "energy", "diff(x)", "diff(λ)"
    );
    if friction {
        head += &format!(" {:>9}", "diff(λ_t)");
    }
    head += "  agrees";
    crate::outln!("{head}");
    for r in &t.rows {
        let mut line = format!("{:<8} {:<9}", r.method, r.preconditioner);
        if let Some(e) = &r.error {
            crate::outln!("{line} FAILED: {e}");
            continue;
        }
        let Some(s) = &r.solved else {
            continue;
        };
        if !r.converged {
            crate::outln!("{line} {}", s.status);
            continue;
        }
        for n in &names {
            // -0 prints as 0 (`-0.00000e0` reads as a tiny negative value).
            let z = |v: f64| if v == 0.0 { 0.0 } else { v };
            for k in 0..dim {
                let v = s.probes.get(n).and_then(|u| u.get(k).copied());
                line += &format!(" {:>12.5e}", z(v.unwrap_or(f64::NAN)));
            }
        }
        line += &format!(
            " {:>7} {:>8} {:>9.4} {:>9.2e} {:>15.8e} {:>9.2e} {:>9.2e}",
            s.iterations,
            s.inner_iterations,
            s.time_s,
            s.kkt_max,
            s.energy,
            s.rel_diff,
            s.rel_diff_lambda,
        );
        if friction {
            line += &format!(" {:>9.2e}", s.rel_diff_lambda_t.unwrap_or(f64::NAN));
        }
        let verdict = if !r.certified {
            "NOT CERTIFIED".to_string()
        } else if r.agrees && penalised_row(&r.method) {
            // A penalised answer agrees to its O(ε_p), as the guide's table says.
            "yes (O(ε))".to_string()
        } else if r.agrees {
            "yes".to_string()
        } else if let Some(why) = &s.disagrees {
            // The check it fails, so that a certified `no` is read right.
            format!("no ({why})")
        } else {
            "no".to_string()
        };
        line += &format!("  {verdict}");
        crate::outln!("{line}");
        // A row solved by another method (a fallback) says so under it:
        // its numbers are that method's.
        if let Some(note) = &s.fallback {
            crate::outln!("{:<8} └ {note}", "");
        }
    }
}
