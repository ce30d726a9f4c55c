//! Reading the plane and axisymmetric checkpoint (the layout of the
//! module's documentation, either file layout) into [`Checkpoint`]: the root
//! attributes and the kind, `/mesh`, and every `/steps/NNNN` with its
//! friction arrays; [`check_checkpoint`] reads and checks every step
//! without keeping them. Every read is bounded by the file.

use super::*;

/// Reads a checkpoint: the mesh, every step (in index order) and the string
/// root attributes. A file without `/steps` gives zero steps; a file without
/// `/mesh` or with a missing dataset is rejected, naming the missing path.
pub fn read_checkpoint(path: &Path) -> Result<Checkpoint, IoError> {
    read_checkpoint_keeping(path, true)
}

/// [`read_checkpoint`] that checks every step, one at a time, and keeps
/// none (`steps` and `friction` empty, `step_groups` every group): the
/// whole file verified without holding its steps (`pack`).
pub fn check_checkpoint(path: &Path) -> Result<Checkpoint, IoError> {
    read_checkpoint_keeping(path, false)
}

fn read_checkpoint_keeping(path: &Path, keep: bool) -> Result<Checkpoint, IoError> {
    let (ctx, file) = open_checkpoint(path)?;
    // A 3D checkpoint (write_solid_checkpoint) has another layout, read
    // by `read_solid_checkpoint` (issue 45).
    let solid = file
        .attr("model")
        .and_then(|a| a.read_scalar::<VarLenUnicode>())
        .is_ok_and(|m| m.as_str() == crate::fem::ElementKind::Solid.model_name());
    if solid {
        return Err(ctx.format(
            "a 3D (solid) checkpoint: `signorini plot`, `pack`, a 3D problem's --restart and h5py read it (docs/problem-format.md §6), not this command",
        ));
    }

    let mut attrs = Vec::new();
    for name in file.attr_names().map_err(ctx.h5("/"))? {
        if RESERVED_ROOT_ATTRS.contains(&name.as_str()) {
            continue;
        }
        // Only string attributes are user attributes; skip anything else.
        if let Ok(a) = file.attr(&name) {
            if let Ok(v) = a.read_scalar::<VarLenUnicode>() {
                attrs.push((name, v.as_str().to_string()));
            }
        }
    }
    // The kind from the root flags (`model` is for other readers).
    let kind = crate::fem::ElementKind::from_file_flags(
        get_attr::<u8>(&ctx, &file, "plane_strain")? != 0,
        has_attr(&ctx, &file, "axisymmetric")? && get_attr::<u8>(&ctx, &file, "axisymmetric")? != 0,
    );

    if !file.link_exists("mesh") {
        return Err(ctx.missing("group /mesh"));
    }
    let g = file.group("mesh").map_err(|e| linked(&ctx, "/mesh", e))?;
    let mut mesh = read_mesh(&ctx.of_file(&g), &g)?;
    mesh.kind = kind;

    let mut steps = Vec::new();
    let mut friction = Vec::new();
    let mut step_groups = Vec::new();
    if let Some((sg, names)) = step_names(&ctx, &file)? {
        for (_, name) in names {
            let g = sg
                .group(&name)
                .map_err(|e| linked(&ctx, &format!("/steps/{name}"), e))?;
            let gctx = ctx.of_file(&g);
            let step = read_step(&gctx, &g, &mesh)?;
            let fr = read_step_friction(&gctx, &g, mesh.contact.points.len())?;
            if keep {
                steps.push(step);
                friction.push(fr);
            }
            step_groups.push(name);
        }
    }
    Ok(Checkpoint {
        mesh,
        steps,
        step_groups,
        friction,
        attrs,
    })
}

