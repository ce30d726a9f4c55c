//! The loads: gravity, tractions and point forces as nodal forces, added to
//! d through each point's T (docs/methods.md §2.2, §2.8), and a check that
//! C and d stay within the range of double precision.
//!
//! Gravity is th |T|/3 ρ g per vertex (summed in triangle order, as the
//! element part of d in `stiffness.rs`), a traction P on a segment of
//! length ℓ is ½ th ℓ P per node, and a point force f (per unit thickness)
//! acts on the copy of the lowest body. The full nodal loads (before the
//! elimination) are kept for the reactions R = K u − f.

use super::conditions::PointDofs;
use super::element::ElementKind;
use super::element::Vector;
use super::stiffness::Materials;
use super::topology::{dim_name, group_names, Topology};
use super::{FemError, Model};
use crate::mesh::Mesh;
use crate::problem::{
    num, shorten, Dirichlet, Force, Material, ModelSection, Slip, Traction, TractionLoad,
    MAX_MAGNITUDE,
};
use crate::qp::Csr;
use std::collections::BTreeMap;
use std::path::Path;

/// The boundary loads of a problem: its `[[traction]]` and `[[force]]`
/// entries.
#[derive(Clone, Copy)]
pub(super) struct BoundaryLoads<'a> {
    pub(super) traction: &'a [Traction],
    pub(super) force: &'a [Force],
}

/// The nodal loads on every point [N] (thickness included), and their
/// tractions and point forces (`bl`) added to `d` (gravity is in d
/// already); messages name `path`, the TOML file.
pub(super) fn nodal_loads(
    mesh: &Mesh,
    topo: &Topology,
    dofs: &[PointDofs],
    path: &Path,
    bl: BoundaryLoads,
    mats: &Materials,
    d: &mut [f64],
) -> Result<Vec<Vector>, FemError> {
    let mut loads = Loads {
        dofs,
        nodal: gravity(topo, mats),
        d,
        kind: mats.kind,
    };
    loads.add_tractions(mesh, topo, path, bl.traction)?;
    loads.add_point_forces(mesh, topo, path, bl.force)?;
    Ok(loads.nodal)
}

/// The body loads on each point: th |T|/3 ρ g per vertex (with the
/// centrifugal load per radian when axisymmetric), in triangle order.
fn gravity(topo: &Topology, mats: &Materials) -> Vec<Vector> {
    let mut loads = vec![[0.0f64; 2]; topo.points.len()];
    for (tri, &mi) in topo.triangles.iter().zip(&topo.tri_material) {
        let pts = [
            topo.points[tri[0]],
            topo.points[tri[1]],
            topo.points[tri[2]],
        ];
        let (fb, c) = (mats.bforce[mi as usize], mats.spin[mi as usize]);
        for (a, &p) in tri.iter().enumerate() {
            let f = mats.kind.nodal_body_load(&pts, a, fb, c);
            loads[p][0] += f[0];
            loads[p][1] += f[1];
        }
    }
    loads
}

