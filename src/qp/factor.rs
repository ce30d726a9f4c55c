//! Sparse Cholesky factorization of C (faer, AMD ordering, supernodal), with
//! the symbolic analysis kept for refactoring matrices of the same pattern.
//!
//! A semicoercive C (floating bodies) is singular. Given a basis R of ker C we
//! pick k "fixing" DOFs S (pivoted QR on Rᵀ, so R_S is nonsingular) and factor
//! C + Σ_{i∈S} c_ii eᵢeᵢᵀ, which is SPD. This regularised matrix serves as a
//! preconditioner; with the fixing DOFs' rows and columns removed instead it is the
//! classical fixing-node generalised inverse (Farhat–Géradin).

use super::sparse::Csr;
use super::QpError;
use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Side};

pub struct Cholesky {
    n: usize,
    llt: Llt<usize, f64>,
    /// DOFs that received a spring (empty for SPD C).
    pub fixing: Vec<usize>,
}

impl Cholesky {
    /// Factor C, regularised along `kernel` (may be empty).
    pub fn new(c: &Csr, kernel: &[Vec<f64>]) -> Result<Cholesky, QpError> {
        let fixing = fixing_dofs(kernel, c.nrows);
        let diag = c.diag();
        let scale = diag
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        let shift: Vec<(usize, f64)> = fixing
            .iter()
            .map(|&i| (i, if diag[i] > 0.0 { diag[i] } else { scale }))
            .collect();
        let (sym, vals) = lower_csc(c, &shift);
        let symbolic = SymbolicLlt::try_new(sym.as_ref(), Side::Lower)
            .map_err(|e| QpError::Factor(format!("symbolic analysis: {e:?}")))?;
        let mat = SparseColMatRef::new(sym.as_ref(), &vals);
        let llt = Llt::try_new_with_symbolic(symbolic, mat, Side::Lower).map_err(|e| {
            QpError::Factor(format!(
                "C is not positive definite ({e:?}); a body may be free to move without the kernel being known"
            ))
        })?;
        Ok(Cholesky {
            n: c.nrows,
            llt,
            fixing,
        })
    }

    /// x ← (C + springs)⁻¹ x
    pub fn solve_in_place(&self, x: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n);
        let m = MatMut::from_column_major_slice_mut(x, self.n, 1);
        self.llt.solve_in_place_with_conj(Conj::No, m);
    }

    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x);
        x
    }
}

/// The lower triangle of symmetric `c` as a faer CSC pattern + values, with
/// `shift` added to the diagonal. Row i of CSR with cols ≥ i is column i of
/// the lower triangle, because C is symmetric.
fn lower_csc(c: &Csr, shift: &[(usize, f64)]) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
    let n = c.nrows;
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(c.nnz() / 2 + n);
    let mut vals = Vec::with_capacity(c.nnz() / 2 + n);
    let mut extra = vec![0.0; n];
    for &(i, s) in shift {
        extra[i] += s;
    }
    col_ptr.push(0);
    for j in 0..n {
        let (cols, v) = c.row(j);
        let mut has_diag = false;
        for (&i, &a) in cols.iter().zip(v) {
            if i >= j {
                if i == j {
                    has_diag = true;
                    row_idx.push(i);
                    vals.push(a + extra[j]);
                } else {
                    if !has_diag {
                        row_idx.push(j);
                        vals.push(extra[j]);
                        has_diag = true;
                    }
                    row_idx.push(i);
                    vals.push(a);
                }
            }
        }
        if !has_diag {
            row_idx.push(j);
            vals.push(extra[j]);
        }
        col_ptr.push(row_idx.len());
    }
    (
        SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        vals,
    )
}

/// k DOFs such that R restricted to them is nonsingular: columns of Rᵀ
/// chosen by pivoted Gram–Schmidt (largest remaining norm first).
pub fn fixing_dofs(kernel: &[Vec<f64>], n: usize) -> Vec<usize> {
    let k = kernel.len();
    if k == 0 {
        return vec![];
    }
    // rows[i] = R[i, :] (length k), orthogonalised in place.
    let mut rows: Vec<Vec<f64>> = (0..n)
        .map(|i| kernel.iter().map(|z| z[i]).collect())
        .collect();
    let mut chosen = Vec::with_capacity(k);
    for _ in 0..k {
        let (best, bn) = rows
            .iter()
            .enumerate()
            .filter(|(i, _)| !chosen.contains(i))
            .map(|(i, r)| (i, r.iter().map(|v| v * v).sum::<f64>()))
            .fold(
                (usize::MAX, 0.0),
                |acc, (i, v)| if v > acc.1 { (i, v) } else { acc },
            );
        if best == usize::MAX || bn <= 0.0 {
            break;
        }
        chosen.push(best);
        let q: Vec<f64> = rows[best].iter().map(|v| v / bn.sqrt()).collect();
        for r in rows.iter_mut() {
            let p: f64 = r.iter().zip(&q).map(|(a, b)| a * b).sum();
            for (a, b) in r.iter_mut().zip(&q) {
                *a -= p * b;
            }
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lap1d(n: usize, dirichlet: bool) -> Csr {
        let mut t = vec![];
        for i in 0..n - 1 {
            t.push((i, i, 1.0));
            t.push((i + 1, i + 1, 1.0));
            t.push((i, i + 1, -1.0));
            t.push((i + 1, i, -1.0));
        }
        if dirichlet {
            t.push((0, 0, 1.0));
        }
        Csr::from_triplets(n, n, &t)
    }

    #[test]
    fn solves_spd() {
        let c = lap1d(50, true);
        let f = Cholesky::new(&c, &[]).unwrap();
        let x: Vec<f64> = (0..50).map(|i| (i as f64).sin()).collect();
        let b = c.mul(&x);
        let y = f.solve(&b);
        for (a, b) in x.iter().zip(&y) {
            assert!((a - b).abs() < 1e-9, "{a} {b}");
        }
    }

    #[test]
    fn singular_with_kernel_factors() {
        let c = lap1d(20, false);
        let f = Cholesky::new(&c, &[vec![1.0; 20]]).unwrap();
        assert_eq!(f.fixing.len(), 1);
        let b: Vec<f64> = (0..20)
            .map(|i| {
                if i == 0 {
                    1.0
                } else if i == 19 {
                    -1.0
                } else {
                    0.0
                }
            })
            .collect();
        let y = f.solve(&b);
        // (C + s·e_i e_iᵀ) y = b with b ⟂ ker C = span(1): summing the rows gives
        // s·y_i = 0, so y_i = 0 and C y = b exactly.
        let r = c.mul(&y);
        assert!(y[f.fixing[0]].abs() < 1e-10);
        let err: f64 = r.iter().zip(&b).map(|(a, b)| (a - b).abs()).sum();
        assert!(err < 1e-8, "{err}");
    }
}
