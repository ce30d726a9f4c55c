//! ker C of a semicoercive stiffness (floating bodies): the basis R that the
//! FEM layer hands over in `QpProblem::kernel`, checked and orthonormalised
//! once for every method that eliminates rigid motions (ASM and ASM-CGH
//! docs/methods.md §4.7–4.8, the dual methods §4.6, SSN §7).
//!
//! The check is in C's own scale: ‖C z‖ ≤ [`KERNEL_TOL`]·max diag C·‖z‖ (a
//! vector that is not a rigid motion would make every FETI-type elimination
//! silently wrong), and zero or non-finite vectors are errors, not skipped.

use crate::linalg::error::{KernelDefect, LinalgError};
use crate::linalg::sparse::{dot, norm, norm_inf, Csr};

/// Relative test ‖C z‖ / (max diag C · ‖z‖) a kernel vector must pass.
pub const KERNEL_TOL: f64 = 1e-8;

/// A vector whose component outside span(previous vectors) is at most this
/// fraction of its norm is dropped as dependent.
const DEPENDENT: f64 = 1e-10;

/// An orthonormal basis of span(kernel) (modified Gram–Schmidt, twice;
/// dependent vectors dropped), after checking that every vector is in ker C.
pub fn orthonormal_kernel(c: &Csr, kernel: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, LinalgError> {
    let cmax = norm_inf(&c.diag()).max(f64::MIN_POSITIVE);
    let mut out: Vec<Vec<f64>> = vec![];
    for (i, z) in kernel.iter().enumerate() {
        if z.len() != c.ncols {
            return Err(LinalgError::Kernel {
                index: i,
                defect: KernelDefect::Length {
                    len: z.len(),
                    ncols: c.ncols,
                },
            });
        }
        let nz = norm(z);
        if !nz.is_finite() || nz <= 0.0 {
            return Err(LinalgError::Kernel {
                index: i,
                defect: KernelDefect::ZeroOrNotFinite,
            });
        }
        let cz = c.mul(z);
        if norm(&cz) > KERNEL_TOL * cmax * nz {
            return Err(LinalgError::Kernel {
                index: i,
                defect: KernelDefect::NotInKernel {
                    ratio: norm(&cz) / (cmax * nz),
                },
            });
        }
        let mut v: Vec<f64> = z.iter().map(|a| a / nz).collect();
        for _ in 0..2 {
            for q in &out {
                let p = dot(&v, q);
                for (a, b) in v.iter_mut().zip(q) {
                    *a -= p * b;
                }
            }
        }
        let nv = norm(&v);
        if nv > DEPENDENT {
            v.iter_mut().for_each(|a| *a /= nv);
            out.push(v);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two free unit masses joined by a spring, plus a clamped third one:
    /// ker C = span{e0 + e1}.
    fn c() -> Csr {
        Csr::from_triplets(
            3,
            3,
            &[
                (0, 0, 1.0),
                (0, 1, -1.0),
                (1, 0, -1.0),
                (1, 1, 1.0),
                (2, 2, 5.0),
            ],
        )
    }

    #[test]
    fn orthonormalises_and_drops_dependent_vectors() {
        let r = orthonormal_kernel(&c(), &[vec![2.0, 2.0, 0.0], vec![-1.0, -1.0, 0.0]]).unwrap();
        assert_eq!(r.len(), 1);
        let s = 0.5f64.sqrt();
        assert!((r[0][0] - s).abs() < 1e-15 && (r[0][1] - s).abs() < 1e-15 && r[0][2] == 0.0);
        // Two independent vectors of a zero C come out orthonormal.
        let z = Csr::zeros(3, 3);
        let r = orthonormal_kernel(&z, &[vec![1.0, 1.0, 0.0], vec![1.0, 0.0, 1.0]]).unwrap();
        assert_eq!(r.len(), 2);
        assert!(dot(&r[0], &r[1]).abs() < 1e-15);
        assert!(r.iter().all(|v| (norm(v) - 1.0).abs() < 1e-15));
        assert!(orthonormal_kernel(&c(), &[]).unwrap().is_empty());
    }

    #[test]
    fn bad_vectors_are_errors() {
        for (bad, want) in [
            (vec![1.0, 0.0, 0.0], "is not in ker C"),
            (vec![0.0, 0.0, 0.0], "is zero or not finite"),
            (vec![f64::NAN, 1.0, 0.0], "is zero or not finite"),
            (vec![1.0, 1.0], "has length 2, C has 3 columns"),
        ] {
            let e = orthonormal_kernel(&c(), &[vec![1.0, 1.0, 0.0], bad.clone()]).unwrap_err();
            assert!(
                matches!(e, LinalgError::Kernel { index: 1, .. }) && !e.is_memory(),
                "{bad:?}: {e:?}"
            );
            assert!(
                e.to_string().starts_with("kernel vector 1 ") && e.to_string().contains(want),
                "{e}"
            );
        }
    }
}
