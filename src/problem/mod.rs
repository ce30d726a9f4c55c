//! The problem file (`*.toml`), as specified in `docs/problem-format.md`.
//!
//! Parsing is strict: unknown keys are rejected with the key, the table and
//! the line, so a typo never silently drops a load. Values are checked here
//! (E > 0, −1 < ν < 0.5, ρ ≥ 0, …); names are checked against the mesh in
//! `fem::topology`.

mod raw;
mod toml_error;
mod validate;

pub use crate::qp::SolverSection;
use serde::{Deserialize, Deserializer};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Largest magnitude accepted for E, loads and prescribed displacements:
/// their products (stiffness × displacement, energy) must stay far inside
/// the range of double precision. The smallest accepted E is its inverse.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// Longest name (group, material, probe) accepted: names are echoed in
/// messages, which must stay one short line.
pub const MAX_NAME: usize = 256;

/// A number as shown in a message: as Rust writes it when that is short
/// (`0.3`, `-250`), else in scientific form (`1e200`, not 201 digits).
pub fn num(v: f64) -> String {
    let plain = format!("{v}");
    if plain.len() <= 12 {
        plain
    } else {
        format!("{v:e}")
    }
}

/// A name as shown in a message: at most 60 characters, then `…`.
pub fn shorten(s: &str) -> String {
    const KEEP: usize = 60;
    if s.chars().count() <= KEEP {
        s.to_string()
    } else {
        let head: String = s.chars().take(KEEP).collect();
        format!("{head}… ({} characters)", s.chars().count())
    }
}

/// A vector key as written (`u`, `p`, `gravity`, `f`, a probe, a step's
/// `dirichlet` value): two components for a 2D mesh, three for a 3D one.
/// The dimension is the mesh's, known only once it is read, so the file
/// keeps what was written and [`Problem::check_dimension`] holds it against
/// the mesh (docs/problem-format.md §12). Equality compares the values.
#[derive(Debug, Clone, Copy)]
pub struct Components {
    c: [f64; 3],
    len: usize,
    /// Byte offset of the value in the problem file (for messages).
    at: Option<usize>,
}

impl PartialEq for Components {
    fn eq(&self, o: &Components) -> bool {
        self.values() == o.values()
    }
}

impl From<[f64; 2]> for Components {
    fn from(v: [f64; 2]) -> Components {
        Components {
            c: [v[0], v[1], 0.0],
            len: 2,
            at: None,
        }
    }
}

impl From<[f64; 3]> for Components {
    fn from(c: [f64; 3]) -> Components {
        Components {
            c,
            len: 3,
            at: None,
        }
    }
}

impl Components {
    /// The components as written.
    pub fn values(&self) -> &[f64] {
        &self.c[..self.len]
    }

    /// How many components were written (2 or 3).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Never: a vector key has two or three components.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// [x, y] (a 2D model; the dimension is checked before any use).
    pub fn xy(&self) -> [f64; 2] {
        [self.c[0], self.c[1]]
    }

    /// [x, y, z] (a 3D model; z = 0 for a 2-vector).
    pub fn xyz(&self) -> [f64; 3] {
        self.c
    }

    /// The same vector with every component scaled by `f`.
    pub fn scaled(&self, f: f64) -> Components {
        Components {
            c: self.c.map(|v| v * f),
            ..*self
        }
    }

    /// `[a, b]` or `[a, b, c]` as a message shows it.
    pub fn show(&self) -> String {
        let v: Vec<String> = self.values().iter().map(|&v| num(v)).collect();
        format!("[{}]", v.join(", "))
    }
}

fn components<E: serde::de::Error>(v: toml::Spanned<Vec<f64>>) -> Result<Components, E> {
    let at = Some(v.span().start);
    match v.get_ref().as_slice() {
        [a, b] => Ok(Components {
            c: [*a, *b, 0.0],
            len: 2,
            at,
        }),
        [a, b, c] => Ok(Components {
            c: [*a, *b, *c],
            len: 3,
            at,
        }),
        w => Err(E::custom(format!(
            "expected 2 components [x, y] (3, [x, y, z], in a 3D model), found {}",
            w.len()
        ))),
    }
}

