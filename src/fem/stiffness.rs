//! Boundary conditions, DOF elimination and assembly of the QP (methods.md
//! §2.2–2.8).
//!
//! Dirichlet components and slip lines (Γ0, u·n = 0) are eliminated node by
//! node: each point's displacement is u_p = u0_p + T_p ξ_p, where the rows of
//! all conditions at the point fix u0_p and T_p has orthonormal columns
//! spanning what is left free (2, 1 or 0 DOFs). This is the report's
//! elimination option of §2.5 with a unit tangent instead of (1, −n1/n2), so
//! it is well-conditioned for any normal, and it combines Dirichlet and slip
//! at corners. C = Σ T_eᵀC_eT_e, d = Σ T_eᵀ(d_e − C_e u0_e), A ← A T, g ← g − A u0.

use super::element;
use super::topology::Topology;
use super::FemError;
use crate::linalg::dense::sym_eigen;
use crate::mesh::Mesh;
use crate::problem::{Plane, Problem};
use crate::qp::{Csr, QpProblem};

/// Per-point elimination: u = u0 + T ξ with `ndof` columns of T used.
#[derive(Debug, Clone, Copy, Default)]
pub struct PointDofs {
    pub start: usize,
    pub ndof: usize,
    /// Columns of T (unit, orthogonal); only the first `ndof` are used.
    pub t: [[f64; 2]; 2],
    pub u0: [f64; 2],
}

/// The assembled problem with the maps back to the mesh.
pub struct Model {
    pub topo: Topology,
    pub dofs: Vec<PointDofs>,
    pub qp: QpProblem,
    /// QP row → contact row (rows whose points are all fixed are left out).
    pub qp_rows: Vec<usize>,
    /// Kernel vectors and the body each belongs to.
    pub kernel_body: Vec<u32>,
    pub plane: Plane,
    pub thickness: f64,
    /// The Dirichlet and slip conditions r·u = v, kept for the reactions:
    /// (point, unit direction r, index into `cond_groups`).
    pub conditions: Vec<(usize, [f64; 2], u32)>,
    /// What set each condition: (kind "dirichlet" | "slip", physical group name).
    pub cond_groups: Vec<(&'static str, String)>,
    /// Nodal external force on each point [N] (tractions, point forces,
    /// gravity; thickness included), before the elimination: the load side
    /// of the balance R = K u − f.
    pub loads: Vec<[f64; 2]>,
    /// The name of each body: its physical surface name(s), "+"-joined,
    /// with " #b" when bodies share a material.
    pub body_names: Vec<String>,
}

impl Model {
    /// "body 'punch'": a body as messages name it.
    pub fn body_label(&self, b: usize) -> String {
        match self.body_names.get(b) {
            Some(n) => format!("body '{n}'"),
            None => format!("body {b}"),
        }
    }

    /// Point displacements of a change `dx` of the QP unknowns (u0 left out):
    /// the motion along a direction such as a rigid mode.
    pub fn motions(&self, dx: &[f64]) -> Vec<[f64; 2]> {
        self.dofs
            .iter()
            .map(|p| {
                let mut u = [0.0, 0.0];
                for k in 0..p.ndof {
                    let xi = dx[p.start + k];
                    u[0] += p.t[k][0] * xi;
                    u[1] += p.t[k][1] * xi;
                }
                u
            })
            .collect()
    }

    /// The bodies that the point motions `u` move (by more than 10⁻³ of the
    /// largest motion), each with the rigid motion that fits it best:
    /// `body 1 (translation along (1, 0))` or `body 1 (rotation about (0.5, 0.25))`.
    pub fn describe_rigid_motion(&self, u: &[[f64; 2]]) -> String {
        let umax = u
            .iter()
            .fold(0.0f64, |m, v| m.max(v[0].hypot(v[1])))
            .max(f64::MIN_POSITIVE);
        let parts: Vec<String> = (0..self.topo.nbodies)
            .filter_map(|b| {
                self.body_motion(u, b, 1e-3 * umax)
                    .map(|what| format!("{} ({what})", self.body_label(b)))
            })
            .collect();
        if parts.is_empty() {
            "no body".into()
        } else {
            parts.join(", ")
        }
    }

    /// The rigid motion that fits the point motions `u` of body `b` best
    /// (least squares): "translation along (dx, dy)" or "rotation about
    /// (x, y)"; None if no point of the body moves by more than `min`.
    pub fn body_motion(&self, u: &[[f64; 2]], b: usize, min: f64) -> Option<String> {
        let pts: Vec<usize> = (0..u.len().min(self.topo.points.len()))
            .filter(|&p| self.topo.point_body[p] as usize == b)
            .collect();
        let bmax = pts
            .iter()
            .fold(0.0f64, |m, &p| m.max(u[p][0].hypot(u[p][1])));
        if pts.is_empty() || !(bmax > min) {
            return None;
        }
        // a + ω × (x − c) about the centroid c.
        let k = pts.len() as f64;
        let mut c = [0.0, 0.0];
        let mut a = [0.0, 0.0];
        for &p in &pts {
            let x = self.topo.points[p];
            c = [c[0] + x[0] / k, c[1] + x[1] / k];
            a = [a[0] + u[p][0] / k, a[1] + u[p][1] / k];
        }
        let (mut num, mut den, mut rmax) = (0.0, 0.0, 0.0f64);
        for &p in &pts {
            let r = [self.topo.points[p][0] - c[0], self.topo.points[p][1] - c[1]];
            num += r[0] * u[p][1] - r[1] * u[p][0];
            den += r[0] * r[0] + r[1] * r[1];
            rmax = rmax.max(r[0].hypot(r[1]));
        }
        let w = if den > 0.0 { num / den } else { 0.0 };
        let an = a[0].hypot(a[1]);
        // 4 decimals, and no "-0".
        let g = |v: f64| format!("{v:.4}").parse::<f64>().unwrap_or(v) + 0.0;
        Some(if an > 0.0 && (w * rmax).abs() <= 1e-3 * an {
            format!("translation along ({}, {})", g(a[0] / an), g(a[1] / an))
        } else if w != 0.0 && w.is_finite() {
            // The fixed point of the motion: a + ω × (p − c) = 0, rounded to
            // 10⁻⁵ of the body's size (no round-off noise such as 1e-17).
            let q = 10f64.powi(rmax.log10().floor() as i32 - 5);
            let p = [c[0] - a[1] / w, c[1] + a[0] / w].map(|v| {
                if q > 0.0 && q.is_finite() {
                    (v / q).round() * q
                } else {
                    v
                }
            });
            format!("rotation about ({}, {})", g_sig(p[0]), g_sig(p[1]))
        } else {
            "not a rigid motion".to_string()
        })
    }

