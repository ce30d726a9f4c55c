//! From a Gmsh mesh and a problem file to bodies and points (docs/methods.md
//! §1.1, §2.1, §2.3).
//!
//! A body is a set of triangles connected through edges after the mesh is cut
//! along the conforming contact curves (docs/problem-format.md). Every
//! (node, body) pair becomes one *point* (nodes on an interface appear once
//! per side); points are numbered body after body, bodies in the order of
//! their lowest node tag. The contact rows on points come from `pairs.rs`;
//! the physical groups are looked up here, with errors that name them.

pub use super::contact::{ContactRow, RowKind};
use super::edges::{Edges, UnionFind, NONE32};
use super::element::ElementKind;
use super::element::{Point, Vector};
use super::FemError;
use crate::mesh::Mesh;
use crate::problem::{Contact, ContactPair, Material};
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Debug, Clone, Default)]
pub struct Topology {
    /// Coordinates of each point.
    pub points: Vec<Point>,
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
    pub(super) mesh_tri_body: Vec<u32>,
    /// Mesh triangles, oriented counter-clockwise.
    mesh_tris: Vec<[usize; 3]>,
    pub contact: Vec<ContactRow>,
    /// Segments between contact rows (for the contact VTU).
    pub contact_segments: Vec<[usize; 2]>,
    pub interface_names: Vec<String>,
    /// The rows of each interface (same order as `interface_names`):
    /// conforming, node-to-segment or mortar; the outputs record it.
    pub interface_kinds: Vec<super::contact::RowKind>,
    /// The kind of model: the measure of the triangles and of the contact
    /// rows' tributary weights (docs/design.md §"Element kinds").
    pub kind: super::element::ElementKind,
}

/// A point of a physical group: (point, mesh node, Some((segment node a,
/// b, owner mesh triangle)) on a curve, None on a physical point).
pub(super) type GroupPoint = (usize, usize, Option<(usize, usize, usize)>);

