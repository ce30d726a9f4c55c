//! The HDF5 checkpoint (`model.h5`, docs/problem-format.md §6): the mesh once,
//! then one group per load step; its layout is below (§ Layout); what it holds is
//! [`Checkpoint`].
//!
//! Every write is crash-safe: the file is built (or copied and extended) in
//! a private staging directory, closed, fsynced and renamed over the target.
//! A run with load steps writes the split layout (§ Layout): each
//! step its own file and a new small index, so no step copies the earlier
//! ones.
//! Every read is bounded by the file: a dataset or attribute whose shape
//! needs more bytes than the file holds is refused before any allocation
//! (checkpoints are written uncompressed, so a genuine one always fits).
//!
//! # Layout
//!
//! Layout (indices are 0-based; "rows" = contact constraint rows):
//!
//! ```text
//! /                       attrs: one string attribute per `attrs` entry
//!                                (e.g. problem, toml, version, and the
//!                                fingerprint `--restart` compares),
//!                                plane_strain (u8 0/1: the stress has a 4th component,
//!                                also 1 for an axisymmetric model), model (string:
//!                                plane_strain | plane_stress | axisymmetric),
//!                                last_step (u64, once a step exists)
//! /mesh/nodes             f64  [n, 2]   undeformed point coordinates
//! /mesh/node_tags         u64  [n]      Gmsh node tag of each point
//! /mesh/body              u32  [n]      body of each point
//! /mesh/triangles         u64  [m, 3]   point indices, counter-clockwise
//! /mesh/material          u32  [m]      index into material_names
//! /mesh/contact_points    f64  [rows, 2]
//! /mesh/contact_first     u64  [rows]   point index of the first side
//! /mesh/contact_second    u64  [rows, 2] point indices of the other side
//! /mesh/contact_weights   f64  [rows, 2] their weights
//! /mesh/contact_normal    f64  [rows, 2]
//! /mesh/contact_gap0      f64  [rows]
//! /mesh/contact_interface u32  [rows]   index into interface_names
//! /mesh/contact_segments  u64  [k, 2]   contact-point indices
//! /mesh                   attrs: material_names, interface_names,
//!                                interface_discretizations ("node-to-node",
//!                                "nts" or "mortar" per interface; absent in
//!                                checkpoints written before it)
//!                                (1-D arrays of variable-length UTF-8 strings)
//! /steps/NNNN             one group per step (4+ digits, 1-based):
//!     displacement f64 [n, 2], stress f64 [m, 4], von_mises f64 [m],
//!     principal_stress f64 [m, 2], multipliers f64 [rows],
//!     contact_pressure f64 [rows], gap f64 [rows], active u8 [rows]
//!     attrs: time, energy, kkt_* (every residual of `qp::Kkt`), time_* (f64); iterations (u64);
//!            converged (u8 0/1); method, preconditioner (strings)
//!     with `[output] reference_step` (that step and later ones):
//!     displacement_change f64 [n, 2], stress_change f64 [m, 4],
//!     contact_pressure_change f64 [rows]; attr reference_step (u64)
//!     with friction (docs/methods.md §9): multipliers_t f64 [rows],
//!     tangential_traction f64 [rows], slip f64 [rows], state u8 [rows]
//! ```
//!
//! Two layouts hold this tree. A single solve writes it as one file. A run
//! with load steps writes it split, so that a step writes its own data and
//! nothing else ([`write_mesh_file`], [`write_step_file`], [`write_index`]):
//! `NAME_mesh.h5` holds `/mesh`, `NAME_NNNN.h5` holds `/steps/NNNN`, and
//! `NAME.h5` holds the root attributes and HDF5 external links `/mesh` and
//! `/steps/NNNN` to them (relative file names, resolved next to `NAME.h5`),
//! so h5py and [`read_checkpoint`] see the same tree. The small index is
//! rewritten and renamed into place at each step: it is the step's commit.

use std::path::Path;
use std::str::FromStr;

use ::hdf5::types::VarLenUnicode;
use ::hdf5::{File, Group, H5Type, Location};

