//! A 3D model (P1 tetrahedra, no contact yet; issue 45) as a run: the
//! model built by `fem::solid` from the problem file
//! (`fem::solid_input`), solved by the QP driver with the KKT certificate
//! and verdict of 2D ([`Verdict`]), and its outputs — the VTU of the
//! tetrahedra, the HDF5 checkpoint in its 3D layout, the JSON summary —
//! written as one transaction. The plane pipeline ([`super::Run`] and its
//! observers) is not dimension-generic yet: docs/design.md ("Where it
//! stands") lists what is left to fold.

use super::output::{output_paths, Transaction};
use super::steps::{preconditioner_label, Verdict};
use super::summary::{KktSummary, Timings};
use super::RunError;
use crate::fem::element::{ElementKind, Point3, Vector3};
use crate::fem::solid::SolidModel;
use crate::fem::solid_input::{add_point_forces, solid_input};
use crate::mesh::Mesh;
use crate::output::{SolidContactOutput, SolidOutput, StepInfo};
use crate::problem::{num, shorten, Problem};
use crate::qp::{registry, MethodId, SolveOptions};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A 3D problem read and assembled.
pub struct SolidPrepared {
    pub problem: Problem,
    /// FNV-1a 64 of the mesh file's bytes.
    pub mesh_hash: u64,
    pub mesh: Mesh,
    pub model: SolidModel,
    pub t_read: f64,
    pub t_assemble: f64,
}

/// Build the solid model of a problem whose mesh holds tetrahedra
/// (`run::load`); probes are checked against the mesh.
pub(super) fn prepare(
    problem: Problem,
    mesh: Mesh,
    mesh_hash: u64,
    t0: Instant,
) -> Result<SolidPrepared, RunError> {
    let t_read = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let input = solid_input(&problem)?;
    let mut model = crate::fem::solid::build(&mesh, &problem.path, &input)?;
    add_point_forces(&mut model, &mesh, &problem)?;
    check_probes(&problem, &model)?;
    Ok(SolidPrepared {
        problem,
        mesh_hash,
        mesh,
        model,
        t_read,
        t_assemble: t1.elapsed().as_secs_f64(),
    })
}

/// A probe must lie in a tetrahedron or within
/// [`crate::post::PROBE_TOLERANCE`] × its size of one (as in 2D); it
/// reports the node nearest to it.
fn check_probes(problem: &Problem, model: &SolidModel) -> Result<(), RunError> {
    for (name, x) in &problem.file.output.probes {
        let x = x.xyz();
        let (mut best, mut size) = (f64::INFINITY, 0.0);
        for t in &model.tets {
            let p = t.map(|v| model.points[v]);
            let (d, h) = outside(&p, x);
            if d < best {
                (best, size) = (d, h);
            }
            if d == 0.0 {
                break;
            }
        }
        if best > crate::post::PROBE_TOLERANCE * size {
            return Err(RunError::Solver {
                path: problem.path.clone(),
                msg: format!(
                    "[output] probe {}: ({}, {}, {}) lies outside the mesh: {best:.3e} outside the nearest tetrahedron, whose size is {size:.3e}; a probe must lie in a tetrahedron or within {} × its size of it",
                    shorten(name),
                    num(x[0]),
                    num(x[1]),
                    num(x[2]),
                    crate::post::PROBE_TOLERANCE
                ),
            });
        }
    }
    Ok(())
}

/// How far `x` lies outside the tetrahedron `p` (0 inside), measured as
/// the most negative barycentric coordinate times the tetrahedron's size,
/// and that size (its longest edge).
fn outside(p: &[Point3; 4], x: Point3) -> (f64, f64) {
    let sub = |a: Point3, b: Point3| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let det = |a: Vector3, b: Vector3, c: Vector3| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    let (e1, e2, e3) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let r = sub(x, p[0]);
    let v = det(e1, e2, e3);
    let l1 = det(r, e2, e3) / v;
    let l2 = det(e1, r, e3) / v;
    let l3 = det(e1, e2, r) / v;
    let l0 = 1.0 - l1 - l2 - l3;
    let mut h = 0.0f64;
    for i in 0..4 {
        for j in i + 1..4 {
            let d = sub(p[i], p[j]);
            h = h.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
        }
    }
    let worst = [l0, l1, l2, l3].into_iter().fold(0.0f64, f64::min);
    (-worst * h, h)
}