/// The points of a mesh cut into bodies: each point's node and body, and
/// each node's copies (body, point) as CSR.
struct Points {
    point_node: Vec<usize>,
    point_body: Vec<u32>,
    copy_ptr: Vec<usize>,
    copy_list: Vec<(u32, usize)>,
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
    pub fn outward_normal(&self, mesh: &Mesh, t: usize, a: usize, b: usize) -> Vector {
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

    /// Build the topology of a model of kind `kind` whose `[materials]`
    /// are `materials` and `[[contact]]` entries `contact`: checks
    /// materials, orientation, contact curves; messages name `path`, the
    /// TOML file.
    pub fn build(
        mesh: &Mesh,
        path: &Path,
        kind: ElementKind,
        materials: &BTreeMap<String, Material>,
        contact: &[Contact],
    ) -> Result<Topology, FemError> {
        let err = |msg: String| FemError::new(path, msg);
        let mpath = mesh.path.display().to_string();
        let (nt, nn) = (mesh.triangles.len(), mesh.nodes.len());
        let mut lap = super::Lap::new("Topology::build");
        let (material_names, tri_material) = material_of_triangles(mesh, path, materials)?;
        lap.lap("materials");
        let signs = signed_areas(mesh, path)?;
        if nn >= NONE32 as usize || nt >= NONE32 as usize / 3 {
            return Err(err(format!(
                "{mpath}: {nn} nodes and {nt} triangles: more than this program indexes (2^32 - 1 nodes, (2^32 - 1) / 3 triangles)"
            )));
        }
        lap.lap("areas");
        let edges = Edges::build(nn, &mesh.triangles).map_err(|(a, b)| {
            err(format!(
                "{mpath}: edge ({}, {}) is shared by more than two triangles (overlapping mesh?)",
                mesh.node_tags[a], mesh.node_tags[b]
            ))
        })?;
        lap.lap("edges");
        let (interface_names, contact_edges) = conforming_edges(mesh, path, contact)?;
        let (mesh_tri_body, nbodies) = bodies(mesh, &edges, &contact_edges);
        lap.lap("bodies");
        let mut mesh_tris = mesh.triangles.clone();
        orient(
            mesh,
            path,
            &signs,
            &mesh_tri_body,
            nbodies,
            &mut mesh_tris,
            |t| {
                material_names
                    .get(tri_material[t] as usize)
                    .map(String::as_str)
                    .unwrap_or("?")
            },
        )?;
        drop(signs);
        lap.lap("orientation");
        let p = points(mesh, &mesh_tris, &mesh_tri_body, nbodies);
        let mut topo = Topology {
            points: p.point_node.iter().map(|&v| mesh.nodes[v]).collect(),
            point_node: p.point_node,
            point_body: p.point_body,
            triangles: vec![],
            tri_body: mesh_tri_body.clone(),
            tri_material,
            material_names,
            nbodies,
            copy_ptr: p.copy_ptr,
            copy_list: p.copy_list,
            edges,
            mesh_tri_body,
            mesh_tris,
            contact: vec![],
            contact_segments: vec![],
            interface_kinds: vec![super::contact::RowKind::Conforming; interface_names.len()],
            interface_names,
            kind,
        };
        topo.triangles = topo.point_triangles();
        lap.lap("points");
        topo.build_conforming(mesh, path, contact, &contact_edges)?;
        lap.lap("conforming contact");
        topo.build_nonmatching(mesh, path, materials, contact)?;
        lap.lap("non-matching contact");
        Ok(topo)
    }

    /// The mesh triangles in point indices (each vertex's copy in the
    /// triangle's body).
    fn point_triangles(&self) -> Vec<[usize; 3]> {
        // The point of each node with one copy (most of them), to map the
        // triangles without searching the copies.
        let single: Vec<u32> = (0..self.copy_ptr.len() - 1)
            .map(|v| match self.copies(v) {
                [(_, p)] => *p as u32,
                _ => NONE32,
            })
            .collect();
        self.mesh_tris
            .iter()
            .zip(&self.mesh_tri_body)
            .map(|(tri, &b)| {
                tri.map(|v| match single[v] {
                    NONE32 => self.point(v, b).unwrap_or(0),
                    p => p as usize,
                })
            })
            .collect()
    }

    /// Each body's name: the physical surface names of its triangles in order
    /// of first appearance, "+"-joined (one name unless a body spans several),
    /// with " #b" when bodies share a name.
    pub fn body_names(&self) -> Vec<String> {
        let mut names: Vec<Vec<u32>> = vec![vec![]; self.nbodies];
        for (&b, &m) in self.tri_body.iter().zip(&self.tri_material) {
            let v = &mut names[b as usize];
            if !v.contains(&m) {
                v.push(m);
            }
        }
        let joined: Vec<String> = names
            .iter()
            .map(|ms| {
                ms.iter()
                    .map(|&m| self.material_names[m as usize].as_str())
                    .collect::<Vec<_>>()
                    .join("+")
            })
            .collect();
        // Bodies of one material share a name: the body number tells them apart.
        joined
            .iter()
            .enumerate()
            .map(|(b, n)| {
                if joined.iter().filter(|m| *m == n).count() > 1 {
                    format!("{n} #{b}")
                } else {
                    n.clone()
                }
            })
            .collect()
    }

    /// The points of group `name` (a curve or a point): (point, mesh node,
    /// Some((segment node a, b, owner triangle)) for a curve). On a curve,
    /// the copies owned by each segment's triangles; `what` names the TOML
    /// entry in messages.
    pub(super) fn group_points(
        &self,
        mesh: &Mesh,
        path: &Path,
        name: &str,
        what: &str,
    ) -> Result<Vec<GroupPoint>, FemError> {
        let err = |msg: String| FemError::new(path, msg);
        let Some(g) = mesh.group_any(name) else {
            return Err(err(format!(
                "{what}: no physical group named \"{name}\" in {} (curves: {}; points: {})",
                mesh.path.display(),
                group_names(mesh, 1),
                group_names(mesh, 0)
            )));
        };
        let mut out = vec![];
        match g.dim {
            0 => {
                for &e in &g.elements {
                    let v = mesh.points[e];
                    for &(_, p) in self.copies(v) {
                        out.push((p, v, None));
                    }
                }
            }
            1 => {
                for &e in &g.elements {
                    let [a, b] = mesh.lines[e];
                    let ts = self.edge_triangles(a, b);
                    if ts.is_empty() {
                        return Err(err(format!(
                            "{what}: segment ({}, {}) of curve \"{name}\" is not an edge of any triangle",
                            mesh.node_tags[a], mesh.node_tags[b]
                        )));
                    }
                    for &t in &ts {
                        let body = self.mesh_triangle_body(t);
                        for v in [a, b] {
                            if let Some(p) = self.point(v, body) {
                                out.push((p, v, Some((a, b, t))));
                            }
                        }
                    }
                }
            }
            d => {
                return Err(err(format!(
                    "{what}: \"{name}\" is a physical {} in {}, expected a curve or a point",
                    dim_name(d),
                    mesh.path.display()
                )))
            }
        }
        Ok(out)
    }
}

/// The material of each triangle (an index into the names, in the order of
/// `[materials]`): every triangle needs exactly one.
fn material_of_triangles(
    mesh: &Mesh,
    path: &Path,
    materials: &BTreeMap<String, Material>,
) -> Result<(Vec<String>, Vec<u32>), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let mpath = mesh.path.display().to_string();
    let mut material_names: Vec<String> = vec![];
    let mut tri_material = vec![u32::MAX; mesh.triangles.len()];
    for name in materials.keys() {
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
    Ok((material_names, tri_material))
}

/// Twice the signed area of each mesh triangle; a degenerate one is an error.
fn signed_areas(mesh: &Mesh, path: &Path) -> Result<Vec<f64>, FemError> {
    let mut signs: Vec<f64> = Vec::with_capacity(mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let x = tri.map(|v| mesh.nodes[v]);
        let a = super::element::area2(&x);
        let e2 = (0..3)
            .map(|k| {
                let (a, b) = (x[k], x[(k + 1) % 3]);
                (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
            })
            .fold(0.0f64, f64::max);
        let proper = a.abs() > 1e-12 * e2; // false for NaN too
        if !proper {
            return Err(FemError::new(
                path,
                format!(
                    "{}: triangle {} is degenerate (area {:.3e})",
                    mesh.path.display(),
                    mesh.triangle_tags[t],
                    a / 2.0
                ),
            ));
        }
        signs.push(a);
    }
    Ok(signs)
}

/// The interface names of the conforming `[[contact]] on` curves and their
/// segments as sorted (a < b) node pairs with their interface. A segment in
/// two `[[contact]]` curves is refused: one entry's keys (normals, friction)
/// would silently give way to the other's there (docs/problem-format.md §5).
#[allow(clippy::type_complexity)]
fn conforming_edges(
    mesh: &Mesh,
    path: &Path,
    contact: &[Contact],
) -> Result<(Vec<String>, Vec<((usize, usize), u32)>), FemError> {
    let mut interface_names: Vec<String> = vec![];
    // The [[contact]] entry of each interface.
    let mut entry: Vec<usize> = vec![];
    let mut contact_edges: Vec<((usize, usize), u32)> = vec![];
    for (ci, c) in contact.iter().enumerate() {
        if let ContactPair::Conforming { on, .. } = &c.pair {
            let g = curve_group(mesh, on, &format!("[[contact]] #{}", ci + 1), path)?;
            let id = interface_names.len() as u32;
            interface_names.push(on.clone());
            entry.push(ci);
            for &l in &g.elements {
                let [a, b] = mesh.lines[l];
                let key = if a < b { (a, b) } else { (b, a) };
                contact_edges.push((key, id));
            }
        }
    }
    // Stable sort by key; a group may list a segment twice, two groups may not.
    contact_edges.sort_by_key(|e| e.0);
    let mut dedup: Vec<((usize, usize), u32)> = Vec::with_capacity(contact_edges.len());
    for e in contact_edges {
        match dedup.last_mut() {
            Some(last) if last.0 == e.0 && last.1 == e.1 => {}
            Some(last) if last.0 == e.0 => {
                let c = contact;
                let (i, j) = (entry[last.1 as usize], entry[e.1 as usize]);
                let ((a, b), (i, j)) = (e.0, (i.min(j), i.max(j)));
                return Err(FemError::new(
                    path,
                    format!(
                        "[[contact]] #{} ({}) and #{} ({}) overlap: both hold the segment ({}, {}); give each segment of a contact curve to one [[contact]]",
                        i + 1,
                        c[i].keys(),
                        j + 1,
                        c[j].keys(),
                        mesh.node_tags[a],
                        mesh.node_tags[b]
                    ),
                ));
            }
            _ => dedup.push(e),
        }
    }
    Ok((interface_names, dedup))
}

/// The body of each mesh triangle and the number of bodies: triangles
/// joined through edges not on a conforming contact curve, numbered as
/// [`cell_bodies`] does.
fn bodies(
    mesh: &Mesh,
    edges: &Edges,
    contact_edges: &[((usize, usize), u32)],
) -> (Vec<u32>, usize) {
    let mut on_contact = vec![false; edges.len()];
    for &((a, b), _) in contact_edges {
        if let Some(e) = edges.find(a, b) {
            on_contact[e] = true;
        }
    }
    let joined = edges
        .tri
        .iter()
        .enumerate()
        .filter(|&(e, ts)| ts[1] != NONE32 && !on_contact[e])
        .map(|(_, ts)| (ts[0] as usize, ts[1] as usize));
    cell_bodies(&mesh.triangles, &mesh.node_tags, joined)
}

/// The body of each cell (D + 1 nodes: triangles in 2D, tetrahedra in 3D)
/// and the number of bodies: the cells `joined` through a shared facet
/// (an edge in 2D, a face in 3D) are one body, and the bodies are numbered
/// in the order of (lowest node tag, lowest cell).
pub(super) fn cell_bodies<const N: usize>(
    cells: &[[usize; N]],
    node_tags: &[u64],
    joined: impl IntoIterator<Item = (usize, usize)>,
) -> (Vec<u32>, usize) {
    let nt = cells.len();
    let mut uf = UnionFind::new(nt);
    for (a, b) in joined {
        uf.union(a, b);
    }
    // Each set's root is its lowest cell.
    let mut root_min_tag = vec![u64::MAX; nt];
    let mut cell_root = vec![0u32; nt];
    for (t, cell) in cells.iter().enumerate() {
        let r = uf.find(t);
        cell_root[t] = r as u32;
        let m = cell.iter().map(|&v| node_tags[v]).min().unwrap_or(0);
        root_min_tag[r] = root_min_tag[r].min(m);
    }
    drop(uf);
    let mut roots: Vec<(u64, usize)> = (0..nt)
        .filter(|&t| cell_root[t] as usize == t)
        .map(|r| (root_min_tag[r], r))
        .collect();
    drop(root_min_tag);
    roots.sort_unstable();
    let mut body_of_root = vec![u32::MAX; nt];
    for (i, &(_, r)) in roots.iter().enumerate() {
        body_of_root[r] = i as u32;
    }
    let cell_body = cell_root
        .iter()
        .map(|&r| body_of_root[r as usize])
        .collect();
    (cell_body, roots.len())
}

/// Orientation: flip (in `tris`) a body whose triangles are all clockwise;
/// a mix is an inverted element (`surface(t)` names its physical surface).
fn orient<'a>(
    mesh: &Mesh,
    path: &Path,
    signs: &[f64],
    tri_body: &[u32],
    nbodies: usize,
    tris: &mut [[usize; 3]],
    surface: impl Fn(usize) -> &'a str,
) -> Result<(), FemError> {
    let mut pos = vec![0usize; nbodies];
    let mut neg = vec![0usize; nbodies];
    for (t, &a) in signs.iter().enumerate() {
        if a > 0.0 {
            pos[tri_body[t] as usize] += 1;
        } else {
            neg[tri_body[t] as usize] += 1;
        }
    }
    for (t, &a) in signs.iter().enumerate() {
        let b = tri_body[t] as usize;
        let majority_pos = pos[b] >= neg[b];
        if (a > 0.0) != majority_pos {
            return Err(FemError::new(
                path,
                format!(
                    "{}: triangle {} of physical surface '{}' is inverted (its orientation differs from the rest of body {b})",
                    mesh.path.display(),
                    mesh.triangle_tags[t],
                    surface(t)
                ),
            ));
        }
        if !majority_pos {
            tris[t].swap(1, 2);
        }
    }
    Ok(())
}

/// One point per (node, body) of the triangles, numbered body after body
/// and, within a body, in node tag order; a node's copies in body order.
fn points(mesh: &Mesh, tris: &[[usize; 3]], tri_body: &[u32], nbodies: usize) -> Points {
    let nn = mesh.nodes.len();
    // The distinct bodies of each node: the first one seen, and the rare
    // others (nodes on a contact curve) as sorted (node, body) pairs.
    let mut first_body = vec![NONE32; nn];
    let mut extra: Vec<(usize, u32)> = vec![];
    for (t, tri) in tris.iter().enumerate() {
        let b = tri_body[t];
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
    let mut fill = body_ptr;
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
    Points {
        point_node,
        point_body,
        copy_ptr,
        copy_list,
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

/// "point", "curve", "surface" or "volume": a group dimension in messages.
pub fn dim_name(d: u8) -> &'static str {
    match d {
        0 => "point",
        1 => "curve",
        2 => "surface",
        _ => "volume",
    }
}

/// The names of the physical groups of dimension `dim`, quoted, or "none".
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
