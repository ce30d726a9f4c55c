//! Figures of an HDF5 checkpoint (`signorini plot`), drawn with `plotters`:
//!
//! * the deformed mesh, every triangle coloured by a field (viridis colour
//!   map and colour bar; a legend for the categorical fields `material` and
//!   `body`), x and y at the same scale;
//! * or the contact pressure along each interface against arc length, of
//!   one step or of every step (one curve each: a load-step sequence);
//! * with `change`, the fields relative to the reference step
//!   (`[output] reference_step`) instead of the absolute ones.
//!
//! PNG is rasterised in memory (nodal fields interpolated linearly inside
//! each triangle, per pixel) and encoded with `png`; SVG draws one polygon
//! per triangle (nodal fields on a few sub-triangles per triangle). The text
//! uses DejaVu Sans embedded in the binary (crate `dejavu`), so no system
//! font is needed. The finished file is written atomically.
//!
//! A 3D checkpoint is drawn flat (`solid`): the section of the tetrahedra
//! by a plane (`--cut`), or the contact footprint of each interface in its
//! own plane (`--contact`).
//!
//! The code: options, checks and the steps drawn here; the mesh figure in
//! `mesh`, its colour scale, colour bar and legend in `colorbar`, the
//! contact figure in `contact`, and fonts, colours and number formats in
//! `style`.

mod colorbar;
mod contact;
mod cut;
mod footprint;
mod mesh;
mod panel;
mod solid;
mod style;

pub use contact::{arc_lengths, interface_chains, Tangential};
pub use cut::{Frame, Plane};
pub use footprint::FootprintSummary;
pub use mesh::auto_scale;
pub use solid::{
    default_plane, render_solid, CutSummary, SolidField, SolidPlotOptions, SolidPlotSummary,
};
pub use style::{fmt_num, viridis};

use crate::fem::ElementKind;
use crate::output::{Checkpoint, OutMesh, StepOutput};
pub use crate::problem::Units;
use contact::draw_contact;
use mesh::draw_mesh;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use style::{de, encode_png, font_size, register_fonts};

/// A failure of `plot`: one line, naming the file or the bad option.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotError(pub String);

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PlotError {}

pub(super) fn err(msg: impl Into<String>) -> PlotError {
    // Keep the message on one line whatever the source said.
    PlotError(msg.into().replace('\n', " "))
}

/// What colours the triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    VonMises,
    Ux,
    Uy,
    Umag,
    Sxx,
    Syy,
    Sxy,
    Szz,
    S1,
    S2,
    Material,
    Body,
    /// Axisymmetric σrr (stress component 0, as `sxx`).
    Srr,
    /// Axisymmetric σzz, the axial stress (component 1, as `syy`); only
    /// the resolved form of `szz` on an axisymmetric checkpoint
    /// ([`Field::for_model`]), never parsed.
    SzzAxial,
    /// Axisymmetric σrz (component 2, as `sxy`).
    Srz,
    /// Axisymmetric hoop stress σθθ (component 3, where a plane model has
    /// σzz; docs/problem-format.md §11).
    Stt,
}

/// How a field lives on the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// One value per triangle.
    Cell,
    /// One value per point (interpolated linearly inside a triangle).
    Nodal,
    /// One category per triangle (legend instead of colour bar).
    Categorical,
}

