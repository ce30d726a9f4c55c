//! The contact pairs, as rows on points (docs/methods.md §2.6–2.7, §7).
//!
//! Conforming curves (`[[contact]] on = "NAME"`): the mesh is cut along the
//! curve, so each of its nodes has a copy in the body on either side; a row
//! n·(u_k − u_l) ≤ 0 couples the two copies, with n outward of the lower
//! body k, averaged over the node's segments or one row per segment normal
//! (§2.6). Non-matching pairs (`slave`, `master`): each slave node is
//! projected orthogonally on the nearest master segment of another body (a
//! bounding-box tree finds it) and gives n·(Σ w u_master − u_slave) ≤ g with
//! the initial gap g ≥ 0 (§7).

use super::contact::{ContactRow, RowKind};
use super::edges::NONE32;
use super::element::{Point, Vector};
use super::topology::{curve_group, Topology};
use super::FemError;
use crate::mesh::{Mesh, PhysicalGroup};
use crate::problem::{Contact, ContactPair, Discretization, Material, NonMatchingPair, NormalKind};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

/// A conforming node on one pair of bodies: (mesh node, body k, body l), k < l.
type NodePair = (usize, u32, u32);

/// What the segments of a conforming curve leave at one of their nodes: the
/// segment normals with half their lengths, and the interface.
struct Acc {
    normals: Vec<(Vector, f64)>,
    interface: u32,
}

/// A conforming segment: nodes a, b, bodies k < l, normal outward of k.
type ConformingSeg = (usize, usize, u32, u32, Vector);

/// A pair without `discretization` whose slave is more than this many times
/// stiffer than its master gets node-to-segment rows (measured: mortar with
/// a slave 100 times (meshes/rollers.toml) or 4200 times (tests/hard/punch.toml)
/// stiffer alternates open and closed rows; 3 times (NAFEMS 1 and 2) is
/// within the verification tolerances; docs/methods.md §7.1).
pub(super) const STIFF_SLAVE: f64 = 10.0;

impl Topology {
    /// Node-to-node rows on conforming curves (docs/methods.md §2.6–2.7).
    pub(super) fn build_conforming(
        &mut self,
        mesh: &Mesh,
        path: &Path,
        contact: &[Contact],
        contact_edges: &[((usize, usize), u32)],
    ) -> Result<(), FemError> {
        let kind_of: Vec<NormalKind> = contact
            .iter()
            .filter_map(|c| match c.pair {
                ContactPair::Conforming { normals, .. } => Some(normals),
                ContactPair::NonMatching(_) => None,
            })
            .collect();
        let (acc, segs) = self.conforming_nodes(mesh, path, contact_edges)?;
        let mut keys: Vec<NodePair> = acc.keys().copied().collect();
        keys.sort_unstable_by_key(|&(v, k, l)| (k, l, mesh.node_tags[v]));
        // The rows of each node pair, with their normal (to pick a segment's row).
        let mut rows_at: HashMap<NodePair, Vec<(usize, Vector)>> = HashMap::new();
        for key in keys {
            let (v, k, l) = key;
            let a = &acc[&key];
            let first = self.point(v, k).unwrap_or(0);
            let second = self.point(v, l).unwrap_or(0);
            let kind = kind_of
                .get(a.interface as usize)
                .copied()
                .unwrap_or_default();
            for (n, t) in self.row_normals(mesh, path, v, a, kind)? {
                let r = self.contact.len();
                self.contact.push(ContactRow {
                    kind: RowKind::Conforming,
                    first,
                    second: [(second, 1.0), (second, 0.0)],
                    normal: n,
                    gap0: 0.0,
                    trib: t,
                    interface: a.interface,
                    masters: vec![],
                });
                rows_at.entry(key).or_default().push((r, n));
            }
        }
        for (a, b, k, l, n) in segs {
            // The row of node v nearest in normal to this segment's.
            let pick = |v: usize| -> Option<usize> {
                let rows = rows_at.get(&(v, k, l))?;
                if rows.len() == 1 {
                    return Some(rows[0].0);
                }
                rows.iter()
                    .min_by(|x, y| {
                        let dx = (x.1[0] - n[0]).abs() + (x.1[1] - n[1]).abs();
                        let dy = (y.1[0] - n[0]).abs() + (y.1[1] - n[1]).abs();
                        dx.total_cmp(&dy)
                    })
                    .map(|r| r.0)
            };
            if let (Some(ra), Some(rb)) = (pick(a), pick(b)) {
                self.contact_segments.push([ra, rb]);
            }
        }
        Ok(())
    }

