//! The contact footprint of a 3D checkpoint: per interface, its slave
//! triangles laid in the interface's own plane (through the centroid,
//! normal to the rows' mean normal weighted by their pressure), filled by the contact pressure, the
//! boundary of the active set outlined; with friction the boundary of the
//! slip zone (white) and the tangential traction as arrows (docs/methods.md
//! §12.6).

use super::cut::{cross, norm, sub, Frame};
use super::panel::{Fill, Panel, P2};
use super::style::fmt_num;
use crate::output::{SolidCheckpoint, SolidStep};
use std::collections::HashMap;

/// What the footprint of one interface shows.
#[derive(Debug, Clone)]
pub struct FootprintSummary {
    /// The `[[contact]]` entry (0-based) and its name ("slave/master").
    pub interface: usize,
    pub name: String,
    pub rows: usize,
    pub active: usize,
    pub triangles: usize,
    /// The slave triangles' area, and the area they cover in the plane
    /// (equal for a flat surface) \[m²\].
    pub surface_area: f64,
    pub area: f64,
    /// The area where the active flag, linear on the triangles, is ≥ ½.
    pub active_area: f64,
    pub max_pressure: f64,
    /// The plane: its unit normal (the rows' mean, weighted by their
    /// pressure) and axes.
    pub normal: [f64; 3],
    pub axes: [String; 2],
    /// With friction: the rows in contact that stick and that slip, the
    /// arrows drawn and the largest tangential traction \[Pa\].
    pub stick: Option<usize>,
    pub slip: Option<usize>,
    pub arrows: usize,
    pub max_tangential: f64,
}

/// The panels of the interfaces with slave triangles and the summaries of
/// every interface with rows, in entry order.
pub(super) fn footprints(
    ck: &SolidCheckpoint,
    step: &SolidStep,
    names: &[String],
    length: &str,
) -> (Vec<Panel>, Vec<FootprintSummary>) {
    let c = &ck.contact;
    let mut ids: Vec<usize> = c.interface.iter().map(|&i| i as usize).collect();
    ids.sort_unstable();
    ids.dedup();
    let at = |r: usize| ck.points[c.slave[r]];
    let mut panels = Vec::new();
    let mut out = Vec::new();
    for k in ids {
        let rows: Vec<usize> = (0..c.slave.len())
            .filter(|&r| c.interface[r] as usize == k)
            .collect();
        let tris: Vec<[usize; 3]> = c
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&r| c.interface[r] as usize == k))
            .collect();
        // The plane of the contact zone: the rows' normals weighted by
        // their pressure (on a curved slave surface the mean of every
        // row's normal tilts towards the rows far from the contact: the
        // quarter cylinder of verification/cylinder3d drew its strip in a
        // plane 25° off the block), or all rows' mean when none carries
        // any.
        let weight = |r: usize| {
            let p = step.contact_pressure[r];
            if p.is_finite() && p > 0.0 {
                p
            } else {
                0.0
            }
        };
        let loaded = rows.iter().any(|&r| weight(r) > 0.0);
        let mut n = [0.0; 3];
        for &r in &rows {
            let w = if loaded { weight(r) } else { 1.0 };
            for d in 0..3 {
                n[d] += w * c.normal[r][d];
            }
        }
        let l = norm(n);
        let n = if l > 0.0 {
            n.map(|v| v / l)
        } else {
            [0.0, 0.0, 1.0]
        };
        let frame = Frame::of_normal(n);
        // Local point numbers of the rows the triangles use.
        let mut local: HashMap<usize, usize> = HashMap::new();
        let mut used: Vec<usize> = Vec::new();
        let mut ltris = Vec::with_capacity(tris.len());
        for t in &tris {
            ltris.push(t.map(|r| {
                *local.entry(r).or_insert_with(|| {
                    used.push(r);
                    used.len() - 1
                })
            }));
        }
        let pts: Vec<P2> = used.iter().map(|&r| frame.project(at(r))).collect();
        let p: Vec<f64> = used.iter().map(|&r| step.contact_pressure[r]).collect();
        let act: Vec<bool> = used.iter().map(|&r| step.active[r] != 0).collect();
        let mut surface_area = 0.0;
        let mut area = 0.0;
        for (t, lt) in tris.iter().zip(&ltris) {
            surface_area += 0.5 * norm(cross(sub(at(t[1]), at(t[0])), sub(at(t[2]), at(t[0]))));
            area += area2(pts[lt[0]], pts[lt[1]], pts[lt[2]]);
        }
        let (outline, active_area) = active_boundary(&pts, &ltris, &act);
        let edges = unique_edges(&ltris)
            .into_iter()
            .map(|(a, b, _)| [pts[a], pts[b]])
            .collect();
        let name = names
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("interface {k}"));
        let max_pressure = rows
            .iter()
            .map(|&r| step.contact_pressure[r])
            .fold(f64::NEG_INFINITY, f64::max);
        let nactive = rows.iter().filter(|&&r| step.active[r] != 0).count();
        let fr = friction(step, &rows, &used, &pts, &ltris, &frame);
        let stick_slip = fr.counts.map_or(String::new(), |(a, b)| {
            // The white line is the edge between the zones: with one zone
            // only it would be the contact zone's edge, so it is not named.
            if a > 0 && b > 0 {
                format!("; {a} stick, {b} slip (white line: the slip zone's edge)")
            } else {
                format!("; {a} stick, {b} slip")
            }
        });
        let title = format!(
            "{name}: {nactive} of {} rows active{stick_slip}; plane normal ({}, {}, {})",
            rows.len(),
            fmt_num(round3(n[0])),
            fmt_num(round3(n[1])),
            fmt_num(round3(n[2]))
        );
        // Rows without a slave triangle (a surface's isolated nodes) are
        // counted, not drawn.
        if !ltris.is_empty() {
            panels.push(Panel {
                title,
                labels: frame.labels.clone().map(|s| format!("{s} [{length}]")),
                pts,
                tris: ltris,
                fill: Fill::Nodal(p),
                edges,
                outline,
                zones: fr.zones,
                arrows: fr.arrows.clone(),
            });
        }
        out.push(FootprintSummary {
            interface: k,
            name,
            rows: rows.len(),
            active: nactive,
            triangles: tris.len(),
            surface_area,
            area,
            active_area,
            max_pressure,
            normal: n,
            axes: frame.labels,
            stick: fr.counts.map(|c| c.0),
            slip: fr.counts.map(|c| c.1),
            arrows: fr.arrows.len(),
            max_tangential: fr.max,
        });
    }
    (panels, out)
}

