//! Mortar rows with dual multipliers on triangle surfaces (docs/methods.md
//! §11.6): segment-based integration on the clipped polygons of each slave
//! triangle and the master triangles projected onto its plane, the 2D rows
//! of `fem/mortar.rs` (§7.1) on surfaces.

use super::super::element::{Point3, Vector3};
use super::super::solid::Facet;
use super::super::FemError;
use super::search::TriangleTree;
use super::{cross, dot, tangent_frame, unit, Row3};
use crate::fem::contact::RowKind;
use crate::problem::NonMatchingPair;
use std::collections::BTreeMap;
use std::path::Path;

/// An initial penetration at a Gauss point deeper than this fraction of
/// the slave triangle's longest edge is refused (2D: the same).
const TOL_PEN: f64 = 1e-6;

/// A clip polygon smaller than this fraction of its slave triangle carries
/// no weight (round-off of the clipping where triangles share an edge).
const TINY: f64 = 1e-12;

/// The 7-point rule on a triangle, exact to degree 5 (Strang & Fix):
/// barycentric points and weights summing to 1.
const GAUSS7: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.059_715_871_789_770;
    const B1: f64 = 0.470_142_064_105_115;
    const W1: f64 = 0.132_394_152_788_506;
    const A2: f64 = 0.797_426_985_353_087;
    const B2: f64 = 0.101_286_507_323_456;
    const W2: f64 = 0.125_939_180_544_827;
    const C: f64 = 1.0 / 3.0;
    [
        ([C, C, C], 0.225),
        ([A1, B1, B1], W1),
        ([B1, A1, B1], W1),
        ([B1, B1, A1], W1),
        ([A2, B2, B2], W2),
        ([B2, A2, B2], W2),
        ([B2, B2, A2], W2),
    ]
};

type P2 = [f64; 2];

fn cross2(o: P2, a: P2, b: P2) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Barycentric coordinates of q in the plane triangle t.
fn bary(t: &[P2; 3], q: P2) -> [f64; 3] {
    let a = cross2(t[0], t[1], t[2]);
    [
        cross2(q, t[1], t[2]) / a,
        cross2(t[0], q, t[2]) / a,
        cross2(t[0], t[1], q) / a,
    ]
}

