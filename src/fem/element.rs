//! The P1 element of docs/methods.md §1.4 and §2.2: material matrix D, strain
//! matrix B, element stiffness C_e = t_h|T| BᵀDB, stresses τ̄ = D B x_e, and
//! [`ElementKind`], the one place that knows which kind of model (plane
//! strain, plane stress, axisymmetric, solid 3D) an element belongs to
//! (docs/design.md §"Element kinds").

use crate::problem::{Material, ModelSection, Plane};

/// A point of a `D`-dimensional model: (x, y), (r, z) or (x, y, z). The
/// dimension is a const generic where code is shared by the plane and the
/// solid kinds (docs/design.md §"Element kinds").
pub type PointD<const D: usize> = [f64; D];

/// A point (x, y) of the plane, or (r, z) of an axisymmetric model.
pub type Point = PointD<2>;

/// A vector of the plane: a displacement, a force, a normal.
pub type Vector = PointD<2>;

/// A point (x, y, z) of a solid model.
pub type Point3 = PointD<3>;

/// A vector of a solid model.
pub type Vector3 = PointD<3>;

/// One rigid motion of a free body: a translation along axis k, or a
/// rotation about axis k (u = e_k × (x − c)); in the plane the rotation is
/// about z, `Rotation(2)` (docs/methods.md §1.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigidMode {
    Translation(usize),
    Rotation(usize),
}

impl RigidMode {
    /// The motion at `x` of a body centred at `c`, rotations divided by the
    /// body's size `l` so that every motion is of one magnitude.
    #[inline]
    pub fn at<const D: usize>(self, x: PointD<D>, c: PointD<D>, l: f64) -> PointD<D> {
        let mut u = [0.0; D];
        match self {
            RigidMode::Translation(k) => u[k] = 1.0,
            RigidMode::Rotation(k) => {
                // e_k × r with r = x − c: components i = k + 1, j = k + 2.
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                u[i] = -(x[j] - c[j]) / l;
                u[j] = (x[i] - c[i]) / l;
            }
        }
        u
    }
}

/// The three rigid motions of a plane body.
pub const PLANE_MODES: [RigidMode; 3] = [
    RigidMode::Translation(0),
    RigidMode::Translation(1),
    RigidMode::Rotation(2),
];

/// The six rigid motions of a solid body.
pub const SOLID_MODES: [RigidMode; 6] = [
    RigidMode::Translation(0),
    RigidMode::Translation(1),
    RigidMode::Translation(2),
    RigidMode::Rotation(0),
    RigidMode::Rotation(1),
    RigidMode::Rotation(2),
];

/// The kind of model an element belongs to, and everything that depends
/// on it: the material matrix and the strain operator (through
/// [`ElementKind::material`], [`ElementKind::stiffness`],
/// [`ElementKind::stress`]), the integration measure of a triangle (area ×
/// thickness, or r dA per radian), the boundary measure of a segment
/// (ℓ/2 per node, or ∫N r ds), the rigid modes, and the stress components
/// and their names (docs/design.md §"Element kinds"; docs/methods.md §1.4,
/// §2.2, §10). Nothing outside this module asks which kind a model is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ElementKind {
    /// Plane strain: ε_zz = 0, σ_zz = ν(σ_xx + σ_yy), per unit thickness.
    PlaneStrain,
    /// Plane stress: σ_zz = 0; every integral is over the thickness t_h.
    PlaneStress { thickness: f64 },
    /// Axisymmetric about the y axis (x = r ≥ 0, y = z): every integral is
    /// per radian, ∫ · r dr dz (docs/methods.md §10).
    Axisymmetric,
    /// A 3D body of P1 tetrahedra (docs/design.md §"Adding a kind: solid
    /// 3D"): six stress components, six rigid modes, volume measure.
    Solid,
}

impl Default for ElementKind {
    /// Plane strain, as `[model] plane` defaults to.
    fn default() -> ElementKind {
        ElementKind::PlaneStrain
    }
}

/// The names of the stress components of a plane model: σxx, σyy, σxy, σzz.
const PLANE_STRESS_NAMES: [&str; 4] = ["sxx", "syy", "sxy", "szz"];

/// The names of the stress components of an axisymmetric model: σrr, σzz,
/// σrz, σθθ (docs/problem-format.md §11).
const AXI_STRESS_NAMES: [&str; 4] = ["srr", "szz", "srz", "stt"];

/// The names of the stress components of a solid model, in VTK's order of
/// a symmetric tensor: σxx, σyy, σzz, σxy, σyz, σxz.
const SOLID_STRESS_NAMES: [&str; 6] = ["sxx", "syy", "szz", "sxy", "syz", "sxz"];

/// Component names of the multi-component output arrays (VTU), per array.
pub type ComponentNames = &'static [(&'static str, &'static [&'static str])];

/// [`ComponentNames`] of a plane model.
pub const PLANE_COMPONENT_NAMES: ComponentNames = &[
    ("displacement", &["ux", "uy", "uz"]),
    ("displacement_change", &["dux", "duy", "duz"]),
    ("reaction", &["Rx", "Ry", "Rz"]),
    ("stress", &["sxx", "syy", "sxy", "szz"]),
    ("stress_change", &["dsxx", "dsyy", "dsxy", "dszz"]),
    ("principal_stress", &["s1", "s2"]),
    ("normal", &["nx", "ny", "nz"]),
    ("tangent", &["tx", "ty", "tz"]),
];

/// [`ComponentNames`] of an axisymmetric model (x = r, y = z): (σrr, σzz,
/// σrz, σθθ), the 4th the hoop stress (docs/problem-format.md §6).
const AXI_COMPONENT_NAMES: ComponentNames = &[
    ("displacement", &["ur", "uz", "u3"]),
    ("displacement_change", &["dur", "duz", "du3"]),
    ("reaction", &["Rr", "Rz", "R3"]),
    ("stress", &["srr", "szz", "srz", "stt"]),
    ("stress_change", &["dsrr", "dszz", "dsrz", "dstt"]),
    ("principal_stress", &["s1", "s2"]),
    ("normal", &["nx", "ny", "nz"]),
    ("tangent", &["tx", "ty", "tz"]),
];

/// [`ComponentNames`] of a solid model.
const SOLID_COMPONENT_NAMES: ComponentNames = &[
    ("displacement", &["ux", "uy", "uz"]),
    ("displacement_change", &["dux", "duy", "duz"]),
    ("reaction", &["Rx", "Ry", "Rz"]),
    ("stress", &SOLID_STRESS_NAMES),
    (
        "stress_change",
        &["dsxx", "dsyy", "dszz", "dsxy", "dsyz", "dsxz"],
    ),
    ("principal_stress", &["s1", "s2", "s3"]),
    ("normal", &["nx", "ny", "nz"]),
    ("tangent", &["tx", "ty", "tz"]),
];

impl ElementKind {
    /// The dimension of the model's space: 3 for a solid, else 2.
    pub fn dim(self) -> usize {
        match self {
            ElementKind::Solid => 3,
            _ => 2,
        }
    }

