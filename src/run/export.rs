//! The assembled QP min ½xᵀCx − xᵀd, Ax ≤ g (with friction: the tangential
//! rows T, their offsets t0 and the slip bounds, docs/methods.md §9) as
//! Matrix Market files plus `meta.json`, so other solvers (Clarabel, OSQP,
//! MATLAB's quadprog, …) can be run on exactly the problem signorini solves;
//! optionally with signorini's solution. The format is documented in the
//! README ("Exported QP"). `signorini export --qp DIR` is this API plus flag
//! parsing and printing.

use super::compare::Comparable;
use super::prepare::options;
use super::steps::Verdict;
use super::summary::Cells;
use super::RunError;
use crate::io::{atomic, mtx};
use crate::qp::{kkt, Frame, Friction, Kkt, QpProblem, QpResult, SlipBound, SolverSection};
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
    /// The run's verdict on the solve (as `solve` judges a step, without
    /// `--strict`: [`Verdict::Penalised`] counts as certified there).
    pub verdict: Verdict,
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

/// The files of one export: the directory, the header line every file
/// carries, and the names written so far.
struct Files<'a> {
    dir: &'a Path,
    src: String,
    names: Vec<String>,
}

impl Files<'_> {
    /// Write `name` with `f` (atomically: the writers of `io` stage and
    /// rename), and remember it.
    fn put(
        &mut self,
        name: &str,
        f: impl FnOnce(&Path) -> Result<(), crate::io::IoError>,
    ) -> Result<(), RunError> {
        f(&self.dir.join(name))?;
        self.names.push(name.to_string());
        Ok(())
    }

    /// A vector file with its header and a one-line description.
    fn vector(&mut self, name: &str, v: &[f64], what: &str) -> Result<(), RunError> {
        let header = format!("{}\n{what}", self.src);
        self.put(name, |p| mtx::write_vector(p, v, &header))
    }

    /// A sparse matrix file (`symmetric`: the lower triangle).
    fn sparse(
        &mut self,
        name: &str,
        a: &crate::qp::Csr,
        symmetric: bool,
        what: &str,
    ) -> Result<(), RunError> {
        let header = format!("{}\n{what}", self.src);
        self.put(name, |p| mtx::write_sparse(p, a, symmetric, &header))
    }
}

/// The objective line of `meta.json` for the friction law (None: none)
/// and its frame: one tangential row per contact row (plane and
/// axisymmetric models, |·| of the slip), or two (solid models, the
/// Euclidean norm of the pair, docs/methods.md §12).
fn objective(law: Option<(&str, Frame)>) -> String {
    let Some((law, frame)) = law else {
        return "min 1/2 x'Cx - d'x subject to Ax <= g".to_string();
    };
    let (term, rows) = match frame {
        Frame::Line => ("|(Tx - t0)_i|", ""),
        Frame::Plane => (
            "||((Tx - t0)_2i, (Tx - t0)_2i+1)||_2",
            " (rows 2i, 2i+1 of T: the two tangents of contact row i, from 0)",
        ),
    };
    let coulomb = if law == "tresca" {
        ""
    } else {
        ", with s_i = mu_i lambda_i (Coulomb: a fixed point)"
    };
    format!("min 1/2 x'Cx - d'x + sum_i s_i {term} subject to Ax <= g{rows}{coulomb}")
}

/// C, A, d, g and the kernel basis R (one column per rigid mode).
fn write_qp(files: &mut Files, qp: &crate::qp::QpProblem) -> Result<(), RunError> {
    files.sparse(
        "C.mtx",
        &qp.c,
        true,
        "C: stiffness, symmetric positive (semi)definite, lower triangle",
    )?;
    files.sparse("A.mtx", &qp.a, false, "A: one row per contact constraint")?;
    files.vector("d.mtx", &qp.d, "d: load vector")?;
    files.vector("g.mtx", &qp.g, "g: initial gaps")?;
    let src = files.src.clone();
    files.put("R.mtx", |p| {
        atomic::write_atomic_with(p, |w| {
            writeln!(w, "%%MatrixMarket matrix array real general")?;
            writeln!(
                w,
                "% {src}\n% R: basis of ker C (column-major), one column per rigid mode"
            )?;
            writeln!(w, "{} {}", qp.n(), qp.kernel.len())?;
            for v in &qp.kernel {
                for x in v {
                    writeln!(w, "{x:e}")?;
                }
            }
            Ok(())
        })
    })
}

