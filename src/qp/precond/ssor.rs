//! SSOR(ω): W = 1/(2−ω) (D/ω + L)(D/ω)⁻¹(D/ω + L)ᵀ, 0 < ω < 2 (methods.md §4.2).

use super::Preconditioner;
use crate::qp::{sparse::Csr, QpError};

pub struct Ssor {
    c: Csr,
    diag_w: Vec<f64>,
    omega: f64,
}

impl Ssor {
    pub fn new(c: &Csr, omega: f64) -> Result<Ssor, QpError> {
        if !(omega > 0.0 && omega < 2.0) {
            return Err(QpError::BadParameter(format!(
                "SSOR: omega = {omega} must lie in (0, 2)"
            )));
        }
        let d = c.diag();
        if let Some(i) = d.iter().position(|v| !(*v > 0.0)) {
            return Err(QpError::Unsupported(format!(
                "SSOR: diagonal entry {i} of C is not positive"
            )));
        }
        Ok(Ssor {
            c: c.clone(),
            diag_w: d.iter().map(|v| v / omega).collect(),
            omega,
        })
    }
}

impl Preconditioner for Ssor {
    fn name(&self) -> &'static str {
        "ssor"
    }
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let n = r.len();
        let dw = &self.diag_w;
        // forward: (D/ω + L) y = r
        for i in 0..n {
            let (cols, vals) = self.c.row(i);
            let mut s = r[i];
            for (&j, &a) in cols.iter().zip(vals) {
                if j < i {
                    s -= a * z[j];
                }
            }
            z[i] = s / dw[i];
        }
        // y ← (D/ω) y
        for i in 0..n {
            z[i] *= dw[i];
        }
        // backward: (D/ω + Lᵀ) z = y  (Lᵀ = strict upper part, C symmetric)
        for i in (0..n).rev() {
            let (cols, vals) = self.c.row(i);
            let mut s = z[i];
            for (&j, &a) in cols.iter().zip(vals) {
                if j > i {
                    s -= a * z[j];
                }
            }
            z[i] = s / dw[i];
        }
        let f = 2.0 - self.omega;
        for v in z.iter_mut() {
            *v *= f;
        }
    }
}
