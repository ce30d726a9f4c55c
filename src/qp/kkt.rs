//! The KKT certificate computed after every solve, independently of the method
//! (docs/methods.md §8, docs/problem-format.md §8): relative, unit-free
//! residuals of (x, λ).
//!
//! The four residuals of the problem-format contract are kept as the contract
//! defines them. A fifth, `contact_balance`, measures the force balance at the
//! contact unknowns against the contact forces themselves: when most of the
//! load goes to the supports, ‖d‖ is large and a relative error of 10⁻⁶ in the
//! contact forces would hide behind it in `stationarity` alone.
//!
//! NaN or Inf anywhere (x, λ, a residual) makes every residual infinite:
//! such an answer is never certified.

use crate::linalg::sparse::{norm, norm_inf};
use crate::qp::{Kkt, QpProblem};

/// Floor of the contact-force scale, relative to the load scale: contact
/// forces below 10⁻⁴ of the loads are measured against 10⁻⁴ of the loads.
pub const CONTACT_FLOOR: f64 = 1e-4;

/// Residuals of (x, λ) for `qp`, with r = Cx − d + Aᵀλ and S = max(‖d‖, ‖Cx‖):
/// * stationarity ‖r‖ / S;
/// * contact_balance ‖r_Γ‖ / max(‖Aᵀλ‖, 10⁻⁴·S), Γ = the unknowns A touches;
/// * primal max((Ax − g)⁺) / max|x|;
/// * dual max((−λ)⁺) / max(max|λ|, 1);
/// * complementarity |λᵀ(Ax − g)| / max(max|λ|·max|x|, tiny).
///
/// A zero denominator gives the raw numerator.
pub fn residuals(qp: &QpProblem, x: &[f64], lambda: &[f64]) -> Kkt {
    residuals_with_friction(qp, x, lambda, &[])
}

/// [`residuals`] with the tangential forces `lambda_t` of a frictional
/// problem (docs/methods.md §9.4): r = Cx − d + Aᵀλ + Tᵀλ_t, Γ also holds
/// the unknowns T touches, and `friction` = max of
/// * the bound max((|λ_tᵢ| − sᵢ)⁺) / max(max|λ|, max|λ_t|, 1);
/// * the slip rule Σ(sᵢ|vᵢ| − λ_tᵢvᵢ) / max(max(|λ|, |λ_t|)·max|x|, tiny),
///   zero iff every slip vᵢ ≠ 0 has λ_tᵢ = sᵢ·sign vᵢ (given the bound),
///
/// with s the slip bound at λ and v = T x − t0. Without friction
/// `lambda_t` must be empty and the result is [`residuals`]'s.
pub fn residuals_with_friction(qp: &QpProblem, x: &[f64], lambda: &[f64], lambda_t: &[f64]) -> Kkt {
    let finite = |v: &[f64]| v.iter().all(|e| e.is_finite());
    let mt = if qp.friction.is_some() { qp.m() } else { 0 };
    if x.len() != qp.n()
        || lambda.len() != qp.m()
        || lambda_t.len() != mt
        || !finite(x)
        || !finite(lambda)
        || !finite(lambda_t)
    {
        return Kkt::not_finite();
    }
    let cx = qp.c.mul(x);
    let mut alam = qp.a.mul_t(lambda);
    if let Some(f) = &qp.friction {
        f.t.mul_t_add(lambda_t, &mut alam);
    }
    let r: Vec<f64> = cx
        .iter()
        .zip(&qp.d)
        .zip(&alam)
        .map(|((c, d), a)| c - d + a)
        .collect();
    let scale = norm(&qp.d).max(norm(&cx));
    let stationarity = ratio(norm(&r), scale);
    // Γ: the columns of A (contact unknowns).
    let mut on_gamma = vec![false; qp.n()];
    for &c in &qp.a.indices {
        on_gamma[c] = true;
    }
    if let Some(f) = &qp.friction {
        for &c in &f.t.indices {
            on_gamma[c] = true;
        }
    }
    let r_gamma = r
        .iter()
        .zip(&on_gamma)
        .filter(|(_, &g)| g)
        .map(|(v, _)| v * v)
        .sum::<f64>()
        .sqrt();
    let contact_balance = ratio(r_gamma, norm(&alam).max(CONTACT_FLOOR * scale));
    let ax = qp.a.mul(x);
    let viol: Vec<f64> = ax.iter().zip(&qp.g).map(|(a, g)| a - g).collect();
    let xmax = norm_inf(x);
    let pmax = viol.iter().fold(0.0f64, |m, v| m.max(*v));
    // Gaps and displacements share units; a zero solution has no scale.
    let primal = ratio(pmax, xmax);
    let lmax = norm_inf(lambda);
    let dual = lambda.iter().fold(0.0f64, |m, l| m.max(-l)) / lmax.max(1.0);
    let compl: f64 = lambda.iter().zip(&viol).map(|(l, v)| l * v).sum();
    let complementarity = compl.abs() / (lmax * xmax).max(f64::MIN_POSITIVE);
    let friction = match &qp.friction {
        None => 0.0,
        Some(f) => {
            let s = f.slip_bound(lambda);
            let v = f.slip(x);
            let lt = lmax.max(norm_inf(lambda_t));
            let bound = lambda_t
                .iter()
                .zip(&s)
                .fold(0.0f64, |m, (l, s)| m.max(l.abs() - s));
            let slip: f64 = v
                .iter()
                .zip(&s)
                .zip(lambda_t)
                .map(|((v, s), l)| s * v.abs() - l * v)
                .sum();
            (bound / lt.max(1.0)).max(slip.abs() / (lt * xmax).max(f64::MIN_POSITIVE))
        }
    };
    let k = Kkt {
        primal,
        dual,
        complementarity,
        stationarity,
        contact_balance,
        friction,
    };
    if k.max().is_finite() {
        k
    } else {
        Kkt::not_finite()
    }
}

fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        num / den
    } else {
        num
    }
}

impl Kkt {
    /// Every residual infinite: NaN or Inf in the answer.
    pub fn not_finite() -> Kkt {
        Kkt {
            primal: f64::INFINITY,
            dual: f64::INFINITY,
            complementarity: f64::INFINITY,
            stationarity: f64::INFINITY,
            contact_balance: f64::INFINITY,
            friction: f64::INFINITY,
        }
    }
    /// The largest residual; NaN if any is NaN (`f64::max` would drop it).
    pub fn max(&self) -> f64 {
        let all = [
            self.primal,
            self.dual,
            self.complementarity,
            self.stationarity,
            self.contact_balance,
            self.friction,
        ];
        if all.iter().any(|v| v.is_nan()) {
            return f64::NAN;
        }
        all.iter().fold(0.0f64, |m, v| m.max(*v))
    }
    /// NaN-safe check against a target: certified iff every residual is
    /// finite and at most `target`.
    pub fn within(&self, target: f64) -> bool {
        let m = self.max();
        target.is_finite() && m.is_finite() && m <= target
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::Csr;

    /// Two springs: x0 free, x1 pressed against a wall x1 ≤ 0.
    fn qp(k_soft: f64, f: f64) -> QpProblem {
        QpProblem {
            c: Csr::from_triplets(2, 2, &[(0, 0, 1e4), (1, 1, k_soft)]),
            d: vec![1e4, f],
            a: Csr::from_triplets(1, 2, &[(0, 1, 1.0)]),
            g: vec![0.0],
            kernel: vec![],
            friction: None,
        }
    }

    #[test]
    fn exact_answer_is_certified() {
        let q = qp(1.0, 2.0);
        let k = residuals(&q, &[1.0, 0.0], &[2.0]);
        assert!(k.within(1e-14), "{k:?}");
    }

    #[test]
    fn a_contact_force_error_cannot_hide_behind_a_large_load() {
        // The load on the free unknown is 5000 × the contact force: a 10⁻³
        // relative error in λ is 2e-7 of ‖d‖ (certified by stationarity
        // alone) but 10⁻³ of the contact force.
        let q = qp(1.0, 2.0);
        let k = residuals(&q, &[1.0, 0.0], &[2.0 * (1.0 + 1e-3)]);
        assert!(k.stationarity < 1e-6, "{k:?}");
        assert!((k.contact_balance - 1e-3).abs() < 1e-6, "{k:?}");
        assert!(!k.within(1e-6));
    }

    #[test]
    fn nan_and_inf_are_never_certified() {
        let q = qp(1.0, 2.0);
        for bad in [f64::NAN, f64::INFINITY, 1e300] {
            let k = residuals(&q, &[1.0, bad], &[2.0]);
            assert!(!k.within(1e300), "{bad}: {k:?}");
            let k = residuals(&q, &[1.0, 0.0], &[bad]);
            assert!(!k.within(1e300), "{bad}: {k:?}");
        }
        let k = Kkt {
            stationarity: f64::NAN,
            ..Default::default()
        };
        assert!(k.max().is_nan() && !k.within(1.0));
        assert!(!Kkt::default().within(f64::NAN));
    }
}