/// Friction (docs/methods.md §9, §12): one tangential row per contact row
/// (two in 3D), in the order of A, the offsets t0 of the slip v = Tx − t0,
/// and the bound per contact row (s for Tresca, μ for Coulomb); returns
/// the bound's file name.
fn write_friction(files: &mut Files, f: &Friction) -> Result<&'static str, RunError> {
    let (t_what, bound_norm) = match f.frame {
        Frame::Line => (
            "T: one tangential row per contact row (the order of A)",
            "|lambda_t|",
        ),
        Frame::Plane => (
            "T: two tangential rows per contact row, 2i and 2i+1 for row i of A (from 0)",
            "||(lambda_t_2i, lambda_t_2i+1)||_2",
        ),
    };
    files.sparse("T.mtx", &f.t, false, t_what)?;
    files.vector(
        "t0.mtx",
        &f.t0,
        "t0: tangential offsets, the slip is v = Tx - t0",
    )?;
    let (name, values, what) = match &f.bound {
        SlipBound::Tresca(s) => (
            "s.mtx",
            s,
            format!("s: Tresca slip bound per contact row (N), {bound_norm} <= s"),
        ),
        SlipBound::Coulomb(mu) => (
            "mu.mtx",
            mu,
            format!("mu: Coulomb coefficient per contact row, {bound_norm} <= mu lambda"),
        ),
    };
    files.vector(name, values, &what)?;
    Ok(name)
}

/// x, λ (and λ_t) and the residuals of what was written (the values
/// round-trip exactly), not the solver's claim: meta.json cannot
/// contradict the files.
fn write_solution(
    files: &mut Files,
    qp: &crate::qp::QpProblem,
    method: &str,
    res: &QpResult,
    verdict: Verdict,
) -> Result<ExportedSolution, RunError> {
    files.vector("x.mtx", &res.x, "x: signorini's solution")?;
    files.vector("lambda.mtx", &res.lambda, "lambda: contact multipliers")?;
    let lambda_t: &[f64] = if qp.friction.is_some() {
        files.vector(
            "lambda_t.mtx",
            &res.lambda_t,
            "lambda_t: tangential forces, one per row of T",
        )?;
        &res.lambda_t
    } else {
        &[]
    };
    Ok(ExportedSolution {
        method: method.to_string(),
        converged: res.status.converged(),
        verdict,
        energy: qp.energy_with_friction(&res.x, &res.lambda),
        kkt: kkt::residuals_with_friction(qp, &res.x, &res.lambda, lambda_t),
    })
}