/// A force and its moment about [`MOMENT_POINT`] (3-vectors).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Resultant3 {
    pub force: Vector3,
    pub moment: Vector3,
}

/// The point moments are taken about: the origin, as in 2D.
pub const MOMENT_POINT: Point3 = [0.0; 3];

impl Resultant3 {
    /// Add the force `f` acting at `x`: m += (x − o) × f.
    pub fn add(&mut self, x: Point3, f: Vector3) {
        let r = [0, 1, 2].map(|k| x[k] - MOMENT_POINT[k]);
        for k in 0..3 {
            self.force[k] += f[k];
        }
        self.moment[0] += r[1] * f[2] - r[2] * f[1];
        self.moment[1] += r[2] * f[0] - r[0] * f[2];
        self.moment[2] += r[0] * f[1] - r[1] * f[0];
    }
}

/// The reaction of one physical group carrying `[[dirichlet]]` and/or
/// `[[slip]]` (docs/problem-format.md §7, §12).
#[derive(Debug, Clone, Serialize)]
pub struct GroupReaction3 {
    pub on: String,
    /// "dirichlet", "slip", or "dirichlet+slip".
    pub kind: String,
    /// Nodes the group holds.
    pub points: usize,
    #[serde(flatten)]
    pub resultant: Resultant3,
}

/// One contact interface of a 3D model in the JSON summary.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Interface3 {
    pub rows: usize,
    pub active: usize,
    /// The largest λ / tributary area (N/m²).
    pub max_pressure: f64,
    /// On the slave side, from the master side.
    #[serde(flatten)]
    pub resultant: Resultant3,
}

/// The nearest node to a requested probe and its displacement.
#[derive(Debug, Clone, Serialize)]
pub struct Probe3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub node: usize,
    /// Gmsh node tag.
    pub tag: u64,
    pub u: Vector3,
}

/// `NAME.json` of a 3D model: the keys of the 2D summary that apply
/// without contact, with 3-vectors (docs/problem-format.md §12).
#[derive(Debug, Clone, Serialize)]
pub struct SolidSummary {
    pub problem: String,
    /// "solid".
    pub model: &'static str,
    pub method: String,
    pub preconditioner: String,
    pub ordering: String,
    pub converged: bool,
    pub status: String,
    pub iterations: usize,
    pub inner_iterations: usize,
    pub nodes: usize,
    pub mesh_nodes: usize,
    pub tetrahedra: usize,
    pub bodies: usize,
    pub rigid_modes: usize,
    pub dofs: usize,
    pub constraints: usize,
    pub active: usize,
    pub failed_steps: Vec<usize>,
    pub energy: f64,
    pub strain_energy: f64,
    pub load_work: f64,
    pub kkt: KktSummary,
    /// The point the moments are about.
    pub moment_point: Point3,
    pub loads: Resultant3,
    pub reactions: BTreeMap<String, GroupReaction3>,
    /// Per `[[contact]]` interface (its groups, "/"-joined): rows, active
    /// rows, the largest pressure, and the force the master side exerts
    /// on the slave side with its moment about `moment_point`.
    pub contact: BTreeMap<String, Interface3>,
    pub notes: Vec<String>,
    pub probes: BTreeMap<String, Probe3>,
    #[serde(rename = "timings_s")]
    pub timings: Timings,
}

impl SolidSummary {
    /// Pretty-printed, keys in alphabetical order at every level (as 2D).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(&serde_json::to_value(self)?)
    }
}

/// What a 3D run did.
pub struct SolidOutcome {
    pub summary: SolidSummary,
    pub output: SolidOutput,
    /// The contact surface's values (empty without `[[contact]]`).
    pub contact: SolidContactOutput,
    /// Converged and within the KKT target (exit code 0, else 3).
    pub certified: bool,
    /// The files written: VTU, HDF5, JSON.
    pub files: Vec<PathBuf>,
}

