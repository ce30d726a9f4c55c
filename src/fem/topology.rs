//! From a Gmsh mesh and a problem file to bodies, node copies and contact rows.
//!
//! A body is a set of triangles connected through edges after the mesh is cut
//! along the conforming contact curves (problem-format.md). Every (node, body)
//! pair becomes one *point* (nodes on an interface appear once per side);
//! points are numbered body after body (methods.md §2.3), bodies in the order
//! of their lowest node tag.

use super::FemError;
use crate::mesh::Mesh;
use crate::problem::{NormalKind, Problem};
use std::collections::HashMap;

/// How a contact row couples points: n·(u_first − u_second) ≤ g (conforming,
/// n outward of the lower body) or n·(Σ w u_master − u_slave) ≤ g (non-matching,
/// n outward of the master).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowKind {
    Conforming,
    NonMatching,
}

/// One contact constraint row (methods.md §2.7, §7 for non-matching).
#[derive(Debug, Clone)]
pub struct ContactRow {
    pub kind: RowKind,
    /// Point of body k (conforming) or the slave point.
    pub first: usize,
    /// Point of body l (weight 1), or the two master points with (1−ξ, ξ).
    pub second: [(usize, f64); 2],
    /// Contract normal: outward of body k, or of the master segment.
    pub normal: [f64; 2],
    /// Initial gap g ≥ 0.
    pub gap0: f64,
    /// Length that the row's force acts on (half the adjacent segments).
    pub trib: f64,
    pub interface: u32,
}

impl ContactRow {
    /// Coefficients c_p (2-vectors) of the row Σ c_p·u_p ≤ g.
    pub fn coefficients(&self) -> Vec<(usize, [f64; 2])> {
        let n = self.normal;
        match self.kind {
            RowKind::Conforming => vec![(self.first, n), (self.second[0].0, [-n[0], -n[1]])],
            RowKind::NonMatching => {
                let mut v = vec![(self.first, [-n[0], -n[1]])];
                for &(p, w) in &self.second {
                    if w != 0.0 {
                        v.push((p, [w * n[0], w * n[1]]));
                    }
                }
                v
            }
        }
    }
}

#[derive(Debug, Clone, Default)]
pub struct Topology {
    /// Coordinates of each point.
    pub points: Vec<[f64; 2]>,
    /// Mesh node index of each point.
    pub point_node: Vec<usize>,
    pub point_body: Vec<u32>,
    /// Triangles in point indices, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    pub tri_body: Vec<u32>,
    pub tri_material: Vec<u32>,
    pub material_names: Vec<String>,
    pub nbodies: usize,
    /// copies[node] = [(body, point)] (CSR: copy_ptr, copy_list).
    copy_ptr: Vec<usize>,
    copy_list: Vec<(u32, usize)>,
    /// Mesh-node edges → up to two triangles (mesh triangle indices).
    edges: Edges,
    /// Mesh triangle → its body.
    mesh_tri_body: Vec<u32>,
    /// Mesh triangles, oriented counter-clockwise.
    mesh_tris: Vec<[usize; 3]>,
    pub contact: Vec<ContactRow>,
    /// Segments between contact rows (for the contact VTU).
    pub contact_segments: Vec<[usize; 2]>,
    pub interface_names: Vec<String>,
}

/// "No triangle" / "no body" in the u32 index arrays.
const NONE32: u32 = u32::MAX;

/// The edges of a triangle mesh, grouped by their lower node: the edges
/// (a, b), a < b, of node a are `hi[ptr[a]..ptr[a + 1]]` (sorted by b), and
/// edge e borders the triangles `tri[e]` (the second NONE32 on a boundary).
/// An edge is found by a binary search in its lower node's list.
#[derive(Debug, Clone, Default)]
struct Edges {
    ptr: Vec<usize>,
    hi: Vec<u32>,
    tri: Vec<[u32; 2]>,
}

