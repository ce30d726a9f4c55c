//! `--start-from COARSE.h5` (docs/methods.md §7.2, "The nested start";
//! docs/problem-format.md §6): the answer of the same model on a coarser
//! mesh, read from its checkpoint and interpolated onto this mesh, starts
//! each load step's solve. This is nested iteration (Hüeber & Wohlmuth,
//! CMAME 194, 2005, §5): from a start whose contact zone is within a coarse
//! element of the answer, the Newton steps on the fine mesh do not grow
//! with its refinement.
//!
//! Displacements are interpolated linearly in the coarse tetrahedra of the
//! point's own body (a point a little outside its coarse body, as on a
//! curved surface meshed finer, is extrapolated from the nearest
//! tetrahedron); the contact pressure in the same tetrahedra from the
//! coarse slave points, times each fine row's tributary area, gives λ̂.
//! The solve decides and certifies as from any start: nothing of the
//! coarse answer enters the result.

use super::SolidPrepared;
use crate::fem::contact3d::search::BoxTree;
use crate::fem::element::{Point3, Vector3};
use crate::io::hdf5::{read_solid_checkpoint, SolidSteps};
use crate::run::RunError;
use std::path::{Path, PathBuf};

/// A point farther outside its coarse body than this many times the
/// tetrahedron's size (least barycentric coordinate below −FAR) is no part
/// of that body: the meshes are not of one geometry.
const FAR: f64 = 0.5;
/// Points of a body that vote for its coarse body, at most.
const VOTERS: usize = 2000;

/// The interpolated coarse answers, one per coarse load step.
#[derive(Debug, Clone)]
pub struct NestedStart {
    /// The coarse checkpoint.
    pub path: PathBuf,
    /// Per coarse step: its pseudo-time, the displacement of every point
    /// of this model and λ̂ per contact row of this model.
    steps: Vec<(f64, Vec<Vector3>, Vec<f64>)>,
    /// Seconds spent reading and interpolating.
    pub seconds: f64,
}

/// Linear interpolation weights of one point: four coarse points and
/// their barycentric coordinates.
type Weights = ([usize; 4], [f64; 4]);