    /// The segments of the conforming curves, each checked to lie between
    /// two bodies, and what they leave at each node pair.
    fn conforming_nodes(
        &self,
        mesh: &Mesh,
        path: &Path,
        contact_edges: &[((usize, usize), u32)],
    ) -> Result<(HashMap<NodePair, Acc>, Vec<ConformingSeg>), FemError> {
        let err = |msg: String| FemError::new(path, msg);
        let mut acc: HashMap<NodePair, Acc> = HashMap::new();
        let mut segs = vec![];
        for &((a, b), id) in contact_edges {
            let ts = self.edge_triangles(a, b);
            let name = &self.interface_names[id as usize];
            let bodies: Vec<u32> = ts.iter().map(|&t| self.mesh_tri_body[t]).collect();
            if ts.len() != 2 || bodies[0] == bodies[1] {
                return Err(err(format!(
                    "contact curve \"{name}\" is not between two bodies: its segment ({}, {}) {}",
                    mesh.node_tags[a],
                    mesh.node_tags[b],
                    if ts.len() < 2 {
                        "borders one body only (is the curve on the outer boundary?)".to_string()
                    } else {
                        "lies inside one body (the curve does not cut it into two)".to_string()
                    }
                )));
            }
            let (tk, tl) = if bodies[0] < bodies[1] {
                (ts[0], ts[1])
            } else {
                (ts[1], ts[0])
            };
            let (k, l) = (self.mesh_tri_body[tk], self.mesh_tri_body[tl]);
            let n = self.outward_normal(mesh, tk, a, b);
            let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
            let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            let kind = self.kind;
            for (v, w) in [
                (a, kind.boundary_weight(len, pa, pb)),
                (b, kind.boundary_weight(len, pb, pa)),
            ] {
                let e = acc.entry((v, k, l)).or_insert(Acc {
                    normals: vec![],
                    interface: id,
                });
                e.normals.push((n, w));
            }
            segs.push((a, b, k, l, n));
        }
        Ok((acc, segs))
    }

    /// The rows' normals at node `v` with their tributary lengths: one
    /// averaged normal, or one per distinct segment normal (§2.6).
    fn row_normals(
        &self,
        mesh: &Mesh,
        path: &Path,
        v: usize,
        a: &Acc,
        kind: NormalKind,
    ) -> Result<Vec<(Vector, f64)>, FemError> {
        let trib: f64 = a.normals.iter().map(|x| x.1).sum();
        let mut normals: Vec<(Vector, f64)> = vec![];
        match kind {
            NormalKind::Averaged => {
                let s = a
                    .normals
                    .iter()
                    .fold([0.0, 0.0], |s, (n, _)| [s[0] + n[0], s[1] + n[1]]);
                let len = (s[0] * s[0] + s[1] * s[1]).sqrt();
                let nonzero = len > 1e-12; // false for NaN too
                if !nonzero {
                    return Err(FemError::new(
                        path,
                        format!(
                            "contact curve \"{}\": the normals at node {} cancel (a cusp); use normals = \"segment\"",
                            self.interface_names[a.interface as usize], mesh.node_tags[v]
                        ),
                    ));
                }
                normals.push(([s[0] / len, s[1] / len], trib));
            }
            NormalKind::Segment => {
                for &(n, t) in &a.normals {
                    // Two segments with the same normal (a straight line) give one row.
                    if let Some(e) = normals
                        .iter_mut()
                        .find(|(m, _)| (m[0] - n[0]).abs() + (m[1] - n[1]).abs() < 1e-12)
                    {
                        e.1 += t;
                    } else {
                        normals.push((n, t));
                    }
                }
            }
        }
        Ok(normals)
    }

