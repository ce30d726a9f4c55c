//! 3D models of P1 tetrahedra (issue 45), from a 3D mesh to the QP
//! min ½xᵀCx − xᵀd s.t. Ax ≤ g, on the
//! shared pieces — [`ElementKind::Solid`], [`PointDofs`]`<3>`, the
//! [`RigidMode`](super::element::RigidMode)s (`solid_modes`), the body detection (`topology::cell_bodies`), the
//! ordered parallel assembly (`stiffness::assemble`), the elimination of
//! the conditions (`conditions::eliminate`), the QP layer. Dirichlet
//! components, slip on plane surfaces, tractions (`pn` or `p`) on boundary
//! triangles, gravity, and contact (`contact3d`: the mesh cut along
//! conforming surfaces, node-to-node and node-to-surface rows; docs/
//! methods.md §11). What is still 2D-only is listed in docs/design.md
//! §"Adding a kind: solid 3D".

use super::conditions::{number, Cond, PointDofs};
use super::contact3d::{
    conforming_rows, dot, mirror_into_slip_planes, mortar_rows, nts_rows, reduced_rows, Row3,
};
use super::element::{ElementKind, MaterialMatrix, Point3, Vector3};
use super::pairs::STIFF_SLAVE;
use super::solid_modes::{near_kernel, rigid_kernel};
use super::stiffness::{assemble, Cells, Materials};
use super::topology::cell_bodies;
use super::FemError;
use crate::mesh::Mesh;
use crate::problem::{
    model_size, Contact, ContactPair, Discretization, Material, NormalKind, Prescribed,
};
use crate::qp::QpProblem;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// A traction on a boundary surface: `pn` along the outward normal
/// (negative pushes in) or a fixed vector `p` (N/m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolidTraction {
    Normal(f64),
    Vector(Vector3),
}

/// What a solid model is made of besides its mesh: the TOML sections of a
/// 3D problem, typed (docs/problem-format.md §"3D models").
#[derive(Debug, Clone, Default)]
pub struct SolidInput {
    /// Material of each Physical Volume.
    pub materials: BTreeMap<String, Material>,
    /// g (m/s²): the body force ρg.
    pub gravity: Vector3,
    /// `[[dirichlet]]`: the group and what it prescribes (components, or
    /// a turn about an axis).
    pub dirichlet: Vec<(String, Prescribed)>,
    /// `[[slip]]`: plane surfaces on which u·n = 0.
    pub slip: Vec<String>,
    /// `[[traction]]`: the surface and its load.
    pub traction: Vec<(String, SolidTraction)>,
    /// `[[contact]]`, the 2D contract on surfaces: `on` a surface between
    /// two bodies (the mesh is cut there), or `slave`/`master` surfaces of
    /// two bodies (mortar or node-to-surface rows), with friction
    /// (docs/methods.md §12).
    pub contact: Vec<Contact>,
}

/// The assembled solid model with the maps back to the mesh.
#[derive(Clone)]
pub struct SolidModel {
    pub kind: ElementKind,
    /// The points: one per mesh node and body of its tetrahedra (a node on
    /// a conforming contact surface has one in each of the two bodies),
    /// node after node; without a contact cut, the mesh nodes.
    pub points: Vec<Point3>,
    /// The mesh node of each point.
    pub point_node: Vec<usize>,
    /// Tetrahedra, positively oriented, in point indices.
    pub tets: Vec<[usize; 4]>,
    /// The material of each tetrahedron (index into `material_names`).
    pub tet_material: Vec<u32>,
    pub material_names: Vec<String>,
    /// u_p = u0_p + T_p ξ_p.
    pub dofs: Vec<PointDofs<3>>,
    pub qp: QpProblem,
    /// Nodal external forces (N), before the elimination.
    pub loads: Vec<Vector3>,
    /// The body of each point (tetrahedra joined through faces off the
    /// contact cut).
    pub point_body: Vec<u32>,
    pub nbodies: usize,
    /// The contact rows on points (docs/methods.md §11).
    pub contact: Vec<Row3>,
    /// The contact row of each QP row (rows on fixed points only are left
    /// out).
    pub qp_rows: Vec<usize>,
    /// Each `[[contact]]` entry's surfaces, `on` or `slave/master`.
    pub interface_names: Vec<String>,
    /// The body of each kernel vector.
    pub kernel_body: Vec<u32>,
}

