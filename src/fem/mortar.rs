//! Mortar rows of non-matching pairs (`discretization = "mortar"`,
//! docs/methods.md §7.1): segment-to-segment integration over the overlap
//! of each slave segment with the master segments it sees along the
//! averaged slave normal field, dual (biorthogonal) multipliers (Wohlmuth
//! 2000; Popp, Gee & Wall 2009 for the 2D integration; Popp, Seitz, Gee &
//! Wall 2013 for the dual basis built on the projecting part of a slave
//! segment only). D is diagonal, so each slave node j gives one row
//!
//!   n_j·(u_j − Σ_m (M_jm / D_jj) u_m) ≤ g̃_j / D_jj,
//!
//! the NTS row with the mortar weights (n_j the averaged slave normal). Its
//! multiplier is a nodal force like an NTS multiplier, and λ_j / D_jj is the
//! mortar multiplier, a traction (the row's `trib` is D_jj).

use super::contact::{ContactRow, RowKind};
use super::element::{Point, Vector};
use super::pairs::{BoundarySeg, Pair};
use super::topology::Topology;
use super::FemError;
use crate::mesh::Mesh;
use crate::problem::NonMatchingPair;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Gauss–Legendre points and weights on [0, 1] (5 points: exact to degree
/// 9, so D, M and g̃ are exact on straight interfaces, where the integrands
/// are quadratic).
const GAUSS: [(f64, f64); 5] = [
    (0.5 - 0.5 * GL_X2, 0.5 * GL_W2),
    (0.5 - 0.5 * GL_X1, 0.5 * GL_W1),
    (0.5, 0.5 * 128.0 / 225.0),
    (0.5 + 0.5 * GL_X1, 0.5 * GL_W1),
    (0.5 + 0.5 * GL_X2, 0.5 * GL_W2),
];
/// The 5-point Gauss–Legendre rule on [−1, 1]: nodes ±x₁, ±x₂ (and 0).
const GL_X1: f64 = 0.538_469_310_105_683_1;
const GL_X2: f64 = 0.906_179_845_938_664;
const GL_W1: f64 = 0.478_628_670_499_366_47;
const GL_W2: f64 = 0.236_926_885_056_189_08;

/// Overlaps shorter than this fraction of the slave segment are round-off.
const MIN_OVERLAP: f64 = 1e-12;

fn cross(a: Vector, b: Vector) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn sub(a: Vector, b: Vector) -> Vector {
    [a[0] - b[0], a[1] - b[1]]
}

fn lerp(a: Point, b: Point, s: f64) -> Point {
    [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])]
}

fn unit(v: Vector) -> Vector {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    [v[0] / l, v[1] / l]
}

/// A slave segment: end points, their averaged unit normals.
#[derive(Clone, Copy)]
struct SlaveGeom {
    x: [Point; 2],
    n: [Vector; 2],
}

impl SlaveGeom {
    fn point(&self, s: f64) -> Point {
        lerp(self.x[0], self.x[1], s)
    }

    /// The interpolated normal field n(s) = N₁ n₁ + N₂ n₂ (not unit).
    fn normal(&self, s: f64) -> Vector {
        lerp(self.n[0], self.n[1], s)
    }

    /// The slave coordinate s whose normal ray passes through `y`:
    /// (x(s) − y) × n(s) = 0, a quadratic in s; the root nearest to the
    /// segment (Popp et al. 2009, the projection of master nodes).
    fn project(&self, y: Point) -> Option<f64> {
        let (e, dn) = (sub(self.x[1], self.x[0]), sub(self.n[1], self.n[0]));
        let d = sub(self.x[0], y);
        let c0 = cross(d, self.n[0]);
        let c1 = cross(d, dn) + cross(e, self.n[0]);
        let c2 = cross(e, dn);
        let near = |r: f64| (r - 0.5).abs();
        if c2.abs() <= 1e-14 * c1.abs() {
            return (c1 != 0.0).then(|| -c0 / c1);
        }
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc < 0.0 {
            return None;
        }
        let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
        let r1 = q / c2;
        let r2 = if q != 0.0 { c0 / q } else { r1 };
        Some(if near(r1) <= near(r2) { r1 } else { r2 })
    }

