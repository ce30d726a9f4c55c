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

    /// Whether linear elements of this kind lock as ν → 0.5: every kind
    /// whose strain has a constrained volume (plane strain, axisymmetric,
    /// solid); plane stress lets the thickness change, and its modulus
    /// E/(1 − ν²) stays finite (docs/guide.md, "Nearly incompressible
    /// materials").
    pub fn locks_near_incompressible(self) -> bool {
        !matches!(self, ElementKind::PlaneStress { .. })
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

mod axi;
mod plane;
mod solid;
#[cfg(test)]
mod tests;

use axi::axi_stress;
pub use axi::*;
pub use plane::*;
use plane::{d_plane_strain, d_plane_stress, plane_stress_of};
pub use solid::*;
use solid::{cross, dot, sub};