impl super::Discrete<3> for SolidModel {
    fn dofs(&self) -> &[PointDofs<3>] {
        &self.dofs
    }
    fn qp(&self) -> &QpProblem {
        &self.qp
    }
    fn qp_mut(&mut self) -> &mut QpProblem {
        &mut self.qp
    }
    fn tangential_displacement(&self, u: &[Vector3]) -> Vec<f64> {
        super::contact3d::friction::tangential_displacement(self, u)
    }
}

impl SolidModel {
    /// Full nodal displacements from the QP unknowns.
    pub fn displacements(&self, x: &[f64]) -> Vec<Vector3> {
        super::discrete::point_displacements(&self.dofs, x)
    }

    /// The contact pressure of each QP row from its multipliers λ: the
    /// slave point, λ / area (N/m²; docs/methods.md §11.2), and the row.
    pub fn contact_pressure(&self, lambda: &[f64]) -> Vec<(usize, f64, &Row3)> {
        self.qp_rows
            .iter()
            .zip(lambda)
            .map(|(&r, &l)| {
                let row = &self.contact[r];
                (row.slave, l / row.area, row)
            })
            .collect()
    }

    /// The six stresses (VTK's order) of every tetrahedron.
    pub fn stresses(&self, materials: &BTreeMap<String, Material>, u: &[Vector3]) -> Vec<[f64; 6]> {
        let d: Vec<MaterialMatrix> = self
            .material_names
            .iter()
            .map(|m| self.kind.material(&materials[m]))
            .collect();
        self.tets
            .iter()
            .zip(&self.tet_material)
            .map(|(t, &m)| {
                let ue: [f64; 12] = std::array::from_fn(|i| u[t[i / 3]][i % 3]);
                self.kind
                    .tet_stress(&t.map(|v| self.points[v]), &d[m as usize], &ue)
            })
            .collect()
    }
}

/// A condition r·u = v at a point (r need not be unit).
pub(super) type Cond3 = Cond<3>;

/// The condition r·u = v.
fn cond(r: Vector3, v: f64) -> Cond3 {
    Cond { r, v, src: 0 }
}

/// A face of the tetrahedra: the vertex opposite it in its first
/// tetrahedron, how many tetrahedra share it, the first one and the
/// second one if any.
type Face = (usize, u8, usize, Option<usize>);

/// The faces of the tetrahedra: sorted nodes → [`Face`], for the outward
/// normal of a boundary triangle, to tell an interior face and to join the
/// tetrahedra into bodies.
fn faces(tets: &[[usize; 4]]) -> HashMap<[usize; 3], Face> {
    let mut f: HashMap<[usize; 3], Face> = HashMap::with_capacity(4 * tets.len());
    for (t, tet) in tets.iter().enumerate() {
        for skip in 0..4 {
            let mut k: Vec<usize> = (0..4).filter(|&i| i != skip).map(|i| tet[i]).collect();
            k.sort_unstable();
            let e = f
                .entry([k[0], k[1], k[2]])
                .or_insert((tet[skip], 0, t, None));
            e.1 += 1;
            if e.1 == 2 {
                e.3 = Some(t);
            }
        }
    }
    f
}

/// A boundary triangle of a Physical Surface: its nodes, its points (the
/// copies in its body, which differ from the nodes only on a contact cut),
/// its body, the weight |F|/3 of each node, its outward unit normal and
/// its Gmsh tag (for messages).
#[derive(Debug, Clone, Copy)]
pub(super) struct Facet {
    pub(super) nodes: [usize; 3],
    pub(super) points: [usize; 3],
    pub(super) body: u32,
    pub(super) weight: f64,
    pub(super) normal: Vector3,
    pub(super) tag: u64,
}

