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
        super::split::write_links(&ctx, &file, mesh_file, steps)?;
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

/// The friction arrays of a step (docs/methods.md §12.6), 2D's names with
/// three columns: `multipliers_t` the tangential force (N), `tangential_traction`
/// (Pa), `slip` (m) as \[r, 3\] in global coordinates, `state` \[r\]; and
/// `multipliers_t_frame` \[r, 2\], the QP's λ_t along each row's frame
/// (the warm start of `--restart`).
fn write_solid_friction(
    ctx: &Ctx,
    s: &Group,
    c: &crate::output::SolidContactOutput,
) -> Result<(), IoError> {
    let r = c.points.len();
    for (what, got) in [
        ("multipliers_t", c.tangential_force.len()),
        ("tangential_traction", c.tangential_traction.len()),
        ("slip", c.slip.len()),
        ("state", c.friction_state.len()),
    ] {
        if got != r {
            return Err(ctx.format(format!(
                "step field {what} has {got} entries, the contact rows {r}"
            )));
        }
    }
    for (name, v) in [
        ("multipliers_t", &c.tangential_force),
        ("tangential_traction", &c.tangential_traction),
        ("slip", &c.slip),
    ] {
        write_ds(ctx, s, name, &[r, 3], v.as_flattened())?;
    }
    if c.multiplier_t.len() == r {
        write_ds(
            ctx,
            s,
            "multipliers_t_frame",
            &[r, 2],
            c.multiplier_t.as_flattened(),
        )?;
    }
    write_ds(ctx, s, "state", &[r], &c.friction_state)
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
pub(super) fn set_root(ctx: &Ctx, root: &Group, attrs: &[(&str, String)]) -> Result<(), IoError> {
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
    if !contact.friction_state.is_empty() {
        write_solid_friction(ctx, &s, contact)?;
    }
    if let Some(c) = &out.change {
        write_ds(
            ctx,
            &s,
            "displacement_change",
            &[n, 3],
            c.displacement.as_flattened(),
        )?;
        write_ds(ctx, &s, "stress_change", &[m, 6], c.stress.as_flattened())?;
        write_ds(
            ctx,
            &s,
            "contact_pressure_change",
            &[r],
            &c.contact_pressure,
        )?;
        set_attr_scalar(ctx, &s, "reference_step", &(c.reference_step as u64))?;
    }
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

/// A step's displacement \[n\], stress \[m\] and contact pressure \[r\].
pub type StepFields = (Vec<[f64; 3]>, Vec<[f64; 6]>, Vec<f64>);

/// What a restart of a 3D run reads of its checkpoint
/// ([`read_solid_restart`]).
#[derive(Debug, Clone, Default)]
pub struct SolidRestartData {
    /// The root attribute `model` ("solid" for a 3D checkpoint).
    pub model: Option<String>,
    /// The root attribute `fingerprint`.
    pub fingerprint: Option<String>,
    /// Rows of `/mesh/nodes`, `/mesh/tetrahedra`, `/mesh/contact_slave`.
    pub points: usize,
    pub tets: usize,
    pub rows: usize,
    /// The step groups in index order: (name, attribute `time`, attribute
    /// `reference_step` if the step has change fields).
    pub steps: Vec<(String, f64, Option<u64>)>,
    /// Step `reference`'s displacement, stress and contact pressure (the
    /// step asked for, when the checkpoint holds it).
    pub reference: Option<StepFields>,
    /// The last step's displacement \[points, 3\] and active flags \[rows\],
    /// read when the sizes are the `n` and `r` asked for.
    pub displacement: Option<Vec<[f64; 3]>>,
    pub active: Option<Vec<u8>>,
    /// The last step's λ_n \[rows\] and, with friction, λ_t along each
    /// row's frame \[rows, 2\] (`multipliers_t_frame`; None in a checkpoint
    /// without friction or written before it existed).
    pub multipliers: Option<Vec<f64>>,
    pub multipliers_t: Option<Vec<[f64; 2]>>,
}

/// Reads what a restart needs of the 3D checkpoint at `path` (single file
/// or split layout): the root attributes, the mesh's sizes, the step groups
/// and their times, and, when the checkpoint has `n` points and `r` contact
/// rows, its last step's displacement and active flags. A 2D checkpoint
/// gives `model` ≠ "solid" and nothing else.
pub fn read_solid_restart(
    path: &Path,
    n: usize,
    m: usize,
    r: usize,
    reference: Option<usize>,
) -> Result<SolidRestartData, IoError> {
    let (_, file) = super::open_checkpoint(path)?;
    // Every dataset read has its shape checked against n and r first (the
    // index's size bounds nothing of the files it links to).
    let ctx = Ctx::writing(path);
    let root: &Group = &file;
    let text = |name: &str| -> Result<Option<String>, IoError> {
        Ok(if super::has_attr(&ctx, root, name)? {
            Some(super::get_attr_str(&ctx, root, name)?)
        } else {
            None
        })
    };
    let mut out = SolidRestartData {
        model: text("model")?,
        fingerprint: text("fingerprint")?,
        ..Default::default()
    };
    if out.model.as_deref() != Some(crate::fem::ElementKind::Solid.model_name()) {
        return Ok(out);
    }
    if !file.link_exists("mesh") {
        return Err(ctx.missing("group /mesh"));
    }
    let mesh = file
        .group("mesh")
        .map_err(|e| super::linked(&ctx, "/mesh", e))?;
    out.points = super::dataset_len(&ctx, &mesh, "nodes")?;
    out.tets = super::dataset_len(&ctx, &mesh, "tetrahedra")?;
    out.rows = super::dataset_len(&ctx, &mesh, "contact_slave")?;
    let Some((sg, names)) = super::step_names(&ctx, &file)? else {
        return Ok(out);
    };
    for (_, name) in &names {
        let g = sg
            .group(name)
            .map_err(|e| super::linked(&ctx, &format!("/steps/{name}"), e))?;
        let t: f64 = super::get_attr(&ctx, &g, "time")?;
        let k = if super::has_attr(&ctx, &g, "reference_step")? {
            Some(super::get_attr::<u64>(&ctx, &g, "reference_step")?)
        } else {
            None
        };
        out.steps.push((name.clone(), t, k));
    }
    let sizes = out.points == n && out.tets == m && out.rows == r;
    if let (Some(k), true) = (reference, sizes) {
        if let Some((_, name)) = names.iter().find(|(i, _)| *i == k) {
            let g = sg
                .group(name)
                .map_err(|e| super::linked(&ctx, &format!("/steps/{name}"), e))?;
            let (_, u) = super::read_ds::<f64>(&ctx, &g, "displacement", Some(3), Some(n))?;
            let (_, st) = super::read_ds::<f64>(&ctx, &g, "stress", Some(6), Some(m))?;
            let (_, p) = super::read_ds::<f64>(&ctx, &g, "contact_pressure", None, Some(r))?;
            out.reference = Some((
                u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                st.chunks_exact(6)
                    .map(|c| std::array::from_fn(|i| c[i]))
                    .collect(),
                p,
            ));
        }
    }
    if let (Some((_, last)), true) = (names.last(), sizes) {
        let g = sg
            .group(last)
            .map_err(|e| super::linked(&ctx, &format!("/steps/{last}"), e))?;
        let (_, u) = super::read_ds::<f64>(&ctx, &g, "displacement", Some(3), Some(n))?;
        out.displacement = Some(u.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
        let (_, a) = super::read_ds::<u8>(&ctx, &g, "active", None, Some(r))?;
        out.active = Some(a);
        let (_, l) = super::read_ds::<f64>(&ctx, &g, "multipliers", None, Some(r))?;
        out.multipliers = Some(l);
        if g.link_exists("multipliers_t_frame") {
            let (_, t) = super::read_ds::<f64>(&ctx, &g, "multipliers_t_frame", Some(2), Some(r))?;
            out.multipliers_t = Some(t.chunks_exact(2).map(|c| [c[0], c[1]]).collect());
        }
    }
    Ok(out)
}