/// Solve a 3D model and write its outputs in `dir` as one transaction;
/// `strict` as `--strict` (the verdict of 2D, [`Verdict::of`]).
pub fn solve_solid(
    prep: &SolidPrepared,
    method: MethodId,
    opts: &SolveOptions,
    strict: bool,
    dir: &Path,
    compress: bool,
    started: Instant,
) -> Result<SolidOutcome, RunError> {
    if let Some(sig) = super::interrupted() {
        return Err(RunError::Interrupted(sig));
    }
    let path = &prep.problem.path;
    let mut tx = Transaction::open(dir, &prep.problem.name)?;
    tx.plan(false, 0, true);
    let t_solve = Instant::now();
    let res = registry::solve(method, &prep.model.qp, opts).map_err(|e| RunError::Solver {
        path: path.clone(),
        msg: format!("{method}: {e}"),
    })?;
    let time_solve = t_solve.elapsed().as_secs_f64();
    let target = opts.settings.kkt_target;
    let verdict = Verdict::of(method, &res, target, strict);
    let t_write = Instant::now();
    let materials = &prep.problem.file.materials;
    let out = crate::post::solid_output(&prep.model, materials, &res.x);
    let contact = contact_output(prep, &out.displacement, &res.lambda, &res.active);
    let forces = forces(prep, &out.displacement, &contact);
    let preconditioner = preconditioner_label(method, opts);
    let ordering = match opts.settings.factor_free(method) {
        Some(why) => format!("none ({why})"),
        None => opts.settings.ordering.name().to_string(),
    };
    let name = &prep.problem.name;
    let files = output_paths(dir, name, None);
    let stage = tx.stage_dir().to_path_buf();
    let staged = |p: &Path| stage.join(p.file_name().unwrap_or_default());
    crate::io::vtu::write_solid_vtu(&staged(&files.vtu), &out, compress)?;
    // The contact VTU of a model with `[[contact]]` (none without).
    let has_contact = !prep.problem.file.contact.is_empty();
    if has_contact {
        crate::io::vtu::write_solid_contact_vtu(&staged(&files.contact_vtu), &contact, compress)?;
    }
    let info = StepInfo {
        method: method.name().to_string(),
        preconditioner: preconditioner.clone(),
        converged: res.status.converged(),
        iterations: res.iterations,
        energy: res.energy,
        kkt: res.kkt,
        time_assemble: prep.t_assemble,
        time_solve,
        time_total: started.elapsed().as_secs_f64(),
    };
    let attrs = [
        ("problem", name.clone()),
        ("toml", prep.problem.text.clone()),
        ("version", env!("CARGO_PKG_VERSION").to_string()),
        ("fingerprint", format!("solid mesh {:016x}", prep.mesh_hash)),
    ];
    let tags: Vec<u64> = prep
        .model
        .point_node
        .iter()
        .map(|&v| prep.mesh.node_tags[v])
        .collect();
    crate::io::hdf5::write_solid_checkpoint(
        &staged(&files.h5),
        &out,
        &contact,
        &tags,
        &attrs,
        prep.problem.file.step_time(0),
        &info,
    )?;
    let certified = verdict.certified();
    let m = &prep.model;
    let mut summary = SolidSummary {
        problem: name.clone(),
        model: ElementKind::Solid.model_name(),
        method: method.name().to_string(),
        preconditioner,
        ordering,
        converged: res.status.converged(),
        status: res.status.describe(),
        iterations: res.iterations,
        inner_iterations: res.inner_iterations,
        nodes: m.points.len(),
        mesh_nodes: prep.mesh.nodes.len(),
        tetrahedra: m.tets.len(),
        bodies: m.nbodies,
        rigid_modes: m.qp.kernel.len(),
        dofs: m.qp.n(),
        constraints: m.qp.m(),
        active: contact.active.iter().filter(|&&a| a).count(),
        contact: forces.interfaces.clone(),
        failed_steps: if certified && res.status.converged() {
            vec![]
        } else {
            vec![1]
        },
        energy: res.energy,
        strain_energy: forces.strain_energy,
        load_work: forces.load_work,
        kkt: KktSummary {
            residuals: res.kkt,
            friction_zero: None,
            target,
            certified,
        },
        moment_point: MOMENT_POINT,
        loads: forces.loads,
        reactions: forces
            .groups
            .into_iter()
            .map(|g| (g.on.clone(), g))
            .collect(),
        notes: res.notes.iter().map(ToString::to_string).collect(),
        probes: probes(prep, &out.displacement),
        timings: Timings {
            read: prep.t_read,
            assemble: prep.t_assemble,
            solve: time_solve,
            write: 0.0,
            total: 0.0,
            phases: res.timings.iter().cloned().collect(),
        },
    };
    summary.timings.write = t_write.elapsed().as_secs_f64();
    summary.timings.total = started.elapsed().as_secs_f64();
    let json = summary
        .to_json()
        .map_err(|e| RunError::Output(format!("{}: {e}", files.json.display())))?;
    crate::io::atomic::write_atomic_bytes(&staged(&files.json), json.as_bytes())?;
    if let Some(sig) = super::interrupted() {
        return Err(RunError::Interrupted(sig));
    }
    let written: Vec<&PathBuf> = [&files.vtu, &files.contact_vtu, &files.h5, &files.json]
        .into_iter()
        .filter(|p| has_contact || *p != &files.contact_vtu)
        .collect();
    let names: Vec<String> = written
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    tx.commit(&names)?;
    tx.finish();
    Ok(SolidOutcome {
        summary,
        output: out,
        certified: certified && res.status.converged(),
        files: written.into_iter().cloned().collect(),
        contact,
    })
}