/// Refuses a body force beyond ±[`MAX_MAGNITUDE`] (the bound of every
/// load, docs/problem-format.md §2): ρ|g| of each material, and with a spin
/// the centrifugal ρω²·r_max (r_max the largest radius of the material's
/// triangles). Names the key and the material: a load past the bound
/// overflows in the solver's products (a stagnation far from the cause).
pub(super) fn check_body_forces(
    topo: &Topology,
    materials: &BTreeMap<String, Material>,
    model: &ModelSection,
    path: &Path,
) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let g = model.gravity.map_or([0.0, 0.0], |g| g.xy());
    let w = model.omega.unwrap_or(0.0);
    let mut r_max = vec![0.0f64; topo.material_names.len()];
    for (tri, &mi) in topo.triangles.iter().zip(&topo.tri_material) {
        for &p in tri {
            if let Some(r) = r_max.get_mut(mi as usize) {
                *r = r.max(topo.points[p][0].abs());
            }
        }
    }
    for (mi, name) in topo.material_names.iter().enumerate() {
        let Some(m) = materials.get(name) else {
            continue;
        };
        let rg = m.rho * g[0].hypot(g[1]);
        if !(rg <= MAX_MAGNITUDE) {
            return Err(err(format!(
                "[model] gravity with [materials.{}] rho = {}: the body force ρ|g| = {rg:.3e} is beyond ±{MAX_MAGNITUDE:e}; change the units",
                shorten(name),
                num(m.rho)
            )));
        }
        if w != 0.0 {
            let Some(c) = topo.kind.centrifugal_force(m.rho, w, r_max[mi]) else {
                continue;
            };
            if !(c <= MAX_MAGNITUDE) {
                return Err(err(format!(
                    "[model] omega = {}: the centrifugal body force ρω²r of [materials.{}] (rho = {}, r up to {:.3e}) reaches {c:.3e}, beyond ±{MAX_MAGNITUDE:e}; change the units or the spin",
                    num(w),
                    shorten(name),
                    num(m.rho),
                    r_max[mi]
                )));
            }
        }
    }
    Ok(())
}

/// Warns of each `[[traction]]` whose every segment has no measure in the
/// model's kind ([`ElementKind::measureless_segment`]: the axis r = 0 of
/// an axisymmetric model, ∫ N r ds = 0 there), so that it adds no load at
/// all.
pub(super) fn warn_measureless_tractions(
    mesh: &Mesh,
    kind: ElementKind,
    tractions: &[Traction],
    path: &Path,
) {
    for (i, tr) in tractions.iter().enumerate() {
        let Some(g) = mesh.group_any(&tr.on).filter(|g| g.dim == 1) else {
            continue;
        };
        let why = |l: &[usize; 2]| match (mesh.nodes.get(l[0]), mesh.nodes.get(l[1])) {
            (Some(&a), Some(&b)) => kind.measureless_segment(a, b),
            _ => None,
        };
        let lines: Vec<[usize; 2]> = g
            .elements
            .iter()
            .filter_map(|&li| mesh.lines.get(li).copied())
            .collect();
        let Some(where_) = lines.first().and_then(why) else {
            continue;
        };
        if lines.iter().all(|l| why(l).is_some()) {
            log::warn!(
                "{}: [[traction]] #{} (on = \"{}\"): the curve lies on {where_}, where a traction acts on no area; it adds no load",
                path.display(),
                i + 1,
                shorten(&tr.on)
            );
        }
    }
}

/// The nodal loads being summed, and d.
struct Loads<'a> {
    dofs: &'a [PointDofs],
    nodal: Vec<Vector>,
    d: &'a mut [f64],
    /// The measure of the tractions: ½ th ℓ, or ∫ N_a r ds per radian.
    kind: ElementKind,
}