use super::atomic::{write_atomic, IoError};
use crate::output::{
    Change, Checkpoint, ContactGeometry, OutMesh, StepFriction, StepInfo, StepOutput,
};

mod read;
mod solid;
mod solid_read;
mod split;
pub use read::{check_checkpoint, read_checkpoint};
use read::{read_step, read_step_info};
pub use solid::{
    read_solid_restart, write_solid_checkpoint, write_solid_index, write_solid_mesh_file,
    write_solid_step_file, SolidRestartData,
};
pub use solid_read::{is_solid_checkpoint, read_solid_checkpoint, read_solid_step, SolidSteps};
pub use split::{
    checkpoint_files, mesh_file_name, pack, step_file_name, unpack_part, write_index,
    write_mesh_file, write_step_file, CheckpointFiles, Packed,
};

/// Root attributes that are not user strings.
const RESERVED_ROOT_ATTRS: [&str; 4] = ["plane_strain", "last_step", "axisymmetric", "model"];

/// The root attributes of the mesh's kind: `plane_strain` (1 when the
/// stress has a fourth component, σzz or, axisymmetric, σθθ), `model`
/// ("plane_strain", "plane_stress" or "axisymmetric"; `plane_strain` alone
/// reads as plane strain for an axisymmetric model, readers of the kind
/// use this one) when `with_model`, and `axisymmetric` = 1 when it is.
fn set_kind_attrs(
    ctx: &Ctx,
    root: &Group,
    kind: crate::fem::ElementKind,
    with_model: bool,
) -> Result<(), IoError> {
    let (four_components, on_axis) = kind.file_flags();
    set_attr_scalar(ctx, root, "plane_strain", &four_components)?;
    if with_model {
        set_attr_str(ctx, root, "model", kind.model_name())?;
    }
    if let Some(a) = on_axis {
        set_attr_scalar(ctx, root, "axisymmetric", &a)?;
    }
    Ok(())
}

/// Error context: the file the user named plus an HDF5 location.
struct Ctx<'a> {
    path: &'a Path,
    /// The size of the file being read (u64::MAX when writing): no dataset
    /// of an uncompressed checkpoint can hold more bytes, so a shape that
    /// claims more is refused before anything is allocated.
    limit: u64,
}

impl<'a> Ctx<'a> {
    fn writing(path: &'a Path) -> Ctx<'a> {
        Ctx {
            path,
            limit: u64::MAX,
        }
    }

    /// Refuses `count` values of `size` bytes at `loc` if the file cannot hold them.
    fn check_fits(&self, loc: &str, shape: &[usize], size: usize) -> Result<(), IoError> {
        let bytes = shape
            .iter()
            .try_fold(size as u128, |a, &d| a.checked_mul(d as u128));
        match bytes {
            Some(b) if b <= self.limit as u128 => Ok(()),
            _ => Err(self.format(format!(
                "{loc}: shape {shape:?} needs more bytes than the file holds ({} bytes); the checkpoint is corrupt",
                self.limit
            ))),
        }
    }
}

impl<'a> Ctx<'a> {
    /// The context of reading the object `loc`, which may live in another
    /// file (an external link of a split checkpoint): the size bound is
    /// that file's.
    fn of_file(&self, loc: &Location) -> Ctx<'a> {
        let limit = std::fs::metadata(loc.filename())
            .map(|m| m.len())
            .unwrap_or(self.limit);
        Ctx {
            path: self.path,
            limit,
        }
    }
}

impl Ctx<'_> {
    fn h5(&self, location: impl Into<String>) -> impl FnOnce(::hdf5::Error) -> IoError + '_ {
        let location = location.into();
        move |cause| IoError::Hdf5 {
            path: self.path.to_path_buf(),
            location,
            cause,
        }
    }

    fn format(&self, message: impl Into<String>) -> IoError {
        IoError::format(self.path, message)
    }

    fn missing(&self, what: impl Into<String>) -> IoError {
        IoError::missing(self.path, what)
    }
}

fn vlu(ctx: &Ctx, what: &str, s: &str) -> Result<VarLenUnicode, IoError> {
    VarLenUnicode::from_str(s)
        .map_err(|_| ctx.format(format!("{what}: string contains a NUL byte")))
}

