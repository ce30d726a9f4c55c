//! The mesh figure: the deformed mesh, every triangle coloured by a field,
//! x and y at the same scale; rasterised per pixel (PNG) or drawn as
//! polygons (SVG).

use super::colorbar::{color_scale, draw_colorbar, draw_legend, field_values, ColorScale, Values};
use super::style::{category_color, de, fmt_num, tick, titled, viridis};
use super::{err, PlotError, PlotOptions};
use crate::output::{OutMesh, StepOutput};
use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::HashSet;

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

pub(super) fn bbox(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
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

/// The chart of the mesh figure: metres on both axes.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The data window of the mesh figure: centre (cx, cy) and half-widths
/// (hx, hy) \[m\].
#[derive(Clone, Copy)]
struct Window {
    cx: f64,
    cy: f64,
    hx: f64,
    hy: f64,
}

#[allow(clippy::too_many_arguments)]
pub(super) fn draw_mesh<DB: DrawingBackend>(
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
    // The window first: a figure that cannot be drawn is refused before
    // anything is.
    let (lo, hi) = bbox(pts.iter().map(|&(x, y)| [x, y]));
    if !lo[0].is_finite() || !lo[1].is_finite() {
        return Err(err("no finite point coordinates to draw"));
    }
    check_extent(lo, hi, scale)?;

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
                opts.field.label(&opts.units),
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
    let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
    let (rx, ry) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
    let per_px = (rx / pw.max(1) as f64).max(ry / ph.max(1) as f64) * 1.06;
    let (hx, hy) = (0.5 * per_px * pw as f64, 0.5 * per_px * ph as f64);
    let win = Window { cx, cy, hx, hy };
    let mut chart = build(cx - hx..cx + hx, cy - hy..cy + hy).map_err(de)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(format!("x [{}]", opts.units.length))
        .y_desc(format!("y [{}]", opts.units.length))
        .label_style(("sans-serif", fs * 0.9))
        .axis_desc_style(("sans-serif", fs))
        .x_label_formatter(&|v| tick(*v, 2.0 * hx))
        .y_label_formatter(&|v| tick(*v, 2.0 * hy))
        .draw()
        .map_err(de)?;

    let paint = Paint {
        mesh,
        values: &values,
        cs,
        pts: &pts,
    };
    if raster {
        paint.pixels(root, &chart, win);
    } else {
        paint.polygons(&mut chart)?;
    }
    draw_edges(&mut chart, mesh, &pts, opts.edges, win)?;

    match &values {
        Values::Categories(_, names) => draw_legend(&strip, names, opts.field, fs)?,
        _ => draw_colorbar(
            &strip,
            cs,
            opts.field,
            &opts.units,
            fs,
            bar_w,
            margin + yl / 8,
        )?,
    }
    Ok(range)
}

/// Refuses deformed coordinates whose extent a double cannot hold with
/// the figure's margins: the axis span (up to 1.06 times the extent, and
/// the plotting library's tick search works on multiples of it, hence the
/// factor 16) must stay finite. An infinite axis drew nothing sensible,
/// and its tick search never returned (issue 34).
pub(super) fn check_extent(lo: [f64; 2], hi: [f64; 2], scale: f64) -> Result<(), PlotError> {
    for (k, axis) in ["x", "y"].iter().enumerate() {
        if !((hi[k] - lo[k]) * 16.0).is_finite() {
            return Err(err(format!(
                "/mesh/nodes displaced by {} × the displacement: the {axis} coordinates run from {} to {}, a span too large to draw",
                fmt_num(scale),
                fmt_num(lo[k]),
                fmt_num(hi[k])
            )));
        }
    }
    Ok(())
}

/// What fills the triangles: the field's values on the deformed points.
struct Paint<'a> {
    mesh: &'a OutMesh,
    values: &'a Values,
    cs: ColorScale,
    pts: &'a [(f64, f64)],
}