/// `[x, y]` or `[x, y, z]`: serde's fixed-size arrays would drop a third
/// component silently, and the mesh decides which is right.
fn vector<'de, D: Deserializer<'de>>(d: D) -> Result<Components, D::Error> {
    components(toml::Spanned::<Vec<f64>>::deserialize(d)?)
}

fn opt_vector<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Components>, D::Error> {
    Option::<toml::Spanned<Vec<f64>>>::deserialize(d)?
        .map(components)
        .transpose()
}

fn map_vector<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<String, Components>, D::Error> {
    BTreeMap::<String, toml::Spanned<Vec<f64>>>::deserialize(d)?
        .into_iter()
        .map(|(k, v)| components(v).map(|p| (k, p)))
        .collect()
}

/// Errors of the problem file. The message names the file, and the key or
/// table where it applies.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Syntax { path: PathBuf, msg: String },
    #[error("{path}: {msg}")]
    Invalid { path: PathBuf, msg: String },
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSection {
    /// Path of the `.msh`, relative to the TOML file.
    pub file: PathBuf,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    #[default]
    Strain,
    Stress,
    /// Axisymmetric about the y axis: mesh x = r ≥ 0, y = z; every
    /// integral is per radian, ∫ · r dr dz (docs/methods.md §10).
    Axisymmetric,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(from = "raw::RawModel")]