    /// Where the normal ray at s meets the line of master segment (y₁, y₂):
    /// (ξ, gap along the unit normal; > 0 open).
    fn ray(&self, s: f64, y: [Point; 2]) -> Option<(f64, f64)> {
        let x = self.point(s);
        let n = self.normal(s);
        let em = sub(y[1], y[0]);
        let den = cross(em, n);
        if den == 0.0 {
            return None;
        }
        let xi = cross(sub(x, y[0]), n) / den;
        let p = lerp(y[0], y[1], xi);
        let nu = unit(n);
        Some((xi, nu[0] * (p[0] - x[0]) + nu[1] * (p[1] - x[1])))
    }
}

/// A piece of a slave segment [s0, s1] integrated against one master segment.
struct Piece {
    s0: f64,
    s1: f64,
    master: usize,
}

/// `[a, b]` minus the intervals of `covered`.
fn uncovered(a: f64, b: f64, covered: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut parts = vec![(a, b)];
    for &(c, d) in covered {
        let mut next = vec![];
        for (p, q) in parts {
            if d <= p || c >= q {
                next.push((p, q));
                continue;
            }
            if c > p {
                next.push((p, c));
            }
            if d < q {
                next.push((d, q));
            }
        }
        parts = next;
    }
    parts
}

impl Topology {
    /// Mortar rows of one non-matching pair (docs/methods.md §7.1), one per
    /// slave node whose segments overlap the master, in (body, node tag)
    /// order, and the slave segments between the rows.
    pub(super) fn mortar_rows(
        &mut self,
        mesh: &Mesh,
        path: &Path,
        c: &NonMatchingPair,
        pair: &Pair,
    ) -> Result<(), FemError> {
        let (id, what) = (pair.id, &pair.what);
        let (msegs, ssegs) = (&pair.masters[..], &pair.slaves[..]);
        let err = |msg: String| FemError::new(path, msg);
        let (sname, mname) = (c.slave.as_str(), c.master.as_str());
        let normal = slave_normals(ssegs).map_err(|v| {
            err(format!(
                "{what}: the normals of slave curve \"{sname}\" cancel at node {} (a cusp); split the curve there",
                mesh.node_tags[v]
            ))
        })?;
        // D_jj, M_jm (by master point) and g̃_j, per slave node.
        let mut dj: HashMap<(usize, u32), f64> = HashMap::new();
        let mut mj: HashMap<(usize, u32), BTreeMap<usize, f64>> = HashMap::new();
        let mut gj: HashMap<(usize, u32), f64> = HashMap::new();
        let kind = self.kind;
        let mut body_sizes: Option<Vec<f64>> = None;
        for &(a, b, sb, ns) in ssegs {
            let geom = SlaveGeom {
                x: [mesh.nodes[a], mesh.nodes[b]],
                n: [normal[&(a, sb)], normal[&(b, sb)]],
            };
            let len = {
                let e = sub(geom.x[1], geom.x[0]);
                (e[0] * e[0] + e[1] * e[1]).sqrt()
            };
            let pieces = overlap_pieces(mesh, msegs, &geom, sb, ns);
            // Axisymmetric: every integral carries r (per radian; the dual
            // basis is then biorthogonal in the r-weighted product), so a
            // segment on the axis has no weight (docs/methods.md §10).
            let rw = |s: f64| kind.line_density(geom.point(s));
            if pieces.is_empty() {
                continue;
            }
            let Some((de, amat)) = dual_basis(&pieces, len, rw) else {
                continue;
            };
            let keys = [(a, sb), (b, sb)];
            for (i, key) in keys.iter().enumerate() {
                *dj.entry(*key).or_insert(0.0) += de[i];
            }
            for p in &pieces {
                let (ma, mb, mbody, _) = msegs[p.master];
                let y = [mesh.nodes[ma], mesh.nodes[mb]];
                let (pa, pb) = (
                    self.point(ma, mbody).unwrap_or(0),
                    self.point(mb, mbody).unwrap_or(0),
                );
                for &(t, w) in &GAUSS {
                    let s = p.s0 + t * (p.s1 - p.s0);
                    let wl = w * (p.s1 - p.s0) * len * rw(s);
                    let Some((xi, g)) = geom.ray(s, y) else {
                        continue;
                    };
                    if g < 0.0 && c.interference {
                        let sizes = body_sizes.get_or_insert_with(|| self.body_sizes());
                        let size = |b: u32| sizes.get(b as usize).copied().unwrap_or(0.0);
                        let x = geom.point(s);
                        let at = format!(
                            "({:.6e}, {:.6e}) of \"{sname}\" against \"{mname}\"",
                            x[0], x[1]
                        );
                        super::interference::check_overlap(
                            what,
                            &at,
                            -g,
                            len,
                            [size(sb), size(mbody)],
                        )
                        .map_err(err)?;
                    }
                    if g < -1e-6 * len && !c.interference {
                        let x = geom.point(s);
                        return Err(err(format!(
                            "{what}: slave curve \"{sname}\" penetrates master \"{mname}\" by {:.3e} at ({:.6e}, {:.6e}) (initial gap must be >= 0; set interference = true if the overlap is an intended fit)",
                            -g, x[0], x[1]
                        )));
                    }
                    let nn = [1.0 - s, s];
                    for (i, key) in keys.iter().enumerate() {
                        let phi = amat[i][0] * nn[0] + amat[i][1] * nn[1];
                        *gj.entry(*key).or_insert(0.0) += phi * g * wl;
                        let m = mj.entry(*key).or_default();
                        *m.entry(pa).or_insert(0.0) += phi * (1.0 - xi) * wl;
                        *m.entry(pb).or_insert(0.0) += phi * xi * wl;
                    }
                }
            }
        }
        // One row per slave node with a positive weight.
        let mut snodes: Vec<(usize, u32)> = dj.keys().copied().collect();
        snodes.sort_unstable_by_key(|&(v, b)| (b, mesh.node_tags[v]));
        let nslave = normal.len();
        let mut row_of: HashMap<(usize, u32), usize> = HashMap::new();
        for key in snodes {
            let d = dj[&key];
            if d.is_nan() || d <= 0.0 {
                continue;
            }
            let gap = gj.get(&key).copied().unwrap_or(0.0) / d;
            if c.max_gap.is_some_and(|maxg| gap > maxg) {
                continue;
            }
            let mut masters: Vec<(usize, f64)> = mj
                .get(&key)
                .map(|m| m.iter().map(|(&p, &w)| (p, w / d)).collect())
                .unwrap_or_default();
            masters.retain(|&(_, w)| w != 0.0);
            let mut heavy = masters.clone();
            heavy.sort_by(|x, y| y.1.abs().total_cmp(&x.1.abs()).then(x.0.cmp(&y.0)));
            let second = match heavy.as_slice() {
                [] => continue,
                [p] => [*p, (p.0, 0.0)],
                [p, q, ..] => [*p, *q],
            };
            let n = normal[&key];
            row_of.insert(key, self.contact.len());
            self.contact.push(ContactRow {
                kind: RowKind::Mortar,
                first: self.point(key.0, key.1).unwrap_or(0),
                second,
                // The row's normal is outward of the master: −n_j.
                normal: [-n[0], -n[1]],
                gap0: gap,
                trib: d,
                interface: id,
                masters,
            });
        }
        if row_of.is_empty() {
            return Err(err(format!(
                "{what}: no slave segment of \"{sname}\" overlaps a master segment of \"{mname}\" along its normal"
            )));
        }
        if row_of.len() < nslave {
            log::warn!(
                "{what}: {} slave node(s) of \"{sname}\" have no mortar weight (their segments do not overlap \"{mname}\") and are not constrained",
                nslave - row_of.len()
            );
        }
        for &(a, b, body, _) in ssegs {
            if let (Some(&ra), Some(&rb)) = (row_of.get(&(a, body)), row_of.get(&(b, body))) {
                self.contact_segments.push([ra, rb]);
            }
        }
        Ok(())
    }
}

