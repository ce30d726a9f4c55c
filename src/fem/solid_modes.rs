//! The rigid motions of a solid model's bodies (docs/methods.md §1.7,
//! §7.2): the basis of ker C that the conditions leave free, body by body,
//! and the six rigid motions per body that the multigrid carries as its
//! near-null space. Split from `solid.rs`, which builds the model.

use super::conditions::{Cond, PointDofs};
use super::contact3d::dot;
use super::element::{Point3, RigidMode, SOLID_MODES};
use super::solid::Cond3;

/// Each body's box centre and size, the frame of its rigid motions.
fn body_frames(points: &[Point3], point_body: &[u32], nbodies: usize) -> Vec<(Point3, f64)> {
    let mut lo = vec![[f64::MAX; 3]; nbodies];
    let mut hi = vec![[f64::MIN; 3]; nbodies];
    for (p, x) in points.iter().enumerate() {
        let b = point_body[p] as usize;
        for k in 0..3 {
            lo[b][k] = lo[b][k].min(x[k]);
            hi[b][k] = hi[b][k].max(x[k]);
        }
    }
    (0..nbodies)
        .map(|b| {
            let c = [0, 1, 2].map(|k| (lo[b][k] + hi[b][k]) / 2.0);
            let l = (0..3)
                .map(|k| hi[b][k] - lo[b][k])
                .fold(0.0, f64::max)
                .max(1e-300);
            (c, l)
        })
        .collect()
}

/// The near-null space of the iterative ssn path (docs/methods.md §7.2,
/// the 2D `rigid::near_kernel` in 3D): each point's unknowns as one
/// block, and the six rigid motions of every body in the reduced unknowns,
/// whatever the conditions hold. None if the points' unknowns are not
/// contiguous in point order.
pub(super) fn near_kernel(
    points: &[Point3],
    dofs: &[PointDofs<3>],
    n: usize,
) -> Option<crate::qp::NearKernel> {
    // One frame for every body (the box of all points): where a stiff row
    // of J glues two bodies an aggregate may take points of both, and its
    // six columns must then hold the rigid motions of the pair; per-body
    // frames (other centres and sizes) would give it a rotation by another
    // angle on each side (docs/methods.md §7.2).
    let frames = body_frames(points, &vec![0; points.len()], 1);
    let mut modes = vec![vec![0.0; n]; SOLID_MODES.len()];
    let mut block_ptr = vec![0usize];
    for (p, pd) in dofs.iter().enumerate() {
        if pd.ndof == 0 {
            continue;
        }
        if pd.start != *block_ptr.last()? {
            return None;
        }
        let (c, l) = frames[0];
        for (mode, &m) in modes.iter_mut().zip(SOLID_MODES.iter()) {
            let u = m.at(points[p], c, l);
            for j in 0..pd.ndof {
                mode[pd.start + j] = dot(pd.t[j], u);
            }
        }
        block_ptr.push(pd.start + pd.ndof);
    }
    (*block_ptr.last()? == n).then_some(crate::qp::NearKernel { block_ptr, modes })
}

/// The rigid motions (the six [`SOLID_MODES`]) of each body that satisfy
/// its homogeneous conditions, in the reduced unknowns, orthonormalised
/// (docs/methods.md §1.7; the 2D rigid.rs in 3D).
pub(super) fn rigid_kernel(
    points: &[Point3],
    point_body: &[u32],
    nbodies: usize,
    conds: &[Vec<Cond3>],
    dofs: &[PointDofs<3>],
    n: usize,
) -> (Vec<Vec<f64>>, Vec<u32>) {
    let frames = body_frames(points, point_body, nbodies);
    let (centre, size) = (|b: usize| frames[b].0, |b: usize| frames[b].1);
    let motion = |m: RigidMode, b: usize, x: Point3| m.at(x, centre(b), size(b));
    let mut gtg = vec![vec![vec![0.0; 6]; 6]; nbodies];
    for (p, cs) in conds.iter().enumerate() {
        let b = point_body[p] as usize;
        for &Cond { r, .. } in cs {
            let l = dot(r, r).sqrt();
            let row: Vec<f64> = SOLID_MODES
                .iter()
                .map(|&m| dot(r, motion(m, b, points[p])) / l)
                .collect();
            for i in 0..6 {
                for j in 0..6 {
                    gtg[b][i][j] += row[i] * row[j];
                }
            }
        }
    }
    let mut kernel: Vec<Vec<f64>> = vec![];
    let mut owner = vec![];
    for (b, m) in gtg.iter().enumerate() {
        let (vals, vecs) = crate::linalg::dense::sym_eigen(m);
        for (k, &val) in vals.iter().enumerate() {
            if val > 1e-9 {
                continue;
            }
            // sym_eigen returns the eigenvectors as rows (as 2D reads them, rigid.rs).
            let coef: Vec<f64> = vecs[k].clone();
            let mut z = vec![0.0; n];
            for (p, pd) in dofs
                .iter()
                .enumerate()
                .filter(|(p, _)| point_body[*p] as usize == b)
            {
                let mut u = [0.0; 3];
                for (i, &mode) in SOLID_MODES.iter().enumerate() {
                    let w = motion(mode, b, points[p]);
                    for c in 0..3 {
                        u[c] += coef[i] * w[c];
                    }
                }
                for r in 0..pd.ndof {
                    z[pd.start + r] = dot(pd.t[r], u);
                }
            }
            for q in &kernel {
                let s: f64 = q.iter().zip(&z).map(|(a, b)| a * b).sum();
                for (zi, qi) in z.iter_mut().zip(q) {
                    *zi -= s * qi;
                }
            }
            let nz = z.iter().map(|v| v * v).sum::<f64>().sqrt();
            if nz > 1e-12 {
                kernel.push(z.into_iter().map(|v| v / nz).collect());
                owner.push(b as u32);
            }
        }
    }
    (kernel, owner)
}
