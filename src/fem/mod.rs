//! Finite elements: from a mesh and a problem file to the QP
//! min ½xᵀCx − xᵀd s.t. Ax ≤ g with the maps back to the mesh
//! (docs/methods.md §1–2, §7).
//!
//! [`build_with`] is the list of steps, one module each: bodies and points
//! (`topology`, with the mesh graph in `edges`), the contact pairs as rows
//! on points (`pairs`), Dirichlet and slip conditions and their elimination
//! u = u0 + Tξ (`conditions`), the stiffness matrix and the element part of
//! d (`stiffness`, over the P1 `element`), tractions and point forces
//! (`loads`), the rows of A and g (`contact`), and the rigid modes with the
//! semicoercive checks (`rigid`). Nothing here reads the environment: the
//! caller chooses threads through [`BuildOptions`].

mod conditions;
mod contact;
pub mod contact3d;
pub mod discrete;
mod edges;
pub mod element;
pub mod friction;
mod interference;
mod loads;
mod mortar;
mod pairs;
mod rigid;
pub mod solid;
pub mod solid_input;
mod solid_modes;
mod sort;
mod stiffness;
pub mod topology;

pub use conditions::PointDofs;
pub use discrete::Discrete;
pub use topology::Topology;

use crate::mesh::Mesh;
use crate::problem::Problem;
use crate::qp::QpProblem;
pub use element::ElementKind;
use element::Vector;
use std::path::{Path, PathBuf};

/// How [`build_with`] runs; the default (and [`build`]) assembles on
/// rayon's threads. The model is the same bit for bit either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuildOptions {
    /// Assemble C and d on rayon's threads (false: on the calling thread).
    pub parallel: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions { parallel: true }
    }
}

/// The assembled problem with the maps back to the mesh.
#[derive(Clone)]
pub struct Model {
    /// Shared by the models of every load step (same mesh, same topology).
    pub topo: std::sync::Arc<Topology>,
    pub dofs: Vec<PointDofs>,
    pub qp: QpProblem,
    /// QP row → contact row (rows whose points are all fixed are left out).
    pub qp_rows: Vec<usize>,
    /// Kernel vectors and the body each belongs to.
    pub kernel_body: Vec<u32>,
    /// The kind of model: plane strain, plane stress (with its thickness)
    /// or axisymmetric.
    pub kind: ElementKind,
    /// The Dirichlet and slip conditions r·u = v, kept for the reactions:
    /// (point, unit direction r, index into `cond_groups`).
    pub conditions: Vec<(usize, Vector, u32)>,
    /// What set each condition: (kind "dirichlet" | "slip", physical group name).
    pub cond_groups: Vec<(&'static str, String)>,
    /// Nodal external force on each point (N; tractions, point forces,
    /// gravity; thickness included), before the elimination: the load side
    /// of the balance R = K u − f.
    pub loads: Vec<Vector>,
    /// The name of each body: its physical surface name(s), "+"-joined,
    /// with " #b" when bodies share a material.
    pub body_names: Vec<String>,
    /// Per contact row: a mortar row at the end of its slave curve on a
    /// line of symmetry, which has no friction ([`friction::on_symmetry_line`]).
    pub symmetry_rows: Vec<bool>,
}

impl Model {
    /// "body 'punch'": a body as messages name it.
    pub fn body_label(&self, b: usize) -> String {
        match self.body_names.get(b) {
            Some(n) => format!("body '{n}'"),
            None => format!("body {b}"),
        }
    }

    /// Point displacements of a change `dx` of the QP unknowns (u0 left out):
    /// the motion along a direction such as a rigid mode.
    pub fn motions(&self, dx: &[f64]) -> Vec<Vector> {
        self.dofs
            .iter()
            .map(|p| {
                let mut u = [0.0, 0.0];
                for k in 0..p.ndof {
                    let xi = dx[p.start + k];
                    u[0] += p.t[k][0] * xi;
                    u[1] += p.t[k][1] * xi;
                }
                u
            })
            .collect()
    }

    /// Full point displacements from the QP unknowns.
    pub fn displacements(&self, x: &[f64]) -> Vec<Vector> {
        discrete::point_displacements(&self.dofs, x)
    }

