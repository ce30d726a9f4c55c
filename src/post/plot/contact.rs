//! The contact figure: the contact pressure along each interface against
//! arc length, one panel per interface, one curve per step drawn.

use super::style::{category_color, de, fmt_num, tick, titled, viridis};
use super::{err, PlotError, Units};
use crate::output::{ContactGeometry, StepOutput};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::HashMap;

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
    let walk = |path: &mut Vec<usize>, used: &mut Vec<bool>| {
        while let Some(&end) = path.last() {
            let Some(k) = adj[&end].iter().copied().find(|&k| !used[k]) else {
                break;
            };
            used[k] = true;
            let [a, b] = segs[k];
            path.push(if a == end { b } else { a });
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
pub(super) fn contact_grid(n: usize) -> (usize, usize) {
    let cols = match n {
        0..=3 => 1,
        4..=8 => 2,
        _ => 3,
    };
    (n.div_ceil(cols).max(1), cols)
}

/// One interface of the contact figure: its name, the point its arc
/// length starts from, and its pieces of (arc length, row).
type Series = (String, [f64; 2], Vec<Vec<(f64, usize)>>);

/// The friction of one drawn step, per contact row: the tangential traction
/// (or its change since the reference step) and the state 0 open, 1 stick,
/// 2 slip (the checkpoint's `tangential_traction` and `state`).
#[derive(Debug, Clone, Default)]
pub struct Tangential {
    pub traction: Vec<f64>,
    pub state: Vec<u8>,
}

/// The interfaces that have contact segments, in index order.
fn contact_series(c: &ContactGeometry) -> Result<Vec<Series>, PlotError> {
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
    Ok(series)
}

/// The contact pressure against arc length, one panel per interface (each
/// with its own pressure axis unless `range` fixes it), one curve per step
/// drawn (coloured along viridis with a legend when there are several).
/// Each panel says where its arc length starts: the first contact point of
/// the interface's first chain (at the first side: the lower body, or the
/// slave). `field`: the dataset drawn, for messages. With friction data
/// (`tangential`, one per step, all present) each interface gets a second
/// panel under its pressure: the tangential traction, stick and slip rows
/// marked; without, the figure is the frictionless one. Returns the
/// pressure range and, with friction, the tangential traction's.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(super) fn draw_contact<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    c: &ContactGeometry,
    steps: &[(usize, StepOutput)],
    tangential: Option<&[Tangential]>,
    title: &str,
    fs: f64,
    range: Option<(f64, f64)>,
    field: &str,
    units: &Units,
) -> Result<(Option<(f64, f64)>, Option<(f64, f64)>), PlotError> {
    let series = contact_series(c)?;
    // Every axis is checked before anything is drawn.
    let axes = series
        .iter()
        .map(|s| panel_axes(s, steps, range, field))
        .collect::<Result<Vec<_>, _>>()?;
    let tangential = tangential.filter(|t| t.len() == steps.len());
    let t_axes = match tangential {
        Some(tg) => {
            let vals: Vec<(usize, &[f64])> = steps
                .iter()
                .zip(tg)
                .map(|((no, _), t)| (*no, &t.traction[..]))
                .collect();
            let what = if field.ends_with("_change") {
                "tangential_traction_change"
            } else {
                "tangential_traction"
            };
            Some(
                series
                    .iter()
                    .map(|s| value_axes(s, &vals, None, what, "tangential traction"))
                    .collect::<Result<Vec<_>, _>>()?,
            )
        }
        None => None,
    };
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
        body = step_legend(body, steps, fs, &|j| color_of(j, 0))?;
    }
    let panels = body.split_evenly(contact_grid(series.len()));
    let mut total: Option<(f64, f64)> = None;
    let mut t_total: Option<(f64, f64)> = None;
    for (k, ((s, ax), panel)) in series.iter().zip(&axes).zip(&panels).enumerate() {
        let (plo, phi) = ax.data;
        total = Some(match total {
            Some((a, b)) => (a.min(plo), b.max(phi)),
            None => (plo, phi),
        });
        match (tangential, &t_axes) {
            (Some(tg), Some(tax)) => {
                let halves = panel.split_evenly((2, 1));
                draw_panel(&halves[0], s, ax, steps, fs, many, units, &|j| {
                    color_of(j, k)
                })?;
                let (tlo, thi) = tax[k].data;
                t_total = Some(match t_total {
                    Some((a, b)) => (a.min(tlo), b.max(thi)),
                    None => (tlo, thi),
                });
                let change = field.ends_with("_change");
                draw_tangential(&halves[1], s, &tax[k], tg, fs, many, change, units, &|j| {
                    color_of(j, k)
                })?;
            }
            _ => draw_panel(panel, s, ax, steps, fs, many, units, &|j| color_of(j, k))?,
        }
    }
    Ok((total, t_total))
}

