//! The solve pipeline shared by the CLI commands and the tests:
//! read → assemble → solve → post-process → write.

use crate::fem::{self, Model};
use crate::io::{self, IoError, OutMesh, StepOutput};
use crate::mesh::{self, Mesh};
use crate::post;
use crate::problem::Problem;
use crate::qp::{precond::PrecondKind, registry, QpResult, SolveOptions, Status};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Bad input: the problem cannot be solved as given (exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error(transparent)]
    Model(#[from] crate::problem::ModelError),
    #[error(transparent)]
    Mesh(#[from] mesh::MeshError),
    #[error(transparent)]
    Fem(#[from] fem::FemError),
    #[error("{path}: {msg}")]
    Solver { path: PathBuf, msg: String },
}

/// A problem read and assembled.
pub struct Prepared {
    pub problem: Problem,
    /// FNV-1a 64 of the mesh file's bytes (part of the checkpoint's fingerprint).
    pub mesh_hash: u64,
    pub mesh: Mesh,
    pub model: Model,
    /// How the models of this problem are built (also each load step's).
    pub build: fem::BuildOptions,
    pub t_read: f64,
    pub t_assemble: f64,
}

/// Read the TOML and the mesh, build the QP. `no_contact` drops every [[contact]].
pub fn prepare(path: &Path, no_contact: bool) -> Result<Prepared, InputError> {
    prepare_with(path, no_contact, &fem::BuildOptions::default())
}

/// [`prepare`] with the options of `fem::build_with`.
pub fn prepare_with(
    path: &Path,
    no_contact: bool,
    build: &fem::BuildOptions,
) -> Result<Prepared, InputError> {
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
fn check_contact_groups(problem: &Problem, mesh: &Mesh) -> Result<(), InputError> {
    for (i, c) in problem.file.contact.iter().enumerate() {
        for name in [&c.on, &c.slave, &c.master].into_iter().flatten() {
            if let Some(g) = mesh.group_any(name) {
                if g.elements.is_empty() {
                    return Err(InputError::Solver {
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

/// A probe farther from every node than this fraction of the mesh's
/// diagonal is refused: it cannot mean any node of this mesh.
const PROBE_REACH: f64 = 0.1;

fn check_probes(problem: &Problem, model: &Model) -> Result<(), InputError> {
    let pts = &model.topo.points;
    if pts.is_empty() || problem.file.output.probes.is_empty() {
        return Ok(());
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in pts {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    for (name, x) in &problem.file.output.probes {
        let p = post::nearest_point(pts, *x);
        let dist = (pts[p][0] - x[0]).hypot(pts[p][1] - x[1]);
        let near = dist <= PROBE_REACH * diag;
        if !near {
            return Err(InputError::Solver {
                path: problem.path.clone(),
                msg: format!(
                    "[output] probe {}: ({:e}, {:e}) lies {dist:.3e} from the nearest node, outside the mesh ([{:e}, {:e}] x [{:e}, {:e}])",
                    crate::problem::shorten(name),
                    x[0],
                    x[1],
                    lo[0],
                    hi[0],
                    lo[1],
                    hi[1]
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
pub fn fingerprint(prep: &Prepared, no_contact: bool) -> String {
    let mut parts = vec![("mesh".to_string(), prep.mesh_hash)];
    let table: toml::Table = toml::from_str(&prep.problem.text).unwrap_or_default();
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
        let text = table
            .get(key)
            .map(|v| toml::to_string(&toml::Table::from_iter([(key.to_string(), v.clone())])))
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
/// with loads and prescribed displacements of that step.
pub fn step_model(prep: &Prepared, s: usize) -> Result<Model, InputError> {
    let mut p = prep.problem.clone();
    p.file = prep.problem.file.at_step(s);
    Ok(fem::build_with(&prep.mesh, &p, &prep.build)?)
}

/// Reduced unknowns ξ = Tᵀ(u − u0) of point displacements `u` (a warm start).
pub fn reduce(model: &Model, u: &[[f64; 2]]) -> Vec<f64> {
    let mut x = vec![0.0; model.qp.n()];
    for (p, pd) in model.dofs.iter().enumerate() {
        let du = [u[p][0] - pd.u0[0], u[p][1] - pd.u0[1]];
        for k in 0..pd.ndof {
            x[pd.start + k] = pd.t[k][0] * du[0] + pd.t[k][1] * du[1];
        }
    }
    x
}

/// Solver choice: method name + options, from [solver] overridden by flags.
#[derive(Debug, Clone, Default)]
pub struct SolverChoice {
    pub method: Option<String>,
    pub preconditioner: Option<String>,
    pub tol: Option<f64>,
    pub max_iter: Option<usize>,
    pub omega: Option<f64>,
    pub release: Option<String>,
}

pub fn options(
    problem: &Problem,
    flags: &SolverChoice,
) -> Result<(String, SolveOptions), InputError> {
    let s = &problem.file.solver;
    let bad = |msg: String| InputError::Solver {
        path: problem.path.clone(),
        msg,
    };
    let method = flags
        .method
        .clone()
        .or(s.method.clone())
        .unwrap_or_else(|| "cgc".into());
    if registry::find(&method).is_none() {
        return Err(bad(format!(
            "unknown method \"{method}\"; known: {}",
            registry::names().join(", ")
        )));
    }
    let pc_name = flags
        .preconditioner
        .clone()
        .or(s.preconditioner.clone())
        .unwrap_or_else(|| "cholesky".into());
    let preconditioner = PrecondKind::parse(&pc_name).ok_or_else(|| {
        bad(format!(
            "unknown preconditioner \"{pc_name}\"; known: none, jacobi, ssor, ic0, mic0, cholesky"
        ))
    })?;
    let mut o = SolveOptions {
        preconditioner,
        ..Default::default()
    };
    if let Some(t) = flags.tol.or(s.tol) {
        if !(t > 0.0 && t < 1.0) {
            return Err(bad(format!("tol = {t} must lie in (0, 1)")));
        }
        o.tol = t;
    }
    if let Some(m) = flags.max_iter.or(s.max_iter) {
        if m == 0 {
            return Err(bad("max_iter must be positive".into()));
        }
        o.max_iter = m;
    }
    if let Some(w) = flags.omega.or(s.omega) {
        if !(w > 0.0 && w < 2.0) {
            return Err(bad(format!("omega = {w} must lie in (0, 2)")));
        }
        o.omega = w;
    }
    if let Some(r) = flags.release.clone().or(s.release.clone()) {
        o.multiple_release = match r.as_str() {
            "multiple" => true,
            "single" => false,
            _ => {
                return Err(bad(format!(
                    "release = \"{r}\": expected \"single\" or \"multiple\""
                )))
            }
        };
    }
    if let Some(p) = s.penalty {
        if p.is_nan() || p <= 0.0 {
            return Err(bad(format!("penalty = {p} must be positive")));
        }
        o.penalty = Some(p);
    }
    if let Some(r) = s.rho {
        if r.is_nan() || r <= 0.0 {
            return Err(bad(format!("rho = {r} must be positive")));
        }
        o.rho = Some(r);
    }
    if let Some(a) = s.accelerate {
        o.accelerate = a;
    }
    if let Some(p) = &s.ssn_path {
        if !["auto", "augmented", "refactor", "schur"].contains(&p.as_str()) {
            return Err(bad(format!(
                "ssn_path = \"{p}\": expected \"auto\", \"augmented\", \"refactor\" or \"schur\""
            )));
        }
        o.ssn_path = Some(p.clone());
    }
    Ok((method, o))
}

/// Run the method; an unbounded problem is bad input naming the bodies.
pub fn solve(prep: &Prepared, method: &str, opts: &SolveOptions) -> Result<QpResult, InputError> {
    solve_model(prep, &prep.model, method, opts)
}

/// [`solve`] for the model of a load step.
pub fn solve_model(
    prep: &Prepared,
    model: &Model,
    method: &str,
    opts: &SolveOptions,
) -> Result<QpResult, InputError> {
    let bad = |msg: String| InputError::Solver {
        path: prep.problem.path.clone(),
        msg,
    };
    let res =
        registry::solve(method, &model.qp, opts).map_err(|e| bad(format!("{method}: {e}")))?;
    if let Status::Unbounded { direction } = &res.status {
        // registry::solve returns Unbounded only with a verified recession
        // direction r (Cr = 0 per body, Ar ≤ 0, dᵀr > 0), scaled to a largest
        // component of 1; described per body as the rigid motion it is.
        let u = model.motions(direction);
        let work = crate::linalg::sparse::dot(&model.qp.d, direction);
        return Err(bad(format!(
            "the problem is unbounded: {} can move as a rigid body without closing any contact, and the loads do positive work on it (dᵀr = {work:.4e} J for a motion of 1 m; a body pulled away from its support, methods.md §1.7)",
            model.describe_rigid_motion(&u)
        )));
    }
    Ok(res)
}

/// Output file paths of one solve.
#[derive(Debug, Clone)]
pub struct Outputs {
    pub vtu: PathBuf,
    pub contact_vtu: PathBuf,
    pub h5: PathBuf,
    pub json: PathBuf,
}

/// Output paths; `step` = Some(k) names the VTU pair of load step k (1-based).
pub fn output_paths(dir: &Path, name: &str, step: Option<usize>) -> Outputs {
    let stem = match step {
        Some(k) => format!("{name}_{k:04}"),
        None => name.to_string(),
    };
    Outputs {
        vtu: dir.join(format!("{stem}.vtu")),
        contact_vtu: dir.join(format!("{stem}_contact.vtu")),
        h5: dir.join(format!("{name}.h5")),
        json: dir.join(format!("{name}.json")),
    }
}

/// A new checkpoint at `h5` holding the mesh and the problem's
/// [`fingerprint`] (steps are appended one by one).
pub fn create_checkpoint(
    prep: &Prepared,
    h5: &Path,
    om: &OutMesh,
    fingerprint: &str,
) -> Result<(), IoError> {
    let attrs = [
        ("problem", prep.problem.name.clone()),
        ("problem_toml", prep.problem.text.clone()),
        ("fingerprint", fingerprint.to_string()),
        (
            "program",
            format!("signorini {}", env!("CARGO_PKG_VERSION")),
        ),
    ];
    io::hdf5::create_checkpoint(h5, om, &attrs)
}

/// Write the VTU pair of a step at `out` and append the step to the
/// checkpoint `out.h5` in place: `out` names files in a staging directory
/// ([`crate::io::atomic::Stage`]), moved into place once all are complete.
pub fn write_step(
    out: &Outputs,
    om: &OutMesh,
    step: &StepOutput,
    index: usize,
    compress: bool,
) -> Result<(), IoError> {
    io::vtu::write_vtu(&out.vtu, om, step, compress)?;
    io::vtu::write_contact_vtu(&out.contact_vtu, om, step, compress)?;
    io::hdf5::append_step_in_place(&out.h5, index, step)
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
            let p = post::nearest_point(pts, *x);
            (name.clone(), pts[p], p, u[p])
        })
        .collect()
}
