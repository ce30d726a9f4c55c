//! The assembled QP min ½xᵀCx − xᵀd, Ax ≤ g (with friction: the tangential
//! rows T, their offsets t0 and the slip bounds, docs/methods.md §9) as
//! Matrix Market files plus `meta.json`, so other solvers (Clarabel, OSQP,
//! MATLAB's quadprog, …) can be run on exactly the problem signorini solves;
//! optionally with signorini's solution. The format is documented in the
//! README ("Exported QP"). `signorini export --qp DIR` is this API plus flag
//! parsing and printing.

use super::prepare::{options, solve, Prepared};
use super::RunError;
use crate::io::{atomic, mtx};
use crate::qp::{kkt, Kkt, QpResult, SlipBound, SolverSection};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where and what to export.
#[derive(Debug, Clone)]
pub struct ExportSpec {
    /// The directory of the files (created if missing).
    pub dir: PathBuf,
    /// Also solve, with the method of `[solver]` and `solver` laid over it,
    /// and write the solution and its residuals.
    pub solution: bool,
    pub solver: SolverSection,
}

/// The solution written with `--solution`.
#[derive(Debug, Clone)]
pub struct ExportedSolution {
    pub method: String,
    pub converged: bool,
    /// The objective of `meta.json` at x (with friction: plus Σ sᵢ|vᵢ|).
    pub energy: f64,
    /// The KKT residuals of the written x, λ (and λ_t) for the written QP.
    pub kkt: Kkt,
}

/// What was written.
#[derive(Debug, Clone)]
pub struct ExportReport {
    pub dir: PathBuf,
    pub n: usize,
    pub m: usize,
    pub nnz_c: usize,
    pub kernel_dim: usize,
    /// `tresca` or `coulomb` when the tangential rows were written.
    pub friction: Option<&'static str>,
    /// The files written, meta.json last.
    pub files: Vec<String>,
    pub solution: Option<ExportedSolution>,
    /// Time spent writing (s).
    pub t_write: f64,
}

