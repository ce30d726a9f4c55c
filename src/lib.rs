//! signorini: contact of several elastic bodies in 2D (Signorini conditions,
//! optionally with Tresca or Coulomb friction) by P1 finite elements, with a
//! choice of quadratic-programming methods (the default, `auto`, runs `ssn`).
//!
//! Two layers with one seam: `mesh`/`problem`/`fem`/`post` turn a Gmsh mesh and
//! a TOML problem into a [`qp::QpProblem`] (plus maps back to the nodes);
//! `qp` solves it without knowing about meshes, every method through one
//! driver that certifies the answer ([`qp::registry::solve`]). [`run`] is the
//! whole pipeline as a library call (load steps, restart, observers, the
//! output transaction); the `signorini` binary is [`cli`] on top of it.
//! The mathematics: docs/methods.md; the file formats: docs/problem-format.md.

// Numerical code: `!(x > 0.0)` is how a NaN takes the refusing branch (the
// lint's `partial_cmp` rewrite hides that), and index loops over several
// arrays of one length read as the formulas they implement.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod cli;
pub mod fem;
pub mod io;
pub mod linalg;
pub mod mesh;
pub mod output;
pub mod post;
pub mod problem;
pub mod qp;
pub mod run;

/// The shipped examples (`meshes/*.toml`, sorted) loaded with their meshes:
/// the inputs of the unit tests that run over every model.
#[cfg(test)]
pub(crate) fn shipped_examples() -> Vec<(std::path::PathBuf, problem::Problem, mesh::Mesh)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let mut tomls: Vec<_> = std::fs::read_dir(&dir)
        .expect("meshes/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    tomls.sort();
    assert!(tomls.len() >= 5, "{tomls:?}");
    tomls
        .into_iter()
        .map(|p| {
            let problem = problem::Problem::load(&p).unwrap_or_else(|e| panic!("{e}"));
            let mesh = mesh::read_msh(&problem.mesh_path()).unwrap_or_else(|e| panic!("{e}"));
            (p, problem, mesh)
        })
        .collect()
}
