//! The master triangle of each slave node (docs/methods.md §11.3): a
//! bounding-volume tree over the master triangles, split at the median of
//! their centres along the longest axis, so building it costs O(M log M)
//! and a nearest query O(log M) on a surface; a box farther than the best
//! triangle found so far is not opened.

use super::super::element::Point3;

/// The orthogonal projection of a point on a triangle's plane falls inside
/// the triangle when it is no farther outside any edge than this fraction
/// of the triangle's longest edge (slave nodes on the master's boundary — a
/// symmetry plane, a body edge — sit on it to round-off).
pub const OUTSIDE_TOL: f64 = 1e-6;

/// A projection: the triangle, the barycentric weights of the projected
/// point (≥ 0, summing to 1) and the signed distance along the triangle's
/// unit normal (positive on the side the normal points to).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub tri: usize,
    pub weights: [f64; 3],
    pub dist: f64,
}

/// The orthogonal projection of `x` on the triangle `p` with unit normal
/// `n`, if it falls inside within [`OUTSIDE_TOL`]; the weights of a point
/// just outside are clamped to 0 and renormalised.
pub fn project(x: Point3, p: &[Point3; 3], n: [f64; 3]) -> Option<([f64; 3], f64)> {
    let sub = |a: Point3, b: Point3| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dist = dot(sub(x, p[0]), n);
    let q = [0, 1, 2].map(|k| x[k] - dist * n[k]);
    let area2 = dot(cross(sub(p[1], p[0]), sub(p[2], p[0])), n);
    if area2.abs() <= 0.0 || !area2.is_finite() {
        return None;
    }
    // λ_i = area of (q, the edge opposite i) / area of the triangle.
    let mut w = [0.0; 3];
    let mut longest = 0.0f64;
    for i in 0..3 {
        let (a, b) = (p[(i + 1) % 3], p[(i + 2) % 3]);
        w[i] = dot(cross(sub(a, q), sub(b, q)), n) / area2;
        longest = longest.max(dot(sub(b, a), sub(b, a)).sqrt());
    }
    // The distance of q outside edge i is −λ_i × (height on edge i) =
    // −λ_i × area2 / |edge i|; bounded by the longest edge's fraction.
    for i in 0..3 {
        if w[i] < 0.0 {
            let (a, b) = (p[(i + 1) % 3], p[(i + 2) % 3]);
            let edge = dot(sub(b, a), sub(b, a)).sqrt();
            if -w[i] * area2.abs() / edge > OUTSIDE_TOL * longest {
                return None;
            }
        }
    }
    let w = w.map(|v| v.max(0.0));
    let s = w[0] + w[1] + w[2];
    Some((w.map(|v| v / s), dist))
}

/// A node of a [`BoxTree`]: its box and either two children or a range of
/// items (`order[start..end]`).
pub struct BoxNode {
    pub lo: Point3,
    pub hi: Point3,
    pub start: usize,
    pub end: usize,
    pub kids: Option<[usize; 2]>,
}

const LEAF: usize = 4;

/// A bounding-volume tree over items given by their boxes: a node's box
/// holds its items' boxes, and a node of more than four items is split at
/// the median of their keys along its box's longest axis (ties to the
/// lower item), so building costs O(n log n). Shared by the master
/// triangles of the contact search and the coarse tetrahedra of a nested
/// start (`run::solid::nested`); each walks it its own way.
pub struct BoxTree {
    /// Node 0 is the root (none when there is no item).
    pub nodes: Vec<BoxNode>,
    /// The items, leaf ranges contiguous.
    pub order: Vec<usize>,
}

impl BoxTree {
    /// The tree of items `0..boxes.len()` with boxes `boxes[i]` = (lo, hi)
    /// and split keys `key(i)` (one per axis).
    pub fn build(boxes: &[(Point3, Point3)], key: impl Fn(usize) -> Point3) -> BoxTree {
        let mut t = BoxTree {
            nodes: vec![],
            order: (0..boxes.len()).collect(),
        };
        if boxes.is_empty() {
            return t;
        }
        let mut todo = vec![(0usize, boxes.len(), usize::MAX, 0usize)];
        while let Some((s, e, parent, side)) = todo.pop() {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for &i in &t.order[s..e] {
                for k in 0..3 {
                    lo[k] = lo[k].min(boxes[i].0[k]);
                    hi[k] = hi[k].max(boxes[i].1[k]);
                }
            }
            let me = t.nodes.len();
            t.nodes.push(BoxNode {
                lo,
                hi,
                start: s,
                end: e,
                kids: None,
            });
            if parent != usize::MAX {
                let kids = t.nodes[parent].kids.get_or_insert([0, 0]);
                kids[side] = me;
            }
            if e - s > LEAF {
                let axis = (0..3)
                    .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
                    .unwrap_or(0);
                let mid = (s + e) / 2;
                t.order[s..e].select_nth_unstable_by(mid - s, |&a, &b| {
                    key(a)[axis].total_cmp(&key(b)[axis]).then(a.cmp(&b))
                });
                todo.push((mid, e, me, 1));
                todo.push((s, mid, me, 0));
            }
        }
        t
    }
}

/// The master triangles in a bounding-volume tree.
pub struct TriangleTree<'a> {
    tris: &'a [[Point3; 3]],
    normals: &'a [[f64; 3]],
    nodes: Vec<BoxNode>,
    order: Vec<usize>,
}

