//! The problem file (`*.toml`), as specified in `docs/problem-format.md`.
//!
//! Parsing is strict: unknown keys are rejected with the key, the table and
//! the line, so a typo never silently drops a load. Values are checked here
//! (E > 0, −1 < ν < 0.5, ρ ≥ 0, …); names are checked against the mesh in
//! `fem::topology`.

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

fn two<E: serde::de::Error>(v: Vec<f64>) -> Result<[f64; 2], E> {
    match v.as_slice() {
        [a, b] => Ok([*a, *b]),
        _ => Err(E::custom(format!(
            "expected 2 components [x, y], found {}",
            v.len()
        ))),
    }
}

/// `[x, y]` with exactly two components (serde's fixed-size arrays would
/// drop a third one silently).
fn pair<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    two(Vec::<f64>::deserialize(d)?)
}

fn opt_pair<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    Option::<Vec<f64>>::deserialize(d)?.map(two).transpose()
}

fn map_pair<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<String, [f64; 2]>, D::Error> {
    BTreeMap::<String, Vec<f64>>::deserialize(d)?
        .into_iter()
        .map(|(k, v)| two(v).map(|p| (k, p)))
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
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    #[serde(default)]
    pub plane: Plane,
    /// Thickness t_h (plane stress; multiplies every stiffness and load).
    #[serde(default = "one")]
    pub thickness: f64,
    /// Gravity vector: body force F = ρ·gravity (methods.md §1.2).
    #[serde(default, deserialize_with = "opt_pair")]
    pub gravity: Option<[f64; 2]>,
}

fn one() -> f64 {
    1.0
}

