//! The KKT certificate computed after every solve, independently of the method
//! (problem-format.md "Outputs"): relative, unit-free residuals.

use super::sparse::{dot, norm, norm_inf};
use super::{Kkt, QpProblem};

/// Residuals of (x, λ) for `qp`:
/// stationarity ‖Cx − d + Aᵀλ‖ / max(‖d‖, ‖Cx‖),
/// primal max((Ax − g)⁺) / max|x|,
/// dual max((−λ)⁺) / max(max|λ|, 1),
/// complementarity |λᵀ(Ax − g)| / max(max|λ|·max|x|, tiny).
pub fn residuals(qp: &QpProblem, x: &[f64], lambda: &[f64]) -> Kkt {
    let cx = qp.c.mul(x);
    let mut r: Vec<f64> = cx.iter().zip(&qp.d).map(|(a, b)| a - b).collect();
    qp.a.mul_t_add(lambda, &mut r);
    let scale = norm(&qp.d).max(norm(&cx));
    let stationarity = if scale > 0.0 {
        norm(&r) / scale
    } else {
        norm(&r)
    };
    let ax = qp.a.mul(x);
    let viol: Vec<f64> = ax.iter().zip(&qp.g).map(|(a, g)| a - g).collect();
    let xmax = norm_inf(x);
    let pmax = viol.iter().fold(0.0f64, |m, v| m.max(*v));
    // Gaps and displacements share units; a zero solution has no scale.
    let primal = if xmax > 0.0 { pmax / xmax } else { pmax };
    let lmax = norm_inf(lambda);
    let dual = lambda.iter().fold(0.0f64, |m, l| m.max(-l)) / lmax.max(1.0);
    let compl = dot(lambda, &viol).abs();
    let complementarity = compl / (lmax * xmax).max(f64::MIN_POSITIVE);
    Kkt {
        primal,
        dual,
        complementarity,
        stationarity,
    }
}

impl Kkt {
    /// The largest of the four residuals.
    pub fn max(&self) -> f64 {
        self.primal
            .max(self.dual)
            .max(self.complementarity)
            .max(self.stationarity)
    }
    /// NaN-safe check against a target.
    pub fn within(&self, target: f64) -> bool {
        let m = self.max();
        m.is_finite() && m <= target
    }
}