impl Field {
    /// The names `--field` accepts (`szz` is the plane name here; on an
    /// axisymmetric checkpoint it resolves to the axial stress).
    pub const ALL: [Field; 15] = [
        Field::VonMises,
        Field::Ux,
        Field::Uy,
        Field::Umag,
        Field::Sxx,
        Field::Syy,
        Field::Sxy,
        Field::Szz,
        Field::S1,
        Field::S2,
        Field::Material,
        Field::Body,
        Field::Srr,
        Field::Srz,
        Field::Stt,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Field::VonMises => "von_mises",
            Field::Ux => "ux",
            Field::Uy => "uy",
            Field::Umag => "umag",
            Field::Sxx => "sxx",
            Field::Syy => "syy",
            Field::Sxy => "sxy",
            Field::Szz => "szz",
            Field::S1 => "s1",
            Field::S2 => "s2",
            Field::Material => "material",
            Field::Body => "body",
            Field::Srr => "srr",
            Field::SzzAxial => "szz",
            Field::Srz => "srz",
            Field::Stt => "stt",
        }
    }

    /// The field as the checkpoint's model names it. An axisymmetric
    /// model's stress is (σrr, σzz, σrz, σθθ) (docs/problem-format.md §11),
    /// so there `sxx`/`srr` draw σrr, `syy`/`szz` the axial σzz, `sxy`/`srz`
    /// σrz and `stt` the hoop stress, each labelled by its axisymmetric name
    /// (`szz` drawing the fourth component would label σθθ as σzz). The
    /// axisymmetric names on a plane checkpoint are refused, naming the
    /// plane one.
    pub fn for_model(self, kind: ElementKind) -> Result<Field, PlotError> {
        match kind.stress_component(self.name()) {
            None => Ok(self),
            Some(Ok(i)) => Ok(Field::stress(i, kind.stress_names()[i])),
            Some(Err(plane)) => Err(err(format!(
                "field \"{}\" is a stress of an axisymmetric model; this checkpoint is plane: use \"{plane}\"",
                self.name()
            ))),
        }
    }

    /// The stress field of component `i` named `name` (the name the
    /// checkpoint's kind gives it).
    fn stress(i: usize, name: &str) -> Field {
        match (i, name) {
            (0, "srr") => Field::Srr,
            (1, "szz") => Field::SzzAxial,
            (2, "srz") => Field::Srz,
            (3, "stt") => Field::Stt,
            (0, _) => Field::Sxx,
            (1, _) => Field::Syy,
            (2, _) => Field::Sxy,
            _ => Field::Szz,
        }
    }

    /// The field named `s`, or an error listing the known names.
    pub fn parse(s: &str) -> Result<Field, PlotError> {
        Field::ALL
            .iter()
            .copied()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Field::ALL.iter().map(|f| f.name()).collect();
                err(format!(
                    "unknown field \"{s}\"; known: {}",
                    names.join(", ")
                ))
            })
    }

    /// The field's unit in `units` (None for the categorical fields).
    pub fn unit(self, units: &Units) -> Option<&str> {
        match self.kind() {
            Kind::Nodal => Some(&units.length),
            Kind::Cell => Some(&units.stress),
            Kind::Categorical => None,
        }
    }

    pub(super) fn kind(self) -> Kind {
        match self {
            Field::Ux | Field::Uy | Field::Umag => Kind::Nodal,
            Field::Material | Field::Body => Kind::Categorical,
            _ => Kind::Cell,
        }
    }

    /// "von_mises \[Pa\]", "body".
    pub fn label(self, units: &Units) -> String {
        match self.unit(units) {
            Some(u) => format!("{} [{u}]", self.name()),
            None => self.name().to_string(),
        }
    }
}

/// Output format, from the file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
}

impl Format {
    pub fn from_path(path: &Path) -> Result<Format, PlotError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("svg") => Ok(Format::Svg),
            _ => Err(err(format!(
                "{}: unsupported output format (the file name must end in .png or .svg)",
                path.display()
            ))),
        }
    }
}

/// What to draw.
#[derive(Debug, Clone)]
pub struct PlotOptions {
    /// 1-based step index; None = last step.
    pub step: Option<usize>,
    pub field: Field,
    /// Displacement magnification; None = automatic (largest displacement
    /// drawn as 5 % of the bounding-box diagonal).
    pub scale: Option<f64>,
    /// Contact pressure along the interfaces instead of the mesh.
    pub contact: bool,
    pub width: u32,
    pub height: u32,
    /// Triangle edges: Some(on/off), None = when triangles are large enough.
    pub edges: Option<bool>,
    /// Colour range (min, max) of the field, or the pressure axis of the
    /// contact plot; values outside get the end colours. None = the data's range.
    pub range: Option<(f64, f64)>,
    /// Logarithmic colour scale (positive values; others get the bottom colour).
    pub log: bool,
    /// Draw the change since the reference step (displacement_change,
    /// stress_change, contact_pressure_change) instead of the fields.
    pub change: bool,
    /// With `contact`: one curve per step, every step of the checkpoint
    /// (with `change`: from the reference step on, the steps before it
    /// having no change fields).
    pub all_steps: bool,
    /// The units of the labels: [`render`] takes them from the
    /// checkpoint's problem (`[model] units`, default m and Pa).
    pub units: Units,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions {
            step: None,
            field: Field::VonMises,
            scale: None,
            contact: false,
            width: 1200,
            height: 900,
            edges: None,
            range: None,
            log: false,
            change: false,
            all_steps: false,
            units: Units::default(),
        }
    }
}

