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
use super::element;
use super::stiffness::Materials;
use super::topology::{dim_name, group_names, Topology};
use super::FemError;
use crate::mesh::Mesh;
use crate::problem::{Problem, TractionLoad};
use crate::qp::Csr;

/// The nodal loads on every point [N] (thickness included), and their
/// tractions and point forces added to `d` (gravity is in d already).
pub(super) fn nodal_loads(
    mesh: &Mesh,
    topo: &Topology,
    dofs: &[PointDofs],
    problem: &Problem,
    mats: &Materials,
    d: &mut [f64],
) -> Result<Vec<[f64; 2]>, FemError> {
    let mut loads = Loads {
        dofs,
        nodal: gravity(topo, mats),
        d,
        axi: false,
    };
    loads.axi = mats.axi.is_some();
    loads.add_tractions(mesh, topo, problem, mats.th)?;
    loads.add_point_forces(mesh, topo, problem, mats.th)?;
    Ok(loads.nodal)
}

/// Gravity on each point: th |T|/3 ρ g per vertex, in triangle order.
fn gravity(topo: &Topology, mats: &Materials) -> Vec<[f64; 2]> {
    let mut loads = vec![[0.0f64; 2]; topo.points.len()];
    for (tri, &mi) in topo.triangles.iter().zip(&topo.tri_material) {
        let pts = [
            topo.points[tri[0]],
            topo.points[tri[1]],
            topo.points[tri[2]],
        ];
        if let Some((_, rw2)) = &mats.axi {
            for (a, &p) in tri.iter().enumerate() {
                let f = element::axi_body_load(&pts, a, mats.bforce[mi as usize], rw2[mi as usize]);
                loads[p][0] += f[0];
                loads[p][1] += f[1];
            }
            continue;
        }
        let w = mats.th * element::area2(&pts) / 6.0;
        let fb = mats.bforce[mi as usize];
        for &p in tri {
            loads[p][0] += w * fb[0];
            loads[p][1] += w * fb[1];
        }
    }
    loads
}

/// The nodal loads being summed, and d.
struct Loads<'a> {
    dofs: &'a [PointDofs],
    nodal: Vec<[f64; 2]>,
    d: &'a mut [f64],
    /// Axisymmetric: tractions weighted by r (∫ N_a P r ds, per radian).
    axi: bool,
}

impl Loads<'_> {
    /// A force `fv` on point `p`: on the nodal loads, and Tᵀfv on d.
    fn add(&mut self, p: usize, fv: [f64; 2]) {
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
        problem: &Problem,
        th: f64,
    ) -> Result<(), FemError> {
        for (i, tr) in problem.file.traction.iter().enumerate() {
            let what = format!("[[traction]] #{} (on = \"{}\")", i + 1, tr.on);
            if let Some(g) = mesh.group_any(&tr.on) {
                if g.dim != 1 {
                    return Err(FemError::new(
                        &problem.path,
                        format!(
                            "{what}: \"{}\" is a physical {}, expected a curve",
                            tr.on,
                            dim_name(g.dim)
                        ),
                    ));
                }
            }
            for (p, v, seg) in topo.group_points(mesh, problem, &tr.on, &what)? {
                let Some((a, b, t)) = seg else { continue };
                let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
                let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
                let pv = match tr.load {
                    TractionLoad::Vector(pv) => pv,
                    TractionLoad::Normal(pn) => {
                        let nrm = topo.outward_normal(mesh, t, a, b);
                        [pn * nrm[0], pn * nrm[1]]
                    }
                };
                // Axisymmetric: ∫ N_p r ds = ℓ(2r_p + r_q)/6 per radian
                // (docs/methods.md §10); th = 1 there.
                let w = if self.axi {
                    let (rp, rq) = if v == a {
                        (pa[0], pb[0])
                    } else {
                        (pb[0], pa[0])
                    };
                    len * (2.0 * rp + rq) / 6.0
                } else {
                    0.5 * th * len
                };
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
        problem: &Problem,
        th: f64,
    ) -> Result<(), FemError> {
        for (i, fo) in problem.file.force.iter().enumerate() {
            let what = format!("[[force]] #{} (on = \"{}\")", i + 1, fo.on);
            let g = mesh
                .group_any(&fo.on)
                .filter(|g| g.dim == 0)
                .ok_or_else(|| {
                    FemError::new(
                        &problem.path,
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
                    self.add(p, [th * fo.f[0], th * fo.f[1]]);
                }
            }
        }
        Ok(())
    }
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
