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

use crate::io::atomic::write_atomic_bytes;
use crate::io::hdf5::{read_checkpoint, Checkpoint};
use crate::io::{ContactGeometry, OutMesh, StepOutput};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// A failure of `plot`: one line, naming the file or the bad option.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotError(pub String);

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PlotError {}

fn err(msg: impl Into<String>) -> PlotError {
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
}

/// How a field lives on the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// One value per triangle.
    Cell,
    /// One value per point (interpolated linearly inside a triangle).
    Nodal,
    /// One category per triangle (legend instead of colour bar).
    Categorical,
}

impl Field {
    pub const ALL: [Field; 12] = [
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

    /// SI unit of the field (None for the categorical fields).
    pub fn unit(self) -> Option<&'static str> {
        match self.kind() {
            Kind::Nodal => Some("m"),
            Kind::Cell => Some("Pa"),
            Kind::Categorical => None,
        }
    }

    fn kind(self) -> Kind {
        match self {
            Field::Ux | Field::Uy | Field::Umag => Kind::Nodal,
            Field::Material | Field::Body => Kind::Categorical,
            _ => Kind::Cell,
        }
    }

    /// "von_mises \[Pa\]", "body".
    pub fn label(self) -> String {
        match self.unit() {
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
    /// With `contact`: one curve per step, every step of the checkpoint.
    pub all_steps: bool,
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
    pub steps: usize,
    /// Displacement scale used (None for the contact plot).
    pub scale: Option<f64>,
    /// Largest displacement magnitude of the step \[m\].
    pub max_displacement: f64,
    /// Range of the plotted values (field, or contact pressure); None for a
    /// categorical field.
    pub range: Option<(f64, f64)>,
}

/// Reads `h5`, draws the figure and writes it to `out` (format from its
/// extension) atomically.
pub fn plot_file(h5: &Path, out: &Path, opts: &PlotOptions) -> Result<PlotSummary, PlotError> {
    let format = Format::from_path(out)?;
    check_options(opts)?;
    let ck = read_checkpoint(h5).map_err(|e| err(e.to_string()))?;
    let name = h5
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "checkpoint".to_string());
    let (bytes, summary) =
        render(&ck, &name, opts, format).map_err(|e| err(format!("{}: {}", h5.display(), e.0)))?;
    write_atomic_bytes(out, &bytes).map_err(|e| err(e.to_string()))?;
    Ok(summary)
}

fn check_options(opts: &PlotOptions) -> Result<(), PlotError> {
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
    // The steps drawn (all of them for the contact plot of a sequence), as
    // changes since the reference step with `change`.
    let picked: Vec<usize> = if opts.all_steps {
        (1..=nsteps).collect()
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
        steps: nsteps,
        scale: None,
        max_displacement: max_u,
        range: None,
    };
    let bytes = match format {
        Format::Png => {
            let mut buf = vec![255u8; (w as usize) * (h as usize) * 3];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw(&root, true, mesh, &drawn, name, opts, &mut summary)?;
                root.present().map_err(de)?;
            }
            encode_png(&buf, w, h)?
        }
        Format::Svg => {
            let mut s = String::new();
            {
                let root = SVGBackend::with_string(&mut s, (w, h)).into_drawing_area();
                draw(&root, false, mesh, &drawn, name, opts, &mut summary)?;
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
    name: &str,
    opts: &PlotOptions,
    summary: &mut PlotSummary,
) -> Result<(), PlotError> {
    root.fill(&WHITE).map_err(de)?;
    let fs = font_size(opts.width, opts.height);
    let (step_no, step) = (drawn[drawn.len() - 1].0, &drawn[drawn.len() - 1].1);
    let since = match step.change.as_ref() {
        Some(c) if opts.change => format!(", change since step {}", c.reference_step),
        _ => String::new(),
    };
    if opts.contact {
        let (steps, what) = if opts.all_steps {
            (format!("steps 1–{step_no}{since}"), "contact pressure")
        } else {
            (format!("step {step_no}{since}"), "contact pressure")
        };
        let title = format!("{name} — {steps} — {what}");
        summary.range = draw_contact(root, &mesh.contact, drawn, &title, fs, opts.range)?;
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

/// The scale that draws the largest displacement as 5 % of the diagonal of
/// the bounding box of `points` (1 when nothing moves).
pub fn auto_scale(points: &[[f64; 2]], max_u: f64) -> f64 {
    let (lo, hi) = bbox(points.iter().copied());
    let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    if max_u > 0.0 && diag > 0.0 && diag.is_finite() {
        0.05 * diag / max_u
    } else {
        1.0
    }
}

fn bbox(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo, hi)
}

// ---------------------------------------------------------------- fonts, colours

fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let bytes = dejavu::sans::regular();
        for family in ["sans-serif", "serif", "monospace"] {
            let _ = plotters::style::register_font(family, FontStyle::Normal, bytes);
        }
    });
}

fn font_size(w: u32, h: u32) -> f64 {
    (w.min(h) as f64 / 45.0).clamp(11.0, 30.0)
}

fn de<E: std::fmt::Display>(e: E) -> PlotError {
    err(format!("drawing failed: {e}"))
}

/// Viridis (matplotlib) at t = 0, 0.1, …, 1.
const VIRIDIS: [(u8, u8, u8); 11] = [
    (0x44, 0x01, 0x54),
    (0x48, 0x24, 0x75),
    (0x41, 0x44, 0x87),
    (0x35, 0x5f, 0x8d),
    (0x2a, 0x78, 0x8e),
    (0x21, 0x91, 0x8c),
    (0x22, 0xa8, 0x84),
    (0x44, 0xbf, 0x70),
    (0x7a, 0xd1, 0x51),
    (0xbd, 0xdf, 0x26),
    (0xfd, 0xe7, 0x25),
];

/// Colour of t ∈ [0, 1] (clamped) on the viridis map; NaN is grey.
pub fn viridis(t: f64) -> RGBColor {
    if !t.is_finite() {
        return RGBColor(160, 160, 160);
    }
    let x = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Qualitative palette (matplotlib tab10) for categories and line series.
const TAB10: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

fn category_color(i: usize) -> RGBColor {
    let (r, g, b) = TAB10[i % TAB10.len()];
    RGBColor(r, g, b)
}

/// Short number: 4 significant digits, exponent outside [1e-3, 1e5),
/// trailing zeros removed.
pub fn fmt_num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_nan() {
            "NaN".into()
        } else if v == 0.0 {
            "0".into()
        } else {
            format!("{v}")
        };
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let d = (3 - a.log10().floor() as i32).max(0) as usize;
        trim_zeros(&format!("{v:.d$}"))
    } else {
        let s = format!("{v:.3e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim_zeros(m)),
            None => s,
        }
    }
}

