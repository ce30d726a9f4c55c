//! Preconditioners W ≈ C behind one trait (the PC of PETSc's KSP/PC split),
//! methods.md §4.2. A preconditioned method only ever applies z = W⁻¹r; the
//! report's split W = EEᵀ is never needed in the original variables.

mod cholesky;
mod ic0;
mod jacobi;
mod ssor;

use super::sparse::Csr;
use super::QpError;
use crate::linalg::cholesky::Workspace;

pub use cholesky::CholeskyPc;
pub use ic0::Ic0;
pub use jacobi::Jacobi;
pub use ssor::Ssor;

/// Which preconditioner (CLI names are part of the contract).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PrecondKind {
    None,
    Jacobi,
    Ssor,
    Ic0,
    Mic0,
    Cholesky,
}

impl PrecondKind {
    pub const ALL: [PrecondKind; 6] = [
        PrecondKind::None,
        PrecondKind::Jacobi,
        PrecondKind::Ssor,
        PrecondKind::Ic0,
        PrecondKind::Mic0,
        PrecondKind::Cholesky,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PrecondKind::None => "none",
            PrecondKind::Jacobi => "jacobi",
            PrecondKind::Ssor => "ssor",
            PrecondKind::Ic0 => "ic0",
            PrecondKind::Mic0 => "mic0",
            PrecondKind::Cholesky => "cholesky",
        }
    }

    pub fn parse(s: &str) -> Option<PrecondKind> {
        Self::ALL.iter().copied().find(|k| k.name() == s)
    }
}

/// A preconditioner's name: the one parser of the problem file's
/// `preconditioner` and of `--preconditioner`; the error lists the names.
impl std::str::FromStr for PrecondKind {
    type Err = String;
    fn from_str(name: &str) -> Result<PrecondKind, String> {
        PrecondKind::parse(name).ok_or_else(|| {
            format!(
                "unknown preconditioner \"{name}\"; known: {}",
                PrecondKind::ALL.map(PrecondKind::name).join(", ")
            )
        })
    }
}

/// z = W⁻¹ r for an SPD W ≈ C.
pub trait Preconditioner: Send + Sync {
    fn name(&self) -> &'static str;
    fn apply(&self, r: &[f64], z: &mut [f64]);
    /// W = I: lets CGC use the explicit projection for orthogonal rows.
    fn is_identity(&self) -> bool {
        false
    }
}

/// W = I.
pub struct Identity;

impl Preconditioner for Identity {
    fn name(&self) -> &'static str {
        "none"
    }
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
    fn is_identity(&self) -> bool {
        true
    }
}

/// Build the preconditioner of `kind` for C; `kernel` (rigid modes) lets the
/// factorizations regularise a semicoercive C.
pub fn build(
    kind: PrecondKind,
    c: &Csr,
    kernel: &[Vec<f64>],
    omega: f64,
) -> Result<Box<dyn Preconditioner>, QpError> {
    build_in(kind, c, kernel, omega, &Workspace::new())
}

/// [`build`], the Cholesky factor taken from (or kept in) `ws`.
pub fn build_in(
    kind: PrecondKind,
    c: &Csr,
    kernel: &[Vec<f64>],
    omega: f64,
    ws: &Workspace,
) -> Result<Box<dyn Preconditioner>, QpError> {
    Ok(match kind {
        PrecondKind::None => Box::new(Identity),
        PrecondKind::Jacobi => Box::new(Jacobi::new(c)?),
        PrecondKind::Ssor => Box::new(Ssor::new(c, omega)?),
        PrecondKind::Ic0 => Box::new(Ic0::new(c, false)?),
        PrecondKind::Mic0 => Box::new(Ic0::new(c, true)?),
        PrecondKind::Cholesky => Box::new(CholeskyPc {
            factor: ws.cholesky(c, kernel)?,
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::sparse::dot;

    /// A 2D 5-point Laplacian + identity shift: SPD, not diagonal.
    fn test_matrix(m: usize) -> Csr {
        let n = m * m;
        let mut t = vec![];
        for i in 0..m {
            for j in 0..m {
                let k = i * m + j;
                t.push((k, k, 4.5));
                if i + 1 < m {
                    t.push((k, k + m, -1.0));
                    t.push((k + m, k, -1.0));
                }
                if j + 1 < m {
                    t.push((k, k + 1, -1.0));
                    t.push((k + 1, k, -1.0));
                }
            }
        }
        Csr::from_triplets(n, n, &t)
    }

    #[test]
    fn every_preconditioner_is_spd_and_cholesky_is_exact() {
        let c = test_matrix(8);
        let n = c.nrows;
        let r: Vec<f64> = (0..n).map(|i| ((i * 7 % 11) as f64) - 5.0).collect();
        let s: Vec<f64> = (0..n).map(|i| ((i * 3 % 5) as f64) - 2.0).collect();
        for kind in PrecondKind::ALL {
            let p = build(kind, &c, &[], 1.3).unwrap();
            let mut z = vec![0.0; n];
            p.apply(&r, &mut z);
            let mut w = vec![0.0; n];
            p.apply(&s, &mut w);
            // symmetric: sᵀW⁻¹r = rᵀW⁻¹s ; positive: rᵀW⁻¹r > 0
            assert!(
                (dot(&s, &z) - dot(&r, &w)).abs() < 1e-10 * dot(&r, &z).abs().max(1.0),
                "{kind:?}"
            );
            assert!(dot(&r, &z) > 0.0, "{kind:?}");
            if kind == PrecondKind::Cholesky {
                let back = c.mul(&z);
                for (a, b) in back.iter().zip(&r) {
                    assert!((a - b).abs() < 1e-10);
                }
            }
        }
    }

    #[test]
    fn mic0_preserves_row_sums() {
        // MIC: (W − C)·1 = 0, so W⁻¹(C·1) = 1.
        let c = test_matrix(6);
        let ones = vec![1.0; c.nrows];
        let b = c.mul(&ones);
        let p = build(PrecondKind::Mic0, &c, &[], 1.0).unwrap();
        let mut z = vec![0.0; c.nrows];
        p.apply(&b, &mut z);
        for v in z {
            assert!((v - 1.0).abs() < 1e-10, "{v}");
        }
    }
}