pub(super) fn read_mesh(ctx: &Ctx, g: &Group) -> Result<OutMesh, IoError> {
    let (n, nodes) = read_ds::<f64>(ctx, g, "nodes", Some(2), None)?;
    let (_, point_tags) = read_ds::<u64>(ctx, g, "node_tags", None, Some(n))?;
    let (_, point_body) = read_ds::<u32>(ctx, g, "body", None, Some(n))?;
    let (m, tri) = read_ds::<u64>(ctx, g, "triangles", Some(3), None)?;
    let tri = indices(ctx, "/mesh/triangles", &tri, n)?;
    let triangles = tri.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let (_, material) = read_ds::<u32>(ctx, g, "material", None, Some(m))?;
    let material_names = get_attr_str_list(ctx, g, "material_names")?;

    let (r, cpoints) = read_ds::<f64>(ctx, g, "contact_points", Some(2), None)?;
    let (_, first) = read_ds::<u64>(ctx, g, "contact_first", None, Some(r))?;
    let first = indices(ctx, "/mesh/contact_first", &first, n)?;
    let (_, second) = read_ds::<u64>(ctx, g, "contact_second", Some(2), Some(r))?;
    let second = indices(ctx, "/mesh/contact_second", &second, n)?;
    let (_, weights) = read_ds::<f64>(ctx, g, "contact_weights", Some(2), Some(r))?;
    let (_, normal) = read_ds::<f64>(ctx, g, "contact_normal", Some(2), Some(r))?;
    let (_, gap0) = read_ds::<f64>(ctx, g, "contact_gap0", None, Some(r))?;
    let (_, interface) = read_ds::<u32>(ctx, g, "contact_interface", None, Some(r))?;
    let (_, seg) = read_ds::<u64>(ctx, g, "contact_segments", Some(2), None)?;
    let seg = indices(ctx, "/mesh/contact_segments", &seg, r)?;
    let interface_names = get_attr_str_list(ctx, g, "interface_names")?;
    let interface_discretizations = if has_attr(ctx, g, "interface_discretizations")? {
        get_attr_str_list(ctx, g, "interface_discretizations")?
    } else {
        vec![]
    };

    let second = second
        .chunks_exact(2)
        .zip(weights.chunks_exact(2))
        .map(|(i, w)| [(i[0], w[0]), (i[1], w[1])])
        .collect();
    Ok(OutMesh {
        points: pairs(&nodes),
        point_tags,
        point_body,
        triangles,
        material,
        material_names,
        kind: crate::fem::ElementKind::from_file_flags(false, false),
        contact: ContactGeometry {
            points: pairs(&cpoints),
            first,
            second,
            normal: pairs(&normal),
            gap0,
            segments: pairs(&seg),
            // The checkpoint keeps no row kind: a non-matching interface is
            // named "slave->master" (fem::topology).
            nonmatching: interface
                .iter()
                .map(|&i| {
                    interface_names
                        .get(i as usize)
                        .is_some_and(|n| n.contains("->"))
                })
                .collect(),
            interface,
            interface_names,
            interface_discretizations,
        },
    })
}

pub(super) fn read_step(ctx: &Ctx, g: &Group, mesh: &OutMesh) -> Result<StepOutput, IoError> {
    let n = Some(mesh.points.len());
    let m = Some(mesh.triangles.len());
    let r = Some(mesh.contact.points.len());
    let (_, displacement) = read_ds::<f64>(ctx, g, "displacement", Some(2), n)?;
    let (_, stress) = read_ds::<f64>(ctx, g, "stress", Some(4), m)?;
    let (_, von_mises) = read_ds::<f64>(ctx, g, "von_mises", None, m)?;
    let (_, principal) = read_ds::<f64>(ctx, g, "principal_stress", Some(2), m)?;
    let (_, multipliers) = read_ds::<f64>(ctx, g, "multipliers", None, r)?;
    let (_, contact_pressure) = read_ds::<f64>(ctx, g, "contact_pressure", None, r)?;
    let (_, gap) = read_ds::<f64>(ctx, g, "gap", None, r)?;
    let (_, active) = read_ds::<u8>(ctx, g, "active", None, r)?;
    let change = if g.link_exists("displacement_change") {
        let (_, du) = read_ds::<f64>(ctx, g, "displacement_change", Some(2), n)?;
        let (_, ds) = read_ds::<f64>(ctx, g, "stress_change", Some(4), m)?;
        let (_, dp) = read_ds::<f64>(ctx, g, "contact_pressure_change", None, r)?;
        let k = get_attr::<u64>(ctx, g, "reference_step")?;
        Some(Change {
            reference_step: usize::try_from(k)
                .map_err(|_| ctx.format(format!("{}@reference_step: {k} too large", g.name())))?,
            displacement: pairs(&du),
            stress: ds
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            contact_pressure: dp,
        })
    } else {
        None
    };

    let info = read_step_info(ctx, g)?;
    Ok(StepOutput {
        time: get_attr(ctx, g, "time")?,
        displacement: pairs(&displacement),
        stress: stress
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        von_mises,
        principal: pairs(&principal),
        multipliers,
        contact_pressure,
        gap,
        active,
        reaction: vec![],
        info,
        change,
    })
}

/// The solver record of the step group `g` (its attributes).
pub(super) fn read_step_info(ctx: &Ctx, g: &Group) -> Result<StepInfo, IoError> {
    let iterations = get_attr::<u64>(ctx, g, "iterations")?;
    // Every residual of the certificate; checkpoints written before all
    // were kept have the first four only (the others read as 0).
    let mut kkt = crate::qp::Kkt::default();
    for (k, (name, _)) in kkt.named().into_iter().enumerate() {
        let attr = format!("kkt_{name}");
        if k < 4 || has_attr(ctx, g, &attr)? {
            kkt.set(name, get_attr(ctx, g, &attr)?);
        }
    }
    let info = StepInfo {
        method: get_attr_str(ctx, g, "method")?,
        preconditioner: get_attr_str(ctx, g, "preconditioner")?,
        converged: get_attr::<u8>(ctx, g, "converged")? != 0,
        iterations: usize::try_from(iterations)
            .map_err(|_| ctx.format(format!("{}@iterations: {iterations} too large", g.name())))?,
        energy: get_attr(ctx, g, "energy")?,
        kkt,
        time_assemble: get_attr(ctx, g, "time_assemble")?,
        time_solve: get_attr(ctx, g, "time_solve")?,
        time_total: get_attr(ctx, g, "time_total")?,
    };
    Ok(info)
}
