//! The first slice of 3D (issue 45): a model of P1 tetrahedra without
//! contact, from a 3D mesh to the QP min ½xᵀCx − xᵀd (no rows), on the
//! shared pieces — [`ElementKind::Solid`], [`PointDofs`]`<3>`, the
//! [`RigidMode`]s, the body detection (`topology::cell_bodies`), the
//! ordered parallel assembly (`stiffness::assemble`), the elimination of
//! the conditions (`conditions::eliminate`), the QP layer. Dirichlet
//! components, slip on plane surfaces, tractions (`pn` or `p`) on boundary
//! triangles, gravity. What is still 2D-only (the topology cut along
//! contact surfaces, the outputs) is listed in docs/design.md §"Adding a
//! kind: solid 3D".

use super::conditions::{number, Cond, PointDofs};
use super::element::{ElementKind, MaterialMatrix, Point3, RigidMode, Vector3, SOLID_MODES};
use super::stiffness::{assemble, Cells, Materials};
use super::topology::cell_bodies;
use super::FemError;
use crate::linalg::sparse::Csr;
use crate::mesh::Mesh;
use crate::problem::Material;
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
    /// `[[dirichlet]]`: the group and its prescribed ux, uy, uz.
    pub dirichlet: Vec<(String, [Option<f64>; 3])>,
    /// `[[slip]]`: plane surfaces on which u·n = 0.
    pub slip: Vec<String>,
    /// `[[traction]]`: the surface and its load.
    pub traction: Vec<(String, SolidTraction)>,
}

/// The assembled solid model with the maps back to the mesh.
#[derive(Clone)]
pub struct SolidModel {
    pub kind: ElementKind,
    /// The mesh nodes (a point per node: no contact cut yet).
    pub points: Vec<Point3>,
    /// Tetrahedra, positively oriented, in node indices.
    pub tets: Vec<[usize; 4]>,
    /// The material of each tetrahedron (index into `material_names`).
    pub tet_material: Vec<u32>,
    pub material_names: Vec<String>,
    /// u_p = u0_p + T_p ξ_p.
    pub dofs: Vec<PointDofs<3>>,
    pub qp: QpProblem,
    /// Nodal external forces (N), before the elimination.
    pub loads: Vec<Vector3>,
    /// The body of each node (connected through tetrahedra).
    pub point_body: Vec<u32>,
    pub nbodies: usize,
}

