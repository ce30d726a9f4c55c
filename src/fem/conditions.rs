//! Dirichlet conditions and slip lines, and their elimination point by point
//! (docs/methods.md §2.4–2.5).
//!
//! Dirichlet components and slip lines (Γ0, u·n = 0) are conditions r·u = v
//! at points. They are eliminated node by node: each point's displacement is
//! u_p = u0_p + T_p ξ_p, where the rows of all conditions at the point fix
//! u0_p and T_p has orthonormal columns spanning what is left free (2, 1 or
//! 0 DOFs). This is the elimination option of §2.5 with a unit tangent
//! instead of (1, −n1/n2), so it is well-conditioned for any normal, and it
//! combines Dirichlet and slip at corners. The unknowns ξ are numbered point
//! by point (§2.3).

use super::element::{PointD, Vector};
use super::topology::{dim_name, Topology};
use super::FemError;
use crate::mesh::Mesh;
use crate::problem::{model_size, Dirichlet, Prescribed, Slip};
use std::path::Path;

/// Per-point elimination: u = u0 + T ξ with `ndof` columns of T used, in
/// a model of dimension `D` (2: plane and axisymmetric, 3: solid).
#[derive(Debug, Clone, Copy)]
pub struct PointDofs<const D: usize = 2> {
    pub start: usize,
    pub ndof: usize,
    /// Columns of T (unit, orthogonal); only the first `ndof` are used.
    pub t: [[f64; D]; D],
    pub u0: [f64; D],
}

impl<const D: usize> Default for PointDofs<D> {
    fn default() -> Self {
        PointDofs {
            start: 0,
            ndof: 0,
            t: [[0.0; D]; D],
            u0: [0.0; D],
        }
    }
}

/// One linear condition r·u = v at a point of a model of dimension D;
/// `src` indexes the names of the TOML entries that set conditions (for
/// messages).
#[derive(Debug, Clone, Copy)]
pub(super) struct Cond<const D: usize = 2> {
    pub(super) r: PointD<D>,
    pub(super) v: f64,
    pub(super) src: usize,
}

/// The conditions of every point and what set them.
pub(super) struct Conditions {
    /// The conditions at each point.
    pub(super) at: Vec<Vec<Cond>>,
    /// What set each condition: `[[dirichlet]] on = "NAME"`, `[[slip]] on = "NAME"`.
    src: Vec<String>,
    /// The same as (kind "dirichlet" | "slip", physical group name).
    pub(super) groups: Vec<(&'static str, String)>,
}

impl Conditions {
    /// The `[[dirichlet]]` and `[[slip]]` conditions, in that order.
    pub(super) fn collect(
        mesh: &Mesh,
        topo: &Topology,
        path: &Path,
        dirichlet: &[Dirichlet],
        slip: &[Slip],
    ) -> Result<Conditions, FemError> {
        let mut c = Conditions {
            at: vec![vec![]; topo.points.len()],
            src: vec![],
            groups: vec![],
        };
        c.add_dirichlet(mesh, topo, path, dirichlet)?;
        c.add_slip(mesh, topo, path, slip)?;
        c.add_implied(mesh, topo, path)?;
        Ok(c)
    }

    /// ux, uy (or u) on the points of a curve or point group.
    fn add_dirichlet(
        &mut self,
        mesh: &Mesh,
        topo: &Topology,
        path: &Path,
        dirichlet: &[Dirichlet],
    ) -> Result<(), FemError> {
        // The model's size, for a turn's nodes on its axis.
        let size = || model_size(topo.points.iter().map(|x| [x[0], x[1], 0.0]));
        for (i, dch) in dirichlet.iter().enumerate() {
            let what = format!("[[dirichlet]] #{} (on = \"{}\")", i + 1, dch.on);
            let [ux, uy, _] = dch.value.components();
            let turn = match dch.value {
                Prescribed::Turn(t) => Some((t, size())),
                _ => None,
            };
            let mut pts: Vec<usize> = topo
                .group_points(mesh, path, &dch.on, &what)?
                .into_iter()
                .map(|x| x.0)
                .collect();
            pts.sort_unstable();
            pts.dedup();
            let src = self.src.len();
            self.src.push(format!("[[dirichlet]] on = \"{}\"", dch.on));
            self.groups.push(("dirichlet", dch.on.clone()));
            for p in pts {
                // A turn about z: u·e_θ = θρ (none on the axis).
                let x = topo.points[p];
                if let Some((r, v)) = turn.and_then(|(t, s)| t.condition([x[0], x[1], 0.0], s)) {
                    self.at[p].push(Cond {
                        r: [r[0], r[1]],
                        v,
                        src,
                    });
                }
                if let Some(v) = ux {
                    self.at[p].push(Cond {
                        r: [1.0, 0.0],
                        v,
                        src,
                    });
                }
                if let Some(v) = uy {
                    self.at[p].push(Cond {
                        r: [0.0, 1.0],
                        v,
                        src,
                    });
                }
            }
        }
        Ok(())
    }

