//! The errors of the linear algebra layer. They describe what failed in
//! linear-algebra terms and carry the sizes as data; what a user can change
//! in the product's settings to avoid them is said where they are
//! converted (the QP layer), not here: linalg knows no settings file.

use crate::linalg::ordering::Ordering;

/// A failed factorization, ordering or kernel check.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinalgError {
    /// The numeric factorization met a pivot that is not positive.
    #[error(
        "C is not positive definite ({detail}); a body may be free to move without the kernel being known"
    )]
    NotPositiveDefinite { detail: String },
    /// faer's symbolic analysis refused the pattern.
    #[error("symbolic analysis: {0}")]
    Symbolic(String),
    /// A bordered factor's border names a DOF twice or one out of range.
    #[error("bordered factor: border DOF {dof} out of range or repeated")]
    BadBorder { dof: usize },
    /// The fill-reducing ordering failed (AMD or METIS).
    #[error("{0}")]
    Ordering(String),
    /// The pattern's graph is too large for METIS's 32-bit indices.
    #[error(
        "nested dissection: the graph has {entries} adjacency entries, more than METIS's 32-bit indices hold"
    )]
    GraphTooLarge { entries: usize },
    /// An allocation of the factorization failed (`stage`: which one).
    #[error("out of memory for the {stage}")]
    OutOfMemory { stage: &'static str },
    /// A numeric factor of `bytes` (values and scratch; `nnz` entries of L)
    /// exceeds the `available` bytes, which are the caller's limit when
    /// `by_limit`, else the machine's free memory and swap.
    #[error(
        "the Cholesky factor ({} ordering, nnz(L) = {nnz}) needs {}, more than {} ({})",
        ordering.name(),
        human_size(*bytes),
        if *by_limit { "the limit set for the factors" } else { "the memory and swap available" },
        human_size(*available)
    )]
    FactorTooLarge {
        bytes: u64,
        available: u64,
        nnz: usize,
        ordering: Ordering,
        by_limit: bool,
    },
    /// A vector handed over as a basis vector of ker C is not one.
    #[error("kernel vector {index} {defect}")]
    Kernel { index: usize, defect: KernelDefect },
}

/// Why a vector is not a basis vector of ker C.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KernelDefect {
    #[error("has length {len}, C has {ncols} columns")]
    Length { len: usize, ncols: usize },
    #[error("is zero or not finite")]
    ZeroOrNotFinite,
    /// `ratio` = ‖Cz‖/(max diag C·‖z‖), above the tolerance.
    #[error("is not in ker C (‖Cz‖/(max diag C·‖z‖) = {ratio:.3e})")]
    NotInKernel { ratio: f64 },
}

impl LinalgError {
    /// The failure is one of resources, not of the matrix: a method must
    /// not read it as "this matrix cannot be factored" and take another
    /// path, or the bits of an answer would depend on the machine's free
    /// memory. It ends the solve with the message.
    pub fn is_memory(&self) -> bool {
        matches!(
            self,
            LinalgError::OutOfMemory { .. } | LinalgError::FactorTooLarge { .. }
        )
    }
}

/// `b` bytes in the largest binary unit that keeps the number ≥ 1.
pub fn human_size(b: u64) -> String {
    let (v, unit) = match b {
        b if b >= 1 << 30 => (b as f64 / (1u64 << 30) as f64, "GiB"),
        b if b >= 1 << 20 => (b as f64 / (1u64 << 20) as f64, "MiB"),
        b if b >= 1 << 10 => (b as f64 / 1024.0, "KiB"),
        b => return format!("{b} bytes"),
    };
    format!("{v:.1} {unit}")
}