// ---------------------------------------------------------------- writing

fn write_ds<T: H5Type>(
    ctx: &Ctx,
    g: &Group,
    name: &str,
    shape: &[usize],
    data: &[T],
) -> Result<(), IoError> {
    let loc = format!("{}/{}", g.name(), name);
    let expected: usize = shape.iter().product();
    if expected != data.len() {
        return Err(ctx.format(format!(
            "{loc}: {} values for shape {:?}",
            data.len(),
            shape
        )));
    }
    if g.link_exists(name) {
        g.unlink(name).map_err(ctx.h5(loc.clone()))?;
    }
    let ds = g
        .new_dataset::<T>()
        .shape(shape.to_vec())
        .create(name)
        .map_err(ctx.h5(loc.clone()))?;
    ds.write_raw(data).map_err(ctx.h5(loc))?;
    Ok(())
}

fn flat2<T: Copy>(v: &[[T; 2]]) -> Vec<T> {
    v.iter().flat_map(|a| [a[0], a[1]]).collect()
}

fn set_attr_scalar<T: H5Type>(ctx: &Ctx, loc: &Location, name: &str, v: &T) -> Result<(), IoError> {
    let where_ = format!("{}@{}", loc.name(), name);
    if loc
        .attr_names()
        .map_err(ctx.h5(where_.clone()))?
        .iter()
        .any(|a| a == name)
    {
        loc.delete_attr(name).map_err(ctx.h5(where_.clone()))?;
    }
    let a = loc
        .new_attr::<T>()
        .create(name)
        .map_err(ctx.h5(where_.clone()))?;
    a.write_scalar(v).map_err(ctx.h5(where_))
}

fn set_attr_str(ctx: &Ctx, loc: &Location, name: &str, v: &str) -> Result<(), IoError> {
    let s = vlu(ctx, name, v)?;
    set_attr_scalar(ctx, loc, name, &s)
}

fn set_attr_str_list(ctx: &Ctx, loc: &Location, name: &str, v: &[String]) -> Result<(), IoError> {
    let where_ = format!("{}@{}", loc.name(), name);
    let data = v
        .iter()
        .map(|s| vlu(ctx, name, s))
        .collect::<Result<Vec<_>, _>>()?;
    let a = loc
        .new_attr::<VarLenUnicode>()
        .shape(data.len())
        .create(name)
        .map_err(ctx.h5(where_.clone()))?;
    a.write_raw(data.as_slice()).map_err(ctx.h5(where_))
}

fn check_mesh(ctx: &Ctx, mesh: &OutMesh) -> Result<(), IoError> {
    let n = mesh.points.len();
    let m = mesh.triangles.len();
    let c = &mesh.contact;
    let r = c.points.len();
    let lens = [
        ("node_tags", mesh.point_tags.len(), n),
        ("body", mesh.point_body.len(), n),
        ("material", mesh.material.len(), m),
        ("contact_first", c.first.len(), r),
        ("contact_second", c.second.len(), r),
        ("contact_normal", c.normal.len(), r),
        ("contact_gap0", c.gap0.len(), r),
        ("contact_interface", c.interface.len(), r),
    ];
    for (what, got, want) in lens {
        if got != want {
            return Err(ctx.format(format!("{what} has {got} entries, expected {want}")));
        }
    }
    Ok(())
}

/// Creates a new checkpoint at `path` (replacing any existing file) holding
/// `/mesh` and the root attributes `attrs` (strings) plus `plane_strain`.
pub fn create_checkpoint(
    path: &Path,
    mesh: &OutMesh,
    attrs: &[(&str, String)],
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    check_mesh(&ctx, mesh)?;
    for (k, _) in attrs {
        if RESERVED_ROOT_ATTRS.contains(k) {
            return Err(ctx.format(format!("root attribute name {k:?} is reserved")));
        }
    }
    write_atomic(path, |tmp| {
        let file = File::create(tmp).map_err(ctx.h5("/"))?;
        {
            let root: &Group = &file;
            for (k, v) in attrs {
                set_attr_str(&ctx, root, k, v)?;
            }
            set_kind_attrs(&ctx, root, mesh.kind, true)?;
            let g = file.create_group("mesh").map_err(ctx.h5("/mesh"))?;
            write_mesh(&ctx, &g, mesh)?;
        }
        file.close().map_err(ctx.h5("/"))
    })
}

