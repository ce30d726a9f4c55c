//! The split layout of a checkpoint with load steps (docs/problem-format.md
//! §6): `NAME_mesh.h5`, one `NAME_NNNN.h5` per step, and `NAME.h5` an index
//! of external links to them.

use super::*;

/// The file of a split checkpoint `NAME.h5` that holds `/mesh`: `NAME_mesh.h5`.
pub fn mesh_file_name(name: &str) -> String {
    format!("{name}_mesh.h5")
}

/// The file of a split checkpoint `NAME.h5` that holds `/steps/NNNN`:
/// `NAME_NNNN.h5` (the stem of the step's VTU).
pub fn step_file_name(name: &str, index: usize) -> String {
    format!("{name}_{}.h5", step_name(index))
}

/// When `file` (at `path`) is one part of a split checkpoint, not its
/// index — no root attributes, only `/mesh` or only `/steps` — the message
/// that names the index to open instead (`NAME.h5` for `NAME_mesh.h5` or
/// `NAME_NNNN.h5`) and the step; None for any other file. Every reader
/// would otherwise fail on the first root attribute it needs, naming it.
pub fn part_of_split(path: &Path, file: &File) -> Option<String> {
    if !file.attr_names().ok()?.is_empty() {
        return None;
    }
    let groups = file.member_names().ok()?;
    let stem = path.file_stem()?.to_str()?;
    let (index, what) = match groups.as_slice() {
        [g] if g == "mesh" => (
            stem.strip_suffix("_mesh")?.to_string(),
            "the mesh".to_string(),
        ),
        [g] if g == "steps" => {
            let (name, step) = stem.rsplit_once('_')?;
            if step.len() != 4 || !step.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            (
                name.to_string(),
                format!("step {}", step.trim_start_matches('0')),
            )
        }
        _ => return None,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    let index = dir.join(format!("{index}.h5"));
    Some(format!(
        "one part of a split checkpoint ({what} of {}), not a checkpoint of its own: give its index {} (`plot --step K` draws one step; docs/problem-format.md §6)",
        index.display(),
        index.display()
    ))
}

/// Writes the mesh file of a split checkpoint at `path` (a new file of a
/// staging directory: the stage fsyncs and renames it): `/mesh` as in the
/// single-file layout.
pub fn write_mesh_file(path: &Path, mesh: &OutMesh) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    check_mesh(&ctx, mesh)?;
    let file = File::create(path).map_err(ctx.h5("/"))?;
    {
        let g = file.create_group("mesh").map_err(ctx.h5("/mesh"))?;
        write_mesh(&ctx, &g, mesh)?;
    }
    file.close().map_err(ctx.h5("/"))
}

/// Writes the file of step `index` (1-based) of a split checkpoint at
/// `path` (a new file of a staging directory): the group `/steps/NNNN` as
/// in the single-file layout, with the friction arrays when given. Sizes
/// are checked against `mesh`.
pub fn write_step_file(
    path: &Path,
    mesh: &OutMesh,
    index: usize,
    step: &StepOutput,
    friction: Option<&StepFriction>,
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    if index == 0 {
        return Err(ctx.format("step indices start at 1"));
    }
    let (n, m, r) = (
        mesh.points.len(),
        mesh.triangles.len(),
        mesh.contact.points.len(),
    );
    check_step(&ctx, step, n, m, r)?;
    if let Some(f) = friction {
        check_friction(&ctx, f, r)?;
    }
    let file = File::create(path).map_err(ctx.h5("/"))?;
    {
        let steps = file.create_group("steps").map_err(ctx.h5("/steps"))?;
        let name = step_name(index);
        let g = steps
            .create_group(&name)
            .map_err(ctx.h5(format!("/steps/{name}")))?;
        write_step(&ctx, &g, step)?;
        if let Some(f) = friction {
            write_friction(&ctx, &g, f)?;
        }
    }
    file.close().map_err(ctx.h5("/"))
}