/// The forces of a solved 3D model (as 2D's `post::forces`, without
/// contact).
struct Forces3 {
    groups: Vec<GroupReaction3>,
    interfaces: BTreeMap<String, Interface3>,
    loads: Resultant3,
    strain_energy: f64,
    load_work: f64,
}

/// Reactions R_p = (K u)_p − f_p at the held nodes, in the directions the
/// conditions fix; a node held by several groups shares its reaction
/// between them by the least-norm split over their condition directions
/// (each direction wholly to the one group that fixes it; equally between
/// groups that fix the same one). Strain energy ½uᵀKu and fᵀu.
fn forces(prep: &SolidPrepared, u: &[Vector3], contact: &SolidContactOutput) -> Forces3 {
    let m = &prep.model;
    // The contact forces on the points, −λ c_p for each row Σ c_p·u_p ≤ g
    // (K u = f + contact + reaction), and each interface's resultant on
    // its slave side.
    let mut fc = vec![[0.0; 3]; m.points.len()];
    let mut interfaces: BTreeMap<String, Interface3> = BTreeMap::new();
    for (r, row) in m.contact.iter().enumerate() {
        let lam = contact.multiplier[r];
        let name = m.interface_names[row.interface as usize].clone();
        let it = interfaces.entry(name).or_default();
        it.rows += 1;
        it.active += usize::from(contact.active[r]);
        it.max_pressure = it.max_pressure.max(contact.pressure[r]);
        let slave_body = m.point_body[row.slave];
        for (p, c) in row.coefficients() {
            let f = c.map(|ck| -lam * ck);
            for k in 0..3 {
                fc[p][k] += f[k];
            }
            if m.point_body[p] == slave_body {
                it.resultant.add(m.points[p], f);
            }
        }
    }
    let kind = ElementKind::Solid;
    let mats: Vec<_> = m
        .material_names
        .iter()
        .map(|n| kind.material(&prep.problem.file.materials[n]))
        .collect();
    let mut fint = vec![[0.0; 3]; m.points.len()];
    let mut strain_energy = 0.0;
    for (t, &mi) in m.tets.iter().zip(&m.tet_material) {
        let k = kind.tet_stiffness(&t.map(|v| m.points[v]), &mats[mi as usize]);
        let ue: [f64; 12] = std::array::from_fn(|i| u[t[i / 3]][i % 3]);
        for i in 0..12 {
            let fi: f64 = (0..12).map(|j| k[i][j] * ue[j]).sum();
            fint[t[i / 3]][i % 3] += fi;
            strain_energy += 0.5 * ue[i] * fi;
        }
    }
    let mut loads = Resultant3::default();
    let mut load_work = 0.0;
    for ((x, f), ui) in m.points.iter().zip(&m.loads).zip(u) {
        loads.add(*x, *f);
        load_work += f[0] * ui[0] + f[1] * ui[1] + f[2] * ui[2];
    }
    // The condition directions of each group at each node.
    let f = &prep.problem.file;
    let mut held: Vec<Vec<(usize, Vector3)>> = vec![vec![]; m.points.len()];
    let mut names: Vec<(String, String)> = vec![];
    let mut group = |on: &str, kind: &str| -> usize {
        match names.iter().position(|(n, _)| n == on) {
            Some(i) => {
                if !names[i].1.contains(kind) {
                    names[i].1 = format!("{}+{kind}", names[i].1);
                }
                i
            }
            None => {
                names.push((on.to_string(), kind.to_string()));
                names.len() - 1
            }
        }
    };
    let mesh = &prep.mesh;
    // The points of each node (one per body on a contact surface).
    let mut node_ptr = vec![0usize; mesh.nodes.len() + 1];
    for &v in &m.point_node {
        node_ptr[v + 1] += 1;
    }
    for v in 0..mesh.nodes.len() {
        node_ptr[v + 1] += node_ptr[v];
    }
    let nodes_of = |on: &str| -> Vec<usize> {
        let Some(g) = mesh.group_any(on) else {
            return vec![];
        };
        let mut v: Vec<usize> = match g.dim {
            0 => g.elements.iter().map(|&e| mesh.points[e]).collect(),
            1 => g.elements.iter().flat_map(|&e| mesh.lines[e]).collect(),
            2 => g.elements.iter().flat_map(|&e| mesh.triangles[e]).collect(),
            _ => g.elements.iter().flat_map(|&e| mesh.tets[e]).collect(),
        };
        v.sort_unstable();
        v.dedup();
        // Every point of those nodes: a condition holds each copy.
        v.iter()
            .flat_map(|&n| node_ptr[n]..node_ptr[n + 1])
            .collect()
    };
    for d in &f.dirichlet {
        let gi = group(&d.on, "dirichlet");
        let comps = d.value.components();
        for v in nodes_of(&d.on) {
            for (k, c) in comps.iter().enumerate() {
                if c.is_some() {
                    let mut r = [0.0; 3];
                    r[k] = 1.0;
                    held[v].push((gi, r));
                }
            }
        }
    }
    for s in &f.slip {
        let gi = group(&s.on, "slip");
        let nodes = nodes_of(&s.on);
        // The plane's normal: the fixed direction the elimination left
        // (the complement of the node's free directions), projected.
        let Some(n) = slip_normal(mesh, &s.on) else {
            continue;
        };
        for v in nodes {
            held[v].push((gi, n));
        }
    }
    let mut groups: Vec<GroupReaction3> = names
        .iter()
        .map(|(on, kind)| GroupReaction3 {
            on: on.clone(),
            kind: kind.clone(),
            points: 0,
            resultant: Resultant3::default(),
        })
        .collect();
    for (p, dirs) in held.iter().enumerate() {
        if dirs.is_empty() {
            continue;
        }
        let r = [0, 1, 2].map(|k| fint[p][k] - m.loads[p][k] - fc[p][k]);
        // α = Mᵀ (M Mᵀ)⁺ r: the least-norm split of r over the directions.
        let mut mmt = vec![vec![0.0; 3]; 3];
        for (_, d) in dirs {
            for i in 0..3 {
                for j in 0..3 {
                    mmt[i][j] += d[i] * d[j];
                }
            }
        }
        let (vals, vecs) = crate::linalg::dense::sym_eigen(&mmt);
        let top = vals.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let mut y = [0.0; 3];
        for (k, &l) in vals.iter().enumerate() {
            if l.abs() > 1e-12 * top {
                let c: f64 = (0..3).map(|i| vecs[i][k] * r[i]).sum::<f64>() / l;
                for i in 0..3 {
                    y[i] += c * vecs[i][k];
                }
            }
        }
        let mut counted: Vec<usize> = vec![];
        for &(g, d) in dirs {
            let a = d[0] * y[0] + d[1] * y[1] + d[2] * y[2];
            groups[g].resultant.add(m.points[p], d.map(|c| a * c));
            if !counted.contains(&g) {
                counted.push(g);
                groups[g].points += 1;
            }
        }
    }
    Forces3 {
        groups,
        interfaces,
        loads,
        strain_energy,
        load_work,
    }
}

