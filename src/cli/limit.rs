//! `signorini limit model.toml`: what a contact solve is measured against in
//! the benchmark: one sparse Cholesky factorization of C and one solve
//! C x = d, on the same assembled C the methods see (with the fixing-DOF
//! springs of `linalg::cholesky` when a body floats, so it is defined for
//! semicoercive C; that regularisation costs nothing extra).
//! Prints one JSON line with the phase times.

use super::solve::{bad_input, EXIT_BAD_INPUT};
use crate::run;
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

// clap prints these doc comments as `--help`: brackets such as [px] stay
// literal there, so rustdoc must not read them as links.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone)]
pub struct LimitArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Ignore every [[contact]] (contact curves become interior lines).
    #[arg(long)]
    pub no_contact: bool,
    /// Factor and solve this many times; the JSON holds the median.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
    /// amd | nested-dissection; overrides [solver] ordering (docs/methods.md §3).
    #[arg(long)]
    pub ordering: Option<String>,
    /// Largest factor allowed, e.g. "8 GiB"; overrides [solver] memory_limit.
    #[arg(long)]
    pub memory_limit: Option<String>,
}

pub fn run(a: &LimitArgs, _quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let prep = match run::prepare_with(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let flags = crate::qp::SolverSection {
        ordering: a.ordering.clone(),
        memory_limit: a.memory_limit.clone(),
        ..Default::default()
    };
    let settings = match run::options(&prep.problem, &flags) {
        Ok((_, o)) => o.settings,
        Err(e) => return bad_input(&e),
    };
    let ordering = settings.ordering;
    let qp = &prep.model.qp;
    let (mut tf, mut ts) = (vec![], vec![]);
    let mut residual = f64::NAN;
    for _ in 0..a.repeat.max(1) {
        let t0 = Instant::now();
        let ch = match settings.workspace().cholesky(&qp.c, &qp.kernel) {
            Ok(c) => c,
            Err(e) => {
                let e = crate::qp::QpError::from(e);
                eprintln!("error: {}: {e}", a.problem.display());
                return EXIT_BAD_INPUT;
            }
        };
        tf.push(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        let x = ch.solve(&qp.d);
        ts.push(t1.elapsed().as_secs_f64());
        if qp.kernel.is_empty() {
            let cx = qp.c.mul(&x);
            let r: Vec<f64> = cx.iter().zip(&qp.d).map(|(a, b)| a - b).collect();
            residual = crate::linalg::sparse::norm(&r)
                / crate::linalg::sparse::norm(&qp.d).max(f64::MIN_POSITIVE);
        }
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    let (f, s) = (med(&mut tf), med(&mut ts));
    println!(
        "{}",
        json!({
            "problem": a.problem.display().to_string(),
            "n": qp.n(), "nnz_C": qp.c.nnz(), "kernel_dim": qp.kernel.len(),
            "t_read": prep.t_read, "t_assemble": prep.t_assemble,
            "t_factor": f, "t_solve": s, "t_factor_solve": f + s,
            "repeat": a.repeat.max(1), "ordering": ordering.name(),
            "relative_residual": if residual.is_finite() { json!(residual) } else { json!(null) },
        })
    );
    0
}