/// An axis tick: [`fmt_num`], with a value within rounding of zero against
/// the axis span written as 0 (ticks are sums of steps: a centred axis put
/// "-2.22e-16" where 0 belonged).
fn tick(v: f64, span: f64) -> String {
    if v.abs() <= 1e-9 * span.abs() {
        "0".into()
    } else {
        fmt_num(v)
    }
}

fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        let t = s.trim_end_matches('0').trim_end_matches('.');
        if t == "-0" {
            "0".into()
        } else {
            t.to_string()
        }
    } else {
        s.to_string()
    }
}

fn encode_png(buf: &[u8], w: u32, h: u32) -> Result<Vec<u8>, PlotError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc
            .write_header()
            .map_err(|e| err(format!("PNG encoding failed: {e}")))?;
        wr.write_image_data(buf)
            .map_err(|e| err(format!("PNG encoding failed: {e}")))?;
        wr.finish()
            .map_err(|e| err(format!("PNG encoding failed: {e}")))?;
    }
    Ok(out)
}

// ---------------------------------------------------------------- mesh figure

/// The values of a field: per triangle, per point, or categories.
enum Values {
    Cell(Vec<f64>),
    Nodal(Vec<f64>),
    Categories(Vec<usize>, Vec<String>),
}

fn field_values(mesh: &OutMesh, step: &StepOutput, field: Field) -> Values {
    let cell = |f: &dyn Fn(usize) -> f64| Values::Cell((0..mesh.triangles.len()).map(f).collect());
    let nodal = |f: &dyn Fn([f64; 2]) -> f64| {
        Values::Nodal(step.displacement.iter().map(|&u| f(u)).collect())
    };
    match field {
        Field::VonMises => cell(&|i| step.von_mises[i]),
        Field::Sxx => cell(&|i| step.stress[i][0]),
        Field::Syy => cell(&|i| step.stress[i][1]),
        Field::Sxy => cell(&|i| step.stress[i][2]),
        Field::Szz => cell(&|i| step.stress[i][3]),
        Field::S1 => cell(&|i| step.principal[i][0]),
        Field::S2 => cell(&|i| step.principal[i][1]),
        Field::Ux => nodal(&|u| u[0]),
        Field::Uy => nodal(&|u| u[1]),
        Field::Umag => nodal(&|u| u[0].hypot(u[1])),
        Field::Material => {
            let cats: Vec<usize> = mesh.material.iter().map(|&m| m as usize).collect();
            let n = cats.iter().max().map_or(0, |&m| m + 1);
            let names = (0..n)
                .map(|i| {
                    mesh.material_names
                        .get(i)
                        .cloned()
                        .unwrap_or_else(|| format!("material {i}"))
                })
                .collect();
            Values::Categories(cats, names)
        }
        Field::Body => {
            let cats: Vec<usize> = mesh
                .triangles
                .iter()
                .map(|t| mesh.point_body[t[0]] as usize)
                .collect();
            let n = cats.iter().max().map_or(0, |&m| m + 1);
            // A body is named by the materials (physical surfaces) it holds.
            let mut mats: Vec<Vec<u32>> = vec![vec![]; n];
            for (&b, &m) in cats.iter().zip(&mesh.material) {
                if !mats[b].contains(&m) {
                    mats[b].push(m);
                }
            }
            let names = mats
                .iter()
                .enumerate()
                .map(|(i, ms)| {
                    let n: Vec<&str> = ms
                        .iter()
                        .filter_map(|&m| mesh.material_names.get(m as usize).map(|s| s.as_str()))
                        .collect();
                    if n.is_empty() {
                        format!("body {i}")
                    } else {
                        format!("{i}: {}", n.join("+"))
                    }
                })
                .collect();
            Values::Categories(cats, names)
        }
    }
}