/// Smallest and largest accepted image side \[px\].
pub const MIN_SIDE: u32 = 200;
pub const MAX_SIDE: u32 = 10000;

/// What was drawn.
#[derive(Debug, Clone)]
pub struct PlotSummary {
    /// The 1-based step drawn and the number of steps in the file.
    pub step: usize,
    /// The first step drawn (with `all_steps`: 1, or with `change` the
    /// reference step, the steps before it having no change to draw).
    pub first_step: usize,
    pub steps: usize,
    /// Displacement scale used (None for the contact plot).
    pub scale: Option<f64>,
    /// Largest displacement magnitude of the step \[m\].
    pub max_displacement: f64,
    /// Range of the plotted values (field, or contact pressure); None for a
    /// categorical field.
    pub range: Option<(f64, f64)>,
    /// The contact plot of a checkpoint with friction data: the range of
    /// the tangential traction drawn (or of its change).
    pub tangential_range: Option<(f64, f64)>,
    /// The contact plot with friction: rows that stick and that slip at
    /// the last step drawn.
    pub stick_slip: Option<(usize, usize)>,
    /// The field drawn, named as the checkpoint's model names it
    /// ([`Field::for_model`]).
    pub field: Field,
    /// The units of the labels (`[model] units` of the checkpoint's problem).
    pub units: Units,
}

/// Refuses options out of range or that exclude each other.
pub fn check_options(opts: &PlotOptions) -> Result<(), PlotError> {
    for (what, v) in [("width", opts.width), ("height", opts.height)] {
        if !(MIN_SIDE..=MAX_SIDE).contains(&v) {
            return Err(err(format!(
                "--{what} {v} out of range ({MIN_SIDE} to {MAX_SIDE} pixels)"
            )));
        }
    }
    if let Some(s) = opts.scale {
        if !s.is_finite() {
            return Err(err(format!("--scale {s}: must be a finite number")));
        }
    }
    if let Some((lo, hi)) = opts.range {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(err(format!(
                "--range {lo},{hi}: expected two finite numbers MIN,MAX with MIN < MAX"
            )));
        }
        // The span, with the factor 16 the axis tick search needs, must be
        // a double: an infinite axis never ended that search (issue 34).
        if !((hi - lo) * 16.0).is_finite() {
            return Err(err(format!(
                "--range {},{}: the span MAX − MIN is too large to draw (more than a double holds with the figure's margins)",
                fmt_num(lo),
                fmt_num(hi)
            )));
        }
        if opts.log && lo <= 0.0 {
            return Err(err(format!(
                "--range {lo},{hi} with --log: MIN must be positive"
            )));
        }
    }
    if opts.log && opts.contact {
        return Err(err(
            "--log applies to the mesh fields, not to the contact plot (--contact)",
        ));
    }
    if opts.all_steps && !opts.contact {
        return Err(err(
            "--all-steps draws the contact pressure of every step: add --contact",
        ));
    }
    if opts.all_steps && opts.step.is_some() {
        return Err(err("--all-steps and --step exclude each other"));
    }
    Ok(())
}

