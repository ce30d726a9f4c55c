//! The list of methods. Adding a method = one type implementing
//! [`Method`] in its family's folder + one line here.

use super::driver::{self, Method};
use super::{Kkt, QpError, QpProblem, QpResult, SolveOptions};
use crate::linalg::cholesky::Workspace;

pub use super::driver::{check_problem, check_warm_start};

/// Every method, in the order of `signorini methods` and `compare`.
pub const METHODS: &[&dyn Method] = &[
    &super::primal::cgc::CgcMethod,
    &super::primal::preelim::PreelimMethod,
    &super::primal::penalty::PenaltyMethod,
    &super::dual::uzawa::UzawaMethod,
    &super::dual::polyak::DualMethod,
    &super::active_set::AsmMethod,
    &super::active_set::cgh::AsmCghMethod,
    &super::dual::mprgp::MprgpMethod,
    &super::ssn::SsnMethod,
];

pub fn find(name: &str) -> Option<&'static dyn Method> {
    METHODS.iter().copied().find(|m| m.name() == name)
}

pub fn names() -> Vec<&'static str> {
    METHODS.iter().map(|m| m.name()).collect()
}

/// Whether a result of method `name` with residuals `kkt` is certified at
/// `target`. Penalty solves its own penalised problem: unless `strict`, it is
/// certified by the stationarity of that problem (its λ = (Ax − g)⁺/ε_p), and
/// its O(ε_p) violation of Ax ≤ g is reported, not certified.
pub fn certified(name: &str, kkt: &Kkt, target: f64, strict: bool) -> bool {
    if name == "penalty" && !strict {
        let own = Kkt {
            primal: 0.0,
            dual: kkt.dual,
            complementarity: 0.0,
            ..*kkt
        };
        // NaN anywhere still fails.
        return own.within(target) && !kkt.max().is_nan() && kkt.max().is_finite();
    }
    kkt.within(target)
}

/// Solve `qp` by method `name` with a fresh [`Workspace`] of the settings'
/// ordering ([`driver::run`]).
pub fn solve(name: &str, qp: &QpProblem, opts: &SolveOptions) -> Result<QpResult, QpError> {
    solve_in(name, qp, opts, &opts.settings.workspace())
}

/// Solve `qp` by method `name`, reusing factorizations kept in `ws`
/// (load steps: C is the same in every step).
pub fn solve_in(
    name: &str,
    qp: &QpProblem,
    opts: &SolveOptions,
    ws: &Workspace,
) -> Result<QpResult, QpError> {
    let m = find(name).ok_or_else(|| {
        QpError::BadParameter(format!(
            "unknown method \"{name}\"; known: {}",
            names().join(", ")
        ))
    })?;
    driver::run(m, qp, opts, ws)
}