pub struct ModelSection {
    pub plane: Plane,
    /// Thickness t_h (plane stress; multiplies every stiffness and load).
    pub thickness: f64,
    /// Gravity vector: body force F = ρ·gravity (methods.md §1.2).
    pub gravity: Option<Components>,
    /// Angular velocity ω [rad/s] about the axis (axisymmetric only): the
    /// centrifugal body force ρω²r along r (docs/methods.md §10).
    pub omega: Option<f64>,
    /// The load factor of the step on the centrifugal load ρω²r (set by
    /// [`ProblemFile::at_step`], like the factor on gravity; None = 1).
    pub centrifugal_factor: Option<f64>,
    /// The units the numbers are in, as labels only (`signorini plot`):
    /// `units = { length = "mm", stress = "MPa" }`; default m and Pa.
    /// Nothing is converted, and the solution does not depend on it.
    pub units: Option<Units>,
    /// Where `plane`, `thickness` and `omega` are written (byte offsets),
    /// None where absent: a 3D model refuses them naming the line
    /// ([`Problem::check_dimension`]).
    pub written_2d: [(&'static str, Option<usize>); 3],
}

/// `[model] units`: the names of the model's length and stress units
/// (labels of the figures; docs/problem-format.md §2).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields, try_from = "UnitsKeys")]
pub struct Units {
    pub length: String,
    pub stress: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct UnitsKeys {
    length: String,
    stress: String,
}

impl TryFrom<UnitsKeys> for Units {
    type Error = String;
    fn try_from(k: UnitsKeys) -> Result<Units, String> {
        for (key, v) in [("length", &k.length), ("stress", &k.stress)] {
            if v.trim().is_empty() || v.len() > 32 || v.chars().any(char::is_control) {
                return Err(format!(
                    "[model] units.{key} = {v:?}: a unit name of 1 to 32 printable bytes, e.g. \"mm\" or \"MPa\""
                ));
            }
        }
        Ok(Units {
            length: k.length,
            stress: k.stress,
        })
    }
}

impl Default for Units {
    /// SI: m and Pa.
    fn default() -> Units {
        Units {
            length: "m".into(),
            stress: "Pa".into(),
        }
    }
}

impl Units {
    /// The `[model] units` of a problem file's text (the checkpoint keeps
    /// it as `problem_toml`); SI when absent or unreadable.
    pub fn of_problem_text(text: &str) -> Units {
        let table: toml::Table = toml::from_str(text).unwrap_or_default();
        table
            .get("model")
            .and_then(|m| m.get("units"))
            .and_then(|u| u.clone().try_into::<Units>().ok())
            .unwrap_or_default()
    }
}

impl Default for ModelSection {
    fn default() -> Self {
        ModelSection {
            plane: Plane::Strain,
            thickness: 1.0,
            gravity: None,
            omega: None,
            centrifugal_factor: None,
            units: None,
            written_2d: [("plane", None), ("thickness", None), ("omega", None)],
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    #[serde(rename = "E")]
    pub e: f64,
    pub nu: f64,
    #[serde(default)]
    pub rho: f64,
}

/// A `[[dirichlet]]` entry: the group and what it prescribes.
#[derive(Debug, Clone, PartialEq)]
pub struct Dirichlet {
    pub on: String,
    pub value: Prescribed,
}

/// What a `[[dirichlet]]` prescribes: `u = [ux, uy]` (`[ux, uy, uz]` in
/// 3D), any of `ux`, `uy`, `uz` (a component not given stays free), or a
/// `turn` about an axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Prescribed {
    /// `u`: every component.
    All(Components),
    /// `ux`, `uy`, `uz`; at least one is present.
    Components {
        ux: Option<f64>,
        uy: Option<f64>,
        uz: Option<f64>,
    },
    /// `turn = { angle, axis, origin }`: u·e_θ = angle·ρ at each node, the
    /// radial and axial components free (docs/methods.md §2.5).
    Turn(Turn),
}

/// A rigid turn by `angle` (radians) about the axis through `origin` along
/// the unit `axis`: at a node x, ρ = |axis × (x − origin)| and
/// e_θ = axis × (x − origin)/ρ; the condition is u·e_θ = angle·ρ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turn {
    pub angle: f64,
    /// The unit axis as written and normalised (3D); None in a plane
    /// model, whose axis is z.
    pub axis: Option<Components>,
    /// The point on the axis; None: the origin.
    pub origin: Option<Components>,
}

impl Turn {
    /// The unit axis [x, y, z] (z when not given).
    pub fn axis_xyz(&self) -> [f64; 3] {
        self.axis.map_or([0.0, 0.0, 1.0], |a| a.xyz())
    }

    /// The origin [x, y, z] (z = 0 for a 2-vector; 0 when not given).
    pub fn origin_xyz(&self) -> [f64; 3] {
        self.origin.map_or([0.0; 3], |o| o.xyz())
    }

    /// The condition r·u = v at a node `x` ([x, y, 0] in a plane model):
    /// r = e_θ, v = angle·ρ; None on the axis, ρ ≤ 1e-12 × `size` (the
    /// model's size), where the turn sets nothing.
    pub fn condition(&self, x: [f64; 3], size: f64) -> Option<([f64; 3], f64)> {
        let (e, o) = (self.axis_xyz(), self.origin_xyz());
        let d = [x[0] - o[0], x[1] - o[1], x[2] - o[2]];
        let c = [
            e[1] * d[2] - e[2] * d[1],
            e[2] * d[0] - e[0] * d[2],
            e[0] * d[1] - e[1] * d[0],
        ];
        let rho = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        (rho > 1e-12 * size).then(|| (c.map(|v| v / rho), self.angle * rho))
    }
}

/// The size of a model for [`Turn::condition`]: the diagonal of the
/// bounding box of its points.
pub fn model_size(points: impl IntoIterator<Item = [f64; 3]>) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for x in points {
        for k in 0..3 {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    let d: f64 = (0..3).map(|k| (hi[k] - lo[k]).max(0.0).powi(2)).sum();
    d.sqrt()
}

impl From<[Option<f64>; 3]> for Prescribed {
    /// `ux`, `uy`, `uz` as given (None: free).
    fn from([ux, uy, uz]: [Option<f64>; 3]) -> Prescribed {
        Prescribed::Components { ux, uy, uz }
    }
}

impl Prescribed {
    /// The prescribed [ux, uy, uz]; None where the component is free (uz
    /// of a 2-vector `u` is None).
    pub fn components(&self) -> [Option<f64>; 3] {
        match *self {
            Prescribed::All(u) => {
                let [x, y, z] = u.xyz();
                [Some(x), Some(y), (u.len() == 3).then_some(z)]
            }
            Prescribed::Components { ux, uy, uz } => [ux, uy, uz],
            // Along e_θ, which varies from node to node: no fixed component.
            Prescribed::Turn(_) => [None; 3],
        }
    }

    /// The same components with every value scaled by `f`.
    fn scaled(&self, f: f64) -> Prescribed {
        match *self {
            Prescribed::All(u) => Prescribed::All(u.scaled(f)),
            Prescribed::Components { ux, uy, uz } => Prescribed::Components {
                ux: ux.map(|v| v * f),
                uy: uy.map(|v| v * f),
                uz: uz.map(|v| v * f),
            },
            Prescribed::Turn(t) => Prescribed::Turn(Turn {
                angle: t.angle * f,
                ..t
            }),
        }
    }

    /// The same components with the values `u` of a load step
    /// (`[[steps]] dirichlet`); a free component stays free.
    fn replaced(&self, u: Components) -> Prescribed {
        let c = u.xyz();
        match *self {
            Prescribed::All(_) => Prescribed::All(u),
            Prescribed::Components { ux, uy, uz } => Prescribed::Components {
                ux: ux.map(|_| c[0]),
                uy: uy.map(|_| c[1]),
                uz: uz.map(|_| c[2]),
            },
            // Refused when the file is read (validate::check_steps).
            Prescribed::Turn(t) => Prescribed::Turn(t),
        }
    }
}

/// A `[[traction]]` entry: the curve and its load.
#[derive(Debug, Clone, PartialEq)]
pub struct Traction {
    pub on: String,
    pub load: TractionLoad,
}

/// The load of a `[[traction]]` [N/m²].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TractionLoad {
    /// `p = [px, py]` (`[px, py, pz]` in 3D): a fixed vector.
    Vector(Components),
    /// `pn`: along the outward normal of the body owning the segment
    /// (negative pushes in).
    Normal(f64),
}

impl TractionLoad {
    fn scaled(&self, f: f64) -> TractionLoad {
        match *self {
            TractionLoad::Vector(p) => TractionLoad::Vector(p.scaled(f)),
            TractionLoad::Normal(v) => TractionLoad::Normal(v * f),
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slip {
    pub on: String,
}

/// A point force (extension): `f` [N per unit thickness; N in 3D] at a
/// physical point.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Force {
    pub on: String,
    #[serde(deserialize_with = "vector")]
    pub f: Components,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum NormalKind {
    /// Definition B of methods.md §2.6: one averaged normal per node.
    #[default]
    Averaged,
    /// Definition A: one row per segment through the node.
    Segment,
}

/// A `[[contact]]` entry: which curves it pairs and the friction law on
/// them (docs/problem-format.md §2, §4).
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    pub pair: ContactPair,
    pub friction: FrictionLaw,
}

/// The two forms of a `[[contact]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub enum ContactPair {
    /// `on = "curve"`: one physical curve shared by two bodies, node-to-node
    /// rows (docs/methods.md §2.6–2.7).
    Conforming { on: String, normals: NormalKind },
    /// `slave`, `master`: two curves, one on each body (docs/methods.md §7).
    NonMatching(NonMatchingPair),
}

/// A non-matching pair: slave curve projected onto the master curve.
#[derive(Debug, Clone, PartialEq)]
pub struct NonMatchingPair {
    pub slave: String,
    pub master: String,
    /// Largest initial gap at which a slave node is paired (None: every
    /// slave node that projects onto the master).
    pub max_gap: Option<f64>,
    /// `discretization` as written; None: the default, mortar rows, or
    /// node-to-segment rows when the slave is much stiffer than the master
    /// (decided with the mesh, `fem::pairs`; docs/problem-format.md §2).
    pub discretization: Option<Discretization>,
    /// `interference = true`: an initial overlap of the slave into the
    /// master is intended (a shrink or press fit); the negative gap enters
    /// g and is resolved in the first step (docs/problem-format.md §5).
    pub interference: bool,
}

/// The rows of a non-matching pair (`discretization`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Discretization {
    /// `"nts"`: node-to-segment rows (the report's; they miss the contact
    /// patch test, docs/methods.md §7). On request, or the default of a
    /// pair whose slave is much stiffer than its master.
    Nts,
    /// `"mortar"` (the default): segment-to-segment rows with dual
    /// multipliers (docs/methods.md §7.1).
    #[default]
    Mortar,
}

impl Discretization {
    /// The key's value: `"nts"` or `"mortar"` (the outputs record it).
    pub fn name(self) -> &'static str {
        match self {
            Discretization::Nts => "nts",
            Discretization::Mortar => "mortar",
        }
    }
}

/// The friction law of a pair (docs/methods.md §9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// No friction key, or `friction = 0` (the same results bit for bit).
    Frictionless,
    /// `friction = μ`, μ > 0: the tangential force is bounded by μ λ_n.
    Coulomb(f64),
    /// `tresca = s`, s ≥ 0 (Pa): the tangential traction is bounded by s.
    Tresca(f64),
}

impl Contact {
    /// The curve names of the pair: `[on]` or `[slave, master]`.
    pub fn groups(&self) -> Vec<&str> {
        match &self.pair {
            ContactPair::Conforming { on, .. } => vec![on.as_str()],
            ContactPair::NonMatching(p) => vec![p.slave.as_str(), p.master.as_str()],
        }
    }

