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

/// A slave point on a `[[slip]]` plane is on a plane of symmetry (or a
/// frictionless wall): the model's mirror image has the same point, and its
/// row's normal there is the mean of the two sides', the normal with its
/// component across the plane removed (docs/methods.md §11.7). The averaged
/// normal of a mortar or conforming row, or an NTS row's master facet, sees
/// one side only and tilts out of the plane by about half a facet angle;
/// the tilted row then couples the masters' motion across the plane, and
/// the friction frame misses the plane's held tangent (§12.2), leaving a
/// tangential row too weak to fix its multiplier. `planes[p]` are the unit
/// normals of the slip planes through point p. A normal more than 30° out
/// of the planes (|n·e| > 1/2, a part in them shorter than cos 30°) is a
/// surface that meets a wall at an angle, not a mirrored one (a one-sided
/// average tilts by half a facet angle, and a mesh with facets of 60° is
/// no model of a curved surface), and is kept. An NTS row keeps its projected point:
/// its gap along the new normal n' is g (n·n'); a mortar row's gap is an
/// integral over its facets and a conforming row's is 0, both kept.
/// cos 30°: the least part of a row's normal in the slip planes for it to
/// be taken as a mirrored row ([`mirror_into_slip_planes`]).
const MIRROR_LEAST: f64 = 0.866_025_403_784_438_6;

pub(super) fn mirror_into_slip_planes(rows: &mut [Row3], planes: &[Vec<Vector3>]) {
    for row in rows.iter_mut() {
        let es = &planes[row.slave];
        if es.is_empty() {
            continue;
        }
        // An orthonormal basis of the planes' normals (two planes meet on
        // a symmetry edge; a third would fix the point).
        let mut basis: Vec<Vector3> = vec![];
        for &e in es {
            let mut v = e;
            for b in &basis {
                let c = dot(v, *b);
                v = [0, 1, 2].map(|k| v[k] - c * b[k]);
            }
            let l = dot(v, v).sqrt();
            if l > 1e-6 {
                basis.push(v.map(|c| c / l));
            }
        }
        let n = row.normal;
        let mut m = n;
        for b in &basis {
            let c = dot(m, *b);
            m = [0, 1, 2].map(|k| m[k] - c * b[k]);
        }
        let l = dot(m, m).sqrt();
        if !(MIRROR_LEAST..1.0).contains(&l) {
            continue;
        }
        let m = m.map(|c| c / l);
        if row.kind == RowKind::NonMatching {
            row.gap0 *= dot(n, m);
        }
        row.normal = m;
        row.tangents = tangent_frame(m);
    }
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

    fn row(kind: RowKind, slave: usize, n: Vector3, gap0: f64) -> Row3 {
        Row3 {
            kind,
            slave,
            masters: vec![(1, 1.0)],
            normal: n,
            tangents: tangent_frame(n),
            gap0,
            area: 1.0,
            interface: 0,
        }
    }

    /// A row on a slip plane gets the normal of the mirrored model, in the
    /// plane; on a symmetry edge, along the edge's normal plane; a normal
    /// far from the plane, one already in it and one off every plane keep
    /// their bits.
    #[test]
    fn rows_on_slip_planes_take_the_mirrored_normal() {
        let ex = [1.0, 0.0, 0.0];
        let ey = [0.0, 1.0, 0.0];
        let tilted = unit([0.1, 0.05, -1.0]);
        // 45° out of the plane: a chamfer meeting a wall, kept.
        let steep = unit([1.0, 0.0, -1.0]);
        let flat = [0.0, 0.0, -1.0];
        let planes = vec![vec![ex], vec![ex, ey], vec![], vec![ex], vec![ex]];
        let mut rows = vec![
            row(RowKind::NonMatching, 0, tilted, 0.2),
            row(RowKind::Mortar, 1, tilted, 0.2),
            row(RowKind::Mortar, 2, tilted, 0.2),
            row(RowKind::Mortar, 3, steep, 0.2),
            row(RowKind::Conforming, 4, flat, 0.0),
        ];
        let before = rows.clone();
        mirror_into_slip_planes(&mut rows, &planes);
        let want = unit([0.0, 0.05, -1.0]);
        for k in 0..3 {
            assert!((rows[0].normal[k] - want[k]).abs() < 1e-15, "{:?}", rows[0]);
        }
        assert!((rows[0].gap0 - 0.2 * dot(tilted, want)).abs() < 1e-15);
        assert!(rows[0].gap0 < 0.2);
        // Mortar gaps are kept; the edge leaves n = −e_z.
        assert_eq!(rows[1].normal, [0.0, 0.0, -1.0]);
        assert_eq!(rows[1].gap0, 0.2);
        assert_eq!(rows[1].tangents, tangent_frame([0.0, 0.0, -1.0]));
        for r in [2, 3, 4] {
            assert_eq!(rows[r], before[r], "row {r}");
        }
        // The frame is rebuilt: orthonormal to the new normal.
        for t in rows[0].tangents {
            assert!(dot(t, rows[0].normal).abs() < 1e-15);
        }
    }
}
