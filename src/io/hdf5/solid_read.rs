//! Reading the 3D checkpoint (docs/problem-format.md §6 "The 3D
//! checkpoint") into [`SolidCheckpoint`]: the mesh and contact rows once,
//! then the steps `/steps/NNNN` asked for (either layout: the groups may
//! be external links of a split checkpoint). Every read is bounded by the
//! file, as in 2D.

use super::{
    get_attr, get_attr_str_list, has_attr, indices, linked, read_ds, read_step_info, step_names,
    Ctx, RESERVED_ROOT_ATTRS,
};
use crate::io::atomic::IoError;
use crate::output::{SolidCheckpoint, SolidContactMesh, SolidStep};
use ::hdf5::types::VarLenUnicode;
use ::hdf5::{File, Group};
use std::path::Path;

/// Which steps [`read_solid_checkpoint`] reads (a plot needs one, and a
/// long run's steps need not all be in memory).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolidSteps {
    All,
    /// The root attribute `last_step` when it names a step group, else the
    /// highest-numbered group.
    Last,
    /// The group `/steps/NNNN` with this number.
    One(usize),
    /// Every step read and checked, one at a time, and none kept: the
    /// whole file verified without holding its steps (`pack`).
    Checked,
    /// No step read: the mesh, the contact rows and the root attributes
    /// (then [`read_solid_step`] one step at a time).
    MeshOnly,
}

/// Whether `path` is a checkpoint file whose root says `model = "solid"`
/// (false for anything unreadable: the 2D reader then says why).
pub fn is_solid_checkpoint(path: &Path) -> bool {
    if !path.is_file() {
        return false;
    }
    File::open(path)
        .and_then(|f| f.attr("model"))
        .and_then(|a| a.read_scalar::<VarLenUnicode>())
        .is_ok_and(|m| m.as_str() == crate::fem::ElementKind::Solid.model_name())
}

/// Reads a 3D checkpoint: mesh, contact rows, the steps `which` names and
/// the string root attributes. A step asked for that the file lacks is
/// refused naming the steps it has.
pub fn read_solid_checkpoint(path: &Path, which: SolidSteps) -> Result<SolidCheckpoint, IoError> {
    let (ctx, file) = super::open_checkpoint(path)?;
    let mut attrs = Vec::new();
    for name in file.attr_names().map_err(ctx.h5("/"))? {
        if RESERVED_ROOT_ATTRS.contains(&name.as_str()) || name == "dim" {
            continue;
        }
        if let Ok(v) = file
            .attr(&name)
            .and_then(|a| a.read_scalar::<VarLenUnicode>())
        {
            attrs.push((name, v.as_str().to_string()));
        }
    }
    if get_attr::<u64>(&ctx, &file, "dim")? != 3 {
        return Err(ctx.format("root attribute dim: expected 3 for a solid checkpoint"));
    }
    if !file.link_exists("mesh") {
        return Err(ctx.missing("group /mesh"));
    }
    let g = file.group("mesh").map_err(|e| linked(&ctx, "/mesh", e))?;
    let mut ck = read_mesh(&ctx.of_file(&g), &g)?;
    ck.attrs = attrs;

    let Some((sg, names)) = step_names(&ctx, &file)? else {
        return Ok(ck);
    };
    ck.step_indices = names.iter().map(|(i, _)| *i).collect();
    let pick: Vec<&(usize, String)> = match which {
        SolidSteps::All | SolidSteps::Checked => names.iter().collect(),
        SolidSteps::MeshOnly => vec![],
        SolidSteps::Last => {
            let last = if has_attr(&ctx, &file, "last_step")? {
                let k = get_attr::<u64>(&ctx, &file, "last_step")?;
                names.iter().find(|(i, _)| *i as u64 == k)
            } else {
                None
            };
            last.or(names.last()).into_iter().collect()
        }
        SolidSteps::One(k) => match names.iter().find(|(i, _)| *i == k) {
            Some(s) => vec![s],
            None => {
                return Err(ctx.format(format!(
                    "step {k} out of range: the checkpoint has {}",
                    describe_steps(&ck.step_indices)
                )))
            }
        },
    };
    for (i, name) in pick {
        let g = sg
            .group(name)
            .map_err(|e| linked(&ctx, &format!("/steps/{name}"), e))?;
        let step = read_step(&ctx.of_file(&g), &g, &ck, *i)?;
        if which != SolidSteps::Checked {
            ck.steps.push(step);
        }
    }
    Ok(ck)
}

/// Reads step `index` of the 3D checkpoint at `path` whose mesh `ck` was
/// read before ([`SolidSteps::MeshOnly`]), without reading the mesh again.
pub fn read_solid_step(
    path: &Path,
    ck: &SolidCheckpoint,
    index: usize,
) -> Result<SolidStep, IoError> {
    let (ctx, file) = super::open_checkpoint(path)?;
    let loc = format!("/steps/{}", super::step_name(index));
    let g = file.group(&loc).map_err(|e| linked(&ctx, &loc, e))?;
    read_step(&ctx.of_file(&g), &g, ck, index)
}

