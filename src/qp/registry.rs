//! The list of methods. Adding a method = one file in `qp/` + one line here.

use super::{kkt, QpError, QpProblem, QpResult, SolveOptions};

pub type SolveFn = fn(&QpProblem, &SolveOptions) -> Result<QpResult, QpError>;

pub struct MethodInfo {
    /// CLI name (part of the contract).
    pub name: &'static str,
    pub summary: &'static str,
    /// Whether `--preconditioner` applies.
    pub preconditioned: bool,
    pub solve: SolveFn,
}

pub const METHODS: &[MethodInfo] = &[MethodInfo {
    name: "cgc",
    summary: "conjugate gradients with constraints (§4.1), preconditioned (§4.2)",
    preconditioned: true,
    solve: super::cgc::solve,
}];

pub fn find(name: &str) -> Option<&'static MethodInfo> {
    METHODS.iter().find(|m| m.name == name)
}

pub fn names() -> Vec<&'static str> {
    METHODS.iter().map(|m| m.name).collect()
}

/// Run method `name` and attach the KKT certificate.
pub fn solve(name: &str, qp: &QpProblem, opts: &SolveOptions) -> Result<QpResult, QpError> {
    let m = find(name).ok_or_else(|| {
        QpError::BadParameter(format!(
            "unknown method \"{name}\"; known: {}",
            names().join(", ")
        ))
    })?;
    let mut r = (m.solve)(qp, opts)?;
    r.kkt = kkt::residuals(qp, &r.x, &r.lambda);
    Ok(r)
}
