//! Power iteration for ‖H‖ of a symmetric positive semidefinite operator
//! given only as v ↦ Hv (the dual Hessian H = A C⁻¹ Aᵀ applied through a
//! factor of C, docs/methods.md §4.5, §4.6).
//!
//! The dual methods need ‖H‖ only for a step length (Uzawa's ρ = 1/‖H‖,
//! MPRGP's ᾱ = 1.9/‖H‖) and for scales (SMALBE's ρ and M₀), so a few steps
//! suffice. The start vector is a fixed pseudo-random sequence with every
//! component in [0.5, 1.5): deterministic (the same numbers on every run),
//! with a component along every row, and not aligned with the structured
//! eigenvectors of a mesh. The estimate ‖Hv‖ for the last unit v lies below
//! ‖H‖ and approaches it from below.

use crate::linalg::sparse::norm;

/// Start vector of length `m`: a linear congruential sequence mapped to
/// [0.5, 1.5).
pub fn start_vector(m: usize) -> Vec<f64> {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..m)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            0.5 + ((state >> 11) as f64) / ((1u64 << 53) as f64)
        })
        .collect()
}

/// ‖Hv‖ after `iters` power steps from `v` (each step normalises v and
/// applies H). Returns 0 when v is zero (or H maps it to zero) and stops
/// early on a NaN.
pub fn norm_estimate(
    mut v: Vec<f64>,
    iters: usize,
    mut apply: impl FnMut(&[f64]) -> Vec<f64>,
) -> f64 {
    let mut est = 0.0;
    for _ in 0..iters {
        let nv = norm(&v);
        if nv.is_nan() || nv <= 0.0 {
            break;
        }
        v.iter_mut().for_each(|a| *a /= nv);
        let w = apply(&v);
        est = norm(&w);
        v = w;
    }
    est
}

#[cfg(test)]
mod tests {
    use super::*;

    /// H = diag(1, …, m): the estimate lies below ‖H‖ = m and approaches it.
    #[test]
    fn diagonal_operator_from_below() {
        let m = 20;
        let h = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .enumerate()
                .map(|(i, a)| (i + 1) as f64 * a)
                .collect()
        };
        let e5 = norm_estimate(start_vector(m), 5, h);
        let e200 = norm_estimate(start_vector(m), 200, h);
        assert!(e5 <= m as f64 * (1.0 + 1e-12) && e200 <= m as f64 * (1.0 + 1e-12));
        assert!(e5 < e200, "{e5} {e200}");
        assert!((e200 - m as f64).abs() <= 1e-3 * m as f64, "{e200}");
    }

    /// Deterministic: the same start and the same numbers every call; every
    /// component in [0.5, 1.5).
    #[test]
    fn start_is_fixed() {
        let a = start_vector(50);
        assert_eq!(a, start_vector(50));
        assert!(a.iter().all(|&x| (0.5..1.5).contains(&x)));
        assert_eq!(&start_vector(10)[..], &a[..10]);
    }

    #[test]
    fn zero_operator_and_empty_vector() {
        assert_eq!(
            norm_estimate(start_vector(4), 10, |v| vec![0.0; v.len()]),
            0.0
        );
        assert_eq!(norm_estimate(vec![], 10, |v| v.to_vec()), 0.0);
    }
}
