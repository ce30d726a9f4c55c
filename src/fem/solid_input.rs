//! The problem file of a 3D model as [`fem::solid`](super::solid)'s typed
//! input: the one place where the TOML entries of a 3D problem become a
//! [`SolidInput`], and where what a 3D model does not take yet is refused
//! (docs/problem-format.md §12). Kept apart from `solid.rs` so that the
//! library's solid model and the problem file's reading of it change
//! independently. The vector keys have been held against the mesh's
//! dimension before (`Problem::check_dimension`).

use super::element::Vector3;
use super::solid::{SolidInput, SolidModel, SolidTraction};
use super::FemError;
use crate::mesh::Mesh;
use crate::problem::{shorten, Force, ProblemFile, TractionLoad};
use std::path::Path;

/// The [`SolidInput`] of a 3D problem file `f` (a load step's:
/// `ProblemFile::at_step`).
pub fn solid_input(f: &ProblemFile) -> SolidInput {
    SolidInput {
        materials: f.materials.clone(),
        gravity: f.model.gravity.map_or([0.0; 3], |g| g.xyz()),
        dirichlet: f
            .dirichlet
            .iter()
            .map(|d| (d.on.clone(), d.value))
            .collect(),
        slip: f.slip.iter().map(|s| s.on.clone()).collect(),
        contact: f.contact.clone(),
        traction: f
            .traction
            .iter()
            .map(|t| {
                let load = match t.load {
                    TractionLoad::Normal(pn) => SolidTraction::Normal(pn),
                    TractionLoad::Vector(p) => SolidTraction::Vector(p.xyz()),
                };
                (t.on.clone(), load)
            })
            .collect(),
    }
}

/// Adds the `[[force]]` entries `forces` of the problem file `path` (a force in N at the nodes of
/// a Physical Point) to a built model: d += Tᵀ f at each node, and the
/// nodal loads (the QP's d is linear in the loads, docs/methods.md §2.3).
pub fn add_point_forces(
    model: &mut SolidModel,
    mesh: &Mesh,
    path: &Path,
    forces: &[Force],
) -> Result<(), FemError> {
    for (i, fo) in forces.iter().enumerate() {
        let what = format!("[[force]] #{} (on = \"{}\")", i + 1, shorten(&fo.on));
        let Some(g) = mesh.group_any(&fo.on).filter(|g| g.dim == 0) else {
            let points: Vec<&str> = mesh
                .groups
                .iter()
                .filter(|g| g.dim == 0)
                .map(|g| g.name.as_str())
                .collect();
            return Err(FemError::new(
                path,
                format!(
                    "{what}: no physical point named \"{}\" in {} (points: {})",
                    shorten(&fo.on),
                    mesh.path.display(),
                    if points.is_empty() {
                        "none".to_string()
                    } else {
                        points.join(", ")
                    }
                ),
            ));
        };
        let f: Vector3 = fo.f.xyz();
        for &e in &g.elements {
            // The copy of the lowest body on a contact surface, as in 2D.
            let node = mesh.points[e];
            let Some(v) = model.point_node.iter().position(|&n| n == node) else {
                continue;
            };
            let p = &model.dofs[v];
            for r in 0..p.ndof {
                let t = p.t[r];
                model.qp.d[p.start + r] += t[0] * f[0] + t[1] * f[1] + t[2] * f[2];
            }
            for k in 0..3 {
                model.loads[v][k] += f[k];
            }
        }
    }
    Ok(())
}