fn finite_range(v: &[f64]) -> (f64, f64) {
    let (lo, hi) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if lo.is_finite() {
        (lo, hi)
    } else {
        (0.0, 0.0)
    }
}

/// The colour scale of a figure: linear or logarithmic over (lo, hi).
#[derive(Debug, Clone, Copy)]
struct ColorScale {
    lo: f64,
    hi: f64,
    log: bool,
}

impl ColorScale {
    /// Position of `v` on the colour map (0 bottom, 1 top, clamped by the
    /// map); on a log scale a value ≤ 0 sits at the bottom.
    fn t(&self, v: f64) -> f64 {
        if self.log {
            if v > 0.0 {
                normalize(v.log10(), self.lo.log10(), self.hi.log10())
            } else if v.is_nan() {
                v
            } else {
                0.0
            }
        } else {
            normalize(v, self.lo, self.hi)
        }
    }

    /// Tick values: five, evenly spaced on the scale.
    fn ticks(&self) -> Vec<f64> {
        if self.log && self.hi > self.lo && self.lo > 0.0 {
            let r = self.hi / self.lo;
            (0..5).map(|i| self.lo * r.powf(i as f64 / 4.0)).collect()
        } else {
            ticks(self.lo, self.hi)
        }
    }
}

/// The colour scale for `values`: `opts.range` if given, else the finite
/// values' range (the positive values' range on a log scale).
fn color_scale(v: &[f64], opts: &PlotOptions) -> Result<ColorScale, PlotError> {
    if let Some((lo, hi)) = opts.range {
        return Ok(ColorScale {
            lo,
            hi,
            log: opts.log,
        });
    }
    if opts.log {
        let pos: Vec<f64> = v.iter().copied().filter(|x| *x > 0.0).collect();
        if pos.is_empty() {
            return Err(err(format!(
                "--log: {} has no positive value (give --range MIN,MAX or drop --log)",
                opts.field.name()
            )));
        }
        let (lo, hi) = finite_range(&pos);
        return Ok(ColorScale { lo, hi, log: true });
    }
    let (lo, hi) = finite_range(v);
    Ok(ColorScale { lo, hi, log: false })
}

/// Position of `v` on the colour map of range (lo, hi).
fn normalize(v: f64, lo: f64, hi: f64) -> f64 {
    if hi > lo {
        (v - lo) / (hi - lo)
    } else {
        0.5
    }
}

