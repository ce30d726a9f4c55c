//! Flat figures of the 3D plots: panels of triangles in a plane's own
//! axes, coloured by a value per triangle or per point, one metre as long
//! in both axes, with one colour bar for all (the 2D figure's colour bar,
//! triangle filler and tick format).

use super::colorbar::{draw_colorbar_labelled, ColorScale};
use super::mesh::{bbox, check_extent, fill_triangle, subdivide};
use super::style::{de, fmt_num, tick, titled, viridis};
use super::{err, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(super) type P2 = (f64, f64);

/// What fills a panel's triangles.
pub(super) enum Fill {
    /// One value per triangle.
    Cell(Vec<f64>),
    /// One value per point, linear inside each triangle.
    Nodal(Vec<f64>),
}

/// One panel: its triangles in plane coordinates and what to draw on them.
pub(super) struct Panel {
    pub title: String,
    /// Axis labels with their unit.
    pub labels: [String; 2],
    pub pts: Vec<P2>,
    pub tris: Vec<[usize; 3]>,
    pub fill: Fill,
    /// Thin lines (element edges), drawn when large enough or asked.
    pub edges: Vec<[P2; 2]>,
    /// Bold lines (the active set's boundary).
    pub outline: Vec<[P2; 2]>,
    /// Bold white lines (friction: the boundary of the slip zone).
    pub zones: Vec<[P2; 2]>,
    /// Arrows from tail to tip (friction: the tangential traction).
    pub arrows: Vec<[P2; 2]>,
}

/// Draws `panels` side by side (a grid of up to three columns) under
/// `title`, with one colour bar `bar_label` of scale `cs` on the right.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    raster: bool,
    title: &str,
    panels: &[Panel],
    cs: ColorScale,
    bar_label: &str,
    fs: f64,
    edges: Option<bool>,
) -> Result<(), PlotError> {
    for p in panels {
        let (lo, hi) = bbox(p.pts.iter().map(|&(x, y)| [x, y]));
        if !lo[0].is_finite() || !lo[1].is_finite() {
            return Err(err("no finite point coordinates to draw"));
        }
        check_extent(lo, hi, 1.0)?;
    }
    root.fill(&WHITE).map_err(de)?;
    let body = titled(root, title, fs)?;
    let text: TextStyle = ("sans-serif", fs).into();
    let tw = |s: &str| {
        root.estimate_text_size(s, &text)
            .map(|(w, _)| w as f64)
            .unwrap_or(fs * 0.6 * s.chars().count() as f64)
    };
    let bar_w = (fs * 1.6).round();
    let widest = cs
        .ticks()
        .iter()
        .map(|&v| tw(&fmt_num(v)))
        .fold(0.0, f64::max);
    let strip_w = (fs + bar_w + fs * 0.5 + widest + fs)
        .max(tw(bar_label) + 2.0 * fs)
        .min(body.dim_in_pixel().0 as f64 * 0.45) as u32;
    let (main, strip) = body.split_horizontally(body.dim_in_pixel().0.saturating_sub(strip_w));
    let cols = match panels.len() {
        0 | 1 => 1,
        2 | 4 => 2,
        _ => 3,
    };
    let rows = panels.len().div_ceil(cols).max(1);
    let cells = main.split_evenly((rows, cols));
    for (p, area) in panels.iter().zip(&cells) {
        draw_panel(root, area, raster, p, cs, fs, edges)?;
    }
    let margin = (fs * 0.8) as u32;
    let top = if panels.len() > 1 { fs * 1.6 } else { 0.0 } as u32;
    draw_colorbar_labelled(&strip, cs, bar_label, fs, bar_w, margin + top + fs as u32)
}