/// Write the QP of `prep` (and with `spec.solution` signorini's answer)
/// into `spec.dir`. Every file is written atomically, meta.json last; an
/// error names the file.
pub fn export(prep: &Prepared, spec: &ExportSpec) -> Result<ExportReport, RunError> {
    let qp = &prep.model.qp;
    let solved: Option<(String, QpResult)> = if spec.solution {
        let (method, opts) = options(&prep.problem, &spec.solver)?;
        let r = solve(prep, method, &opts)?;
        Some((method.name().to_string(), r))
    } else {
        None
    };
    std::fs::create_dir_all(&spec.dir).map_err(|e| {
        RunError::Output(format!(
            "{}: cannot create directory: {e}",
            spec.dir.display()
        ))
    })?;
    let t_write = Instant::now();
    let friction = qp.friction.as_ref();
    let law = friction.map(|f| match f.bound {
        SlipBound::Tresca(_) => "tresca",
        SlipBound::Coulomb(_) => "coulomb",
    });
    let objective = match law {
        None => "min 1/2 x'Cx - d'x subject to Ax <= g",
        Some("tresca") => {
            "min 1/2 x'Cx - d'x + sum_i s_i |(Tx - t0)_i| subject to Ax <= g"
        }
        Some(_) => {
            "min 1/2 x'Cx - d'x + sum_i s_i |(Tx - t0)_i| subject to Ax <= g, with s_i = mu_i lambda_i (Coulomb: a fixed point)"
        }
    };
    let src = format!(
        "signorini export of {} ({objective})",
        prep.problem.path.display()
    );
    let mut files = vec![];
    let put = |name: &str,
               files: &mut Vec<String>,
               f: &dyn Fn(&Path) -> Result<(), crate::io::IoError>|
     -> Result<(), RunError> {
        f(&spec.dir.join(name))?;
        files.push(name.to_string());
        Ok(())
    };
    put("C.mtx", &mut files, &|p| {
        mtx::write_sparse(
            p,
            &qp.c,
            true,
            &format!("{src}\nC: stiffness, symmetric positive (semi)definite, lower triangle"),
        )
    })?;
    put("A.mtx", &mut files, &|p| {
        mtx::write_sparse(
            p,
            &qp.a,
            false,
            &format!("{src}\nA: one row per contact constraint"),
        )
    })?;
    put("d.mtx", &mut files, &|p| {
        mtx::write_vector(p, &qp.d, &format!("{src}\nd: load vector"))
    })?;
    put("g.mtx", &mut files, &|p| {
        mtx::write_vector(p, &qp.g, &format!("{src}\ng: initial gaps"))
    })?;
    // Kernel of C (rigid motions of floating bodies), one column each.
    let k = qp.kernel.len();
    put("R.mtx", &mut files, &|p| {
        atomic::write_atomic_with(p, |w| {
            writeln!(w, "%%MatrixMarket matrix array real general")?;
            writeln!(
                w,
                "% {src}\n% R: basis of ker C (column-major), one column per rigid mode"
            )?;
            writeln!(w, "{} {}", qp.n(), k)?;
            for v in &qp.kernel {
                for x in v {
                    writeln!(w, "{x:e}")?;
                }
            }
            Ok(())
        })
    })?;
    // Friction (docs/methods.md §9): one tangential row per contact row, in
    // the order of A, the slip v = Tx − t0 and its bound.
    let bound_file = match friction.map(|f| &f.bound) {
        Some(SlipBound::Tresca(_)) => Some("s.mtx"),
        Some(SlipBound::Coulomb(_)) => Some("mu.mtx"),
        None => None,
    };
    if let Some(f) = friction {
        put("T.mtx", &mut files, &|p| {
            mtx::write_sparse(
                p,
                &f.t,
                false,
                &format!("{src}\nT: one tangential row per contact row (the order of A)"),
            )
        })?;
        put("t0.mtx", &mut files, &|p| {
            mtx::write_vector(
                p,
                &f.t0,
                &format!("{src}\nt0: tangential offsets, the slip is v = Tx - t0"),
            )
        })?;
        let (name, values, what) = match &f.bound {
            SlipBound::Tresca(s) => (
                "s.mtx",
                s,
                "s: Tresca slip bound per row (N), |lambda_t| <= s",
            ),
            SlipBound::Coulomb(mu) => (
                "mu.mtx",
                mu,
                "mu: Coulomb coefficient per row, |lambda_t| <= mu lambda",
            ),
        };
        put(name, &mut files, &|p| {
            mtx::write_vector(p, values, &format!("{src}\n{what}"))
        })?;
    }
    let mut solution = None;
    if let Some((method, res)) = &solved {
        put("x.mtx", &mut files, &|p| {
            mtx::write_vector(p, &res.x, &format!("{src}\nx: signorini's solution"))
        })?;
        put("lambda.mtx", &mut files, &|p| {
            mtx::write_vector(
                p,
                &res.lambda,
                &format!("{src}\nlambda: contact multipliers"),
            )
        })?;
        if friction.is_some() {
            put("lambda_t.mtx", &mut files, &|p| {
                mtx::write_vector(
                    p,
                    &res.lambda_t,
                    &format!("{src}\nlambda_t: tangential forces, one per contact row"),
                )
            })?;
        }
        // The residuals of what was written (the values round-trip
        // exactly), not the solver's claim: meta.json cannot contradict the
        // files.
        let lambda_t: &[f64] = if friction.is_some() {
            &res.lambda_t
        } else {
            &[]
        };
        solution = Some(ExportedSolution {
            method: method.clone(),
            converged: res.status.converged(),
            energy: qp.energy_with_friction(&res.x, &res.lambda),
            kkt: kkt::residuals_with_friction(qp, &res.x, &res.lambda, lambda_t),
        });
    }
    let has = solution.is_some();
    let fr = friction.is_some();
    let mut meta = json!({
        "format": "signorini-qp",
        "version": 1,
        "objective": objective,
        "files": {"C": "C.mtx", "A": "A.mtx", "d": "d.mtx", "g": "g.mtx", "R": "R.mtx",
                  "x": has.then_some("x.mtx"), "lambda": has.then_some("lambda.mtx")},
        "problem": prep.problem.path.display().to_string(),
        "mesh": prep.problem.mesh_path().display().to_string(),
        "n": qp.n(),
        "m": qp.m(),
        "nnz_C": qp.c.nnz(),
        "nnz_A": qp.a.nnz(),
        "kernel_dim": k,
        "nodes": prep.mesh.nodes.len(),
        "triangles": prep.model.topo.triangles.len(),
        "energy": solution.as_ref().map(|s| s.energy),
        "method": solution.as_ref().map(|s| s.method.clone()),
        "converged": solution.as_ref().map(|s| s.converged),
        "kkt": solution.as_ref().map(|s| {
            let mut v = json!({
                "primal": s.kkt.primal, "dual": s.kkt.dual,
                "complementarity": s.kkt.complementarity, "stationarity": s.kkt.stationarity});
            if fr {
                v["friction"] = json!(s.kkt.friction);
            }
            v
        }),
        "t_read": prep.t_read,
        "t_assemble": prep.t_assemble,
    });
    // Friction's keys only with friction: a frictionless export is as before.
    if let (Some(f), Some(law), Some(bound)) = (friction, law, bound_file) {
        let files = &mut meta["files"];
        files["T"] = json!("T.mtx");
        files["t0"] = json!("t0.mtx");
        files[bound.trim_end_matches(".mtx")] = json!(bound);
        files["lambda_t"] = json!(has.then_some("lambda_t.mtx"));
        meta["friction"] = json!(law);
        meta["nnz_T"] = json!(f.t.nnz());
    }
    let text = serde_json::to_string_pretty(&meta).unwrap_or_default();
    put("meta.json", &mut files, &|p| {
        atomic::write_atomic_bytes(p, text.as_bytes())
    })?;
    Ok(ExportReport {
        dir: spec.dir.clone(),
        n: qp.n(),
        m: qp.m(),
        nnz_c: qp.c.nnz(),
        kernel_dim: k,
        friction: law,
        files,
        solution,
        t_write: t_write.elapsed().as_secs_f64(),
    })
}