/// The axes of one panel: arc length 0..smax and the pressure range, and
/// the pressures' own range (0 included).
struct PanelAxes {
    xr: std::ops::Range<f64>,
    yr: std::ops::Range<f64>,
    data: (f64, f64),
}

/// The axes of panel `s`: the pressure axis from `range`, or the data's
/// range padded by 6 % (0 included). An axis whose span f64 cannot hold
/// (with the factor 16 the plotting library's tick search needs) is
/// refused, naming the field and the step: an infinite axis never ended
/// that search (issue 34).
fn panel_axes(
    s: &Series,
    steps: &[(usize, StepOutput)],
    range: Option<(f64, f64)>,
    field: &str,
) -> Result<PanelAxes, PlotError> {
    let vals: Vec<(usize, &[f64])> = steps
        .iter()
        .map(|(no, st)| (*no, &st.contact_pressure[..]))
        .collect();
    value_axes(s, &vals, range, field, "pressure")
}

/// [`panel_axes`] for any per-row values of each step (step number,
/// values); `axis` names the value axis in the message.
fn value_axes(
    s: &Series,
    steps: &[(usize, &[f64])],
    range: Option<(f64, f64)>,
    field: &str,
    axis: &str,
) -> Result<PanelAxes, PlotError> {
    let (name, _, pieces) = s;
    let pts = || {
        steps.iter().flat_map(|(_, st)| {
            pieces
                .iter()
                .flatten()
                .map(|&(s, r)| (s, st[r]))
                .filter(|(s, p)| s.is_finite() && p.is_finite())
        })
    };
    let smax = pts().map(|q| q.0).fold(0.0, f64::max);
    let (plo, phi) = pts().fold((0.0f64, 0.0f64), |(a, b), q| (a.min(q.1), b.max(q.1)));
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
    if !((yr.end - yr.start) * 16.0).is_finite() {
        // The step holding the largest magnitude, for the message.
        let (no, v) = steps
            .iter()
            .flat_map(|(no, st)| pieces.iter().flatten().map(move |&(_, r)| (*no, st[r])))
            .filter(|(_, p)| p.is_finite())
            .fold(
                (0, 0.0f64),
                |m, q| if q.1.abs() > m.1.abs() { q } else { m },
            );
        return Err(err(format!(
            "{field} of step {no} on {name} reaches {}: the {axis} axis would span more than a double holds{}",
            fmt_num(v),
            if axis == "pressure" { " (give --range MIN,MAX)" } else { "" }
        )));
    }
    let xr = 0.0..if smax > 0.0 { smax } else { 1.0 };
    if !(xr.end * 16.0).is_finite() {
        return Err(err(format!(
            "/mesh/contact_points of {name}: the arc length reaches {}, more than a double holds with the figure's margins",
            fmt_num(xr.end)
        )));
    }
    Ok(PanelAxes {
        xr,
        yr,
        data: (plo, phi),
    })
}

/// One legend for every panel, in a strip under the title (the steps have
/// the same colours in each), wrapped onto more lines when the labels do
/// not fit on one. Returns the area below it.
fn step_legend<DB: DrawingBackend>(
    body: DrawingArea<DB, Shift>,
    steps: &[(usize, StepOutput)],
    fs: f64,
    color_of: &dyn Fn(usize) -> RGBColor,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
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
                color_of(j).stroke_width(4),
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
    Ok(rest)
}

/// One interface's panel: its caption, axes and one curve per step.
#[allow(clippy::too_many_arguments)]
fn draw_panel<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    (name, start, pieces): &Series,
    ax: &PanelAxes,
    steps: &[(usize, StepOutput)],
    fs: f64,
    many: bool,
    units: &Units,
    color_of: &dyn Fn(usize) -> RGBColor,
) -> Result<(), PlotError> {
    let (xr, yr) = (ax.xr.clone(), ax.yr.clone());
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
        .x_desc(format!("arc length s [{}]", units.length))
        .y_desc(format!("contact pressure [{}]", units.stress))
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
        let color = color_of(j);
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
    Ok(())
}

