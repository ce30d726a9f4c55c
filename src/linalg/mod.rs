//! Linear algebra shared by the FEM and QP layers: sparse matrices ([`sparse`]),
//! sparse Cholesky of a (semi)definite stiffness ([`cholesky`]) and its
//! fill-reducing orderings ([`ordering`]), small dense
//! kernels ([`dense`]), the checked basis of ker C ([`kernel`]) and
//! C + Aᵀdiag(w)A on one pattern ([`augmented`]), and a smoothed-aggregation
//! AMG preconditioner with its PCG ([`amg`]). Algorithms live in `qp`; the
//! kernels they share live here, once. Failures are [`LinalgError`]s, which
//! know nothing of the solver settings: the QP layer converts them and adds
//! the advice.

pub mod amg;
pub mod augmented;
pub mod cholesky;
pub mod dense;
pub mod error;
pub mod kernel;
pub mod ordering;
pub mod power;
pub mod rotation;
pub mod sparse;

pub use error::LinalgError;

/// How many parts faer's parallel kernels split their work into, whatever
/// the number of cores (docs/methods.md §8.5). faer's default follows
/// rayon's thread count, and its blocked kernels sum in an order set by
/// that count: the same model gave other bits (1e-13 relative in the
/// stresses) on 1 and 2 threads. A fixed count makes the splits, and so
/// the bits, the same on every machine; rayon runs the parts on however
/// many threads it has. 8 parts cost nothing measurable on 2 cores
/// (BENCHMARKS.md, Notes) and leave room for 8.
pub const PAR_SPLITS: usize = 8;

/// faer's parallelism for every kernel signorini calls ([`PAR_SPLITS`]).
pub fn par() -> faer::Par {
    faer::Par::rayon(PAR_SPLITS)
}

/// Make faer's global parallelism [`par`]: faer's high-level dense
/// routines (LLᵀ, LU, eigen) read the global, not an argument. Called where
/// every solve starts ([`cholesky::Workspace`]); an atomic store.
pub fn fix_parallelism() {
    faer::set_global_parallelism(par());
}
