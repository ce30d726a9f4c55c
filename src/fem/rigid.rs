//! Rigid motions and the semicoercive checks (docs/methods.md §1.7).
//!
//! A body's rigid motions that its Dirichlet and slip conditions leave free
//! span the kernel of C (reduced unknowns, orthonormalised, one set per
//! body). A body with a kernel must touch a contact row, and a kernel
//! motion that slides along every contact (Az = 0) must not be worked on by
//! the loads (dᵀz = 0); otherwise the QP is unbounded and refused before
//! any solver runs. The messages name the body and the motion
//! (translation direction or centre of rotation).

use super::conditions::{normalize, Cond, PointDofs};
use super::element::ElementKind;
use super::element::{Point, Vector, PLANE_MODES};
use super::topology::Topology;
use super::{FemError, Model};
use crate::linalg::dense::sym_eigen;
use std::path::Path;

/// The rigid motions of each body at a point: translations along x and y
/// and a rotation about the centre of the body's bounding box, scaled by its
/// size so that the three are of one magnitude.
struct RigidBasis {
    lo: Vec<Point>,
    hi: Vec<Point>,
}

impl RigidBasis {
    fn new(topo: &Topology) -> RigidBasis {
        let nb = topo.nbodies;
        let mut lo = vec![[f64::MAX; 2]; nb];
        let mut hi = vec![[f64::MIN; 2]; nb];
        for (p, x) in topo.points.iter().enumerate() {
            let b = topo.point_body[p] as usize;
            for k in 0..2 {
                lo[b][k] = lo[b][k].min(x[k]);
                hi[b][k] = hi[b][k].max(x[k]);
            }
        }
        RigidBasis { lo, hi }
    }

    /// The three motions of body `b` at the point `x`.
    fn at(&self, b: usize, x: Point) -> [Vector; 3] {
        let (lo, hi) = (self.lo[b], self.hi[b]);
        let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        let l = ((hi[0] - lo[0]).max(hi[1] - lo[1])).max(1e-300);
        PLANE_MODES.map(|m| m.at(x, c, l))
    }
}