fn write_mesh(ctx: &Ctx, g: &Group, mesh: &OutMesh) -> Result<(), IoError> {
    let n = mesh.points.len();
    let m = mesh.triangles.len();
    let c = &mesh.contact;
    let r = c.points.len();
    let k = c.segments.len();
    let u = |x: usize| x as u64;

    write_ds(ctx, g, "nodes", &[n, 2], &flat2(&mesh.points))?;
    write_ds(ctx, g, "node_tags", &[n], &mesh.point_tags)?;
    write_ds(ctx, g, "body", &[n], &mesh.point_body)?;
    let tri: Vec<u64> = mesh.triangles.iter().flat_map(|t| t.map(u)).collect();
    write_ds(ctx, g, "triangles", &[m, 3], &tri)?;
    write_ds(ctx, g, "material", &[m], &mesh.material)?;
    set_attr_str_list(ctx, g, "material_names", &mesh.material_names)?;

    write_ds(ctx, g, "contact_points", &[r, 2], &flat2(&c.points))?;
    let first: Vec<u64> = c.first.iter().map(|&i| u(i)).collect();
    write_ds(ctx, g, "contact_first", &[r], &first)?;
    let second: Vec<u64> = c
        .second
        .iter()
        .flat_map(|s| [u(s[0].0), u(s[1].0)])
        .collect();
    write_ds(ctx, g, "contact_second", &[r, 2], &second)?;
    let weights: Vec<f64> = c.second.iter().flat_map(|s| [s[0].1, s[1].1]).collect();
    write_ds(ctx, g, "contact_weights", &[r, 2], &weights)?;
    write_ds(ctx, g, "contact_normal", &[r, 2], &flat2(&c.normal))?;
    write_ds(ctx, g, "contact_gap0", &[r], &c.gap0)?;
    write_ds(ctx, g, "contact_interface", &[r], &c.interface)?;
    let seg: Vec<u64> = c.segments.iter().flat_map(|s| s.map(u)).collect();
    write_ds(ctx, g, "contact_segments", &[k, 2], &seg)?;
    set_attr_str_list(ctx, g, "interface_names", &c.interface_names)?;
    set_attr_str_list(
        ctx,
        g,
        "interface_discretizations",
        &c.interface_discretizations,
    )?;
    Ok(())
}

/// The group name of step `index` (1-based): `NNNN`.
pub fn step_name(index: usize) -> String {
    format!("{index:04}")
}

/// Appends step `index` (1-based) as `/steps/NNNN` and sets the root
/// attribute `last_step`. Steps with an index ≥ `index` already in the file
/// are removed first (a restart from an earlier step rewrites the history
/// after it), so the file always holds a consistent sequence.
///
/// Crash-safe: the checkpoint is copied to a temporary file in the same
/// directory, extended, closed, fsynced and renamed over the original.
pub fn append_step(path: &Path, index: usize, step: &StepOutput) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    if index == 0 {
        return Err(ctx.format("step indices start at 1"));
    }
    write_atomic(path, |tmp| {
        std::fs::copy(path, tmp).map_err(|e| IoError::io(path, "cannot copy checkpoint", e))?;
        append_step_in_place(tmp, index, step)
    })
}