    /// Node-to-segment rows of non-matching pairs (docs/methods.md §7), or
    /// mortar rows (`discretization = "mortar"`, §7.1, `mortar.rs`).
    pub(super) fn build_nonmatching(
        &mut self,
        mesh: &Mesh,
        path: &Path,
        materials: &BTreeMap<String, Material>,
        contact: &[Contact],
    ) -> Result<(), FemError> {
        let mut seen: Vec<(usize, Segments, Segments)> = vec![];
        for (ci, c) in contact.iter().enumerate() {
            let ContactPair::NonMatching(nm) = &c.pair else {
                continue;
            };
            let (sname, mname) = (&nm.slave, &nm.master);
            let what = format!("[[contact]] #{}", ci + 1);
            let sg = curve_group(mesh, sname, &what, path)?;
            let mg = curve_group(mesh, mname, &what, path)?;
            let id = self.interface_names.len() as u32;
            self.interface_names.push(format!("{sname}->{mname}"));
            let pair = Pair {
                id,
                masters: self.boundary_segments(mesh, path, mg, &what, "master", mname)?,
                slaves: self.boundary_segments(mesh, path, sg, &what, "slave", sname)?,
                what,
            };
            let disc = match nm.discretization {
                Some(d) => d,
                None => self.default_discretization(materials, &pair, sname, mname),
            };
            self.interface_kinds.push(match disc {
                Discretization::Mortar => RowKind::Mortar,
                Discretization::Nts => RowKind::NonMatching,
            });
            let (ss, ms) = (segment_set(&pair.slaves), segment_set(&pair.masters));
            for (i, si, mi) in &seen {
                let twice = shared(si, &ss)
                    .zip(shared(mi, &ms))
                    .or_else(|| shared(si, &ms).zip(shared(mi, &ss)));
                if let Some(((a, b), (p, q))) = twice {
                    let tag = |v: usize| mesh.node_tags[v];
                    return Err(FemError::new(
                        path,
                        format!(
                            "[[contact]] #{} ({}) and #{} ({}) overlap: both pair the segment ({}, {}) with the segment ({}, {}), so its nodes would get their rows twice; give each stretch of curve to one [[contact]]",
                            i + 1,
                            contact[*i].keys(),
                            ci + 1,
                            c.keys(),
                            tag(a),
                            tag(b),
                            tag(p),
                            tag(q)
                        ),
                    ));
                }
            }
            seen.push((ci, ss, ms));
            match disc {
                Discretization::Mortar => self.mortar_rows(mesh, path, nm, &pair)?,
                Discretization::Nts => self.nonmatching_rows(mesh, path, nm, &pair)?,
            }
        }
        Ok(())
    }

    /// The rows of a non-matching pair without `discretization`: mortar,
    /// unless the slave is more than [`STIFF_SLAVE`] times stiffer than the
    /// master (the least Young's modulus of the slave's bodies against the
    /// largest of the master's), where mortar multipliers, which live on the
    /// slave, alternate between open and closed rows: node-to-segment rows
    /// then, with a warning (docs/methods.md §7.1, which side is the slave).
    fn default_discretization(
        &self,
        materials: &BTreeMap<String, Material>,
        pair: &Pair,
        sname: &str,
        mname: &str,
    ) -> Discretization {
        let bodies = |segs: &[MasterSeg]| -> HashSet<u32> { segs.iter().map(|s| s.2).collect() };
        let (sb, mb) = (bodies(&pair.slaves), bodies(&pair.masters));
        let (mut e_slave, mut e_master) = (f64::INFINITY, 0.0f64);
        for (&b, &m) in self.tri_body.iter().zip(&self.tri_material) {
            let Some(mat) = self
                .material_names
                .get(m as usize)
                .and_then(|n| materials.get(n))
            else {
                continue;
            };
            if sb.contains(&b) {
                e_slave = e_slave.min(mat.e);
            }
            if mb.contains(&b) {
                e_master = e_master.max(mat.e);
            }
        }
        if e_slave > STIFF_SLAVE * e_master {
            log::warn!(
                "{}: slave \"{sname}\" (E = {e_slave:e}) is {:.0} times stiffer than master \"{mname}\" (E = {e_master:e}): node-to-segment rows, not the default mortar rows, whose multipliers oscillate on a stiff slave; make the softer body the slave for mortar rows, or write discretization = \"nts\"",
                pair.what,
                e_slave / e_master
            );
            Discretization::Nts
        } else {
            Discretization::Mortar
        }
    }

