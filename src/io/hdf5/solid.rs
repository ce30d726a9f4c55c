//! The 3D checkpoint (a solid model, docs/problem-format.md §6 "The 3D
//! checkpoint"): a single solve's in one piece; a run with load steps
//! splits it as 2D does (a mesh file, a file per step, an index of
//! external links). Read by h5py and by the 3D cross-check
//! (scripts/fenicsx_crosscheck3d.py).

use super::{
    set_attr_scalar, set_attr_str, set_attr_str_list, step_name, write_ds, Ctx, RESERVED_ROOT_ATTRS,
};
use crate::io::atomic::{write_atomic, IoError};
use crate::output::StepInfo;
use ::hdf5::{File, Group};
use std::path::Path;

/// Writes the checkpoint of a solved solid (3D) model at `path` in one
/// piece (the 3D layout of the module's documentation): root attributes
/// `attrs` (strings), `model` = "solid", `dim` = 3 and `last_step` = 1;
/// `/mesh` with D = 3 columns and tetrahedra; one step `/steps/0001` with
/// `time` and `info`, and the contact rows' datasets.
pub fn write_solid_checkpoint(
    path: &Path,
    out: &crate::output::SolidOutput,
    contact: &crate::output::SolidContactOutput,
    node_tags: &[u64],
    attrs: &[(&str, String)],
    time: f64,
    info: &StepInfo,
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    check_attrs(&ctx, attrs)?;
    check_sizes(&ctx, out, node_tags)?;
    write_atomic(path, |tmp| {
        let file = File::create(tmp).map_err(ctx.h5("/"))?;
        {
            let root: &Group = &file;
            set_root(&ctx, root, attrs)?;
            let g = file.create_group("mesh").map_err(ctx.h5("/mesh"))?;
            write_mesh(&ctx, &g, out, contact, node_tags)?;
            let steps = file.create_group("steps").map_err(ctx.h5("/steps"))?;
            write_step(&ctx, &steps, 1, out, contact, time, info)?;
            set_attr_scalar(&ctx, root, "last_step", &1u64)?;
        }
        file.close().map_err(ctx.h5("/"))
    })
}

/// The mesh file of a split 3D checkpoint (a run with load steps,
/// docs/problem-format.md §6): `/mesh` as in [`write_solid_checkpoint`],
/// at `path` (a new file of a staging directory).
pub fn write_solid_mesh_file(
    path: &Path,
    out: &crate::output::SolidOutput,
    contact: &crate::output::SolidContactOutput,
    node_tags: &[u64],
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    check_sizes(&ctx, out, node_tags)?;
    let file = File::create(path).map_err(ctx.h5("/"))?;
    {
        let g = file.create_group("mesh").map_err(ctx.h5("/mesh"))?;
        write_mesh(&ctx, &g, out, contact, node_tags)?;
    }
    file.close().map_err(ctx.h5("/"))
}

/// The file of step `index` (1-based) of a split 3D checkpoint:
/// `/steps/NNNN` as in [`write_solid_checkpoint`].
pub fn write_solid_step_file(
    path: &Path,
    index: usize,
    out: &crate::output::SolidOutput,
    contact: &crate::output::SolidContactOutput,
    time: f64,
    info: &StepInfo,
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    if index == 0 {
        return Err(ctx.format("step indices start at 1"));
    }
    let file = File::create(path).map_err(ctx.h5("/"))?;
    {
        let steps = file.create_group("steps").map_err(ctx.h5("/steps"))?;
        write_step(&ctx, &steps, index, out, contact, time, info)?;
    }
    file.close().map_err(ctx.h5("/"))
}

/// The index of a split 3D checkpoint: the root attributes of
/// [`write_solid_checkpoint`] and external links `/mesh` → `mesh_file`,
/// `/steps/NNNN` → each step's file (names relative to the index, as 2D's
/// `write_index`).
pub fn write_solid_index(
    path: &Path,
    attrs: &[(&str, String)],
    mesh_file: &str,
    steps: &[(usize, String)],
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    check_attrs(&ctx, attrs)?;
    let file = File::create(path).map_err(ctx.h5("/"))?;
    {
        let root: &Group = &file;
        set_root(&ctx, root, attrs)?;
        root.link_external(mesh_file, "/mesh", "mesh")
            .map_err(ctx.h5("/mesh"))?;
        let g = file.create_group("steps").map_err(ctx.h5("/steps"))?;
        for (index, f) in steps {
            let name = step_name(*index);
            g.link_external(f, &format!("/steps/{name}"), &name)
                .map_err(ctx.h5(format!("/steps/{name}")))?;
        }
        if let Some(last) = steps.iter().map(|s| s.0).max() {
            set_attr_scalar(&ctx, root, "last_step", &(last as u64))?;
        }
    }
    file.close().map_err(ctx.h5("/"))
}

fn check_attrs(ctx: &Ctx, attrs: &[(&str, String)]) -> Result<(), IoError> {
    for (k, _) in attrs {
        if RESERVED_ROOT_ATTRS.contains(k) || *k == "dim" {
            return Err(ctx.format(format!("root attribute name {k:?} is reserved")));
        }
    }
    Ok(())
}

