//! Reading and assembling a problem (docs/problem-format.md §1–§2): the
//! TOML and the mesh become a [`Prepared`] (a [`Model`] holding the QP),
//! checked for contact curves without elements and probes off the mesh.
//! Also the pieces every step needs: the model of load step `s`, the warm
//! start of the previous step, the checkpoint's fingerprint, the solver
//! choice ([`options`]) and the solve with its unbounded-problem message.

use super::RunError;
use crate::fem::{self, Model};
use crate::linalg::cholesky::Workspace;
use crate::mesh::{self, Mesh};
use crate::post;
use crate::problem::Problem;
use crate::qp::registry::{self, MethodRef};
use crate::qp::{MethodChoice, MethodId, QpResult, Settings, SolveOptions, SolverSection, Status};
use std::path::Path;
use std::time::Instant;

/// A problem read and assembled.
pub struct Prepared {
    pub problem: Problem,
    /// FNV-1a 64 of the mesh file's bytes (part of the checkpoint's fingerprint).
    pub mesh_hash: u64,
    pub mesh: Mesh,
    pub model: Model,
    /// `--no-contact`: every `[[contact]]` was dropped (part of the fingerprint).
    pub no_contact: bool,
    /// How the models of this problem are built (also each load step's).
    pub build: fem::BuildOptions,
    pub t_read: f64,
    pub t_assemble: f64,
}

/// Read the TOML and the mesh, build the QP. `no_contact` drops every `[[contact]]`.
pub fn prepare(path: &Path, no_contact: bool) -> Result<Prepared, RunError> {
    prepare_with(path, no_contact, &fem::BuildOptions::default())
}

/// [`prepare`] with the options of `fem::build_with`.
pub fn prepare_with(
    path: &Path,
    no_contact: bool,
    build: &fem::BuildOptions,
) -> Result<Prepared, RunError> {
    let (problem, mesh, mesh_hash, t0) = read(path, no_contact)?;
    plane(problem, mesh, mesh_hash, t0, no_contact, build)
}

/// What [`load`] read: a plane or axisymmetric model (triangles), or a
/// solid one (tetrahedra).
pub enum Loaded {
    Plane(Box<Prepared>),
    Solid(Box<super::solid::SolidPrepared>),
}

/// Read the TOML and the mesh and build the model of the mesh's
/// dimension: the one place where a run branches on it (docs/design.md,
/// "Where it stands").
pub fn load(path: &Path, no_contact: bool, build: &fem::BuildOptions) -> Result<Loaded, RunError> {
    let (problem, mesh, mesh_hash, t0) = read(path, no_contact)?;
    if mesh.dim() == 3 {
        let p = super::solid::prepare(problem, mesh, mesh_hash, t0, no_contact)?;
        return Ok(Loaded::Solid(Box::new(p)));
    }
    Ok(Loaded::Plane(Box::new(plane(
        problem, mesh, mesh_hash, t0, no_contact, build,
    )?)))
}

/// The problem file and its mesh, the vector keys held against the mesh's
/// dimension; the mesh file's hash and when the reading began.
fn read(path: &Path, no_contact: bool) -> Result<(Problem, Mesh, u64, Instant), RunError> {
    let t0 = Instant::now();
    let mut problem = Problem::load(path)?;
    if no_contact {
        problem.file.contact.clear();
    }
    let mesh_path = problem.mesh_path();
    let bytes = mesh::gmsh::read_mesh_bytes(&mesh_path)?;
    let mesh_hash = fnv1a(&bytes);
    let mesh = mesh::gmsh::parse_msh(&mesh_path, &bytes)?;
    drop(bytes);
    problem.check_dimension(mesh.dim())?;
    Ok((problem, mesh, mesh_hash, t0))
}

/// The plane (or axisymmetric) model of a problem read by [`read`].
fn plane(
    problem: Problem,
    mesh: Mesh,
    mesh_hash: u64,
    t0: Instant,
    no_contact: bool,
    build: &fem::BuildOptions,
) -> Result<Prepared, RunError> {
    check_contact_groups(&problem, &mesh)?;
    let t_read = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let model = fem::build_with(&mesh, &problem, build)?;
    check_probes(&problem, &model)?;
    Ok(Prepared {
        problem,
        mesh_hash,
        mesh,
        model,
        no_contact,
        build: *build,
        t_read,
        t_assemble: t1.elapsed().as_secs_f64(),
    })
}