    /// The kind of `[model]` (its `plane` and `thickness`).
    pub fn of(model: &ModelSection) -> ElementKind {
        match model.plane {
            Plane::Strain => ElementKind::PlaneStrain,
            Plane::Stress => ElementKind::PlaneStress {
                thickness: model.thickness,
            },
            Plane::Axisymmetric => ElementKind::Axisymmetric,
        }
    }

    /// The thickness that turns a force per unit length into a pressure
    /// (and multiplies every stiffness and load): t_h in plane stress, 1
    /// in plane strain and per radian (methods.md §2.2, §10).
    pub fn thickness(self) -> f64 {
        match self {
            ElementKind::PlaneStress { thickness } => thickness,
            ElementKind::PlaneStrain | ElementKind::Axisymmetric | ElementKind::Solid => 1.0,
        }
    }

    /// The name of the kind in the files (HDF5 root attribute `model`):
    /// "plane_strain", "plane_stress" or "axisymmetric".
    pub fn model_name(self) -> &'static str {
        match self {
            ElementKind::PlaneStrain => "plane_strain",
            ElementKind::PlaneStress { .. } => "plane_stress",
            ElementKind::Axisymmetric => "axisymmetric",
            ElementKind::Solid => "solid",
        }
    }

    /// The HDF5 root flags of the kind (docs/problem-format.md): the value
    /// of `plane_strain` (1 when the stress has a fourth component, σzz
    /// or, axisymmetric, σθθ) and of `axisymmetric` when written (only 1).
    pub fn file_flags(self) -> (u8, Option<u8>) {
        match self {
            ElementKind::PlaneStrain => (1, None),
            ElementKind::PlaneStress { .. } => (0, None),
            ElementKind::Axisymmetric => (1, Some(1)),
            // Not written yet: a solid checkpoint needs its own root
            // attribute (docs/design.md, what is left of issue 45).
            ElementKind::Solid => (1, None),
        }
    }

    /// The kind of a file's root flags [`ElementKind::file_flags`]; the
    /// thickness of plane stress is not in the file (the written fields
    /// do not depend on it), 1 here.
    pub fn from_file_flags(plane_strain: bool, axisymmetric: bool) -> ElementKind {
        match (plane_strain, axisymmetric) {
            (_, true) => ElementKind::Axisymmetric,
            (true, false) => ElementKind::PlaneStrain,
            (false, false) => ElementKind::PlaneStress { thickness: 1.0 },
        }
    }

    /// The unit of forces when it is not N (per unit thickness): "N/rad"
    /// for an axisymmetric model.
    pub fn force_unit(self) -> Option<&'static str> {
        match self {
            ElementKind::Axisymmetric => Some("N/rad"),
            _ => None,
        }
    }

    /// The conditions this kind imposes by itself, without a TOML entry,
    /// on the points `points` of a model: u_r = 0 on every point on the
    /// axis r = x = 0 (within 1e-9 of the largest |x|) of an axisymmetric
    /// model (methods.md §10); None for a plane model, or when no point
    /// lies on the axis (a tube). A point at r < 0 is outside the domain
    /// of the kind: the first one is the error.
    pub fn implied_conditions(
        self,
        points: &[Point],
    ) -> Result<Option<ImpliedConditions>, OutsideDomain> {
        if let ElementKind::PlaneStrain | ElementKind::PlaneStress { .. } | ElementKind::Solid =
            self
        {
            return Ok(None);
        }
        let rmax = points.iter().fold(0.0f64, |m, x| m.max(x[0].abs()));
        let tol = 1e-9 * rmax;
        let mut on_axis = vec![];
        for (p, x) in points.iter().enumerate() {
            if x[0] < -tol {
                return Err(OutsideDomain { point: p, at: *x });
            }
            if x[0] <= tol {
                on_axis.push(p);
            }
        }
        Ok((!on_axis.is_empty()).then_some(ImpliedConditions {
            what: "the axis r = 0 (axisymmetric: u_r = 0)",
            group: ("axis", "r = 0"),
            direction: [1.0, 0.0],
            points: on_axis,
        }))
    }

    /// The largest body force of a spin ω about the axis of the kind on a
    /// material of density `rho` whose points reach the distance `r_max`
    /// from the axis (r_max the largest |x|): the centrifugal ρω²r_max of
    /// an axisymmetric model (methods.md §10); None for a plane model,
    /// which has no axis for a spin to load.
    pub fn centrifugal_force(self, rho: f64, omega: f64, r_max: f64) -> Option<f64> {
        match self {
            ElementKind::Axisymmetric => Some(rho * omega * omega * r_max),
            ElementKind::PlaneStrain | ElementKind::PlaneStress { .. } | ElementKind::Solid => None,
        }
    }

    /// Why a (finite) gravity `g` of `[model]` does not suit this kind: an
    /// axisymmetric model (x = r, y = z) takes gravity along z only (a
    /// radial body force is not axisymmetric); None when it does.
    pub fn gravity_misfit(self, g: Vector) -> Option<&'static str> {
        match self {
            ElementKind::Axisymmetric if g[0] != 0.0 => Some(
                "an axisymmetric model (x = r, y = z) takes gravity along z only; give [0, gz]",
            ),
            _ => None,
        }
    }

    /// Why a spin ω about the axis (`[model] omega`) does not suit this
    /// kind: a plane model has no axis; None when it does (axisymmetric).
    pub fn spin_misfit(self) -> Option<&'static str> {
        match self {
            ElementKind::Axisymmetric => None,
            ElementKind::PlaneStrain | ElementKind::PlaneStress { .. } | ElementKind::Solid => {
                Some("applies to plane = \"axisymmetric\" only")
            }
        }
    }

    /// Why a boundary segment (a, b) has no measure in this kind, so that
    /// a traction on it adds no load: both ends on the axis r = 0 of an
    /// axisymmetric model (∫ N r ds = 0 there); None when the segment has
    /// a measure (every segment of a plane model).
    pub fn measureless_segment(self, a: Point, b: Point) -> Option<&'static str> {
        match self {
            ElementKind::Axisymmetric if a[0] == 0.0 && b[0] == 0.0 => {
                Some("the axis r = 0 of the axisymmetric model")
            }
            _ => None,
        }
    }

    /// The number of stress components the files keep: 4 (σzz or σθθ),
    /// 3 in plane stress (σzz = 0), 6 in a solid.
    pub fn stress_len(self) -> usize {
        match self {
            ElementKind::PlaneStress { .. } => 3,
            ElementKind::PlaneStrain | ElementKind::Axisymmetric => 4,
            ElementKind::Solid => 6,
        }
    }

    /// The names of the stress components of [`ElementKind::stress`] (four)
    /// or of [`ElementKind::tet_stress`] (six, VTK's order).
    pub fn stress_names(self) -> &'static [&'static str] {
        match self {
            ElementKind::Axisymmetric => &AXI_STRESS_NAMES,
            ElementKind::Solid => &SOLID_STRESS_NAMES,
            _ => &PLANE_STRESS_NAMES,
        }
    }

    /// The component of the stress that `name` denotes in this kind: its
    /// own names, and on an axisymmetric model also the plane names (sxx =
    /// σrr, syy = σzz, sxy = σrz; szz is its own σzz). Some(Err(the plane
    /// name of the same component)) for an axisymmetric name on a plane
    /// model; None when `name` names no stress component.
    pub fn stress_component(self, name: &str) -> Option<Result<usize, &'static str>> {
        let own = self.stress_names();
        if let Some(i) = own.iter().position(|n| *n == name) {
            return Some(Ok(i));
        }
        let plane = PLANE_STRESS_NAMES.iter().position(|n| *n == name);
        let axi = AXI_STRESS_NAMES.iter().position(|n| *n == name);
        match (self, plane, axi) {
            (ElementKind::Axisymmetric, Some(i), _) => Some(Ok(i)),
            (_, _, Some(i)) => Some(Err(PLANE_STRESS_NAMES[i])),
            _ => None,
        }
    }

    /// The component names of the output arrays (displacement, stress, …).
    pub fn component_names(self) -> ComponentNames {
        match self {
            ElementKind::Axisymmetric => AXI_COMPONENT_NAMES,
            ElementKind::Solid => SOLID_COMPONENT_NAMES,
            _ => PLANE_COMPONENT_NAMES,
        }
    }

    /// The rigid modes of a free body of this kind: the three motions of
    /// the plane, the axial translation only when axisymmetric (a radial
    /// translation strains the hoop, u_r/r ≠ 0), three translations and
    /// three rotations in a solid (methods.md §1.7, §10).
    pub fn rigid_modes(self) -> &'static [RigidMode] {
        match self {
            ElementKind::Axisymmetric => &PLANE_MODES[1..2],
            ElementKind::Solid => &SOLID_MODES,
            _ => &PLANE_MODES,
        }
    }

    /// The motions of the plane that are rigid modes of a 2D kind, as a
    /// mask over [translation x, translation y, rotation].
    pub fn plane_mode_mask(self) -> [bool; 3] {
        PLANE_MODES.map(|m| self.rigid_modes().contains(&m))
    }

    /// The number of rigid modes of a free body ([`ElementKind::rigid_modes`]).
    pub fn n_rigid_modes(self) -> usize {
        self.rigid_modes().len()
    }

    /// The material matrix of `m` in this kind (methods.md §1.4, §10).
    pub fn material(self, m: &Material) -> MaterialMatrix {
        MaterialMatrix {
            d: match self {
                ElementKind::PlaneStrain => Elasticity::Plane(d_plane_strain(m)),
                ElementKind::PlaneStress { .. } => Elasticity::Plane(d_plane_stress(m)),
                ElementKind::Axisymmetric => Elasticity::Axisymmetric(d_axi(m)),
                ElementKind::Solid => Elasticity::Solid(d_solid(m)),
            },
            nu: m.nu,
            out_of_plane: self.stress_len() == 4,
        }
    }

    /// The element stiffness C_e (6×6): t_h|T| BᵀDB, or r̄|T| B4ᵀD4B4 per
    /// radian (methods.md §2.2, §10).
    pub fn stiffness(self, p: &[Point; 3], d: &MaterialMatrix) -> [[f64; 6]; 6] {
        match &d.d {
            Elasticity::Plane(d3) => stiffness(p, d3, self.thickness()),
            Elasticity::Axisymmetric(d4) => axi_stiffness(p, d4),
            Elasticity::Solid(_) => unreachable!("{}", NO_TRIANGLES),
        }
    }

    /// Rows 2a and 2a + 1 of [`ElementKind::stiffness`] (vertex `a`), bit
    /// for bit.
    #[inline]
    pub fn stiffness_rows(self, p: &[Point; 3], d: &MaterialMatrix, a: usize) -> [[f64; 6]; 2] {
        match &d.d {
            Elasticity::Plane(d3) => stiffness_rows(p, d3, self.thickness(), a),
            Elasticity::Axisymmetric(d4) => {
                let k = axi_stiffness(p, d4);
                [k[2 * a], k[2 * a + 1]]
            }
            Elasticity::Solid(_) => unreachable!("{}", NO_TRIANGLES),
        }
    }

    /// The four stress components of [`ElementKind::stress_names`] at the
    /// element (constant, or at the centroid when axisymmetric) from its
    /// displacements `u`.
    pub fn stress(self, p: &[Point; 3], d: &MaterialMatrix, u: &[f64; 6]) -> [f64; 4] {
        match &d.d {
            Elasticity::Plane(d3) => plane_stress_of(p, d3, d.nu, d.out_of_plane, u),
            Elasticity::Axisymmetric(d4) => axi_stress(p, d4, u),
            Elasticity::Solid(_) => unreachable!("{}", NO_TRIANGLES),
        }
    }

    /// The equivalent (von Mises) stress of [`ElementKind::stress`]: the
    /// report's τe in the plane, with σθθ when axisymmetric.
    pub fn von_mises(self, s: &[f64; 4]) -> f64 {
        match self {
            ElementKind::Axisymmetric => von_mises_axi(s),
            _ => von_mises(s),
        }
    }

    /// The body load of vertex `a` of a triangle `p` (the element part of
    /// d): th |T|/3 f_b, or ∫ N_a (f_b r + c r² e_r) dA per radian with the
    /// centrifugal coefficient c = ρω² (methods.md §2.2, §10).
    #[inline]
    pub fn body_load(self, p: &[Point; 3], a: usize, fb: Vector, c: f64) -> Vector {
        match self {
            ElementKind::Axisymmetric => axi_body_load(p, a, fb, c),
            _ => {
                let area = area2(p) / 2.0;
                let th = self.thickness();
                [th * area / 3.0 * fb[0], th * area / 3.0 * fb[1]]
            }
        }
    }

    /// [`ElementKind::body_load`] as the nodal loads sum it (th·2|T|/6 per
    /// vertex: the same value, rounded as the reactions' balance has
    /// always been).
    #[inline]
    pub fn nodal_body_load(self, p: &[Point; 3], a: usize, fb: Vector, c: f64) -> Vector {
        match self {
            ElementKind::Axisymmetric => axi_body_load(p, a, fb, c),
            _ => {
                let w = self.thickness() * area2(p) / 6.0;
                [w * fb[0], w * fb[1]]
            }
        }
    }

    /// The boundary measure of node `x` on a segment (x, y) of length
    /// `len`, ∫ N_x ds = ℓ/2, or ∫ N_x r ds = ℓ(2r_x + r_y)/6 per radian
    /// (methods.md §10): the tributary weight of a contact row, without
    /// the thickness.
    #[inline]
    pub fn boundary_weight(self, len: f64, x: Point, y: Point) -> f64 {
        match self {
            ElementKind::Axisymmetric => len * (2.0 * x[0] + y[0]) / 6.0,
            _ => len / 2.0,
        }
    }

    /// The weight of a constant traction at node `x` of a segment (x, y):
    /// ½ th ℓ, or [`ElementKind::boundary_weight`] per radian.
    #[inline]
    pub fn traction_weight(self, len: f64, x: Point, y: Point) -> f64 {
        match self {
            ElementKind::Axisymmetric => self.boundary_weight(len, x, y),
            _ => 0.5 * self.thickness() * len,
        }
    }

    /// The density of the boundary measure at a point `x` of a segment:
    /// r when axisymmetric (the mortar integrals, methods.md §7.1, §10), 1
    /// otherwise.
    #[inline]
    pub fn line_density(self, x: Point) -> f64 {
        match self {
            ElementKind::Axisymmetric => x[0],
            _ => 1.0,
        }
    }

    /// The rows of vertex `a` of the element stiffness of a cell `p` (a
    /// triangle, D = 2 and N = 3, or a tetrahedron, D = 3 and N = 4), as
    /// its N blocks of D×D: `k[b][i][j]` = C_e[D a + i][D b + j]. The one
    /// entry point of the shared assembly (`stiffness::assemble`); the
    /// plane's values are [`ElementKind::stiffness_rows`]'s, bit for bit.
    #[inline]
    pub fn cell_stiffness_rows<const D: usize, const N: usize>(
        self,
        p: &[PointD<D>; N],
        d: &MaterialMatrix,
        a: usize,
    ) -> [[[f64; D]; D]; N] {
        let blocks = |row: &dyn Fn(usize, usize) -> f64| {
            std::array::from_fn(|b| {
                std::array::from_fn(|i| std::array::from_fn(|j| row(i, D * b + j)))
            })
        };
        match &d.d {
            Elasticity::Solid(d6) => {
                let k = tet_stiffness(&cell_points(p), d6);
                blocks(&|i, c| k[D * a + i][c])
            }
            _ => {
                let k = self.stiffness_rows(&cell_points(p), d, a);
                blocks(&|i, c| k[i][c])
            }
        }
    }

    /// The body load of vertex `a` of a cell `p` (the element part of d):
    /// [`ElementKind::body_load`] of a triangle, |T|/4 f_b of a
    /// tetrahedron (`c`, the centrifugal coefficient, is the plane's).
    #[inline]
    pub fn cell_body_load<const D: usize, const N: usize>(
        self,
        p: &[PointD<D>; N],
        a: usize,
        fb: PointD<D>,
        c: f64,
    ) -> PointD<D> {
        match self {
            ElementKind::Solid => {
                let f = self.tet_body_load(&cell_points(p), std::array::from_fn(|k| fb[k]));
                std::array::from_fn(|k| f[k])
            }
            _ => {
                let f = self.body_load(&cell_points(p), a, std::array::from_fn(|k| fb[k]), c);
                std::array::from_fn(|k| f[k])
            }
        }
    }

    /// C_e = |T| BᵀDB (12×12) of a tetrahedron of a solid model
    /// (docs/design.md §"Adding a kind: solid 3D"; methods.md §2.2 in 3D).
    pub fn tet_stiffness(self, p: &[Point3; 4], d: &MaterialMatrix) -> [[f64; 12]; 12] {
        tet_stiffness(p, &d.solid())
    }

    /// The six stresses (σxx, σyy, σzz, σxy, σyz, σxz) of a tetrahedron
    /// from its displacements `u` (3 per vertex).
    pub fn tet_stress(self, p: &[Point3; 4], d: &MaterialMatrix, u: &[f64; 12]) -> [f64; 6] {
        tet_stress(p, &d.solid(), u)
    }

    /// The body load of each vertex of a tetrahedron: |T|/4 f_b.
    pub fn tet_body_load(self, p: &[Point3; 4], fb: Vector3) -> Vector3 {
        let w = crate::mesh::gmsh::volume6(p).abs() / 24.0;
        fb.map(|f| w * f)
    }

    /// The boundary measure of each node of a boundary triangle, |F|/3,
    /// and the triangle's unit normal (right-handed to its node order).
    pub fn facet_weight(self, p: &[Point3; 3]) -> (f64, Vector3) {
        let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        let a2 = dot(n, n).sqrt();
        (a2 / 6.0, n.map(|c| c / a2))
    }
}