fn draw_panel<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    area: &DrawingArea<DB, Shift>,
    raster: bool,
    p: &Panel,
    cs: ColorScale,
    fs: f64,
    edges: Option<bool>,
) -> Result<(), PlotError> {
    let area = if p.title.is_empty() {
        area.clone()
    } else {
        // A title wider than its panel (a 3D footprint's counts and plane
        // normal) is set smaller rather than clipped at both sides.
        let size = fs * 1.05;
        let width = area.dim_in_pixel().0 as f64;
        let wide = area
            .estimate_text_size(&p.title, &("sans-serif", size).into_font().into())
            .map_or(0.0, |(w, _)| w as f64);
        let size = if wide > 0.98 * width {
            size * 0.98 * width / wide
        } else {
            size
        };
        area.titled(&p.title, ("sans-serif", size).into_font().color(&BLACK))
            .map_err(de)?
    };
    let (lo, hi) = bbox(p.pts.iter().map(|&(x, y)| [x, y]));
    let margin = (fs * 0.8) as u32;
    let xl = (fs * 3.2) as u32;
    let yl = (fs * 4.6) as u32;
    let build = |xr: std::ops::Range<f64>, yr: std::ops::Range<f64>| {
        ChartBuilder::on(&area)
            .margin(margin)
            .x_label_area_size(xl)
            .y_label_area_size(yl)
            .build_cartesian_2d(xr, yr)
    };
    let (pw, ph) = build(0.0..1.0, 0.0..1.0)
        .map_err(de)?
        .plotting_area()
        .dim_in_pixel();
    // Widen one data range so that one metre is as long in x as in y.
    let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
    let (rx, ry) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
    let per_px = (rx / pw.max(1) as f64).max(ry / ph.max(1) as f64) * 1.06;
    let (hx, hy) = (0.5 * per_px * pw as f64, 0.5 * per_px * ph as f64);
    let mut chart = build(cx - hx..cx + hx, cy - hy..cy + hy).map_err(de)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(p.labels[0].clone())
        .y_desc(p.labels[1].clone())
        // Ticks a few font sizes apart, so narrow panels stay legible.
        .x_labels(((pw as f64 / (fs * 5.0)) as usize).clamp(3, 10))
        .y_labels(((ph as f64 / (fs * 2.5)) as usize).clamp(3, 10))
        .label_style(("sans-serif", fs * 0.9))
        .axis_desc_style(("sans-serif", fs))
        .x_label_formatter(&|v| tick(*v, 2.0 * hx))
        .y_label_formatter(&|v| tick(*v, 2.0 * hy))
        .draw()
        .map_err(de)?;
    if raster {
        // Every pixel of every triangle, in the root's (absolute) pixels.
        let (x0, y0) = chart.backend_coord(&(cx - hx, cy + hy));
        let (x1, y1) = chart.backend_coord(&(cx + hx, cy - hy));
        let (sx, sy) = ((x1 - x0) as f64 / (2.0 * hx), (y1 - y0) as f64 / (2.0 * hy));
        let px: Vec<P2> = p
            .pts
            .iter()
            .map(|&(x, y)| {
                (
                    x0 as f64 + (x - (cx - hx)) * sx,
                    y0 as f64 + ((cy + hy) - y) * sy,
                )
            })
            .collect();
        let clip = (x0.min(x1), y0.min(y1), x0.max(x1), y0.max(y1));
        for (i, t) in p.tris.iter().enumerate() {
            let v = match &p.fill {
                Fill::Cell(v) => [v[i]; 3],
                Fill::Nodal(v) => [v[t[0]], v[t[1]], v[t[2]]],
            };
            fill_triangle([px[t[0]], px[t[1]], px[t[2]]], clip, |x, y, l| {
                let c = viridis(cs.t(l[0] * v[0] + l[1] * v[1] + l[2] * v[2]));
                let _ = root.draw_pixel((x, y), &c);
            });
        }
    } else {
        let k = match &p.fill {
            Fill::Nodal(_) if p.tris.len() * 9 <= 60_000 => 3,
            Fill::Nodal(_) if p.tris.len() * 4 <= 60_000 => 2,
            _ => 1,
        };
        let sub = subdivide(k);
        let mut polys: Vec<(Vec<P2>, RGBColor)> = Vec::with_capacity(p.tris.len() * k * k);
        for (i, t) in p.tris.iter().enumerate() {
            let (a, b, c) = (p.pts[t[0]], p.pts[t[1]], p.pts[t[2]]);
            let v = match &p.fill {
                Fill::Cell(v) => [v[i]; 3],
                Fill::Nodal(v) => [v[t[0]], v[t[1]], v[t[2]]],
            };
            for (l, tri) in &sub {
                let at = |q: [f64; 3]| {
                    (
                        q[0] * a.0 + q[1] * b.0 + q[2] * c.0,
                        q[0] * a.1 + q[1] * b.1 + q[2] * c.1,
                    )
                };
                let value = l[0] * v[0] + l[1] * v[1] + l[2] * v[2];
                polys.push((
                    vec![at(tri[0]), at(tri[1]), at(tri[2])],
                    viridis(cs.t(value)),
                ));
            }
        }
        chart
            .draw_series(polys.into_iter().map(|(q, c)| Polygon::new(q, c.filled())))
            .map_err(de)?;
    }
    let (ex0, _) = chart.backend_coord(&(cx - hx, cy));
    let (ex1, _) = chart.backend_coord(&(cx + hx, cy));
    let px_per_m = (ex1 - ex0) as f64 / (2.0 * hx);
    let mean_len = if p.edges.is_empty() {
        0.0
    } else {
        p.edges
            .iter()
            .map(|[a, b]| (a.0 - b.0).hypot(a.1 - b.1))
            .sum::<f64>()
            / p.edges.len() as f64
    };
    if edges.unwrap_or(mean_len * px_per_m >= 7.0) {
        let style = BLACK.mix(0.35).stroke_width(1);
        chart
            .draw_series(
                p.edges
                    .iter()
                    .map(|&[a, b]| PathElement::new(vec![a, b], style)),
            )
            .map_err(de)?;
    }
    let bold = RGBColor(220, 20, 60).stroke_width(((fs / 6.0).round() as u32).max(2));
    chart
        .draw_series(
            p.outline
                .iter()
                .map(|&[a, b]| PathElement::new(vec![a, b], bold)),
        )
        .map_err(de)?;
    let white = WHITE.stroke_width(((fs / 6.0).round() as u32).max(2));
    chart
        .draw_series(
            p.zones
                .iter()
                .map(|&[a, b]| PathElement::new(vec![a, b], white)),
        )
        .map_err(de)?;
    // Arrows: a shaft and two barbs of a quarter of its length at ±25°.
    let thin = BLACK.stroke_width(((fs / 10.0).round() as u32).max(1));
    let mut lines = Vec::with_capacity(3 * p.arrows.len());
    for &[a, b] in &p.arrows {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        lines.push(vec![a, b]);
        for ang in [0.436f64, -0.436] {
            let (c, s) = (ang.cos(), ang.sin());
            let back = (-0.3 * (c * dx - s * dy), -0.3 * (s * dx + c * dy));
            lines.push(vec![b, (b.0 + back.0, b.1 + back.1)]);
        }
    }
    chart
        .draw_series(lines.into_iter().map(|l| PathElement::new(l, thin)))
        .map_err(de)?;
    Ok(())
}