#[allow(clippy::too_many_arguments)]
fn draw_mesh<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    raster: bool,
    mesh: &OutMesh,
    step: &StepOutput,
    opts: &PlotOptions,
    scale: f64,
    title: &str,
    fs: f64,
) -> Result<Option<(f64, f64)>, PlotError> {
    let values = field_values(mesh, step, opts.field);
    let cs = match &values {
        Values::Cell(v) | Values::Nodal(v) => Some(color_scale(v, opts)?),
        Values::Categories(..) => None,
    };
    let range = cs.map(|c| (c.lo, c.hi));
    let cs = cs.unwrap_or(ColorScale {
        lo: 0.0,
        hi: 0.0,
        log: false,
    });
    let pts: Vec<(f64, f64)> = mesh
        .points
        .iter()
        .zip(&step.displacement)
        .map(|(p, u)| (p[0] + scale * u[0], p[1] + scale * u[1]))
        .collect();

    let body = titled(root, title, fs)?;

    // Right strip: colour bar or legend, as wide as its text needs.
    let text: TextStyle = ("sans-serif", fs).into();
    let tw = |s: &str| {
        root.estimate_text_size(s, &text)
            .map(|(w, _)| w as f64)
            .unwrap_or(fs * 0.6 * s.chars().count() as f64)
    };
    let bar_w = (fs * 1.6).round();
    let labels: Vec<String> = match (&values, range) {
        (Values::Categories(_, names), _) => names.clone(),
        (_, Some(_)) => cs.ticks().iter().map(|&v| fmt_num(v)).collect(),
        _ => vec![],
    };
    let widest = labels.iter().map(|s| tw(s)).fold(0.0, f64::max);
    let strip_w = (fs + bar_w + fs * 0.5 + widest + fs)
        .max(
            tw(&format!(
                "{}{}",
                opts.field.label(),
                if cs.log { " (log)" } else { "" }
            )) + 2.0 * fs,
        )
        .min(body.dim_in_pixel().0 as f64 * 0.45) as u32;
    let (main, strip) = body.split_horizontally(body.dim_in_pixel().0.saturating_sub(strip_w));

    // Plot area: measure it once with dummy ranges (nothing is drawn), then
    // widen the data ranges so one metre is as long in x as in y.
    let margin = (fs * 0.8) as u32;
    let xl = (fs * 3.2) as u32;
    let yl = (fs * 4.6) as u32;
    let build = |xr: std::ops::Range<f64>, yr: std::ops::Range<f64>| {
        ChartBuilder::on(&main)
            .margin(margin)
            .x_label_area_size(xl)
            .y_label_area_size(yl)
            .build_cartesian_2d(xr, yr)
    };
    let (pw, ph) = build(0.0..1.0, 0.0..1.0)
        .map_err(de)?
        .plotting_area()
        .dim_in_pixel();
    let (lo, hi) = bbox(pts.iter().map(|&(x, y)| [x, y]));
    if !lo[0].is_finite() || !lo[1].is_finite() {
        return Err(err("no finite point coordinates to draw"));
    }
    let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
    let (rx, ry) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
    let per_px = (rx / pw.max(1) as f64).max(ry / ph.max(1) as f64) * 1.06;
    let (hx, hy) = (0.5 * per_px * pw as f64, 0.5 * per_px * ph as f64);
    let mut chart = build(cx - hx..cx + hx, cy - hy..cy + hy).map_err(de)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style(("sans-serif", fs * 0.9))
        .axis_desc_style(("sans-serif", fs))
        .x_label_formatter(&|v| tick(*v, 2.0 * hx))
        .y_label_formatter(&|v| tick(*v, 2.0 * hy))
        .draw()
        .map_err(de)?;

    // Colour of triangle i (cell values) or of a value (nodal).
    let cell_color = |i: usize| -> RGBColor {
        match &values {
            Values::Cell(v) => viridis(cs.t(v[i])),
            Values::Categories(c, _) => category_color(c[i]),
            Values::Nodal(v) => {
                let t = mesh.triangles[i];
                viridis(cs.t((v[t[0]] + v[t[1]] + v[t[2]]) / 3.0))
            }
        }
    };

    if raster {
        // Pixel mapping of the plot area (absolute backend coordinates).
        let (x0, y0) = chart.backend_coord(&(cx - hx, cy + hy));
        let (x1, y1) = chart.backend_coord(&(cx + hx, cy - hy));
        let (sx, sy) = ((x1 - x0) as f64 / (2.0 * hx), (y1 - y0) as f64 / (2.0 * hy));
        let to_px = |(x, y): (f64, f64)| {
            (
                x0 as f64 + (x - (cx - hx)) * sx,
                y0 as f64 + ((cy + hy) - y) * sy,
            )
        };
        let px: Vec<(f64, f64)> = pts.iter().map(|&p| to_px(p)).collect();
        let clip = (x0.min(x1), y0.min(y1), x0.max(x1), y0.max(y1));
        for (i, t) in mesh.triangles.iter().enumerate() {
            let nodal = match &values {
                Values::Nodal(v) => Some([v[t[0]], v[t[1]], v[t[2]]]),
                _ => None,
            };
            let flat = cell_color(i);
            fill_triangle([px[t[0]], px[t[1]], px[t[2]]], clip, |x, y, l| {
                let c = match nodal {
                    Some(v) => viridis(cs.t(l[0] * v[0] + l[1] * v[1] + l[2] * v[2])),
                    None => flat,
                };
                let _ = root.draw_pixel((x, y), &c);
            });
        }
    } else {
        // Vector output: one polygon per triangle, nodal fields on k² sub-triangles.
        let m = mesh.triangles.len();
        let k = match &values {
            Values::Nodal(_) if m * 9 <= 60_000 => 3,
            Values::Nodal(_) if m * 4 <= 60_000 => 2,
            _ => 1,
        };
        let mut polys: Vec<(Vec<(f64, f64)>, RGBColor)> = Vec::with_capacity(m * k * k);
        for (i, t) in mesh.triangles.iter().enumerate() {
            let (a, b, c) = (pts[t[0]], pts[t[1]], pts[t[2]]);
            match &values {
                Values::Nodal(v) if k > 1 => {
                    let val = [v[t[0]], v[t[1]], v[t[2]]];
                    for (l, tri) in subdivide(k) {
                        let at = |q: [f64; 3]| {
                            (
                                q[0] * a.0 + q[1] * b.0 + q[2] * c.0,
                                q[0] * a.1 + q[1] * b.1 + q[2] * c.1,
                            )
                        };
                        let value = l[0] * val[0] + l[1] * val[1] + l[2] * val[2];
                        polys.push((
                            vec![at(tri[0]), at(tri[1]), at(tri[2])],
                            viridis(cs.t(value)),
                        ));
                    }
                }
                _ => polys.push((vec![a, b, c], cell_color(i))),
            }
        }
        chart
            .draw_series(polys.into_iter().map(|(p, c)| Polygon::new(p, c.filled())))
            .map_err(de)?;
    }

    // Edges, when the triangles are large enough to see them.
    let (ex0, _) = chart.backend_coord(&(cx - hx, cy));
    let (ex1, _) = chart.backend_coord(&(cx + hx, cy));
    let px_per_m = (ex1 - ex0) as f64 / (2.0 * hx);
    let edges = unique_edges(&mesh.triangles);
    let mean_len = if edges.is_empty() {
        0.0
    } else {
        edges
            .iter()
            .map(|&(p, q)| (pts[p].0 - pts[q].0).hypot(pts[p].1 - pts[q].1))
            .sum::<f64>()
            / edges.len() as f64
    };
    if opts.edges.unwrap_or(mean_len * px_per_m >= 7.0) {
        let style = BLACK.mix(0.35).stroke_width(1);
        chart
            .draw_series(
                edges
                    .iter()
                    .map(|&(p, q)| PathElement::new(vec![pts[p], pts[q]], style)),
            )
            .map_err(de)?;
    }

    match &values {
        Values::Categories(_, names) => draw_legend(&strip, names, opts.field, fs)?,
        _ => draw_colorbar(&strip, cs, opts.field, fs, bar_w, margin + yl / 8)?,
    }
    Ok(range)
}

