//! Preconditioned conjugate gradients with a stall test, the solver the
//! AMG hierarchy serves.

use super::kernels::*;
use crate::linalg::sparse::Csr;

/// Result of [`pcg`].
#[derive(Debug, Clone, Copy)]
pub struct PcgReport {
    pub iterations: usize,
    /// ‖b − Kx‖₂ / ‖b‖₂ of the returned x (recomputed, not the recursion's).
    pub rel_residual: f64,
    pub converged: bool,
    /// Stopped because the stall window of [`pcg_stall`] passed without
    /// halving the residual: the rounding floor of b − Kx is above rtol.
    pub stalled: bool,
}

/// A stall window for [`pcg_stall`] with a multigrid preconditioner.
pub const PCG_STALL: usize = 50;

/// Preconditioned CG for K x = b from the given x (warm start), stop when
/// ‖b − Kx‖₂ ≤ rtol·‖b‖₂ (or b = 0, then x = 0) or after max_iter.
/// Deterministic. The stop is confirmed on the true residual: if the
/// recursive one has drifted, CG restarts from the true one.
pub fn pcg(
    k: &Csr,
    b: &[f64],
    x: &mut [f64],
    m: &dyn Fn(&[f64], &mut [f64]),
    rtol: f64,
    max_iter: usize,
) -> PcgReport {
    pcg_stall(k, b, x, m, rtol, max_iter, usize::MAX)
}

/// [`pcg`] that also stops when `stall` steps have not halved the best
/// residual once it is below √rtol·‖b‖₂ (counts only; a CG residual may
/// grow for a while before): the rounding floor of b − Kx (a soft body
/// beside a stiff one) lies above rtol. [`PCG_STALL`] suits a multigrid
/// preconditioner, not a weak one, whose CG may crawl that long.
pub fn pcg_stall(
    k: &Csr,
    b: &[f64],
    x: &mut [f64],
    m: &dyn Fn(&[f64], &mut [f64]),
    rtol: f64,
    max_iter: usize,
    stall: usize,
) -> PcgReport {
    let n = b.len();
    let bn = pdot(b, b).sqrt();
    if bn == 0.0 {
        x.fill(0.0);
        return PcgReport {
            iterations: 0,
            rel_residual: 0.0,
            converged: true,
            stalled: false,
        };
    }
    let tol = rtol * bn;
    let true_residual = |x: &[f64], r: &mut [f64]| {
        for_rows(r, |i, ri| *ri = b[i] - k.row_dot(i, x));
    };
    let pnorm = |v: &[f64]| pdot(v, v).sqrt();
    let mut r = vec![0.0; n];
    true_residual(x, &mut r);
    let mut z = vec![0.0; n];
    let mut q = vec![0.0; n];
    let mut it = 0;
    let r0 = pnorm(&r);
    let (mut best, mut best_at, mut stalled) = (r0, 0usize, false);
    if r0 > tol && max_iter > 0 {
        m(&r, &mut z);
        let mut rz = pdot(&r, &z);
        let mut p = z.clone();
        while it < max_iter {
            let pq = mul_dot(k, &p, &mut q);
            if !(pq > 0.0) || !(rz > 0.0) {
                break; // K or M not SPD (or exact convergence)
            }
            let alpha = rz / pq;
            let rn = cg_step(alpha, &p, &q, x, &mut r).sqrt();
            it += 1;
            if rn <= 0.5 * best {
                (best, best_at) = (rn, it);
            } else if it - best_at >= stall && best <= rtol.sqrt() * bn {
                stalled = true;
                break;
            }
            let mut restart = false;
            if rn <= tol {
                true_residual(x, &mut r);
                if pnorm(&r) <= tol {
                    break;
                }
                restart = true;
            }
            m(&r, &mut z);
            let rz_new = pdot(&r, &z);
            let beta = if restart { 0.0 } else { rz_new / rz };
            rz = rz_new;
            for_rows(&mut p, |i, pi| *pi = z[i] + beta * *pi);
        }
    }
    true_residual(x, &mut r);
    let rel = pnorm(&r) / bn;
    PcgReport {
        iterations: it,
        rel_residual: rel,
        converged: rel <= rtol,
        stalled: stalled && rel > rtol,
    }
}