/// Averaged slave normals: the sum of the adjacent segments' unit outward
/// normals, normalized (docs/methods.md §7.1); `Err(node)` where they cancel.
fn slave_normals(ssegs: &[BoundarySeg]) -> Result<HashMap<(usize, u32), Vector>, usize> {
    let mut nsum: HashMap<(usize, u32), Vector> = HashMap::new();
    for &(a, b, body, n) in ssegs {
        for v in [a, b] {
            let e = nsum.entry((v, body)).or_insert([0.0, 0.0]);
            e[0] += n[0];
            e[1] += n[1];
        }
    }
    let mut normal: HashMap<(usize, u32), Vector> = HashMap::new();
    for (&(v, body), s) in &nsum {
        let len = (s[0] * s[0] + s[1] * s[1]).sqrt();
        if len.is_nan() || len <= 1e-12 {
            return Err(v);
        }
        normal.insert((v, body), [s[0] / len, s[1] / len]);
    }
    Ok(normal)
}

/// The dual basis of a slave segment of length `len` on its projecting
/// `pieces`: Φ = A N with A = D_e M_e⁻¹, M_e, D_e the mass and lumped
/// matrices on the pieces (Popp et al. 2013; on a whole segment
/// Φ₁ = 2N₁ − N₂, Φ₂ = 2N₂ − N₁), the integrals weighted by `rw` (r when
/// axisymmetric, docs/methods.md §10; 1 otherwise). Returns (D_e, A);
/// None when M_e is singular.
fn dual_basis(
    pieces: &[Piece],
    len: f64,
    rw: impl Fn(f64) -> f64,
) -> Option<([f64; 2], [[f64; 2]; 2])> {
    let mut me = [[0.0; 2]; 2];
    let mut de = [0.0; 2];
    for p in pieces {
        for &(t, w) in &GAUSS {
            let s = p.s0 + t * (p.s1 - p.s0);
            let wl = w * (p.s1 - p.s0) * len * rw(s);
            let nn = [1.0 - s, s];
            for i in 0..2 {
                de[i] += nn[i] * wl;
                for k in 0..2 {
                    me[i][k] += nn[i] * nn[k] * wl;
                }
            }
        }
    }
    let det = me[0][0] * me[1][1] - me[0][1] * me[1][0];
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let inv = [
        [me[1][1] / det, -me[0][1] / det],
        [-me[1][0] / det, me[0][0] / det],
    ];
    let amat = [
        [de[0] * inv[0][0], de[0] * inv[0][1]],
        [de[1] * inv[1][0], de[1] * inv[1][1]],
    ];
    Some((de, amat))
}

