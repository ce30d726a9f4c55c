//! Node-to-surface rows of a non-matching pair in 3D (docs/methods.md
//! §11.2): each slave node projected orthogonally on the nearest master
//! triangle of another body, with the master triangle's normal, as the 2D
//! node-to-segment rows (`pairs.rs`).

use super::super::element::{Point3, Vector3};
use super::super::solid::Facet;
use super::super::FemError;
use super::search::{Hit, TriangleTree};
use super::{dot, tangent_frame, Row3};
use crate::fem::contact::RowKind;
use crate::problem::NonMatchingPair;
use std::collections::BTreeMap;
use std::path::Path;

/// An initial penetration deeper than this fraction of the master
/// triangle's size is refused (the 2D rows' tolerance).
const TOL_PEN: f64 = 1e-6;

/// The rows of the pair `c` (interface `id`, `what` its TOML entry in
/// messages): one per slave point that projects on a master triangle of
/// another body within `max_gap`, in point order.
#[allow(clippy::too_many_arguments)]
pub(in crate::fem) fn nts_rows(
    points: &[Point3],
    slave: &[Facet],
    master: &[Facet],
    c: &NonMatchingPair,
    id: u32,
    what: &str,
    node_tag: impl Fn(usize) -> u64,
    path: &Path,
) -> Result<Vec<Row3>, FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let (sname, mname) = (c.slave.as_str(), c.master.as_str());
    let tris: Vec<[Point3; 3]> = master.iter().map(|f| f.points.map(|p| points[p])).collect();
    let normals: Vec<Vector3> = master.iter().map(|f| f.normal).collect();
    let size = |t: usize| {
        let p = &tris[t];
        (0..3)
            .map(|i| {
                let d = [0, 1, 2].map(|k| p[(i + 1) % 3][k] - p[i][k]);
                dot(d, d).sqrt()
            })
            .fold(0.0, f64::max)
    };
    let tree = TriangleTree::build(&tris, &normals);
    let mut rows = vec![];
    let (hits, mut skipped) = project_slaves(
        points, slave, master, &tree, what, sname, mname, &node_tag, path,
    )?;
    for (s, area, hit) in hits {
        let f = &master[hit.tri];
        let n = f.normal;
        let g = hit.dist;
        if g < -TOL_PEN * size(hit.tri) && !c.interference {
            return Err(err(format!(
                "{what}: slave node {} of \"{sname}\" penetrates master \"{mname}\" by {:.3e} (initial gap must be >= 0; set interference = true if the overlap is an intended fit)",
                node_tag(s),
                -g
            )));
        }
        if c.max_gap.is_some_and(|m| g > m) {
            skipped += 1;
            continue;
        }
        rows.push(Row3 {
            kind: RowKind::NonMatching,
            slave: s,
            masters: (0..3).map(|i| (f.points[i], hit.weights[i])).collect(),
            normal: n,
            tangents: tangent_frame(n),
            gap0: if c.interference { g } else { g.max(0.0) },
            area,
            interface: id,
        });
    }
    if rows.is_empty() {
        return Err(err(format!(
            "{what}: no slave node of \"{sname}\" finds a master triangle of \"{mname}\" within reach"
        )));
    }
    if skipped > 0 {
        log::warn!("{what}: {skipped} slave node(s) of \"{sname}\" have no master triangle within reach and are not constrained");
    }
    Ok(rows)
}

/// A slave point, its tributary area and its projection.
pub(super) type Projected = (usize, f64, Hit);

