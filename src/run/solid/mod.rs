//! A 3D model (P1 tetrahedra, with or without contact; issue 45) as a run:
//! the model of each load step built by `fem::solid` from the problem file
//! (`fem::solid_input`), solved by the QP driver with the KKT certificate
//! and verdict of 2D ([`super::Verdict`]), and its outputs — the VTU of
//! the tetrahedra, the HDF5 checkpoint in its 3D layout, the JSON summary —
//! written as one transaction ([`solve_solid`]); `--restart` ([`SolidRestart`])
//! and `compare` (`compare.rs`). The plane pipeline ([`super::Run`] and
//! its observers) is not dimension-generic yet: docs/design.md ("Where it
//! stands") lists what is left to fold.

mod compare;
mod forces;
mod nested;
mod restart;
mod steps;

pub use nested::NestedStart;
pub use restart::SolidRestart;
pub use steps::{solve_solid, Reference, SolidRun};

use super::summary::{KktSummary, Timings};
use super::RunError;
use crate::fem::element::{Point3, Vector3};
use crate::fem::solid::SolidModel;
use crate::fem::solid_input::{add_point_forces, solid_input};
use crate::mesh::Mesh;
use crate::output::{SolidContactOutput, SolidOutput};
use crate::problem::{num, shorten, Problem};
use crate::qp::{registry, MethodId, QpResult, SolveOptions, Status};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use forces::probes;

/// A 3D problem read and assembled.
pub struct SolidPrepared {
    pub problem: Problem,
    /// `--no-contact`: every `[[contact]]` was dropped (part of the fingerprint).
    pub no_contact: bool,
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
    no_contact: bool,
) -> Result<SolidPrepared, RunError> {
    let t_read = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    // With [[steps]] the prepared model is step 1's.
    let model = build_step(&problem, &mesh, 0)?;
    check_probes(&problem, &model)?;
    Ok(SolidPrepared {
        problem,
        no_contact,
        mesh_hash,
        mesh,
        model,
        t_read,
        t_assemble: t1.elapsed().as_secs_f64(),
    })
}

impl SolidPrepared {
    /// The problem's fingerprint (docs/problem-format.md §6): the mesh
    /// file's hash and each part of the TOML that defines the answer, as
    /// 2D's; a restart must match it.
    pub fn fingerprint(&self) -> String {
        super::prepare::fingerprint_of(self.mesh_hash, &self.problem.text, self.no_contact, |_| {})
    }
}

/// The model of load step `s` (0-based; the problem as written without
/// `[[steps]]`): the step's loads and prescribed displacements on the same
/// mesh, points and contact rows, so that C and the DOF numbering are those
/// of every step (a workspace's factor serves them all, docs/methods.md
/// §8.5).
fn build_step(problem: &Problem, mesh: &Mesh, s: usize) -> Result<SolidModel, RunError> {
    build_file(problem, mesh, &problem.file.at_step(s))
}

/// The model of `file`: the problem's own, or one of its load steps'.
fn build_file(
    problem: &Problem,
    mesh: &Mesh,
    file: &crate::problem::ProblemFile,
) -> Result<SolidModel, RunError> {
    let input = solid_input(file);
    let mut model = crate::fem::solid::build(mesh, &problem.path, &input)?;
    add_point_forces(&mut model, mesh, &problem.path, &file.force)?;
    Ok(model)
}

/// The model of the problem as written, its loads at factor 1 and no step
/// applied (what `export` writes, as in 2D): the prepared one without
/// `[[steps]]`.
pub(super) fn written_model(
    prep: &SolidPrepared,
) -> Result<std::borrow::Cow<'_, SolidModel>, RunError> {
    if prep.problem.file.steps.is_empty() {
        return Ok(std::borrow::Cow::Borrowed(&prep.model));
    }
    let m = build_file(&prep.problem, &prep.mesh, &prep.problem.file)?;
    Ok(std::borrow::Cow::Owned(m))
}

/// The model of step `s`: the prepared one for the first (or only) step.
pub(super) fn step_model(
    prep: &SolidPrepared,
    s: usize,
) -> Result<std::borrow::Cow<'_, SolidModel>, RunError> {
    if s == 0 {
        return Ok(std::borrow::Cow::Borrowed(&prep.model));
    }
    let m = build_step(&prep.problem, &prep.mesh, s)?;
    Ok(std::borrow::Cow::Owned(m))
}

/// Solve `model` by `method` with the factorizations kept in `ws`; an
/// unbounded problem (a verified recession direction, docs/methods.md
/// §1.7) is bad input naming the bodies that move.
pub(super) fn solve_in(
    prep: &SolidPrepared,
    model: &SolidModel,
    method: MethodId,
    opts: &SolveOptions,
    ws: &crate::linalg::cholesky::Workspace,
) -> Result<QpResult, RunError> {
    let bad = |msg: String| RunError::Solver {
        path: prep.problem.path.clone(),
        msg,
    };
    let res = registry::solve_in(method, &model.qp, opts, ws)
        .map_err(|e| bad(format!("{method}: {e}")))?;
    if let Status::Unbounded { direction } = &res.status {
        let u = model.displacements(direction);
        let work = crate::linalg::sparse::dot(&model.qp.d, direction);
        return Err(bad(crate::run::unbounded_message(
            &model.qp,
            direction,
            &moving_bodies(model, &u),
            work,
            "§12.3",
        )));
    }
    Ok(res)
}

/// The bodies a motion `u` moves (by more than 10⁻³ of its largest
/// displacement), each named by its physical volumes.
fn moving_bodies(model: &SolidModel, u: &[Vector3]) -> String {
    let norm = |v: &Vector3| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let umax = u.iter().map(norm).fold(0.0f64, f64::max);
    let mut moves = vec![false; model.nbodies];
    for (p, v) in u.iter().enumerate() {
        if norm(v) > 1e-3 * umax {
            moves[model.point_body[p] as usize] = true;
        }
    }
    let mut names: Vec<Vec<&str>> = vec![vec![]; model.nbodies];
    for (t, &mi) in model.tets.iter().zip(&model.tet_material) {
        let b = model.point_body[t[0]] as usize;
        let name = model.material_names[mi as usize].as_str();
        if !names[b].contains(&name) {
            names[b].push(name);
        }
    }
    let parts: Vec<String> = (0..model.nbodies)
        .filter(|&b| moves[b])
        .map(|b| format!("the body of volume(s) \"{}\"", names[b].join("\", \"")))
        .collect();
    if parts.is_empty() {
        "no body".into()
    } else {
        parts.join(", ")
    }
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
    /// On the slave side, from the master side (normal and tangential
    /// forces).
    #[serde(flatten)]
    pub resultant: Resultant3,
    /// With friction: the rows in contact that stick, and that slip.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stick: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip: Option<usize>,
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
    /// With `[[steps]]`: one row per step (docs/problem-format.md §7).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub steps: Vec<super::StepRow>,
    /// `[output] reference_step`: the step the `*_change` fields refer to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_step: Option<usize>,
    /// `--start-from`: the coarser mesh's checkpoint each step started
    /// from (docs/methods.md §7.2, "The nested start").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_from: Option<String>,
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