/// A non-matching pair whose slave and master surfaces share a body is
/// refused, naming the body's Physical Volumes and how many of the master's
/// triangles lie on it (a master selected by a bounding box that also
/// takes the slave body's coplanar faces, say).
fn check_bodies(
    slave: &[Facet],
    master: &[Facet],
    what: &str,
    pair: &crate::problem::NonMatchingPair,
    body_volumes: &[Vec<&str>],
    path: &Path,
) -> Result<(), FemError> {
    let sb: std::collections::BTreeSet<u32> = slave.iter().map(|f| f.body).collect();
    let Some(b) = master.iter().map(|f| f.body).find(|b| sb.contains(b)) else {
        return Ok(());
    };
    let on = master.iter().filter(|f| f.body == b).count();
    let volumes = body_volumes
        .get(b as usize)
        .map(|v| v.join("\", \""))
        .unwrap_or_default();
    Err(FemError::new(
        path,
        format!(
            "{what}: slave \"{}\" and master \"{}\" both lie on body {} (Physical Volume(s) \"{volumes}\"; {on} of the master's {} triangles): a non-matching pair must join two bodies",
            pair.slave,
            pair.master,
            b + 1,
            master.len()
        ),
    ))
}

/// The points of the nodes: one per node and body of its tetrahedra, node
/// after node, bodies in increasing order (one per node without a contact
/// cut, in node order: the points are then the nodes).
struct Cut {
    /// The points of node v are `node_ptr[v]..node_ptr[v + 1]`.
    node_ptr: Vec<usize>,
    point_body: Vec<u32>,
}

impl Cut {
    /// The point of node `v` in body `b` (its first point if none is).
    fn point(&self, v: usize, b: u32) -> usize {
        let r = self.node_ptr[v]..self.node_ptr[v + 1];
        r.clone()
            .find(|&p| self.point_body[p] == b)
            .unwrap_or(r.start)
    }

    fn points(&self, v: usize) -> std::ops::Range<usize> {
        self.node_ptr[v]..self.node_ptr[v + 1]
    }
}

/// The outward unit normal of face `tri` of tetrahedron `tet` and the weight
/// |F|/3 of its nodes.
fn outward(points: &[Point3], tri: [usize; 3], tet: &[usize; 4]) -> (f64, Vector3) {
    let (w, n) = ElementKind::Solid.facet_weight(&tri.map(|v| points[v]));
    let opp = tet
        .iter()
        .copied()
        .find(|v| !tri.contains(v))
        .unwrap_or(tri[0]);
    let (x0, o) = (points[tri[0]], points[opp]);
    if dot(n, [o[0] - x0[0], o[1] - x0[1], o[2] - x0[2]]) > 0.0 {
        (w, n.map(|c| -c))
    } else {
        (w, n)
    }
}

/// The triangles of a Physical Surface `name` on the boundary of the
/// volume mesh; `what` names the TOML entry.
#[allow(clippy::too_many_arguments)]
fn surface(
    mesh: &Mesh,
    nodes: &[Point3],
    tets: &[[usize; 4]],
    tet_body: &[u32],
    cut: &Cut,
    faces: &HashMap<[usize; 3], Face>,
    path: &Path,
    name: &str,
    what: &str,
) -> Result<Vec<Facet>, FemError> {
    let Some(g) = mesh.group(name, 2) else {
        let other = mesh.group_any(name).map_or(String::new(), |g| {
            format!(" (it is a group of dimension {})", g.dim)
        });
        return Err(FemError::new(
            path,
            format!(
                "{what}: no Physical Surface \"{name}\" in {}{other}",
                mesh.path.display()
            ),
        ));
    };
    let mut out = vec![];
    for &t in &g.elements {
        let tri = mesh.triangles[t];
        let mut key = tri;
        key.sort_unstable();
        // The reader has checked that every triangle is a face; one inside
        // a body (two tetrahedra) is on no boundary.
        let Some(&(_, count, t0, _)) = faces.get(&key) else {
            continue;
        };
        if count == 2 {
            return Err(FemError::new(
                path,
                format!(
                    "{what}: triangle {} of \"{name}\" lies inside the volume mesh (two tetrahedra share it), not on its boundary",
                    mesh.triangle_tags[t]
                ),
            ));
        }
        let (weight, normal) = outward(nodes, tri, &tets[t0]);
        let body = tet_body[t0];
        out.push(Facet {
            nodes: tri,
            points: tri.map(|v| cut.point(v, body)),
            body,
            weight,
            normal,
            tag: mesh.triangle_tags[t],
        });
    }
    Ok(out)
}