/// "1 step (1)", "3 steps (1 to 3)", "no step".
fn describe_steps(idx: &[usize]) -> String {
    match idx {
        [] => "no step".into(),
        [a] => format!("1 step ({a})"),
        [a, .., b] => format!("{} steps ({a} to {b})", idx.len()),
    }
}

fn triples<T: Copy>(v: &[T]) -> Vec<[T; 3]> {
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

fn read_mesh(ctx: &Ctx, g: &Group) -> Result<SolidCheckpoint, IoError> {
    let (n, nodes) = read_ds::<f64>(ctx, g, "nodes", Some(3), None)?;
    let (_, point_tags) = read_ds::<u64>(ctx, g, "node_tags", None, Some(n))?;
    let (_, point_body) = read_ds::<u32>(ctx, g, "body", None, Some(n))?;
    let (m, tets) = read_ds::<u64>(ctx, g, "tetrahedra", Some(4), None)?;
    let tets = indices(ctx, "/mesh/tetrahedra", &tets, n)?;
    let (_, material) = read_ds::<u32>(ctx, g, "material", None, Some(m))?;
    let material_names = get_attr_str_list(ctx, g, "material_names")?;
    // The contact rows: all five datasets or none (a model without contact).
    let contact = if g.link_exists("contact_slave") {
        let (r, slave) = read_ds::<u64>(ctx, g, "contact_slave", None, None)?;
        let (_, normal) = read_ds::<f64>(ctx, g, "contact_normal", Some(3), Some(r))?;
        let (_, gap0) = read_ds::<f64>(ctx, g, "contact_gap0", None, Some(r))?;
        let (_, interface) = read_ds::<u32>(ctx, g, "contact_interface", None, Some(r))?;
        let (_, tris) = read_ds::<u64>(ctx, g, "contact_triangles", Some(3), None)?;
        SolidContactMesh {
            slave: indices(ctx, "/mesh/contact_slave", &slave, n)?,
            normal: triples(&normal),
            gap0,
            interface,
            triangles: triples(&indices(ctx, "/mesh/contact_triangles", &tris, r)?),
        }
    } else {
        SolidContactMesh::default()
    };
    Ok(SolidCheckpoint {
        points: triples(&nodes),
        point_tags,
        point_body,
        tets: tets
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        material,
        material_names,
        contact,
        ..Default::default()
    })
}

fn read_step(
    ctx: &Ctx,
    g: &Group,
    ck: &SolidCheckpoint,
    index: usize,
) -> Result<SolidStep, IoError> {
    let n = Some(ck.points.len());
    let m = Some(ck.tets.len());
    let r = ck.contact.slave.len();
    let (_, displacement) = read_ds::<f64>(ctx, g, "displacement", Some(3), n)?;
    let (_, stress) = read_ds::<f64>(ctx, g, "stress", Some(6), m)?;
    let (_, von_mises) = read_ds::<f64>(ctx, g, "von_mises", None, m)?;
    let (_, principal) = read_ds::<f64>(ctx, g, "principal_stress", Some(3), m)?;
    // Contact datasets are written (empty) without contact; older files may lack them.
    let rows = |name: &str| -> Result<Vec<f64>, IoError> {
        if r == 0 && !g.link_exists(name) {
            return Ok(vec![]);
        }
        Ok(read_ds::<f64>(ctx, g, name, None, Some(r))?.1)
    };
    let active = if r == 0 && !g.link_exists("active") {
        vec![]
    } else {
        read_ds::<u8>(ctx, g, "active", None, Some(r))?.1
    };
    // Friction (all four, or none).
    let (mut tangential_force, mut tangential_traction, mut slip, mut friction_state) =
        (vec![], vec![], vec![], vec![]);
    if g.link_exists("multipliers_t") {
        let vecs = |name: &str| -> Result<Vec<[f64; 3]>, IoError> {
            Ok(triples(&read_ds::<f64>(ctx, g, name, Some(3), Some(r))?.1))
        };
        tangential_force = vecs("multipliers_t")?;
        tangential_traction = vecs("tangential_traction")?;
        slip = vecs("slip")?;
        friction_state = read_ds::<u8>(ctx, g, "state", None, Some(r))?.1;
        if let Some(&bad) = friction_state.iter().find(|&&v| v > 2) {
            return Err(ctx.format(format!(
                "{}/state: {bad} is not 0 (open), 1 (stick) or 2 (slip)",
                g.name()
            )));
        }
    }
    Ok(SolidStep {
        index,
        time: get_attr(ctx, g, "time")?,
        displacement: triples(&displacement),
        stress: stress
            .chunks_exact(6)
            .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
            .collect(),
        von_mises,
        principal: triples(&principal),
        multipliers: rows("multipliers")?,
        contact_pressure: rows("contact_pressure")?,
        gap: rows("gap")?,
        active,
        tangential_force,
        tangential_traction,
        slip,
        friction_state,
        info: read_step_info(ctx, g)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_described_by_their_numbers() {
        assert_eq!(describe_steps(&[]), "no step");
        assert_eq!(describe_steps(&[1]), "1 step (1)");
        assert_eq!(describe_steps(&[1, 2, 3]), "3 steps (1 to 3)");
    }
}