    /// The segments of curve `g` with their owner body and outward normal;
    /// each must be on the boundary of one body.
    fn boundary_segments(
        &self,
        mesh: &Mesh,
        path: &Path,
        g: &PhysicalGroup,
        what: &str,
        role: &str,
        name: &str,
    ) -> Result<Vec<MasterSeg>, FemError> {
        let mut segs = vec![];
        for &li in &g.elements {
            let [a, b] = mesh.lines[li];
            let ts = self.edge_triangles(a, b);
            if ts.len() != 1 {
                return Err(FemError::new(
                    path,
                    format!(
                        "{what}: {role} curve \"{name}\" segment ({}, {}) is not on the boundary of one body",
                        mesh.node_tags[a], mesh.node_tags[b]
                    ),
                ));
            }
            let body = self.mesh_tri_body[ts[0]];
            let n = self.outward_normal(mesh, ts[0], a, b);
            segs.push((a, b, body, n));
        }
        Ok(segs)
    }

    /// One row per slave node that finds a master segment within reach, in
    /// (body, node tag) order, and the segments between the rows.
    fn nonmatching_rows(
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
        let tree = SegmentTree::build(mesh, msegs);
        let mut stack = vec![];
        // Slave nodes with owner body and tributary length.
        let mut slave: HashMap<(usize, u32), f64> = HashMap::new();
        let kind = self.kind;
        for &(a, b, body, _) in ssegs {
            let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
            let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            *slave.entry((a, body)).or_insert(0.0) += kind.boundary_weight(len, pa, pb);
            *slave.entry((b, body)).or_insert(0.0) += kind.boundary_weight(len, pb, pa);
        }
        let mut snodes: Vec<((usize, u32), f64)> = slave.into_iter().collect();
        snodes.sort_unstable_by_key(|((v, b), _)| (*b, mesh.node_tags[*v]));
        let mut row_of: HashMap<(usize, u32), usize> = HashMap::new();
        let mut skipped = 0usize;
        let tol_pen = 1e-6;
        let mut body_sizes: Option<Vec<f64>> = None;
        for ((v, sb), trib) in snodes {
            let xs = mesh.nodes[v];
            // Nearest master segment whose orthogonal projection falls on it.
            let best = tree.nearest(mesh, msegs, xs, sb, &mut stack);
            let Some((_, si, xi)) = best else {
                skipped += 1;
                continue;
            };
            let (a, b, mb, n) = msegs[si];
            let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
            let p = [pa[0] + xi * (pb[0] - pa[0]), pa[1] + xi * (pb[1] - pa[1])];
            let g = n[0] * (xs[0] - p[0]) + n[1] * (xs[1] - p[1]);
            let seg_len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            if g < -tol_pen * seg_len && !c.interference {
                return Err(err(format!(
                    "{what}: slave node {} of \"{sname}\" penetrates master \"{mname}\" by {:.3e} (initial gap must be >= 0; set interference = true if the overlap is an intended fit)",
                    mesh.node_tags[v], -g
                )));
            }
            if g < 0.0 && c.interference {
                let sizes = body_sizes.get_or_insert_with(|| self.body_sizes());
                let size = |b: u32| sizes.get(b as usize).copied().unwrap_or(0.0);
                let at = format!(
                    "slave node {} of \"{sname}\" against \"{mname}\"",
                    mesh.node_tags[v]
                );
                super::interference::check_overlap(what, &at, -g, seg_len, [size(sb), size(mb)])
                    .map_err(err)?;
            }
            if let Some(maxg) = c.max_gap {
                if g > maxg {
                    skipped += 1;
                    continue;
                }
            }
            let first = self.point(v, sb).unwrap_or(0);
            let m1 = self.point(a, mb).unwrap_or(0);
            let m2 = self.point(b, mb).unwrap_or(0);
            row_of.insert((v, sb), self.contact.len());
            self.contact.push(ContactRow {
                kind: RowKind::NonMatching,
                first,
                second: [(m1, 1.0 - xi), (m2, xi)],
                normal: n,
                // An intended interference keeps its overlap (g < 0): the
                // first step pushes it out (docs/problem-format.md §5).
                gap0: if c.interference { g } else { g.max(0.0) },
                trib,
                interface: id,
                masters: vec![],
            });
        }
        if row_of.is_empty() {
            return Err(err(format!(
                "{what}: no slave node of \"{sname}\" finds a master segment of \"{mname}\" within reach"
            )));
        }
        if skipped > 0 {
            log::warn!("{what}: {skipped} slave node(s) of \"{sname}\" have no master segment within reach and are not constrained");
        }
        for &(a, b, body, _) in ssegs {
            if let (Some(&ra), Some(&rb)) = (row_of.get(&(a, body)), row_of.get(&(b, body))) {
                self.contact_segments.push([ra, rb]);
            }
        }
        Ok(())
    }
}

