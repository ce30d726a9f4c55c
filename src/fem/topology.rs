//! From a Gmsh mesh and a problem file to bodies, node copies and contact rows.
//!
//! A body is a set of triangles connected through edges after the mesh is cut
//! along the conforming contact curves (problem-format.md). Every (node, body)
//! pair becomes one *point* (nodes on an interface appear once per side);
//! points are numbered body after body (methods.md §2.3), bodies in the order
//! of their lowest node tag.

use super::FemError;
use crate::mesh::Mesh;
use crate::model::{NormalKind, Problem};
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
    /// Sorted mesh-node edge → up to two triangles (mesh triangle indices).
    edge_tris: HashMap<(usize, usize), [usize; 2]>,
    /// Mesh triangle → its body.
    mesh_tri_body: Vec<u32>,
    /// Mesh triangles, oriented counter-clockwise.
    mesh_tris: Vec<[usize; 3]>,
    pub contact: Vec<ContactRow>,
    /// Segments between contact rows (for the contact VTU).
    pub contact_segments: Vec<[usize; 2]>,
    pub interface_names: Vec<String>,
}

const NONE: usize = usize::MAX;

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
        let key = if a < b { (a, b) } else { (b, a) };
        self.edge_tris
            .get(&key)
            .map(|t| t.iter().copied().filter(|&x| x != NONE).collect())
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

        // --- orientation and degenerate triangles
        let mut mesh_tris = mesh.triangles.clone();
        let mut hmax: f64 = 0.0;
        for tri in &mesh_tris {
            for k in 0..3 {
                let (a, b) = (mesh.nodes[tri[k]], mesh.nodes[tri[(k + 1) % 3]]);
                hmax = hmax.max(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
            }
        }
        let signs: Vec<f64> = mesh_tris
            .iter()
            .map(|t| super::element::area2(&[mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]]]))
            .collect();
        for (t, &a) in signs.iter().enumerate() {
            let tri = mesh_tris[t];
            let e2 = (0..3)
                .map(|k| {
                    let (a, b) = (mesh.nodes[tri[k]], mesh.nodes[tri[(k + 1) % 3]]);
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
        }

        // --- edges → triangles
        let mut edge_tris: HashMap<(usize, usize), [usize; 2]> = HashMap::with_capacity(2 * nt);
        for (t, tri) in mesh_tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = if a < b { (a, b) } else { (b, a) };
                let e = edge_tris.entry(key).or_insert([NONE, NONE]);
                if e[0] == NONE {
                    e[0] = t;
                } else if e[1] == NONE {
                    e[1] = t;
                } else {
                    return Err(err(format!(
                        "{mpath}: edge ({}, {}) is shared by more than two triangles (overlapping mesh?)",
                        mesh.node_tags[a], mesh.node_tags[b]
                    )));
                }
            }
        }

        // --- conforming contact edges
        let mut interface_names: Vec<String> = vec![];
        let mut contact_edge: HashMap<(usize, usize), u32> = HashMap::new();
        for (ci, c) in problem.file.contact.iter().enumerate() {
            if let Some(on) = &c.on {
                let g = curve_group(mesh, on, &format!("[[contact]] #{}", ci + 1), &problem.path)?;
                let id = interface_names.len() as u32;
                interface_names.push(on.clone());
                for &l in &g.elements {
                    let [a, b] = mesh.lines[l];
                    let key = if a < b { (a, b) } else { (b, a) };
                    contact_edge.insert(key, id);
                }
            }
        }

        // --- bodies: union-find over edges not on contact curves
        let mut uf = UnionFind::new(nt);
        for (key, ts) in &edge_tris {
            if ts[1] != NONE && !contact_edge.contains_key(key) {
                uf.union(ts[0], ts[1]);
            }
        }
        let mut root_min_tag: HashMap<usize, u64> = HashMap::new();
        for (t, tri) in mesh_tris.iter().enumerate() {
            let r = uf.find(t);
            let m = tri.iter().map(|&v| mesh.node_tags[v]).min().unwrap_or(0);
            let e = root_min_tag.entry(r).or_insert(u64::MAX);
            *e = (*e).min(m);
        }
        let mut roots: Vec<(u64, usize)> = root_min_tag.iter().map(|(&r, &m)| (m, r)).collect();
        roots.sort_unstable();
        let body_of_root: HashMap<usize, u32> = roots
            .iter()
            .enumerate()
            .map(|(i, &(_, r))| (r, i as u32))
            .collect();
        let mesh_tri_body: Vec<u32> = (0..nt).map(|t| body_of_root[&uf.find(t)]).collect();
        let nbodies = roots.len();

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
                    "{mpath}: triangle {} is inverted (its orientation differs from the rest of body {b})",
                    mesh.triangle_tags[t]
                )));
            }
            if !majority_pos {
                mesh_tris[t].swap(1, 2);
            }
        }

        // --- points: (body, node tag) order
        let mut pairs: Vec<(u32, usize)> = Vec::with_capacity(3 * nt);
        for (t, tri) in mesh_tris.iter().enumerate() {
            for &v in tri {
                pairs.push((mesh_tri_body[t], v));
            }
        }
        pairs.sort_unstable_by_key(|&(b, v)| (b, mesh.node_tags[v]));
        pairs.dedup();
        let mut copy_count = vec![0usize; nn + 1];
        for &(_, v) in &pairs {
            copy_count[v + 1] += 1;
        }
        for i in 0..nn {
            copy_count[i + 1] += copy_count[i];
        }
        let copy_ptr = copy_count.clone();
        let mut fill = copy_count;
        let mut copy_list = vec![(0u32, 0usize); pairs.len()];
        let mut points = Vec::with_capacity(pairs.len());
        let mut point_node = Vec::with_capacity(pairs.len());
        let mut point_body = Vec::with_capacity(pairs.len());
        for (p, &(b, v)) in pairs.iter().enumerate() {
            copy_list[fill[v]] = (b, p);
            fill[v] += 1;
            points.push(mesh.nodes[v]);
            point_node.push(v);
            point_body.push(b);
        }
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
            edge_tris,
            mesh_tri_body,
            mesh_tris: mesh_tris.clone(),
            contact: vec![],
            contact_segments: vec![],
            interface_names,
        };
        topo.triangles = mesh_tris
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let b = topo.mesh_tri_body[t];
                tri.map(|v| topo.point(v, b).unwrap_or(0))
            })
            .collect();

        topo.build_conforming(mesh, problem, &contact_edge)?;
        topo.build_nonmatching(mesh, problem)?;
        Ok(topo)
    }

    /// Node-to-node rows on conforming curves (methods.md §2.6–2.7).
    fn build_conforming(
        &mut self,
        mesh: &Mesh,
        problem: &Problem,
        contact_edge: &HashMap<(usize, usize), u32>,
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
        let mut edges: Vec<((usize, usize), u32)> =
            contact_edge.iter().map(|(k, v)| (*k, *v)).collect();
        edges.sort_unstable();
        let mut seg_info = vec![];
        for &((a, b), id) in &edges {
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
                let mut best: Option<(f64, usize, f64)> = None;
                for (si, &(a, b, mb, _)) in msegs.iter().enumerate() {
                    if mb == sb {
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

struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n).collect(),
        }
    }
    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}