    /// The effective thickness for forces → pressures (1 in plane strain).
    pub fn t_eff(&self) -> f64 {
        self.kind.thickness()
    }
}

impl Discrete<2> for Model {
    fn dofs(&self) -> &[PointDofs] {
        &self.dofs
    }
    fn qp(&self) -> &QpProblem {
        &self.qp
    }
    fn qp_mut(&mut self) -> &mut QpProblem {
        &mut self.qp
    }
    fn tangential_displacement(&self, u: &[Vector]) -> Vec<f64> {
        friction::tangential_displacement(self, u)
    }
}

/// Build the whole model with the default options.
pub fn build(mesh: &Mesh, problem: &Problem) -> Result<Model, FemError> {
    build_with(mesh, problem, &BuildOptions::default())
}

/// Build the whole model: topology, conditions, QP, checks.
pub fn build_with(mesh: &Mesh, problem: &Problem, opts: &BuildOptions) -> Result<Model, FemError> {
    let mut lap = Lap::new("fem::build");
    let (f, path) = (&problem.file, problem.path.as_path());
    let kind = ElementKind::of(&f.model);
    if mesh.dim() != 2 {
        return Err(FemError::new(
            path,
            format!(
                "{}: a 3D mesh (tetrahedra): `signorini solve`, `compare`, `limit` and `plot` run 3D models, but this command does not yet (issue 45)",
                mesh.path.display()
            ),
        ));
    }
    let topo = Topology::build(mesh, path, kind, &f.materials, &f.contact)?;
    lap.lap("topology");
    let conds = conditions::Conditions::collect(mesh, &topo, path, &f.dirichlet, &f.slip)?;
    lap.lap("conditions");
    let body_names = topo.body_names();
    let dofs = conds.eliminate(mesh, &topo, &body_names, path)?;
    let n = dofs.last().map_or(0, |pd| pd.start + pd.ndof);
    lap.lap("elimination");
    loads::check_body_forces(&topo, &f.materials, &f.model, path)?;
    loads::warn_measureless_tractions(mesh, kind, &f.traction, path);
    let mats = stiffness::Materials::new(&topo, &f.materials, &f.model);
    let (c, mut d) = stiffness::assemble(
        stiffness::Cells::plane(&topo),
        &dofs,
        n,
        &mats,
        opts.parallel,
    );
    lap.lap("stiffness");
    let bl = loads::BoundaryLoads {
        traction: &f.traction,
        force: &f.force,
    };
    let loads = loads::nodal_loads(mesh, &topo, &dofs, path, bl, &mats, &mut d)?;
    loads::check_scale(&c, &d, &dofs, &topo, mesh, path)?;
    lap.lap("loads");
    let (a, g, qp_rows) = contact::reduced_rows(mesh, &topo, &dofs, n, path)?;
    lap.lap("contact rows");
    let conditions = conds.list();
    let symmetry_rows = friction::symmetry_rows(
        &topo,
        &dofs,
        &conditions,
        &conds.groups,
        &f.dirichlet,
        &f.steps,
    );
    let friction = friction::build(&topo, &dofs, n, path, &f.contact, &qp_rows, &symmetry_rows)?;
    lap.lap("friction rows");
    let (kernel, kernel_body) = rigid::rigid_modes(&topo, &dofs, &conds.at, n, kind);
    let near = rigid::near_kernel(&topo, &dofs, n);
    let model = Model {
        topo: std::sync::Arc::new(topo),
        dofs,
        qp: QpProblem {
            c,
            d,
            a,
            g,
            kernel,
            friction,
            near,
        },
        qp_rows,
        kernel_body,
        kind,
        conditions,
        cond_groups: conds.groups,
        loads,
        body_names,
        symmetry_rows,
    };
    let mut model = model;
    model.start_step(None);
    lap.lap("rigid modes");
    rigid::check_semicoercive(&model, path)?;
    lap.lap("semicoercivity check");
    Ok(model)
}

/// The model of a load step of the problem `base` was built from
/// (`problem` is that problem at the step, `ProblemFile::at_step`): a step
/// changes only loads and prescribed values (docs/problem-format.md §2), so
/// C, A, T and the rigid modes of `base` are kept and only d, g, u0, the
/// nodal loads and the friction offset t0 are computed again
/// (docs/methods.md §8.5). Bit for bit the model [`build_with`] makes; when
/// the step changes which DOFs a point has (a prescribed value turning a
/// free point into a fixed one), that full build is what it returns.
pub fn step_model(
    base: &Model,
    mesh: &Mesh,
    problem: &Problem,
    opts: &BuildOptions,
) -> Result<Model, FemError> {
    step_model_reusing(base, None, mesh, problem, opts)
}

/// [`step_model`] made from `prev` (the model of another step of the same
/// problem, which is given up) instead of a copy of `base` when it has
/// `base`'s DOFs, hence its C and A: a sequence of load steps copies C once.
pub fn step_model_reusing(
    base: &Model,
    prev: Option<Model>,
    mesh: &Mesh,
    problem: &Problem,
    opts: &BuildOptions,
) -> Result<Model, FemError> {
    let mut lap = Lap::new("fem::step_model");
    let f = &problem.file;
    let mats = stiffness::Materials::new(&base.topo, &f.materials, &f.model);
    let bl = loads::BoundaryLoads {
        traction: &f.traction,
        force: &f.force,
    };
    let path = problem.path.as_path();
    let Some(s) = loads::step_loads(base, mesh, path, &f.dirichlet, &f.slip, bl, &mats)? else {
        log::debug!("fem::step_model: the DOFs changed, full assembly");
        return build_with(mesh, problem, opts);
    };
    lap.lap("loads");
    // Everything but the step's values is the base's.
    let mut model = match prev {
        Some(m) if loads::same_dofs(&m.dofs, &base.dofs) => m,
        _ => base.clone(),
    };
    model.dofs = s.dofs;
    model.qp.d = s.d;
    model.qp.g = s.g;
    model.loads = s.loads;
    model.start_step(None);
    rigid::check_semicoercive(&model, path)?;
    lap.lap("copy and checks");
    Ok(model)
}

/// A problem that does not fit its mesh: the message names the TOML file
/// and the group, key, node or element.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {msg}")]
pub struct FemError {
    pub path: PathBuf,
    pub msg: String,
}

/// Debug log of the time each phase of a build takes (`--log-level debug`).
pub(crate) struct Lap {
    what: &'static str,
    clock: std::time::Instant,
    last: f64,
}

impl Lap {
    pub(crate) fn new(what: &'static str) -> Lap {
        Lap {
            what,
            clock: std::time::Instant::now(),
            last: 0.0,
        }
    }

    /// Log the time since the last call (or since `new`) under `phase`.
    pub(crate) fn lap(&mut self, phase: &str) {
        let t = self.clock.elapsed().as_secs_f64();
        log::debug!("{}: {phase} {:.3} s", self.what, t - self.last);
        self.last = t;
    }
}

impl FemError {
    pub fn new(path: &Path, msg: String) -> FemError {
        FemError {
            path: path.to_path_buf(),
            msg,
        }
    }
}
