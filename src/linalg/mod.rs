//! Linear algebra shared by the FEM and QP layers: sparse matrices ([`sparse`]),
//! sparse Cholesky of a (semi)definite stiffness ([`cholesky`]) and its
//! fill-reducing orderings ([`ordering`]), small dense
//! kernels ([`dense`]), the checked basis of ker C ([`kernel`]) and
//! C + Aᵀdiag(w)A on one pattern ([`augmented`]), and a smoothed-aggregation
//! AMG preconditioner with its PCG ([`amg`]). Algorithms live in `qp`; the
//! kernels they share live here, once.

pub mod amg;
pub mod augmented;
pub mod cholesky;
pub mod dense;
pub mod kernel;
pub mod ordering;
pub mod power;
pub mod rotation;
pub mod sparse;
