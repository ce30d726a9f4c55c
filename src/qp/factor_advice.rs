//! The linear algebra's errors as the QP layer reports them: the
//! [`LinalgError`] says what failed, this adds what the user can change in
//! `[solver]` (docs/problem-format.md) to avoid it.

use super::QpError;
use crate::linalg::ordering::Ordering;
use crate::linalg::LinalgError;

impl From<LinalgError> for QpError {
    fn from(e: LinalgError) -> QpError {
        match &e {
            LinalgError::FactorTooLarge {
                ordering, by_limit, ..
            } => QpError::Memory(format!("{e}: {}", too_large_hint(*ordering, *by_limit))),
            e if e.is_memory() => QpError::Memory(e.to_string()),
            LinalgError::GraphTooLarge { .. } => {
                QpError::Factor(format!("{e}; use [solver] ordering = \"amd\""))
            }
            LinalgError::Kernel { .. } => QpError::BadParameter(e.to_string()),
            _ => QpError::Factor(e.to_string()),
        }
    }
}

/// What to change when a factor does not fit: the other ordering (about a
/// quarter less fill on 2D meshes, docs/methods.md §3), ssn's iterative
/// path (no factor, §7.2), and when the user's own limit refused it, that
/// limit first.
fn too_large_hint(ordering: Ordering, by_limit: bool) -> String {
    let options = match ordering {
        Ordering::Amd => "[solver] ordering = \"nested-dissection\" (about a quarter less fill on 2D meshes, docs/methods.md §3), method ssn with [solver] ssn_path = \"iterative\" (no factor, docs/methods.md §7.2), a coarser mesh or a larger machine",
        Ordering::NestedDissection => "method ssn with [solver] ssn_path = \"iterative\" (no factor, docs/methods.md §7.2), a coarser mesh or a larger machine",
    };
    if by_limit {
        format!("raise [solver] memory_limit, or {options}")
    } else {
        format!("try {options}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn too_large(ordering: Ordering, by_limit: bool) -> String {
        let e = LinalgError::FactorTooLarge {
            bytes: 3 << 30,
            available: 1 << 30,
            nnz: 12345,
            ordering,
            by_limit,
        };
        match QpError::from(e) {
            QpError::Memory(m) => m,
            other => panic!("{other:?}"),
        }
    }

    /// The messages users saw before linalg lost its knowledge of
    /// `[solver]`, word for word.
    #[test]
    fn a_factor_too_large_gets_the_solver_advice() {
        assert_eq!(
            too_large(Ordering::Amd, false),
            "the Cholesky factor (amd ordering, nnz(L) = 12345) needs 3.0 GiB, more than the memory and swap available (1.0 GiB): try [solver] ordering = \"nested-dissection\" (about a quarter less fill on 2D meshes, docs/methods.md §3), method ssn with [solver] ssn_path = \"iterative\" (no factor, docs/methods.md §7.2), a coarser mesh or a larger machine"
        );
        let e = too_large(Ordering::NestedDissection, true);
        assert!(
            e.contains("more than the limit set for the factors (1.0 GiB): raise [solver] memory_limit, or method ssn with [solver] ssn_path = \"iterative\"")
                && e.contains("coarser mesh")
                && !e.contains("ordering ="),
            "{e}"
        );
    }

    #[test]
    fn other_failures_keep_their_kind() {
        let oom = LinalgError::OutOfMemory {
            stage: "numeric factorization",
        };
        assert!(
            matches!(QpError::from(oom), QpError::Memory(m) if m == "out of memory for the numeric factorization")
        );
        let spd = LinalgError::NotPositiveDefinite { detail: "x".into() };
        assert!(
            matches!(QpError::from(spd).to_string(), m if m.starts_with("factorization failed: C is not positive definite (x)"))
        );
        let big = QpError::from(LinalgError::GraphTooLarge { entries: 7 }).to_string();
        assert!(big.ends_with("use [solver] ordering = \"amd\""), "{big}");
        let k = LinalgError::Kernel {
            index: 0,
            defect: crate::linalg::error::KernelDefect::ZeroOrNotFinite,
        };
        assert!(
            matches!(QpError::from(k), QpError::BadParameter(m) if m == "kernel vector 0 is zero or not finite")
        );
    }
}
