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
use crate::mesh::Mesh;
use crate::model::{Plane, Problem};
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
}

impl Model {
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
                    .map(|what| format!("body {b} ({what})"))
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

/// Build the whole model: topology, conditions, QP.
pub fn build(mesh: &Mesh, problem: &Problem) -> Result<Model, FemError> {
    let topo = Topology::build(mesh, problem)?;
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

    // --- eliminate per point
    let mut dofs = Vec::with_capacity(np);
    let mut next = 0usize;
    for (p, cs) in conds.iter().enumerate() {
        let pd = eliminate(cs).map_err(|m| {
            let mut from: Vec<usize> = cs.iter().map(|c| c.src).collect();
            from.sort_unstable();
            from.dedup();
            let from: Vec<&str> = from.iter().map(|&i| cond_src[i].as_str()).collect();
            err(format!(
                "conflicting conditions at node {} (body {}) from {}: {m}",
                mesh.node_tags[topo.point_node[p]],
                topo.point_body[p],
                from.join(", ")
            ))
        })?;
        let pd = PointDofs { start: next, ..pd };
        next += pd.ndof;
        dofs.push(pd);
    }
    let n = next;

    // --- stiffness and body force
    let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(topo.triangles.len() * 36);
    let mut d = vec![0.0; n];
    let mats: Vec<&crate::model::Material> = topo
        .material_names
        .iter()
        .map(|m| &f.materials[m])
        .collect();
    let dmats: Vec<[[f64; 3]; 3]> = mats
        .iter()
        .map(|m| element::d_matrix(m, f.model.plane))
        .collect();
    let gvec = f.model.gravity.unwrap_or([0.0, 0.0]);
    for (t, tri) in topo.triangles.iter().enumerate() {
        let mi = topo.tri_material[t] as usize;
        let pts = [
            topo.points[tri[0]],
            topo.points[tri[1]],
            topo.points[tri[2]],
        ];
        let ke = element::stiffness(&pts, &dmats[mi], th);
        let area = element::area2(&pts) / 2.0;
        let fb = [mats[mi].rho * gvec[0], mats[mi].rho * gvec[1]];
        let mut fe = [0.0; 6];
        for a in 0..3 {
            fe[2 * a] = th * area / 3.0 * fb[0];
            fe[2 * a + 1] = th * area / 3.0 * fb[1];
        }
        // fe − Ke u0
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
                        let v = ta[0] * (ke[2 * a][2 * b] * tb[0] + ke[2 * a][2 * b + 1] * tb[1])
                            + ta[1]
                                * (ke[2 * a + 1][2 * b] * tb[0] + ke[2 * a + 1][2 * b + 1] * tb[1]);
                        trip.push((ia, pb.start + kb, v));
                    }
                }
            }
        }
    }
    let add_force = |d: &mut Vec<f64>, p: usize, fv: [f64; 2]| {
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
    let c = Csr::from_triplets(n, n, &trip);
    drop(trip);

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

    // --- rigid modes left after the conditions (per body)
    let (kernel, kernel_body) = rigid_modes(&topo, &dofs, &conds, n);
    let qp = QpProblem { c, d, a, g, kernel };
    let model = Model {
        topo,
        dofs,
        qp,
        qp_rows,
        kernel_body,
        plane: f.model.plane,
        thickness: f.model.thickness,
    };
    check_semicoercive(&model, problem)?;
    Ok(model)
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
            let row: Vec<f64> = z.iter().map(|zi| r[0] * zi[0] + r[1] * zi[1]).collect();
            for i in 0..3 {
                for j in 0..3 {
                    gtg[b][i][j] += row[i] * row[j];
                }
            }
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
            for (p, pd) in dofs.iter().enumerate() {
                if topo.point_body[p] as usize != b {
                    continue;
                }
                let z = basis(b, topo.points[p]);
                let u = [
                    c[0] * z[0][0] + c[1] * z[1][0] + c[2] * z[2][0],
                    c[0] * z[0][1] + c[1] * z[1][1] + c[2] * z[2][1],
                ];
                for j in 0..pd.ndof {
                    v[pd.start + j] = pd.t[j][0] * u[0] + pd.t[j][1] * u[1];
                }
            }
            let nv = v.iter().map(|a| a * a).sum::<f64>().sqrt();
            if nv > 0.0 {
                v.iter_mut().for_each(|a| *a /= nv);
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
                "body {b} is not supported: {free} and it has no contact ({} free rigid motion(s){})",
                modes.len(),
                if work { "; the loads would move it without limit" } else { "" }
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

/// Symmetric eigen-decomposition of a small dense matrix (cyclic Jacobi).
pub fn sym_eigen(a: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = a.len();
    let mut a: Vec<Vec<f64>> = a.to_vec();
    let mut v: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    for _ in 0..100 {
        let mut off = 0.0;
        let mut diag = 0.0;
        for i in 0..n {
            diag += a[i][i].abs();
            for j in i + 1..n {
                off += a[i][j].abs();
            }
        }
        if off <= 1e-15 * diag.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = if theta == 0.0 {
                    1.0
                } else {
                    theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let vals = (0..n).map(|i| a[i][i]).collect();
    let vecs = (0..n).map(|k| (0..n).map(|i| v[i][k]).collect()).collect();
    (vals, vecs)
}