/// The vertices of a cell as the kind's own type ([`Point`]s of a
/// triangle, [`Point3`]s of a tetrahedron): the same values; a cell of
/// another shape is a programming error (an index out of bounds).
#[inline]
fn cell_points<const D: usize, const N: usize, const E: usize, const M: usize>(
    p: &[PointD<D>; N],
) -> [PointD<E>; M] {
    debug_assert!(
        D == E && N == M,
        "a cell of {N} points in {D}D read as {M} in {E}D"
    );
    std::array::from_fn(|i| std::array::from_fn(|k| p[i][k]))
}

/// What the triangle methods say when asked for a solid's element.
const NO_TRIANGLES: &str = "a solid model's cells are tetrahedra (ElementKind::tet_*)";

fn sub(a: Point3, b: Point3) -> Vector3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: Vector3, b: Vector3) -> Vector3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: Vector3, b: Vector3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The conditions r·u = 0 an [`ElementKind`] imposes by itself
/// ([`ElementKind::implied_conditions`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ImpliedConditions {
    /// What sets them, in messages ("the axis r = 0 (…)").
    pub what: &'static str,
    /// The group of their reactions: (kind, name).
    pub group: (&'static str, &'static str),
    /// The unit direction r of the condition r·u = 0.
    pub direction: Vector,
    /// The points they hold, in increasing order.
    pub points: Vec<usize>,
}