impl<'a> TriangleTree<'a> {
    /// The tree of triangles `tris` (vertex coordinates) with their unit
    /// normals.
    pub fn build(tris: &'a [[Point3; 3]], normals: &'a [[f64; 3]]) -> TriangleTree<'a> {
        // Boxes padded by 1e-9 of the coordinates' size: a triangle at a
        // computed distance d is never pruned by its box's round-off.
        let scale = tris
            .iter()
            .flatten()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let pad = 1e-9 * scale;
        let boxes: Vec<(Point3, Point3)> = tris
            .iter()
            .map(|p| {
                let mut lo = [f64::INFINITY; 3];
                let mut hi = [f64::NEG_INFINITY; 3];
                for v in p {
                    for k in 0..3 {
                        lo[k] = lo[k].min(v[k] - pad);
                        hi[k] = hi[k].max(v[k] + pad);
                    }
                }
                (lo, hi)
            })
            .collect();
        let centre = |i: usize| {
            let p = &tris[i];
            [0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0)
        };
        let BoxTree { nodes, order } = BoxTree::build(&boxes, centre);
        TriangleTree {
            tris,
            normals,
            nodes,
            order,
        }
    }

    /// The triangles whose boxes meet the box [lo, hi], in increasing
    /// order.
    pub fn overlapping(&self, lo: Point3, hi: Point3) -> Vec<usize> {
        let mut out = vec![];
        if self.nodes.is_empty() {
            return out;
        }
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let nd = &self.nodes[ni];
            if (0..3).any(|k| nd.lo[k] > hi[k] || nd.hi[k] < lo[k]) {
                continue;
            }
            match nd.kids {
                Some([a, b]) => {
                    stack.push(b);
                    stack.push(a);
                }
                None => out.extend(self.order[nd.start..nd.end].iter().copied().filter(|&i| {
                    let t = &self.tris[i];
                    (0..3).all(|k| {
                        let (a, b) = t
                            .iter()
                            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                                (a.min(v[k]), b.max(v[k]))
                            });
                        a <= hi[k] && b >= lo[k]
                    })
                })),
            }
        }
        out.sort_unstable();
        out
    }

    /// The triangle nearest to `x` (the least |distance| to its plane) on
    /// which `x` projects orthogonally, among those `keep` accepts; ties go
    /// to the lower triangle index.
    pub fn nearest(&self, x: Point3, keep: impl Fn(usize) -> bool) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        if self.nodes.is_empty() {
            return None;
        }
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let nd = &self.nodes[ni];
            let d2: f64 = (0..3)
                .map(|k| {
                    let d = (nd.lo[k] - x[k]).max(x[k] - nd.hi[k]).max(0.0);
                    d * d
                })
                .sum();
            if let Some(b) = best {
                if d2 > b.dist * b.dist {
                    continue;
                }
            }
            match nd.kids {
                Some([a, b]) => {
                    stack.push(b);
                    stack.push(a);
                }
                None => {
                    for &i in &self.order[nd.start..nd.end] {
                        if !keep(i) {
                            continue;
                        }
                        let Some((weights, dist)) = project(x, &self.tris[i], self.normals[i])
                        else {
                            continue;
                        };
                        let better = match best {
                            None => true,
                            Some(b) => {
                                dist.abs() < b.dist.abs()
                                    || (dist.abs() == b.dist.abs() && i < b.tri)
                            }
                        };
                        if better {
                            best = Some(Hit {
                                tri: i,
                                weights,
                                dist,
                            });
                        }
                    }
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tree finds what a scan over all triangles finds, on a bumpy
    /// surface of 2 × 20 × 20 triangles.
    #[test]
    fn tree_agrees_with_a_scan() {
        let n = 20;
        let z = |i: usize, j: usize| 0.1 * ((i * 7 + j * 3) % 5) as f64 / 5.0;
        let mut tris = vec![];
        for i in 0..n {
            for j in 0..n {
                let p = |a: usize, b: usize| [a as f64, b as f64, z(a, b)];
                tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        let normals: Vec<[f64; 3]> = tris
            .iter()
            .map(|p| {
                let (a, b) = (
                    [0, 1, 2].map(|k| p[1][k] - p[0][k]),
                    [0, 1, 2].map(|k| p[2][k] - p[0][k]),
                );
                let c = [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ];
                let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                c.map(|v| v / l)
            })
            .collect();
        let tree = TriangleTree::build(&tris, &normals);
        for q in 0..200 {
            let x = [
                (q * 37 % 211) as f64 / 211.0 * n as f64,
                (q * 53 % 199) as f64 / 199.0 * n as f64,
                0.3 + (q % 3) as f64 * 0.2,
            ];
            let mut scan: Option<Hit> = None;
            for i in 0..tris.len() {
                if let Some((w, d)) = project(x, &tris[i], normals[i]) {
                    if scan.is_none_or(|b| d.abs() < b.dist.abs()) {
                        scan = Some(Hit {
                            tri: i,
                            weights: w,
                            dist: d,
                        });
                    }
                }
            }
            let got = tree.nearest(x, |_| true);
            assert_eq!(
                got.map(|h| h.dist.abs()),
                scan.map(|h| h.dist.abs()),
                "{x:?}"
            );
        }
    }

    /// A point on an edge of the triangle projects inside; one farther
    /// outside than the tolerance does not.
    #[test]
    fn edge_points_are_inside_within_the_tolerance() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let n = [0.0, 0.0, 1.0];
        let (w, d) = project([0.5, -1e-9, 0.2], &p, n).unwrap();
        assert!((d - 0.2).abs() < 1e-15 && w[2] == 0.0 && (w[0] + w[1] - 1.0).abs() < 1e-15);
        assert!(project([0.5, -1e-5, 0.2], &p, n).is_none());
    }
}