fn check_sizes(
    ctx: &Ctx,
    out: &crate::output::SolidOutput,
    node_tags: &[u64],
) -> Result<(), IoError> {
    let (n, m) = (out.points.len(), out.tets.len());
    let lens = [
        ("node_tags", node_tags.len(), n),
        ("body", out.point_body.len(), n),
        ("displacement", out.displacement.len(), n),
        ("material", out.material.len(), m),
        ("stress", out.stress.len(), m),
        ("von_mises", out.von_mises.len(), m),
        ("principal_stress", out.principal.len(), m),
    ];
    for (what, got, want) in lens {
        if got != want {
            return Err(ctx.format(format!("{what} has {got} entries, expected {want}")));
        }
    }
    Ok(())
}

/// The root attributes: `attrs`, `model` = "solid", `dim` = 3.
fn set_root(ctx: &Ctx, root: &Group, attrs: &[(&str, String)]) -> Result<(), IoError> {
    for (k, v) in attrs {
        set_attr_str(ctx, root, k, v)?;
    }
    set_attr_str(
        ctx,
        root,
        "model",
        crate::fem::ElementKind::Solid.model_name(),
    )?;
    set_attr_scalar(ctx, root, "dim", &3u64)
}

/// `/mesh`: points, tags, bodies, tetrahedra, materials, contact rows.
fn write_mesh(
    ctx: &Ctx,
    g: &Group,
    out: &crate::output::SolidOutput,
    contact: &crate::output::SolidContactOutput,
    node_tags: &[u64],
) -> Result<(), IoError> {
    let (n, m) = (out.points.len(), out.tets.len());
    write_ds(ctx, g, "nodes", &[n, 3], out.points.as_flattened())?;
    write_ds(ctx, g, "node_tags", &[n], node_tags)?;
    write_ds(ctx, g, "body", &[n], &out.point_body)?;
    let tets: Vec<u64> = out.tets.iter().flatten().map(|&i| i as u64).collect();
    write_ds(ctx, g, "tetrahedra", &[m, 4], &tets)?;
    write_ds(ctx, g, "material", &[m], &out.material)?;
    set_attr_str_list(ctx, g, "material_names", &out.material_names)?;
    let r = contact.points.len();
    let slave: Vec<u64> = contact.slave.iter().map(|&i| i as u64).collect();
    write_ds(ctx, g, "contact_slave", &[r], &slave)?;
    write_ds(
        ctx,
        g,
        "contact_normal",
        &[r, 3],
        contact.normal.as_flattened(),
    )?;
    write_ds(ctx, g, "contact_gap0", &[r], &contact.gap0)?;
    write_ds(ctx, g, "contact_interface", &[r], &contact.interface)?;
    let tris: Vec<u64> = contact
        .triangles
        .iter()
        .flatten()
        .map(|&i| i as u64)
        .collect();
    write_ds(
        ctx,
        g,
        "contact_triangles",
        &[contact.triangles.len(), 3],
        &tris,
    )
}

/// `/steps/NNNN` of step `index` in `steps`.
fn write_step(
    ctx: &Ctx,
    steps: &Group,
    index: usize,
    out: &crate::output::SolidOutput,
    contact: &crate::output::SolidContactOutput,
    time: f64,
    info: &StepInfo,
) -> Result<(), IoError> {
    let (n, m, r) = (out.points.len(), out.tets.len(), contact.points.len());
    let name = step_name(index);
    let s = steps
        .create_group(&name)
        .map_err(ctx.h5(format!("/steps/{name}")))?;
    write_ds(
        ctx,
        &s,
        "displacement",
        &[n, 3],
        out.displacement.as_flattened(),
    )?;
    write_ds(ctx, &s, "stress", &[m, 6], out.stress.as_flattened())?;
    write_ds(ctx, &s, "von_mises", &[m], &out.von_mises)?;
    write_ds(
        ctx,
        &s,
        "principal_stress",
        &[m, 3],
        out.principal.as_flattened(),
    )?;
    write_ds(ctx, &s, "multipliers", &[r], &contact.multiplier)?;
    write_ds(ctx, &s, "contact_pressure", &[r], &contact.pressure)?;
    write_ds(ctx, &s, "gap", &[r], &contact.gap)?;
    let active: Vec<u8> = contact.active.iter().map(|&a| u8::from(a)).collect();
    write_ds(ctx, &s, "active", &[r], &active)?;
    set_attr_scalar(ctx, &s, "time", &time)?;
    set_attr_str(ctx, &s, "method", &info.method)?;
    set_attr_str(ctx, &s, "preconditioner", &info.preconditioner)?;
    set_attr_scalar(ctx, &s, "converged", &u8::from(info.converged))?;
    set_attr_scalar(ctx, &s, "iterations", &(info.iterations as u64))?;
    for (name, v) in info.kkt.named() {
        set_attr_scalar(ctx, &s, &format!("kkt_{name}"), &v)?;
    }
    for (name, v) in [
        ("energy", info.energy),
        ("time_assemble", info.time_assemble),
        ("time_solve", info.time_solve),
        ("time_total", info.time_total),
    ] {
        set_attr_scalar(ctx, &s, name, &v)?;
    }
    Ok(())
}