impl SolidModel {
    /// Full nodal displacements from the QP unknowns.
    pub fn displacements(&self, x: &[f64]) -> Vec<Vector3> {
        self.dofs
            .iter()
            .map(|p| {
                let mut u = p.u0;
                for k in 0..p.ndof {
                    for (c, uc) in u.iter_mut().enumerate() {
                        *uc += p.t[k][c] * x[p.start + k];
                    }
                }
                u
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
type Cond3 = Cond<3>;

/// The condition r·u = v.
fn cond(r: Vector3, v: f64) -> Cond3 {
    Cond { r, v, src: 0 }
}

fn dot(a: Vector3, b: Vector3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
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

/// A boundary triangle of a Physical Surface: its nodes, the weight |F|/3
/// of each, its outward unit normal and its Gmsh tag (for messages).
#[derive(Debug, Clone, Copy)]
struct Facet {
    nodes: [usize; 3],
    weight: f64,
    normal: Vector3,
    tag: u64,
}

/// The triangles of a Physical Surface `name` with each one's node weight
/// |F|/3 and outward unit normal; `what` names the TOML entry.
fn surface(
    mesh: &Mesh,
    points: &[Point3],
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
    let kind = ElementKind::Solid;
    let mut out = vec![];
    for &t in &g.elements {
        let tri = mesh.triangles[t];
        let (w, mut n) = kind.facet_weight(&tri.map(|v| points[v]));
        let mut key = tri;
        key.sort_unstable();
        // The reader has checked that every triangle is a face; one inside
        // a body (two tetrahedra) is on no boundary.
        if let Some(&(_, 2, _, _)) = faces.get(&key) {
            return Err(FemError::new(
                path,
                format!(
                    "{what}: triangle {} of \"{name}\" lies inside the volume mesh (two tetrahedra share it), not on its boundary",
                    mesh.triangle_tags[t]
                ),
            ));
        }
        if let Some(&(opp, ..)) = faces.get(&key) {
            let x0 = points[tri[0]];
            let o = points[opp];
            if dot(n, [o[0] - x0[0], o[1] - x0[1], o[2] - x0[2]]) > 0.0 {
                n = n.map(|c| -c);
            }
        }
        out.push(Facet {
            nodes: tri,
            weight: w,
            normal: n,
            tag: mesh.triangle_tags[t],
        });
    }
    Ok(out)
}

/// Build the solid model of a 3D `mesh` (docs/design.md §"Adding a kind:
/// solid 3D"): messages name the TOML file `path` and the group.
pub fn build(mesh: &Mesh, path: &Path, input: &SolidInput) -> Result<SolidModel, FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let kind = ElementKind::Solid;
    let points: Vec<Point3> = (0..mesh.nodes.len()).map(|i| mesh.node::<3>(i)).collect();
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
    let tets = mesh.tets.clone();
    let nn = points.len();
    let fc = faces(&tets);
    // Bodies: tetrahedra joined through their faces (the 2D cut of
    // topology.rs, without contact surfaces yet); a node's body is its
    // tetrahedra's.
    let joined = fc.values().filter_map(|f| f.3.map(|s| (f.2, s)));
    let (tet_body, nbodies) = cell_bodies(&tets, &mesh.node_tags, joined);
    let mut used = vec![false; nn];
    let mut point_body = vec![u32::MAX; nn];
    for (t, tet) in tets.iter().enumerate() {
        for &v in tet {
            used[v] = true;
            if point_body[v] == u32::MAX {
                point_body[v] = tet_body[t];
            } else if point_body[v] != tet_body[t] {
                return Err(err(format!(
                    "{}: node {} joins two bodies that share no face (tetrahedra touching at an edge or a vertex): a 3D model has no contact cut yet (issue 45)",
                    mesh.path.display(),
                    mesh.node_tags[v]
                )));
            }
        }
    }
    // A node of no tetrahedron: a body of its own.
    let mut nbodies = nbodies;
    for b in point_body.iter_mut().filter(|b| **b == u32::MAX) {
        *b = nbodies as u32;
        nbodies += 1;
    }
    // Conditions.
    let mut conds: Vec<Vec<Cond3>> = vec![vec![]; nn];
    for v in (0..nn).filter(|&v| !used[v]) {
        // A node of no tetrahedron (a point element): held, no unknowns.
        conds[v] = vec![
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
        let mut nodes: Vec<usize> = match g.dim {
            0 => g.elements.iter().map(|&e| mesh.points[e]).collect(),
            1 => g.elements.iter().flat_map(|&e| mesh.lines[e]).collect(),
            2 => g.elements.iter().flat_map(|&e| mesh.triangles[e]).collect(),
            _ => g.elements.iter().flat_map(|&e| mesh.tets[e]).collect(),
        };
        nodes.sort_unstable();
        nodes.dedup();
        for v in nodes {
            for (k, uk) in u.iter().enumerate() {
                if let Some(val) = uk {
                    let mut r = [0.0; 3];
                    r[k] = 1.0;
                    conds[v].push(cond(r, *val));
                }
            }
        }
    }
    for (i, on) in input.slip.iter().enumerate() {
        let what = format!("[[slip]] #{} (on = \"{on}\")", i + 1);
        let tris = surface(mesh, &points, &fc, path, on, &what)?;
        let Some(&Facet {
            nodes: t0,
            normal: n0,
            ..
        }) = tris.first()
        else {
            continue;
        };
        let x0 = points[t0[0]];
        let size = tris
            .iter()
            .flat_map(|t| t.nodes)
            .map(|v| {
                (0..3)
                    .map(|k| (points[v][k] - x0[k]).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        for f in &tris {
            let (tri, n) = (f.nodes, f.normal);
            let off = tri
                .iter()
                .map(|&v| dot(n0, [0, 1, 2].map(|k| points[v][k] - x0[k])).abs())
                .fold(0.0, f64::max);
            if dot(n, n0) < 1.0 - 1e-10 || off > 1e-9 * size {
                return Err(err(format!(
                    "{what}: the surface is not plane (its triangle {} has normal ({:.4}, {:.4}, {:.4}), the first ({:.4}, {:.4}, {:.4})): a slip surface in 3D must be a plane",
                    f.tag,
                    n[0], n[1], n[2], n0[0], n0[1], n0[2]
                )));
            }
        }
        let mut nodes: Vec<usize> = tris.iter().flat_map(|t| t.nodes).collect();
        nodes.sort_unstable();
        nodes.dedup();
        for v in nodes {
            conds[v].push(cond(n0, 0.0));
        }
    }
    // The elimination of the plane, by Gram–Schmidt in 3D.
    let dofs = number(&conds, |v, m| {
        err(format!(
            "conflicting conditions at node {}: {m}",
            mesh.node_tags[v]
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
    let mut tractions = vec![[0.0; 3]; nn];
    for (i, (on, load)) in input.traction.iter().enumerate() {
        let what = format!("[[traction]] #{} (on = \"{on}\")", i + 1);
        for Facet {
            nodes: tri,
            weight: w,
            normal: nrm,
            ..
        } in surface(mesh, &points, &fc, path, on, &what)?
        {
            let p = match *load {
                SolidTraction::Normal(pn) => nrm.map(|c| pn * c),
                SolidTraction::Vector(p) => p,
            };
            for v in tri {
                for k in 0..3 {
                    tractions[v][k] += w * p[k];
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
    let mut loads = vec![[0.0; 3]; nn];
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
    let kernel = rigid_kernel(&points, &point_body, nbodies, &conds, &dofs, n);
    if !kernel.is_empty() {
        return Err(err(format!(
            "{}: {} rigid motion(s) of the bodies are held by no condition, and a 3D model has no contact yet (issue 45): add [[dirichlet]] or [[slip]]",
            mesh.path.display(),
            kernel.len()
        )));
    }
    let qp = QpProblem {
        c,
        d,
        a: Csr::from_triplets(0, n, &[]),
        g: vec![],
        kernel,
        friction: None,
        near: None,
    };
    Ok(SolidModel {
        kind,
        points,
        tets,
        tet_material,
        material_names,
        dofs,
        qp,
        loads,
        point_body,
        nbodies,
    })
}

/// The rigid motions (the six [`SOLID_MODES`]) of each body that satisfy
/// its homogeneous conditions, in the reduced unknowns, orthonormalised
/// (docs/methods.md §1.7; the 2D rigid.rs in 3D).
fn rigid_kernel(
    points: &[Point3],
    point_body: &[u32],
    nbodies: usize,
    conds: &[Vec<Cond3>],
    dofs: &[PointDofs<3>],
    n: usize,
) -> Vec<Vec<f64>> {
    let mut lo = vec![[f64::MAX; 3]; nbodies];
    let mut hi = vec![[f64::MIN; 3]; nbodies];
    for (p, x) in points.iter().enumerate() {
        let b = point_body[p] as usize;
        for k in 0..3 {
            lo[b][k] = lo[b][k].min(x[k]);
            hi[b][k] = hi[b][k].max(x[k]);
        }
    }
    let centre = |b: usize| [0, 1, 2].map(|k| (lo[b][k] + hi[b][k]) / 2.0);
    let size = |b: usize| {
        (0..3)
            .map(|k| hi[b][k] - lo[b][k])
            .fold(0.0, f64::max)
            .max(1e-300)
    };
    let motion = |m: RigidMode, b: usize, x: Point3| m.at(x, centre(b), size(b));
    let mut gtg = vec![vec![vec![0.0; 6]; 6]; nbodies];
    for (p, cs) in conds.iter().enumerate() {
        let b = point_body[p] as usize;
        for &Cond { r, .. } in cs {
            let l = dot(r, r).sqrt();
            let row: Vec<f64> = SOLID_MODES
                .iter()
                .map(|&m| dot(r, motion(m, b, points[p])) / l)
                .collect();
            for i in 0..6 {
                for j in 0..6 {
                    gtg[b][i][j] += row[i] * row[j];
                }
            }
        }
    }
    let mut kernel: Vec<Vec<f64>> = vec![];
    for (b, m) in gtg.iter().enumerate() {
        let (vals, vecs) = crate::linalg::dense::sym_eigen(m);
        for (k, &val) in vals.iter().enumerate() {
            if val > 1e-9 {
                continue;
            }
            let coef: Vec<f64> = (0..6).map(|i| vecs[i][k]).collect();
            let mut z = vec![0.0; n];
            for (p, pd) in dofs
                .iter()
                .enumerate()
                .filter(|(p, _)| point_body[*p] as usize == b)
            {
                let mut u = [0.0; 3];
                for (i, &mode) in SOLID_MODES.iter().enumerate() {
                    let w = motion(mode, b, points[p]);
                    for c in 0..3 {
                        u[c] += coef[i] * w[c];
                    }
                }
                for r in 0..pd.ndof {
                    z[pd.start + r] = dot(pd.t[r], u);
                }
            }
            for q in &kernel {
                let s: f64 = q.iter().zip(&z).map(|(a, b)| a * b).sum();
                for (zi, qi) in z.iter_mut().zip(q) {
                    *zi -= s * qi;
                }
            }
            let nz = z.iter().map(|v| v * v).sum::<f64>().sqrt();
            if nz > 1e-12 {
                kernel.push(z.into_iter().map(|v| v / nz).collect());
            }
        }
    }
    kernel
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