impl Edges {
    /// The edges of `tris` (nodes < nn < 2^32 − 1, fewer than (2^32 − 1) / 3
    /// triangles). Err((a, b)): the first edge (in triangle order, then
    /// local edge order) that a third triangle shares, as that triangle
    /// lists it.
    fn build(nn: usize, tris: &[[usize; 3]]) -> Result<Edges, (usize, usize)> {
        // Half-edges (lower node, higher node, 3 × triangle + local edge),
        // sorted by lower node and, for one node, in (triangle, local
        // edge) order.
        let half_edges = || {
            tris.iter().enumerate().flat_map(|(t, tri)| {
                (0..3).map(move |k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    (a.min(b) as u32, a.max(b) as u32, (3 * t + k) as u32)
                })
            })
        };
        let (mut half, ptr) = super::bucket_sort(half_edges, |h| h.0 as usize, nn);
        let mut out = Edges {
            ptr: Vec::with_capacity(nn + 1),
            hi: Vec::with_capacity(half.len() / 2 + nn),
            tri: Vec::with_capacity(half.len() / 2 + nn),
        };
        out.ptr.push(0);
        // The third half-edge (3t + k) of an overfull edge that comes first.
        let mut overfull: Option<u32> = None;
        for lo in 0..nn {
            let list = &mut half[ptr[lo]..ptr[lo + 1]];
            list.sort_unstable();
            let mut i = 0;
            while i < list.len() {
                let hi = list[i].1;
                let mut j = i + 1;
                while j < list.len() && list[j].1 == hi {
                    j += 1;
                }
                if j - i > 2 {
                    let third = list[i + 2].2;
                    if overfull.map(|o| third < o).unwrap_or(true) {
                        overfull = Some(third);
                    }
                }
                out.hi.push(hi);
                out.tri.push([
                    list[i].2 / 3,
                    if j - i > 1 { list[i + 1].2 / 3 } else { NONE32 },
                ]);
                i = j;
            }
            out.ptr.push(out.hi.len());
        }
        if let Some(tk) = overfull {
            let tri = tris[tk as usize / 3];
            let k = tk as usize % 3;
            return Err((tri[k], tri[(k + 1) % 3]));
        }
        Ok(out)
    }

    fn len(&self) -> usize {
        self.hi.len()
    }

    /// The index of edge (a, b), if it is an edge of the mesh.
    fn find(&self, a: usize, b: usize) -> Option<usize> {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        let (s, e) = (*self.ptr.get(lo)?, *self.ptr.get(lo + 1)?);
        let hi = u32::try_from(hi).ok()?;
        self.hi[s..e].binary_search(&hi).ok().map(|k| s + k)
    }
}

impl Topology {
    /// The point of mesh node `node` in body `body`.
    pub fn point(&self, node: usize, body: u32) -> Option<usize> {
        self.copies(node)
            .iter()
            .find(|(b, _)| *b == body)
            .map(|c| c.1)
    }

    /// All copies (body, point) of a mesh node.
    pub fn copies(&self, node: usize) -> &[(u32, usize)] {
        &self.copy_list[self.copy_ptr[node]..self.copy_ptr[node + 1]]
    }

    /// Triangles (mesh indices) having the edge (a, b).
    pub fn edge_triangles(&self, a: usize, b: usize) -> Vec<usize> {
        self.edges
            .find(a, b)
            .map(|e| {
                self.edges.tri[e]
                    .iter()
                    .filter(|&&x| x != NONE32)
                    .map(|&x| x as usize)
                    .collect()
            })
            .unwrap_or_default()
    }

    pub fn mesh_triangle_body(&self, t: usize) -> u32 {
        self.mesh_tri_body[t]
    }

    /// Unit outward normal of mesh triangle `t` on its edge (a, b).
    pub fn outward_normal(&self, mesh: &Mesh, t: usize, a: usize, b: usize) -> [f64; 2] {
        let tri = self.mesh_tris[t];
        let c = tri.iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
        let (pa, pb, pc) = (mesh.nodes[a], mesh.nodes[b], mesh.nodes[c]);
        let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
        let len = (dx * dx + dy * dy).sqrt();
        let mut n = [dy / len, -dx / len];
        // Pointing away from the third vertex.
        if n[0] * (pc[0] - pa[0]) + n[1] * (pc[1] - pa[1]) > 0.0 {
            n = [-n[0], -n[1]];
        }
        n
    }