/// The unit normal of the plane slip surface `on` (fem::solid has checked
/// that it is plane): its first triangle's.
fn slip_normal(mesh: &Mesh, on: &str) -> Option<Vector3> {
    let g = mesh.group(on, 2)?;
    let t = mesh.triangles[*g.elements.first()?];
    let p = t.map(|v| mesh.node::<3>(v));
    let (_, n) = ElementKind::Solid.facet_weight(&p);
    Some(n)
}

/// Each probe's nearest node and its displacement.
fn probes(prep: &SolidPrepared, u: &[Vector3]) -> BTreeMap<String, Probe3> {
    let pts = &prep.model.points;
    prep.problem
        .file
        .output
        .probes
        .iter()
        .filter(|_| !pts.is_empty())
        .map(|(name, x)| {
            let x = x.xyz();
            let d2 = |p: &Point3| (0..3).map(|k| (p[k] - x[k]).powi(2)).sum::<f64>();
            let node = (0..pts.len())
                .min_by(|&a, &b| d2(&pts[a]).total_cmp(&d2(&pts[b])))
                .unwrap_or(0);
            (
                name.clone(),
                Probe3 {
                    x: pts[node][0],
                    y: pts[node][1],
                    z: pts[node][2],
                    node,
                    tag: prep.mesh.node_tags[prep.model.point_node[node]],
                    u: u[node],
                },
            )
        })
        .collect()
}

