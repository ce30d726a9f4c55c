//! The output data model: what a solve produces and a checkpoint holds
//! (the output mesh, the fields of each step, the friction arrays), as
//! plain arrays. `post` builds it from a solved model, `io` writes and
//! reads it (VTU, HDF5, JSON) and `post::plot` draws it; it knows nothing
//! of the solver, the mesh reader or the file formats.

use crate::fem::element::{Point, Vector};

/// The output mesh: contact nodes appear once per side (one point per body copy).
#[derive(Debug, Clone, Default)]
pub struct OutMesh {
    /// Point coordinates (x, y) of the duplicated mesh.
    pub points: Vec<Point>,
    /// Gmsh node tag each point came from.
    pub point_tags: Vec<u64>,
    /// Body number of each point (0-based).
    pub point_body: Vec<u32>,
    /// Triangles (counter-clockwise) in point indices.
    pub triangles: Vec<[usize; 3]>,
    /// Material index of each triangle (into `material_names`).
    pub material: Vec<u32>,
    pub material_names: Vec<String>,
    /// The kind of model: which stress components are written (σzz in
    /// plane strain, the hoop stress σθθ named "stt" when axisymmetric,
    /// docs/problem-format.md §6) and under which names.
    pub kind: crate::fem::ElementKind,
    /// The contact constraints: one contact point per constraint row.
    pub contact: ContactGeometry,
}

/// One point per constraint row, placed at the node of the first side
/// (body k of a conforming pair, or the slave node); segments join the
/// points of consecutive rows along the same interface.
#[derive(Debug, Clone, Default)]
pub struct ContactGeometry {
    pub points: Vec<Point>,
    /// Output-mesh point index of the first side (k / slave) of each row.
    pub first: Vec<usize>,
    /// Output-mesh point indices of the other side: one point (conforming),
    /// or two master points with weights (1-ξ, ξ) (non-matching).
    pub second: Vec<[(usize, f64); 2]>,
    pub normal: Vec<Vector>,
    /// Initial gap g of each row.
    pub gap0: Vec<f64>,
    /// Line cells in contact-point indices.
    pub segments: Vec<[usize; 2]>,
    /// Interface index of each row (into `interface_names`).
    pub interface: Vec<u32>,
    pub interface_names: Vec<String>,
    /// The discretization of each interface (same order as
    /// `interface_names`): `"node-to-node"`, `"nts"` or `"mortar"`; empty
    /// when read from a checkpoint that did not record it.
    pub interface_discretizations: Vec<String>,
    /// Whether each row is node-to-segment (slave point, two master points)
    /// rather than a conforming node pair.
    pub nonmatching: Vec<bool>,
}

/// A solved solid (3D) model as plain arrays: the tetrahedra and their
/// fields (docs/design.md §"Adding a kind: solid 3D"; the 2D [`OutMesh`]
/// and [`StepOutput`] are not dimension-generic yet).
#[derive(Debug, Clone, Default)]
pub struct SolidOutput {
    pub points: Vec<[f64; 3]>,
    /// Body number of each point (0-based).
    pub point_body: Vec<u32>,
    /// Tetrahedra (positively oriented) in point indices.
    pub tets: Vec<[usize; 4]>,
    /// Material index of each tetrahedron (into `material_names`).
    pub material: Vec<u32>,
    pub material_names: Vec<String>,
    pub displacement: Vec<[f64; 3]>,
    /// (σxx, σyy, σzz, σxy, σyz, σxz) of each tetrahedron.
    pub stress: Vec<[f64; 6]>,
    pub von_mises: Vec<f64>,
    /// σ1 ≥ σ2 ≥ σ3 of each tetrahedron.
    pub principal: Vec<[f64; 3]>,
    /// The support's reaction at each point (N; zero off the supports;
    /// empty: not computed), in the VTU only, as 2D.
    pub reaction: Vec<[f64; 3]>,
    /// The fields minus those of `[output] reference_step` (from that step
    /// on).
    pub change: Option<SolidChange>,
}

/// A 3D step's fields minus those of the reference step (docs/problem-format.md
/// §2 `[output] reference_step`).
#[derive(Debug, Clone, Default)]
pub struct SolidChange {
    /// The reference step (1-based).
    pub reference_step: usize,
    /// Per point: u − u_ref.
    pub displacement: Vec<[f64; 3]>,
    /// Per tetrahedron: σ − σ_ref (the six components).
    pub stress: Vec<[f64; 6]>,
    /// Per contact row: p − p_ref.
    pub contact_pressure: Vec<f64>,
}

