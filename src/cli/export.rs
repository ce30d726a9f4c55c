//! `signorini export --qp DIR model.toml`: the flags of
//! [`crate::run::export()`] (the assembled QP as Matrix Market files plus
//! `meta.json`, README "Exported QP") and its one line of report.

use super::solve::bad_input;
use super::SolverFlags;
use crate::run::{self, ExportSpec, Verdict};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

// clap prints these doc comments as `--help`: brackets such as [px] stay
// literal there, so rustdoc must not read them as links.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Write C.mtx, A.mtx, d.mtx, g.mtx, R.mtx (kernel), with friction T.mtx,
    /// t0.mtx and s.mtx (Tresca) or mu.mtx (Coulomb), and meta.json into this directory.
    #[arg(long, value_name = "DIR")]
    pub qp: PathBuf,
    /// Ignore every [[contact]] (A and g are then empty).
    #[arg(long)]
    pub no_contact: bool,
    /// Also solve (method from [solver] or the flags) and write x.mtx, λ.mtx
    /// (lambda.mtx), with friction λ_t (lambda_t.mtx), and the optimal value
    /// and the residuals of the written files into meta.json, as a reference.
    #[arg(long)]
    pub solution: bool,
    #[command(flatten)]
    pub solver: SolverFlags,
}

pub fn run(a: &ExportArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let t0 = Instant::now();
    let prep = match run::load(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let spec = ExportSpec {
        dir: a.qp.clone(),
        solution: a.solution,
        solver: a.solver.section(),
    };
    let r = match run::export(prep.comparable(), &spec) {
        Ok(r) => r,
        Err(e) => return bad_input(&e),
    };
    if !quiet {
        crate::outln!(
            "exported {} (n = {}, m = {}, nnz(C) = {}, kernel {}{}) to {} in {:.3} s (write {:.3} s)",
            a.problem.display(),
            r.n,
            r.m,
            r.nnz_c,
            r.kernel_dim,
            r.friction
                .map(|l| format!(", {l} friction"))
                .unwrap_or_default(),
            a.qp.display(),
            t0.elapsed().as_secs_f64(),
            r.t_write
        );
    }
    // A solution not converged or not certified is written and flagged
    // (meta.json) and exits 3, as solve does.
    match &r.solution {
        Some(s)
            if !s.verdict.certified() || (a.solver.strict && s.verdict != Verdict::Certified) =>
        {
            crate::errln!(
                "warning: {}: the exported solution ({}) is {} (written and flagged in {}; docs/methods.md §8)",
                a.problem.display(),
                s.method,
                if s.converged { "not certified" } else { "not converged" },
                a.qp.join("meta.json").display()
            );
            run::EXIT_NOT_CONVERGED
        }
        _ => 0,
    }
}