    /// The conditions the element kind imposes by itself (u_r = 0 on the
    /// axis of an axisymmetric model, docs/methods.md §10), added without
    /// a TOML entry; a point outside the kind's domain is an error.
    fn add_implied(&mut self, mesh: &Mesh, topo: &Topology, path: &Path) -> Result<(), FemError> {
        let implied = topo.kind.implied_conditions(&topo.points).map_err(|e| {
            FemError::new(path, e.message(mesh.node_tags[topo.point_node[e.point]]))
        })?;
        let Some(ic) = implied else {
            return Ok(());
        };
        let src = self.src.len();
        self.src.push(ic.what.into());
        self.groups.push((ic.group.0, ic.group.1.into()));
        for p in ic.points {
            self.at[p].push(Cond {
                r: ic.direction,
                v: 0.0,
                src,
            });
        }
        Ok(())
    }

    /// u·n = 0 on the points of a curve, n the unit average of the outward
    /// normals of the point's segments on that curve (§2.5–2.6).
    fn add_slip(
        &mut self,
        mesh: &Mesh,
        topo: &Topology,
        path: &Path,
        slip: &[Slip],
    ) -> Result<(), FemError> {
        for (i, s) in slip.iter().enumerate() {
            let what = format!("[[slip]] #{} (on = \"{}\")", i + 1, s.on);
            if let Some(g) = mesh.group_any(&s.on) {
                if g.dim != 1 {
                    return Err(FemError::new(
                        path,
                        format!(
                            "{what}: \"{}\" is a physical {}, expected a curve",
                            s.on,
                            dim_name(g.dim)
                        ),
                    ));
                }
            }
            // Averaged unit normal per point over the segments of this line.
            let mut sum: std::collections::BTreeMap<usize, Vector> = Default::default();
            for (p, _, seg) in topo.group_points(mesh, path, &s.on, &what)? {
                if let Some((a, b, t)) = seg {
                    let n = topo.outward_normal(mesh, t, a, b);
                    let e = sum.entry(p).or_insert([0.0, 0.0]);
                    e[0] += n[0];
                    e[1] += n[1];
                }
            }
            let src = self.src.len();
            self.src.push(format!("[[slip]] on = \"{}\"", s.on));
            self.groups.push(("slip", s.on.clone()));
            for (p, n) in sum {
                let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
                if len > 1e-12 {
                    self.at[p].push(Cond {
                        r: [n[0] / len, n[1] / len],
                        v: 0.0,
                        src,
                    });
                }
            }
        }
        Ok(())
    }

    /// Each point's u = u0 + Tξ, its unknowns numbered after the previous
    /// point's; conflicting conditions are an error that names the node,
    /// the body (`body_names`) and the TOML entries.
    pub(super) fn eliminate(
        &self,
        mesh: &Mesh,
        topo: &Topology,
        body_names: &[String],
        path: &Path,
    ) -> Result<Vec<PointDofs>, FemError> {
        number(&self.at, |p, m| {
            let cs = &self.at[p];
            let mut from: Vec<usize> = cs.iter().map(|c| c.src).collect();
            from.sort_unstable();
            from.dedup();
            let from: Vec<&str> = from.iter().map(|&i| self.src[i].as_str()).collect();
            FemError::new(
                path,
                format!(
                    "conflicting conditions at node {} ({}) from {}: {m}",
                    mesh.node_tags[topo.point_node[p]],
                    match body_names.get(topo.point_body[p] as usize) {
                        Some(n) => format!("body '{n}'"),
                        None => format!("body {}", topo.point_body[p]),
                    },
                    from.join(", ")
                ),
            )
        })
    }