    /// The pair as written: `on = "x"` or `slave = "s", master = "m"`.
    pub fn keys(&self) -> String {
        match &self.pair {
            ContactPair::Conforming { on, .. } => format!("on = \"{}\"", shorten(on)),
            ContactPair::NonMatching(p) => format!(
                "slave = \"{}\", master = \"{}\"",
                shorten(&p.slave),
                shorten(&p.master)
            ),
        }
    }

    /// Whether the pair has friction (μ > 0, or a `tresca` bound).
    pub fn has_friction(&self) -> bool {
        self.friction != FrictionLaw::Frictionless
    }
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    #[serde(default, deserialize_with = "map_vector")]
    pub probes: BTreeMap<String, Components>,
    /// Directory for outputs (the `--out` flag overrides it).
    pub dir: Option<PathBuf>,
    /// zlib-compress VTU arrays.
    #[serde(default)]
    pub compress: bool,
    /// Load step (1-based) whose state is the reference: this step and every
    /// later one get `displacement_change`, `stress_change` and
    /// `contact_pressure_change` relative to it (docs/problem-format.md §2, §6).
    pub reference_step: Option<usize>,
}

/// One load step (extension): pseudo-time `t`, a factor on every load
/// (tractions, point forces, gravity) and on every prescribed displacement,
/// or explicit displacement values for named `[[dirichlet]]` groups.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadStep {
    /// Pseudo-time (default: the step number).
    pub t: Option<f64>,
    /// Factor on loads and prescribed displacements (default 1).
    pub factor: Option<f64>,
    /// Factor on loads only (overrides `factor` for loads).
    pub load: Option<f64>,
    /// Factor on prescribed displacements only (overrides `factor` for them).
    pub displacement: Option<f64>,
    /// Explicit prescribed displacement per `[[dirichlet]] on` name: [ux, uy]
    /// ([ux, uy, uz] in 3D; replaces the group's values and its factor in
    /// this step).
    #[serde(default, deserialize_with = "map_vector")]
    pub dirichlet: BTreeMap<String, Components>,
}