/// A boundary segment of a non-matching pair (master or slave): nodes,
/// owner body, outward normal.
type MasterSeg = (usize, usize, u32, Vector);
pub(super) type BoundarySeg = MasterSeg;

/// A non-matching pair: its interface, its name in messages, its segments.
pub(super) struct Pair {
    pub(super) id: u32,
    pub(super) what: String,
    pub(super) masters: Vec<MasterSeg>,
    pub(super) slaves: Vec<MasterSeg>,
}

/// Segments as sorted (a < b) mesh node pairs.
type Segments = HashSet<(usize, usize)>;

fn segment_set(segs: &[MasterSeg]) -> Segments {
    segs.iter()
        .map(|&(a, b, _, _)| (a.min(b), a.max(b)))
        .collect()
}

/// The smallest segment in both sets (the smallest, so that the message
/// does not depend on hashing).
fn shared(a: &Segments, b: &Segments) -> Option<(usize, usize)> {
    a.intersection(b).min().copied()
}

/// Orthogonal projection of `xs` on the segment (pa, pb): (distance, ξ) if
/// ξ ∈ [−1e-9, 1 + 1e-9] (ξ clamped to [0, 1]).
#[inline]
fn project_on_segment(xs: Point, pa: Point, pb: Point) -> Option<(f64, f64)> {
    let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
    let l2 = dx * dx + dy * dy;
    let xi = ((xs[0] - pa[0]) * dx + (xs[1] - pa[1]) * dy) / l2;
    if !(-1e-9..=1.0 + 1e-9).contains(&xi) {
        return None;
    }
    let xi = xi.clamp(0.0, 1.0);
    let p = [pa[0] + xi * dx, pa[1] + xi * dy];
    let dist = ((xs[0] - p[0]).powi(2) + (xs[1] - p[1]).powi(2)).sqrt();
    Some((dist, xi))
}

/// The master segments in a bounding-box tree, for the nearest segment of
/// each slave node in O(log n) instead of a scan over all of them.
struct SegmentTree {
    nodes: Vec<BoxNode>,
    /// Segment indices; a leaf holds `order[start..end]`.
    order: Vec<u32>,
}

/// A tree node: bounding box (enlarged by far more than round-off) and
/// either two children or a range of segments.
struct BoxNode {
    lo: Point,
    hi: Point,
    start: u32,
    end: u32,
    /// Children (NONE32: a leaf).
    kids: [u32; 2],
}

const LEAF_SIZE: usize = 4;