impl Paint<'_> {
    /// Colour of triangle i (cell values) or of a value (nodal).
    fn cell_color(&self, i: usize) -> RGBColor {
        match self.values {
            Values::Cell(v) => viridis(self.cs.t(v[i])),
            Values::Categories(c, _) => category_color(c[i]),
            Values::Nodal(v) => {
                let t = self.mesh.triangles[i];
                viridis(self.cs.t((v[t[0]] + v[t[1]] + v[t[2]]) / 3.0))
            }
        }
    }

    /// Raster output: every pixel of every triangle, nodal fields
    /// interpolated linearly inside it.
    fn pixels<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        chart: &Chart<'_, DB>,
        win: Window,
    ) {
        let Window { cx, cy, hx, hy } = win;
        let cs = self.cs;
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
        let px: Vec<(f64, f64)> = self.pts.iter().map(|&p| to_px(p)).collect();
        let clip = (x0.min(x1), y0.min(y1), x0.max(x1), y0.max(y1));
        for (i, t) in self.mesh.triangles.iter().enumerate() {
            let nodal = match self.values {
                Values::Nodal(v) => Some([v[t[0]], v[t[1]], v[t[2]]]),
                _ => None,
            };
            let flat = self.cell_color(i);
            fill_triangle([px[t[0]], px[t[1]], px[t[2]]], clip, |x, y, l| {
                let c = match nodal {
                    Some(v) => viridis(cs.t(l[0] * v[0] + l[1] * v[1] + l[2] * v[2])),
                    None => flat,
                };
                let _ = root.draw_pixel((x, y), &c);
            });
        }
    }

    /// Vector output: one polygon per triangle, nodal fields on k²
    /// sub-triangles.
    fn polygons<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<(), PlotError> {
        let (mesh, pts) = (self.mesh, self.pts);
        let m = mesh.triangles.len();
        let k = match self.values {
            Values::Nodal(_) if m * 9 <= 60_000 => 3,
            Values::Nodal(_) if m * 4 <= 60_000 => 2,
            _ => 1,
        };
        let mut polys: Vec<(Vec<(f64, f64)>, RGBColor)> = Vec::with_capacity(m * k * k);
        for (i, t) in mesh.triangles.iter().enumerate() {
            let (a, b, c) = (pts[t[0]], pts[t[1]], pts[t[2]]);
            match self.values {
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
                            viridis(self.cs.t(value)),
                        ));
                    }
                }
                _ => polys.push((vec![a, b, c], self.cell_color(i))),
            }
        }
        chart
            .draw_series(polys.into_iter().map(|(p, c)| Polygon::new(p, c.filled())))
            .map_err(de)?;
        Ok(())
    }
}

/// The triangle edges, when asked (`edges`) or, by default, when the
/// triangles are large enough to see them.
fn draw_edges<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    mesh: &OutMesh,
    pts: &[(f64, f64)],
    edges: Option<bool>,
    win: Window,
) -> Result<(), PlotError> {
    let Window { cx, cy, hx, .. } = win;
    let (ex0, _) = chart.backend_coord(&(cx - hx, cy));
    let (ex1, _) = chart.backend_coord(&(cx + hx, cy));
    let px_per_m = (ex1 - ex0) as f64 / (2.0 * hx);
    let list = unique_edges(&mesh.triangles);
    let mean_len = if list.is_empty() {
        0.0
    } else {
        list.iter()
            .map(|&(p, q)| (pts[p].0 - pts[q].0).hypot(pts[p].1 - pts[q].1))
            .sum::<f64>()
            / list.len() as f64
    };
    if edges.unwrap_or(mean_len * px_per_m >= 7.0) {
        let style = BLACK.mix(0.35).stroke_width(1);
        chart
            .draw_series(
                list.iter()
                    .map(|&(p, q)| PathElement::new(vec![pts[p], pts[q]], style)),
            )
            .map_err(de)?;
    }
    Ok(())
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
pub(super) fn subdivide(k: usize) -> Vec<([f64; 3], [[f64; 3]; 3])> {
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
pub(super) fn fill_triangle(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extents_a_double_cannot_draw_are_refused() {
        assert!(check_extent([0.0, -1.0], [1000.0, 2.0], 1.0).is_ok());
        // A collapsed axis is drawn (as before).
        assert!(check_extent([5.0, 5.0], [5.0, 6.0], 1.0).is_ok());
        let e = check_extent([-1e308, 0.0], [1e308, 1.0], 1.0)
            .unwrap_err()
            .0;
        assert!(
            e.contains("x coordinates") && e.contains("too large"),
            "{e}"
        );
        let e = check_extent([0.0, -1e307], [1.0, 1e307], 1.0)
            .unwrap_err()
            .0;
        assert!(e.contains("y coordinates") && e.contains("-1e307"), "{e}");
    }

    #[test]
    fn subdivision_covers_the_triangle() {
        for k in 1..5 {
            let s = subdivide(k);
            assert_eq!(s.len(), k * k);
        }
    }
}