/// A point outside the domain of an [`ElementKind`] (x = r < 0 in an
/// axisymmetric model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutsideDomain {
    /// The point.
    pub point: usize,
    /// Where it lies.
    pub at: Point,
}

impl OutsideDomain {
    /// The message of the error, naming the point by its mesh node tag
    /// `node`.
    pub fn message(&self, node: u64) -> String {
        format!(
            "[model] plane = \"axisymmetric\" takes x = r >= 0, but node {node} lies at x = {:e}; mirror the mesh to r >= 0",
            self.at[0]
        )
    }
}

/// The material matrix of one material in one [`ElementKind`]
/// ([`ElementKind::material`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialMatrix {
    d: Elasticity,
    /// ν: σzz = ν(σxx + σyy) of plane strain.
    nu: f64,
    /// Whether σzz is ν(σxx + σyy) (plane strain) rather than 0.
    out_of_plane: bool,
}

/// D (3×3) of a plane model, D4 (4×4) of an axisymmetric one, D6 (6×6)
/// of a solid.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Elasticity {
    Plane([[f64; 3]; 3]),
    Axisymmetric([[f64; 4]; 4]),
    Solid([[f64; 6]; 6]),
}

impl MaterialMatrix {
    /// D6 of a solid model's material.
    fn solid(&self) -> [[f64; 6]; 6] {
        match self.d {
            Elasticity::Solid(d6) => d6,
            _ => unreachable!("a plane model's material asked for its 3D matrix"),
        }
    }
}