/// Sutherland–Hodgman: the polygon `subject` clipped by the convex,
/// counter-clockwise triangle `clip`.
fn clip_polygon(subject: &[P2], clip: &[P2; 3]) -> Vec<P2> {
    let mut out: Vec<P2> = subject.to_vec();
    for i in 0..3 {
        let (a, b) = (clip[i], clip[(i + 1) % 3]);
        let input = std::mem::take(&mut out);
        let Some(&last) = input.last() else {
            break;
        };
        let inside = |p: P2| cross2(a, b, p) >= 0.0;
        let cut = |p: P2, q: P2| {
            let (dp, dq) = (cross2(a, b, p), cross2(a, b, q));
            let t = dp / (dp - dq);
            [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
        };
        let mut s = last;
        for &e in &input {
            if inside(e) {
                if !inside(s) {
                    out.push(cut(s, e));
                }
                out.push(e);
            } else if inside(s) {
                out.push(cut(s, e));
            }
            s = e;
        }
    }
    out
}

/// A Gauss point of a slave triangle's projecting part: its weight (area),
/// the slave shape functions, the master points with theirs, the gap.
struct Gp {
    w: f64,
    ns: [f64; 3],
    masters: [(usize, f64); 3],
    gap: f64,
}

/// Mortar rows of the pair `c` (docs/methods.md §11.6): per slave node j
/// with D_jj > 0, −n_j·(Σ_m (M_jm / D_jj) u_m − u_j) ≤ g̃_j / D_jj with n_j
/// the slave's averaged normal — a [`Row3`] whose normal is −n_j.
#[allow(clippy::too_many_arguments)]
pub(in crate::fem) fn mortar_rows(
    points: &[Point3],
    slave: &[Facet],
    master: &[Facet],
    c: &NonMatchingPair,
    id: u32,
    what: &str,
    node_tag: impl Fn(usize) -> u64,
    path: &Path,
) -> Result<Vec<Row3>, FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let (sname, mname) = (c.slave.as_str(), c.master.as_str());
    // The slave nodes' averaged normals (area-weighted).
    let mut nsum: BTreeMap<usize, Vector3> = BTreeMap::new();
    for f in slave {
        for &p in &f.points {
            let e = nsum.entry(p).or_insert([0.0; 3]);
            for k in 0..3 {
                e[k] += 3.0 * f.weight * f.normal[k];
            }
        }
    }
    let tris: Vec<[Point3; 3]> = master.iter().map(|f| f.points.map(|p| points[p])).collect();
    let normals: Vec<Vector3> = master.iter().map(|f| f.normal).collect();
    let tree = TriangleTree::build(&tris, &normals);
    // The facing check of node-to-surface rows: the far face of a body
    // named as slave is refused as such, not as out of reach.
    super::nts::project_slaves(
        points, slave, master, &tree, what, sname, mname, &node_tag, path,
    )?;
    // Reach: how far along the normal a master triangle may lie.
    let reach = c.max_gap.unwrap_or(f64::INFINITY);
    // Without max_gap (no limit, docs/problem-format.md §2), a master may
    // lie anywhere ahead of a slave triangle: its search box is the slave's
    // swept along its normal across the two surfaces' extent.
    let extent = {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let slave_pts = slave.iter().flat_map(|f| f.points.map(|p| points[p]));
        for v in tris.iter().flatten().copied().chain(slave_pts) {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    };
    // Per slave point: D_jj, g̃_j and M_jm.
    let mut dj: BTreeMap<usize, f64> = BTreeMap::new();
    let mut gj: BTreeMap<usize, f64> = BTreeMap::new();
    let mut mj: BTreeMap<usize, BTreeMap<usize, f64>> = BTreeMap::new();
    let (mut facing_away, mut facing) = (0usize, 0usize);
    for f in slave {
        let x = f.points.map(|p| points[p]);
        let n = f.normal;
        let e1 = unit([0, 1, 2].map(|k| x[1][k] - x[0][k]));
        let e2 = cross(n, e1);
        let to2 = |y: Point3| {
            let d = [0, 1, 2].map(|k| y[k] - x[0][k]);
            [dot(d, e1), dot(d, e2)]
        };
        let s2 = x.map(to2);
        // (e1, e2, n) is right-handed, so the slave triangle is
        // counter-clockwise in it when its normal is n.
        let ccw = cross2(s2[0], s2[1], s2[2]) > 0.0;
        let clip = if ccw { s2 } else { [s2[0], s2[2], s2[1]] };
        let area = 0.5 * cross2(s2[0], s2[1], s2[2]).abs();
        let size = (0..3)
            .map(|i| {
                let d = [0, 1, 2].map(|k| x[(i + 1) % 3][k] - x[i][k]);
                dot(d, d).sqrt()
            })
            .fold(0.0, f64::max);
        // Candidates: masters whose box meets the slave's, widened by the
        // reach along every axis; without one, widened by the triangle's
        // size and swept along n across the surfaces' extent.
        let (pad, sweep) = if reach.is_finite() {
            (reach, 0.0)
        } else {
            (size, extent)
        };
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &x {
            for k in 0..3 {
                let far = v[k] + sweep * n[k];
                lo[k] = lo[k].min(v[k].min(far) - pad);
                hi[k] = hi[k].max(v[k].max(far) + pad);
            }
        }
        let mut gps: Vec<Gp> = vec![];
        for mi in tree.overlapping(lo, hi) {
            let mf = &master[mi];
            if dot(mf.normal, n) >= 0.0 {
                facing_away += 1;
                continue;
            }
            facing += 1;
            let y = tris[mi];
            let m2 = y.map(to2);
            let poly = clip_polygon(&m2, &clip);
            if poly.len() < 3 {
                continue;
            }
            let cen = poly.iter().fold([0.0, 0.0], |s, p| {
                [
                    s[0] + p[0] / poly.len() as f64,
                    s[1] + p[1] / poly.len() as f64,
                ]
            });
            let parea: f64 = (0..poly.len())
                .map(|i| 0.5 * cross2(cen, poly[i], poly[(i + 1) % poly.len()]))
                .sum();
            if parea.abs() <= TINY * area {
                continue;
            }
            for i in 0..poly.len() {
                let t = [cen, poly[i], poly[(i + 1) % poly.len()]];
                let ta = 0.5 * cross2(t[0], t[1], t[2]).abs();
                for (b, w) in GAUSS7 {
                    let q = [0, 1].map(|k| b[0] * t[0][k] + b[1] * t[1][k] + b[2] * t[2][k]);
                    let ns = bary(&s2, q);
                    let nm = bary(&m2, q);
                    let xs: Point3 = [0, 1, 2].map(|k| x[0][k] + q[0] * e1[k] + q[1] * e2[k]);
                    let ym: Point3 = [0, 1, 2].map(|k| (0..3).map(|a| nm[a] * y[a][k]).sum());
                    let gap = dot(n, [0, 1, 2].map(|k| ym[k] - xs[k]));
                    gps.push(Gp {
                        w: w * ta,
                        ns,
                        masters: [0, 1, 2].map(|a| (mf.points[a], nm[a])),
                        gap,
                    });
                }
            }
        }
        if gps.is_empty() {
            continue;
        }
        // Master triangles beyond the reach see no row.
        gps.retain(|g| g.gap <= reach);
        if let Some(g) = gps
            .iter()
            .find(|g| g.gap < -TOL_PEN * size && !c.interference)
        {
            let j = (0..3)
                .max_by(|&a, &b| g.ns[a].total_cmp(&g.ns[b]))
                .unwrap_or(0);
            return Err(err(format!(
                "{what}: slave surface \"{sname}\" penetrates master \"{mname}\" by {:.3e} near slave node {} (initial gap must be >= 0; set interference = true if the overlap is an intended fit)",
                -g.gap,
                node_tag(f.points[j])
            )));
        }
        // The dual basis on the projecting part P: A = D_e M_e⁻¹.
        let mut me = [[0.0; 3]; 3];
        let mut de = [0.0; 3];
        for g in &gps {
            for a in 0..3 {
                de[a] += g.w * g.ns[a];
                for b in 0..3 {
                    me[a][b] += g.w * g.ns[a] * g.ns[b];
                }
            }
        }
        let Some(minv) = inv3(&me) else {
            continue;
        };
        let amat: [[f64; 3]; 3] =
            std::array::from_fn(|a| std::array::from_fn(|b| de[a] * minv[a][b]));
        for g in &gps {
            let phi: [f64; 3] = std::array::from_fn(|a| (0..3).map(|b| amat[a][b] * g.ns[b]).sum());
            for a in 0..3 {
                let j = f.points[a];
                *gj.entry(j).or_insert(0.0) += g.w * phi[a] * g.gap;
                let row = mj.entry(j).or_default();
                for &(m, nm) in &g.masters {
                    *row.entry(m).or_insert(0.0) += g.w * phi[a] * nm;
                }
            }
        }
        for a in 0..3 {
            *dj.entry(f.points[a]).or_insert(0.0) += de[a];
        }
    }
    if facing == 0 && facing_away > 0 {
        return Err(err(format!(
            "{what}: slave surface \"{sname}\" faces away from master \"{mname}\": no master triangle near it faces it; name the faces of the two bodies that touch"
        )));
    }
    let mut rows = vec![];
    for (j, d) in dj {
        let scale = nsum.get(&j).map_or(0.0, |s| dot(*s, *s).sqrt());
        if d <= 0.0 || scale <= 0.0 {
            continue;
        }
        let nj = nsum[&j].map(|v| -v / scale);
        let masters: Vec<(usize, f64)> = mj
            .remove(&j)
            .unwrap_or_default()
            .into_iter()
            .map(|(m, w)| (m, w / d))
            .filter(|(_, w)| *w != 0.0)
            .collect();
        let g = gj.get(&j).copied().unwrap_or(0.0) / d;
        rows.push(Row3 {
            kind: RowKind::Mortar,
            slave: j,
            masters,
            normal: nj,
            tangents: tangent_frame(nj),
            gap0: g,
            area: d,
            interface: id,
        });
    }
    if rows.is_empty() {
        return Err(err(format!(
            "{what}: no slave triangle of \"{sname}\" sees a master triangle of \"{mname}\" within reach"
        )));
    }
    Ok(rows)
}

/// The inverse of a 3×3 matrix, None when it is singular to round-off
/// (a projecting part too thin to carry a dual basis).
fn inv3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det: f64 = (0..3).map(|j| m[0][j] * c(0, j)).sum();
    let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    if det.abs() <= 1e-12 * scale.powi(3) || !det.is_finite() {
        return None;
    }
    Some(std::array::from_fn(|i| {
        std::array::from_fn(|j| c(j, i) / det)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square clipped by a triangle inside it is the triangle; the
    /// 7-point rule integrates N_a N_b exactly (|T|(1 + δ_ab)/12).
    #[test]
    fn clipping_and_the_rule() {
        let sq = [[-1.0, -1.0], [2.0, -1.0], [2.0, 2.0], [-1.0, 2.0]];
        let t = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let p = clip_polygon(&sq, &t);
        let a: f64 = (0..p.len())
            .map(|i| 0.5 * cross2([0.0, 0.0], p[i], p[(i + 1) % p.len()]))
            .sum();
        assert!((a - 0.5).abs() < 1e-15, "{p:?}");
        let half = clip_polygon(&[[0.5, -1.0], [3.0, -1.0], [0.5, 3.0]], &t);
        let a: f64 = (0..half.len())
            .map(|i| 0.5 * cross2([0.0, 0.0], half[i], half[(i + 1) % half.len()]))
            .sum();
        assert!((a - 0.125).abs() < 1e-15, "{half:?}");
        for a in 0..3 {
            for b in 0..3 {
                let s: f64 = GAUSS7.iter().map(|(p, w)| w * p[a] * p[b]).sum();
                let want = if a == b { 2.0 } else { 1.0 } / 12.0;
                assert!((s - want).abs() < 1e-14);
            }
        }
    }
}