    /// Full point displacements from the QP unknowns.
    pub fn displacements(&self, x: &[f64]) -> Vec<[f64; 2]> {
        self.dofs
            .iter()
            .map(|p| {
                let mut u = p.u0;
                for k in 0..p.ndof {
                    let xi = x[p.start + k];
                    u[0] += p.t[k][0] * xi;
                    u[1] += p.t[k][1] * xi;
                }
                u
            })
            .collect()
    }

    /// The effective thickness for forces → pressures (1 in plane strain).
    pub fn t_eff(&self) -> f64 {
        match self.plane {
            Plane::Stress => self.thickness,
            Plane::Strain => 1.0,
        }
    }
}

/// One linear condition r·u = v at a point; `src` indexes the names of the
/// TOML entries that set conditions (for messages).
#[derive(Clone, Copy)]
struct Cond {
    r: [f64; 2],
    v: f64,
    src: usize,
}

/// Build the whole model: topology, conditions, QP (default options).
pub fn build(mesh: &Mesh, problem: &Problem) -> Result<Model, FemError> {
    build_with(mesh, problem, &super::BuildOptions::default())
}

/// Build the whole model: topology, conditions, QP.
pub fn build_with(
    mesh: &Mesh,
    problem: &Problem,
    opts: &super::BuildOptions,
) -> Result<Model, FemError> {
    let mut lap = super::Lap::new("fem::build");
    let topo = Topology::build(mesh, problem)?;
    lap.lap("topology");
    let f = &problem.file;
    let err = |msg: String| FemError::new(&problem.path, msg);
    let np = topo.points.len();
    let th = match f.model.plane {
        Plane::Stress => f.model.thickness,
        Plane::Strain => 1.0,
    };

    // --- conditions per point
    let mut conds: Vec<Vec<Cond>> = vec![vec![]; np];
    // What set each condition: `[[dirichlet]] on = "NAME"`, `[[slip]] on = "NAME"`.
    let mut cond_src: Vec<String> = vec![];
    let mut cond_groups: Vec<(&'static str, String)> = vec![];
    // Points of a group: for a curve, the copies owned by each segment's body.
    let group_points =
        |name: &str,
         what: &str|
         -> Result<Vec<(usize, usize, Option<(usize, usize, usize)>)>, FemError> {
            // (point, mesh node, Some((segment node a, b, owner triangle)) for curves)
            let Some(g) = mesh.group_any(name) else {
                return Err(err(format!(
                    "{what}: no physical group named \"{name}\" in {} (curves: {}; points: {})",
                    mesh.path.display(),
                    super::topology::group_names(mesh, 1),
                    super::topology::group_names(mesh, 0)
                )));
            };
            let mut out = vec![];
            match g.dim {
                0 => {
                    for &e in &g.elements {
                        let v = mesh.points[e];
                        for &(_, p) in topo.copies(v) {
                            out.push((p, v, None));
                        }
                    }
                }
                1 => {
                    for &e in &g.elements {
                        let [a, b] = mesh.lines[e];
                        let ts = topo.edge_triangles(a, b);
                        if ts.is_empty() {
                            return Err(err(format!(
                            "{what}: segment ({}, {}) of curve \"{name}\" is not an edge of any triangle",
                            mesh.node_tags[a], mesh.node_tags[b]
                        )));
                        }
                        for &t in &ts {
                            let body = topo.mesh_triangle_body(t);
                            for v in [a, b] {
                                if let Some(p) = topo.point(v, body) {
                                    out.push((p, v, Some((a, b, t))));
                                }
                            }
                        }
                    }
                }
                d => {
                    return Err(err(format!(
                        "{what}: \"{name}\" is a physical {} in {}, expected a curve or a point",
                        super::topology::dim_name(d),
                        mesh.path.display()
                    )))
                }
            }
            Ok(out)
        };

    for (i, dch) in f.dirichlet.iter().enumerate() {
        let what = format!("[[dirichlet]] #{} (on = \"{}\")", i + 1, dch.on);
        let (ux, uy) = match dch.u {
            Some(u) => (Some(u[0]), Some(u[1])),
            None => (dch.ux, dch.uy),
        };
        let mut pts: Vec<usize> = group_points(&dch.on, &what)?
            .into_iter()
            .map(|x| x.0)
            .collect();
        pts.sort_unstable();
        pts.dedup();
        let src = cond_src.len();
        cond_src.push(format!("[[dirichlet]] on = \"{}\"", dch.on));
        cond_groups.push(("dirichlet", dch.on.clone()));
        for p in pts {
            if let Some(v) = ux {
                conds[p].push(Cond {
                    r: [1.0, 0.0],
                    v,
                    src,
                });
            }
            if let Some(v) = uy {
                conds[p].push(Cond {
                    r: [0.0, 1.0],
                    v,
                    src,
                });
            }
        }
    }
    for (i, s) in f.slip.iter().enumerate() {
        let what = format!("[[slip]] #{} (on = \"{}\")", i + 1, s.on);
        let g = mesh.group_any(&s.on);
        if let Some(g) = g {
            if g.dim != 1 {
                return Err(err(format!(
                    "{what}: \"{}\" is a physical {}, expected a curve",
                    s.on,
                    super::topology::dim_name(g.dim)
                )));
            }
        }
        // Averaged unit normal per point over the segments of this line.
        let mut sum: std::collections::BTreeMap<usize, [f64; 2]> = Default::default();
        for (p, _, seg) in group_points(&s.on, &what)? {
            if let Some((a, b, t)) = seg {
                let n = topo.outward_normal(mesh, t, a, b);
                let e = sum.entry(p).or_insert([0.0, 0.0]);
                e[0] += n[0];
                e[1] += n[1];
            }
        }
        let src = cond_src.len();
        cond_src.push(format!("[[slip]] on = \"{}\"", s.on));
        cond_groups.push(("slip", s.on.clone()));
        for (p, n) in sum {
            let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
            if len > 1e-12 {
                conds[p].push(Cond {
                    r: [n[0] / len, n[1] / len],
                    v: 0.0,
                    src,
                });
            }
        }
    }

    lap.lap("conditions");
    // --- eliminate per point
    let body_names = body_names(&topo);
    let mut dofs = Vec::with_capacity(np);
    let mut next = 0usize;
    for (p, cs) in conds.iter().enumerate() {
        let pd = eliminate(cs).map_err(|m| {
            let mut from: Vec<usize> = cs.iter().map(|c| c.src).collect();
            from.sort_unstable();
            from.dedup();
            let from: Vec<&str> = from.iter().map(|&i| cond_src[i].as_str()).collect();
            err(format!(
                "conflicting conditions at node {} ({}) from {}: {m}",
                mesh.node_tags[topo.point_node[p]],
                match body_names.get(topo.point_body[p] as usize) {
                    Some(n) => format!("body '{n}'"),
                    None => format!("body {}", topo.point_body[p]),
                },
                from.join(", ")
            ))
        })?;
        let pd = PointDofs { start: next, ..pd };
        next += pd.ndof;
        dofs.push(pd);
    }
    let n = next;

    lap.lap("elimination");
    // --- stiffness and body force
    let mats: Vec<&crate::problem::Material> = topo
        .material_names
        .iter()
        .map(|m| &f.materials[m])
        .collect();
    let dmats: Vec<[[f64; 3]; 3]> = mats
        .iter()
        .map(|m| element::d_matrix(m, f.model.plane))
        .collect();
    let bforce: Vec<[f64; 2]> = {
        let gvec = f.model.gravity.unwrap_or([0.0, 0.0]);
        mats.iter()
            .map(|m| [m.rho * gvec[0], m.rho * gvec[1]])
            .collect()
    };
    let (c, mut d) = assemble_stiffness(&topo, &dofs, n, &dmats, &bforce, th, opts.parallel);
    lap.lap("stiffness");
    // Full nodal loads: gravity first (th |T|/3 F per vertex, as in d).
    let mut loads = vec![[0.0f64; 2]; np];
    for (tri, &mi) in topo.triangles.iter().zip(&topo.tri_material) {
        let pts = [
            topo.points[tri[0]],
            topo.points[tri[1]],
            topo.points[tri[2]],
        ];
        let w = th * element::area2(&pts) / 6.0;
        let fb = bforce[mi as usize];
        for &p in tri {
            loads[p][0] += w * fb[0];
            loads[p][1] += w * fb[1];
        }
    }
    let mut add_force = |d: &mut Vec<f64>, p: usize, fv: [f64; 2]| {
        loads[p][0] += fv[0];
        loads[p][1] += fv[1];
        let pd = dofs[p];
        for k in 0..pd.ndof {
            d[pd.start + k] += pd.t[k][0] * fv[0] + pd.t[k][1] * fv[1];
        }
    };
    // --- tractions (constant P on each segment: ½ t_h ℓ P per node, §2.2)
    for (i, tr) in f.traction.iter().enumerate() {
        let what = format!("[[traction]] #{} (on = \"{}\")", i + 1, tr.on);
        if let Some(g) = mesh.group_any(&tr.on) {
            if g.dim != 1 {
                return Err(err(format!(
                    "{what}: \"{}\" is a physical {}, expected a curve",
                    tr.on,
                    super::topology::dim_name(g.dim)
                )));
            }
        }
        let items = group_points(&tr.on, &what)?;
        for (p, _, seg) in items {
            let Some((a, b, t)) = seg else { continue };
            let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
            let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            let pv = match (tr.p, tr.pn) {
                (Some(pv), _) => pv,
                (None, Some(pn)) => {
                    let nrm = topo.outward_normal(mesh, t, a, b);
                    [pn * nrm[0], pn * nrm[1]]
                }
                _ => [0.0, 0.0],
            };
            add_force(&mut d, p, [0.5 * th * len * pv[0], 0.5 * th * len * pv[1]]);
        }
    }
    // --- point forces [N per unit thickness]: on the copy of the lowest body
    for (i, fo) in f.force.iter().enumerate() {
        let what = format!("[[force]] #{} (on = \"{}\")", i + 1, fo.on);
        let g = mesh
            .group_any(&fo.on)
            .filter(|g| g.dim == 0)
            .ok_or_else(|| {
                err(format!(
                    "{what}: no physical point named \"{}\" in {} (points: {})",
                    fo.on,
                    mesh.path.display(),
                    super::topology::group_names(mesh, 0)
                ))
            })?;
        for &e in &g.elements {
            let v = mesh.points[e];
            if let Some(&(_, p)) = topo.copies(v).first() {
                // f is per unit thickness, like every other load (§2.2).
                add_force(&mut d, p, [th * fo.f[0], th * fo.f[1]]);
            }
        }
    }

    check_scale(&c, &d, &dofs, &topo, mesh, problem)?;
    lap.lap("loads");
    // --- contact rows in the reduced DOFs
    let mut atrip = vec![];
    let mut g = vec![];
    let mut qp_rows = vec![];
    for (r, row) in topo.contact.iter().enumerate() {
        let mut gr = row.gap0;
        let mut entries = vec![];
        for (p, cvec) in row.coefficients() {
            let pd = dofs[p];
            gr -= cvec[0] * pd.u0[0] + cvec[1] * pd.u0[1];
            for k in 0..pd.ndof {
                let v = cvec[0] * pd.t[k][0] + cvec[1] * pd.t[k][1];
                if v.abs() > 1e-14 {
                    entries.push((pd.start + k, v));
                }
            }
        }
        if entries.is_empty() {
            if gr < -1e-12 * (1.0 + row.gap0.abs()) {
                return Err(err(format!(
                    "contact row at node {} of \"{}\" is violated by the prescribed displacements alone",
                    mesh.node_tags[topo.point_node[row.first]],
                    topo.interface_names[row.interface as usize]
                )));
            }
            continue;
        }
        let qi = qp_rows.len();
        for (j, v) in entries {
            atrip.push((qi, j, v));
        }
        g.push(gr);
        qp_rows.push(r);
    }
    let a = Csr::from_triplets(qp_rows.len(), n, &atrip);

    lap.lap("contact rows");
    // --- rigid modes left after the conditions (per body)
    let (kernel, kernel_body) = rigid_modes(&topo, &dofs, &conds, n);
    let qp = QpProblem { c, d, a, g, kernel };
    let conditions = conds
        .iter()
        .enumerate()
        .flat_map(|(p, cs)| cs.iter().map(move |c| (p, c.r, c.src as u32)))
        .collect();
    let model = Model {
        topo,
        dofs,
        qp,
        qp_rows,
        kernel_body,
        plane: f.model.plane,
        thickness: f.model.thickness,
        conditions,
        cond_groups,
        loads,
        body_names,
    };
    lap.lap("rigid modes");
    check_semicoercive(&model, problem)?;
    lap.lap("semicoercivity check");
    Ok(model)
}

/// Refuses a C or d that is not finite, or whose displacement scale
/// max|d| / max C_ii is so large that energies would overflow (a NaN in the
/// solver otherwise). Names the body and node of the largest load.
fn check_scale(
    c: &Csr,
    d: &[f64],
    dofs: &[PointDofs],
    topo: &Topology,
    mesh: &Mesh,
    problem: &Problem,
) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(&problem.path, msg);
    let point_of = |j: usize| {
        dofs.iter()
            .position(|p| j >= p.start && j < p.start + p.ndof)
    };
    let at = |j: usize| {
        point_of(j)
            .map(|p| {
                format!(
                    "node {} (body {})",
                    mesh.node_tags[topo.point_node[p]], topo.point_body[p]
                )
            })
            .unwrap_or_default()
    };
    if let Some(k) = c.data.iter().position(|v| !v.is_finite()) {
        let row = c.indptr.partition_point(|&s| s <= k).saturating_sub(1);
        return Err(err(format!(
            "the stiffness matrix C is not finite at {}: check E and the coordinates",
            at(row)
        )));
    }
    if let Some(j) = d.iter().position(|v| !v.is_finite()) {
        return Err(err(format!(
            "the load vector d is not finite at {}: the loads overflow; change the units",
            at(j)
        )));
    }
    let cmax = c.diag().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (jmax, dmax) = d.iter().enumerate().fold((0, 0.0f64), |(jm, m), (j, v)| {
        if v.abs() > m {
            (j, v.abs())
        } else {
            (jm, m)
        }
    });
    if cmax > 0.0 && dmax > 0.0 {
        // Displacement and energy scales; 1e250 leaves the solver's own
        // products (norms, squares) room before overflow.
        let u = dmax / cmax;
        if !(u.is_finite() && u * dmax < 1e250 && u < 1e150) {
            return Err(err(format!(
                "the loads (largest |d| = {dmax:e} at {}) on a stiffness of scale {cmax:e} give displacements of about {u:e}: beyond the range of double precision; check E and the loads, or change the units",
                at(jmax)
            )));
        }
    }
    Ok(())
}

/// Each body's name: the physical surface names of its triangles in order
/// of first appearance, "+"-joined (one name unless a body spans several).
fn body_names(topo: &Topology) -> Vec<String> {
    let mut names: Vec<Vec<u32>> = vec![vec![]; topo.nbodies];
    for (&b, &m) in topo.tri_body.iter().zip(&topo.tri_material) {
        let v = &mut names[b as usize];
        if !v.contains(&m) {
            v.push(m);
        }
    }
    let joined: Vec<String> = names
        .iter()
        .map(|ms| {
            ms.iter()
                .map(|&m| topo.material_names[m as usize].as_str())
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

/// Points per parallel work item of the assembly.
const CHUNK_POINTS: usize = 2048;

/// `f` of every item, in order, on rayon's threads if `parallel`. The
/// results never depend on it: every item works on its own data.
fn map_items<T: Send, R: Send>(
    parallel: bool,
    items: Vec<T>,
    f: impl Fn(T) -> R + Sync + Send,
) -> Vec<R> {
    use rayon::prelude::*;
    if !parallel || items.len() <= 1 {
        items.into_iter().map(f).collect()
    } else {
        items.into_par_iter().map(f).collect()
    }
}

/// Run `f` on every item, on rayon's threads if `parallel`.
fn for_each_mut<T: Send>(parallel: bool, items: &mut [T], f: impl Fn(&mut T) + Sync + Send) {
    use rayon::prelude::*;
    if !parallel || items.len() <= 1 {
        items.iter_mut().for_each(f);
    } else {
        items.par_iter_mut().for_each(f);
    }
}

/// The row blocks of a chunk of points (in rank order): columns and values
/// (point i of the chunk at `at[i]..at[i + 1]`), two d entries per point;
/// `coff` is scratch.
#[derive(Default)]
struct Block {
    cols: Vec<usize>,
    vals: Vec<f64>,
    at: Vec<usize>,
    d: Vec<f64>,
    coff: Vec<usize>,
}

/// Where a thread copies the blocks of its DOF rows: the rows, and C's
/// indices and values from entry `off` on, and d, of those rows.
struct Target<'a> {
    rows: std::ops::Range<usize>,
    off: usize,
    ind: &'a mut [usize],
    dat: &'a mut [f64],
    d: &'a mut [f64],
}

/// A point without conditions: ndof 2, T = I, u0 = 0 (the assembly skips
/// the transformation, which changes nothing but the sign of zeros).
fn is_free(pd: &PointDofs) -> bool {
    pd.ndof == 2 && pd.t == [[1.0, 0.0], [0.0, 1.0]] && pd.u0 == [0.0, 0.0]
}

/// Z-order (Morton) keys of 2D positions: 16 bits per axis over the box of
/// all of them. Sorting by key puts nearby positions near each other.
struct Morton {
    lo: [f64; 2],
    scale: [f64; 2],
}

impl Morton {
    fn new(pts: &[[f64; 2]]) -> Morton {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for x in pts {
            for k in 0..2 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        let scale = [0, 1].map(|k| {
            let e = hi[k] - lo[k];
            if e > 0.0 && e.is_finite() {
                65535.0 / e
            } else {
                0.0
            }
        });
        Morton { lo, scale }
    }

    fn key(&self, x: [f64; 2]) -> u64 {
        let q = [0, 1].map(|k| ((x[k] - self.lo[k]) * self.scale[k]).clamp(0.0, 65535.0) as u64);
        let spread = |mut v: u64| {
            v = (v | (v << 8)) & 0x00FF_00FF;
            v = (v | (v << 4)) & 0x0F0F_0F0F;
            v = (v | (v << 2)) & 0x3333_3333;
            (v | (v << 1)) & 0x5555_5555
        };
        spread(q[0]) | (spread(q[1]) << 1)
    }
}

/// Indices 0..keys.len() sorted by (key, index).
fn sorted_by_key(parallel: bool, keys: impl Iterator<Item = u64>) -> Vec<u32> {
    use rayon::prelude::*;
    let mut k: Vec<u64> = keys
        .enumerate()
        .map(|(i, key)| (key << 32) | i as u64)
        .collect();
    if parallel {
        k.par_sort_unstable();
    } else {
        k.sort_unstable();
    }
    k.into_iter().map(|x| x as u32).collect()
}

/// A point as the assembly reads it, stored in Z-order.
#[derive(Clone, Copy, Default)]
struct RankPoint {
    x: [f64; 2],
    start: usize,
    /// The point's index.
    p: u32,
    ndof: u8,
    free: bool,
}

/// A triangle as the assembly reads it: its vertices (Z-order ranks), mesh
/// index and material.
#[derive(Clone, Copy, Default)]
struct TriRec {
    v: [u32; 3],
    t: u32,
    mat: u32,
}

/// C = Σ T_eᵀC_eT_e and the element part of d = Σ T_eᵀ(f_e − C_e u0_e).
///
/// The pattern of C is the point adjacency of the mesh expanded to the
/// DOFs of each point (sorted columns, both triangles). The values are
/// gathered row block by row block: the rows of point p take the rows of
/// p's vertex in the element matrices of its triangles, in increasing
/// triangle order, so every entry is summed in triangle order whatever
/// the number of threads (the same sums as a sequential loop over the
/// triangles), and every work item computes only its own row blocks: no
/// triplets, no sort of C, no allocation per element.
///
/// Gmsh numbers nodes (and so points) in no spatial order, and at a
/// million nodes nearly every access in point order misses the cache. So
/// the work runs over a copy of the point data in Z-order ("ranks") and
/// the triangles grouped by their lowest rank: the triangles around a
/// point and their vertices are then mostly in cache. The row blocks,
/// computed a few chunks of ranks at a time, are copied to their place.
fn assemble_stiffness(
    topo: &Topology,
    dofs: &[PointDofs],
    n: usize,
    dmats: &[[[f64; 3]; 3]],
    bforce: &[[f64; 2]],
    th: f64,
    parallel: bool,
) -> (Csr, Vec<f64>) {
    let np = topo.points.len();
    let mut lap = super::Lap::new("assemble_stiffness");
    // Points in Z-order: rank r holds point rp[r].p.
    let mut rank = vec![0u32; np];
    let rp: Vec<RankPoint> = {
        let z = Morton::new(&topo.points);
        let order = sorted_by_key(parallel, topo.points.iter().map(|&x| z.key(x)));
        order
            .iter()
            .enumerate()
            .map(|(r, &p)| {
                let p = p as usize;
                rank[p] = r as u32;
                let pd = &dofs[p];
                RankPoint {
                    x: topo.points[p],
                    start: pd.start,
                    p: p as u32,
                    ndof: pd.ndof as u8,
                    free: is_free(pd),
                }
            })
            .collect()
    };
    lap.lap("point order");
    // Triangles bucketed by their lowest vertex rank (mesh order within a
    // bucket), vertices as ranks.
    let trec: Vec<TriRec> = {
        let recs = || {
            topo.triangles.iter().enumerate().map(|(t, tri)| TriRec {
                v: tri.map(|v| rank[v]),
                t: t as u32,
                mat: topo.tri_material[t],
            })
        };
        let low = |rec: &TriRec| rec.v.iter().copied().min().unwrap_or(0) as usize;
        super::bucket_sort(recs, low, np).0
    };
    drop(rank);
    lap.lap("triangle order");
    // Rank → its triangles (indices into trec), in increasing mesh order.
    let mut inc_ptr = vec![0usize; np + 1];
    for rec in &trec {
        for &v in &rec.v {
            inc_ptr[v as usize + 1] += 1;
        }
    }
    for r in 0..np {
        inc_ptr[r + 1] += inc_ptr[r];
    }
    let mut inc = vec![0u32; inc_ptr[np]];
    {
        let mut fill = inc_ptr[..np].to_vec();
        for (i, rec) in trec.iter().enumerate() {
            for &v in &rec.v {
                inc[fill[v as usize]] = i as u32;
                fill[v as usize] += 1;
            }
        }
    }
    {
        // Each list in mesh order, chunk by chunk.
        let mut items = Vec::with_capacity(np.div_ceil(CHUNK_POINTS));
        let mut rest = &mut inc[..];
        for s in (0..np).step_by(CHUNK_POINTS) {
            let e = (s + CHUNK_POINTS).min(np);
            let (part, r) = std::mem::take(&mut rest).split_at_mut(inc_ptr[e] - inc_ptr[s]);
            rest = r;
            items.push((s, e, part));
        }
        map_items(parallel, items, |(s, e, part)| {
            for r in s..e {
                part[inc_ptr[r] - inc_ptr[s]..inc_ptr[r + 1] - inc_ptr[s]]
                    .sort_unstable_by_key(|&i| trec[i as usize].t);
            }
        });
    }
    let (rp, trec, inc_ptr, inc) = (&rp[..], &trec[..], &inc_ptr[..], &inc[..]);
    let tris_of = |r: usize| &inc[inc_ptr[r]..inc_ptr[r + 1]];
    lap.lap("incidence");

    let chunks: Vec<(usize, usize)> = (0..np)
        .step_by(CHUNK_POINTS)
        .map(|s| (s, (s + CHUNK_POINTS).min(np)))
        .collect();

    // Pass 1, by rank: the neighbours of each point with DOFs (the vertices
    // with DOFs of its triangles, itself included) as ranks, in increasing
    // point order, and the length of the point's rows.
    // Kept per chunk (rank r is entry r % CHUNK_POINTS of chunk r / CHUNK_POINTS).
    struct Nbrs {
        adj: Vec<u32>,
        ptr: Vec<u32>,
        len: Vec<u32>,
    }
    let parts: Vec<Nbrs> = map_items(parallel, chunks.clone(), |(s, e)| {
        let mut adj: Vec<u32> = Vec::with_capacity((e - s) * 8);
        let mut ptr: Vec<u32> = Vec::with_capacity(e - s + 1);
        let mut len: Vec<u32> = Vec::with_capacity(e - s);
        let mut buf: Vec<u64> = Vec::with_capacity(64);
        ptr.push(0);
        for r in s..e {
            if rp[r].ndof == 0 {
                ptr.push(adj.len() as u32);
                len.push(0);
                continue;
            }
            buf.clear();
            for &i in tris_of(r) {
                for &q in &trec[i as usize].v {
                    let x = &rp[q as usize];
                    let key = ((x.p as u64) << 32) | q as u64;
                    if x.ndof > 0 && !buf.contains(&key) {
                        buf.push(key);
                    }
                }
            }
            buf.sort_unstable();
            let mut l = 0u32;
            for &k in &buf {
                let q = k as u32;
                adj.push(q);
                l += rp[q as usize].ndof as u32;
            }
            ptr.push(adj.len() as u32);
            len.push(l);
        }
        Nbrs { adj, ptr, len }
    });
    let parts = &parts[..];
    let nbrs = |r: usize| {
        let (c, k) = (&parts[r / CHUNK_POINTS], r % CHUNK_POINTS);
        &c.adj[c.ptr[k] as usize..c.ptr[k + 1] as usize]
    };
    lap.lap("neighbours");
    // CSR row pointers in DOF order.
    let mut len_of = vec![0u32; np];
    for (r, x) in rp.iter().enumerate() {
        len_of[x.p as usize] = parts[r / CHUNK_POINTS].len[r % CHUNK_POINTS];
    }
    let mut indptr = Vec::with_capacity(n + 1);
    indptr.push(0usize);
    for (pd, &len) in dofs.iter().zip(&len_of) {
        for _ in 0..pd.ndof {
            indptr.push(indptr[indptr.len() - 1] + len as usize);
        }
    }
    drop(len_of);
    let nnz = indptr[n];
    let indptr_ref = &indptr[..];
    lap.lap("row pointers");

    // Pass 2, by rank: each chunk's row blocks (columns, values, d) into
    // its own buffers; a few chunks per thread at a time, then copied.
    let block = |((s, e), mut buf): ((usize, usize), Block)| -> Block {
        let Block {
            cols,
            vals,
            at,
            d: dv,
            coff,
        } = &mut buf;
        cols.clear();
        vals.clear();
        at.clear();
        at.push(0);
        dv.clear();
        dv.resize(2 * (e - s), 0.0);
        for r in s..e {
            let pr = rp[r];
            if pr.ndof == 0 {
                at.push(cols.len());
                continue;
            }
            let nb = nbrs(r);
            coff.clear();
            let c0 = cols.len();
            for &q in nb {
                let x = &rp[q as usize];
                coff.push(cols.len() - c0);
                cols.extend(x.start..x.start + x.ndof as usize);
            }
            let len = cols.len() - c0;
            for _ in 1..pr.ndof {
                cols.extend_from_within(c0..c0 + len);
            }
            let v0 = vals.len();
            vals.resize(v0 + pr.ndof as usize * len, 0.0);
            let blk = &mut vals[v0..];
            let dr = &mut dv[2 * (r - s)..2 * (r - s) + 2];
            let pp = if pr.free {
                None
            } else {
                Some(&dofs[pr.p as usize])
            };
            for &i in tris_of(r) {
                let rec = trec[i as usize];
                let vx = rec.v.map(|v| &rp[v as usize]);
                let a = if rec.v[0] as usize == r {
                    0
                } else if rec.v[1] as usize == r {
                    1
                } else {
                    2
                };
                let mi = rec.mat as usize;
                let pts = [vx[0].x, vx[1].x, vx[2].x];
                let ke = element::stiffness_rows(&pts, &dmats[mi], th, a);
                let area = element::area2(&pts) / 2.0;
                let fb = bforce[mi];
                let mut fe = [th * area / 3.0 * fb[0], th * area / 3.0 * fb[1]];
                // fe − Ke u0
                for (k, fk) in fe.iter_mut().enumerate() {
                    for b in 0..3 {
                        if vx[b].free {
                            continue;
                        }
                        let u0 = dofs[vx[b].p as usize].u0;
                        *fk -= ke[k][2 * b] * u0[0] + ke[k][2 * b + 1] * u0[1];
                    }
                }
                match pp {
                    None => {
                        dr[0] += fe[0];
                        dr[1] += fe[1];
                    }
                    Some(pp) => {
                        for ka in 0..pp.ndof {
                            let ta = pp.t[ka];
                            dr[ka] += ta[0] * fe[0] + ta[1] * fe[1];
                        }
                    }
                }
                for b in 0..3 {
                    if vx[b].ndof == 0 {
                        continue;
                    }
                    let col = nb
                        .iter()
                        .position(|&q| q == rec.v[b])
                        .map(|k| coff[k])
                        .unwrap_or(0);
                    match pp {
                        None if vx[b].free => {
                            blk[col] += ke[0][2 * b];
                            blk[col + 1] += ke[0][2 * b + 1];
                            blk[len + col] += ke[1][2 * b];
                            blk[len + col + 1] += ke[1][2 * b + 1];
                        }
                        _ => {
                            let pa = &dofs[pr.p as usize];
                            let pb = &dofs[vx[b].p as usize];
                            for ka in 0..pa.ndof {
                                let ta = pa.t[ka];
                                let row = ka * len + col;
                                for kb in 0..pb.ndof {
                                    let tb = pb.t[kb];
                                    let v = ta[0]
                                        * (ke[0][2 * b] * tb[0] + ke[0][2 * b + 1] * tb[1])
                                        + ta[1] * (ke[1][2 * b] * tb[0] + ke[1][2 * b + 1] * tb[1]);
                                    blk[row + kb] += v;
                                }
                            }
                        }
                    }
                }
            }
            at.push(cols.len());
        }
        buf
    };
    let mut indices = vec![0usize; nnz];
    let mut data = vec![0.0f64; nnz];
    let mut d = vec![0.0f64; n];
    let threads = if parallel {
        rayon::current_num_threads().max(1)
    } else {
        1
    };
    // The copy goes to `threads` disjoint ranges of DOFs, each scanning
    // the round's blocks for its own points.
    let mut targets = Vec::with_capacity(threads);
    {
        let (mut ind_rest, mut dat_rest, mut d_rest) =
            (&mut indices[..], &mut data[..], &mut d[..]);
        let (mut lo, mut off) = (0usize, 0usize);
        for k in 1..=threads {
            // The rows [lo, hi) of whole points, with about k/threads of
            // the entries.
            let hi = if k == threads {
                n
            } else {
                let q = dofs.partition_point(|pd| indptr[pd.start] < nnz / threads * k);
                dofs.get(q).map(|pd| pd.start).unwrap_or(n).max(lo)
            };
            let end = indptr[hi];
            let (ind, ir) = std::mem::take(&mut ind_rest).split_at_mut(end - off);
            let (dat, dr) = std::mem::take(&mut dat_rest).split_at_mut(end - off);
            let (dd, ddr) = std::mem::take(&mut d_rest).split_at_mut(hi - lo);
            ind_rest = ir;
            dat_rest = dr;
            d_rest = ddr;
            targets.push(Target {
                rows: lo..hi,
                off,
                ind,
                dat,
                d: dd,
            });
            lo = hi;
            off = end;
        }
    }
    let per_round = 2 * threads;
    let mut pool: Vec<Block> = (0..per_round).map(|_| Block::default()).collect();
    for round in chunks.chunks(per_round) {
        let items: Vec<_> = round.iter().copied().zip(pool.drain(..)).collect();
        let out = map_items(parallel, items, block);
        let copy = |t: &mut Target| {
            for (&(s, e), b) in round.iter().zip(&out) {
                for r in s..e {
                    let x = rp[r];
                    let k = x.ndof as usize;
                    if k == 0 || !t.rows.contains(&x.start) {
                        continue;
                    }
                    let (b0, b1) = (b.at[r - s], b.at[r - s + 1]);
                    let i0 = indptr_ref[x.start] - t.off;
                    let i1 = i0 + (b1 - b0);
                    t.ind[i0..i1].copy_from_slice(&b.cols[b0..b1]);
                    t.dat[i0..i1].copy_from_slice(&b.vals[b0..b1]);
                    let (d0, dk) = (x.start - t.rows.start, 2 * (r - s));
                    t.d[d0..d0 + k].copy_from_slice(&b.d[dk..dk + k]);
                }
            }
        };
        for_each_mut(parallel, &mut targets, copy);
        pool = out;
    }
    drop(targets);
    lap.lap("values");
    let c = Csr {
        nrows: n,
        ncols: n,
        indptr,
        indices,
        data,
    };
    (c, d)
}

/// Combine the conditions r·u = v at one point into u = u0 + Tξ.
fn eliminate(cs: &[Cond]) -> Result<PointDofs, String> {
    let mut pd = PointDofs {
        start: 0,
        ndof: 2,
        t: [[1.0, 0.0], [0.0, 1.0]],
        u0: [0.0, 0.0],
    };
    if cs.is_empty() {
        return Ok(pd);
    }
    let q1 = normalize(cs[0].r);
    let v1 = cs[0].v / norm2(cs[0].r);
    // A second, independent condition?
    let second = cs.iter().skip(1).find(|c| {
        let r = normalize(c.r);
        (r[0] * q1[1] - r[1] * q1[0]).abs() > 1e-8
    });
    match second {
        None => {
            // all parallel: check consistency
            for c in &cs[1..] {
                let r = normalize(c.r);
                let s = r[0] * q1[0] + r[1] * q1[1];
                let v = c.v / norm2(c.r);
                if (v - s * v1).abs() > 1e-9 * (1.0 + v.abs() + v1.abs()) {
                    return Err(format!(
                        "two conditions prescribe different values ({} and {}) in one direction",
                        v1 * s,
                        v
                    ));
                }
            }
            pd.ndof = 1;
            pd.u0 = [v1 * q1[0], v1 * q1[1]];
            pd.t = [[-q1[1], q1[0]], [0.0, 0.0]];
        }
        Some(c2) => {
            let (r1, r2) = (cs[0].r, c2.r);
            let det = r1[0] * r2[1] - r1[1] * r2[0];
            let u = [
                (cs[0].v * r2[1] - c2.v * r1[1]) / det,
                (r1[0] * c2.v - r2[0] * cs[0].v) / det,
            ];
            for c in cs {
                let res = c.r[0] * u[0] + c.r[1] * u[1] - c.v;
                if res.abs() > 1e-9 * (1.0 + c.v.abs() + u[0].abs() + u[1].abs()) {
                    return Err(format!(
                        "more than two independent conditions that disagree (residual {res:.3e})"
                    ));
                }
            }
            pd.ndof = 0;
            pd.u0 = u;
            pd.t = [[0.0, 0.0], [0.0, 0.0]];
        }
    }
    Ok(pd)
}

fn norm2(r: [f64; 2]) -> f64 {
    (r[0] * r[0] + r[1] * r[1]).sqrt()
}
fn normalize(r: [f64; 2]) -> [f64; 2] {
    let l = norm2(r);
    [r[0] / l, r[1] / l]
}

/// Rigid motions z = (a1 − b·ȳ, a2 + b·x̄) of each body that satisfy the
/// homogeneous conditions (methods.md §1.7), in reduced DOFs, orthonormalised.
fn rigid_modes(
    topo: &Topology,
    dofs: &[PointDofs],
    conds: &[Vec<Cond>],
    n: usize,
) -> (Vec<Vec<f64>>, Vec<u32>) {
    let nb = topo.nbodies;
    let mut lo = vec![[f64::MAX; 2]; nb];
    let mut hi = vec![[f64::MIN; 2]; nb];
    for (p, x) in topo.points.iter().enumerate() {
        let b = topo.point_body[p] as usize;
        for k in 0..2 {
            lo[b][k] = lo[b][k].min(x[k]);
            hi[b][k] = hi[b][k].max(x[k]);
        }
    }
    // GᵀG per body (3×3) from every condition row.
    let mut gtg = vec![[[0.0f64; 3]; 3]; nb];
    let basis = |b: usize, x: [f64; 2]| -> [[f64; 2]; 3] {
        let c = [(lo[b][0] + hi[b][0]) / 2.0, (lo[b][1] + hi[b][1]) / 2.0];
        let l = ((hi[b][0] - lo[b][0]).max(hi[b][1] - lo[b][1])).max(1e-300);
        [
            [1.0, 0.0],
            [0.0, 1.0],
            [-(x[1] - c[1]) / l, (x[0] - c[0]) / l],
        ]
    };
    for (p, cs) in conds.iter().enumerate() {
        let b = topo.point_body[p] as usize;
        let z = basis(b, topo.points[p]);
        for c in cs {
            let r = normalize(c.r);
            let row: [f64; 3] = z.map(|zi| r[0] * zi[0] + r[1] * zi[1]);
            for i in 0..3 {
                for j in 0..3 {
                    gtg[b][i][j] += row[i] * row[j];
                }
            }
        }
    }
    // Points of each body (they are numbered body after body, but do not
    // rely on it): CSR by counting.
    let mut bptr = vec![0usize; nb + 1];
    for &b in &topo.point_body {
        bptr[b as usize + 1] += 1;
    }
    for b in 0..nb {
        bptr[b + 1] += bptr[b];
    }
    let mut bpts = vec![0usize; topo.point_body.len()];
    {
        let mut fill = bptr[..nb].to_vec();
        for (p, &b) in topo.point_body.iter().enumerate() {
            bpts[fill[b as usize]] = p;
            fill[b as usize] += 1;
        }
    }
    let mut kernel = vec![];
    let mut owner = vec![];
    for b in 0..nb {
        let (vals, vecs) = sym_eigen(&gtg[b].iter().map(|r| r.to_vec()).collect::<Vec<_>>());
        for k in 0..3 {
            if vals[k] > 1e-9 {
                continue;
            }
            let c = &vecs[k];
            let mut v = vec![0.0; n];
            for &p in &bpts[bptr[b]..bptr[b + 1]] {
                let pd = &dofs[p];
                let z = basis(b, topo.points[p]);
                let u = [
                    c[0] * z[0][0] + c[1] * z[1][0] + c[2] * z[2][0],
                    c[0] * z[0][1] + c[1] * z[1][1] + c[2] * z[2][1],
                ];
                for j in 0..pd.ndof {
                    v[pd.start + j] = pd.t[j][0] * u[0] + pd.t[j][1] * u[1];
                }
            }
            // Only the body's DOFs are nonzero (in increasing order: the
            // same sum as over all of v).
            let body_dofs = bpts[bptr[b]..bptr[b + 1]]
                .iter()
                .flat_map(|&p| dofs[p].start..dofs[p].start + dofs[p].ndof);
            let nv = body_dofs.clone().map(|i| v[i] * v[i]).sum::<f64>().sqrt();
            if nv > 0.0 {
                for i in body_dofs {
                    v[i] /= nv;
                }
                kernel.push(v);
                owner.push(b as u32);
            }
        }
    }
    (kernel, owner)
}

/// A coordinate for messages: 6 significant digits, no trailing noise.
fn g_sig(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    format!("{v:.5e}")
        .parse::<f64>()
        .map(|x| format!("{}", x + 0.0))
        .unwrap_or_else(|_| format!("{v}"))
}

/// The bodies and the rigid motion (translation direction or centre of
/// rotation) of the kernel combination Σ c_k z_k.
fn describe_mode(m: &Model, c: &[f64]) -> String {
    let n = m.qp.n();
    let mut z = vec![0.0; n];
    for (ck, zk) in c.iter().zip(&m.qp.kernel) {
        for (zi, v) in z.iter_mut().zip(zk) {
            *zi += ck * v;
        }
    }
    m.describe_rigid_motion(&m.motions(&z))
}

/// Semicoercive checks of methods.md §1.7 that need no iteration: a body
/// with free rigid motions and no contact at all, and a rigid motion that
/// leaves every contact row unchanged (Az = 0) while the loads work on it
/// (dᵀz ≠ 0): f is then unbounded below.
fn check_semicoercive(m: &Model, problem: &Problem) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(&problem.path, msg);
    let qp = &m.qp;
    let k = qp.kernel.len();
    if k == 0 {
        return Ok(());
    }
    // Bodies with a kernel and no contact row touching them.
    let mut touched = vec![false; m.topo.nbodies];
    for &r in &m.qp_rows {
        for (p, _) in m.topo.contact[r].coefficients() {
            touched[m.topo.point_body[p] as usize] = true;
        }
    }
    for &b in &m.kernel_body {
        if !touched[b as usize] {
            let modes: Vec<&Vec<f64>> = m
                .kernel_body
                .iter()
                .zip(&qp.kernel)
                .filter(|(&x, _)| x == b)
                .map(|(_, z)| z)
                .collect();
            let work = modes
                .iter()
                .any(|z| z.iter().zip(&qp.d).map(|(a, b)| a * b).sum::<f64>().abs() > 0.0);
            let free = if modes.len() >= 3 {
                "no Dirichlet or slip condition fixes it".to_string()
            } else {
                let what: Vec<String> = modes
                    .iter()
                    .filter_map(|z| m.body_motion(&m.motions(z), b as usize, 0.0))
                    .collect();
                format!(
                    "its Dirichlet and slip conditions leave {} free",
                    what.join(" and ")
                )
            };
            return Err(err(format!(
                "{} is not supported: {free} and it has no contact ({} free rigid motion(s){})",
                m.body_label(b as usize),
                modes.len(),
                if work {
                    "; the loads would move it without limit"
                } else {
                    ""
                }
            )));
        }
    }
    // Null space of A Z (k small): eigenvectors of (AZ)ᵀ(AZ) with ~0 eigenvalue.
    let az: Vec<Vec<f64>> = qp.kernel.iter().map(|z| qp.a.mul(z)).collect();
    let mut mtm = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..k {
            mtm[i][j] = az[i].iter().zip(&az[j]).map(|(a, b)| a * b).sum();
        }
    }
    let dz: Vec<f64> = qp
        .kernel
        .iter()
        .map(|z| z.iter().zip(&qp.d).map(|(a, b)| a * b).sum())
        .collect();
    let dnorm = qp.d.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
    let (vals, vecs) = sym_eigen(&mtm);
    let amax = vals.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(1e-300);
    for (lam, c) in vals.iter().zip(&vecs) {
        if *lam <= 1e-12 * amax {
            let work: f64 = c.iter().zip(&dz).map(|(a, b)| a * b).sum();
            if work.abs() > 1e-9 * dnorm {
                return Err(err(format!(
                    "the problem is unbounded: a rigid motion of {} slides along every contact without opening it, and the loads do work on it (semicoercive condition of methods.md §1.7 violated)",
                    describe_mode(m, c)
                )));
            }
            log::warn!(
                "a rigid motion of {} is free (loads do no work on it): the solution is not unique",
                describe_mode(m, c)
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The former assembly: 36 triplets per triangle, then
    /// `Csr::from_triplets` (the reference for the gathered assembly).
    fn reference_stiffness(
        topo: &Topology,
        dofs: &[PointDofs],
        n: usize,
        dmats: &[[[f64; 3]; 3]],
        bforce: &[[f64; 2]],
        th: f64,
    ) -> (Csr, Vec<f64>) {
        let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(topo.triangles.len() * 36);
        let mut d = vec![0.0; n];
        for (t, tri) in topo.triangles.iter().enumerate() {
            let mi = topo.tri_material[t] as usize;
            let pts = [
                topo.points[tri[0]],
                topo.points[tri[1]],
                topo.points[tri[2]],
            ];
            let ke = element::stiffness(&pts, &dmats[mi], th);
            let area = element::area2(&pts) / 2.0;
            let fb = bforce[mi];
            let mut fe = [0.0; 6];
            for a in 0..3 {
                fe[2 * a] = th * area / 3.0 * fb[0];
                fe[2 * a + 1] = th * area / 3.0 * fb[1];
            }
            for i in 0..6 {
                for b in 0..3 {
                    let u0 = dofs[tri[b]].u0;
                    fe[i] -= ke[i][2 * b] * u0[0] + ke[i][2 * b + 1] * u0[1];
                }
            }
            for a in 0..3 {
                let pa = dofs[tri[a]];
                for ka in 0..pa.ndof {
                    let ta = pa.t[ka];
                    let ia = pa.start + ka;
                    d[ia] += ta[0] * fe[2 * a] + ta[1] * fe[2 * a + 1];
                    for b in 0..3 {
                        let pb = dofs[tri[b]];
                        for kb in 0..pb.ndof {
                            let tb = pb.t[kb];
                            let v = ta[0]
                                * (ke[2 * a][2 * b] * tb[0] + ke[2 * a][2 * b + 1] * tb[1])
                                + ta[1]
                                    * (ke[2 * a + 1][2 * b] * tb[0]
                                        + ke[2 * a + 1][2 * b + 1] * tb[1]);
                            trip.push((ia, pb.start + kb, v));
                        }
                    }
                }
            }
        }
        (Csr::from_triplets(n, n, &trip), d)
    }

    #[test]
    fn gathered_assembly_matches_triplets_on_shipped_models() {
        for (path, problem, mesh) in crate::shipped_examples() {
            let m = build(&mesh, &problem).unwrap();
            let f = &problem.file;
            let th = match f.model.plane {
                Plane::Stress => f.model.thickness,
                Plane::Strain => 1.0,
            };
            let mats: Vec<&crate::problem::Material> = m
                .topo
                .material_names
                .iter()
                .map(|x| &f.materials[x])
                .collect();
            let dmats: Vec<_> = mats
                .iter()
                .map(|x| element::d_matrix(x, f.model.plane))
                .collect();
            let gvec = f.model.gravity.unwrap_or([0.0, 0.0]);
            let bforce: Vec<_> = mats
                .iter()
                .map(|x| [x.rho * gvec[0], x.rho * gvec[1]])
                .collect();
            let n = m.qp.n();
            let (cr, dr) = reference_stiffness(&m.topo, &m.dofs, n, &dmats, &bforce, th);
            let (cs, ds) = assemble_stiffness(&m.topo, &m.dofs, n, &dmats, &bforce, th, false);
            let (cp, dp) = assemble_stiffness(&m.topo, &m.dofs, n, &dmats, &bforce, th, true);
            // Threads change nothing, bit for bit.
            assert_eq!(cs, cp, "{}", path.display());
            assert_eq!(ds, dp);
            // Same pattern; values equal up to the order of summation.
            assert_eq!(cs.indptr, cr.indptr, "{}", path.display());
            assert_eq!(cs.indices, cr.indices, "{}", path.display());
            let cmax = cr.data.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (x, y) in cs.data.iter().zip(&cr.data) {
                assert!(
                    (x - y).abs() <= 1e-14 * cmax,
                    "{}: {x} vs {y}",
                    path.display()
                );
            }
            // d is summed in triangle order in both: bit for bit.
            assert_eq!(ds, dr, "{}", path.display());
        }
    }
}