/// [`append_step`] without the copy: extends the checkpoint `path` itself
/// (a file in a staging directory, which is renamed into place once complete).
pub fn append_step_in_place(path: &Path, index: usize, step: &StepOutput) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    if index == 0 {
        return Err(ctx.format("step indices start at 1"));
    }
    let file = File::open_rw(path).map_err(ctx.h5("/"))?;
    {
        if !file.link_exists("mesh") {
            return Err(ctx.missing("group /mesh"));
        }
        let mesh = file.group("mesh").map_err(ctx.h5("/mesh"))?;
        let n = dataset_len(&ctx, &mesh, "nodes")?;
        let m = dataset_len(&ctx, &mesh, "triangles")?;
        let r = dataset_len(&ctx, &mesh, "contact_first")?;
        check_step(&ctx, step, n, m, r)?;

        let steps = if file.link_exists("steps") {
            file.group("steps").map_err(ctx.h5("/steps"))?
        } else {
            file.create_group("steps").map_err(ctx.h5("/steps"))?
        };
        for name in steps.member_names().map_err(ctx.h5("/steps"))? {
            if parse_step_name(&name).is_some_and(|i| i >= index) {
                steps
                    .unlink(&name)
                    .map_err(ctx.h5(format!("/steps/{name}")))?;
            }
        }
        let name = step_name(index);
        let g = steps
            .create_group(&name)
            .map_err(ctx.h5(format!("/steps/{name}")))?;
        write_step(&ctx, &g, step)?;
        set_attr_scalar(&ctx, &file, "last_step", &(index as u64))?;
    }
    file.close().map_err(ctx.h5("/"))
}

/// The group /steps and its step groups (index, name) in step order.
type StepNames = (Group, Vec<(usize, String)>);

/// The [`StepNames`] of `file`; None without /steps.
fn step_names(ctx: &Ctx, file: &File) -> Result<Option<StepNames>, IoError> {
    if !file.link_exists("steps") {
        return Ok(None);
    }
    let sg = file.group("steps").map_err(ctx.h5("/steps"))?;
    let mut names: Vec<(usize, String)> = sg
        .member_names()
        .map_err(ctx.h5("/steps"))?
        .into_iter()
        .filter_map(|nm| parse_step_name(&nm).map(|i| (i, nm)))
        .collect();
    names.sort();
    Ok(Some((sg, names)))
}

/// An HDF5 error opening `loc`, with a hint when it is an external link of
/// a split checkpoint whose file is missing: the file is named (as HDF5
/// looked for it, next to the index), and so is what makes a checkpoint.
/// Opens the checkpoint at `path` for reading, for every reader (2D, 3D,
/// restart, one step): a regular file (a directory or a device is refused
/// naming it), its size the bound of every dataset's claimed shape
/// (`Ctx::limit`), and a part of a split checkpoint refused naming the
/// index to give instead ([`split::part_of_split`]).
fn open_checkpoint(path: &Path) -> Result<(Ctx<'_>, File), IoError> {
    let meta =
        std::fs::metadata(path).map_err(|e| IoError::io(path, "cannot open checkpoint", e))?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "is a directory, not a checkpoint file"
        } else {
            "is not a regular file (a FIFO, socket or device)"
        };
        return Err(IoError::io(
            path,
            "cannot open checkpoint",
            std::io::Error::new(std::io::ErrorKind::InvalidInput, what),
        ));
    }
    let ctx = Ctx {
        path,
        limit: meta.len(),
    };
    let file = File::open(path).map_err(ctx.h5("/"))?;
    if let Some(msg) = split::part_of_split(path, &file) {
        return Err(ctx.format(msg));
    }
    Ok((ctx, file))
}

fn linked(ctx: &Ctx, loc: &str, cause: ::hdf5::Error) -> IoError {
    let text = cause.to_string();
    if text.contains("external") {
        let hint = "a checkpoint written with load steps is NAME.h5 with NAME_mesh.h5 and one NAME_NNNN.h5 per step beside it: copy or move them as a whole, or make one self-contained file with `signorini pack`";
        let dir = match ctx.path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => std::path::PathBuf::from("."),
        };
        let target = external_file_name(&text).map(|n| dir.join(n));
        return ctx.format(match target {
            Some(f) if !f.exists() => format!(
                "{loc}: its data is in {}, which does not exist; {hint}",
                f.display()
            ),
            Some(f) => format!(
                "{loc}: the file it links to, {}, cannot be opened ({text}); {hint}",
                f.display()
            ),
            None => format!("{loc}: the file it links to cannot be opened ({text}); {hint}"),
        });
    }
    IoError::Hdf5 {
        path: ctx.path.to_path_buf(),
        location: loc.to_string(),
        cause,
    }
}