/// The contact surface of a solved solid model (docs/problem-format.md
/// §12): one point per contact row, at its slave point, and the slave
/// surfaces' triangles on those points.
#[derive(Debug, Clone, Default)]
pub struct SolidContactOutput {
    /// The slave point of each row (reference coordinates).
    pub points: Vec<[f64; 3]>,
    /// The slave point's index in [`SolidOutput::points`].
    pub slave: Vec<usize>,
    /// Slave-surface triangles in row indices (a triangle with a node
    /// that has no row of the same interface is left out).
    pub triangles: Vec<[usize; 3]>,
    /// The row's unit normal (outward of the master).
    pub normal: Vec<[f64; 3]>,
    pub interface: Vec<u32>,
    /// The initial gap g₀ and the current one g₀ − Σ c_p·u_p.
    pub gap0: Vec<f64>,
    pub gap: Vec<f64>,
    /// λ (N) and λ / tributary area (N/m²).
    pub multiplier: Vec<f64>,
    pub pressure: Vec<f64>,
    pub active: Vec<bool>,
    /// p − p_ref of `[output] reference_step` (empty before it or without).
    pub pressure_change: Vec<f64>,
    /// With friction (else empty; docs/methods.md §12.6), per row in
    /// global coordinates: the tangential force λ_t1 t1 + λ_t2 t2 on the
    /// slave point (N), it over the tributary area (Pa), the step's slip
    /// v1 t1 + v2 t2 (m), and the state 0 open, 1 stick, 2 slip.
    pub tangential_force: Vec<[f64; 3]>,
    pub tangential_traction: Vec<[f64; 3]>,
    pub slip: Vec<[f64; 3]>,
    pub friction_state: Vec<u8>,
    /// With friction: the QP's own λ_t1, λ_t2 of each row along its
    /// tangent frame, as the solve left them (`--restart` reads them back
    /// as the next step's warm start, so that a continued run is the
    /// uninterrupted one bit for bit).
    pub multiplier_t: Vec<[f64; 2]>,
}

/// The fields of one solved (load) step.
#[derive(Debug, Clone, Default)]
pub struct StepOutput {
    /// Pseudo-time of the step (1.0 for a single solve).
    pub time: f64,
    /// Nodal displacement per output point.
    pub displacement: Vec<Vector>,
    /// Per triangle: σxx, σyy, σxy, σzz (σzz = 0 in plane stress).
    pub stress: Vec<[f64; 4]>,
    /// Per triangle: the report's τe = sqrt(σxx² + σyy² − σxxσyy + 3σxy²).
    pub von_mises: Vec<f64>,
    /// Per triangle: in-plane principal stresses (σ1 ≥ σ2).
    pub principal: Vec<[f64; 2]>,
    /// Per contact row: λ (nodal force), pressure (λ / tributary length), current gap, active flag.
    pub multipliers: Vec<f64>,
    pub contact_pressure: Vec<f64>,
    pub gap: Vec<f64>,
    pub active: Vec<u8>,
    /// Per point: the reaction force of the Dirichlet/slip conditions
    /// (zero where nothing is prescribed; empty if not computed).
    pub reaction: Vec<Vector>,
    /// Solver record stored as attributes.
    pub info: StepInfo,
    /// The change since the reference step (`[output] reference_step`), on
    /// that step and every later one.
    pub change: Option<Change>,
}

/// A step's fields minus those of the reference step: what the loads added
/// since then (e.g. plate motion on top of the gravity state).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Change {
    /// The reference step (1-based).
    pub reference_step: usize,
    /// Per output point: u − u_ref.
    pub displacement: Vec<Vector>,
    /// Per triangle: σ − σ_ref (σxx, σyy, σxy, σzz).
    pub stress: Vec<[f64; 4]>,
    /// Per contact row: p − p_ref.
    pub contact_pressure: Vec<f64>,
}

impl Change {
    /// The fields of `step` minus those of `reference` (same mesh).
    pub fn between(step: &StepOutput, reference: &StepOutput, reference_step: usize) -> Change {
        let sub2 = |a: &Vector, b: &Vector| [a[0] - b[0], a[1] - b[1]];
        Change {
            reference_step,
            displacement: step
                .displacement
                .iter()
                .zip(&reference.displacement)
                .map(|(a, b)| sub2(a, b))
                .collect(),
            stress: step
                .stress
                .iter()
                .zip(&reference.stress)
                .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]])
                .collect(),
            contact_pressure: step
                .contact_pressure
                .iter()
                .zip(&reference.contact_pressure)
                .map(|(a, b)| a - b)
                .collect(),
        }
    }
}