/// The area below the title, with a small margin all round.
fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    fs: f64,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
    let m = (fs * 0.5) as u32;
    root.margin(m, m / 2, m / 2, m + m / 2)
        .titled(title, ("sans-serif", fs * 1.35).into_font().color(&BLACK))
        .map_err(de)
}

/// Edges of the triangles, each once (sorted point pairs).
fn unique_edges(tris: &[[usize; 3]]) -> Vec<(usize, usize)> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for t in tris {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let e = (a.min(b), a.max(b));
            if seen.insert(e) {
                out.push(e);
            }
        }
    }
    out
}

/// The k² sub-triangles of the reference triangle: (barycentric centroid,
/// barycentric vertices).
fn subdivide(k: usize) -> Vec<([f64; 3], [[f64; 3]; 3])> {
    let kf = k as f64;
    let node = |i: usize, j: usize| {
        let (b, c) = (i as f64 / kf, j as f64 / kf);
        [1.0 - b - c, b, c]
    };
    let mut out = Vec::with_capacity(k * k);
    for i in 0..k {
        for j in 0..k - i {
            let tri = [node(i, j), node(i + 1, j), node(i, j + 1)];
            out.push((centroid(&tri), tri));
            if i + j + 1 < k {
                let tri = [node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)];
                out.push((centroid(&tri), tri));
            }
        }
    }
    out
}

fn centroid(t: &[[f64; 3]; 3]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for v in t {
        for k in 0..3 {
            c[k] += v[k] / 3.0;
        }
    }
    c
}

/// Calls `put(x, y, barycentric)` for every pixel whose centre lies in the
/// triangle (pixel coordinates), within `clip` = (x0, y0, x1, y1) inclusive.
fn fill_triangle(
    v: [(f64, f64); 3],
    clip: (i32, i32, i32, i32),
    mut put: impl FnMut(i32, i32, [f64; 3]),
) {
    let area = (v[1].0 - v[0].0) * (v[2].1 - v[0].1) - (v[2].0 - v[0].0) * (v[1].1 - v[0].1);
    if !area.is_finite() || area.abs() < 1e-12 {
        return;
    }
    let xmin = v.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let xmax = v.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let ymin = v.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let ymax = v.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let ix0 = ((xmin - 0.5).ceil() as i32).max(clip.0);
    let ix1 = ((xmax - 0.5).floor() as i32).min(clip.2);
    let iy0 = ((ymin - 0.5).ceil() as i32).max(clip.1);
    let iy1 = ((ymax - 0.5).floor() as i32).min(clip.3);
    let eps = 1e-9;
    for y in iy0..=iy1 {
        let py = y as f64 + 0.5;
        for x in ix0..=ix1 {
            let px = x as f64 + 0.5;
            let l1 = ((px - v[0].0) * (v[2].1 - v[0].1) - (v[2].0 - v[0].0) * (py - v[0].1)) / area;
            let l2 = ((v[1].0 - v[0].0) * (py - v[0].1) - (px - v[0].0) * (v[1].1 - v[0].1)) / area;
            let l0 = 1.0 - l1 - l2;
            if l0 >= -eps && l1 >= -eps && l2 >= -eps {
                put(x, y, [l0, l1, l2]);
            }
        }
    }
}

/// Tick values of the colour bar: min, max and three between.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    if hi > lo {
        (0..5).map(|i| lo + (hi - lo) * i as f64 / 4.0).collect()
    } else {
        vec![lo]
    }
}

fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    cs: ColorScale,
    field: Field,
    fs: f64,
    bar_w: f64,
    top: u32,
) -> Result<(), PlotError> {
    let (_, h) = area.dim_in_pixel();
    let x0 = fs.round() as i32;
    let x1 = x0 + bar_w as i32;
    let y0 = top as i32 + (fs * 2.2) as i32;
    let y1 = h as i32 - (fs * 4.2) as i32;
    if y1 <= y0 + 10 {
        return Ok(());
    }
    let label = ("sans-serif", fs).into_font().color(&BLACK);
    let title = if cs.log {
        format!("{} (log)", field.label())
    } else {
        field.label()
    };
    area.draw(&Text::new(
        title,
        (x0 - (fs * 0.5) as i32, top as i32),
        label.clone(),
    ))
    .map_err(de)?;
    let bands = ((y1 - y0) as usize).min(256);
    let span = (y1 - y0) as f64;
    draw_bands(area, bands, (x0, x1), y0, span)?;
    area.draw(&Rectangle::new([(x0, y0), (x1, y1)], BLACK.stroke_width(1)))
        .map_err(de)?;
    let tick_style = label.pos(Pos::new(HPos::Left, VPos::Center));
    for v in cs.ticks() {
        let t = cs.t(v);
        let y = y1 - (t * span).round() as i32;
        area.draw(&PathElement::new(
            vec![(x1, y), (x1 + (fs * 0.4) as i32, y)],
            BLACK.stroke_width(1),
        ))
        .map_err(de)?;
        area.draw(&Text::new(
            fmt_num(v),
            (x1 + (fs * 0.6) as i32, y),
            tick_style.clone(),
        ))
        .map_err(de)?;
    }
    Ok(())
}

/// The gradient of the colour bar: `bands` horizontal strips from the top
/// (t = 1) to the bottom (t = 0).
fn draw_bands<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    bands: usize,
    (x0, x1): (i32, i32),
    y0: i32,
    span: f64,
) -> Result<(), PlotError> {
    for b in 0..bands {
        let ya = y0 + (span * b as f64 / bands as f64).round() as i32;
        let yb = y0 + (span * (b + 1) as f64 / bands as f64).round() as i32;
        let t = 1.0 - (b as f64 + 0.5) / bands as f64;
        area.draw(&Rectangle::new([(x0, ya), (x1, yb)], viridis(t).filled()))
            .map_err(de)?;
    }
    Ok(())
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    names: &[String],
    field: Field,
    fs: f64,
) -> Result<(), PlotError> {
    let style = ("sans-serif", fs).into_font().color(&BLACK);
    let x0 = fs.round() as i32;
    let mut y = (fs * 2.0) as i32;
    area.draw(&Text::new(field.name().to_string(), (x0, y), style.clone()))
        .map_err(de)?;
    y += (fs * 2.0) as i32;
    let box_s = fs as i32;
    let row_style = style.pos(Pos::new(HPos::Left, VPos::Center));
    for (i, n) in names.iter().enumerate() {
        area.draw(&Rectangle::new(
            [(x0, y - box_s / 2), (x0 + box_s, y + box_s / 2)],
            category_color(i).filled(),
        ))
        .map_err(de)?;
        area.draw(&Text::new(
            n.clone(),
            (x0 + box_s + (fs * 0.5) as i32, y),
            row_style.clone(),
        ))
        .map_err(de)?;
        y += (fs * 1.6) as i32;
    }
    Ok(())
}

// ---------------------------------------------------------------- contact figure

/// The contact rows of interface `iface` as polylines: its segments chained
/// through shared points. Each chain is oriented so that its first segment
/// (in `segments` order) runs as stored, and the chains come in the order
/// of their first segments; a branch or a break starts a new chain.
pub fn interface_chains(c: &ContactGeometry, iface: u32) -> Vec<Vec<usize>> {
    let segs: Vec<[usize; 2]> = c
        .segments
        .iter()
        .copied()
        .filter(|&[a, b]| c.interface[a] == iface && c.interface[b] == iface && a != b)
        .collect();
    let mut adj: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, &[a, b]) in segs.iter().enumerate() {
        adj.entry(a).or_default().push(k);
        adj.entry(b).or_default().push(k);
    }
    let mut used = vec![false; segs.len()];
    // Extends `path` from its last point through unused segments.
    let walk = |path: &mut Vec<usize>, used: &mut Vec<bool>| loop {
        let end = *path.last().unwrap();
        let next = adj[&end].iter().copied().find(|&k| !used[k]);
        match next {
            Some(k) => {
                used[k] = true;
                let [a, b] = segs[k];
                path.push(if a == end { b } else { a });
            }
            None => break,
        }
    };
    let mut chains = Vec::new();
    for k in 0..segs.len() {
        if used[k] {
            continue;
        }
        used[k] = true;
        let [a, b] = segs[k];
        let mut fwd = vec![a, b];
        walk(&mut fwd, &mut used);
        let mut back = vec![a];
        walk(&mut back, &mut used);
        back.reverse();
        back.pop();
        back.extend(fwd);
        chains.push(back);
    }
    chains
}