/// D of plane strain for ē = (e11, e22, 2e12) (methods.md §1.4); also the
/// in-plane block of the axisymmetric D4.
fn d_plane_strain(m: &Material) -> [[f64; 3]; 3] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    [
        [f * (1.0 - nu), f * nu, 0.0],
        [f * nu, f * (1.0 - nu), 0.0],
        [0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
    ]
}

/// D of plane stress for ē = (e11, e22, 2e12) (methods.md §1.4).
fn d_plane_stress(m: &Material) -> [[f64; 3]; 3] {
    let (e, nu) = (m.e, m.nu);
    let f = e / (1.0 - nu * nu);
    [
        [f, f * nu, 0.0],
        [f * nu, f, 0.0],
        [0.0, 0.0, f * (1.0 - nu) / 2.0],
    ]
}

/// D6 of an isotropic solid for ε = (εxx, εyy, εzz, 2εxy, 2εyz, 2εxz):
/// λ + 2μ on the normal diagonal, λ off it, μ on the shears.
pub fn d_solid(m: &Material) -> [[f64; 6]; 6] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let (a, b, g) = (f * (1.0 - nu), f * nu, f * (1.0 - 2.0 * nu) / 2.0);
    let mut d = [[0.0; 6]; 6];
    for i in 0..3 {
        for j in 0..3 {
            d[i][j] = if i == j { a } else { b };
        }
        d[3 + i][3 + i] = g;
    }
    d
}

/// B (6×12) of a tetrahedron, for ε in the order of [`d_solid`], and its
/// volume |T|: the gradients of the barycentric coordinates are the rows
/// of J⁻¹, J = [p1 − p0, p2 − p0, p3 − p0] (cofactors over det J = 6|T|).
pub fn tet_b(p: &[Point3; 4]) -> ([[f64; 12]; 6], f64) {
    let (e1, e2, e3) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let det = dot(e1, cross(e2, e3));
    let g1 = cross(e2, e3).map(|c| c / det);
    let g2 = cross(e3, e1).map(|c| c / det);
    let g3 = cross(e1, e2).map(|c| c / det);
    let g0 = [0, 1, 2].map(|k| -(g1[k] + g2[k] + g3[k]));
    let mut b = [[0.0; 12]; 6];
    for (a, g) in [g0, g1, g2, g3].iter().enumerate() {
        let c = 3 * a;
        b[0][c] = g[0];
        b[1][c + 1] = g[1];
        b[2][c + 2] = g[2];
        b[3][c] = g[1];
        b[3][c + 1] = g[0];
        b[4][c + 1] = g[2];
        b[4][c + 2] = g[1];
        b[5][c] = g[2];
        b[5][c + 2] = g[0];
    }
    (b, det.abs() / 6.0)
}

/// C_e = |T| BᵀD6B (12×12) of a tetrahedron.
pub fn tet_stiffness(p: &[Point3; 4], d6: &[[f64; 6]; 6]) -> [[f64; 12]; 12] {
    let (b, vol) = tet_b(p);
    let mut db = [[0.0; 12]; 6];
    for i in 0..6 {
        for j in 0..12 {
            db[i][j] = (0..6).map(|k| d6[i][k] * b[k][j]).sum();
        }
    }
    let mut k = [[0.0; 12]; 12];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = vol * (0..6).map(|l| b[l][i] * db[l][j]).sum::<f64>();
        }
    }
    k
}

/// σ = D6 B u of a tetrahedron, (σxx, σyy, σzz, σxy, σyz, σxz).
pub fn tet_stress(p: &[Point3; 4], d6: &[[f64; 6]; 6], u: &[f64; 12]) -> [f64; 6] {
    let (b, _) = tet_b(p);
    let mut e = [0.0; 6];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..12).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 6];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..6).map(|k| d6[i][k] * e[k]).sum();
    }
    s
}

/// The 3D von Mises stress of (σxx, σyy, σzz, σxy, σyz, σxz):
/// sqrt(½[(σxx−σyy)² + (σyy−σzz)² + (σzz−σxx)²] + 3(σxy² + σyz² + σxz²)).
pub fn von_mises_solid(s: &[f64; 6]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]))
        .max(0.0)
        .sqrt()
}

/// The principal stresses σ1 ≥ σ2 ≥ σ3 of (σxx, σyy, σzz, σxy, σyz, σxz):
/// the eigenvalues of the symmetric 3×3 tensor by the trigonometric
/// formula of the deviator's invariants (Smith, CACM 4 (1961) 168).
pub fn principal_solid(s: &[f64; 6]) -> [f64; 3] {
    let (xx, yy, zz, xy, yz, xz) = (s[0], s[1], s[2], s[3], s[4], s[5]);
    let off = xy * xy + yz * yz + xz * xz;
    let q = (xx + yy + zz) / 3.0;
    let (a, b, c) = (xx - q, yy - q, zz - q);
    let p2 = a * a + b * b + c * c + 2.0 * off;
    if p2 <= 0.0 || !p2.is_finite() {
        return [q, q, q];
    }
    let p = (p2 / 6.0).sqrt();
    // det((σ − qI)/p) / 2
    let det = a * (b * c - yz * yz) - xy * (xy * c - yz * xz) + xz * (xy * yz - b * xz);
    let r = (det / (p * p * p) / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let s1 = q + 2.0 * p * phi.cos();
    let s3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    [s1, 3.0 * q - s1 - s3, s3]
}

/// Twice the signed area: positive for counter-clockwise vertices.
pub fn area2(p: &[Point; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
}

/// B (3×6) of §2.2 for counter-clockwise vertices, and |T|.
pub fn b_matrix(p: &[Point; 3]) -> ([[f64; 6]; 3], f64) {
    let a2 = area2(p);
    let b = [p[1][1] - p[2][1], p[2][1] - p[0][1], p[0][1] - p[1][1]];
    let c = [p[2][0] - p[1][0], p[0][0] - p[2][0], p[1][0] - p[0][0]];
    let mut bm = [[0.0; 6]; 3];
    for a in 0..3 {
        bm[0][2 * a] = b[a] / a2;
        bm[1][2 * a + 1] = c[a] / a2;
        bm[2][2 * a] = c[a] / a2;
        bm[2][2 * a + 1] = b[a] / a2;
    }
    (bm, a2 / 2.0)
}

/// D B (3×6).
#[inline]
fn d_times_b(d: &[[f64; 3]; 3], b: &[[f64; 6]; 3]) -> [[f64; 6]; 3] {
    let mut db = [[0.0; 6]; 3];
    for i in 0..3 {
        for j in 0..6 {
            db[i][j] = (0..3).map(|k| d[i][k] * b[k][j]).sum();
        }
    }
    db
}

/// Entry (i, j) of C_e from B, |T| and D B: the one expression that both
/// [`stiffness`] and [`stiffness_rows`] use, so that they agree bit for bit.
#[inline]
fn ke_entry(b: &[[f64; 6]; 3], db: &[[f64; 6]; 3], th: f64, area: f64, i: usize, j: usize) -> f64 {
    th * area * (0..3).map(|l| b[l][i] * db[l][j]).sum::<f64>()
}

/// C_e = t_h |T| BᵀDB (6×6).
pub fn stiffness(p: &[Point; 3], d: &[[f64; 3]; 3], th: f64) -> [[f64; 6]; 6] {
    let (b, area) = b_matrix(p);
    let db = d_times_b(d, &b);
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ke_entry(&b, &db, th, area, i, j);
        }
    }
    k
}