impl SegmentTree {
    fn build(mesh: &Mesh, segs: &[MasterSeg]) -> SegmentTree {
        let ends = |s: &MasterSeg| (mesh.nodes[s.0], mesh.nodes[s.1]);
        // Round-off of the projected point is ~1e-16 of the coordinates; the
        // boxes are enlarged by 1e-9 of them, so that a segment at computed
        // distance d is never pruned by a box at computed distance > d.
        let scale = segs
            .iter()
            .flat_map(|s| {
                let (a, b) = ends(s);
                [a[0].abs(), a[1].abs(), b[0].abs(), b[1].abs()]
            })
            .fold(0.0f64, f64::max);
        let pad = 1e-9 * scale;
        let mid: Vec<Point> = segs
            .iter()
            .map(|s| {
                let (a, b) = ends(s);
                [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
            })
            .collect();
        let mut tree = SegmentTree {
            nodes: vec![],
            order: (0..segs.len() as u32).collect(),
        };
        if segs.is_empty() {
            return tree;
        }
        // Iterative top-down build: (node, start, end).
        tree.nodes.push(BoxNode {
            lo: [0.0; 2],
            hi: [0.0; 2],
            start: 0,
            end: segs.len() as u32,
            kids: [NONE32; 2],
        });
        let mut todo = vec![0usize];
        while let Some(ni) = todo.pop() {
            let (s, e) = (tree.nodes[ni].start as usize, tree.nodes[ni].end as usize);
            let mut lo = [f64::INFINITY; 2];
            let mut hi = [f64::NEG_INFINITY; 2];
            for &si in &tree.order[s..e] {
                let (a, b) = ends(&segs[si as usize]);
                for k in 0..2 {
                    lo[k] = lo[k].min(a[k]).min(b[k]);
                    hi[k] = hi[k].max(a[k]).max(b[k]);
                }
            }
            tree.nodes[ni].lo = [lo[0] - pad, lo[1] - pad];
            tree.nodes[ni].hi = [hi[0] + pad, hi[1] + pad];
            if e - s <= LEAF_SIZE {
                continue;
            }
            // Split at the median midpoint along the longer side.
            let axis = if hi[0] - lo[0] >= hi[1] - lo[1] { 0 } else { 1 };
            let m = s + (e - s) / 2;
            tree.order[s..e].select_nth_unstable_by(m - s, |&x, &y| {
                mid[x as usize][axis]
                    .total_cmp(&mid[y as usize][axis])
                    .then(x.cmp(&y))
            });
            let k = tree.nodes.len() as u32;
            tree.nodes[ni].kids = [k, k + 1];
            for (a, b) in [(s, m), (m, e)] {
                todo.push(tree.nodes.len());
                tree.nodes.push(BoxNode {
                    lo: [0.0; 2],
                    hi: [0.0; 2],
                    start: a as u32,
                    end: b as u32,
                    kids: [NONE32; 2],
                });
            }
        }
        tree
    }

    /// Distance from `x` to the box of node `ni`.
    #[inline]
    fn box_dist(&self, ni: usize, x: Point) -> f64 {
        let n = &self.nodes[ni];
        let dx = (n.lo[0] - x[0]).max(x[0] - n.hi[0]).max(0.0);
        let dy = (n.lo[1] - x[1]).max(x[1] - n.hi[1]).max(0.0);
        (dx * dx + dy * dy).sqrt()
    }

    /// The segment (distance, index, ξ) of a body other than `body` whose
    /// projection of `xs` falls on it, nearest first and the lowest index
    /// among equal distances: exactly the result of a scan over all
    /// segments keeping the first strictly nearer one.
    fn nearest(
        &self,
        mesh: &Mesh,
        segs: &[MasterSeg],
        xs: Point,
        body: u32,
        stack: &mut Vec<u32>,
    ) -> Option<(f64, usize, f64)> {
        let mut best: Option<(f64, usize, f64)> = None;
        if self.nodes.is_empty() {
            return None;
        }
        stack.clear();
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let ni = ni as usize;
            if let Some(b) = best {
                // Keep boxes at (computed) distance ≤ the best: ties matter.
                if self.box_dist(ni, xs) > b.0 * (1.0 + 1e-12) {
                    continue;
                }
            }
            let node = &self.nodes[ni];
            if node.kids[0] == NONE32 {
                for &si in &self.order[node.start as usize..node.end as usize] {
                    let si = si as usize;
                    let (a, b, mb, _) = segs[si];
                    if mb == body {
                        continue;
                    }
                    if let Some((dist, xi)) = project_on_segment(xs, mesh.nodes[a], mesh.nodes[b]) {
                        let better = match best {
                            None => true,
                            Some(bb) => dist < bb.0 || (dist == bb.0 && si < bb.1),
                        };
                        if better {
                            best = Some((dist, si, xi));
                        }
                    }
                }
            } else {
                // Nearer child on top of the stack.
                let [k0, k1] = node.kids;
                let (d0, d1) = (
                    self.box_dist(k0 as usize, xs),
                    self.box_dist(k1 as usize, xs),
                );
                if d0 <= d1 {
                    stack.push(k1);
                    stack.push(k0);
                } else {
                    stack.push(k0);
                    stack.push(k1);
                }
            }
        }
        best
    }
}