/// FNV-1a, 64 bits: a fingerprint, not a defence against a forger (the
/// checkpoint is the user's own file; this catches the wrong file).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// A contact curve that exists but holds no segment would give no
/// constraint at all: the bodies would pass through each other unnoticed.
fn check_contact_groups(problem: &Problem, mesh: &Mesh) -> Result<(), RunError> {
    for (i, c) in problem.file.contact.iter().enumerate() {
        for name in c.groups() {
            if let Some(g) = mesh.group_any(name) {
                if g.elements.is_empty() {
                    return Err(RunError::Solver {
                        path: problem.path.clone(),
                        msg: format!(
                            "[[contact]] #{}: the physical group \"{}\" in {} has no elements, so it would give no contact constraint",
                            i + 1,
                            crate::problem::shorten(name),
                            mesh.path.display()
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

/// Every probe must lie in the mesh: in a triangle, or within
/// [`post::PROBE_TOLERANCE`] × that triangle's size of it (a point on the
/// boundary, or just past a curved one that the mesh's chords cut). It then
/// reports the output point nearest to it ([`probes`]).
fn check_probes(problem: &Problem, model: &Model) -> Result<(), RunError> {
    let topo = &model.topo;
    if topo.points.is_empty() || problem.file.output.probes.is_empty() {
        return Ok(());
    }
    use crate::problem::num;
    for (name, x) in &problem.file.output.probes {
        let Some(at) = post::locate(&topo.points, &topo.triangles, x.xy()) else {
            continue;
        };
        if !at.inside() {
            let tri = topo.triangles[at.triangle];
            return Err(RunError::Solver {
                path: problem.path.clone(),
                msg: format!(
                    "[output] probe {}: ({}, {}) lies outside the mesh: {:.3e} from the nearest triangle (points {}, {}, {}), whose size is {:.3e}; a probe must lie in a triangle or within {} × its size of it",
                    crate::problem::shorten(name),
                    num(x.xy()[0]),
                    num(x.xy()[1]),
                    at.distance,
                    tri[0],
                    tri[1],
                    tri[2],
                    at.size,
                    post::PROBE_TOLERANCE
                ),
            });
        }
    }
    Ok(())
}

/// The fingerprint of the problem stored in the checkpoint: one FNV-1a hash
/// per part that fixes the sequence of load steps, as `part=hex` pairs
/// joined by `;`. The parts are the mesh file's bytes and each top-level
/// table of the TOML except `[mesh]` (its path), `[solver]` and `[output]`
/// (they change how, not what, is solved), normalised by re-serialising, plus
/// `--no-contact`. A restart compares part by part and names what differs.
/// `[output] reference_step` is not a part: a restart checks it against the
/// checkpoint's change fields instead (`run::Restart`), so that adding one
/// after the steps a checkpoint holds is continued, not refused.
pub fn fingerprint(prep: &Prepared, no_contact: bool) -> String {
    fingerprint_as(prep, no_contact, false)
}

/// The fingerprint a checkpoint of this problem carries if it was written
/// before mortar became the default of a non-matching pair, when a pair
/// without `discretization` had node-to-segment rows: the pairs that run
/// node-to-segment rows hashed without the key. None when no pair does.
/// A restart accepts either (`run::Restart`).
pub fn fingerprint_before_mortar(prep: &Prepared, no_contact: bool) -> Option<String> {
    let nts = crate::fem::topology::RowKind::NonMatching;
    prep.model
        .topo
        .interface_kinds
        .contains(&nts)
        .then(|| fingerprint_as(prep, no_contact, true))
}

fn fingerprint_as(prep: &Prepared, no_contact: bool, before_mortar: bool) -> String {
    fingerprint_of(prep.mesh_hash, &prep.problem.text, no_contact, |entries| {
        with_discretization(entries, &prep.model.topo, before_mortar)
    })
}

/// The fingerprint of a problem whose mesh file hashes to `mesh_hash` and
/// whose TOML is `text`: FNV-1a of each part that defines the answer
/// (docs/problem-format.md §6); `contact` may rewrite the `[[contact]]`
/// entries first (the rows a default stands for).
pub(super) fn fingerprint_of(
    mesh_hash: u64,
    text: &str,
    no_contact: bool,
    mut contact: impl FnMut(&mut [toml::Value]),
) -> String {
    let mut parts = vec![("mesh".to_string(), mesh_hash)];
    let table: toml::Table = toml::from_str(text).unwrap_or_default();
    for key in [
        "model",
        "materials",
        "dirichlet",
        "traction",
        "slip",
        "force",
        "contact",
        "steps",
    ] {
        // `[model] units` only names the units (labels): not a part.
        let mut value = table.get(key).map(|v| {
            let mut v = v.clone();
            if let (true, Some(t)) = (key == "model", v.as_table_mut()) {
                t.remove("units");
            }
            v
        });
        if key == "contact" {
            if let Some(toml::Value::Array(entries)) = value.as_mut() {
                contact(entries);
            }
        }
        let text = value
            .map(|v| toml::to_string(&toml::Table::from_iter([(key.to_string(), v)])))
            .and_then(Result::ok)
            .unwrap_or_default();
        parts.push((key.to_string(), fnv1a(text.as_bytes())));
    }
    parts.push(("no_contact".to_string(), u64::from(no_contact)));
    parts
        .iter()
        .map(|(k, h)| format!("{k}={h:016x}"))
        .collect::<Vec<_>>()
        .join(";")
}

/// The `[[contact]]` entries as the fingerprint sees them: a non-matching
/// pair (`slave`, `master`) without `discretization` gets the rows it was
/// built with written out (`topo.interface_kinds`: mortar, or nts for a
/// much stiffer slave), so that it hashes as those rows do, the same as the
/// key written by hand, and a checkpoint of node-to-segment rows, the
/// default before, is refused rather than continued with other rows.
fn with_discretization(
    entries: &mut [toml::Value],
    topo: &crate::fem::Topology,
    before_mortar: bool,
) {
    // Interfaces: the conforming pairs first, then the non-matching ones,
    // each in the order of the entries (fem::topology, fem::pairs).
    let conforming = entries
        .iter()
        .filter(|e| e.as_table().is_some_and(|t| !t.contains_key("slave")))
        .count();
    let mut k = conforming;
    for e in entries {
        let toml::Value::Table(t) = e else { continue };
        if !t.contains_key("slave") {
            continue;
        }
        if let Some(&kind) = topo.interface_kinds.get(k) {
            let nts = kind == crate::fem::topology::RowKind::NonMatching;
            if before_mortar && nts {
                // Written as the default of its time.
                t.remove("discretization");
            } else if !t.contains_key("discretization") {
                let name = kind.discretization().to_string();
                t.insert("discretization".into(), toml::Value::String(name));
            }
        }
        k += 1;
    }
}

/// Whether the problem has a non-matching pair without `discretization`
/// (mortar by default; node-to-segment before): the hint of a refused
/// restart whose contact part differs.
pub(super) fn has_default_discretization(prep: &Prepared) -> bool {
    let table: toml::Table = toml::from_str(&prep.problem.text).unwrap_or_default();
    table
        .get("contact")
        .and_then(toml::Value::as_array)
        .is_some_and(|entries| {
            entries.iter().any(|e| {
                e.as_table()
                    .is_some_and(|t| t.contains_key("slave") && !t.contains_key("discretization"))
            })
        })
}

/// The parts of two fingerprints that differ (names; `all` if one is malformed).
pub fn fingerprint_diff(a: &str, b: &str) -> Vec<String> {
    let parse = |s: &str| -> Option<Vec<(String, String)>> {
        s.split(';')
            .map(|p| {
                p.split_once('=')
                    .map(|(k, v)| (k.to_string(), v.to_string()))
            })
            .collect()
    };
    match (parse(a), parse(b)) {
        (Some(x), Some(y)) if x.len() == y.len() => x
            .iter()
            .zip(&y)
            .filter(|(p, q)| p != q)
            .map(|(p, q)| {
                if p.0 == q.0 {
                    p.0.clone()
                } else {
                    format!("{}/{}", p.0, q.0)
                }
            })
            .collect(),
        _ if a == b => vec![],
        _ => vec!["all".to_string()],
    }
}

/// The model of load step `s` (0-based): the same mesh and DOF numbering,
/// with loads and prescribed displacements of that step. C, A and the
/// elimination are the prepared model's; only d, g and u0 are computed
/// again ([`fem::step_model`], the same bits as a full build).
pub fn step_model(prep: &Prepared, s: usize) -> Result<Model, RunError> {
    step_model_reusing(prep, s, None)
}

/// [`step_model`] made from the model `prev` of an earlier step (given up):
/// C is not copied again ([`fem::step_model_reusing`]).
pub fn step_model_reusing(
    prep: &Prepared,
    s: usize,
    prev: Option<Model>,
) -> Result<Model, RunError> {
    let mut p = prep.problem.clone();
    p.file = prep.problem.file.at_step(s);
    Ok(fem::step_model_reusing(
        &prep.model,
        prev,
        &prep.mesh,
        &p,
        &prep.build,
    )?)
}

/// Reduced unknowns ξ = Tᵀ(u − u0) of point displacements `u` (a warm
/// start; [`crate::fem::Discrete::reduce`]).
pub fn reduce(model: &Model, u: &[[f64; 2]]) -> Vec<f64> {
    crate::fem::Discrete::reduce(model, u)
}

/// The QP rows' flags of per-contact-row `active` flags (a working-set
/// warm start); None if they are not this model's rows.
pub fn reduce_active(model: &Model, active: &[u8]) -> Option<Vec<bool>> {
    let rows = &model.qp_rows;
    rows.iter()
        .map(|&r| active.get(r).map(|a| *a != 0))
        .collect::<Option<Vec<bool>>>()
        .filter(|_| active.len() == model.topo.contact.len())
}

/// The QP rows' values of per-contact-row `values` (a multiplier warm
/// start); None if they are not this model's rows.
pub fn reduce_rows(model: &Model, values: &[f64]) -> Option<Vec<f64>> {
    (values.len() == model.topo.contact.len())
        .then(|| {
            model
                .qp_rows
                .iter()
                .map(|&r| values.get(r).copied())
                .collect()
        })
        .flatten()
}

/// The method and the options of a solve: the problem's `[solver]` with
/// `flags` (the command line) laid over it, validated once
/// ([`Settings::from_section`]).
pub fn options(
    problem: &Problem,
    flags: &SolverSection,
) -> Result<(MethodId, SolveOptions), RunError> {
    let bad = |msg: String| RunError::Solver {
        path: problem.path.clone(),
        msg,
    };
    let s = problem.file.solver.overlay(flags);
    let method = s.method.unwrap_or(MethodChoice::Auto).resolve();
    let settings = Settings::from_section(&s).map_err(bad)?;
    for key in s.unused_by(method) {
        log::warn!(
            "{}: [solver] {key} does not apply to method {method}; it is ignored",
            problem.path.display()
        );
    }
    Ok((method, SolveOptions::new(settings)))
}

/// Run the method; an unbounded problem is bad input naming the bodies.
pub fn solve(
    prep: &Prepared,
    method: impl MethodRef,
    opts: &SolveOptions,
) -> Result<QpResult, RunError> {
    solve_model(prep, &prep.model, method, opts)
}

/// [`solve`] for the model of a load step.
pub fn solve_model(
    prep: &Prepared,
    model: &Model,
    method: impl MethodRef,
    opts: &SolveOptions,
) -> Result<QpResult, RunError> {
    solve_model_in(prep, model, method, opts, &opts.settings.workspace())
}

/// [`solve_model`] reusing the factorizations kept in `ws` (load steps:
/// C is the same in every step, docs/methods.md §8.5).
pub fn solve_model_in(
    prep: &Prepared,
    model: &Model,
    method: impl MethodRef,
    opts: &SolveOptions,
    ws: &Workspace,
) -> Result<QpResult, RunError> {
    let bad = |msg: String| RunError::Solver {
        path: prep.problem.path.clone(),
        msg,
    };
    let method = method.to_id().map_err(|e| bad(e.to_string()))?;
    let res = registry::solve_in(method, &model.qp, opts, ws)
        .map_err(|e| bad(format!("{method}: {e}")))?;
    if let Status::Unbounded { direction } = &res.status {
        // registry::solve returns Unbounded only with a verified recession
        // direction r (Cr = 0 per body, Ar ≤ 0, dᵀr > 0), scaled to a largest
        // component of 1; described per body as the rigid motion it is.
        let u = model.motions(direction);
        let work = crate::linalg::sparse::dot(&model.qp.d, direction);
        return Err(bad(crate::run::unbounded_message(
            &model.qp,
            direction,
            &model.describe_rigid_motion(&u),
            work,
            "§9.3",
        )));
    }
    Ok(res)
}

/// Probes: nearest output point to each requested point.
pub fn probes(prep: &Prepared, u: &[[f64; 2]]) -> Vec<(String, [f64; 2], usize, [f64; 2])> {
    // The point numbering is the same in every load step.
    let pts = &prep.model.topo.points;
    prep.problem
        .file
        .output
        .probes
        .iter()
        .map(|(name, x)| {
            let p = post::nearest_point(pts, x.xy());
            (name.clone(), pts[p], p, u[p])
        })
        .collect()
}