/// The whole problem file, checked and typed (`validate`).
#[derive(Debug, Clone)]
pub struct ProblemFile {
    pub mesh: MeshSection,
    pub model: ModelSection,
    pub materials: BTreeMap<String, Material>,
    pub dirichlet: Vec<Dirichlet>,
    pub traction: Vec<Traction>,
    pub slip: Vec<Slip>,
    pub force: Vec<Force>,
    pub contact: Vec<Contact>,
    pub solver: SolverSection,
    pub output: OutputSection,
    /// Load steps (extension); none = one step with the values as given.
    pub steps: Vec<LoadStep>,
}

impl ProblemFile {
    /// The problem of load step `s` (0-based): loads and prescribed
    /// displacements scaled or replaced as the step says.
    pub fn at_step(&self, s: usize) -> ProblemFile {
        let mut f = self.clone();
        let Some(st) = self.steps.get(s) else {
            return f;
        };
        let lf = st.load.or(st.factor).unwrap_or(1.0);
        let df = st.displacement.or(st.factor).unwrap_or(1.0);
        for t in f.traction.iter_mut() {
            t.load = t.load.scaled(lf);
        }
        for fo in f.force.iter_mut() {
            fo.f = fo.f.scaled(lf);
        }
        f.model.gravity = f.model.gravity.map(|g| g.scaled(lf));
        f.model.centrifugal_factor = Some(lf);
        for d in f.dirichlet.iter_mut() {
            d.value = match st.dirichlet.get(&d.on) {
                Some(u) => d.value.replaced(*u),
                None => d.value.scaled(df),
            };
        }
        f
    }