/// Rigid motions z = (a1 − b·ȳ, a2 + b·x̄) of each body that satisfy the
/// homogeneous conditions (docs/methods.md §1.7), in reduced DOFs, orthonormalised.
pub(super) fn rigid_modes(
    topo: &Topology,
    dofs: &[PointDofs],
    conds: &[Vec<Cond>],
    n: usize,
    kind: ElementKind,
) -> (Vec<Vec<f64>>, Vec<u32>) {
    let nb = topo.nbodies;
    let basis = RigidBasis::new(topo);
    // Axisymmetric bodies move rigidly along the axis only (a radial
    // translation strains the hoop, u_r/r ≠ 0; docs/methods.md §10): the
    // other two motions are left out of the search below.
    let modes = kind.plane_mode_mask();
    let skip = |i: usize| !modes[i];
    // GᵀG per body (3×3) from every condition row.
    let mut gtg = vec![[[0.0f64; 3]; 3]; nb];
    for (p, cs) in conds.iter().enumerate() {
        let b = topo.point_body[p] as usize;
        let z = basis.at(b, topo.points[p]);
        for c in cs {
            let r = normalize(c.r);
            let mut row: [f64; 3] = z.map(|zi| r[0] * zi[0] + r[1] * zi[1]);
            for (i, ri) in row.iter_mut().enumerate() {
                if skip(i) {
                    *ri = 0.0;
                }
            }
            for i in 0..3 {
                for j in 0..3 {
                    gtg[b][i][j] += row[i] * row[j];
                }
            }
        }
    }
    // Points of each body (they are numbered body after body, but do not
    // rely on it): CSR by counting.
    let mut bptr = vec![0usize; nb + 1];
    for &b in &topo.point_body {
        bptr[b as usize + 1] += 1;
    }
    for b in 0..nb {
        bptr[b + 1] += bptr[b];
    }
    let mut bpts = vec![0usize; topo.point_body.len()];
    {
        let mut fill = bptr[..nb].to_vec();
        for (p, &b) in topo.point_body.iter().enumerate() {
            bpts[fill[b as usize]] = p;
            fill[b as usize] += 1;
        }
    }
    let mut kernel = vec![];
    let mut owner = vec![];
    for m in gtg.iter_mut() {
        for i in (0..3).filter(|&i| skip(i)) {
            m[i][i] = 1.0;
        }
    }
    for b in 0..nb {
        let (vals, vecs) = sym_eigen(&gtg[b].iter().map(|r| r.to_vec()).collect::<Vec<_>>());
        for k in 0..3 {
            if vals[k] > 1e-9 {
                continue;
            }
            let c = &vecs[k];
            let mut v = vec![0.0; n];
            for &p in &bpts[bptr[b]..bptr[b + 1]] {
                let pd = &dofs[p];
                let z = basis.at(b, topo.points[p]);
                let u = [
                    c[0] * z[0][0] + c[1] * z[1][0] + c[2] * z[2][0],
                    c[0] * z[0][1] + c[1] * z[1][1] + c[2] * z[2][1],
                ];
                for j in 0..pd.ndof {
                    v[pd.start + j] = pd.t[j][0] * u[0] + pd.t[j][1] * u[1];
                }
            }
            // Only the body's DOFs are nonzero (in increasing order: the
            // same sum as over all of v).
            let body_dofs = bpts[bptr[b]..bptr[b + 1]]
                .iter()
                .flat_map(|&p| dofs[p].start..dofs[p].start + dofs[p].ndof);
            let nv = body_dofs.clone().map(|i| v[i] * v[i]).sum::<f64>().sqrt();
            if nv > 0.0 {
                for i in body_dofs {
                    v[i] /= nv;
                }
                kernel.push(v);
                owner.push(b as u32);
            }
        }
    }
    (kernel, owner)
}

/// The near-null space of the iterative ssn path (docs/methods.md §7.2):
/// the unknowns of each point as one block, and the rigid motions of every
/// body — translations along x and y, a rotation about the body's box centre
/// scaled by its size — in the reduced unknowns, whatever the conditions hold.
pub(super) fn near_kernel(
    topo: &Topology,
    dofs: &[PointDofs],
    n: usize,
) -> Option<crate::qp::NearKernel> {
    let basis = RigidBasis::new(topo);
    let mut modes = vec![vec![0.0; n]; 3];
    let mut block_ptr = vec![0usize];
    for (p, pd) in dofs.iter().enumerate() {
        if pd.ndof == 0 {
            continue;
        }
        // The unknowns of a point are contiguous and points come in order
        // (`conditions::eliminate`); otherwise no blocks.
        if pd.start != *block_ptr.last()? {
            return None;
        }
        let u = basis.at(topo.point_body[p] as usize, topo.points[p]);
        for (mode, um) in modes.iter_mut().zip(&u) {
            for j in 0..pd.ndof {
                mode[pd.start + j] = pd.t[j][0] * um[0] + pd.t[j][1] * um[1];
            }
        }
        block_ptr.push(pd.start + pd.ndof);
    }
    (*block_ptr.last()? == n).then_some(crate::qp::NearKernel { block_ptr, modes })
}

impl Model {
    /// The bodies that the point motions `u` move (by more than 10⁻³ of the
    /// largest motion), each with the rigid motion that fits it best:
    /// `body 1 (translation along (1, 0))` or `body 1 (rotation about (0.5, 0.25))`.
    pub fn describe_rigid_motion(&self, u: &[Vector]) -> String {
        let umax = u
            .iter()
            .fold(0.0f64, |m, v| m.max(v[0].hypot(v[1])))
            .max(f64::MIN_POSITIVE);
        let parts: Vec<String> = (0..self.topo.nbodies)
            .filter_map(|b| {
                self.body_motion(u, b, 1e-3 * umax)
                    .map(|what| format!("{} ({what})", self.body_label(b)))
            })
            .collect();
        if parts.is_empty() {
            "no body".into()
        } else {
            parts.join(", ")
        }
    }

