//! Primal methods: they iterate on the displacements x directly
//! (docs/methods.md §4.1–§4.4).

pub mod cgc;
pub mod penalty;
pub mod preelim;
