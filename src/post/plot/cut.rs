//! The geometry of the 3D figures: a plane (`--cut`), its in-plane axes,
//! and the section of the tetrahedra by it (one triangle or quadrilateral
//! per tetrahedron cut).

use super::style::fmt_num;
use super::{err, PlotError};

pub(super) type V3 = [f64; 3];

pub(super) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// A cutting plane: a point on it and its unit normal, and how the user
/// wrote it ("z = 0.5").
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    pub point: [f64; 3],
    pub normal: [f64; 3],
    pub text: String,
}

impl Plane {
    /// `x=A`, `y=A`, `z=A`, or `px,py,pz,nx,ny,nz` (a point and a normal).
    pub fn parse(s: &str) -> Result<Plane, PlotError> {
        let bad = || {
            err(format!(
                "--cut {s}: expected x=A, y=A, z=A or px,py,pz,nx,ny,nz (a point and a normal)"
            ))
        };
        let num = |t: &str| -> Result<f64, PlotError> {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(bad)
        };
        if let Some((axis, v)) = s.split_once('=') {
            let k = match axis.trim() {
                "x" | "X" => 0,
                "y" | "Y" => 1,
                "z" | "Z" => 2,
                _ => return Err(bad()),
            };
            let a = num(v)?;
            return Ok(Plane::axis(k, a));
        }
        let v: Vec<f64> = s.split(',').map(num).collect::<Result<_, _>>()?;
        let [px, py, pz, nx, ny, nz] = v[..] else {
            return Err(bad());
        };
        let n = [nx, ny, nz];
        let l = norm(n);
        if !(l > 0.0 && l.is_finite()) {
            return Err(err(format!(
                "--cut {s}: the normal ({nx}, {ny}, {nz}) is zero"
            )));
        }
        Ok(Plane {
            point: [px, py, pz],
            normal: [nx / l, ny / l, nz / l],
            text: format!(
                "through ({}, {}, {}), normal ({}, {}, {})",
                fmt_num(px),
                fmt_num(py),
                fmt_num(pz),
                fmt_num(nx / l),
                fmt_num(ny / l),
                fmt_num(nz / l)
            ),
        })
    }

    /// The plane x_k = a.
    pub fn axis(k: usize, a: f64) -> Plane {
        let mut point = [0.0; 3];
        let mut normal = [0.0; 3];
        point[k] = a;
        normal[k] = 1.0;
        Plane {
            point,
            normal,
            text: format!("{} = {}", ["x", "y", "z"][k], fmt_num(a)),
        }
    }
}

/// In-plane axes of a plane of normal n: (e1, e2, n) right-handed. A
/// normal along a global axis keeps global axes (x–y for z, x–z for y,
/// y–z for x: the coordinates on the figure are the model's); any other
/// takes e1 from the global axis least aligned with n, e2 = n × e1.
#[derive(Debug, Clone)]
pub struct Frame {
    pub normal: V3,
    pub e1: V3,
    pub e2: V3,
    /// The axis labels without unit: "x", or "ξ ∥ (0.99, 0, -0.1)".
    pub labels: [String; 2],
}