    /// The rigid motion that fits the point motions `u` of body `b` best
    /// (least squares): "translation along (dx, dy)" or "rotation about
    /// (x, y)"; None if no point of the body moves by more than `min`.
    pub fn body_motion(&self, u: &[Vector], b: usize, min: f64) -> Option<String> {
        let pts: Vec<usize> = (0..u.len().min(self.topo.points.len()))
            .filter(|&p| self.topo.point_body[p] as usize == b)
            .collect();
        let bmax = pts
            .iter()
            .fold(0.0f64, |m, &p| m.max(u[p][0].hypot(u[p][1])));
        let moves = bmax > min; // false for NaN too
        if pts.is_empty() || !moves {
            return None;
        }
        // a + ω × (x − c) about the centroid c.
        let k = pts.len() as f64;
        let mut c = [0.0, 0.0];
        let mut a = [0.0, 0.0];
        for &p in &pts {
            let x = self.topo.points[p];
            c = [c[0] + x[0] / k, c[1] + x[1] / k];
            a = [a[0] + u[p][0] / k, a[1] + u[p][1] / k];
        }
        let (mut num, mut den, mut rmax) = (0.0, 0.0, 0.0f64);
        for &p in &pts {
            let r = [self.topo.points[p][0] - c[0], self.topo.points[p][1] - c[1]];
            num += r[0] * u[p][1] - r[1] * u[p][0];
            den += r[0] * r[0] + r[1] * r[1];
            rmax = rmax.max(r[0].hypot(r[1]));
        }
        let w = if den > 0.0 { num / den } else { 0.0 };
        let an = a[0].hypot(a[1]);
        // 4 decimals, and no "-0".
        let g = |v: f64| format!("{v:.4}").parse::<f64>().unwrap_or(v) + 0.0;
        Some(if an > 0.0 && (w * rmax).abs() <= 1e-3 * an {
            format!("translation along ({}, {})", g(a[0] / an), g(a[1] / an))
        } else if w != 0.0 && w.is_finite() {
            // The fixed point of the motion: a + ω × (p − c) = 0, rounded to
            // 10⁻⁵ of the body's size (no round-off noise such as 1e-17).
            let q = 10f64.powi(rmax.log10().floor() as i32 - 5);
            let p = [c[0] - a[1] / w, c[1] + a[0] / w].map(|v| {
                if q > 0.0 && q.is_finite() {
                    (v / q).round() * q
                } else {
                    v
                }
            });
            format!("rotation about ({}, {})", g_sig(p[0]), g_sig(p[1]))
        } else {
            "not a rigid motion".to_string()
        })
    }
}

/// A coordinate for messages: 6 significant digits, no trailing noise.
fn g_sig(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    format!("{v:.5e}")
        .parse::<f64>()
        .map(|x| format!("{}", x + 0.0))
        .unwrap_or_else(|_| format!("{v}"))
}

/// The bodies and the rigid motion (translation direction or centre of
/// rotation) of the kernel combination Σ c_k z_k.
fn describe_mode(m: &Model, c: &[f64]) -> String {
    let n = m.qp.n();
    let mut z = vec![0.0; n];
    for (ck, zk) in c.iter().zip(&m.qp.kernel) {
        for (zi, v) in z.iter_mut().zip(zk) {
            *zi += ck * v;
        }
    }
    m.describe_rigid_motion(&m.motions(&z))
}