/// Rows 2a and 2a+1 of C_e (the two rows of vertex `a`), bit for bit equal
/// to those of [`stiffness`].
#[inline]
pub fn stiffness_rows(p: &[Point; 3], d: &[[f64; 3]; 3], th: f64, a: usize) -> [[f64; 6]; 2] {
    let (b, area) = b_matrix(p);
    let db = d_times_b(d, &b);
    let mut k = [[0.0; 6]; 2];
    for (r, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ke_entry(&b, &db, th, area, 2 * a + r, j);
        }
    }
    k
}

/// Stresses (σxx, σyy, σxy, σzz) of a plane element from its
/// displacements: σzz = ν(σxx + σyy) when `out_of_plane` (plane strain),
/// else 0.
fn plane_stress_of(
    p: &[Point; 3],
    d: &[[f64; 3]; 3],
    nu: f64,
    out_of_plane: bool,
    u: &[f64; 6],
) -> [f64; 4] {
    let (b, _) = b_matrix(p);
    let mut e = [0.0; 3];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..6).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 3];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..3).map(|k| d[i][k] * e[k]).sum();
    }
    let szz = if out_of_plane {
        nu * (s[0] + s[1])
    } else {
        0.0
    };
    [s[0], s[1], s[2], szz]
}

/// D4 of an axisymmetric body for ε = (ε_rr, ε_zz, 2ε_rz, ε_θθ)
/// (docs/methods.md §10; Zienkiewicz & Taylor, The Finite Element Method,
/// vol. 1, ch. "Axisymmetric stress analysis").
pub fn d_axi(m: &Material) -> [[f64; 4]; 4] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let (a, b, g) = (f * (1.0 - nu), f * nu, f * (1.0 - 2.0 * nu) / 2.0);
    [
        [a, b, 0.0, b],
        [b, a, 0.0, b],
        [0.0, 0.0, g, 0.0],
        [b, b, 0.0, a],
    ]
}

/// The centroid radius r̄ = (r₁ + r₂ + r₃)/3 of a triangle (x = r).
pub fn centroid_r(p: &[Point; 3]) -> f64 {
    (p[0][0] + p[1][0] + p[2][0]) / 3.0
}

/// B4 (4×6) of the axisymmetric P1 triangle with the hoop row evaluated
/// at the centroid, N_a(r̄)/r̄ = 1/(3r̄): the one-point rule for the hoop
/// terms, finite whenever the triangle has area (r̄ > 0 even with two
/// vertices on the axis), with |T|, r̄. Zienkiewicz & Taylor (vol. 1,
/// "Axisymmetric stress analysis") give this centroid approximation; the
/// in-plane rows are constant, so r̄|T| BᵀD4B is the one-point rule of
/// ∫ BᵀD4B r dA (docs/methods.md §10).
pub fn axi_b(p: &[Point; 3]) -> ([[f64; 6]; 4], f64, f64) {
    let (b3, area) = b_matrix(p);
    let rbar = centroid_r(p);
    let mut b = [[0.0; 6]; 4];
    b[..3].copy_from_slice(&b3);
    for a in 0..3 {
        b[3][2 * a] = 1.0 / (3.0 * rbar);
    }
    (b, area, rbar)
}

/// C_e = r̄ |T| B4ᵀ D4 B4 (6×6, per radian) of the axisymmetric triangle.
pub fn axi_stiffness(p: &[Point; 3], d4: &[[f64; 4]; 4]) -> [[f64; 6]; 6] {
    let (b, area, rbar) = axi_b(p);
    let mut db = [[0.0; 6]; 4];
    for i in 0..4 {
        for j in 0..6 {
            db[i][j] = (0..4).map(|k| d4[i][k] * b[k][j]).sum();
        }
    }
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = rbar * area * (0..4).map(|l| b[l][i] * db[l][j]).sum::<f64>();
        }
    }
    k
}

/// ∫ N_a (f_b r + c r² e_r) dA over an axisymmetric triangle, exactly
/// (∫ λ₁^i λ₂^j λ₃^k dA = 2|T| i! j! k! / (i + j + k + 2)!): the nodal force
/// per radian of vertex `a` from a body force f_b (gravity, along z) and a
/// centrifugal load c r along r (c = ρω²).
pub fn axi_body_load(p: &[Point; 3], a: usize, fb: Vector, c: f64) -> Vector {
    let area = area2(p) / 2.0;
    let r = [p[0][0], p[1][0], p[2][0]];
    let w1 = area / 12.0 * (r[a] + r[0] + r[1] + r[2]);
    let fact = [1.0, 1.0, 2.0, 6.0];
    let mut w2 = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let mut k = [0usize; 3];
            k[a] += 1;
            k[i] += 1;
            k[j] += 1;
            w2 += r[i] * r[j] * 2.0 * area * fact[k[0]] * fact[k[1]] * fact[k[2]] / 120.0;
        }
    }
    [w1 * fb[0] + c * w2, w1 * fb[1]]
}

/// (σ_rr, σ_zz, σ_rz, σ_θθ) at the centroid of an axisymmetric triangle.
fn axi_stress(p: &[Point; 3], d4: &[[f64; 4]; 4], u: &[f64; 6]) -> [f64; 4] {
    let (b, _, _) = axi_b(p);
    let mut e = [0.0; 4];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..6).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 4];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..4).map(|k| d4[i][k] * e[k]).sum();
    }
    s
}

/// von Mises from the four components (σ_rr, σ_zz, σ_rz, σ_θθ) of an
/// axisymmetric stress: sqrt(½[(σ1−σ2)² + (σ2−σ3)² + (σ3−σ1)²] + 3τ²).
pub fn von_mises_axi(s: &[f64; 4]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[3], s[3] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * s[2] * s[2])
        .max(0.0)
        .sqrt()
}

/// The report's equivalent stress τe = sqrt(σxx² + σyy² − σxxσyy + 3σxy²) (§1.4).
pub fn von_mises(s: &[f64; 4]) -> f64 {
    (s[0] * s[0] + s[1] * s[1] - s[0] * s[1] + 3.0 * s[2] * s[2])
        .max(0.0)
        .sqrt()
}