/// Write the QP of `prep` (and with `spec.solution` signorini's answer)
/// into `spec.dir`. Every file is written atomically, meta.json last; an
/// error names the file.
pub fn export(prep: &dyn Comparable, spec: &ExportSpec) -> Result<ExportReport, RunError> {
    // Before any solve: a path that is a file cannot take the files.
    if spec.dir.exists() && !spec.dir.is_dir() {
        return Err(RunError::Output(format!(
            "{}: exists and is not a directory: --qp names the directory of the files",
            spec.dir.display()
        )));
    }
    // The problem as written: with `[[steps]]`, its loads at factor 1 and
    // no step applied (t0 = 0), plane and solid alike.
    let written = prep.written()?;
    let qp = written.qp();
    let solved: Option<(String, QpResult, Verdict)> = if spec.solution {
        let (method, opts) = options(prep.problem(), &spec.solver)?;
        let r = written.solve(method, &opts)?;
        let verdict = Verdict::of(method, &r, opts.settings.kkt_target, false);
        Some((method.name().to_string(), r, verdict))
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
    let framed = friction.map(|f| {
        let law = match f.bound {
            SlipBound::Tresca(_) => "tresca",
            SlipBound::Coulomb(_) => "coulomb",
        };
        (law, f.frame)
    });
    let law = framed.map(|(l, _)| l);
    let mut files = Files {
        dir: &spec.dir,
        src: format!(
            "signorini export of {} ({})",
            prep.problem().path.display(),
            objective(framed)
        ),
        names: vec![],
    };
    write_qp(&mut files, qp)?;
    let bound_file = friction
        .map(|f| write_friction(&mut files, f))
        .transpose()?;
    let solution = solved
        .as_ref()
        .map(|(method, res, verdict)| write_solution(&mut files, qp, method, res, *verdict))
        .transpose()?;
    let mut meta = meta_json(prep, qp, framed, solution.as_ref());
    // Friction's keys only with friction: a frictionless export is as before.
    if let (Some(f), Some(law), Some(bound)) = (friction, law, bound_file) {
        let has = solution.is_some();
        let names = &mut meta["files"];
        names["T"] = json!("T.mtx");
        names["t0"] = json!("t0.mtx");
        names[bound.trim_end_matches(".mtx")] = json!(bound);
        names["lambda_t"] = json!(has.then_some("lambda_t.mtx"));
        meta["friction"] = json!(law);
        meta["nnz_T"] = json!(f.t.nnz());
        meta["tangential_rows"] = json!(f.frame.rows());
    }
    let text = serde_json::to_string_pretty(&meta).unwrap_or_default();
    files.put("meta.json", |p| {
        atomic::write_atomic_bytes(p, text.as_bytes())
    })?;
    Ok(ExportReport {
        dir: spec.dir.clone(),
        n: qp.n(),
        m: qp.m(),
        nnz_c: qp.c.nnz(),
        kernel_dim: qp.kernel.len(),
        friction: law,
        files: files.names,
        solution,
        t_write: t_write.elapsed().as_secs_f64(),
    })
}

/// `meta.json` (docs/guide.md, "Exported QP"): sizes, sources and, with a
/// solution, its energy, method and every KKT residual (the one [`Kkt`]
/// type, as in the run's JSON).
fn meta_json(
    prep: &dyn Comparable,
    qp: &QpProblem,
    law: Option<(&str, Frame)>,
    solution: Option<&ExportedSolution>,
) -> serde_json::Value {
    let problem = prep.problem();
    let has = solution.is_some();
    let (nodes, cells) = prep.mesh_size();
    let (t_read, t_assemble) = prep.times();
    let mut meta = json!({
        "format": "signorini-qp",
        "version": 1,
        "objective": objective(law),
        "files": {"C": "C.mtx", "A": "A.mtx", "d": "d.mtx", "g": "g.mtx", "R": "R.mtx",
                  "x": has.then_some("x.mtx"), "lambda": has.then_some("lambda.mtx")},
        "problem": problem.path.display().to_string(),
        "mesh": problem.mesh_path().display().to_string(),
        "dim": match cells {
            Cells::Triangles(_) => 2,
            Cells::Tetrahedra(_) => 3,
        },
        "n": qp.n(),
        "m": qp.m(),
        "nnz_C": qp.c.nnz(),
        "nnz_A": qp.a.nnz(),
        "kernel_dim": qp.kernel.len(),
        "nodes": nodes,
        "energy": solution.map(|s| s.energy),
        "method": solution.map(|s| s.method.clone()),
        "converged": solution.map(|s| s.converged),
        "certified": solution.map(|s| s.verdict.certified()),
        "kkt": solution.map(|s| s.kkt),
        "t_read": t_read,
        "t_assemble": t_assemble,
    });
    // "triangles": n in 2D, "tetrahedra": n in 3D.
    meta[cells.key()] = json!(cells.count());
    meta
}