impl Loads<'_> {
    /// A force `fv` on point `p`: on the nodal loads, and Tᵀfv on d.
    fn add(&mut self, p: usize, fv: Vector) {
        self.nodal[p][0] += fv[0];
        self.nodal[p][1] += fv[1];
        let pd = self.dofs[p];
        for k in 0..pd.ndof {
            self.d[pd.start + k] += pd.t[k][0] * fv[0] + pd.t[k][1] * fv[1];
        }
    }

    /// `[[traction]]`: a constant P (or pn along the outward normal) on each
    /// segment, ½ th ℓ P per node (§2.2).
    fn add_tractions(
        &mut self,
        mesh: &Mesh,
        topo: &Topology,
        path: &Path,
        traction: &[Traction],
    ) -> Result<(), FemError> {
        for (i, tr) in traction.iter().enumerate() {
            let what = format!("[[traction]] #{} (on = \"{}\")", i + 1, tr.on);
            if let Some(g) = mesh.group_any(&tr.on) {
                if g.dim != 1 {
                    return Err(FemError::new(
                        path,
                        format!(
                            "{what}: \"{}\" is a physical {}, expected a curve",
                            tr.on,
                            dim_name(g.dim)
                        ),
                    ));
                }
            }
            for (p, v, seg) in topo.group_points(mesh, path, &tr.on, &what)? {
                let Some((a, b, t)) = seg else { continue };
                let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
                let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
                let pv = match tr.load {
                    TractionLoad::Vector(pv) => pv.xy(),
                    TractionLoad::Normal(pn) => {
                        let nrm = topo.outward_normal(mesh, t, a, b);
                        [pn * nrm[0], pn * nrm[1]]
                    }
                };
                // ½ th ℓ, or ∫ N_p r ds = ℓ(2r_p + r_q)/6 per radian
                // (docs/methods.md §10).
                let (xp, xq) = if v == a { (pa, pb) } else { (pb, pa) };
                let w = self.kind.traction_weight(len, xp, xq);
                self.add(p, [w * pv[0], w * pv[1]]);
            }
        }
        Ok(())
    }

    /// `[[force]]` [N per unit thickness]: on the copy of the lowest body of
    /// each node of a physical point.
    fn add_point_forces(
        &mut self,
        mesh: &Mesh,
        topo: &Topology,
        path: &Path,
        force: &[Force],
    ) -> Result<(), FemError> {
        let th = self.kind.thickness();
        for (i, fo) in force.iter().enumerate() {
            let what = format!("[[force]] #{} (on = \"{}\")", i + 1, fo.on);
            let g = mesh
                .group_any(&fo.on)
                .filter(|g| g.dim == 0)
                .ok_or_else(|| {
                    FemError::new(
                        path,
                        format!(
                            "{what}: no physical point named \"{}\" in {} (points: {})",
                            fo.on,
                            mesh.path.display(),
                            group_names(mesh, 0)
                        ),
                    )
                })?;
            for &e in &g.elements {
                let v = mesh.points[e];
                if let Some(&(_, p)) = topo.copies(v).first() {
                    // f is per unit thickness, like every other load (§2.2);
                    // per radian in an axisymmetric model (th = 1).
                    let f = fo.f.xy();
                    self.add(p, [th * f[0], th * f[1]]);
                }
            }
        }
        Ok(())
    }
}

/// What a load step changes in a model (`super::step_model`).
pub(super) struct StepLoads {
    pub(super) dofs: Vec<PointDofs>,
    pub(super) d: Vec<f64>,
    pub(super) g: Vec<f64>,
    pub(super) loads: Vec<Vector>,
}

/// The d, g, u0 and nodal loads of a load step of the problem `base` was
/// built from (its `[[dirichlet]]`, `[[slip]]`, boundary loads `bl` and
/// materials with the body forces `mats` at the step; messages name
/// `path`) on `base`'s topology, with the checks a full build makes on
/// them, in the same order; None when the step's conditions give a point
/// other DOFs than in `base` (C and A would differ).
pub(super) fn step_loads(
    base: &Model,
    mesh: &Mesh,
    path: &Path,
    dirichlet: &[Dirichlet],
    slip: &[Slip],
    bl: BoundaryLoads,
    mats: &Materials,
) -> Result<Option<StepLoads>, FemError> {
    let mut lap = super::Lap::new("fem::step_loads");
    let topo = &base.topo;
    let conds = super::conditions::Conditions::collect(mesh, topo, path, dirichlet, slip)?;
    let dofs = conds.eliminate(mesh, topo, &base.body_names, path)?;
    if !same_dofs(&dofs, &base.dofs) {
        return Ok(None);
    }
    lap.lap("conditions");
    let n = base.qp.n();
    let mut d = element_d(topo, &dofs, n, mats);
    lap.lap("element loads");
    let loads = nodal_loads(mesh, topo, &dofs, path, bl, mats, &mut d)?;
    lap.lap("nodal loads");
    // C is the base's, checked when it was built: only d is checked here.
    check_d(&base.qp.c, &d, &dofs, topo, mesh, path)?;
    // The rows of A are the same (same T); g and the check of the rows
    // whose points are all fixed depend on u0.
    let (_, g, _) = super::contact::reduced_rows(mesh, topo, &dofs, n, path)?;
    lap.lap("checks and gaps");
    Ok(Some(StepLoads { dofs, d, g, loads }))
}