/// In-plane principal stresses, σ1 ≥ σ2.
pub fn principal(s: &[f64; 4]) -> [f64; 2] {
    let c = 0.5 * (s[0] + s[1]);
    let r = (0.25 * (s[0] - s[1]).powi(2) + s[2] * s[2]).sqrt();
    [c + r, c - r]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_motions_have_zero_energy_and_stiffness_is_symmetric() {
        let p = [[0.0, 0.0], [2.0, 0.3], [0.4, 1.5]];
        let m = Material {
            e: 1e9,
            nu: 0.3,
            rho: 0.0,
        };
        let d = d_plane_strain(&m);
        let k = stiffness(&p, &d, 1.0);
        for i in 0..6 {
            for j in 0..6 {
                assert!((k[i][j] - k[j][i]).abs() < 1e-6 * k[0][0].abs());
            }
        }
        // translations and the infinitesimal rotation (−y, x)
        let modes = [
            [1.0, 0.0, 1.0, 0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
            [-p[0][1], p[0][0], -p[1][1], p[1][0], -p[2][1], p[2][0]],
        ];
        for z in modes {
            for row in k.iter() {
                let f: f64 = row.iter().zip(&z).map(|(a, b)| a * b).sum();
                assert!(f.abs() < 1e-6 * k[0][0].abs(), "{f}");
            }
        }
    }

    #[test]
    fn stiffness_rows_equal_stiffness_bit_for_bit() {
        let p = [[0.1, -0.2], [2.3, 0.35], [0.45, 1.7]];
        let m = Material {
            e: 3.1e10,
            nu: 0.27,
            rho: 0.0,
        };
        for d in [d_plane_strain(&m), d_plane_stress(&m)] {
            let k = stiffness(&p, &d, 0.7);
            for a in 0..3 {
                let r = stiffness_rows(&p, &d, 0.7, a);
                assert_eq!(r[0], k[2 * a]);
                assert_eq!(r[1], k[2 * a + 1]);
            }
        }
    }

    /// The axisymmetric element: symmetric, zero energy for the axial
    /// translation only, and exact for the uniform state u_r = εr, u_z = 0
    /// (σ_rr = σ_θθ = (a + b)ε, σ_zz = 2bε), also with vertices on the axis.
    #[test]
    fn axisymmetric_element_modes_and_uniform_expansion() {
        let m = Material {
            e: 2e11,
            nu: 0.3,
            rho: 0.0,
        };
        let d4 = d_axi(&m);
        for p in [
            [[0.0, 0.0], [1.0, 0.2], [0.0, 1.0]],
            [[1.0, 0.0], [2.0, 0.3], [1.2, 1.5]],
        ] {
            let k = axi_stiffness(&p, &d4);
            for i in 0..6 {
                for j in 0..6 {
                    assert!((k[i][j] - k[j][i]).abs() < 1e-9 * k[1][1].abs());
                }
            }
            let axial = [0.0, 1.0, 0.0, 1.0, 0.0, 1.0];
            let radial = [1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
            let f = |z: &[f64; 6]| -> f64 {
                k.iter()
                    .map(|row| row.iter().zip(z).map(|(a, b)| a * b).sum::<f64>().abs())
                    .fold(0.0, f64::max)
            };
            assert!(f(&axial) < 1e-6 * k[1][1]);
            assert!(f(&radial) > 1e-3 * k[0][0]);
            let eps = 1e-3;
            let u = [eps * p[0][0], 0.0, eps * p[1][0], 0.0, eps * p[2][0], 0.0];
            let kind = ElementKind::Axisymmetric;
            let s = kind.stress(&p, &kind.material(&m), &u);
            let want = (d4[0][0] + d4[0][1]) * eps;
            assert!((s[0] - want).abs() < 1e-9 * want, "{s:?}");
            assert!((s[3] - want).abs() < 1e-9 * want, "{s:?}");
            assert!((s[1] - 2.0 * d4[0][1] * eps).abs() < 1e-9 * want);
            assert!(s[2].abs() < 1e-9 * want);
        }
    }

    /// The exact load integrals: Σ_a ∫N_a r = ∫r = |T| r̄ and
    /// Σ_a ∫N_a r² = ∫r² = |T|/6 (Σr_i² + Σ_{i<j} r_i r_j)·… checked on
    /// a unit right triangle by a fine midpoint sum.
    #[test]
    fn axisymmetric_body_load_integrals() {
        let p = [[0.5, 0.0], [1.5, 0.0], [0.5, 1.0]];
        let (mut s1, mut s2) = (0.0, 0.0);
        for a in 0..3 {
            let f = axi_body_load(&p, a, [0.0, 1.0], 1.0);
            s1 += f[1];
            s2 += f[0];
        }
        let n = 400;
        let (mut q1, mut q2) = (0.0, 0.0);
        for i in 0..n {
            for j in 0..n - i {
                let x = 0.5 + (i as f64 + 1.0 / 3.0) / n as f64;
                let w = 0.5 / (n * n) as f64;
                q1 += x * w;
                q2 += x * x * w;
                if j + i + 1 < n {
                    let x2 = 0.5 + (i as f64 + 2.0 / 3.0) / n as f64;
                    q1 += x2 * w;
                    q2 += x2 * x2 * w;
                }
            }
        }
        assert!((s1 - q1).abs() < 1e-3 * q1, "{s1} {q1}");
        assert!((s2 - q2).abs() < 1e-3 * q2, "{s2} {q2}");
        assert!((s1 - 0.5 * centroid_r(&p)).abs() < 1e-14);
    }

    #[test]
    fn uniaxial_stress_state() {
        // u = (εx, 0): plane stress σxx = E/(1−ν²) ε, σyy = ν σxx
        let p = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let m = Material {
            e: 200.0,
            nu: 0.25,
            rho: 0.0,
        };
        let kind = ElementKind::PlaneStress { thickness: 1.0 };
        let eps = 1e-3;
        let u = [0.0, 0.0, eps, 0.0, 0.0, 0.0];
        let s = kind.stress(&p, &kind.material(&m), &u);
        let sxx = 200.0 / (1.0 - 0.0625) * eps;
        assert!((s[0] - sxx).abs() < 1e-12);
        assert!((s[1] - 0.25 * sxx).abs() < 1e-12);
        assert_eq!(s[3], 0.0);
        let pr = principal(&s);
        assert!((pr[0] - sxx).abs() < 1e-12 && (pr[1] - 0.25 * sxx).abs() < 1e-12);
    }

    fn steel() -> Material {
        Material {
            e: 2.1e11,
            nu: 0.3,
            rho: 7800.0,
        }
    }

    /// An irregular tetrahedron, scaled by `s`.
    fn tet(s: f64) -> [Point3; 4] {
        [
            [0.1, -0.2, 0.05],
            [1.3, 0.1, -0.1],
            [0.2, 0.9, 0.3],
            [0.4, 0.35, 1.1],
        ]
        .map(|x| x.map(|c| s * c))
    }

    /// The solid element: symmetric, and its kernel is exactly the six
    /// rigid motions at every scale: six eigenvalues below 1e-12 of the
    /// largest, the seventh above 1e-3 of it, and K z = 0 for each motion.
    #[test]
    fn solid_stiffness_kernel_is_the_six_rigid_motions() {
        let kind = ElementKind::Solid;
        let d = kind.material(&steel());
        for s in [1e-3, 1.0, 1e3] {
            let p = tet(s);
            let k = kind.tet_stiffness(&p, &d);
            let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..12 {
                for j in 0..12 {
                    assert!((k[i][j] - k[j][i]).abs() <= 1e-13 * kmax);
                }
            }
            let rows: Vec<Vec<f64>> = k.iter().map(|r| r.to_vec()).collect();
            let (vals, _) = crate::linalg::dense::sym_eigen(&rows);
            let mut ev: Vec<f64> = vals.iter().map(|v| v.abs()).collect();
            ev.sort_by(|a, b| a.total_cmp(b));
            let top = ev[11];
            assert!(ev[5] < 1e-12 * top, "{ev:?}");
            assert!(ev[6] > 1e-3 * top, "{ev:?}");
            let c = p[0];
            for m in kind.rigid_modes() {
                let z: Vec<f64> = p.iter().flat_map(|&x| m.at(x, c, s)).collect();
                let kz = k
                    .iter()
                    .map(|r| r.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>().abs())
                    .fold(0.0, f64::max);
                assert!(kz < 1e-12 * top, "{m:?}: {kz}");
            }
        }
        assert_eq!(kind.n_rigid_modes(), 6);
    }

    /// The unit cube cut into 12 tetrahedra about an off-centre interior
    /// node (node 8): corners 0..8, each face two triangles.
    fn cube_patch() -> (Vec<Point3>, Vec<[usize; 4]>) {
        let mut x: Vec<Point3> = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        x.push([0.37, 0.58, 0.44]);
        let faces = [
            [0, 1, 3, 2],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 3, 7, 5],
        ];
        let mut tets = vec![];
        for f in faces {
            for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
                let mut c = [t[0], t[1], t[2], 8];
                if crate::mesh::gmsh::volume6(&c.map(|v| x[v])) < 0.0 {
                    c.swap(1, 2);
                }
                tets.push(c);
            }
        }
        (x, tets)
    }

    /// Patch test: a linear displacement u = G x + t on an irregular tet
    /// patch gives each element the exact stress D ε(G), and the interior
    /// node is in equilibrium without load (K u = 0 in its rows).
    #[test]
    fn solid_patch_test_linear_field_is_exact() {
        let kind = ElementKind::Solid;
        let m = steel();
        let d = kind.material(&m);
        let (x, tets) = cube_patch();
        let g = [
            [1e-3, 2e-4, -3e-4],
            [5e-4, -7e-4, 1e-4],
            [-2e-4, 3e-4, 4e-4],
        ];
        let u: Vec<Vector3> = x
            .iter()
            .map(|p| {
                [0, 1, 2].map(|i| (0..3).map(|j| g[i][j] * p[j]).sum::<f64>() + 0.01 * i as f64)
            })
            .collect();
        let eps = [
            g[0][0],
            g[1][1],
            g[2][2],
            g[0][1] + g[1][0],
            g[1][2] + g[2][1],
            g[0][2] + g[2][0],
        ];
        let d6 = d_solid(&m);
        let want: Vec<f64> = (0..6)
            .map(|i| (0..6).map(|k| d6[i][k] * eps[k]).sum())
            .collect();
        let smax = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut r = [0.0; 3];
        let mut kmax = 0.0f64;
        for t in &tets {
            let p = t.map(|v| x[v]);
            let ue: [f64; 12] = std::array::from_fn(|i| u[t[i / 3]][i % 3]);
            let s = kind.tet_stress(&p, &d, &ue);
            for i in 0..6 {
                assert!((s[i] - want[i]).abs() < 1e-12 * smax, "{s:?} {want:?}");
            }
            let k = kind.tet_stiffness(&p, &d);
            kmax = k.iter().flatten().fold(kmax, |a, v| a.max(v.abs()));
            let a = t.iter().position(|&v| v == 8).unwrap();
            for (c, rc) in r.iter_mut().enumerate() {
                *rc += (0..12).map(|j| k[3 * a + c][j] * ue[j]).sum::<f64>();
            }
        }
        let umax = u.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        for rc in r {
            assert!(rc.abs() < 1e-12 * kmax * umax, "{r:?}");
        }
    }

    /// Σ over the vertices of |T|/4 ρg is ρg·V; |F|/3 sums to |F| and the
    /// facet normal is the right-handed unit one.
    #[test]
    fn solid_body_load_and_facet_measure() {
        let kind = ElementKind::Solid;
        let (x, tets) = cube_patch();
        let fb = [1.0, -2.0, 9.81];
        let mut tot = [0.0; 3];
        for t in &tets {
            let f = kind.tet_body_load(&t.map(|v| x[v]), fb);
            for c in 0..3 {
                tot[c] += 4.0 * f[c];
            }
        }
        for c in 0..3 {
            assert!((tot[c] - fb[c]).abs() < 1e-14 * 10.0, "{tot:?}");
        }
        let (w, n) = kind.facet_weight(&[[0.0, 0.0, 2.0], [3.0, 0.0, 2.0], [0.0, 4.0, 2.0]]);
        assert!((3.0 * w - 6.0).abs() < 1e-14);
        assert_eq!(n, [0.0, 0.0, 1.0]);
    }

    /// von Mises: σ for uniaxial σ, √3 τ for any pure shear; principal
    /// stresses of R diag(3, −1, 2) Rᵀ are (3, 2, −1).
    #[test]
    fn solid_equivalent_and_principal_stresses() {
        assert!((von_mises_solid(&[5.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 5.0).abs() < 1e-14);
        for k in 3..6 {
            let mut s = [0.0; 6];
            s[k] = 2.0;
            assert!((von_mises_solid(&s) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
        }
        let (c, sn) = (0.3f64.cos(), 0.3f64.sin());
        let (c2, s2) = (1.1f64.cos(), 1.1f64.sin());
        let rz = [[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]];
        let rx = [[1.0, 0.0, 0.0], [0.0, c2, -s2], [0.0, s2, c2]];
        let r: Vec<[f64; 3]> = (0..3)
            .map(|i| [0, 1, 2].map(|j| (0..3).map(|k| rz[i][k] * rx[k][j]).sum()))
            .collect();
        let l = [3.0, -1.0, 2.0];
        let t = |i: usize, j: usize| (0..3).map(|k| r[i][k] * l[k] * r[j][k]).sum::<f64>();
        let s = [t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(1, 2), t(0, 2)];
        let p = principal_solid(&s);
        for (a, b) in p.iter().zip([3.0, 2.0, -1.0]) {
            assert!((a - b).abs() < 1e-12, "{p:?}");
        }
        assert_eq!(principal_solid(&[1.0, 1.0, 1.0, 0.0, 0.0, 0.0]), [1.0; 3]);
    }
}