/// Semicoercive checks of docs/methods.md §1.7 that need no iteration: a body
/// with free rigid motions and no contact at all, and a rigid motion that
/// leaves every contact row unchanged (Az = 0) while the loads work on it
/// (dᵀz ≠ 0): f is then unbounded below.
pub(super) fn check_semicoercive(m: &Model, path: &Path) -> Result<(), FemError> {
    if m.qp.kernel.is_empty() {
        return Ok(());
    }
    check_supported(m, path)?;
    if m.qp.friction.is_some() {
        // Friction may hold a sliding motion: the solver decides
        // (docs/methods.md §9.3).
        return Ok(());
    }
    check_sliding(m, path)
}

/// A body with a kernel and no contact row touching it is refused.
fn check_supported(m: &Model, path: &Path) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let qp = &m.qp;
    let mut touched = vec![false; m.topo.nbodies];
    for &r in &m.qp_rows {
        for (p, _) in m.topo.contact[r].coefficients() {
            touched[m.topo.point_body[p] as usize] = true;
        }
    }
    for &b in &m.kernel_body {
        if !touched[b as usize] {
            let modes: Vec<&Vec<f64>> = m
                .kernel_body
                .iter()
                .zip(&qp.kernel)
                .filter(|(&x, _)| x == b)
                .map(|(_, z)| z)
                .collect();
            let work = modes
                .iter()
                .any(|z| z.iter().zip(&qp.d).map(|(a, b)| a * b).sum::<f64>().abs() > 0.0);
            let free = if modes.len() >= 3 {
                "no Dirichlet or slip condition fixes it".to_string()
            } else {
                let what: Vec<String> = modes
                    .iter()
                    .filter_map(|z| m.body_motion(&m.motions(z), b as usize, 0.0))
                    .collect();
                format!(
                    "its Dirichlet and slip conditions leave {} free",
                    what.join(" and ")
                )
            };
            return Err(err(format!(
                "{} is not supported: {free} and it has no contact ({} free rigid motion(s){})",
                m.body_label(b as usize),
                modes.len(),
                if work {
                    "; the loads would move it without limit"
                } else {
                    ""
                }
            )));
        }
    }
    Ok(())
}

/// A rigid motion with Az = 0 is refused if the loads work on it (dᵀz ≠ 0)
/// and reported (a warning) otherwise.
fn check_sliding(m: &Model, path: &Path) -> Result<(), FemError> {
    let err = |msg: String| FemError::new(path, msg);
    let qp = &m.qp;
    let k = qp.kernel.len();
    // Null space of A Z (k small): eigenvectors of (AZ)ᵀ(AZ) with ~0 eigenvalue.
    let az: Vec<Vec<f64>> = qp.kernel.iter().map(|z| qp.a.mul(z)).collect();
    let mut mtm = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..k {
            mtm[i][j] = az[i].iter().zip(&az[j]).map(|(a, b)| a * b).sum();
        }
    }
    let dz: Vec<f64> = qp
        .kernel
        .iter()
        .map(|z| z.iter().zip(&qp.d).map(|(a, b)| a * b).sum())
        .collect();
    let dnorm = qp.d.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
    let (vals, vecs) = sym_eigen(&mtm);
    let amax = vals.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(1e-300);
    for (lam, c) in vals.iter().zip(&vecs) {
        if *lam <= 1e-12 * amax {
            let work: f64 = c.iter().zip(&dz).map(|(a, b)| a * b).sum();
            if work.abs() > 1e-9 * dnorm {
                return Err(err(format!(
                    "the problem is unbounded: a rigid motion of {} slides along every contact without opening it, and the loads do work on it (semicoercive condition of methods.md §1.7 violated)",
                    describe_mode(m, c)
                )));
            }
            log::warn!(
                "a rigid motion of {} slides along every contact without opening it and the loads do no work on it: unless friction holds it, the solution is unique only up to it, and the one returned has no component along it (methods.md §1.7)",
                describe_mode(m, c)
            );
        }
    }
    Ok(())
}