/// The parts of a slave segment with a master segment of another body
/// facing it along the normal field: candidates nearest first (by the gap
/// at the middle of their overlap), each keeping only what nearer ones left
/// uncovered, so that a part of the slave segment is integrated once.
fn overlap_pieces(
    mesh: &Mesh,
    msegs: &[BoundarySeg],
    geom: &SlaveGeom,
    sbody: u32,
    ns: Vector,
) -> Vec<Piece> {
    let mut cand: Vec<(f64, usize, f64, f64)> = vec![];
    for (mi, &(ma, mb, mbody, nm)) in msegs.iter().enumerate() {
        if mbody == sbody || nm[0] * ns[0] + nm[1] * ns[1] >= 0.0 {
            continue;
        }
        let (Some(sa), Some(sb)) = (geom.project(mesh.nodes[ma]), geom.project(mesh.nodes[mb]))
        else {
            continue;
        };
        let (s0, s1) = (sa.min(sb).max(0.0), sa.max(sb).min(1.0));
        if !(s1 - s0 > MIN_OVERLAP) {
            continue;
        }
        let Some((_, g)) = geom.ray(0.5 * (s0 + s1), [mesh.nodes[ma], mesh.nodes[mb]]) else {
            continue;
        };
        cand.push((g.abs(), mi, s0, s1));
    }
    cand.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut covered: Vec<(f64, f64)> = vec![];
    let mut pieces = vec![];
    for (_, mi, s0, s1) in cand {
        for (p, q) in uncovered(s0, s1, &covered) {
            if q - p > MIN_OVERLAP {
                pieces.push(Piece {
                    s0: p,
                    s1: q,
                    master: mi,
                });
            }
        }
        covered.push((s0, s1));
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Gauss rule integrates s^k exactly up to k = 9.
    #[test]
    fn gauss_rule_is_exact_to_degree_nine() {
        for k in 0..=9 {
            let q: f64 = GAUSS.iter().map(|&(s, w)| w * s.powi(k)).sum();
            assert!((q - 1.0 / (k as f64 + 1.0)).abs() < 1e-14, "k = {k}: {q}");
        }
    }

    /// On a whole segment the dual basis is Φ₁ = 2N₁ − N₂: biorthogonal,
    /// ∫Φ_a N_b = δ_ab ∫N_b, and Σ Φ = 1.
    #[test]
    fn dual_basis_on_the_whole_segment_is_biorthogonal() {
        for (s0, s1) in [(0.0, 1.0), (0.2, 0.7), (0.0, 0.31)] {
            let (mut me, mut de) = ([[0.0; 2]; 2], [0.0; 2]);
            for &(t, w) in &GAUSS {
                let s = s0 + t * (s1 - s0);
                let nn = [1.0 - s, s];
                for i in 0..2 {
                    de[i] += nn[i] * w * (s1 - s0);
                    for k in 0..2 {
                        me[i][k] += nn[i] * nn[k] * w * (s1 - s0);
                    }
                }
            }
            let det = me[0][0] * me[1][1] - me[0][1] * me[1][0];
            let a = [
                [de[0] * me[1][1] / det, -de[0] * me[0][1] / det],
                [-de[1] * me[1][0] / det, de[1] * me[0][0] / det],
            ];
            if (s0, s1) == (0.0, 1.0) {
                assert!((a[0][0] - 2.0).abs() < 1e-13 && (a[0][1] + 1.0).abs() < 1e-13);
            }
            for i in 0..2 {
                for k in 0..2 {
                    let q: f64 = GAUSS
                        .iter()
                        .map(|&(t, w)| {
                            let s = s0 + t * (s1 - s0);
                            let nn = [1.0 - s, s];
                            (a[i][0] * nn[0] + a[i][1] * nn[1]) * nn[k] * w * (s1 - s0)
                        })
                        .sum();
                    let want = if i == k { de[k] } else { 0.0 };
                    assert!(
                        (q - want).abs() < 1e-13,
                        "{s0}..{s1}: ({i},{k}) {q} vs {want}"
                    );
                }
                // Σ_a Φ_a = 1 at any point.
                let s = 0.5 * (s0 + s1);
                let sum: f64 = (0..2).map(|i| a[i][0] * (1.0 - s) + a[i][1] * s).sum();
                assert!((sum - 1.0).abs() < 1e-12);
            }
        }
    }

    /// Projection along a varying normal field: the master point lies on the
    /// ray x(s) + t n(s) of the root found.
    #[test]
    fn projection_along_the_normal_field_hits_the_point() {
        let g = SlaveGeom {
            x: [[0.0, 0.0], [1.0, 0.1]],
            n: [unit([-0.2, -1.0]), unit([0.3, -1.0])],
        };
        for y in [[0.3, -0.5], [1.2, -0.2], [-0.1, -0.05], [0.5, -2.0]] {
            let s = g.project(y).unwrap();
            let r = sub(y, g.point(s));
            assert!(cross(r, g.normal(s)).abs() < 1e-12, "y = {y:?}, s = {s}");
        }
        // Parallel normals: the linear case.
        let f = SlaveGeom {
            x: [[0.0, 0.0], [2.0, 0.0]],
            n: [[0.0, -1.0], [0.0, -1.0]],
        };
        assert!((f.project([0.5, -3.0]).unwrap() - 0.25).abs() < 1e-15);
        let (xi, gap) = f.ray(0.25, [[0.0, -3.0], [1.0, -3.0]]).unwrap();
        assert!((xi - 0.5).abs() < 1e-15 && (gap - 3.0).abs() < 1e-15);
    }

    #[test]
    fn uncovered_subtracts_intervals() {
        assert_eq!(uncovered(0.0, 1.0, &[]), vec![(0.0, 1.0)]);
        assert_eq!(
            uncovered(0.0, 1.0, &[(0.2, 0.4), (0.6, 1.5)]),
            vec![(0.0, 0.2), (0.4, 0.6)]
        );
        assert!(uncovered(0.3, 0.5, &[(0.0, 1.0)]).is_empty());
    }
}