/// Draws the figure of `ck` in memory: the encoded file and what was drawn.
/// `name` is the model name used in the title.
pub fn render(
    ck: &Checkpoint,
    name: &str,
    opts: &PlotOptions,
    format: Format,
) -> Result<(Vec<u8>, PlotSummary), PlotError> {
    check_options(opts)?;
    let nsteps = ck.steps.len();
    if nsteps == 0 {
        return Err(err("the checkpoint holds no step"));
    }
    let step_no = opts.step.unwrap_or(nsteps);
    if step_no == 0 || step_no > nsteps {
        return Err(err(format!(
            "step {step_no} out of range: the checkpoint has {nsteps} step{} (1 to {nsteps})",
            if nsteps == 1 { "" } else { "s" }
        )));
    }
    let mesh = &ck.mesh;
    let problem_toml = ck.attrs.iter().find(|(k, _)| k == "problem_toml");
    let resolved = PlotOptions {
        field: opts.field.for_model(mesh.kind)?,
        units: problem_toml.map_or_else(Units::default, |(_, t)| Units::of_problem_text(t)),
        ..opts.clone()
    };
    let opts = &resolved;
    // The steps drawn (all of them for the contact plot of a sequence), as
    // changes since the reference step with `change`.
    let picked: Vec<usize> = if opts.all_steps {
        (first_drawn(ck, opts)..=nsteps).collect()
    } else {
        vec![step_no]
    };
    let mut drawn = Vec::with_capacity(picked.len());
    for &k in &picked {
        let st = &ck.steps[k - 1];
        check_consistent(mesh, st)?;
        drawn.push((
            k,
            if opts.change {
                change_of(st, k)?
            } else {
                st.clone()
            },
        ));
    }
    let step = &drawn[drawn.len() - 1].1;
    let max_u = step
        .displacement
        .iter()
        .map(|u| u[0].hypot(u[1]))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    register_fonts();
    let (w, h) = (opts.width, opts.height);
    let mut summary = PlotSummary {
        step: step_no,
        first_step: drawn[0].0,
        steps: nsteps,
        scale: None,
        max_displacement: max_u,
        range: None,
        tangential_range: None,
        stick_slip: None,
        field: opts.field,
        units: opts.units.clone(),
    };
    // The friction data of the drawn steps (contact plot; all or nothing).
    let tangential = if opts.contact {
        tangential_of(ck, &drawn, opts.change)?
    } else {
        None
    };
    if let Some(t) = &tangential {
        let last = &t[t.len() - 1].state;
        let n = |v: u8| last.iter().filter(|&&s| s == v).count();
        summary.stick_slip = Some((n(1), n(2)));
    }
    let bytes = match format {
        Format::Png => {
            let mut buf = vec![255u8; (w as usize) * (h as usize) * 3];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw(
                    &root,
                    true,
                    mesh,
                    &drawn,
                    tangential.as_deref(),
                    name,
                    opts,
                    &mut summary,
                )?;
                root.present().map_err(de)?;
            }
            encode_png(&buf, w, h)?
        }
        Format::Svg => {
            let mut s = String::new();
            {
                let root = SVGBackend::with_string(&mut s, (w, h)).into_drawing_area();
                draw(
                    &root,
                    false,
                    mesh,
                    &drawn,
                    tangential.as_deref(),
                    name,
                    opts,
                    &mut summary,
                )?;
                root.present().map_err(de)?;
            }
            s.into_bytes()
        }
    };
    Ok((bytes, summary))
}

#[allow(clippy::too_many_arguments)]
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    raster: bool,
    mesh: &OutMesh,
    drawn: &[(usize, StepOutput)],
    tangential: Option<&[Tangential]>,
    name: &str,
    opts: &PlotOptions,
    summary: &mut PlotSummary,
) -> Result<(), PlotError> {
    root.fill(&WHITE).map_err(de)?;
    let fs = font_size(opts.width, opts.height);
    let (step_no, step) = (drawn[drawn.len() - 1].0, &drawn[drawn.len() - 1].1);
    let first = drawn[0].0;
    let since = match step.change.as_ref() {
        Some(c) if opts.change => format!(", change since step {}", c.reference_step),
        _ => String::new(),
    };
    if opts.contact {
        let what = if tangential.is_some() {
            "contact pressure and tangential traction"
        } else {
            "contact pressure"
        };
        let steps = if opts.all_steps {
            format!("steps {first}–{step_no}{since}")
        } else {
            format!("step {step_no}{since}")
        };
        let title = format!("{name} — {steps} — {what}");
        let field = if opts.change {
            "contact_pressure_change"
        } else {
            "contact_pressure"
        };
        let (range, t_range) = draw_contact(
            root,
            &mesh.contact,
            drawn,
            tangential,
            &title,
            fs,
            opts.range,
            field,
            &opts.units,
        )?;
        summary.range = range;
        summary.tangential_range = t_range;
    } else {
        let title = format!("{name} — step {step_no}{since} — {}", opts.field.name());
        let scale = match opts.scale {
            Some(s) => s,
            None => auto_scale(&mesh.points, summary.max_displacement),
        };
        summary.scale = Some(scale);
        summary.range = draw_mesh(root, raster, mesh, step, opts, scale, &title, fs)?;
    }
    Ok(())
}

