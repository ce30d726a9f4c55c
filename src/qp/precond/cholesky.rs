//! Complete Cholesky W = C (methods.md §4.2, the report's fastest), via faer;
//! a semicoercive C is regularised along its kernel (see `linalg::cholesky`).

use super::Preconditioner;
use crate::linalg::{cholesky::Cholesky, sparse::Csr};
use crate::qp::QpError;

pub struct CholeskyPc {
    pub factor: Cholesky,
}

impl CholeskyPc {
    pub fn new(c: &Csr, kernel: &[Vec<f64>]) -> Result<CholeskyPc, QpError> {
        Ok(CholeskyPc {
            factor: Cholesky::new(c, kernel)?,
        })
    }
}

impl Preconditioner for CholeskyPc {
    fn name(&self) -> &'static str {
        "cholesky"
    }
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
        self.factor.solve_in_place(z);
    }
}