/// The file an external link names, from HDF5's message
/// (`external link file name = 'NAME'`), if it says.
fn external_file_name(text: &str) -> Option<&str> {
    let rest = text.split("external link file name = '").nth(1)?;
    let name = &rest[..rest.find('\'')?];
    (!name.is_empty()).then_some(name)
}

/// Reads the step group `NNNN` of the checkpoint at `path` (either layout)
/// with its friction arrays, sizes checked against `mesh`.
pub fn read_step_of(
    path: &Path,
    mesh: &OutMesh,
    name: &str,
) -> Result<(StepOutput, Option<StepFriction>), IoError> {
    let ctx = Ctx::writing(path);
    let file = File::open(path).map_err(ctx.h5("/"))?;
    let loc = format!("/steps/{name}");
    let g = file.group(&loc).map_err(|e| linked(&ctx, &loc, e))?;
    let gctx = ctx.of_file(&g);
    let step = read_step(&gctx, &g, mesh)?;
    let friction = read_step_friction(&gctx, &g, mesh.contact.points.len())?;
    Ok((step, friction))
}

/// [`append_step_in_place`] with the friction arrays of the step.
pub fn append_step_with_friction_in_place(
    path: &Path,
    index: usize,
    step: &StepOutput,
    friction: &StepFriction,
) -> Result<(), IoError> {
    append_step_in_place(path, index, step)?;
    let ctx = Ctx::writing(path);
    check_friction(&ctx, friction, step.multipliers.len())?;
    let file = File::open_rw(path).map_err(ctx.h5("/"))?;
    {
        let loc = format!("/steps/{}", step_name(index));
        let g = file.group(&loc).map_err(ctx.h5(loc.clone()))?;
        write_friction(&ctx, &g, friction)?;
    }
    file.close().map_err(ctx.h5("/"))
}

/// Refuses friction arrays that are not one value per contact row.
fn check_friction(ctx: &Ctx, friction: &StepFriction, r: usize) -> Result<(), IoError> {
    for (what, got) in [
        ("multipliers_t", friction.multipliers_t.len()),
        ("tangential_traction", friction.tangential_traction.len()),
        ("slip", friction.slip.len()),
        ("state", friction.state.len()),
    ] {
        if got != r {
            return Err(ctx.format(format!(
                "step field {what} has {got} entries, the mesh needs {r}"
            )));
        }
    }
    Ok(())
}

/// The friction arrays in the step group `g`.
fn write_friction(ctx: &Ctx, g: &Group, friction: &StepFriction) -> Result<(), IoError> {
    let r = friction.multipliers_t.len();
    write_ds(ctx, g, "multipliers_t", &[r], &friction.multipliers_t)?;
    write_ds(
        ctx,
        g,
        "tangential_traction",
        &[r],
        &friction.tangential_traction,
    )?;
    write_ds(ctx, g, "slip", &[r], &friction.slip)?;
    write_ds(ctx, g, "state", &[r], &friction.state)
}

/// The friction arrays of the step group `g`, if it has them (all four).
fn read_step_friction(ctx: &Ctx, g: &Group, rows: usize) -> Result<Option<StepFriction>, IoError> {
    if !g.link_exists("multipliers_t") {
        return Ok(None);
    }
    let r = Some(rows);
    let (_, multipliers_t) = read_ds::<f64>(ctx, g, "multipliers_t", None, r)?;
    let (_, tangential_traction) = read_ds::<f64>(ctx, g, "tangential_traction", None, r)?;
    let (_, slip) = read_ds::<f64>(ctx, g, "slip", None, r)?;
    let (_, state) = read_ds::<u8>(ctx, g, "state", None, r)?;
    if let Some(&bad) = state.iter().find(|&&v| v > 2) {
        return Err(ctx.format(format!(
            "{}/state: {bad} is not 0 (open), 1 (stick) or 2 (slip)",
            g.name()
        )));
    }
    Ok(Some(StepFriction {
        multipliers_t,
        tangential_traction,
        slip,
        state,
    }))
}