/// The nearest segment by a scan over all of them (the reference that
/// [`SegmentTree::nearest`] must reproduce).
#[cfg(test)]
fn nearest_brute_force(
    mesh: &Mesh,
    segs: &[MasterSeg],
    xs: Point,
    body: u32,
) -> Option<(f64, usize, f64)> {
    let mut best: Option<(f64, usize, f64)> = None;
    for (si, &(a, b, mb, _)) in segs.iter().enumerate() {
        if mb == body {
            continue;
        }
        let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
        let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
        let l2 = dx * dx + dy * dy;
        let xi = ((xs[0] - pa[0]) * dx + (xs[1] - pa[1]) * dy) / l2;
        if !(-1e-9..=1.0 + 1e-9).contains(&xi) {
            continue;
        }
        let xi = xi.clamp(0.0, 1.0);
        let p = [pa[0] + xi * dx, pa[1] + xi * dy];
        let dist = ((xs[0] - p[0]).powi(2) + (xs[1] - p[1]).powi(2)).sqrt();
        if best.map(|b| dist < b.0).unwrap_or(true) {
            best = Some((dist, si, xi));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_nearest(mesh: &Mesh, segs: &[MasterSeg], queries: &[(Point, u32)]) -> usize {
        let tree = SegmentTree::build(mesh, segs);
        let mut stack = vec![];
        let mut found = 0;
        for &(x, body) in queries {
            let a = tree.nearest(mesh, segs, x, body, &mut stack);
            let b = nearest_brute_force(mesh, segs, x, body);
            // Bit for bit: distance, segment and ξ.
            assert_eq!(
                a.map(|v| (v.0.to_bits(), v.1, v.2.to_bits())),
                b.map(|v| (v.0.to_bits(), v.1, v.2.to_bits())),
                "query {x:?} body {body}"
            );
            found += a.is_some() as usize;
        }
        found
    }

    /// Every boundary curve of every shipped mesh as a master, every mesh
    /// node as a slave (of each body and of none).
    #[test]
    fn segment_tree_matches_brute_force_on_shipped_meshes() {
        for (_, problem, mesh) in crate::shipped_examples() {
            let topo = Topology::build(
                &mesh,
                &problem.path,
                crate::fem::ElementKind::of(&problem.file.model),
                &problem.file.materials,
                &problem.file.contact,
            )
            .unwrap();
            let mut all = vec![];
            for g in mesh.groups.iter().filter(|g| g.dim == 1) {
                let mut segs = vec![];
                for &li in &g.elements {
                    let [a, b] = mesh.lines[li];
                    let ts = topo.edge_triangles(a, b);
                    if ts.len() != 1 {
                        continue;
                    }
                    let n = topo.outward_normal(&mesh, ts[0], a, b);
                    segs.push((a, b, topo.mesh_triangle_body(ts[0]), n));
                }
                let queries: Vec<(Point, u32)> = mesh
                    .nodes
                    .iter()
                    .flat_map(|&x| [(x, 0), (x, 1), (x, NONE32)])
                    .collect();
                assert!(check_nearest(&mesh, &segs, &queries) > 0 || segs.is_empty());
                all.extend(segs);
            }
            // All curves at once (overlapping and duplicated segments).
            let queries: Vec<(Point, u32)> = mesh.nodes.iter().map(|&x| (x, NONE32)).collect();
            check_nearest(&mesh, &all, &queries);
        }
    }

    /// Random segments on an integer grid (exact ties, duplicates,
    /// zero-length and collinear segments) and random queries.
    #[test]
    fn segment_tree_matches_brute_force_on_random_segments() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |n: u64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s % n
        };
        for case in 0..300 {
            let grid = 2 + next(12);
            let nn = 2 + next(40) as usize;
            let scale = [1.0, 1e-3, 1e5, 0.1][case % 4];
            let mesh = Mesh {
                nodes: (0..nn)
                    .map(|_| [next(grid) as f64 * scale, next(grid) as f64 * scale])
                    .collect(),
                ..Mesh::default()
            };
            let nseg = 1 + next(60) as usize;
            let segs: Vec<MasterSeg> = (0..nseg)
                .map(|_| {
                    (
                        next(nn as u64) as usize,
                        next(nn as u64) as usize,
                        next(3) as u32,
                        [0.0, 1.0],
                    )
                })
                .collect();
            let mut queries: Vec<(Point, u32)> = (0..200)
                .map(|_| {
                    let x = [
                        (next(4 * grid) as f64 / 2.0 - grid as f64 / 2.0) * scale,
                        (next(4 * grid) as f64 / 2.0 - grid as f64 / 2.0) * scale,
                    ];
                    (x, next(4) as u32)
                })
                .collect();
            for _ in 0..100 {
                let f = next(1 << 20) as f64 / (1 << 20) as f64;
                let x = [
                    (f * grid as f64 * 1.4 - 0.2 * grid as f64) * scale,
                    (next(1 << 20) as f64 / (1 << 20) as f64 * grid as f64) * scale,
                ];
                queries.push((x, next(4) as u32));
            }
            check_nearest(&mesh, &segs, &queries);
        }
    }
}