/// Writes the index `NAME.h5` of a split checkpoint at `path` (a new file
/// of a staging directory): the root attributes `attrs` (strings),
/// `plane_strain`, `axisymmetric` and `last_step` as in the single-file
/// layout, `/mesh` an external link to `/mesh` of `mesh_file`, and
/// `/steps/NNNN` one external link to `/steps/NNNN` of each `(index,
/// file)` of `steps`. File names are relative: HDF5 looks for them in the
/// index's directory first, so the set can be moved as a whole.
pub fn write_index(
    path: &Path,
    mesh: &OutMesh,
    attrs: &[(&str, String)],
    mesh_file: &str,
    steps: &[(usize, String)],
) -> Result<(), IoError> {
    let ctx = Ctx::writing(path);
    for (k, _) in attrs {
        if RESERVED_ROOT_ATTRS.contains(k) {
            return Err(ctx.format(format!("root attribute name {k:?} is reserved")));
        }
    }
    let file = File::create(path).map_err(ctx.h5("/"))?;
    {
        let root: &Group = &file;
        for (k, v) in attrs {
            set_attr_str(&ctx, root, k, v)?;
        }
        super::set_kind_attrs(&ctx, root, mesh.kind, true)?;
        write_links(&ctx, &file, mesh_file, steps)?;
    }
    file.close().map_err(ctx.h5("/"))
}

/// The links of a split checkpoint's index, plane or solid: `/mesh` →
/// `/mesh` of `mesh_file`, `/steps/NNNN` → `/steps/NNNN` of each `(index,
/// file)` of `steps`, and the root's `last_step`.
pub(super) fn write_links(
    ctx: &Ctx,
    file: &File,
    mesh_file: &str,
    steps: &[(usize, String)],
) -> Result<(), IoError> {
    let root: &Group = file;
    root.link_external(mesh_file, "/mesh", "mesh")
        .map_err(ctx.h5("/mesh"))?;
    let g = file.create_group("steps").map_err(ctx.h5("/steps"))?;
    for (index, f) in steps {
        let name = step_name(*index);
        g.link_external(f, &format!("/steps/{name}"), &name)
            .map_err(ctx.h5(format!("/steps/{name}")))?;
    }
    if let Some(last) = steps.iter().map(|s| s.0).max() {
        set_attr_scalar(ctx, root, "last_step", &(last as u64))?;
    }
    Ok(())
}

/// Where the parts of a checkpoint are stored: the file holding `/mesh`
/// and the file of each step group (in index order), as HDF5 resolved
/// them; each is `path` itself in the single-file layout.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CheckpointFiles {
    pub mesh: std::path::PathBuf,
    /// (step index, group name, file).
    pub steps: Vec<(usize, String, std::path::PathBuf)>,
}

/// The [`CheckpointFiles`] of the checkpoint at `path` (no dataset is read).
pub fn checkpoint_files(path: &Path) -> Result<CheckpointFiles, IoError> {
    let ctx = Ctx::writing(path);
    let file = File::open(path).map_err(ctx.h5("/"))?;
    if !file.link_exists("mesh") {
        return Err(ctx.missing("group /mesh"));
    }
    let mesh = file.group("mesh").map_err(ctx.h5("/mesh"))?;
    let mut out = CheckpointFiles {
        mesh: std::path::PathBuf::from(mesh.filename()),
        steps: vec![],
    };
    if let Some((sg, names)) = step_names(&ctx, &file)? {
        for (i, name) in names {
            let g = sg
                .group(&name)
                .map_err(|e| linked(&ctx, &format!("/steps/{name}"), e))?;
            out.steps
                .push((i, name, std::path::PathBuf::from(g.filename())));
        }
    }
    Ok(out)
}

/// The root attributes of a checkpoint as [`pack`] writes them again: the
/// user's strings and the kind's flags (plane, axisymmetric) or `model` =
/// "solid" and `dim` = 3.
enum Root {
    Plane(Vec<(String, String)>, crate::fem::ElementKind),
    Solid(Vec<(String, String)>),
}

/// The inverse of [`pack`] for one part: a new file `dst` (in a staging
/// directory) holding the group `/mesh` (`step` None) or `/steps/NNNN` of
/// the checkpoint `src`, copied as an HDF5 object (bit for bit). A restart
/// that continues a packed checkpoint of a run with steps writes the split
/// layout's mesh and step files this way.
pub fn unpack_part(src: &Path, step: Option<usize>, dst: &Path) -> Result<(), IoError> {
    let rctx = Ctx::writing(src);
    let wctx = Ctx::writing(dst);
    let from = File::open(src).map_err(rctx.h5("/"))?;
    let to = File::create(dst).map_err(wctx.h5("/"))?;
    match step {
        None => {
            let g = from.group("mesh").map_err(|e| linked(&rctx, "/mesh", e))?;
            let root: &Group = &to;
            g.copy_to(root, "mesh").map_err(wctx.h5("/mesh"))?;
        }
        Some(i) => {
            let name = step_name(i);
            let loc = format!("/steps/{name}");
            let g = from.group(&loc).map_err(|e| linked(&rctx, &loc, e))?;
            let steps = to.create_group("steps").map_err(wctx.h5("/steps"))?;
            g.copy_to(&steps, &name).map_err(wctx.h5(loc))?;
        }
    }
    to.close().map_err(wctx.h5("/"))
}

