//! `signorini export --qp DIR model.toml`: the assembled QP
//! min ½xᵀCx − xᵀd, Ax ≤ g as Matrix Market files plus `meta.json`, so other
//! solvers (Clarabel, OSQP, MATLAB's quadprog, …) can be run on exactly the
//! problem signorini solves. The format is documented in the README
//! ("Exported QP").

use super::solve::{bad_input, EXIT_BAD_INPUT};
use super::SolverFlags;
use crate::io::mtx;
use crate::run;
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

// clap prints these doc comments as `--help`: brackets such as [px] stay
// literal there, so rustdoc must not read them as links.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Write C.mtx, A.mtx, d.mtx, g.mtx, R.mtx (kernel) and meta.json into this directory.
    #[arg(long, value_name = "DIR")]
    pub qp: PathBuf,
    /// Ignore every [[contact]] (A and g are then empty).
    #[arg(long)]
    pub no_contact: bool,
    /// Also solve (method from [solver] or the flags) and write x.mtx, λ.mtx
    /// (lambda.mtx) and the optimal value into meta.json, as a reference.
    #[arg(long)]
    pub solution: bool,
    #[command(flatten)]
    pub solver: SolverFlags,
}

pub fn run(a: &ExportArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let t0 = Instant::now();
    let prep = match run::prepare_with(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let qp = &prep.model.qp;
    let mut solved = None;
    if a.solution {
        let res = run::options(&prep.problem, &a.solver.section)
            .and_then(|(method, opts)| run::solve(&prep, method, &opts).map(|r| (method, r)));
        match res {
            Ok(r) => solved = Some(r),
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        }
    }
    if let Err(e) = std::fs::create_dir_all(&a.qp) {
        eprintln!("error: {}: cannot create directory: {e}", a.qp.display());
        return EXIT_BAD_INPUT;
    }
    let t_write = Instant::now();
    let src = format!(
        "signorini export of {} (min 1/2 x'Cx - d'x subject to Ax <= g)",
        a.problem.display()
    );
    let p = |n: &str| a.qp.join(n);
    let write = || -> Result<(), crate::io::IoError> {
        mtx::write_sparse(
            &p("C.mtx"),
            &qp.c,
            true,
            &format!("{src}\nC: stiffness, symmetric positive (semi)definite, lower triangle"),
        )?;
        mtx::write_sparse(
            &p("A.mtx"),
            &qp.a,
            false,
            &format!("{src}\nA: one row per contact constraint"),
        )?;
        mtx::write_vector(&p("d.mtx"), &qp.d, &format!("{src}\nd: load vector"))?;
        mtx::write_vector(&p("g.mtx"), &qp.g, &format!("{src}\ng: initial gaps"))?;
        // Kernel of C (rigid motions of floating bodies), one column each.
        let k = qp.kernel.len();
        let mut r = vec![];
        for v in &qp.kernel {
            r.extend_from_slice(v);
        }
        crate::io::atomic::write_atomic_with(&p("R.mtx"), |w| {
            writeln!(w, "%%MatrixMarket matrix array real general")?;
            writeln!(
                w,
                "% {src}\n% R: basis of ker C (column-major), one column per rigid mode"
            )?;
            writeln!(w, "{} {}", qp.n(), k)?;
            for x in &r {
                writeln!(w, "{x:e}")?;
            }
            Ok(())
        })?;
        if let Some((_, res)) = &solved {
            mtx::write_vector(
                &p("x.mtx"),
                &res.x,
                &format!("{src}\nx: signorini's solution"),
            )?;
            mtx::write_vector(
                &p("lambda.mtx"),
                &res.lambda,
                &format!("{src}\nlambda: contact multipliers"),
            )?;
        }
        let meta = json!({
            "format": "signorini-qp",
            "version": 1,
            "objective": "min 1/2 x'Cx - d'x subject to Ax <= g",
            "files": {"C": "C.mtx", "A": "A.mtx", "d": "d.mtx", "g": "g.mtx", "R": "R.mtx",
                      "x": solved.as_ref().map(|_| "x.mtx"), "lambda": solved.as_ref().map(|_| "lambda.mtx")},
            "problem": a.problem.display().to_string(),
            "mesh": prep.problem.mesh_path().display().to_string(),
            "n": qp.n(),
            "m": qp.m(),
            "nnz_C": qp.c.nnz(),
            "nnz_A": qp.a.nnz(),
            "kernel_dim": k,
            "nodes": prep.mesh.nodes.len(),
            "triangles": prep.model.topo.triangles.len(),
            "energy": solved.as_ref().map(|(_, r)| qp.energy(&r.x)),
            "method": solved.as_ref().map(|(m, _)| m.name()),
            "converged": solved.as_ref().map(|(_, r)| r.status.converged()),
            "kkt": solved.as_ref().map(|(_, r)| json!({
                "primal": r.kkt.primal, "dual": r.kkt.dual,
                "complementarity": r.kkt.complementarity, "stationarity": r.kkt.stationarity})),
            "t_read": prep.t_read,
            "t_assemble": prep.t_assemble,
        });
        let text = serde_json::to_string_pretty(&meta).unwrap_or_default();
        crate::io::atomic::write_atomic_bytes(&p("meta.json"), text.as_bytes())
    };
    if let Err(e) = write() {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
    if !quiet {
        println!(
            "exported {} (n = {}, m = {}, nnz(C) = {}, kernel {}) to {} in {:.3} s (write {:.3} s)",
            a.problem.display(),
            qp.n(),
            qp.m(),
            qp.c.nnz(),
            qp.kernel.len(),
            a.qp.display(),
            t0.elapsed().as_secs_f64(),
            t_write.elapsed().as_secs_f64()
        );
    }
    0
}