/// The same unknowns point by point (numbering, T, and which points the
/// assembly treats as free): the same C and A.
pub(super) fn same_dofs(a: &[PointDofs], b: &[PointDofs]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(a, b)| {
            a.start == b.start && a.ndof == b.ndof && a.t == b.t && is_free(a) == is_free(b)
        })
}

/// A point without conditions, as `stiffness::assemble` tells them apart
/// (it skips their T, which changes the sign of zeros).
fn is_free(pd: &PointDofs) -> bool {
    pd.ndof == 2 && pd.t == [[1.0, 0.0], [0.0, 1.0]] && pd.u0 == [0.0, 0.0]
}

/// The element part of d, Σ T_eᵀ(f_e − C_e u0_e), without C: the same
/// terms as `stiffness::assemble` adds (`Materials::body_load` and
/// `Materials::stiffness_rows`, r-weighted when axisymmetric), in the same
/// order (each point's in increasing triangle order from 0), so the same
/// bits; C_e is computed only for the triangles with a prescribed vertex.
/// The terms of a chunk of triangles are computed on rayon's threads, then
/// added in triangle order: the same bits on any number of threads.
fn element_d(topo: &Topology, dofs: &[PointDofs], n: usize, mats: &Materials) -> Vec<f64> {
    use rayon::prelude::*;
    /// Triangles per chunk: the terms of one chunk (48 bytes a triangle)
    /// stay in cache between the parallel pass and the sums.
    const CHUNK: usize = 1 << 14;
    let mut d = vec![0.0f64; n];
    // Per point, compact: whether it is free (ndof 2, T = I, u0 = 0) and
    // its first unknown. The triangles visit their points in no order, and
    // a 64-byte PointDofs per visit was most of the time of a load step's d.
    let free_at: Vec<bool> = dofs.iter().map(is_free).collect();
    let start: Vec<usize> = dofs.iter().map(|pd| pd.start).collect();
    // The load of triangle t on its vertex a, f_e − C_e u0_e.
    let term = |t: usize, a: usize, free: [bool; 3], constrained: bool| -> Vector {
        let tri = topo.triangles[t];
        let mi = topo.tri_material[t] as usize;
        let pts = tri.map(|p| topo.points[p]);
        let mut fe = mats.body_load(&pts, mi, a);
        if !constrained || dofs[tri[a]].ndof == 0 {
            return fe;
        }
        let ke = mats.stiffness_rows(&pts, mi, a);
        for (k, fk) in fe.iter_mut().enumerate() {
            for b in 0..3 {
                if free[b] {
                    continue;
                }
                let u0 = dofs[tri[b]].u0;
                *fk -= ke[k][2 * b] * u0[0] + ke[k][2 * b + 1] * u0[1];
            }
        }
        fe
    };
    let mut terms = vec![[[0.0f64; 2]; 3]; CHUNK.min(topo.triangles.len())];
    for c0 in (0..topo.triangles.len()).step_by(CHUNK) {
        let c1 = (c0 + CHUNK).min(topo.triangles.len());
        terms[..c1 - c0]
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, out)| {
                let t = c0 + i;
                let free = topo.triangles[t].map(|p| free_at[p]);
                let constrained = free.iter().any(|f| !f);
                for (a, o) in out.iter_mut().enumerate() {
                    *o = term(t, a, free, constrained);
                }
            });
        for (t, fes) in (c0..c1).zip(&terms) {
            for (&p, fe) in topo.triangles[t].iter().zip(fes) {
                if free_at[p] {
                    d[start[p]] += fe[0];
                    d[start[p] + 1] += fe[1];
                    continue;
                }
                let pd = &dofs[p];
                for (k, ta) in pd.t[..pd.ndof].iter().enumerate() {
                    d[pd.start + k] += ta[0] * fe[0] + ta[1] * fe[1];
                }
            }
        }
    }
    d
}