/// The tangential traction and state of every drawn step, when each has
/// the checkpoint's friction arrays (None: a frictionless checkpoint, or a
/// step without them). With `change` the traction is the change since the
/// reference step, whose own traction must then be in the checkpoint.
fn tangential_of(
    ck: &Checkpoint,
    drawn: &[(usize, StepOutput)],
    change: bool,
) -> Result<Option<Vec<Tangential>>, PlotError> {
    let rows = ck.mesh.contact.points.len();
    let of = |k: usize| -> Result<Option<&crate::output::StepFriction>, PlotError> {
        match ck.friction.get(k.wrapping_sub(1)).and_then(|f| f.as_ref()) {
            None => Ok(None),
            Some(f) if f.tangential_traction.len() == rows && f.state.len() == rows => Ok(Some(f)),
            Some(_) => Err(err(format!(
                "step {k}: the friction arrays do not match the contact rows"
            ))),
        }
    };
    let mut out = Vec::with_capacity(drawn.len());
    for (k, st) in drawn {
        let Some(f) = of(*k)? else {
            return Ok(None);
        };
        let mut traction = f.tangential_traction.clone();
        if change {
            let Some(r) = st.change.as_ref().map(|c| c.reference_step) else {
                return Ok(None);
            };
            let Some(fr) = of(r)? else {
                return Ok(None);
            };
            for (t, t0) in traction.iter_mut().zip(&fr.tangential_traction) {
                *t -= t0;
            }
        }
        out.push(Tangential {
            traction,
            state: f.state.clone(),
        });
    }
    Ok(Some(out))
}

/// The first step of an `all_steps` figure: 1, or with `change` the first
/// step that has change fields (the reference step; the steps before it
/// have no change to draw). A checkpoint without change fields starts at
/// its last step, whose [`change_of`] then says why nothing can be drawn.
fn first_drawn(ck: &Checkpoint, opts: &PlotOptions) -> usize {
    if !opts.change {
        return 1;
    }
    ck.steps
        .iter()
        .position(|s| s.change.is_some())
        .map_or(ck.steps.len(), |i| i + 1)
}

/// Step `k` as its change since the reference step: displacement, stress
/// (von Mises and principal stresses of the stress change) and contact
/// pressure replaced by the differences.
fn change_of(step: &StepOutput, k: usize) -> Result<StepOutput, PlotError> {
    let Some(c) = &step.change else {
        return Err(err(format!(
            "--change: step {k} has no change fields (solve with [output] reference_step = N; steps before N have none)"
        )));
    };
    if c.displacement.len() != step.displacement.len()
        || c.stress.len() != step.stress.len()
        || c.contact_pressure.len() != step.contact_pressure.len()
    {
        return Err(err(format!(
            "step {k}: the change fields do not match the mesh"
        )));
    }
    Ok(StepOutput {
        displacement: c.displacement.clone(),
        von_mises: c
            .stress
            .iter()
            .map(crate::fem::element::von_mises)
            .collect(),
        principal: c
            .stress
            .iter()
            .map(crate::fem::element::principal)
            .collect(),
        stress: c.stress.clone(),
        contact_pressure: c.contact_pressure.clone(),
        ..step.clone()
    })
}

fn check_consistent(mesh: &OutMesh, step: &StepOutput) -> Result<(), PlotError> {
    let n = mesh.points.len();
    let m = mesh.triangles.len();
    let r = mesh.contact.points.len();
    let bad = step.displacement.len() != n
        || step.von_mises.len() != m
        || step.stress.len() != m
        || step.principal.len() != m
        || mesh.material.len() != m
        || mesh.point_body.len() != n
        || step.contact_pressure.len() != r
        || mesh.contact.interface.len() != r
        || mesh.triangles.iter().flatten().any(|&i| i >= n)
        || mesh.contact.segments.iter().flatten().any(|&i| i >= r);
    if bad {
        return Err(err("inconsistent array lengths in the checkpoint"));
    }
    if m == 0 {
        return Err(err("the mesh has no triangle"));
    }
    Ok(())
}
