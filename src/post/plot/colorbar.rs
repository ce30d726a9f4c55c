//! The colour side of the mesh figure: a field's values, their colour
//! scale (linear or logarithmic), and the colour bar or the legend of the
//! categories.

use super::style::{category_color, de, fmt_num, viridis};
use super::{err, Field, PlotError, PlotOptions, Units};
use crate::output::{OutMesh, StepOutput};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The values of a field: per triangle, per point, or categories.
pub(super) enum Values {
    Cell(Vec<f64>),
    Nodal(Vec<f64>),
    Categories(Vec<usize>, Vec<String>),
}

pub(super) fn field_values(mesh: &OutMesh, step: &StepOutput, field: Field) -> Values {
    let cell = |f: &dyn Fn(usize) -> f64| Values::Cell((0..mesh.triangles.len()).map(f).collect());
    let nodal = |f: &dyn Fn([f64; 2]) -> f64| {
        Values::Nodal(step.displacement.iter().map(|&u| f(u)).collect())
    };
    match field {
        Field::VonMises => cell(&|i| step.von_mises[i]),
        Field::Sxx | Field::Srr => cell(&|i| step.stress[i][0]),
        Field::Syy | Field::SzzAxial => cell(&|i| step.stress[i][1]),
        Field::Sxy | Field::Srz => cell(&|i| step.stress[i][2]),
        Field::Szz | Field::Stt => cell(&|i| step.stress[i][3]),
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

pub(super) fn finite_range(v: &[f64]) -> (f64, f64) {
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
pub(super) struct ColorScale {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) log: bool,
}

impl ColorScale {
    /// Position of `v` on the colour map (0 bottom, 1 top, clamped by the
    /// map); on a log scale a value ≤ 0 sits at the bottom.
    pub(super) fn t(&self, v: f64) -> f64 {
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
    pub(super) fn ticks(&self) -> Vec<f64> {
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
pub(super) fn color_scale(v: &[f64], opts: &PlotOptions) -> Result<ColorScale, PlotError> {
    scale_of(v, opts.range, opts.log, opts.field.name(), opts.change)
}

/// [`color_scale`] of the field named `name` (a 3D field is no [`Field`]).
pub(super) fn scale_of(
    v: &[f64],
    range: Option<(f64, f64)>,
    log: bool,
    name: &str,
    change: bool,
) -> Result<ColorScale, PlotError> {
    if let Some((lo, hi)) = range {
        return Ok(ColorScale { lo, hi, log });
    }
    if log {
        let pos: Vec<f64> = v.iter().copied().filter(|x| *x > 0.0).collect();
        if pos.is_empty() {
            return Err(err(format!(
                "--log: {name} has no positive value (give --range MIN,MAX or drop --log)"
            )));
        }
        let (lo, hi) = finite_range(&pos);
        return Ok(ColorScale { lo, hi, log: true });
    }
    let (lo, hi) = finite_range(v);
    // A span beyond a double would put every value at one end and the
    // ticks at ±inf: refused, naming the field (issue 34).
    if !(hi - lo).is_finite() {
        return Err(err(format!(
            "field {name}{}: values from {} to {}, a span too large for the colour scale (give --range MIN,MAX)",
            if change { " (change)" } else { "" },
            fmt_num(lo),
            fmt_num(hi)
        )));
    }
    Ok(ColorScale { lo, hi, log: false })
}

/// Position of `v` on the colour map of range (lo, hi).
pub(super) fn normalize(v: f64, lo: f64, hi: f64) -> f64 {
    if hi > lo {
        (v - lo) / (hi - lo)
    } else {
        0.5
    }
}

/// Tick values of the colour bar: min, max and three between.
pub(super) fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    if hi > lo {
        (0..5).map(|i| lo + (hi - lo) * i as f64 / 4.0).collect()
    } else {
        vec![lo]
    }
}

pub(super) fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    cs: ColorScale,
    field: Field,
    units: &Units,
    fs: f64,
    bar_w: f64,
    top: u32,
) -> Result<(), PlotError> {
    draw_colorbar_labelled(area, cs, &field.label(units), fs, bar_w, top)
}

/// [`draw_colorbar`] titled `label` ("von_mises \[Pa\]").
pub(super) fn draw_colorbar_labelled<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    cs: ColorScale,
    label_text: &str,
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
        format!("{label_text} (log)")
    } else {
        label_text.to_string()
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
pub(super) fn draw_bands<DB: DrawingBackend>(
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

pub(super) fn draw_legend<DB: DrawingBackend>(
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