/// Scalars of one step, written as HDF5 attributes and into the JSON summary.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct StepInfo {
    pub method: String,
    pub preconditioner: String,
    pub converged: bool,
    pub iterations: usize,
    pub energy: f64,
    /// Every residual of the step's KKT certificate (docs/methods.md §8.4).
    pub kkt: crate::qp::Kkt,
    pub time_assemble: f64,
    pub time_solve: f64,
    pub time_total: f64,
}

/// The friction arrays of a step, per contact row (docs/problem-format.md
/// §6): λ_t (N), the tangential traction (Pa), the slip of the step (m) and
/// the state 0 open, 1 stick, 2 slip.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepFriction {
    pub multipliers_t: Vec<f64>,
    pub tangential_traction: Vec<f64>,
    pub slip: Vec<f64>,
    pub state: Vec<u8>,
}

/// Everything a checkpoint holds (its HDF5 layout: [`crate::io::hdf5`]).
#[derive(Debug, Clone, Default)]
pub struct Checkpoint {
    pub mesh: OutMesh,
    /// The steps in increasing index order (1, 2, …).
    pub steps: Vec<StepOutput>,
    /// The name of each step's group under `/steps` (same order): a
    /// restart continues by these names, not by the count
    /// (`run::Restart` refuses a gap, a `0000` or a duplicate).
    pub step_groups: Vec<String>,
    /// The friction arrays of each step (same order; None: frictionless).
    pub friction: Vec<Option<StepFriction>>,
    /// The string attributes of the root group (alphabetical order).
    pub attrs: Vec<(String, String)>,
}

/// A 3D (solid) checkpoint as read back (docs/problem-format.md §6 "The 3D
/// checkpoint"): the mesh, its contact rows, and the steps asked for.
#[derive(Debug, Clone, Default)]
pub struct SolidCheckpoint {
    pub points: Vec<[f64; 3]>,
    pub point_tags: Vec<u64>,
    pub point_body: Vec<u32>,
    pub tets: Vec<[usize; 4]>,
    pub material: Vec<u32>,
    pub material_names: Vec<String>,
    /// The contact rows (none without `[[contact]]`).
    pub contact: SolidContactMesh,
    /// The index of every step group under `/steps`, increasing.
    pub step_indices: Vec<usize>,
    /// The steps read (all of them, or the one asked for), increasing.
    pub steps: Vec<SolidStep>,
    /// The string attributes of the root group (alphabetical order).
    pub attrs: Vec<(String, String)>,
}

/// The contact rows of a 3D checkpoint's mesh.
#[derive(Debug, Clone, Default)]
pub struct SolidContactMesh {
    /// The slave point of each row (index into the points).
    pub slave: Vec<usize>,
    pub normal: Vec<[f64; 3]>,
    pub gap0: Vec<f64>,
    /// The `[[contact]]` entry of each row (0-based).
    pub interface: Vec<u32>,
    /// The slave surfaces' triangles in row indices.
    pub triangles: Vec<[usize; 3]>,
}

/// The fields of one step of a 3D checkpoint.
#[derive(Debug, Clone, Default)]
pub struct SolidStep {
    /// The step's index (the number of its group `/steps/NNNN`).
    pub index: usize,
    pub time: f64,
    pub displacement: Vec<[f64; 3]>,
    /// (σxx, σyy, σzz, σxy, σyz, σxz) per tetrahedron.
    pub stress: Vec<[f64; 6]>,
    pub von_mises: Vec<f64>,
    pub principal: Vec<[f64; 3]>,
    /// Per contact row: λ, pressure, current gap, active flag.
    pub multipliers: Vec<f64>,
    pub contact_pressure: Vec<f64>,
    pub gap: Vec<f64>,
    pub active: Vec<u8>,
    /// With friction (else empty): per contact row the tangential force
    /// (N), traction (Pa) and slip (m) in global coordinates, and the state
    /// 0 open, 1 stick, 2 slip.
    pub tangential_force: Vec<[f64; 3]>,
    pub tangential_traction: Vec<[f64; 3]>,
    pub slip: Vec<[f64; 3]>,
    pub friction_state: Vec<u8>,
    pub info: StepInfo,
}