/// Each slave point projected on its nearest master triangle: (point, its
/// tributary area Σ|F|/3, the projection), and how many found none. A
/// slave whose averaged normals face the way the master's do (Σ area ×
/// n_s·n_m > 0) is refused as facing away (docs/methods.md §11.2).
#[allow(clippy::too_many_arguments)]
pub(super) fn project_slaves(
    points: &[Point3],
    slave: &[Facet],
    master: &[Facet],
    tree: &TriangleTree,
    what: &str,
    sname: &str,
    mname: &str,
    node_tag: &impl Fn(usize) -> u64,
    path: &Path,
) -> Result<(Vec<Projected>, usize), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    // Slave points: Σ A n (the averaged normal, for the facing check) and
    // the tributary area Σ A/3.
    let mut snodes: BTreeMap<usize, (Vector3, f64)> = BTreeMap::new();
    for f in slave {
        for &p in &f.points {
            let e = snodes.entry(p).or_insert(([0.0; 3], 0.0));
            for k in 0..3 {
                e.0[k] += 3.0 * f.weight * f.normal[k];
            }
            e.1 += f.weight;
        }
    }
    let mut skipped = 0usize;
    // Σ area × (n_slave · n_master) over the rows: positive when the slave
    // faces the way the master does.
    let (mut facing, mut total) = (0.0f64, 0.0f64);
    let mut away: Option<(usize, Vector3, Vector3)> = None;
    // The projections first: a wrong-facing pair is named as such before
    // its gaps are judged.
    let mut hits = Vec::with_capacity(snodes.len());
    for (&s, &(sum, area)) in &snodes {
        let Some(hit) = tree.nearest(points[s], |_| true) else {
            skipped += 1;
            continue;
        };
        let ns = sum.map(|v| v / dot(sum, sum).sqrt());
        let n = master[hit.tri].normal;
        let cos = dot(ns, n);
        facing += area * cos;
        total += area;
        if cos > 0.0 && away.is_none_or(|a| cos > dot(a.1, a.2)) {
            away = Some((s, ns, n));
        }
        hits.push((s, area, hit));
    }
    if facing > 0.0 {
        let (s, ns, nm) = away.unwrap_or((0, [0.0; 3], [0.0; 3]));
        return Err(err(format!(
            "{what}: slave surface \"{sname}\" faces away from master \"{mname}\": their outward normals point the same way (mean cosine {:.3}; at slave node {} ({:.3}, {:.3}, {:.3}) against ({:.3}, {:.3}, {:.3})); name the faces of the two bodies that touch",
            facing / total,
            node_tag(s),
            ns[0], ns[1], ns[2], nm[0], nm[1], nm[2]
        )));
    }
    Ok((hits, skipped))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facet(points: [usize; 3], xs: &[Point3], body: u32) -> Facet {
        let p = points.map(|i| xs[i]);
        let (weight, normal) = crate::fem::ElementKind::Solid.facet_weight(&p);
        Facet {
            nodes: points,
            points,
            body,
            weight,
            normal,
            tag: 1,
        }
    }

    /// A slave node above a tilted master triangle: the row has the
    /// master's normal, the barycentric weights of the orthogonal
    /// projection (Σ w = 1, so a rigid translation leaves it unchanged)
    /// and the distance to the plane as its gap; a slave triangle facing
    /// the same way as the master is refused.
    #[test]
    fn a_row_on_a_tilted_master() {
        let t = 0.3f64;
        // Master: a triangle in the plane z = t x (normal ∝ (−t, 0, 1)).
        let mut xs: Vec<Point3> = vec![[0.0, 0.0, 0.0], [2.0, 0.0, 2.0 * t], [0.0, 2.0, 0.0]];
        let n = {
            let l = (1.0 + t * t).sqrt();
            [-t / l, 0.0, 1.0 / l]
        };
        // Slave: a triangle 0.1 above it along n, facing down.
        let base = [[0.5, 0.5], [0.9, 0.5], [0.5, 0.9]];
        for b in base {
            let z = t * b[0];
            xs.push([b[0] + 0.1 * n[0], b[1], z + 0.1 * n[2]]);
        }
        let master = [facet([0, 1, 2], &xs, 0)];
        let slave = [facet([3, 5, 4], &xs, 1)];
        assert!(dot(slave[0].normal, n) < -0.99, "{:?}", slave[0].normal);
        let pair = NonMatchingPair {
            slave: "s".into(),
            master: "m".into(),
            max_gap: None,
            discretization: None,
            interference: false,
        };
        let rows = nts_rows(
            &xs,
            &slave,
            &master,
            &pair,
            0,
            "t",
            |p| p as u64,
            Path::new("t"),
        )
        .unwrap();
        assert_eq!(rows.len(), 3);
        for r in &rows {
            assert!((0..3).all(|k| (r.normal[k] - n[k]).abs() < 1e-15));
            assert!((r.gap0 - 0.1).abs() < 1e-14, "{}", r.gap0);
            let ws: f64 = r.masters.iter().map(|m| m.1).sum();
            assert!((ws - 1.0).abs() < 1e-15);
            // The weights give back the projected point.
            let x = xs[r.slave];
            let p: Vec<f64> = (0..3)
                .map(|k| r.masters.iter().map(|&(m, w)| w * xs[m][k]).sum())
                .collect();
            for k in 0..3 {
                assert!((x[k] - 0.1 * n[k] - p[k]).abs() < 1e-14);
            }
        }
        let away = [facet([3, 4, 5], &xs, 1)];
        let e = nts_rows(
            &xs,
            &away,
            &master,
            &pair,
            0,
            "t",
            |p| p as u64,
            Path::new("t"),
        )
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("faces away"), "{e}");
    }
}
