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
        set_attr_scalar(&ctx, root, "plane_strain", &u8::from(mesh.plane_strain))?;
        set_attr_str(&ctx, root, "model", super::model_kind(mesh))?;
        if mesh.axisymmetric {
            set_attr_scalar(&ctx, root, "axisymmetric", &1u8)?;
        }
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