/// "node N (body B)" of unknown `j`, for messages (empty if no point has it).
fn unknown_at(j: usize, dofs: &[PointDofs], topo: &Topology, mesh: &Mesh) -> String {
    dofs.iter()
        .position(|p| j >= p.start && j < p.start + p.ndof)
        .map(|p| {
            format!(
                "node {} (body {})",
                mesh.node_tags[topo.point_node[p]], topo.point_body[p]
            )
        })
        .unwrap_or_default()
}

/// Refuses a C or d that is not finite, or whose displacement scale
/// max|d| / max C_ii is so large that energies would overflow (a NaN in the
/// solver otherwise). Names the body and node of the largest load.
pub(super) fn check_scale(
    c: &Csr,
    d: &[f64],
    dofs: &[PointDofs],
    topo: &Topology,
    mesh: &Mesh,
    path: &Path,
) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let at = |j: usize| unknown_at(j, dofs, topo, mesh);
    if let Some(k) = c.data.iter().position(|v| !v.is_finite()) {
        let row = c.indptr.partition_point(|&s| s <= k).saturating_sub(1);
        return Err(err(format!(
            "the stiffness matrix C is not finite at {}: check E and the coordinates",
            at(row)
        )));
    }
    check_d(c, d, dofs, topo, mesh, path)
}

/// The part of [`check_scale`] on d (C finite already).
fn check_d(
    c: &Csr,
    d: &[f64],
    dofs: &[PointDofs],
    topo: &Topology,
    mesh: &Mesh,
    path: &Path,
) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let at = |j: usize| unknown_at(j, dofs, topo, mesh);
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

#[cfg(test)]
mod tests {
    /// The model of every load step of every shipped example, made from the
    /// problem's by [`super::super::step_model_reusing`], is the one a full
    /// build makes, bit for bit (d, g, u0, loads, t0; C and A shared).
    #[test]
    fn step_model_is_the_full_build_bit_for_bit() {
        let opts = super::super::BuildOptions::default();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut stepped = 0;
        for (path, problem, mesh) in crate::shipped_examples() {
            let base = super::super::build_with(&mesh, &problem, &opts).unwrap();
            // Step 1 from a copy of the base, the later ones from the last
            // step's model (as a run makes them).
            let mut prev = None;
            for s in 0..problem.file.nsteps() {
                let mut p = problem.clone();
                p.file = problem.file.at_step(s);
                let full = super::super::build_with(&mesh, &p, &opts).unwrap();
                let reused =
                    super::super::step_model_reusing(&base, prev.take(), &mesh, &p, &opts).unwrap();
                let at = format!("{} step {}", path.display(), s + 1);
                assert_eq!(bits(&reused.qp.d), bits(&full.qp.d), "d, {at}");
                assert_eq!(bits(&reused.qp.g), bits(&full.qp.g), "g, {at}");
                assert_eq!(reused.qp.c, full.qp.c, "C, {at}");
                assert_eq!(reused.qp.a, full.qp.a, "A, {at}");
                assert_eq!(reused.qp_rows, full.qp_rows, "{at}");
                let u0 = |m: &super::super::Model| {
                    m.dofs
                        .iter()
                        .flat_map(|p| [p.u0[0].to_bits(), p.u0[1].to_bits(), p.start as u64])
                        .collect::<Vec<_>>()
                };
                assert_eq!(u0(&reused), u0(&full), "u0, {at}");
                let flat =
                    |m: &super::super::Model| m.loads.iter().flat_map(|l| *l).collect::<Vec<f64>>();
                assert_eq!(bits(&flat(&reused)), bits(&flat(&full)), "loads, {at}");
                assert_eq!(reused.qp.friction, full.qp.friction, "friction, {at}");
                stepped += usize::from(problem.file.nsteps() > 1);
                prev = Some(reused);
            }
        }
        // The shipped examples with [[steps]] were among them.
        assert!(stepped >= 2, "{stepped}");
    }
}