impl Frame {
    pub fn of_normal(n: V3) -> Frame {
        const AXES: [V3; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        const NAMES: [&str; 3] = ["x", "y", "z"];
        if let Some(k) = (0..3).find(|&k| n[k].abs() >= 1.0 - 1e-9) {
            let (a, b) = match k {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            return Frame {
                normal: n,
                e1: AXES[a],
                e2: AXES[b],
                labels: [NAMES[a].to_string(), NAMES[b].to_string()],
            };
        }
        let k = (0..3)
            .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
            .unwrap_or(0);
        let a = AXES[k];
        let d = dot(a, n);
        let e1 = sub(a, [d * n[0], d * n[1], d * n[2]]);
        let l = norm(e1);
        let e1 = [e1[0] / l, e1[1] / l, e1[2] / l];
        let e2 = cross(n, e1);
        let dir = |e: V3| format!("({}, {}, {})", r3(e[0]), r3(e[1]), r3(e[2]));
        Frame {
            normal: n,
            e1,
            e2,
            labels: [format!("ξ ∥ {}", dir(e1)), format!("η ∥ {}", dir(e2))],
        }
    }

    /// In-plane coordinates of p: (p·e1, p·e2).
    pub fn project(&self, p: V3) -> (f64, f64) {
        (dot(p, self.e1), dot(p, self.e2))
    }
}

/// A direction component with 3 decimals, "-0" written 0.
fn r3(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() {
        "0".into()
    } else {
        s.to_string()
    }
}

/// A point of a section: on the edge (i, j) of its tetrahedron at
/// p_i + t (p_j − p_i), so that nodal fields interpolate the same way.
pub(super) type EdgePoint = (usize, usize, f64);

/// The section of one tetrahedron: 3 or 4 points in order round it.
pub(super) struct CutPolygon {
    pub tet: usize,
    pub verts: Vec<EdgePoint>,
}

/// The sections of the tetrahedra by `plane`, leaving out those of zero
/// area (a tetrahedron touching the plane at a point or an edge). A
/// vertex on the plane counts as above it, so a face in the plane is
/// drawn once, by the tetrahedron below it; a plane that touches the mesh
/// only from below (its bottom face) is taken from above instead.
pub(super) fn section(points: &[V3], tets: &[[usize; 4]], plane: &Plane) -> Vec<CutPolygon> {
    let d: Vec<f64> = points
        .iter()
        .map(|&p| dot(sub(p, plane.point), plane.normal))
        .collect();
    let below = section_by(points, tets, &d);
    if !below.is_empty() {
        return below;
    }
    let flipped: Vec<f64> = d.iter().map(|v| -v).collect();
    section_by(points, tets, &flipped)
}

/// [`section`] by the signed distances `d` of the points.
fn section_by(points: &[V3], tets: &[[usize; 4]], d: &[f64]) -> Vec<CutPolygon> {
    let mut out = Vec::new();
    let at = |e: EdgePoint| {
        let (a, b) = (points[e.0], points[e.1]);
        [
            a[0] + e.2 * (b[0] - a[0]),
            a[1] + e.2 * (b[1] - a[1]),
            a[2] + e.2 * (b[2] - a[2]),
        ]
    };
    for (k, t) in tets.iter().enumerate() {
        let (up, down): (Vec<usize>, Vec<usize>) = t.iter().partition(|&&i| d[i] >= 0.0);
        if up.is_empty() || down.is_empty() {
            continue;
        }
        let e = |i: usize, j: usize| -> EdgePoint { (i, j, d[i] / (d[i] - d[j])) };
        let verts = match (up.as_slice(), down.as_slice()) {
            ([a], [b, c, dd]) | ([b, c, dd], [a]) => vec![e(*a, *b), e(*a, *c), e(*a, *dd)],
            ([a, b], [c, dd]) => vec![e(*a, *c), e(*a, *dd), e(*b, *dd), e(*b, *c)],
            _ => continue,
        };
        let p: Vec<V3> = verts.iter().map(|&v| at(v)).collect();
        let scale = p.iter().map(|q| norm(sub(*q, p[0]))).fold(0.0, f64::max);
        if polygon_area(&p) > 1e-12 * scale * scale {
            out.push(CutPolygon { tet: k, verts });
        }
    }
    out
}

/// Area of a planar convex polygon in 3D.
pub(super) fn polygon_area(p: &[V3]) -> f64 {
    let mut s = [0.0; 3];
    for i in 1..p.len().saturating_sub(1) {
        let c = cross(sub(p[i], p[0]), sub(p[i + 1], p[0]));
        for k in 0..3 {
            s[k] += c[k];
        }
    }
    0.5 * norm(s)
}

/// The plane's miss: "(the mesh's z runs from A to B)" for an axis
/// plane, else its signed distances.
pub(super) fn misses(points: &[V3], plane: &Plane) -> PlotError {
    let d = points
        .iter()
        .map(|&p| dot(sub(p, plane.point), plane.normal));
    let (lo, hi) = d.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let axis = (0..3).find(|&k| plane.normal[k] == 1.0);
    let what = match axis {
        Some(k) => format!(
            "the mesh's {} runs from {} to {}",
            ["x", "y", "z"][k],
            fmt_num(lo + plane.point[k]),
            fmt_num(hi + plane.point[k])
        ),
        None => format!(
            "the nodes are {} to {} from it along its normal",
            fmt_num(lo),
            fmt_num(hi)
        ),
    };
    err(format!(
        "--cut {}: the plane misses the mesh ({what})",
        plane.text
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tet() -> (Vec<V3>, Vec<[usize; 4]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 1, 2, 3]],
        )
    }

    #[test]
    fn planes_parse() {
        let p = Plane::parse("z=0.5").unwrap();
        assert_eq!((p.point[2], p.normal), (0.5, [0.0, 0.0, 1.0]));
        assert_eq!(p.text, "z = 0.5");
        let p = Plane::parse("0,0,1, 0,0,2").unwrap();
        assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        for bad in ["w=1", "z=", "z=abc", "1,2,3", "0,0,0,0,0,0", "z=inf"] {
            assert!(Plane::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_tet_is_cut_into_a_triangle_or_a_quad_of_the_right_area() {
        let (p, t) = unit_tet();
        // z = 0.5: the triangle of legs 0.5, area 0.125.
        let s = section(&p, &t, &Plane::axis(2, 0.5));
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].verts.len(), 3);
        let at = |e: EdgePoint| {
            let (a, b) = (p[e.0], p[e.1]);
            [0, 1, 2].map(|k| a[k] + e.2 * (b[k] - a[k]))
        };
        let pts: Vec<V3> = s[0].verts.iter().map(|&e| at(e)).collect();
        assert!((polygon_area(&pts) - 0.125).abs() < 1e-14);
        assert!(pts.iter().all(|q| (q[2] - 0.5).abs() < 1e-14));
        // x + y = 0.5 separates {0, 3} from {1, 2}: a quadrilateral.
        let h = 0.5f64.sqrt();
        let plane = Plane::parse(&format!("0.25,0.25,0,{h},{h},0")).unwrap();
        let s = section(&p, &t, &plane);
        assert_eq!(s[0].verts.len(), 4);
        // A plane through a face draws it once (from the side below it,
        // or above for the bottom face), and one that only touches a
        // vertex not at all.
        assert_eq!(section(&p, &t, &Plane::axis(2, 0.0)).len(), 1);
        assert_eq!(section(&p, &t, &Plane::axis(2, 1.0)).len(), 0);
        assert!(section(&p, &t, &Plane::axis(2, 1.5)).is_empty());
        let s = section(&p, &[[0, 1, 2, 3]], &Plane::parse("0,0,0,0,0,-1").unwrap());
        assert_eq!(s.len(), 1, "the face z = 0 seen from above");
    }

    #[test]
    fn frames_keep_global_axes_and_are_right_handed() {
        let f = Frame::of_normal([0.0, 0.0, 1.0]);
        assert_eq!(f.labels, ["x".to_string(), "y".to_string()]);
        let f = Frame::of_normal([0.0, -1.0, 0.0]);
        assert_eq!(f.labels, ["x".to_string(), "z".to_string()]);
        let n = [0.1, 0.2, 0.97];
        let l = norm(n);
        let n = n.map(|v| v / l);
        let f = Frame::of_normal(n);
        assert!(dot(f.e1, n).abs() < 1e-14 && dot(f.e2, n).abs() < 1e-14);
        assert!((norm(f.e1) - 1.0).abs() < 1e-14 && dot(f.e1, f.e2).abs() < 1e-14);
        assert!(f.labels[0].starts_with("ξ ∥ (0.995"), "{}", f.labels[0]);
    }
}