/// At most this many traction arrows across a footprint's width.
const ARROWS_ACROSS: f64 = 16.0;

/// What friction adds to a footprint.
struct FootprintFriction {
    /// The slip zone's boundary in the plane.
    zones: Vec<[P2; 2]>,
    /// Tangential traction arrows (tail at the row, length ∝ traction).
    arrows: Vec<[P2; 2]>,
    /// Rows in contact that stick, that slip (None without friction).
    counts: Option<(usize, usize)>,
    max: f64,
}

/// The slip zone (the ½ contour of the slip flag, linear on the
/// triangles, as the active set's) and the traction arrows of the rows
/// `rows` (`used`: the drawn rows, at `pts`), subsampled to one per cell of
/// a grid [`ARROWS_ACROSS`] cells wide, the longest arrow one cell long.
fn friction(
    step: &SolidStep,
    rows: &[usize],
    used: &[usize],
    pts: &[P2],
    ltris: &[[usize; 3]],
    frame: &Frame,
) -> FootprintFriction {
    let mut f = FootprintFriction {
        zones: vec![],
        arrows: vec![],
        counts: None,
        max: 0.0,
    };
    if step.friction_state.is_empty() {
        return f;
    }
    let state = &step.friction_state;
    f.counts = Some((
        rows.iter().filter(|&&r| state[r] == 1).count(),
        rows.iter().filter(|&&r| state[r] == 2).count(),
    ));
    let slips: Vec<bool> = used.iter().map(|&r| state[r] == 2).collect();
    // The ½ contour only: the surface's own edges keep the active set's red.
    // Drawn only where both zones exist: with no stick row the contour
    // would trace the open zone's edge and read as a stick/slip border.
    if f.counts.is_some_and(|(a, b)| a > 0 && b > 0) {
        f.zones = active_boundary(pts, ltris, &slips).0;
        f.zones.truncate(contour_len(ltris, &slips));
    }
    let tau = &step.tangential_traction;
    let inplane: Vec<P2> = used
        .iter()
        .map(|&r| (dot3(tau[r], frame.e1), dot3(tau[r], frame.e2)))
        .collect();
    f.max = inplane.iter().map(|v| v.0.hypot(v.1)).fold(0.0, f64::max);
    if f.max <= 0.0 || pts.is_empty() {
        return f;
    }
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for p in pts {
        lo = (lo.0.min(p.0), lo.1.min(p.1));
        hi = (hi.0.max(p.0), hi.1.max(p.1));
    }
    let cell = ((hi.0 - lo.0).max(hi.1 - lo.1) / ARROWS_ACROSS).max(1e-300);
    let scale = cell / f.max;
    let mut taken = std::collections::HashSet::new();
    for (i, p) in pts.iter().enumerate() {
        let key = (((p.0 - lo.0) / cell) as i64, ((p.1 - lo.1) / cell) as i64);
        let v = inplane[i];
        if state[used[i]] == 0 || v.0.hypot(v.1) <= 1e-3 * f.max || !taken.insert(key) {
            continue;
        }
        f.arrows.push([*p, (p.0 + scale * v.0, p.1 + scale * v.1)]);
    }
    f
}