/// What [`pack`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Packed {
    /// The steps copied (their group names, in order).
    pub steps: Vec<String>,
    /// The files of the source read (its index or single file first).
    pub sources: Vec<std::path::PathBuf>,
}

/// Writes the checkpoint `src` (either layout) as one self-contained file
/// `dst`: the root attributes, `/mesh` and every `/steps/NNNN` copied as
/// HDF5 objects (datasets and attributes bit for bit, through the external
/// links of a split checkpoint), atomically. The result is the single-file
/// layout, read by everything that reads a checkpoint. `dst` may not be one
/// of the files `src` reads. The source is read whole first
/// ([`check_checkpoint`], one step at a time): a missing or damaged step file is refused, named,
/// before anything is written.
pub fn pack(src: &Path, dst: &Path) -> Result<Packed, IoError> {
    // Every dataset checked (sizes, indices, finiteness of nothing more),
    // by the reader of the checkpoint's kind.
    let (root, step_groups) = if super::solid_read::is_solid_checkpoint(src) {
        let ck =
            super::solid_read::read_solid_checkpoint(src, super::solid_read::SolidSteps::Checked)?;
        let steps = ck.step_indices.iter().map(|&i| step_name(i)).collect();
        (Root::Solid(ck.attrs), steps)
    } else {
        let ck = super::check_checkpoint(src)?;
        (Root::Plane(ck.attrs, ck.mesh.kind), ck.step_groups)
    };
    let files = checkpoint_files(src)?;
    let mut sources = vec![src.to_path_buf()];
    for f in std::iter::once(&files.mesh).chain(files.steps.iter().map(|s| &s.2)) {
        if !sources.contains(f) {
            sources.push(f.clone());
        }
    }
    let dst_real = dst
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .canonicalize()
        .ok()
        .zip(dst.file_name())
        .map(|(d, n)| d.join(n));
    for f in &sources {
        let same = match (f.canonicalize(), &dst_real) {
            (Ok(a), Some(b)) => a == *b,
            _ => false,
        };
        if same {
            return Err(IoError::format(
                dst,
                format!(
                    "is a file of the checkpoint {} ({}); write the packed file under another name",
                    src.display(),
                    f.display()
                ),
            ));
        }
    }
    let rctx = Ctx::writing(src);
    write_atomic(dst, |tmp| {
        let wctx = Ctx::writing(dst);
        let from = File::open(src).map_err(rctx.h5("/"))?;
        let to = File::create(tmp).map_err(wctx.h5("/"))?;
        {
            let g: &Group = &to;
            match &root {
                Root::Plane(attrs, kind) => {
                    for (k, v) in attrs {
                        set_attr_str(&wctx, g, k, v)?;
                    }
                    super::set_kind_attrs(&wctx, g, *kind, false)?;
                }
                Root::Solid(attrs) => {
                    let attrs: Vec<(&str, String)> =
                        attrs.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
                    super::solid::set_root(&wctx, g, &attrs)?;
                }
            }
            let root = g;
            let mesh = from.group("mesh").map_err(|e| linked(&rctx, "/mesh", e))?;
            mesh.copy_to(root, "mesh").map_err(wctx.h5("/mesh"))?;
            if let Some((sg, names)) = step_names(&rctx, &from)? {
                let steps = to.create_group("steps").map_err(wctx.h5("/steps"))?;
                for (_, name) in &names {
                    let loc = format!("/steps/{name}");
                    let g = sg.group(name).map_err(|e| linked(&rctx, &loc, e))?;
                    g.copy_to(&steps, name).map_err(wctx.h5(loc))?;
                }
                if let Some((last, _)) = names.last() {
                    set_attr_scalar(&wctx, root, "last_step", &(*last as u64))?;
                }
            }
        }
        to.close().map_err(wctx.h5("/"))
    })?;
    Ok(Packed {
        steps: step_groups,
        sources,
    })
}
