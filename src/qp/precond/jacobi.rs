//! W = diag(C) (methods.md §4.2, "Diagonal").

use super::Preconditioner;
use crate::qp::{sparse::Csr, QpError};

pub struct Jacobi {
    inv_diag: Vec<f64>,
}

impl Jacobi {
    pub fn new(c: &Csr) -> Result<Jacobi, QpError> {
        let d = c.diag();
        if let Some(i) = d.iter().position(|v| !(*v > 0.0)) {
            return Err(QpError::Unsupported(format!(
                "Jacobi: diagonal entry {i} of C is not positive"
            )));
        }
        Ok(Jacobi {
            inv_diag: d.iter().map(|v| 1.0 / v).collect(),
        })
    }
}

impl Preconditioner for Jacobi {
    fn name(&self) -> &'static str {
        "jacobi"
    }
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for ((zi, ri), di) in z.iter_mut().zip(r).zip(&self.inv_diag) {
            *zi = ri * di;
        }
    }
}
