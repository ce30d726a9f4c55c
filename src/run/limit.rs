//! What a contact solve is measured against in the benchmark (the
//! yardstick, docs/methods.md §3 and §7.2), on the same assembled C the
//! methods see, for plane and solid models alike ([`Assembled`]):
//!
//! * `cholesky` (the default): one sparse Cholesky factorization of C and
//!   one solve C x = d (with the fixing-DOF springs of `linalg::cholesky`
//!   when a body floats, so it is defined for semicoercive C; that
//!   regularisation costs nothing extra);
//! * `iterative`: one AMG-PCG solve of the iterative ssn path's operator
//!   ([`crate::qp::ssn::yardstick`]: C, or C + ρAᵀA when C has a kernel)
//!   with its near-null space, multigrid settings and the settings' tol.
//!
//! `signorini limit` prints the [`LimitReport`] as one JSON line.

use super::prepare::{options, Loaded, Prepared};
use super::solid::SolidPrepared;
use super::summary::Cells;
use super::RunError;
use crate::linalg::ordering::Ordering;
use crate::problem::Problem;
use crate::qp::{ByteSize, QpProblem, SolverSection};
use serde::Serialize;
use std::time::Instant;

/// A prepared model, plane or solid, as `limit` (the yardstick) reads it:
/// the problem, the QP, the times, the mesh's size.
pub trait Assembled {
    fn problem(&self) -> &Problem;
    fn qp(&self) -> &QpProblem;
    /// Seconds to read the files and to assemble the model.
    fn times(&self) -> (f64, f64);
    /// The mesh's nodes and cells (triangles or tetrahedra).
    fn mesh_size(&self) -> (usize, Cells);
}

impl Assembled for Prepared {
    fn problem(&self) -> &Problem {
        &self.problem
    }
    fn qp(&self) -> &QpProblem {
        &self.model.qp
    }
    fn times(&self) -> (f64, f64) {
        (self.t_read, self.t_assemble)
    }
    fn mesh_size(&self) -> (usize, Cells) {
        (
            self.mesh.nodes.len(),
            Cells::Triangles(self.model.topo.triangles.len()),
        )
    }
}

impl Assembled for SolidPrepared {
    fn problem(&self) -> &Problem {
        &self.problem
    }
    fn qp(&self) -> &QpProblem {
        &self.model.qp
    }
    fn times(&self) -> (f64, f64) {
        (self.t_read, self.t_assemble)
    }
    fn mesh_size(&self) -> (usize, Cells) {
        (
            self.mesh.nodes.len(),
            Cells::Tetrahedra(self.model.tets.len()),
        )
    }
}

impl Loaded {
    /// The loaded model as the yardstick reads it.
    pub fn assembled(&self) -> &dyn Assembled {
        match self {
            Loaded::Plane(p) => p.as_ref(),
            Loaded::Solid(s) => s.as_ref(),
        }
    }

    /// The loaded model as `compare` and `export` ask it.
    pub fn comparable(&self) -> &dyn super::compare::Comparable {
        match self {
            Loaded::Plane(p) => p.as_ref(),
            Loaded::Solid(s) => s.as_ref(),
        }
    }
}

/// Which solve is the yardstick.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum LimitPath {
    /// One sparse Cholesky factorization and solve.
    #[default]
    Cholesky,
    /// One AMG-PCG solve as on ssn's iterative path.
    Iterative,
}

impl std::str::FromStr for LimitPath {
    type Err = String;
    fn from_str(s: &str) -> Result<LimitPath, String> {
        match s {
            "cholesky" => Ok(LimitPath::Cholesky),
            "iterative" => Ok(LimitPath::Iterative),
            _ => Err(format!(
                "unknown path \"{s}\"; expected \"cholesky\" or \"iterative\""
            )),
        }
    }
}

/// How to measure.
#[derive(Debug, Clone, Default)]
pub struct LimitSpec {
    /// Factor and solve this many times (0 counts as 1); the report holds
    /// the medians.
    pub repeat: usize,
    /// Overrides `[solver] ordering`.
    pub ordering: Option<Ordering>,
    /// The largest factor allowed; overrides `[solver] memory_limit`.
    pub memory_limit: Option<ByteSize>,
    pub path: LimitPath,
}