/// The `[[contact]]` entry `c` as written, for messages.
fn contact_what(i: usize, c: &Contact) -> String {
    format!("[[contact]] #{} ({})", i + 1, c.keys())
}

/// What 3D contact does not have, refused naming the entry: one row per
/// triangle normal.
fn check_supported_contact(contact: &[Contact], path: &Path) -> Result<(), FemError> {
    for (i, c) in contact.iter().enumerate() {
        let what = contact_what(i, c);
        let no = |why: &str| Err(FemError::new(path, format!("{what}: {why}")));
        if let ContactPair::Conforming {
            normals: NormalKind::Segment,
            ..
        } = &c.pair
        {
            return no(
                "normals = \"segment\" is for curves (2D); a 3D surface has averaged normals",
            );
        }
    }
    Ok(())
}

/// A pair without `discretization`: mortar rows, unless the slave is more
/// than [`STIFF_SLAVE`] times stiffer than the master (the 2D rule and
/// warning, docs/methods.md §7.1).
fn default_discretization(
    slave: &[Facet],
    master: &[Facet],
    body_e: &[(f64, f64)],
    sname: &str,
    mname: &str,
    what: &str,
) -> Discretization {
    let e_slave = slave
        .iter()
        .map(|f| body_e[f.body as usize].0)
        .fold(f64::INFINITY, f64::min);
    let e_master = master
        .iter()
        .map(|f| body_e[f.body as usize].1)
        .fold(0.0, f64::max);
    if e_slave > STIFF_SLAVE * e_master {
        log::warn!(
            "{what}: slave \"{sname}\" (E = {e_slave:e}) is {:.0} times stiffer than master \"{mname}\" (E = {e_master:e}): node-to-surface rows, not the default mortar rows, whose multipliers oscillate on a stiff slave; make the softer body the slave for mortar rows, or write discretization = \"nts\"",
            e_slave / e_master
        );
        Discretization::Nts
    } else {
        Discretization::Mortar
    }
}