    /// The conditions as (point, unit direction r, index into `groups`).
    pub(super) fn list(&self) -> Vec<(usize, Vector, u32)> {
        self.at
            .iter()
            .enumerate()
            .flat_map(|(p, cs)| cs.iter().map(move |c| (p, c.r, c.src as u32)))
            .collect()
    }
}

/// Each point's u = u0 + Tξ from its conditions `at`, its unknowns
/// numbered after the previous point's; `err(p, why)` is the error of
/// conditions that disagree at point p.
pub(super) fn number<const D: usize>(
    at: &[Vec<Cond<D>>],
    err: impl Fn(usize, String) -> FemError,
) -> Result<Vec<PointDofs<D>>, FemError> {
    let mut dofs = Vec::with_capacity(at.len());
    let mut next = 0usize;
    for (p, cs) in at.iter().enumerate() {
        let pd = eliminate(cs).map_err(|m| err(p, m))?;
        let pd = PointDofs { start: next, ..pd };
        next += pd.ndof;
        dofs.push(pd);
    }
    Ok(dofs)
}

/// Combine the conditions r·u = v at one point into u = u0 + Tξ: the
/// closed forms of the plane (which fix its bits), Gram–Schmidt in 3D.
pub(super) fn eliminate<const D: usize>(cs: &[Cond<D>]) -> Result<PointDofs<D>, String> {
    if D == 2 {
        let pd = eliminate_plane(cs)?;
        Ok(PointDofs {
            start: pd.start,
            ndof: pd.ndof,
            t: std::array::from_fn(|k| std::array::from_fn(|c| pd.t[k][c])),
            u0: std::array::from_fn(|c| pd.u0[c]),
        })
    } else {
        gram_schmidt(cs)
    }
}

/// The closed forms of the plane: one condition, or two independent ones
/// (the others checked against them).
fn eliminate_plane<const D: usize>(cs: &[Cond<D>]) -> Result<PointDofs, String> {
    // r of a plane condition (D = 2).
    let rv = |c: &Cond<D>| -> Vector { [c.r[0], c.r[1]] };
    let mut pd = PointDofs {
        start: 0,
        ndof: 2,
        t: [[1.0, 0.0], [0.0, 1.0]],
        u0: [0.0, 0.0],
    };
    if cs.is_empty() {
        return Ok(pd);
    }
    let q1 = normalize(rv(&cs[0]));
    let v1 = cs[0].v / norm2(rv(&cs[0]));
    // A second, independent condition?
    let second = cs.iter().skip(1).find(|c| {
        let r = normalize(rv(c));
        (r[0] * q1[1] - r[1] * q1[0]).abs() > 1e-8
    });
    match second {
        None => {
            // all parallel: check consistency
            for c in &cs[1..] {
                let r = normalize(rv(c));
                let s = r[0] * q1[0] + r[1] * q1[1];
                let v = c.v / norm2(rv(c));
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
            let (r1, r2) = (rv(&cs[0]), rv(c2));
            let det = r1[0] * r2[1] - r1[1] * r2[0];
            let u = [
                (cs[0].v * r2[1] - c2.v * r1[1]) / det,
                (r1[0] * c2.v - r2[0] * cs[0].v) / det,
            ];
            for c in cs {
                let r = rv(c);
                let res = r[0] * u[0] + r[1] * u[1] - c.v;
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

/// Gram–Schmidt on the conditions r·u = v at one point: the independent
/// directions fix u0, the orthonormal complement spans T (docs/methods.md
/// §2.5, in 3D). Conditions that disagree are an error.
fn gram_schmidt<const D: usize>(cs: &[Cond<D>]) -> Result<PointDofs<D>, String> {
    let dot = |a: &PointD<D>, b: &PointD<D>| -> f64 { (0..D).map(|i| a[i] * b[i]).sum() };
    let mut q: Vec<(PointD<D>, f64)> = vec![];
    for c in cs {
        let l = dot(&c.r, &c.r).sqrt();
        let (mut r, mut v) = (c.r.map(|x| x / l), c.v / l);
        for &(qk, wk) in &q {
            let s = dot(&r, &qk);
            r = std::array::from_fn(|i| r[i] - s * qk[i]);
            v -= s * wk;
        }
        let n = dot(&r, &r).sqrt();
        if n > 1e-8 {
            q.push((r.map(|x| x / n), v / n));
        } else if v.abs() > 1e-9 * (1.0 + cs.iter().map(|c| c.v.abs()).sum::<f64>()) {
            return Err(format!(
                "conditions that disagree (residual {v:.3e} along a direction already fixed)"
            ));
        }
    }
    let mut u0 = [0.0; D];
    for &(qk, wk) in &q {
        for i in 0..D {
            u0[i] += wk * qk[i];
        }
    }
    let mut t = [[0.0; D]; D];
    let mut ndof = 0;
    for e in 0..D {
        let mut r = [0.0; D];
        r[e] = 1.0;
        for qk in q.iter().map(|x| x.0).chain(t[..ndof].iter().copied()) {
            let s = dot(&r, &qk);
            r = std::array::from_fn(|i| r[i] - s * qk[i]);
        }
        let n = dot(&r, &r).sqrt();
        if n > 1e-6 && ndof + q.len() < D {
            t[ndof] = r.map(|x| x / n);
            ndof += 1;
        }
    }
    Ok(PointDofs {
        start: 0,
        ndof,
        t,
        u0,
    })
}

/// |r|.
fn norm2(r: Vector) -> f64 {
    (r[0] * r[0] + r[1] * r[1]).sqrt()
}

/// r / |r|.
pub(super) fn normalize(r: Vector) -> Vector {
    let l = norm2(r);
    [r[0] / l, r[1] / l]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cond(r: Vector, v: f64) -> Cond {
        Cond { r, v, src: 0 }
    }

    /// u0 + Tξ satisfies every condition for any ξ, and T has orthonormal
    /// columns orthogonal to every r.
    fn check(cs: &[Cond], ndof: usize) {
        let pd = eliminate(cs).unwrap();
        assert_eq!(pd.ndof, ndof);
        for xi in [[0.0, 0.0], [0.7, -1.3]] {
            let mut u = pd.u0;
            for (tk, x) in pd.t.iter().zip(xi).take(pd.ndof) {
                u[0] += tk[0] * x;
                u[1] += tk[1] * x;
            }
            for c in cs {
                let res = c.r[0] * u[0] + c.r[1] * u[1] - c.v;
                assert!(res.abs() < 1e-12, "{res} for {:?}", c.r);
            }
        }
        for k in 0..pd.ndof {
            assert!((norm2(pd.t[k]) - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn elimination_satisfies_the_conditions_and_refuses_conflicts() {
        check(&[], 2);
        // One Dirichlet component, then a slip line with an oblique normal
        // (r not unit: v is scaled with it), then both at a corner.
        check(&[cond([0.0, 1.0], -0.25)], 1);
        check(&[cond([3.0, 4.0], 0.0), cond([0.6, 0.8], 0.0)], 1);
        check(&[cond([1.0, 0.0], 0.1), cond([0.6, 0.8], 0.0)], 0);
        check(
            &[
                cond([1.0, 0.0], 0.1),
                cond([0.0, 1.0], 0.2),
                cond([1.0, 1.0], 0.3),
            ],
            0,
        );
        // Parallel conditions with different values, and a third
        // independent condition that disagrees.
        assert!(eliminate(&[cond([1.0, 0.0], 0.1), cond([-2.0, 0.0], 0.0)]).is_err());
        assert!(eliminate(&[
            cond([1.0, 0.0], 0.1),
            cond([0.0, 1.0], 0.2),
            cond([1.0, 1.0], 0.0)
        ])
        .is_err());
    }
}
