//! The list of methods and the entry points that solve by method. Adding a
//! method = one type implementing [`Method`] in its family's folder + one
//! variant of [`MethodId`].

use super::driver;
use super::method::{Method, MethodId};
use super::{QpError, QpProblem, QpResult, SolveOptions};
use crate::linalg::cholesky::Workspace;

pub use super::driver::{certified, check_problem, check_warm_start};

/// The method named `name` (a CLI name), if any.
pub fn find(name: &str) -> Option<&'static dyn Method> {
    MethodId::parse(name).map(MethodId::method)
}

/// Every method's name, in the order of `signorini methods` and `compare`.
pub fn names() -> Vec<&'static str> {
    MethodId::ALL.map(MethodId::name).to_vec()
}

/// A method given by identity or by its CLI name (a library user's
/// configuration, a test's table); a name is parsed once, here.
pub trait MethodRef {
    fn to_id(&self) -> Result<MethodId, QpError>;
}

impl MethodRef for MethodId {
    fn to_id(&self) -> Result<MethodId, QpError> {
        Ok(*self)
    }
}

impl MethodRef for str {
    fn to_id(&self) -> Result<MethodId, QpError> {
        MethodId::parse(self).ok_or_else(|| {
            QpError::BadParameter(format!(
                "unknown method \"{self}\"; known: {}",
                MethodId::known()
            ))
        })
    }
}

impl MethodRef for String {
    fn to_id(&self) -> Result<MethodId, QpError> {
        self.as_str().to_id()
    }
}

impl<T: MethodRef + ?Sized> MethodRef for &T {
    fn to_id(&self) -> Result<MethodId, QpError> {
        (**self).to_id()
    }
}

/// Solve `qp` by `method` with a fresh [`Workspace`] of the settings'
/// ordering ([`driver::run`]).
pub fn solve(
    method: impl MethodRef,
    qp: &QpProblem,
    opts: &SolveOptions,
) -> Result<QpResult, QpError> {
    solve_in(method, qp, opts, &opts.settings.workspace())
}

/// Solve `qp` by `method`, reusing factorizations kept in `ws` (load steps:
/// C is the same in every step).
pub fn solve_in(
    method: impl MethodRef,
    qp: &QpProblem,
    opts: &SolveOptions,
    ws: &Workspace,
) -> Result<QpResult, QpError> {
    driver::run(method.to_id()?.method(), qp, opts, ws)
}