    /// Number of load steps (1 without `[[steps]]`).
    pub fn nsteps(&self) -> usize {
        self.steps.len().max(1)
    }

    /// Pseudo-time of step `s` (0-based).
    pub fn step_time(&self, s: usize) -> f64 {
        self.steps
            .get(s)
            .and_then(|st| st.t)
            .unwrap_or((s + 1) as f64)
    }
}

/// A loaded problem: the parsed file plus where it came from.
#[derive(Debug, Clone)]
pub struct Problem {
    pub path: PathBuf,
    /// Problem name = file stem (`model.toml` → `model`).
    pub name: String,
    /// The TOML text (stored in the checkpoint).
    pub text: String,
    pub file: ProblemFile,
}

impl Problem {
    /// Whether any `[[contact]]` has friction (μ > 0 or a `tresca` bound).
    pub fn has_friction(&self) -> bool {
        self.file.contact.iter().any(Contact::has_friction)
    }

    pub fn load(path: &Path) -> Result<Problem, ModelError> {
        let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(path, &text)
    }

    /// Parse `text` as the problem file `path` (used for messages and for
    /// resolving the mesh path).
    pub fn parse(path: &Path, text: &str) -> Result<Problem, ModelError> {
        let raw: raw::RawFile = toml::from_str(text).map_err(|e| ModelError::Syntax {
            path: path.to_path_buf(),
            msg: toml_error::describe_toml_error(text, &e),
        })?;
        let file = validate::validate(raw).map_err(|msg| ModelError::Invalid {
            path: path.to_path_buf(),
            msg,
        })?;
        for w in validate::warnings(&file) {
            log::warn!("{}: {w}", path.display());
        }
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "model".into());
        Ok(Problem {
            path: path.to_path_buf(),
            name,
            text: text.to_string(),
            file,
        })
    }

    /// Holds the vector keys against the mesh's dimension `dim` (2 or 3),
    /// which is known only once the mesh is read: a 2-vector in 3D or a
    /// 3-vector in 2D is refused naming the key and its line, and so are
    /// `uz` in 2D and the keys of a plane model (`plane`, `thickness`,
    /// `omega`) in 3D (docs/problem-format.md §12).
    pub fn check_dimension(&self, dim: usize) -> Result<(), ModelError> {
        let f = &self.file;
        let bad = |at: Option<usize>, msg: String| ModelError::Invalid {
            path: self.path.clone(),
            msg: match at {
                Some(at) => format!("line {}: {msg}", self.line_of(at)),
                None => msg,
            },
        };
        let mut keys: Vec<(String, Components)> = vec![];
        if let Some(g) = f.model.gravity {
            keys.push(("[model] gravity".into(), g));
        }
        for d in &f.dirichlet {
            let what = format!("[[dirichlet]] on = \"{}\": u", shorten(&d.on));
            match d.value {
                Prescribed::All(u) => keys.push((what, u)),
                Prescribed::Components { uz: Some(_), .. } if dim == 2 => {
                    return Err(bad(
                        None,
                        format!(
                            "[[dirichlet]] on = \"{}\": uz is a key of 3D models, and the mesh {} is 2D (triangles); give ux and/or uy",
                            shorten(&d.on),
                            self.mesh_path().display()
                        ),
                    ))
                }
                Prescribed::Components { .. } => {}
                Prescribed::Turn(t) => {
                    let on = shorten(&d.on);
                    let refuse = match (dim, t.axis) {
                        _ if dim == 2 && f.model.plane == Plane::Axisymmetric => Some(format!(
                            "[[dirichlet]] on = \"{on}\": turn is refused in an axisymmetric model, which has no circumferential displacement (u_θ = 0); model the part in 3D"
                        )),
                        (2, Some(a)) => {
                            return Err(bad(a.at, format!(
                                "[[dirichlet]] on = \"{on}\": turn.axis is a key of 3D models only, and the mesh {} is 2D (triangles): a plane model turns about z; give turn = {{ angle, origin = [x, y] }}",
                                self.mesh_path().display()
                            )))
                        }
                        (3, None) => Some(format!(
                            "[[dirichlet]] on = \"{on}\": turn needs axis = [x, y, z] in a 3D model"
                        )),
                        _ => None,
                    };
                    if let Some(msg) = refuse {
                        return Err(bad(None, msg));
                    }
                    if let Some(a) = t.axis {
                        keys.push((format!("[[dirichlet]] on = \"{on}\": turn.axis"), a));
                    }
                    if let Some(o) = t.origin {
                        keys.push((format!("[[dirichlet]] on = \"{on}\": turn.origin"), o));
                    }
                }
            }
        }
        for t in &f.traction {
            if let TractionLoad::Vector(p) = t.load {
                keys.push((format!("[[traction]] on = \"{}\": p", shorten(&t.on)), p));
            }
        }
        for x in &f.force {
            keys.push((format!("[[force]] on = \"{}\": f", shorten(&x.on)), x.f));
        }
        for (name, x) in &f.output.probes {
            keys.push((format!("[output] probes.{}", shorten(name)), *x));
        }
        for (i, st) in f.steps.iter().enumerate() {
            for (name, u) in &st.dirichlet {
                keys.push((
                    format!("[[steps]] #{}: dirichlet.{}", i + 1, shorten(name)),
                    *u,
                ));
            }
        }
        let (axes, cells) = match dim {
            2 => ("[x, y]", "triangles"),
            _ => ("[x, y, z]", "tetrahedra"),
        };
        if let Some((what, v)) = keys.into_iter().find(|(_, v)| v.len() != dim) {
            return Err(bad(
                v.at,
                format!(
                    "{what} = {}: expected {dim} components {axes} for the {dim}D mesh {} ({cells}), found {}",
                    v.show(),
                    self.mesh_path().display(),
                    v.len()
                ),
            ));
        }
        if dim == 3 {
            if let Some((key, at)) = f.model.written_2d.iter().find(|(_, at)| at.is_some()) {
                return Err(bad(
                    *at,
                    format!(
                        "[model] {key}: a key of plane and axisymmetric models, and the mesh {} is 3D (tetrahedra); remove it",
                        self.mesh_path().display()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The 1-based line of byte offset `at` in the problem file.
    fn line_of(&self, at: usize) -> usize {
        let at = at.min(self.text.len());
        self.text.as_bytes()[..at]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    }

    /// The mesh path, resolved relative to the TOML file.
    pub fn mesh_path(&self) -> PathBuf {
        let f = &self.file.mesh.file;
        if f.is_absolute() {
            f.clone()
        } else {
            self.path.parent().unwrap_or(Path::new(".")).join(f)
        }
    }
}