    /// Build the topology. Checks materials, orientation, contact curves.
    pub fn build(mesh: &Mesh, problem: &Problem) -> Result<Topology, FemError> {
        let err = |msg: String| FemError::new(&problem.path, msg);
        let mpath = mesh.path.display().to_string();
        let nt = mesh.triangles.len();
        let nn = mesh.nodes.len();
        let mut lap = super::Lap::new("Topology::build");

        // --- materials per triangle
        let mut material_names: Vec<String> = vec![];
        let mut tri_material = vec![u32::MAX; nt];
        for name in problem.file.materials.keys() {
            let Some(g) = mesh.group_any(name) else {
                return Err(err(format!(
                    "[materials.{name}]: no physical surface named \"{name}\" in {mpath} (surfaces: {})",
                    group_names(mesh, 2)
                )));
            };
            if g.dim != 2 {
                return Err(err(format!(
                    "[materials.{name}]: \"{name}\" is a physical {} in {mpath}, not a surface",
                    dim_name(g.dim)
                )));
            }
            let id = material_names.len() as u32;
            material_names.push(name.clone());
            for &t in &g.elements {
                if tri_material[t] != u32::MAX {
                    return Err(err(format!(
                        "triangle {} is in two physical surfaces with a material (\"{}\" and \"{name}\")",
                        mesh.triangle_tags[t], material_names[tri_material[t] as usize]
                    )));
                }
                tri_material[t] = id;
            }
        }
        if let Some(t) = tri_material.iter().position(|&m| m == u32::MAX) {
            let groups: Vec<&str> = mesh
                .groups
                .iter()
                .filter(|g| g.dim == 2 && g.elements.contains(&t))
                .map(|g| g.name.as_str())
                .collect();
            return Err(err(if groups.is_empty() {
                format!("{mpath}: triangle {} belongs to no physical surface; every triangle needs one (its name selects the material)", mesh.triangle_tags[t])
            } else {
                format!(
                    "physical surface \"{}\" of {mpath} has no material: add [materials.{}]",
                    groups[0], groups[0]
                )
            }));
        }

        lap.lap("materials");
        // --- orientation and degenerate triangles
        let mut mesh_tris = mesh.triangles.clone();
        let mut signs: Vec<f64> = Vec::with_capacity(nt);
        for (t, tri) in mesh_tris.iter().enumerate() {
            let x = tri.map(|v| mesh.nodes[v]);
            let a = super::element::area2(&x);
            let e2 = (0..3)
                .map(|k| {
                    let (a, b) = (x[k], x[(k + 1) % 3]);
                    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
                })
                .fold(0.0f64, f64::max);
            if !(a.abs() > 1e-12 * e2) {
                return Err(err(format!(
                    "{mpath}: triangle {} is degenerate (area {:.3e})",
                    mesh.triangle_tags[t],
                    a / 2.0
                )));
            }
            signs.push(a);
        }
        if nn >= NONE32 as usize || nt >= NONE32 as usize / 3 {
            return Err(err(format!(
                "{mpath}: {nn} nodes and {nt} triangles: more than this program indexes (2^32 - 1 nodes, (2^32 - 1) / 3 triangles)"
            )));
        }

        lap.lap("areas");
        // --- edges → triangles
        let edges = match Edges::build(nn, &mesh_tris) {
            Ok(e) => e,
            Err((a, b)) => {
                return Err(err(format!(
                "{mpath}: edge ({}, {}) is shared by more than two triangles (overlapping mesh?)",
                mesh.node_tags[a], mesh.node_tags[b]
            )))
            }
        };

        lap.lap("edges");
        // --- conforming contact edges: sorted (a < b) node pairs with their
        // interface; a segment in two contact groups belongs to the last one.
        let mut interface_names: Vec<String> = vec![];
        let mut contact_edges: Vec<((usize, usize), u32)> = vec![];
        for (ci, c) in problem.file.contact.iter().enumerate() {
            if let Some(on) = &c.on {
                let g = curve_group(mesh, on, &format!("[[contact]] #{}", ci + 1), &problem.path)?;
                let id = interface_names.len() as u32;
                interface_names.push(on.clone());
                for &l in &g.elements {
                    let [a, b] = mesh.lines[l];
                    let key = if a < b { (a, b) } else { (b, a) };
                    contact_edges.push((key, id));
                }
            }
        }
        // Stable sort by key, then keep the last entry of each key.
        contact_edges.sort_by_key(|e| e.0);
        let mut dedup: Vec<((usize, usize), u32)> = Vec::with_capacity(contact_edges.len());
        for e in contact_edges {
            match dedup.last_mut() {
                Some(last) if last.0 == e.0 => *last = e,
                _ => dedup.push(e),
            }
        }
        let contact_edges = dedup;
        let mut on_contact = vec![false; edges.len()];
        for &((a, b), _) in &contact_edges {
            if let Some(e) = edges.find(a, b) {
                on_contact[e] = true;
            }
        }

        // --- bodies: union-find over edges not on contact curves
        let mut uf = UnionFind::new(nt);
        for (e, ts) in edges.tri.iter().enumerate() {
            if ts[1] != NONE32 && !on_contact[e] {
                uf.union(ts[0] as usize, ts[1] as usize);
            }
        }
        drop(on_contact);
        // Each set's root is its lowest triangle; bodies are numbered in the
        // order of (lowest node tag, root).
        let mut root_min_tag = vec![u64::MAX; nt];
        let mut tri_root = vec![0u32; nt];
        for (t, tri) in mesh_tris.iter().enumerate() {
            let r = uf.find(t);
            tri_root[t] = r as u32;
            let m = tri.iter().map(|&v| mesh.node_tags[v]).min().unwrap_or(0);
            root_min_tag[r] = root_min_tag[r].min(m);
        }
        drop(uf);
        let mut roots: Vec<(u64, usize)> = (0..nt)
            .filter(|&t| tri_root[t] as usize == t)
            .map(|r| (root_min_tag[r], r))
            .collect();
        drop(root_min_tag);
        roots.sort_unstable();
        let mut body_of_root = vec![u32::MAX; nt];
        for (i, &(_, r)) in roots.iter().enumerate() {
            body_of_root[r] = i as u32;
        }
        let mesh_tri_body: Vec<u32> = tri_root.iter().map(|&r| body_of_root[r as usize]).collect();
        drop(tri_root);
        drop(body_of_root);
        let nbodies = roots.len();

        lap.lap("bodies");
        // Orientation: flip a body whose triangles are all clockwise; a mix is an inverted element.
        let mut pos = vec![0usize; nbodies];
        let mut neg = vec![0usize; nbodies];
        for (t, &a) in signs.iter().enumerate() {
            if a > 0.0 {
                pos[mesh_tri_body[t] as usize] += 1;
            } else {
                neg[mesh_tri_body[t] as usize] += 1;
            }
        }
        for (t, &a) in signs.iter().enumerate() {
            let b = mesh_tri_body[t] as usize;
            let majority_pos = pos[b] >= neg[b];
            if (a > 0.0) != majority_pos {
                return Err(err(format!(
                    "{mpath}: triangle {} of physical surface '{}' is inverted (its orientation differs from the rest of body {b})",
                    mesh.triangle_tags[t],
                    material_names
                        .get(tri_material[t] as usize)
                        .map(String::as_str)
                        .unwrap_or("?")
                )));
            }
            if !majority_pos {
                mesh_tris[t].swap(1, 2);
            }
        }
        drop(signs);

        lap.lap("orientation");
        // --- points: (body, node tag) order
        // The distinct bodies of each node: the first one seen, and the rare
        // others (nodes on a contact curve) as sorted (node, body) pairs.
        let mut first_body = vec![NONE32; nn];
        let mut extra: Vec<(usize, u32)> = vec![];
        for (t, tri) in mesh_tris.iter().enumerate() {
            let b = mesh_tri_body[t];
            for &v in tri {
                if first_body[v] == NONE32 {
                    first_body[v] = b;
                } else if first_body[v] != b {
                    extra.push((v, b));
                }
            }
        }
        extra.sort_unstable();
        extra.dedup();
        // Nodes in increasing tag order (the reader numbers them so already).
        let by_tag: Option<Vec<usize>> = if mesh.node_tags.windows(2).all(|w| w[0] < w[1]) {
            None
        } else {
            let mut o: Vec<usize> = (0..nn).collect();
            o.sort_unstable_by_key(|&v| mesh.node_tags[v]);
            Some(o)
        };
        let node_at = |i: usize| by_tag.as_ref().map(|o| o[i]).unwrap_or(i);
        let mut has_extra = vec![false; nn];
        for &(v, _) in &extra {
            has_extra[v] = true;
        }
        let extras_of = |v: usize| -> &[(usize, u32)] {
            if !has_extra[v] {
                return &[];
            }
            let s = extra.partition_point(|e| e.0 < v);
            let e = s + extra[s..].partition_point(|e| e.0 == v);
            &extra[s..e]
        };
        let mut body_ptr = vec![0usize; nbodies + 1];
        for &b in &first_body {
            if b != NONE32 {
                body_ptr[b as usize + 1] += 1;
            }
        }
        for &(_, b) in &extra {
            body_ptr[b as usize + 1] += 1;
        }
        for b in 0..nbodies {
            body_ptr[b + 1] += body_ptr[b];
        }
        let npts = body_ptr[nbodies];
        let mut fill = body_ptr.clone();
        let mut point_node = vec![0usize; npts];
        let mut point_body = vec![0u32; npts];
        let mut copy_ptr = vec![0usize; nn + 1];
        for i in 0..nn {
            let v = node_at(i);
            let b0 = first_body[v];
            if b0 == NONE32 {
                continue;
            }
            let ex = extras_of(v);
            copy_ptr[v + 1] = 1 + ex.len();
            for b in std::iter::once(b0).chain(ex.iter().map(|e| e.1)) {
                let p = fill[b as usize];
                fill[b as usize] += 1;
                point_node[p] = v;
                point_body[p] = b;
            }
        }
        drop(first_body);
        drop(extra);
        for v in 0..nn {
            copy_ptr[v + 1] += copy_ptr[v];
        }
        // Copies of a node in point order (= body order).
        let mut cfill = copy_ptr.clone();
        let mut copy_list = vec![(0u32, 0usize); npts];
        for (p, (&v, &b)) in point_node.iter().zip(&point_body).enumerate() {
            copy_list[cfill[v]] = (b, p);
            cfill[v] += 1;
        }
        drop(cfill);
        let points: Vec<[f64; 2]> = point_node.iter().map(|&v| mesh.nodes[v]).collect();
        let mut topo = Topology {
            points,
            point_node,
            point_body,
            triangles: vec![],
            tri_body: mesh_tri_body.clone(),
            tri_material,
            material_names,
            nbodies,
            copy_ptr,
            copy_list,
            edges,
            mesh_tri_body,
            mesh_tris,
            contact: vec![],
            contact_segments: vec![],
            interface_names,
        };
        // The point of each node with one copy (most of them), to map the
        // triangles without searching the copies.
        let single: Vec<u32> = (0..nn)
            .map(|v| match topo.copies(v) {
                [(_, p)] => *p as u32,
                _ => NONE32,
            })
            .collect();
        topo.triangles = topo
            .mesh_tris
            .iter()
            .zip(&topo.mesh_tri_body)
            .map(|(tri, &b)| {
                tri.map(|v| match single[v] {
                    NONE32 => topo.point(v, b).unwrap_or(0),
                    p => p as usize,
                })
            })
            .collect();
        drop(single);

        lap.lap("points");
        topo.build_conforming(mesh, problem, &contact_edges)?;
        lap.lap("conforming contact");
        topo.build_nonmatching(mesh, problem)?;
        lap.lap("non-matching contact");
        Ok(topo)
    }