/// The contact surface's values (docs/problem-format.md §12): per row its
/// slave point, normal, gaps, λ and λ / area, active; the slave surfaces'
/// triangles on the rows.
fn contact_output(
    prep: &SolidPrepared,
    u: &[Vector3],
    lambda: &[f64],
    active: &[bool],
) -> SolidContactOutput {
    let m = &prep.model;
    let r = m.contact.len();
    let mut multiplier = vec![0.0; r];
    let mut on = vec![false; r];
    for (i, &row) in m.qp_rows.iter().enumerate() {
        multiplier[row] = lambda.get(i).copied().unwrap_or(0.0);
        on[row] = active.get(i).copied().unwrap_or(false);
    }
    let mut c = SolidContactOutput {
        triangles: vec![],
        multiplier,
        active: on,
        ..Default::default()
    };
    for (k, row) in m.contact.iter().enumerate() {
        let moved: f64 = row
            .coefficients()
            .iter()
            .map(|(p, cp)| (0..3).map(|j| cp[j] * u[*p][j]).sum::<f64>())
            .sum();
        c.points.push(m.points[row.slave]);
        c.slave.push(row.slave);
        c.normal.push(row.normal);
        c.interface.push(row.interface);
        c.gap0.push(row.gap0);
        c.gap.push(row.gap0 - moved);
        c.pressure.push(c.multiplier[k] / row.area);
    }
    // Slave-surface triangles: (interface, node) → row.
    let mut row_of: std::collections::HashMap<(u32, usize), usize> =
        std::collections::HashMap::with_capacity(r);
    for (k, row) in m.contact.iter().enumerate() {
        row_of
            .entry((row.interface, m.point_node[row.slave]))
            .or_insert(k);
    }
    let mesh = &prep.mesh;
    for (i, pair) in prep.problem.file.contact.iter().enumerate() {
        let slave = match &pair.pair {
            crate::problem::ContactPair::Conforming { on, .. } => on,
            crate::problem::ContactPair::NonMatching(p) => &p.slave,
        };
        let Some(g) = mesh.group(slave, 2) else {
            continue;
        };
        for &e in &g.elements {
            let t = mesh.triangles[e];
            let rows: Vec<usize> = t
                .iter()
                .filter_map(|&v| row_of.get(&(i as u32, v)).copied())
                .collect();
            if let [a, b, d] = rows[..] {
                c.triangles.push([a, b, d]);
            }
        }
    }
    c
}
