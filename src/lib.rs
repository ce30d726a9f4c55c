//! signorini: frictionless multibody contact of elastic bodies in 2D by P1
//! finite elements, with a choice of quadratic-programming methods.
//!
//! Two layers with one seam: `mesh`/`model`/`fem`/`post` turn a Gmsh mesh and
//! a TOML problem into a [`qp::QpProblem`] (plus maps back to the nodes);
//! `qp` solves it without knowing about meshes.

pub mod cli;
pub mod fem;
pub mod io;
pub mod mesh;
pub mod model;
pub mod pipeline;
pub mod post;
pub mod qp;