    /// Node-to-node rows on conforming curves (methods.md §2.6–2.7).
    fn build_conforming(
        &mut self,
        mesh: &Mesh,
        problem: &Problem,
        contact_edges: &[((usize, usize), u32)],
    ) -> Result<(), FemError> {
        let err = |msg: String| FemError::new(&problem.path, msg);
        let kind_of: Vec<NormalKind> = problem
            .file
            .contact
            .iter()
            .filter(|c| c.on.is_some())
            .map(|c| c.normals)
            .collect();
        // Per (node, k, l): normals of the segments, tributary length, interface.
        struct Acc {
            normals: Vec<([f64; 2], f64)>,
            interface: u32,
        }
        let mut acc: HashMap<(usize, u32, u32), Acc> = HashMap::new();
        let mut seg_info = vec![];
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
            for v in [a, b] {
                let e = acc.entry((v, k, l)).or_insert(Acc {
                    normals: vec![],
                    interface: id,
                });
                e.normals.push((n, len / 2.0));
            }
            seg_info.push((a, b, k, l, n, id));
        }
        let mut keys: Vec<(usize, u32, u32)> = acc.keys().copied().collect();
        keys.sort_unstable_by_key(|&(v, k, l)| (k, l, mesh.node_tags[v]));
        // rows_at[(node,k,l)] = rows (with their segment normal for definition A)
        let mut rows_at: HashMap<(usize, u32, u32), Vec<(usize, [f64; 2])>> = HashMap::new();
        for key in keys {
            let (v, k, l) = key;
            let a = &acc[&key];
            let first = self.point(v, k).unwrap_or(0);
            let second = self.point(v, l).unwrap_or(0);
            let kind = kind_of
                .get(a.interface as usize)
                .copied()
                .unwrap_or_default();
            let trib: f64 = a.normals.iter().map(|x| x.1).sum();
            let mut normals: Vec<([f64; 2], f64)> = vec![];
            match kind {
                NormalKind::Averaged => {
                    let s = a
                        .normals
                        .iter()
                        .fold([0.0, 0.0], |s, (n, _)| [s[0] + n[0], s[1] + n[1]]);
                    let len = (s[0] * s[0] + s[1] * s[1]).sqrt();
                    if !(len > 1e-12) {
                        return Err(err(format!(
                            "contact curve \"{}\": the normals at node {} cancel (a cusp); use normals = \"segment\"",
                            self.interface_names[a.interface as usize], mesh.node_tags[v]
                        )));
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
            for (n, t) in normals {
                let r = self.contact.len();
                self.contact.push(ContactRow {
                    kind: RowKind::Conforming,
                    first,
                    second: [(second, 1.0), (second, 0.0)],
                    normal: n,
                    gap0: 0.0,
                    trib: t,
                    interface: a.interface,
                });
                rows_at.entry(key).or_default().push((r, n));
            }
        }
        for (a, b, k, l, n, _) in seg_info {
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

    /// Node-to-segment rows of non-matching pairs (methods.md §7).
    fn build_nonmatching(&mut self, mesh: &Mesh, problem: &Problem) -> Result<(), FemError> {
        let err = |msg: String| FemError::new(&problem.path, msg);
        for (ci, c) in problem.file.contact.iter().enumerate() {
            let (Some(sname), Some(mname)) = (&c.slave, &c.master) else {
                continue;
            };
            let what = format!("[[contact]] #{}", ci + 1);
            let sg = curve_group(mesh, sname, &what, &problem.path)?;
            let mg = curve_group(mesh, mname, &what, &problem.path)?;
            let id = self.interface_names.len() as u32;
            self.interface_names.push(format!("{sname}->{mname}"));
            // Master segments with their owner body and outward normal.
            let mut msegs = vec![];
            for &li in &mg.elements {
                let [a, b] = mesh.lines[li];
                let ts = self.edge_triangles(a, b);
                if ts.len() != 1 {
                    return Err(err(format!(
                        "{what}: master curve \"{mname}\" segment ({}, {}) is not on the boundary of one body",
                        mesh.node_tags[a], mesh.node_tags[b]
                    )));
                }
                let body = self.mesh_tri_body[ts[0]];
                let n = self.outward_normal(mesh, ts[0], a, b);
                msegs.push((a, b, body, n));
            }
            let tree = SegmentTree::build(mesh, &msegs);
            let mut stack = vec![];
            // Slave nodes with owner body and tributary length.
            let mut slave: HashMap<(usize, u32), f64> = HashMap::new();
            let mut slave_segs = vec![];
            for &li in &sg.elements {
                let [a, b] = mesh.lines[li];
                let ts = self.edge_triangles(a, b);
                if ts.len() != 1 {
                    return Err(err(format!(
                        "{what}: slave curve \"{sname}\" segment ({}, {}) is not on the boundary of one body",
                        mesh.node_tags[a], mesh.node_tags[b]
                    )));
                }
                let body = self.mesh_tri_body[ts[0]];
                let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
                let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
                *slave.entry((a, body)).or_insert(0.0) += len / 2.0;
                *slave.entry((b, body)).or_insert(0.0) += len / 2.0;
                slave_segs.push(((a, body), (b, body)));
            }
            let mut snodes: Vec<((usize, u32), f64)> = slave.into_iter().collect();
            snodes.sort_unstable_by_key(|((v, b), _)| (*b, mesh.node_tags[*v]));
            let mut row_of: HashMap<(usize, u32), usize> = HashMap::new();
            let mut skipped = 0usize;
            let tol_pen = 1e-6;
            for ((v, sb), trib) in snodes {
                let xs = mesh.nodes[v];
                // Nearest master segment whose orthogonal projection falls on it.
                let best = tree.nearest(mesh, &msegs, xs, sb, &mut stack);
                let Some((_, si, xi)) = best else {
                    skipped += 1;
                    continue;
                };
                let (a, b, mb, n) = msegs[si];
                let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
                let p = [pa[0] + xi * (pb[0] - pa[0]), pa[1] + xi * (pb[1] - pa[1])];
                let g = n[0] * (xs[0] - p[0]) + n[1] * (xs[1] - p[1]);
                let seg_len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
                if g < -tol_pen * seg_len {
                    return Err(err(format!(
                        "{what}: slave node {} of \"{sname}\" penetrates master \"{mname}\" by {:.3e} (initial gap must be >= 0)",
                        mesh.node_tags[v], -g
                    )));
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
                    gap0: g.max(0.0),
                    trib,
                    interface: id,
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
            for (sa, sb) in slave_segs {
                if let (Some(&ra), Some(&rb)) = (row_of.get(&sa), row_of.get(&sb)) {
                    self.contact_segments.push([ra, rb]);
                }
            }
        }
        Ok(())
    }
}

/// A master segment of a non-matching pair: nodes, owner body, outward normal.
type MasterSeg = (usize, usize, u32, [f64; 2]);

/// Orthogonal projection of `xs` on the segment (pa, pb): (distance, ξ) if
/// ξ ∈ [−1e-9, 1 + 1e-9] (ξ clamped to [0, 1]).
#[inline]
fn project_on_segment(xs: [f64; 2], pa: [f64; 2], pb: [f64; 2]) -> Option<(f64, f64)> {
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
    lo: [f64; 2],
    hi: [f64; 2],
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
        let mid: Vec<[f64; 2]> = segs
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
    fn box_dist(&self, ni: usize, x: [f64; 2]) -> f64 {
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
        xs: [f64; 2],
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
    xs: [f64; 2],
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

/// The physical curve `name` or a clear error.
pub fn curve_group<'m>(
    mesh: &'m Mesh,
    name: &str,
    what: &str,
    toml: &std::path::Path,
) -> Result<&'m crate::mesh::PhysicalGroup, FemError> {
    match mesh.group_any(name) {
        Some(g) if g.dim == 1 => Ok(g),
        Some(g) => Err(FemError::new(
            toml,
            format!(
                "{what}: \"{name}\" is a physical {} in {}, expected a curve",
                dim_name(g.dim),
                mesh.path.display()
            ),
        )),
        None => Err(FemError::new(
            toml,
            format!(
                "{what}: no physical group named \"{name}\" in {} (curves: {})",
                mesh.path.display(),
                group_names(mesh, 1)
            ),
        )),
    }
}

pub fn dim_name(d: u8) -> &'static str {
    match d {
        0 => "point",
        1 => "curve",
        2 => "surface",
        _ => "volume",
    }
}

pub fn group_names(mesh: &Mesh, dim: u8) -> String {
    let v: Vec<String> = mesh
        .groups
        .iter()
        .filter(|g| g.dim == dim)
        .map(|g| format!("\"{}\"", g.name))
        .collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

/// Union-find over fewer than 2^32 elements; a set's root is its lowest
/// element.
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }
    fn find(&mut self, x: usize) -> usize {
        let mut x = x as u32;
        while self.parent[x as usize] != x {
            let g = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = g;
            x = g;
        }
        x as usize
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb) as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> Vec<(Problem, Mesh)> {
        crate::shipped_examples()
            .into_iter()
            .map(|(_, problem, mesh)| (problem, mesh))
            .collect()
    }

    /// The former edge map (a HashMap filled in triangle order).
    fn edge_map(
        tris: &[[usize; 3]],
    ) -> Result<HashMap<(usize, usize), Vec<usize>>, (usize, usize)> {
        let mut m: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (t, tri) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = m.entry((a.min(b), a.max(b))).or_default();
                if e.len() == 2 {
                    return Err((a, b));
                }
                e.push(t);
            }
        }
        Ok(m)
    }

    fn check_edges(nn: usize, tris: &[[usize; 3]]) {
        let reference = edge_map(tris);
        let edges = Edges::build(nn, tris);
        match (reference, edges) {
            (Err(a), Err(b)) => assert_eq!(a, b),
            (Ok(m), Ok(e)) => {
                assert_eq!(m.len(), e.len());
                for (&(a, b), ts) in &m {
                    let i = e.find(a, b).unwrap();
                    assert_eq!(e.find(b, a), Some(i));
                    let got: Vec<usize> = e.tri[i]
                        .iter()
                        .filter(|&&x| x != NONE32)
                        .map(|&x| x as usize)
                        .collect();
                    assert_eq!(&got, ts);
                }
            }
            (r, e) => panic!("{:?} vs {:?}", r.err(), e.err()),
        }
    }

    #[test]
    fn edges_match_a_hash_map() {
        for (_, mesh) in shipped() {
            check_edges(mesh.nodes.len(), &mesh.triangles);
        }
        // Random small "meshes" with shared and overfull edges.
        let mut s = 0x1234_5678_9abc_def1u64;
        let mut next = |n: u64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % n) as usize
        };
        for case in 0..2000 {
            let nn = 3 + next(8);
            let nt = 1 + next(12);
            let tris: Vec<[usize; 3]> = (0..nt)
                .map(|_| loop {
                    let t = [next(nn as u64), next(nn as u64), next(nn as u64)];
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        break t;
                    }
                })
                .collect();
            check_edges(nn, &tris);
            let _ = case;
        }
    }

    fn check_nearest(mesh: &Mesh, segs: &[MasterSeg], queries: &[([f64; 2], u32)]) -> usize {
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
        for (problem, mesh) in shipped() {
            let topo = Topology::build(&mesh, &problem).unwrap();
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
                let queries: Vec<([f64; 2], u32)> = mesh
                    .nodes
                    .iter()
                    .flat_map(|&x| [(x, 0), (x, 1), (x, NONE32)])
                    .collect();
                assert!(check_nearest(&mesh, &segs, &queries) > 0 || segs.is_empty());
                all.extend(segs);
            }
            // All curves at once (overlapping and duplicated segments).
            let queries: Vec<([f64; 2], u32)> = mesh.nodes.iter().map(|&x| (x, NONE32)).collect();
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
            let mut mesh = Mesh::default();
            mesh.nodes = (0..nn)
                .map(|_| [next(grid) as f64 * scale, next(grid) as f64 * scale])
                .collect();
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
            let mut queries: Vec<([f64; 2], u32)> = (0..200)
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
