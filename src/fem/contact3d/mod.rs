//! Contact rows of 3D models (docs/methods.md §11): node-to-node rows on a
//! conforming surface (the mesh cut there, one point per node and body)
//! and node-to-surface rows of a non-matching pair, each with a unit normal
//! and a tangent frame (for the two tangential rows of 3D friction, issue
//! 46), then the rows in the reduced unknowns as in 2D (`contact.rs`).

pub mod friction;
mod mortar;
mod nts;
pub mod search;

pub(super) use mortar::mortar_rows;
pub(super) use nts::nts_rows;

use super::conditions::PointDofs;
use super::contact::RowKind;
use super::element::Vector3;
use super::solid::Facet;
use super::FemError;
use crate::linalg::sparse::Csr;
use std::collections::BTreeMap;

/// One contact row n·(Σ_m w_m u_m − u_s) ≤ g: the slave point s (a
/// conforming pair: the copy in the higher body l) against master points
/// with weights summing to 1 (the copy in body k, or the three nodes of
/// the master triangle with the projection's barycentric weights), n unit
/// and outward of the master (docs/methods.md §11.1–11.2).
#[derive(Debug, Clone, PartialEq)]
pub struct Row3 {
    pub kind: RowKind,
    pub slave: usize,
    pub masters: Vec<(usize, f64)>,
    pub normal: Vector3,
    /// t1, t2: with n a right-handed orthonormal frame (t1 × t2 = n), for
    /// the tangential rows of friction (docs/methods.md §11.4).
    pub tangents: [Vector3; 2],
    /// Initial normal gap (≥ 0 unless an interference fit).
    pub gap0: f64,
    /// The slave point's tributary area Σ|F|/3: the row's multiplier over
    /// it is the contact pressure.
    pub area: f64,
    pub interface: u32,
}

impl Row3 {
    /// Coefficients c_p (3-vectors) of the row Σ c_p·u_p ≤ g.
    pub fn coefficients(&self) -> Vec<(usize, Vector3)> {
        let n = self.normal;
        let mut v = vec![(self.slave, n.map(|c| -c))];
        v.extend(
            self.masters
                .iter()
                .filter(|(_, w)| *w != 0.0)
                .map(|&(p, w)| (p, n.map(|c| w * c))),
        );
        v
    }
}

pub(super) fn dot(a: Vector3, b: Vector3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vector3, b: Vector3) -> Vector3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: Vector3) -> Vector3 {
    let l = dot(a, a).sqrt();
    a.map(|c| c / l)
}

/// The tangent frame of a unit normal n: t1 = (e × n)/|e × n| with e the
/// coordinate axis least aligned with n (|e × n| ≥ √(2/3)), t2 = n × t1;
/// the same n always gives the same frame (docs/methods.md §11.4).
pub fn tangent_frame(n: Vector3) -> [Vector3; 2] {
    let k = (0..3)
        .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[k] = 1.0;
    let t1 = unit(cross(e, n));
    let t2 = cross(n, t1);
    [t1, t2]
}

/// The node-to-node rows of a conforming surface (docs/methods.md §11.1):
/// each node pair (copy in body k, copy in body l, k < l) gets one row
/// along the area-weighted average of the outward normals (of body k) of
/// its triangles, gap 0, and the tributary area Σ|F|/3. `tris` are the
/// surface's triangles seen from body k, each with body l's points in the
/// same order; `name` for messages, `node_tag` of a point.
pub(super) fn conforming_rows(
    tris: &[(Facet, [usize; 3])],
    interface: u32,
    name: &str,
    node_tag: impl Fn(usize) -> u64,
    path: &std::path::Path,
) -> Result<Vec<Row3>, FemError> {
    // (point in k, point in l) → (Σ A n, Σ A/3).
    let mut acc: BTreeMap<(usize, usize), (Vector3, f64)> = BTreeMap::new();
    for (f, lp) in tris {
        let area = 3.0 * f.weight;
        for i in 0..3 {
            let e = acc.entry((f.points[i], lp[i])).or_insert(([0.0; 3], 0.0));
            for k in 0..3 {
                e.0[k] += area * f.normal[k];
            }
            e.1 += f.weight;
        }
    }
    let mut rows = Vec::with_capacity(acc.len());
    for ((pk, pl), (s, area)) in acc {
        let len = dot(s, s).sqrt();
        // The sum of unit normals weighted by areas: zero only where the
        // surface folds back on itself (a cusp).
        if len <= 1e-12 * 3.0 * area || !len.is_finite() {
            return Err(FemError::new(
                path,
                format!(
                    "contact surface \"{name}\": the normals of its triangles at node {} cancel (the surface folds back on itself there)",
                    node_tag(pk)
                ),
            ));
        }
        let n = s.map(|c| c / len);
        rows.push(Row3 {
            kind: RowKind::Conforming,
            slave: pl,
            masters: vec![(pk, 1.0)],
            normal: n,
            tangents: tangent_frame(n),
            gap0: 0.0,
            area,
            interface,
        });
    }
    Ok(rows)
}

/// The rows in the reduced unknowns: A = rows · T and g = gap0 − rows · u0
/// (docs/methods.md §2.7–2.8), and the row of each QP row. A row whose
/// points are all fixed is left out, and refused (by `violated(row)`) if
/// the prescribed displacements alone violate it — as `contact.rs` in 2D.
pub(super) fn reduced_rows(
    rows: &[Row3],
    dofs: &[PointDofs<3>],
    n: usize,
    violated: impl Fn(&Row3) -> FemError,
) -> Result<(Csr, Vec<f64>, Vec<usize>), FemError> {
    let mut atrip = vec![];
    let mut g = vec![];
    let mut qp_rows = vec![];
    for (r, row) in rows.iter().enumerate() {
        let mut gr = row.gap0;
        let mut entries: Vec<(usize, f64)> = vec![];
        for (p, c) in row.coefficients() {
            let pd = dofs[p];
            gr -= dot(c, pd.u0);
            for k in 0..pd.ndof {
                let v = dot(c, pd.t[k]);
                if v.abs() > 1e-14 {
                    entries.push((pd.start + k, v));
                }
            }
        }
        if entries.is_empty() {
            if gr < -1e-12 * (1.0 + row.gap0.abs()) {
                return Err(violated(row));
            }
            continue;
        }
        let qi = qp_rows.len();
        atrip.extend(entries.into_iter().map(|(j, v)| (qi, j, v)));
        g.push(gr);
        qp_rows.push(r);
    }
    Ok((Csr::from_triplets(qp_rows.len(), n, &atrip), g, qp_rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_frames_are_orthonormal_and_right_handed() {
        for n in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            unit([0.3, -0.5, 0.8]),
            unit([1.0, 1.0, 1.0]),
        ] {
            let [t1, t2] = tangent_frame(n);
            for (a, b, want) in [
                (t1, t1, 1.0),
                (t2, t2, 1.0),
                (t1, t2, 0.0),
                (t1, n, 0.0),
                (t2, n, 0.0),
            ] {
                assert!((dot(a, b) - want).abs() < 1e-15, "{n:?}");
            }
            let c = cross(t1, t2);
            assert!((0..3).all(|k| (c[k] - n[k]).abs() < 1e-15), "{n:?}");
        }
    }
}