fn check_step(ctx: &Ctx, s: &StepOutput, n: usize, m: usize, r: usize) -> Result<(), IoError> {
    let lens = [
        ("displacement", s.displacement.len(), n),
        ("stress", s.stress.len(), m),
        ("von_mises", s.von_mises.len(), m),
        ("principal_stress", s.principal.len(), m),
        ("multipliers", s.multipliers.len(), r),
        ("contact_pressure", s.contact_pressure.len(), r),
        ("gap", s.gap.len(), r),
        ("active", s.active.len(), r),
    ];
    let change = s.change.as_ref().map(|c| {
        [
            ("displacement_change", c.displacement.len(), n),
            ("stress_change", c.stress.len(), m),
            ("contact_pressure_change", c.contact_pressure.len(), r),
        ]
    });
    for (what, got, want) in lens.into_iter().chain(change.into_iter().flatten()) {
        if got != want {
            return Err(ctx.format(format!(
                "step field {what} has {got} entries, the mesh needs {want}"
            )));
        }
    }
    Ok(())
}

fn write_step(ctx: &Ctx, g: &Group, s: &StepOutput) -> Result<(), IoError> {
    let n = s.displacement.len();
    let m = s.stress.len();
    let r = s.multipliers.len();
    // Rows of [f64; N] are the row-major [_, N] datasets as they lie in
    // memory: written without a copy.
    write_ds(
        ctx,
        g,
        "displacement",
        &[n, 2],
        s.displacement.as_flattened(),
    )?;
    write_ds(ctx, g, "stress", &[m, 4], s.stress.as_flattened())?;
    write_ds(ctx, g, "von_mises", &[m], &s.von_mises)?;
    write_ds(
        ctx,
        g,
        "principal_stress",
        &[m, 2],
        s.principal.as_flattened(),
    )?;
    write_ds(ctx, g, "multipliers", &[r], &s.multipliers)?;
    write_ds(ctx, g, "contact_pressure", &[r], &s.contact_pressure)?;
    write_ds(ctx, g, "gap", &[r], &s.gap)?;
    write_ds(ctx, g, "active", &[r], &s.active)?;
    if let Some(c) = &s.change {
        write_ds(
            ctx,
            g,
            "displacement_change",
            &[n, 2],
            c.displacement.as_flattened(),
        )?;
        write_ds(ctx, g, "stress_change", &[m, 4], c.stress.as_flattened())?;
        write_ds(ctx, g, "contact_pressure_change", &[r], &c.contact_pressure)?;
        set_attr_scalar(ctx, g, "reference_step", &(c.reference_step as u64))?;
    }

    let i = &s.info;
    set_attr_scalar(ctx, g, "time", &s.time)?;
    set_attr_str(ctx, g, "method", &i.method)?;
    set_attr_str(ctx, g, "preconditioner", &i.preconditioner)?;
    set_attr_scalar(ctx, g, "converged", &u8::from(i.converged))?;
    set_attr_scalar(ctx, g, "iterations", &(i.iterations as u64))?;
    for (name, v) in i.kkt.named() {
        set_attr_scalar(ctx, g, &format!("kkt_{name}"), &v)?;
    }
    for (name, v) in [
        ("energy", i.energy),
        ("time_assemble", i.time_assemble),
        ("time_solve", i.time_solve),
        ("time_total", i.time_total),
    ] {
        set_attr_scalar(ctx, g, name, &v)?;
    }
    Ok(())
}

// ---------------------------------------------------------------- reading

fn parse_step_name(name: &str) -> Option<usize> {
    if !name.is_empty() && name.bytes().all(|b| b.is_ascii_digit()) {
        name.parse().ok()
    } else {
        None
    }
}

fn open_ds(ctx: &Ctx, g: &Group, name: &str) -> Result<::hdf5::Dataset, IoError> {
    let loc = format!("{}/{}", g.name(), name);
    if !g.link_exists(name) {
        return Err(ctx.missing(format!("dataset {loc}")));
    }
    g.dataset(name).map_err(ctx.h5(loc))
}