/// Arc length along the chains of one interface: (s, row) per point of
/// each piece; s runs on from one piece to the next.
pub fn arc_lengths(c: &ContactGeometry, chains: &[Vec<usize>]) -> Vec<Vec<(f64, usize)>> {
    let mut s = 0.0;
    chains
        .iter()
        .map(|ch| {
            let mut out = Vec::with_capacity(ch.len());
            for (k, &r) in ch.iter().enumerate() {
                if k > 0 {
                    let (p, q) = (c.points[ch[k - 1]], c.points[r]);
                    s += (q[0] - p[0]).hypot(q[1] - p[1]);
                }
                out.push((s, r));
            }
            out
        })
        .collect()
}

/// (rows, columns) of the contact plot's panels for `n` interfaces: one
/// column up to three, then a grid, so that a panel keeps room for its
/// caption, ticks and axis names (six panels stacked in a 900 px figure had
/// 80 px each, and their tick labels overlapped).
fn contact_grid(n: usize) -> (usize, usize) {
    let cols = match n {
        0..=3 => 1,
        4..=8 => 2,
        _ => 3,
    };
    (n.div_ceil(cols).max(1), cols)
}

/// The contact pressure against arc length, one panel per interface (each
/// with its own pressure axis unless `range` fixes it), one curve per step
/// drawn (coloured along viridis with a legend when there are several).
/// Each panel says where its arc length starts: the first contact point of
/// the interface's first chain (at the first side: the lower body, or the
/// slave).
fn draw_contact<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    c: &ContactGeometry,
    steps: &[(usize, StepOutput)],
    title: &str,
    fs: f64,
    range: Option<(f64, f64)>,
) -> Result<Option<(f64, f64)>, PlotError> {
    if c.points.is_empty() {
        return Err(err("no contact interface in the checkpoint"));
    }
    let n_if = c
        .interface
        .iter()
        .map(|&i| i as usize + 1)
        .max()
        .unwrap_or(0)
        .max(c.interface_names.len());
    // (interface name, start point, its pieces of (arc length, row)).
    type Series = (String, [f64; 2], Vec<Vec<(f64, usize)>>);
    let mut series: Vec<Series> = Vec::new();
    for i in 0..n_if {
        let chains = interface_chains(c, i as u32);
        if chains.is_empty() {
            continue;
        }
        let name = c
            .interface_names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("interface {i}"));
        let start = c.points[chains[0][0]];
        series.push((name, start, arc_lengths(c, &chains)));
    }
    if series.is_empty() {
        return Err(err("no contact segment in the checkpoint"));
    }
    let many = steps.len() > 1;
    let color_of = |j: usize, k: usize| {
        if many {
            viridis(j as f64 / (steps.len() - 1) as f64 * 0.9)
        } else {
            category_color(k)
        }
    };
    let mut body = titled(root, title, fs)?;
    if many {
        // One legend for every panel, in a strip under the title (the
        // steps have the same colours in each), wrapped onto more lines
        // when the labels do not fit on one.
        let style = ("sans-serif", fs * 0.85).into_font().color(&BLACK);
        let (sw, _) = body.dim_in_pixel();
        let (x0, line_h) = ((fs * 1.5) as i32, (fs * 1.6) as i32);
        let mut placed = vec![];
        let (mut x, mut y) = (x0, (fs * 0.9) as i32);
        for (j, (no, st)) in steps.iter().enumerate() {
            let label = format!("step {no} (t = {})", fmt_num(st.time));
            let (tw, _) = body.estimate_text_size(&label, &style).map_err(de)?;
            let w = (fs * 2.2) as i32 + tw as i32 + (fs * 1.0) as i32;
            if x + w > sw as i32 && x > x0 {
                x = x0;
                y += line_h;
            }
            placed.push((j, label, x, y));
            x += w;
        }
        let (strip, rest) = body.split_vertically((y + (fs * 1.0) as i32).max(1) as u32);
        for (j, label, x, y) in placed {
            strip
                .draw(&PathElement::new(
                    vec![(x, y), (x + (fs * 1.8) as i32, y)],
                    color_of(j, 0).stroke_width(4),
                ))
                .map_err(de)?;
            strip
                .draw(&Text::new(
                    label,
                    (x + (fs * 2.2) as i32, y - (fs * 0.45) as i32),
                    style.clone(),
                ))
                .map_err(de)?;
        }
        body = rest;
    }
    let panels = body.split_evenly(contact_grid(series.len()));
    let mut total: Option<(f64, f64)> = None;
    for (k, ((name, start, pieces), panel)) in series.iter().zip(&panels).enumerate() {
        let pts = || {
            steps.iter().flat_map(|(_, st)| {
                pieces
                    .iter()
                    .flatten()
                    .map(|&(s, r)| (s, st.contact_pressure[r]))
                    .filter(|(s, p)| s.is_finite() && p.is_finite())
            })
        };
        let smax = pts().map(|q| q.0).fold(0.0, f64::max);
        let (plo, phi) = pts().fold((0.0f64, 0.0f64), |(a, b), q| (a.min(q.1), b.max(q.1)));
        total = Some(match total {
            Some((a, b)) => (a.min(plo), b.max(phi)),
            None => (plo, phi),
        });
        let yr = match range {
            Some((lo, hi)) => lo..hi,
            None => {
                let pad = (phi - plo).max(phi.abs()).max(plo.abs()).max(1e-300) * 0.06;
                if phi > plo {
                    (plo - if plo < 0.0 { pad } else { 0.0 })..(phi + pad)
                } else {
                    0.0..1.0
                }
            }
        };
        let xr = 0.0..if smax > 0.0 { smax } else { 1.0 };
        let (xspan, yspan) = (xr.end - xr.start, yr.end - yr.start);
        let caption = format!(
            "{name} (arc length from ({}, {}){})",
            fmt_num(start[0]),
            fmt_num(start[1]),
            if pieces.len() > 1 {
                format!(", {} pieces end to end", pieces.len())
            } else {
                String::new()
            }
        );
        let mut chart = ChartBuilder::on(panel)
            .margin((fs * 0.8) as u32)
            .caption(caption, ("sans-serif", fs * 1.05))
            .x_label_area_size((fs * 3.0) as u32)
            .y_label_area_size((fs * 6.0) as u32)
            .build_cartesian_2d(xr, yr)
            .map_err(de)?;
        // As many pressure ticks as the panel's plot height holds at about
        // two font heights apart.
        let (_, ph) = panel.dim_in_pixel();
        let y_ticks = ((ph as f64 - fs * 7.0) / (fs * 2.2)).clamp(2.0, 10.0) as usize;
        chart
            .configure_mesh()
            .y_labels(y_ticks)
            .x_desc("arc length s [m]")
            .y_desc("contact pressure [Pa]")
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.12))
            .label_style(("sans-serif", fs * 0.9))
            .axis_desc_style(("sans-serif", fs))
            .x_label_formatter(&|v| tick(*v, xspan))
            .y_label_formatter(&|v| tick(*v, yspan))
            .draw()
            .map_err(de)?;
        let radius = (fs * if many { 0.16 } else { 0.22 }).max(2.0) as i32;
        for (j, (_, st)) in steps.iter().enumerate() {
            let color = color_of(j, k);
            for piece in pieces {
                let line: Vec<(f64, f64)> = piece
                    .iter()
                    .map(|&(s, r)| (s, st.contact_pressure[r]))
                    .collect();
                chart
                    .draw_series(LineSeries::new(line.iter().copied(), color.stroke_width(2)))
                    .map_err(de)?;
                chart
                    .draw_series(line.iter().map(|&p| Circle::new(p, radius, color.filled())))
                    .map_err(de)?;
            }
        }
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn many_interfaces_are_drawn_on_a_grid_every_panel_in_it() {
        for n in 1..=20 {
            let (r, c) = contact_grid(n);
            assert!(r * c >= n && r * c < n + c, "{n}: {r}×{c}");
            // At the default 900 px, a panel keeps ≥ 150 px.
            assert!(900 / r >= 150 || n > 18, "{n}: {r} rows");
        }
        assert_eq!(contact_grid(2), (2, 1));
        assert_eq!(contact_grid(6), (3, 2));
    }

    #[test]
    fn a_tick_within_rounding_of_zero_is_zero() {
        assert_eq!(tick(-2.220446049250313e-16, 2.2), "0");
        assert_eq!(tick(1e-3, 2.2), "0.001");
        assert_eq!(tick(-0.4, 2.2), "-0.4");
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(1.5), "1.5");
        assert_eq!(fmt_num(-0.25), "-0.25");
        assert_eq!(fmt_num(1234.5678), "1235");
        assert_eq!(fmt_num(1.0e6), "1e6");
        assert_eq!(fmt_num(-2.5e-5), "-2.5e-5");
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(viridis(1.0), RGBColor(0xfd, 0xe7, 0x25));
        assert_eq!(viridis(2.0), viridis(1.0));
    }

    #[test]
    fn subdivision_covers_the_triangle() {
        for k in 1..5 {
            let s = subdivide(k);
            assert_eq!(s.len(), k * k);
        }
    }

    #[test]
    fn chains_join_segments_in_order() {
        let c = ContactGeometry {
            points: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [5.0, 0.0], [6.0, 0.0]],
            interface: vec![0, 0, 0, 0, 0],
            segments: vec![[1, 2], [3, 4], [1, 0]],
            ..Default::default()
        };
        let ch = interface_chains(&c, 0);
        assert_eq!(ch, vec![vec![0, 1, 2], vec![3, 4]]);
        let s = arc_lengths(&c, &ch);
        assert_eq!(
            s[0].iter().map(|q| q.0).collect::<Vec<_>>(),
            vec![0.0, 1.0, 2.0]
        );
        assert_eq!(s[1].iter().map(|q| q.0).collect::<Vec<_>>(), vec![2.0, 3.0]);
    }
}