/// The measurement (times in seconds, medians over `repeat`). On the
/// iterative path `t_factor` is the ordering and the multigrid setup,
/// `t_solve` the PCG.
#[derive(Debug, Clone, Serialize)]
pub struct LimitReport {
    pub problem: String,
    pub n: usize,
    #[serde(rename = "nnz_C")]
    pub nnz_c: usize,
    pub kernel_dim: usize,
    pub t_read: f64,
    pub t_assemble: f64,
    pub t_factor: f64,
    pub t_solve: f64,
    pub t_factor_solve: f64,
    pub repeat: usize,
    pub ordering: String,
    /// ‖Cx − d‖/‖d‖ of the last solve (on the iterative path ‖Kx − d‖/‖d‖);
    /// None when C has a kernel and the factor is regularised.
    pub relative_residual: Option<f64>,
    /// The iterative path only: CG steps, unknowns per multigrid level,
    /// operator complexity and contact rows added as springs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub levels: Option<Vec<usize>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub operator_complexity: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub springs: Option<usize>,
}

impl LimitReport {
    /// The JSON line `signorini limit` prints (keys in alphabetical order).
    pub fn to_json_line(&self) -> String {
        serde_json::to_value(self)
            .map(|v| v.to_string())
            .unwrap_or_default()
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Measure the yardstick `spec.path` `spec.repeat` times on `prep`'s model.
pub fn limit(prep: &dyn Assembled, spec: &LimitSpec) -> Result<LimitReport, RunError> {
    let flags = SolverSection {
        ordering: spec.ordering,
        memory_limit: spec.memory_limit,
        ..Default::default()
    };
    let problem = prep.problem();
    let settings = options(problem, &flags)?.1.settings;
    let qp = prep.qp();
    let fail = |msg: String| RunError::Solver {
        path: problem.path.clone(),
        msg,
    };
    let repeat = spec.repeat.max(1);
    let (mut tf, mut ts) = (vec![], vec![]);
    let mut residual = None;
    let mut iterative = None;
    for _ in 0..repeat {
        if spec.path == LimitPath::Iterative {
            let y = crate::qp::ssn::yardstick(qp, settings.tol).map_err(|e| fail(e.to_string()))?;
            tf.push(y.t_order + y.t_setup);
            ts.push(y.t_solve);
            residual = Some(y.rel_residual);
            iterative = Some(y);
            continue;
        }
        let t0 = Instant::now();
        let ch = settings
            .workspace()
            .cholesky(&qp.c, &qp.kernel)
            .map_err(|e| fail(e.to_string()))?;
        tf.push(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        let x = ch.solve(&qp.d);
        ts.push(t1.elapsed().as_secs_f64());
        if qp.kernel.is_empty() {
            let cx = qp.c.mul(&x);
            let r: Vec<f64> = cx.iter().zip(&qp.d).map(|(a, b)| a - b).collect();
            residual = Some(
                crate::linalg::sparse::norm(&r)
                    / crate::linalg::sparse::norm(&qp.d).max(f64::MIN_POSITIVE),
            );
        }
    }
    let (f, s) = (median(&mut tf), median(&mut ts));
    let (t_read, t_assemble) = prep.times();
    Ok(LimitReport {
        problem: problem.path.display().to_string(),
        n: qp.n(),
        nnz_c: qp.c.nnz(),
        kernel_dim: qp.kernel.len(),
        t_read,
        t_assemble,
        t_factor: f,
        t_solve: s,
        t_factor_solve: f + s,
        repeat,
        ordering: match spec.path {
            LimitPath::Cholesky => settings.ordering.name().to_string(),
            LimitPath::Iterative => "block-rcm".to_string(),
        },
        relative_residual: residual.filter(|r| r.is_finite()),
        iterations: iterative.as_ref().map(|y| y.iterations),
        levels: iterative.as_ref().map(|y| y.levels.clone()),
        operator_complexity: iterative.as_ref().map(|y| y.operator_complexity),
        springs: iterative.as_ref().map(|y| y.springs),
    })
}