/// How many of [`active_boundary`]'s segments are the ½ contour inside
/// the triangles (they come first): one per triangle with mixed flags.
fn contour_len(tris: &[[usize; 3]], flag: &[bool]) -> usize {
    tris.iter()
        .filter(|t| {
            let on = t.iter().filter(|&&i| flag[i]).count();
            on == 1 || on == 2
        })
        .count()
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn round3(v: f64) -> f64 {
    let r = (v * 1000.0).round() / 1000.0;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

fn area2(a: P2, b: P2, c: P2) -> f64 {
    0.5 * ((b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1)).abs()
}

/// Edges of the triangles, each once, with how many triangles share it.
fn unique_edges(tris: &[[usize; 3]]) -> Vec<(usize, usize, usize)> {
    let mut count: HashMap<(usize, usize), usize> = HashMap::new();
    let mut order = Vec::new();
    for t in tris {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let e = (a.min(b), a.max(b));
            let c = count.entry(e).or_insert(0);
            if *c == 0 {
                order.push(e);
            }
            *c += 1;
        }
    }
    order.into_iter().map(|e| (e.0, e.1, count[&e])).collect()
}

/// The boundary of the region where the active flag, linear on each
/// triangle, is ≥ ½: the ½ contour inside the triangles, and the parts of
/// the surface's own boundary in that region (a fully active surface is
/// outlined whole). Returns the segments and the region's area.
fn active_boundary(pts: &[P2], tris: &[[usize; 3]], act: &[bool]) -> (Vec<[P2; 2]>, f64) {
    let mid = |a: usize, b: usize| (0.5 * (pts[a].0 + pts[b].0), 0.5 * (pts[a].1 + pts[b].1));
    let mut seg = Vec::new();
    let mut area = 0.0;
    for t in tris {
        let on = t.iter().filter(|&&i| act[i]).count();
        let whole = area2(pts[t[0]], pts[t[1]], pts[t[2]]);
        // The odd vertex out and the two others.
        let odd = (0..3).find(|&i| (on == 1) == act[t[i]]);
        match (on, odd) {
            (3, _) => area += whole,
            (1 | 2, Some(i)) => {
                let (a, b, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
                seg.push([mid(a, b), mid(a, c)]);
                // The corner triangle cut off at the midpoints holds ¼.
                area += if on == 1 { 0.25 } else { 0.75 } * whole;
            }
            _ => {}
        }
    }
    for (a, b, n) in unique_edges(tris) {
        if n != 1 {
            continue;
        }
        match (act[a], act[b]) {
            (true, true) => seg.push([pts[a], pts[b]]),
            (true, false) => seg.push([pts[a], mid(a, b)]),
            (false, true) => seg.push([mid(a, b), pts[b]]),
            _ => {}
        }
    }
    (seg, area)
}

/// The name of each `[[contact]]` entry of the problem text: `on`, or
/// "slave/master" (the JSON summary's keys); empty when unreadable.
pub(super) fn interface_names(problem: &str) -> Vec<String> {
    let table: toml::Table = toml::from_str(problem).unwrap_or_default();
    let Some(list) = table.get("contact").and_then(|c| c.as_array()) else {
        return vec![];
    };
    list.iter()
        .enumerate()
        .map(|(k, e)| {
            let s = |key: &str| e.get(key).and_then(|v| v.as_str());
            match (s("on"), s("slave"), s("master")) {
                (Some(on), _, _) => on.to_string(),
                (_, Some(a), Some(b)) => format!("{a}/{b}"),
                _ => format!("interface {k}"),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_active_boundary_of_a_square() {
        // Two triangles of the unit square, nodes 0 (0,0), 1 (1,0), 2 (1,1), 3 (0,1).
        let pts = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let (seg, a) = active_boundary(&pts, &tris, &[true; 4]);
        assert_eq!(seg.len(), 4, "the whole boundary");
        assert!((a - 1.0).abs() < 1e-15);
        let (seg, a) = active_boundary(&pts, &tris, &[false; 4]);
        assert!(seg.is_empty() && a == 0.0);
        // Node 0 alone: a quarter of each triangle, the contour across both.
        let (seg, a) = active_boundary(&pts, &tris, &[true, false, false, false]);
        assert!((a - 0.25).abs() < 1e-15);
        assert_eq!(seg.len(), 4, "two contour pieces and two half edges");
    }

    #[test]
    fn interfaces_are_named_as_in_the_summary() {
        let t = "[[contact]]\non = \"i\"\n[[contact]]\nslave = \"a\"\nmaster = \"b\"\n";
        assert_eq!(interface_names(t), ["i", "a/b"]);
        assert!(interface_names("not toml [").is_empty());
    }
}
