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
},
MethodInfo {
    name: "preelim",
    summary: "pre-elimination: dense Schur complement onto the contact DOFs, then CGC (§4.3)",
    preconditioned: false,
    solve: super::preelim::solve,
},
MethodInfo {
    name: "penalty",
    summary: "exterior penalty with Gauss–Seidel/SOR relaxation (§4.4)",
    preconditioned: false,
    solve: super::penalty::solve,
},
MethodInfo {
    name: "uzawa",
    summary: "Uzawa's method with Cholesky inner solves (§4.5)",
    preconditioned: false,
    solve: super::uzawa::solve,
},
MethodInfo {
    name: "dual",
    summary: "CGC on the dual functional, H applied through a Cholesky factor (§4.6)",
    preconditioned: false,
    solve: super::dual::solve,
},
MethodInfo {
    name: "asm",
    summary: "active set method, KKT systems by Schur-complement elimination (ASM-E, §4.7)",
    preconditioned: false,
    solve: super::asm::solve,
},
MethodInfo {
    name: "asm-cgh",
    summary: "active set method, KKT systems by CG with hyperbolic pairs (§4.8)",
    preconditioned: false,
    solve: super::asm_cgh::solve,
},
MethodInfo {
    name: "mprgp",
    summary: "MPRGP on the dual, H through one Cholesky factor; SMALBE for floating bodies (§7)",
    preconditioned: false,
    solve: super::mprgp::solve,
},
MethodInfo {
    name: "ssn",
    summary: "semismooth Newton / primal–dual active set, Schur complement with one Cholesky factor (§7)",
    preconditioned: false,
    solve: super::ssn::solve,
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
