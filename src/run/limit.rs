//! What a contact solve is measured against in the benchmark: one sparse
//! Cholesky factorization of C and one solve C x = d, on the same assembled
//! C the methods see (with the fixing-DOF springs of `linalg::cholesky` when
//! a body floats, so it is defined for semicoercive C; that regularisation
//! costs nothing extra; docs/methods.md §3). `signorini limit` prints the
//! [`LimitReport`] as one JSON line.

use super::prepare::{options, Prepared};
use super::RunError;
use crate::linalg::ordering::Ordering;
use crate::qp::{ByteSize, SolverSection};
use serde::Serialize;
use std::time::Instant;

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
}

/// The measurement (times in seconds, medians over `repeat`).
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
    /// ‖Cx − d‖/‖d‖ of the last solve; None when C has a kernel (the
    /// regularised factor solves another system there).
    pub relative_residual: Option<f64>,
}

impl LimitReport {
    /// The JSON line `signorini limit` prints (keys in alphabetical order).
    pub fn to_json_line(&self) -> String {
        serde_json::to_value(self)
            .map(|v| v.to_string())
            .unwrap_or_default()
    }
}

/// Factor C and solve C x = d `spec.repeat` times on `prep`'s model.
pub fn limit(prep: &Prepared, spec: &LimitSpec) -> Result<LimitReport, RunError> {
    let flags = SolverSection {
        ordering: spec.ordering,
        memory_limit: spec.memory_limit,
        ..Default::default()
    };
    let settings = options(&prep.problem, &flags)?.1.settings;
    let qp = &prep.model.qp;
    let repeat = spec.repeat.max(1);
    let (mut tf, mut ts) = (vec![], vec![]);
    let mut residual = None;
    for _ in 0..repeat {
        let t0 = Instant::now();
        let ch = settings
            .workspace()
            .cholesky(&qp.c, &qp.kernel)
            .map_err(|e| RunError::Solver {
                path: prep.problem.path.clone(),
                msg: e.to_string(),
            })?;
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
    let med = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    let (f, s) = (med(&mut tf), med(&mut ts));
    Ok(LimitReport {
        problem: prep.problem.path.display().to_string(),
        n: qp.n(),
        nnz_c: qp.c.nnz(),
        kernel_dim: qp.kernel.len(),
        t_read: prep.t_read,
        t_assemble: prep.t_assemble,
        t_factor: f,
        t_solve: s,
        t_factor_solve: f + s,
        repeat,
        ordering: settings.ordering.name().to_string(),
        relative_residual: residual.filter(|r| r.is_finite()),
    })
}