impl NestedStart {
    /// Reads the coarse checkpoint at `path` and interpolates each of its
    /// steps onto `prep`'s mesh. Refused, naming the file, when it is not
    /// the checkpoint of a 3D model with the same materials and bodies.
    pub fn read(path: &Path, prep: &SolidPrepared) -> Result<NestedStart, RunError> {
        let t0 = std::time::Instant::now();
        let shown = path.display();
        let fail = |msg: String| RunError::Restart(format!("--start-from: {shown}: {msg}"));
        if !path.is_file() {
            return Err(fail("no such file".into()));
        }
        // A frictional step starts from the last step's multipliers and
        // slip (docs/methods.md §12.3), which a coarse displacement does
        // not give: on the sandwich of BENCHMARKS.md (three meshes apart,
        // four steps) it took the first step's Newton steps unchanged (8)
        // and the later ones from 1 to 7.
        if prep.model.qp.friction.is_some() {
            return Err(fail(format!(
                "{} has friction; the nested start is for frictionless contact (a frictional load step starts from the last step's multipliers, docs/methods.md §7.2)",
                prep.problem.path.display()
            )));
        }
        if !crate::io::hdf5::is_solid_checkpoint(path) {
            return Err(fail(
                "not the checkpoint of a 3D model (a solve's NAME.h5 whose root attribute model is \"solid\")"
                    .into(),
            ));
        }
        let ck = read_solid_checkpoint(path, SolidSteps::All).map_err(|e| fail(e.to_string()))?;
        log::debug!(
            "nested start: {} read, {:.3} s",
            shown,
            t0.elapsed().as_secs_f64()
        );
        if ck.steps.is_empty() {
            return Err(fail("the checkpoint holds no solved step".into()));
        }
        let m = &prep.model;
        // Coarse material index → this model's, by name.
        let mat: Vec<Option<u32>> = ck
            .material_names
            .iter()
            .map(|n| {
                m.material_names
                    .iter()
                    .position(|k| k == n)
                    .map(|i| i as u32)
            })
            .collect();
        for (i, name) in m.material_names.iter().enumerate() {
            if !ck.material_names.contains(name) {
                return Err(fail(format!(
                    "no tetrahedron of material '{name}' (this model's volume {i}); the coarse checkpoint has {:?}: a nested start needs a mesh of the same bodies",
                    ck.material_names
                )));
            }
        }
        let cbodies = ck
            .point_body
            .iter()
            .map(|&b| b as usize + 1)
            .max()
            .unwrap_or(0);
        // The coarse tetrahedra of each coarse body, and each body's material.
        let mut tets_of: Vec<Vec<usize>> = vec![vec![]; cbodies];
        let mut cmat: Vec<Option<u32>> = vec![None; cbodies];
        for (t, tet) in ck.tets.iter().enumerate() {
            let b = ck.point_body[tet[0]] as usize;
            tets_of[b].push(t);
            cmat[b] = mat[ck.material[t] as usize];
        }
        let trees: Vec<BodyTree> = tets_of
            .iter()
            .map(|ts| BodyTree::new(&ck.points, &ck.tets, ts))
            .collect();
        // This model's material per body (its tetrahedra's).
        let mut fmat: Vec<Option<u32>> = vec![None; m.nbodies];
        for (tet, &mt) in m.tets.iter().zip(&m.tet_material) {
            fmat[m.point_body[tet[0]] as usize] = Some(mt);
        }
        // Each body of this model is the coarse body of its material that
        // holds most of its points (two bodies of one material are told
        // apart by where they lie).
        let mut body_map = vec![usize::MAX; m.nbodies];
        for b in 0..m.nbodies {
            let mut votes = vec![0usize; cbodies];
            // Up to VOTERS points of the body vote.
            let mine: Vec<usize> = (0..m.points.len())
                .filter(|&p| m.point_body[p] as usize == b)
                .collect();
            let every = mine.len().div_ceil(VOTERS).max(1);
            for x in mine.iter().step_by(every).map(|&p| &m.points[p]) {
                for cb in (0..cbodies).filter(|&cb| cmat[cb].is_some() && cmat[cb] == fmat[b]) {
                    if let Some((_, w)) = trees[cb].locate(&ck.points, &ck.tets, *x) {
                        if w.iter().all(|&v| v >= -1e-9) {
                            votes[cb] += 1;
                        }
                    }
                }
            }
            let best = (0..cbodies).max_by_key(|&cb| (votes[cb], std::cmp::Reverse(cb)));
            match best.filter(|&cb| votes[cb] > 0) {
                Some(cb) => body_map[b] = cb,
                None => {
                    let name = fmat[b].map_or("?", |k| m.material_names[k as usize].as_str());
                    return Err(fail(format!(
                        "no coarse body holds this model's body {b} (material '{name}'): the two meshes are not of the same geometry"
                    )));
                }
            }
        }
        log::debug!(
            "nested start: bodies matched, {:.3} s",
            t0.elapsed().as_secs_f64()
        );
        // Interpolation weights of every point.
        let mut weights: Vec<Weights> = Vec::with_capacity(m.points.len());
        for (p, x) in m.points.iter().enumerate() {
            let cb = body_map[m.point_body[p] as usize];
            match trees[cb].locate(&ck.points, &ck.tets, *x) {
                Some((t, w)) if w.iter().all(|&v| v >= -FAR) => weights.push((ck.tets[t], w)),
                _ => {
                    return Err(fail(format!(
                        "point {p} of this mesh, at ({:e}, {:e}, {:e}), lies outside its body in the coarse mesh: the two meshes are not of the same geometry",
                        x[0], x[1], x[2]
                    )))
                }
            }
        }
        // The coarse contact pressure at its slave points (the largest of
        // the rows a point carries).
        let mut steps = Vec::with_capacity(ck.steps.len());
        for st in &ck.steps {
            let mut pn = vec![0.0f64; ck.points.len()];
            for (r, &s) in ck.contact.slave.iter().enumerate() {
                let v = st.contact_pressure.get(r).copied().unwrap_or(0.0);
                if v.is_finite() && v > pn[s] {
                    pn[s] = v;
                }
            }
            if !st.displacement.iter().flatten().all(|v| v.is_finite()) {
                return Err(fail(format!(
                    "step {} holds displacements that are not finite; it cannot be a start",
                    st.index
                )));
            }
            let u: Vec<Vector3> = weights
                .iter()
                .map(|(ps, w)| {
                    let mut v = [0.0; 3];
                    for (&q, &wq) in ps.iter().zip(w) {
                        for k in 0..3 {
                            v[k] += wq * st.displacement[q][k];
                        }
                    }
                    v
                })
                .collect();
            // λ̂ = the pressure interpolated at the row's slave point (with
            // the weights clipped at zero, so that it stays ≥ 0) times its
            // tributary area.
            let lam: Vec<f64> = m
                .contact
                .iter()
                .map(|row| {
                    let (ps, w) = &weights[row.slave];
                    let wsum: f64 = w.iter().map(|v| v.max(0.0)).sum();
                    let p: f64 = ps.iter().zip(w).map(|(&q, &wq)| wq.max(0.0) * pn[q]).sum();
                    if wsum > 0.0 {
                        p / wsum * row.area
                    } else {
                        0.0
                    }
                })
                .collect();
            steps.push((st.time, u, lam));
        }
        log::debug!(
            "nested start: {} points and {} rows interpolated from {} coarse points, {:.3} s",
            m.points.len(),
            m.contact.len(),
            ck.points.len(),
            t0.elapsed().as_secs_f64()
        );
        Ok(NestedStart {
            path: path.to_path_buf(),
            steps,
            seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The start of the load step at pseudo-time `t`: the point
    /// displacements and λ̂ per contact row of the coarse step at the same
    /// time, if the checkpoint has one.
    pub fn at(&self, t: f64) -> Option<(&[Vector3], &[f64])> {
        self.steps
            .iter()
            .find(|(ts, _, _)| ts.to_bits() == t.to_bits())
            .map(|(_, u, l)| (u.as_slice(), l.as_slice()))
    }

    /// Coarse steps held.
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    /// No coarse step held (never, once read).
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
}

/// Barycentric coordinates of `x` in the tetrahedron `p`.
fn barycentric(p: [Point3; 4], x: Point3) -> Option<[f64; 4]> {
    let e = |i: usize| [p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]];
    let (a, b, c) = (e(1), e(2), e(3));
    let r = [x[0] - p[0][0], x[1] - p[0][1], x[2] - p[0][2]];
    let det = |u: [f64; 3], v: [f64; 3], w: [f64; 3]| {
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])
    };
    let d = det(a, b, c);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let l1 = det(r, b, c) / d;
    let l2 = det(a, r, c) / d;
    let l3 = det(a, b, r) / d;
    Some([1.0 - l1 - l2 - l3, l1, l2, l3])
}

