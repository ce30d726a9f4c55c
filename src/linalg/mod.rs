//! Linear algebra shared by the FEM and QP layers: sparse matrices ([`sparse`]),
//! sparse Cholesky of a (semi)definite stiffness ([`cholesky`]) and small dense
//! kernels ([`dense`]). Algorithms live in `qp`; the kernels they share live
//! here, once.

pub mod cholesky;
pub mod dense;
pub mod power;
pub mod sparse;