/// Build the solid model of a 3D `mesh` (docs/design.md §"Adding a kind:
/// solid 3D"): messages name the TOML file `path` and the group.
pub fn build(mesh: &Mesh, path: &Path, input: &SolidInput) -> Result<SolidModel, FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let kind = ElementKind::Solid;
    check_supported_contact(&input.contact, path)?;
    let nodes: Vec<Point3> = (0..mesh.nodes.len()).map(|i| mesh.node::<3>(i)).collect();
    // Materials of the tetrahedra through their Physical Volumes.
    let mut material_names: Vec<String> = vec![];
    let mut tet_material = vec![u32::MAX; mesh.tets.len()];
    for g in mesh.groups.iter().filter(|g| g.dim == 3) {
        if !input.materials.contains_key(&g.name) {
            continue;
        }
        let mi = material_names.len() as u32;
        material_names.push(g.name.clone());
        for &t in &g.elements {
            tet_material[t] = mi;
        }
    }
    if let Some(t) = tet_material.iter().position(|&m| m == u32::MAX) {
        return Err(err(format!(
            "{}: tetrahedron {} is in no Physical Volume named in [materials]",
            mesh.path.display(),
            mesh.tet_tags[t]
        )));
    }
    let mesh_tets = &mesh.tets;
    let nn = nodes.len();
    let fc = faces(mesh_tets);
    // The conforming contact surfaces cut the mesh (docs/methods.md
    // §11.1): their faces do not join tetrahedra into bodies.
    let mut cut_faces: HashMap<[usize; 3], (u32, usize)> = HashMap::new();
    let mut cut_tris: Vec<Vec<usize>> = vec![vec![]; input.contact.len()];
    for (i, c) in input.contact.iter().enumerate() {
        let ContactPair::Conforming { on, .. } = &c.pair else {
            continue;
        };
        let what = contact_what(i, c);
        let Some(g) = mesh.group(on, 2) else {
            return Err(err(format!(
                "{what}: no Physical Surface \"{on}\" in {}",
                mesh.path.display()
            )));
        };
        for &t in &g.elements {
            let mut key = mesh.triangles[t];
            key.sort_unstable();
            if !matches!(fc.get(&key), Some(&(_, 2, ..))) {
                return Err(err(format!(
                    "{what}: contact surface \"{on}\" is not between two bodies: its triangle {} borders one body only (is the surface on the outer boundary? a surface on the boundary of two meshes is a slave/master pair)",
                    mesh.triangle_tags[t]
                )));
            }
            if let Some(&(j, _)) = cut_faces.get(&key) {
                return Err(err(format!(
                    "{what}: triangle {} of \"{on}\" is also in [[contact]] #{}",
                    mesh.triangle_tags[t],
                    j + 1
                )));
            }
            cut_faces.insert(key, (i as u32, t));
            cut_tris[i].push(t);
        }
    }
    // Bodies: tetrahedra joined through their faces off the contact cut; a
    // node has a point in each body of its tetrahedra.
    let joined = fc
        .iter()
        .filter(|(k, _)| !cut_faces.contains_key(*k))
        .filter_map(|(_, f)| f.3.map(|s| (f.2, s)));
    let (tet_body, nbodies) = cell_bodies(mesh_tets, &mesh.node_tags, joined);
    let mut on_cut = vec![false; nn];
    for (key, &(i, t)) in &cut_faces {
        let f = fc[key];
        let s = f.3.unwrap_or(f.2);
        if tet_body[f.2] == tet_body[s] {
            let c = &input.contact[i as usize];
            return Err(err(format!(
                "{}: contact surface \"{}\" is not between two bodies: its triangle {} lies inside one body (the surface does not cut it into two)",
                contact_what(i as usize, c),
                c.groups()[0],
                mesh.triangle_tags[t]
            )));
        }
        for &v in key {
            on_cut[v] = true;
        }
    }
    let mut node_bodies: Vec<Vec<u32>> = vec![vec![]; nn];
    for (t, tet) in mesh_tets.iter().enumerate() {
        for &v in tet {
            if !node_bodies[v].contains(&tet_body[t]) {
                node_bodies[v].push(tet_body[t]);
            }
        }
    }
    let mut nbodies = nbodies;
    let mut node_ptr = vec![0usize; nn + 1];
    let mut point_body = vec![];
    let mut point_node = vec![];
    let mut used = vec![];
    for (v, bs) in node_bodies.iter_mut().enumerate() {
        if bs.len() > 1 && !on_cut[v] {
            return Err(err(format!(
                "{}: node {} joins two bodies that share no face (tetrahedra touching at an edge or a vertex, not across a [[contact]] surface)",
                mesh.path.display(),
                mesh.node_tags[v]
            )));
        }
        bs.sort_unstable();
        if bs.is_empty() {
            // A node of no tetrahedron: a body of its own.
            bs.push(nbodies as u32);
            nbodies += 1;
            used.push(false);
        } else {
            used.extend(bs.iter().map(|_| true));
        }
        for &b in bs.iter() {
            point_body.push(b);
            point_node.push(v);
        }
        node_ptr[v + 1] = point_body.len();
    }
    let cut = Cut {
        node_ptr,
        point_body,
    };
    let np = point_node.len();
    let points: Vec<Point3> = point_node.iter().map(|&v| nodes[v]).collect();
    let tets: Vec<[usize; 4]> = mesh_tets
        .iter()
        .zip(&tet_body)
        .map(|(t, &b)| t.map(|v| cut.point(v, b)))
        .collect();
    let surf = |on: &str, what: &str| {
        surface(
            mesh, &nodes, mesh_tets, &tet_body, &cut, &fc, path, on, what,
        )
    };
    // Conditions.
    let mut conds: Vec<Vec<Cond3>> = vec![vec![]; np];
    for p in (0..np).filter(|&p| !used[p]) {
        // A node of no tetrahedron (a point element): held, no unknowns.
        conds[p] = vec![
            cond([1.0, 0.0, 0.0], 0.0),
            cond([0.0, 1.0, 0.0], 0.0),
            cond([0.0, 0.0, 1.0], 0.0),
        ];
    }
    for (i, (on, u)) in input.dirichlet.iter().enumerate() {
        let what = format!("[[dirichlet]] #{} (on = \"{on}\")", i + 1);
        let Some(g) = mesh.group_any(on) else {
            return Err(err(format!(
                "{what}: no physical group \"{on}\" in {}",
                mesh.path.display()
            )));
        };
        let mut gnodes: Vec<usize> = match g.dim {
            0 => g.elements.iter().map(|&e| mesh.points[e]).collect(),
            1 => g.elements.iter().flat_map(|&e| mesh.lines[e]).collect(),
            2 => g.elements.iter().flat_map(|&e| mesh.triangles[e]).collect(),
            _ => g.elements.iter().flat_map(|&e| mesh.tets[e]).collect(),
        };
        gnodes.sort_unstable();
        gnodes.dedup();
        let turn = match u {
            Prescribed::Turn(t) => Some((t, model_size(nodes.iter().copied()))),
            _ => None,
        };
        for v in gnodes {
            // A turn: u·e_θ = θρ, nothing on the axis (methods.md §2.5).
            let tc = turn.and_then(|(t, size)| t.condition(nodes[v], size));
            for p in cut.points(v) {
                if let Some((r, val)) = tc {
                    conds[p].push(cond(r, val));
                }
                for (k, uk) in u.components().iter().enumerate() {
                    if let Some(val) = uk {
                        let mut r = [0.0; 3];
                        r[k] = 1.0;
                        conds[p].push(cond(r, *val));
                    }
                }
            }
        }
    }
    // The slip planes' normals through each point, for the contact rows.
    let mut slip_planes: Vec<Vec<Vector3>> = vec![vec![]; np];
    for (i, on) in input.slip.iter().enumerate() {
        let what = format!("[[slip]] #{} (on = \"{on}\")", i + 1);
        let tris = surf(on, &what)?;
        let Some(&Facet {
            nodes: t0,
            normal: n0,
            ..
        }) = tris.first()
        else {
            continue;
        };
        let x0 = nodes[t0[0]];
        let size = tris
            .iter()
            .flat_map(|t| t.nodes)
            .map(|v| {
                (0..3)
                    .map(|k| (nodes[v][k] - x0[k]).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        for f in &tris {
            let (tri, n) = (f.nodes, f.normal);
            let off = tri
                .iter()
                .map(|&v| dot(n0, [0, 1, 2].map(|k| nodes[v][k] - x0[k])).abs())
                .fold(0.0, f64::max);
            if dot(n, n0) < 1.0 - 1e-10 || off > 1e-9 * size {
                return Err(err(format!(
                    "{what}: the surface is not plane (its triangle {} has normal ({:.4}, {:.4}, {:.4}), the first ({:.4}, {:.4}, {:.4})): a slip surface in 3D must be a plane",
                    f.tag,
                    n[0], n[1], n[2], n0[0], n0[1], n0[2]
                )));
            }
        }
        let mut ps: Vec<usize> = tris.iter().flat_map(|t| t.points).collect();
        ps.sort_unstable();
        ps.dedup();
        for p in ps {
            conds[p].push(cond(n0, 0.0));
            slip_planes[p].push(n0);
        }
    }
    // The elimination of the plane, by Gram–Schmidt in 3D.
    let dofs = number(&conds, |p, m| {
        err(format!(
            "conflicting conditions at node {}: {m}",
            mesh.node_tags[point_node[p]]
        ))
    })?;
    let n = dofs.last().map_or(0, |pd| pd.start + pd.ndof);
    // C = Σ T_aᵀ K_ab T_b and the element part of d, Σ T_aᵀ (f_a − K_ab
    // u0_b) with the gravity f_a (methods.md §2.3): the ordered assembly
    // of the plane, on tetrahedra.
    let mats: Vec<&Material> = material_names.iter().map(|m| &input.materials[m]).collect();
    let smats = Materials::<3> {
        kind,
        dmats: mats.iter().map(|m| kind.material(m)).collect(),
        bforce: mats
            .iter()
            .map(|m| input.gravity.map(|g| m.rho * g))
            .collect(),
        spin: vec![0.0; mats.len()],
    };
    let cells = Cells {
        points: &points,
        cells: &tets,
        material: &tet_material,
    };
    let (c, mut d) = assemble(cells, &dofs, n, &smats, true);
    // Tractions on the boundary triangles: d += Tᵀ f.
    let mut tractions = vec![[0.0; 3]; np];
    for (i, (on, load)) in input.traction.iter().enumerate() {
        let what = format!("[[traction]] #{} (on = \"{on}\")", i + 1);
        for f in surf(on, &what)? {
            let p = match *load {
                SolidTraction::Normal(pn) => f.normal.map(|c| pn * c),
                SolidTraction::Vector(p) => p,
            };
            for v in f.points {
                for k in 0..3 {
                    tractions[v][k] += f.weight * p[k];
                }
            }
        }
    }
    for (v, f) in tractions.iter().enumerate() {
        let p = &dofs[v];
        for r in 0..p.ndof {
            d[p.start + r] += dot(p.t[r], *f);
        }
    }
    // The nodal external forces: the gravity of the tetrahedra, then the
    // tractions.
    let mut loads = vec![[0.0; 3]; np];
    for (t, tet) in tets.iter().enumerate() {
        let mi = tet_material[t] as usize;
        let pts = tet.map(|v| points[v]);
        for (a, &v) in tet.iter().enumerate() {
            let f = kind.cell_body_load(&pts, a, smats.bforce[mi], 0.0);
            for k in 0..3 {
                loads[v][k] += f[k];
            }
        }
    }
    for (l, f) in loads.iter_mut().zip(&tractions) {
        for k in 0..3 {
            l[k] += f[k];
        }
    }
    // Contact rows (docs/methods.md §11).
    let mut contact = vec![];
    let interface_names: Vec<String> = input.contact.iter().map(|c| c.groups().join("/")).collect();
    let node_tag = |p: usize| mesh.node_tags[point_node[p]];
    // The least and largest Young's modulus of each body's tetrahedra.
    let mut body_e = vec![(f64::INFINITY, 0.0f64); nbodies];
    for (t, &m) in tet_material.iter().enumerate() {
        let e = mats[m as usize].e;
        let b = &mut body_e[tet_body[t] as usize];
        *b = (b.0.min(e), b.1.max(e));
    }
    // The Physical Volumes of each body, for messages.
    let mut body_volumes: Vec<Vec<&str>> = vec![vec![]; nbodies];
    for (t, &m) in tet_material.iter().enumerate() {
        let (b, name) = (tet_body[t] as usize, material_names[m as usize].as_str());
        if !body_volumes[b].contains(&name) {
            body_volumes[b].push(name);
        }
    }
    for (i, c) in input.contact.iter().enumerate() {
        let what = contact_what(i, c);
        match &c.pair {
            ContactPair::Conforming { on, .. } => {
                let mut tris = vec![];
                for &t in &cut_tris[i] {
                    let tri = mesh.triangles[t];
                    let mut key = tri;
                    key.sort_unstable();
                    let f = fc[&key];
                    let s = f.3.unwrap_or(f.2);
                    let (tk, tl) = if tet_body[f.2] < tet_body[s] {
                        (f.2, s)
                    } else {
                        (s, f.2)
                    };
                    let (weight, normal) = outward(&nodes, tri, &mesh_tets[tk]);
                    let (bk, bl) = (tet_body[tk], tet_body[tl]);
                    let facet = Facet {
                        nodes: tri,
                        points: tri.map(|v| cut.point(v, bk)),
                        body: bk,
                        weight,
                        normal,
                        tag: mesh.triangle_tags[t],
                    };
                    tris.push((facet, tri.map(|v| cut.point(v, bl))));
                }
                contact.extend(conforming_rows(&tris, i as u32, on, node_tag, path)?);
            }
            ContactPair::NonMatching(pair) => {
                let role = |r: &str| format!("{what}: {r} surface");
                let slave = surf(&pair.slave, &role("slave"))?;
                let master = surf(&pair.master, &role("master"))?;
                check_bodies(&slave, &master, &what, pair, &body_volumes, path)?;
                let disc = pair.discretization.unwrap_or_else(|| {
                    default_discretization(
                        &slave,
                        &master,
                        &body_e,
                        &pair.slave,
                        &pair.master,
                        &what,
                    )
                });
                let rows = match disc {
                    Discretization::Mortar => mortar_rows,
                    Discretization::Nts => nts_rows,
                };
                contact.extend(rows(
                    &points, &slave, &master, pair, i as u32, &what, node_tag, path,
                )?);
            }
        }
    }
    mirror_into_slip_planes(&mut contact, &slip_planes);
    let (a, g, qp_rows) = reduced_rows(&contact, &dofs, n, |row| {
        err(format!(
            "contact row at node {} of \"{}\" is violated by the prescribed displacements alone",
            node_tag(row.slave),
            interface_names[row.interface as usize]
        ))
    })?;
    let point_body = cut.point_body;
    let (kernel, kernel_body) = rigid_kernel(&points, &point_body, nbodies, &conds, &dofs, n);
    // A body with free rigid motions must touch a contact row; whether the
    // rows hold them is the QP layer's decision (docs/methods.md §8.2).
    let mut touched = vec![false; nbodies];
    for &r in &qp_rows {
        for (p, _) in contact[r].coefficients() {
            touched[point_body[p] as usize] = true;
        }
    }
    if let Some(&b) = kernel_body.iter().find(|&&b| !touched[b as usize]) {
        let k = kernel_body.iter().filter(|&&x| x == b).count();
        let names: Vec<&str> = tets
            .iter()
            .zip(&tet_material)
            .filter(|(t, _)| point_body[t[0]] == b)
            .map(|(_, &m)| material_names[m as usize].as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        return Err(err(format!(
            "{}: {k} rigid motion(s) of body {} ({}) are held by no [[dirichlet]] or [[slip]] and it has no [[contact]] row: add one",
            mesh.path.display(),
            b + 1,
            names.join(", ")
        )));
    }
    let near = near_kernel(&points, &dofs, n);
    // Friction: two tangential rows per QP row (docs/methods.md §12.2).
    let friction = super::contact3d::friction::build(
        &contact,
        &qp_rows,
        &dofs,
        n,
        &input.contact,
        path,
        node_tag,
    )?;
    let qp = QpProblem {
        c,
        d,
        a,
        g,
        kernel,
        friction,
        near,
    };
    let mut model = SolidModel {
        kind,
        points,
        point_node,
        tets,
        tet_material,
        material_names,
        dofs,
        qp,
        loads,
        point_body,
        nbodies,
        contact,
        qp_rows,
        interface_names,
        kernel_body,
    };
    // The slip of a single solve or first step: from the reference (§12.2).
    super::Discrete::start_step(&mut model, None);
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::super::conditions::eliminate;
    use super::*;

    /// u0 + Tξ satisfies the conditions for any ξ, T is orthonormal, and
    /// conflicting conditions are refused.
    #[test]
    fn elimination_in_3d() {
        let s = 0.5f64.sqrt();
        for (cs, ndof) in [
            (vec![], 3),
            (vec![([0.0, 0.0, 2.0], 0.4)], 2),
            (vec![([s, s, 0.0], 0.0), ([1.0, 0.0, 0.0], 0.1)], 1),
            (
                vec![
                    ([1.0, 0.0, 0.0], 0.1),
                    ([0.0, 1.0, 0.0], 0.2),
                    ([0.0, 0.0, 1.0], -0.3),
                ],
                0,
            ),
            (vec![([1.0, 0.0, 0.0], 0.1), ([2.0, 0.0, 0.0], 0.2)], 2),
        ] {
            let cs: Vec<Cond3> = cs.into_iter().map(|(r, v)| cond(r, v)).collect();
            let pd = eliminate(&cs).unwrap();
            assert_eq!(pd.ndof, ndof, "{cs:?}");
            for xi in [[0.0; 3], [0.3, -1.2, 0.7]] {
                let mut u = pd.u0;
                for k in 0..pd.ndof {
                    for c in 0..3 {
                        u[c] += pd.t[k][c] * xi[k];
                    }
                }
                for c in &cs {
                    assert!((dot(c.r, u) - c.v).abs() < 1e-14, "{cs:?}");
                }
            }
            for i in 0..pd.ndof {
                for j in 0..pd.ndof {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((dot(pd.t[i], pd.t[j]) - want).abs() < 1e-14);
                }
            }
        }
        assert!(eliminate(&[cond([1.0, 0.0, 0.0], 0.1), cond([1.0, 0.0, 0.0], 0.2)]).is_err());
    }
}