impl Default for ModelSection {
    fn default() -> Self {
        ModelSection {
            plane: Plane::Strain,
            thickness: 1.0,
            gravity: None,
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

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dirichlet {
    pub on: String,
    #[serde(default, deserialize_with = "opt_pair")]
    pub u: Option<[f64; 2]>,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Traction {
    pub on: String,
    /// Traction vector P [N/m²].
    #[serde(default, deserialize_with = "opt_pair")]
    pub p: Option<[f64; 2]>,
    /// Normal pressure, positive outward (compression negative).
    pub pn: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slip {
    pub on: String,
}

/// A point force (extension): `f` [N per unit thickness] at a physical point.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Force {
    pub on: String,
    #[serde(deserialize_with = "pair")]
    pub f: [f64; 2],
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

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    /// Conforming interface: one physical curve between two bodies.
    pub on: Option<String>,
    /// Non-matching pair: slave curve projected onto master curve.
    pub slave: Option<String>,
    pub master: Option<String>,
    #[serde(default)]
    pub normals: NormalKind,
    /// Non-matching: largest initial gap at which a slave node is paired
    /// (default: unlimited, i.e. every slave node that projects onto the master).
    pub max_gap: Option<f64>,
    /// Coulomb friction coefficient μ ≥ 0 (default 0: frictionless).
    pub friction: Option<f64>,
    /// Tresca friction: the bound of the tangential traction (Pa), ≥ 0.
    pub tresca: Option<f64>,
    /// Non-matching: "nts" (node-to-segment, the default) or "mortar"
    /// (segment-to-segment with dual multipliers, docs/methods.md §7.1).
    pub discretization: Option<String>,
}

impl Contact {
    /// Whether this non-matching pair uses mortar rows (docs/methods.md §7.1);
    /// the value was checked by `Problem::validate`.
    pub fn mortar(&self) -> bool {
        self.discretization.as_deref() == Some("mortar")
    }
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    #[serde(default, deserialize_with = "map_pair")]
    pub probes: BTreeMap<String, [f64; 2]>,
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
    /// (replaces the group's values and its factor in this step).
    #[serde(default, deserialize_with = "map_pair")]
    pub dirichlet: BTreeMap<String, [f64; 2]>,
}

/// The whole problem file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemFile {
    pub mesh: MeshSection,
    #[serde(default)]
    pub model: ModelSection,
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    #[serde(default)]
    pub dirichlet: Vec<Dirichlet>,
    #[serde(default)]
    pub traction: Vec<Traction>,
    #[serde(default)]
    pub slip: Vec<Slip>,
    #[serde(default)]
    pub force: Vec<Force>,
    #[serde(default)]
    pub contact: Vec<Contact>,
    #[serde(default)]
    pub solver: SolverSection,
    #[serde(default)]
    pub output: OutputSection,
    /// Load steps (extension); none = one step with the values as given.
    #[serde(default)]
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
            t.p = t.p.map(|p| [p[0] * lf, p[1] * lf]);
            t.pn = t.pn.map(|v| v * lf);
        }
        for fo in f.force.iter_mut() {
            fo.f = [fo.f[0] * lf, fo.f[1] * lf];
        }
        f.model.gravity = f.model.gravity.map(|g| [g[0] * lf, g[1] * lf]);
        for d in f.dirichlet.iter_mut() {
            if let Some(u) = st.dirichlet.get(&d.on) {
                if d.u.is_some() {
                    d.u = Some(*u);
                } else {
                    d.ux = d.ux.map(|_| u[0]);
                    d.uy = d.uy.map(|_| u[1]);
                }
            } else {
                d.u = d.u.map(|u| [u[0] * df, u[1] * df]);
                d.ux = d.ux.map(|v| v * df);
                d.uy = d.uy.map(|v| v * df);
            }
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
        self.file
            .contact
            .iter()
            .any(|c| c.friction.is_some_and(|m| m > 0.0) || c.tresca.is_some())
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
        let file: ProblemFile = toml::from_str(text).map_err(|e| ModelError::Syntax {
            path: path.to_path_buf(),
            msg: describe_toml_error(text, &e),
        })?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "model".into());
        let p = Problem {
            path: path.to_path_buf(),
            name,
            text: text.to_string(),
            file,
        };
        p.validate()?;
        Ok(p)
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

    fn invalid(&self, msg: String) -> ModelError {
        ModelError::Invalid {
            path: self.path.clone(),
            msg,
        }
    }

    fn validate(&self) -> Result<(), ModelError> {
        let f = &self.file;
        let finite = |v: f64| v.is_finite();
        // Names are echoed in messages, which must stay one line: no control
        // characters (a TOML escape such as "\n" could put one there).
        let mut names: Vec<(&str, &str)> = vec![];
        names.extend(f.materials.keys().map(|n| ("[materials.NAME]", n.as_str())));
        names.extend(
            f.dirichlet
                .iter()
                .map(|d| ("[[dirichlet]] on", d.on.as_str())),
        );
        names.extend(
            f.traction
                .iter()
                .map(|t| ("[[traction]] on", t.on.as_str())),
        );
        names.extend(f.slip.iter().map(|s| ("[[slip]] on", s.on.as_str())));
        names.extend(f.force.iter().map(|x| ("[[force]] on", x.on.as_str())));
        for c in &f.contact {
            for (what, n) in [
                ("[[contact]] on", &c.on),
                ("[[contact]] slave", &c.slave),
                ("[[contact]] master", &c.master),
            ] {
                if let Some(n) = n {
                    names.push((what, n.as_str()));
                }
            }
        }
        for st in &f.steps {
            names.extend(
                st.dirichlet
                    .keys()
                    .map(|n| ("[[steps]] dirichlet", n.as_str())),
            );
        }
        names.extend(
            f.output
                .probes
                .keys()
                .map(|n| ("[output] probes", n.as_str())),
        );
        let mesh_file = f.mesh.file.to_string_lossy();
        names.push(("[mesh] file", &mesh_file));
        for (what, n) in names {
            if n.chars().any(char::is_control) {
                return Err(self.invalid(format!(
                    "{what}: the name {:?} contains a control character",
                    shorten(n)
                )));
            }
            if n.len() > MAX_NAME {
                return Err(self.invalid(format!(
                    "{what}: the name \"{}\" is longer than {MAX_NAME} bytes",
                    shorten(n)
                )));
            }
        }
        // A contact curve (conforming, or the slave side) that is also fixed
        // or sliding: the contact rows of its points would be dropped without
        // a word. A fixed master is an obstacle and stays allowed.
        for (i, c) in f.contact.iter().enumerate() {
            for n in [&c.on, &c.slave].into_iter().flatten() {
                let fixed = f
                    .dirichlet
                    .iter()
                    .map(|d| ("[[dirichlet]]", &d.on))
                    .chain(f.slip.iter().map(|s| ("[[slip]]", &s.on)))
                    .find(|(_, on)| *on == n);
                if let Some((what, _)) = fixed {
                    return Err(self.invalid(format!(
                        "[[contact]] #{}: curve \"{}\" is also in {what}; a curve is either in contact or supported, not both",
                        i + 1,
                        shorten(n)
                    )));
                }
            }
        }
        let big = |v: f64| {
            let within = v.abs() <= MAX_MAGNITUDE;
            !within
        };
        let too_big = |what: String, v: f64| {
            self.invalid(format!(
                "{what} = {v:e} is beyond ±{MAX_MAGNITUDE:e}: products with it would overflow; change the units"
            ))
        };
        let mut loads: Vec<(String, f64)> = vec![];
        if let Some(g) = f.model.gravity {
            loads.extend(g.iter().map(|v| ("[model] gravity".to_string(), *v)));
        }
        for d in &f.dirichlet {
            let what = format!("[[dirichlet]] on = \"{}\": u", shorten(&d.on));
            loads.extend(
                d.u.iter()
                    .flatten()
                    .chain(&d.ux)
                    .chain(&d.uy)
                    .map(|v| (what.clone(), *v)),
            );
        }
        for t in &f.traction {
            let what = format!("[[traction]] on = \"{}\": p", shorten(&t.on));
            loads.extend(
                t.p.iter()
                    .flatten()
                    .chain(&t.pn)
                    .map(|v| (what.clone(), *v)),
            );
        }
        for x in &f.force {
            let what = format!("[[force]] on = \"{}\": f", shorten(&x.on));
            loads.extend(x.f.iter().map(|v| (what.clone(), *v)));
        }
        for (what, v) in loads {
            if v.is_finite() && big(v) {
                return Err(too_big(what, v));
            }
        }
        for (name, m) in &f.materials {
            if m.e.is_finite() && m.e > 0.0 && (big(m.e) || m.e < 1.0 / MAX_MAGNITUDE) {
                return Err(self.invalid(format!(
                    "[materials.{}] E = {:e} lies outside [{:e}, {MAX_MAGNITUDE:e}]: stiffness products would underflow or overflow; change the units",
                    shorten(name),
                    m.e,
                    1.0 / MAX_MAGNITUDE
                )));
            }
        }
        if !(f.model.thickness > 0.0 && finite(f.model.thickness)) {
            return Err(self.invalid(format!(
                "[model] thickness = {} must be positive",
                f.model.thickness
            )));
        }
        if let Some(g) = f.model.gravity {
            if !g.iter().all(|v| finite(*v)) {
                return Err(self.invalid("[model] gravity must be finite".into()));
            }
        }
        if f.materials.is_empty() {
            return Err(self.invalid(
                "no [materials.NAME] table: every physical surface needs a material".into(),
            ));
        }
        for (name, m) in &f.materials {
            if !(m.e > 0.0 && finite(m.e)) {
                return Err(
                    self.invalid(format!("[materials.{name}] E = {} must be positive", m.e))
                );
            }
            if !(m.nu > -1.0 && m.nu < 0.5) {
                return Err(self.invalid(format!(
                    "[materials.{name}] nu = {} must lie in (-1, 0.5)",
                    m.nu
                )));
            }
            if !(m.rho >= 0.0 && finite(m.rho)) {
                return Err(self.invalid(format!(
                    "[materials.{name}] rho = {} must be non-negative",
                    m.rho
                )));
            }
        }
        for (i, d) in f.dirichlet.iter().enumerate() {
            let n = d.u.is_some() as u8 + (d.ux.is_some() || d.uy.is_some()) as u8;
            if n != 1 {
                return Err(self.invalid(format!(
                    "[[dirichlet]] #{} (on = \"{}\"): give either u = [ux, uy] or ux and/or uy",
                    i + 1,
                    d.on
                )));
            }
            let vals =
                d.u.map(|u| u.to_vec())
                    .unwrap_or_else(|| d.ux.into_iter().chain(d.uy).collect());
            if !vals.iter().all(|v| finite(*v)) {
                return Err(self.invalid(format!(
                    "[[dirichlet]] on = \"{}\": values must be finite",
                    d.on
                )));
            }
        }
        for (i, t) in f.traction.iter().enumerate() {
            if t.p.is_some() == t.pn.is_some() {
                return Err(self.invalid(format!(
                    "[[traction]] #{} (on = \"{}\"): give exactly one of p = [px, py] or pn",
                    i + 1,
                    t.on
                )));
            }
            let ok = t.p.map(|p| p.iter().all(|v| finite(*v))).unwrap_or(true)
                && t.pn.map(finite).unwrap_or(true);
            if !ok {
                return Err(self.invalid(format!(
                    "[[traction]] on = \"{}\": values must be finite",
                    t.on
                )));
            }
        }
        for fo in &f.force {
            if !fo.f.iter().all(|v| finite(*v)) {
                return Err(self.invalid(format!(
                    "[[force]] on = \"{}\": values must be finite",
                    fo.on
                )));
            }
        }
        for (i, c) in f.contact.iter().enumerate() {
            let conf = c.on.is_some();
            let nm = c.slave.is_some() || c.master.is_some();
            if conf == nm || (nm && (c.slave.is_none() || c.master.is_none())) {
                return Err(self.invalid(format!(
                    "[[contact]] #{}: give either on = \"curve\" (conforming) or both slave and master (non-matching)",
                    i + 1
                )));
            }
            if let Some(g) = c.max_gap {
                if g.is_nan() || g < 0.0 {
                    return Err(
                        self.invalid(format!("[[contact]] #{}: max_gap must be >= 0", i + 1))
                    );
                }
            }
            if c.friction.is_some() && c.tresca.is_some() {
                return Err(self.invalid(format!(
                    "[[contact]] #{}: give either friction = μ (Coulomb) or tresca = s (Tresca), not both",
                    i + 1
                )));
            }
            for (key, v) in [("friction", c.friction), ("tresca", c.tresca)] {
                if let Some(v) = v {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(self.invalid(format!(
                            "[[contact]] #{}: {key} = {v} must be a finite number >= 0",
                            i + 1
                        )));
                    }
                }
            }
            if let Some(d) = &c.discretization {
                let pair = match (&c.on, &c.slave, &c.master) {
                    (Some(on), _, _) => format!("on = \"{}\"", shorten(on)),
                    (_, Some(s), Some(m)) => {
                        format!("slave = \"{}\", master = \"{}\"", shorten(s), shorten(m))
                    }
                    _ => String::new(),
                };
                if conf {
                    return Err(self.invalid(format!(
                        "[[contact]] #{} ({pair}): discretization applies to non-matching pairs (slave, master) only; a conforming pair has node-to-node rows",
                        i + 1
                    )));
                }
                if d != "nts" && d != "mortar" {
                    return Err(self.invalid(format!(
                        "[[contact]] #{} ({pair}): discretization = {:?} is unknown; use \"nts\" or \"mortar\"",
                        i + 1,
                        shorten(d)
                    )));
                }
            }
        }
        let s = &f.solver;
        if let Some(t) = s.tol {
            if !(t > 0.0 && t < 1.0) {
                return Err(self.invalid(format!("[solver] tol = {t} must lie in (0, 1)")));
            }
        }
        if s.max_iter == Some(0) {
            return Err(self.invalid("[solver] max_iter must be positive".into()));
        }
        let mut last_t = f64::NEG_INFINITY;
        for (i, st) in f.steps.iter().enumerate() {
            for v in [st.t, st.factor, st.load, st.displacement]
                .into_iter()
                .flatten()
            {
                if !v.is_finite() {
                    return Err(
                        self.invalid(format!("[[steps]] #{}: values must be finite", i + 1))
                    );
                }
            }
            let t = st.t.unwrap_or((i + 1) as f64);
            if t <= last_t {
                return Err(self.invalid(format!(
                    "[[steps]] #{}: t = {t} must increase from step to step",
                    i + 1
                )));
            }
            last_t = t;
            for (name, u) in &st.dirichlet {
                if !f.dirichlet.iter().any(|d| &d.on == name) {
                    return Err(self.invalid(format!(
                        "[[steps]] #{}: dirichlet.{name}: no [[dirichlet]] with on = \"{name}\"",
                        i + 1
                    )));
                }
                if !u.iter().all(|v| v.is_finite()) {
                    return Err(self.invalid(format!(
                        "[[steps]] #{}: dirichlet.{name}: values must be finite",
                        i + 1
                    )));
                }
            }
        }
        if let Some(k) = f.output.reference_step {
            let n = f.nsteps();
            if k == 0 || k > n {
                return Err(self.invalid(format!(
                    "[output] reference_step = {k}: load steps count from 1, and the problem has {n} step{}",
                    if n == 1 { "" } else { "s" }
                )));
            }
        }
        for (name, p) in &f.output.probes {
            if !p.iter().all(|v| finite(*v)) {
                return Err(
                    self.invalid(format!("[output] probe {name}: coordinates must be finite"))
                );
            }
        }
        Ok(())
    }
}

/// One line: what is wrong, where (line:column), and the key when known.
fn describe_toml_error(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', "; ");
    match e.span() {
        Some(span) => {
            let mut start = span.start.min(text.len());
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let line = text[..start].matches('\n').count() + 1;
            let line_start = text[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
            let col = start - line_start + 1;
            let line_text = text[line_start..].lines().next().unwrap_or("");
            let snippet: String = text[start..]
                .lines()
                .next()
                .unwrap_or("")
                .chars()
                .take(40)
                .collect();
            // The table the error is in; none when the error is in a table
            // header itself (the header is the snippet).
            let table = if line_text.trim_start().starts_with('[') {
                String::new()
            } else {
                enclosing_table(text, line_start)
            };
            // The key of a `key = value` line, when the error is in its value.
            let key = line_text
                .split_once('=')
                .map(|(k, _)| k.trim())
                .filter(|k| {
                    !k.is_empty()
                        && !k.starts_with('[')
                        && line_start + line_text.find('=').unwrap_or(0) < start
                })
                .map(|k| format!(", key `{k}`"))
                .unwrap_or_default();
            let at = match snippet.trim() {
                "" => String::new(),
                sn => format!(" (at `{sn}`)"),
            };
            format!("line {line}, column {col}{table}{key}: {msg}{at}")
        }
        None => msg,
    }
}

/// " in [table]" for the table header that precedes byte offset `pos`.
fn enclosing_table(text: &str, pos: usize) -> String {
    text[..pos]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| format!(" in {}", l.split('#').next().unwrap_or(l).trim()))
        .unwrap_or_default()
}