/// Number of rows (first dimension) of a dataset.
fn dataset_len(ctx: &Ctx, g: &Group, name: &str) -> Result<usize, IoError> {
    let ds = open_ds(ctx, g, name)?;
    Ok(ds.shape().first().copied().unwrap_or(0))
}

/// Reads a dataset of shape `[rows]` (cols = None) or `[rows, cols]`; checks
/// the shape and, when `rows` is given, the row count. Returns (rows, values).
fn read_ds<T: H5Type>(
    ctx: &Ctx,
    g: &Group,
    name: &str,
    cols: Option<usize>,
    rows: Option<usize>,
) -> Result<(usize, Vec<T>), IoError> {
    let loc = format!("{}/{}", g.name(), name);
    let ds = open_ds(ctx, g, name)?;
    let shape = ds.shape();
    let nrows = match (cols, shape.as_slice()) {
        (None, [r]) => *r,
        (Some(c), [r, c2]) if *c2 == c => *r,
        // A zero-row 2-D dataset is also accepted whatever its width.
        (Some(_), [0, _]) => 0,
        _ => {
            return Err(ctx.format(format!(
                "{loc}: shape {shape:?}, expected {}",
                match cols {
                    None => "[rows]".to_string(),
                    Some(c) => format!("[rows, {c}]"),
                }
            )))
        }
    };
    if let Some(want) = rows {
        if nrows != want {
            return Err(ctx.format(format!("{loc}: {nrows} rows, expected {want}")));
        }
    }
    ctx.check_fits(&loc, &shape, std::mem::size_of::<T>())?;
    let data = ds.read_raw::<T>().map_err(ctx.h5(loc.clone()))?;
    let expected = nrows * cols.unwrap_or(1);
    if data.len() != expected {
        return Err(ctx.format(format!("{loc}: {} values, expected {expected}", data.len())));
    }
    Ok((nrows, data))
}

fn pairs<T: Copy>(v: &[T]) -> Vec<[T; 2]> {
    v.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
}

fn to_index(ctx: &Ctx, loc: &str, v: u64, bound: usize) -> Result<usize, IoError> {
    match usize::try_from(v) {
        Ok(i) if i < bound => Ok(i),
        _ => Err(ctx.format(format!("{loc}: index {v} out of range (bound {bound})"))),
    }
}

fn indices(ctx: &Ctx, loc: &str, v: &[u64], bound: usize) -> Result<Vec<usize>, IoError> {
    v.iter().map(|&x| to_index(ctx, loc, x, bound)).collect()
}

fn has_attr(ctx: &Ctx, loc: &Location, name: &str) -> Result<bool, IoError> {
    Ok(loc
        .attr_names()
        .map_err(ctx.h5(loc.name()))?
        .iter()
        .any(|a| a == name))
}

fn get_attr<T: H5Type>(ctx: &Ctx, loc: &Location, name: &str) -> Result<T, IoError> {
    let where_ = format!("{}@{}", loc.name(), name);
    if !has_attr(ctx, loc, name)? {
        return Err(ctx.missing(format!("attribute {where_}")));
    }
    let a = loc.attr(name).map_err(ctx.h5(where_.clone()))?;
    a.read_scalar::<T>().map_err(ctx.h5(where_))
}

fn get_attr_str(ctx: &Ctx, loc: &Location, name: &str) -> Result<String, IoError> {
    Ok(get_attr::<VarLenUnicode>(ctx, loc, name)?
        .as_str()
        .to_string())
}

fn get_attr_str_list(ctx: &Ctx, loc: &Location, name: &str) -> Result<Vec<String>, IoError> {
    let where_ = format!("{}@{}", loc.name(), name);
    if !has_attr(ctx, loc, name)? {
        return Err(ctx.missing(format!("attribute {where_}")));
    }
    let a = loc.attr(name).map_err(ctx.h5(where_.clone()))?;
    // Each string takes at least one byte of the file besides its pointer.
    ctx.check_fits(&where_, &a.shape(), 1)?;
    let v = a.read_raw::<VarLenUnicode>().map_err(ctx.h5(where_))?;
    Ok(v.iter().map(|s| s.as_str().to_string()).collect())
}