/// One interface's tangential panel under its pressure panel: the
/// tangential traction against the same arc length, one curve per step,
/// each row marked by its state (filled dot: stick, cross: slip, ring:
/// open), and the arc-length stretches where the last step slips shaded.
#[allow(clippy::too_many_arguments)]
fn draw_tangential<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    (name, _, pieces): &Series,
    ax: &PanelAxes,
    tg: &[Tangential],
    fs: f64,
    many: bool,
    change: bool,
    units: &Units,
    color_of: &dyn Fn(usize) -> RGBColor,
) -> Result<(), PlotError> {
    let (xr, yr) = (ax.xr.clone(), ax.yr.clone());
    let (xspan, yspan) = (xr.end - xr.start, yr.end - yr.start);
    let last = &tg[tg.len() - 1];
    let count = |v: u8| {
        pieces
            .iter()
            .flatten()
            .filter(|&&(_, r)| last.state[r] == v)
            .count()
    };
    let caption = format!(
        "{name}: {} rows stick (dots), {} slip (crosses, shaded){}",
        count(1),
        count(2),
        if many { " at the last step" } else { "" }
    );
    let mut chart = ChartBuilder::on(panel)
        .margin((fs * 0.8) as u32)
        .caption(caption, ("sans-serif", fs * 0.95))
        .x_label_area_size((fs * 3.0) as u32)
        .y_label_area_size((fs * 6.0) as u32)
        .build_cartesian_2d(xr.clone(), yr.clone())
        .map_err(de)?;
    // The slip stretches of the last step: each slipping row's share of
    // the arc, half-way to its neighbours.
    let band = RGBColor(214, 39, 40).mix(0.12);
    for piece in pieces {
        for (i, &(s, r)) in piece.iter().enumerate() {
            if last.state[r] != 2 {
                continue;
            }
            let lo = if i > 0 { 0.5 * (piece[i - 1].0 + s) } else { s };
            let hi = if i + 1 < piece.len() {
                0.5 * (piece[i + 1].0 + s)
            } else {
                s
            };
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(lo, yr.start), (hi, yr.end)],
                    band.filled(),
                )))
                .map_err(de)?;
        }
    }
    let (_, ph) = panel.dim_in_pixel();
    let y_ticks = ((ph as f64 - fs * 7.0) / (fs * 2.2)).clamp(2.0, 10.0) as usize;
    chart
        .configure_mesh()
        .y_labels(y_ticks)
        .x_desc(format!("arc length s [{}]", units.length))
        .y_desc(if change {
            format!("tangential traction change [{}]", units.stress)
        } else {
            format!("tangential traction [{}]", units.stress)
        })
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.12))
        .label_style(("sans-serif", fs * 0.9))
        .axis_desc_style(("sans-serif", fs))
        .x_label_formatter(&|v| tick(*v, xspan))
        .y_label_formatter(&|v| tick(*v, yspan))
        .draw()
        .map_err(de)?;
    let radius = (fs * if many { 0.16 } else { 0.22 }).max(2.0) as i32;
    for (j, t) in tg.iter().enumerate() {
        let color = color_of(j);
        for piece in pieces {
            let line: Vec<(f64, f64, u8)> = piece
                .iter()
                .map(|&(s, r)| (s, t.traction[r], t.state[r]))
                .collect();
            chart
                .draw_series(LineSeries::new(
                    line.iter().map(|&(s, v, _)| (s, v)),
                    color.stroke_width(2),
                ))
                .map_err(de)?;
            for &(s, v, st) in &line {
                let p = (s, v);
                match st {
                    1 => chart
                        .draw_series(std::iter::once(Circle::new(p, radius, color.filled())))
                        .map(|_| ()),
                    2 => chart
                        .draw_series(std::iter::once(Cross::new(
                            p,
                            radius + 2,
                            color.stroke_width(2),
                        )))
                        .map(|_| ()),
                    _ => chart
                        .draw_series(std::iter::once(Circle::new(
                            p,
                            radius,
                            color.stroke_width(1),
                        )))
                        .map(|_| ()),
                }
                .map_err(de)?;
            }
        }
    }
    Ok(())
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