/// One coarse body's tetrahedra in a bounding-volume tree
/// ([`BoxTree`], as the contact search's master triangles): a point is
/// located among the tetrahedra whose boxes hold it, O(log n) on a graded
/// mesh where a uniform grid's cells near the contact would hold hundreds.
struct BodyTree {
    tree: BoxTree,
    /// The tetrahedron of each item of the tree.
    of: Vec<usize>,
    /// The body's box diagonal.
    diag: f64,
}

impl BodyTree {
    fn new(points: &[[f64; 3]], tets: &[[usize; 4]], of: &[usize]) -> BodyTree {
        let boxes: Vec<(Point3, Point3)> = of
            .iter()
            .map(|&t| {
                let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for &q in &tets[t] {
                    for k in 0..3 {
                        a[k] = a[k].min(points[q][k]);
                        b[k] = b[k].max(points[q][k]);
                    }
                }
                (a, b)
            })
            .collect();
        let tree = BoxTree::build(&boxes, |i| {
            let (a, b) = boxes[i];
            [0, 1, 2].map(|k| a[k] + b[k])
        });
        let diag = tree.nodes.first().map_or(0.0, |r| {
            (0..3)
                .map(|k| (r.hi[k] - r.lo[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        });
        BodyTree {
            tree,
            of: of.to_vec(),
            diag,
        }
    }

    /// The tetrahedron that holds `x` (the greatest least barycentric
    /// coordinate among those whose boxes, padded, hold it; ties to the
    /// lower index) and the coordinates. A point no tetrahedron holds is
    /// searched once more with a pad of 10⁻⁴ of the body's size; a point
    /// no box holds, with pads growing ×4 until one does (a point outside
    /// gets the nearest tetrahedron's coordinates, some negative).
    fn locate(
        &self,
        points: &[[f64; 3]],
        tets: &[[usize; 4]],
        x: Point3,
    ) -> Option<(usize, [f64; 4])> {
        if self.tree.nodes.is_empty() {
            return None;
        }
        let mut best: Option<(f64, usize, [f64; 4])> = None;
        let mut pad = 0.0;
        loop {
            let mut stack = vec![0usize];
            while let Some(ni) = stack.pop() {
                let nd = &self.tree.nodes[ni];
                if (0..3).any(|k| x[k] < nd.lo[k] - pad || x[k] > nd.hi[k] + pad) {
                    continue;
                }
                match nd.kids {
                    Some([a, b]) => {
                        stack.push(b);
                        stack.push(a);
                    }
                    None => {
                        for &t in self.tree.order[nd.start..nd.end]
                            .iter()
                            .map(|&i| &self.of[i])
                        {
                            let Some(w) = barycentric(tets[t].map(|q| points[q]), x) else {
                                continue;
                            };
                            let least = w.iter().copied().fold(f64::INFINITY, f64::min);
                            let better = match &best {
                                None => true,
                                Some((b, bt, _)) => least > *b || (least == *b && t < *bt),
                            };
                            if better {
                                best = Some((least, t, w));
                            }
                        }
                    }
                }
            }
            // Held, or found with the first pad (a point just outside a
            // face: its boxes hold it), or the pad is the body's size.
            let found = best.as_ref().map(|(b, _, _)| *b >= 0.0);
            if found == Some(true) || (found.is_some() && pad > 0.0) || pad >= self.diag {
                break;
            }
            pad = if pad == 0.0 {
                1e-4 * self.diag
            } else {
                4.0 * pad
            };
        }
        best.map(|(_, t, w)| (t, w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid finds the tetrahedron holding a point, and the barycentric
    /// coordinates reproduce the point (a linear field is interpolated
    /// exactly); a point outside gets the nearest tetrahedron's
    /// coordinates, one of them negative.
    #[test]
    fn a_point_is_located_and_a_linear_field_interpolated_exactly() {
        // A unit cube in six tetrahedra (Kuhn's split).
        let points: Vec<[f64; 3]> = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let tets = vec![
            [0, 1, 3, 7],
            [0, 1, 5, 7],
            [0, 2, 3, 7],
            [0, 2, 6, 7],
            [0, 4, 5, 7],
            [0, 4, 6, 7],
        ];
        let all: Vec<usize> = (0..tets.len()).collect();
        let tree = BodyTree::new(&points, &tets, &all);
        let f = |x: [f64; 3]| 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2] + 1.0;
        for x in [
            [0.1, 0.2, 0.3],
            [0.9, 0.5, 0.05],
            [0.5, 0.5, 0.5],
            [0.0, 1.0, 1.0],
        ] {
            let (t, w) = tree.locate(&points, &tets, x).unwrap();
            assert!(w.iter().all(|&v| v >= -1e-12), "{x:?}: {w:?}");
            let v: f64 = tets[t]
                .iter()
                .zip(&w)
                .map(|(&q, &wq)| wq * f(points[q]))
                .sum();
            assert!((v - f(x)).abs() <= 1e-12, "{x:?}: {v} vs {}", f(x));
        }
        let (t, w) = tree.locate(&points, &tets, [1.05, 0.5, 0.5]).unwrap();
        assert!(
            w.iter().any(|&v| v < 0.0) && w.iter().all(|&v| v > -0.2),
            "{w:?}"
        );
        let v: f64 = tets[t]
            .iter()
            .zip(&w)
            .map(|(&q, &wq)| wq * f(points[q]))
            .sum();
        assert!((v - f([1.05, 0.5, 0.5])).abs() <= 1e-12);
    }
}
