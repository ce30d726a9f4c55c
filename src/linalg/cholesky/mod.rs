//! Sparse Cholesky factorization of C (faer, supernodal; AMD or nested
//! dissection, [`crate::linalg::ordering`]), with the symbolic analysis kept
//! for refactoring matrices of the same pattern.
//!
//! A semicoercive C (floating bodies) is singular. Given a basis R of ker C we
//! pick k "fixing" DOFs S (pivoted QR on Rᵀ, so R_S is nonsingular) and factor
//! C + Σ_{i∈S} c_ii eᵢeᵢᵀ, which is SPD. This regularised matrix serves as a
//! preconditioner; with the fixing DOFs' rows and columns removed instead it is the
//! classical fixing-node generalised inverse (Farhat–Géradin).
//!
//! **Reuse** is explicit: a [`Workspace`], owned by the caller and passed
//! down, keeps the last factorization keyed by hashes of the pattern and of
//! the values of the (shifted) lower triangle. The same matrix again (load
//! steps: C does not change between steps) reuses the numeric factor; the
//! same pattern with other values (penalty's C + A_JᵀA_J/ε on the fixed
//! pattern of C + AᵀA) reuses the symbolic analysis (ordering,
//! supernodes, elimination tree). [`Cholesky::new`] reuses nothing.
//!
//! The code is split by responsibility: `workspace` makes the factors
//! (caching, orderings, the factorization itself), `border` holds the
//! solves that read the trailing block of a bordered factor, and
//! `memory` refuses a factor that cannot fit before it starts.

mod border;
mod memory;
mod workspace;

pub use border::Forward;
pub use workspace::{matrix_key, Workspace};

use crate::linalg::error::LinalgError;
use crate::linalg::rotation::Rotation;
use crate::linalg::sparse::Csr;
use border::Border;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Conj, MatMut};
use std::sync::Arc;

/// A factor; a clone shares the values (load steps keep it, `qp::ssn`).
#[derive(Clone)]
pub struct Cholesky {
    n: usize,
    llt: Arc<Factor>,
    /// DOFs that received a spring (empty for SPD C).
    pub fixing: Vec<usize>,
}

/// A numeric factor: the symbolic analysis it was made on and the values of L.
struct Factor {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    border: Option<Border>,
    /// The factor is of TᵀKT (rotated rows, [`crate::linalg::rotation`]).
    rot: Option<Arc<Rotation>>,
}

impl Cholesky {
    /// Factor C, regularised along `kernel` (may be empty), reusing nothing.
    pub fn new(c: &Csr, kernel: &[Vec<f64>]) -> Result<Cholesky, LinalgError> {
        Workspace::new().cholesky(c, kernel)
    }
}

impl Cholesky {
    /// x ← (C + springs)⁻¹ x
    pub fn solve_in_place(&self, x: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n);
        self.solve_many_in_place(x, 1);
    }

    /// X ← (C + springs)⁻¹ X for the n×k column-major block `x`: one pass
    /// over the factor for all k columns (supernodal BLAS-3).
    pub fn solve_many_in_place(&self, x: &mut [f64], k: usize) {
        debug_assert_eq!(x.len(), self.n * k);
        if k == 0 {
            return;
        }
        let f = &self.llt;
        if let Some(r) = &f.rot {
            for col in x.chunks_mut(self.n) {
                r.apply_tt(col);
            }
        }
        let m = MatMut::from_column_major_slice_mut(x, self.n, k);
        let par = super::par();
        let mut mem = MemBuffer::new(f.symbolic.solve_in_place_scratch::<f64>(k, par));
        LltRef::new(&f.symbolic, &f.values).solve_in_place_with_conj(
            Conj::No,
            m,
            par,
            MemStack::new(&mut mem),
        );
        if let Some(r) = &f.rot {
            for col in x.chunks_mut(self.n) {
                r.apply_t(col);
            }
        }
    }

    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x);
        x
    }
}

/// What a sparse Cholesky factor of a pattern costs, counted before any
/// numeric work (the symbolic analysis on the same AMD ordering as
/// [`Cholesky::new`]): `nnz` = entries of L (one solve reads each twice),
/// `flops` = Σⱼ cⱼ² over the column counts cⱼ of L (the multiply–adds of
/// the numeric factorization, up to a constant). Used by cost models that
/// must not depend on wall-clock time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FactorCost {
    pub nnz: f64,
    pub flops: f64,
}

/// [`FactorCost`] of the lower triangle of the symmetric pattern `c` (values
/// ignored; a diagonal entry is assumed in every column, as in the factor).
pub fn factor_cost(c: &Csr) -> Result<FactorCost, LinalgError> {
    Workspace::new().factor_cost(c)
}

/// nnz(L) and Σⱼcⱼ² of a symbolic analysis.
fn cost_of(s: &SymbolicCholesky<usize>) -> FactorCost {
    let (mut nnz, mut flops) = (0.0f64, 0.0f64);
    match s.raw() {
        SymbolicCholeskyRaw::Simplicial(t) => {
            for w in t.col_ptr().windows(2) {
                let cj = (w[1] - w[0]) as f64;
                nnz += cj;
                flops += cj * cj;
            }
        }
        SymbolicCholeskyRaw::Supernodal(t) => {
            let (b, e) = (t.supernode_begin(), t.supernode_end());
            for sn in 0..t.n_supernodes() {
                let ncols = e[sn] - b[sn];
                let below = t.supernode(sn).pattern().len();
                for k in 0..ncols {
                    let cj = (ncols - k + below) as f64;
                    nnz += cj;
                    flops += cj * cj;
                }
            }
        }
    }
    FactorCost { nnz, flops }
}

/// k DOFs such that R restricted to them is nonsingular: columns of Rᵀ
/// chosen by pivoted Gram–Schmidt (largest remaining norm first).
pub fn fixing_dofs(kernel: &[Vec<f64>], n: usize) -> Vec<usize> {
    let k = kernel.len();
    if k == 0 {
        return vec![];
    }
    // rows[i·k..(i + 1)·k] = R[i, :], orthogonalised in place (one array:
    // n small vectors were n allocations, kept by the allocator after).
    let mut rows: Vec<f64> = (0..n)
        .flat_map(|i| kernel.iter().map(move |z| z[i]))
        .collect();
    let mut chosen = Vec::with_capacity(k);
    for _ in 0..k {
        let (best, bn) = rows
            .chunks_exact(k)
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
        let q: Vec<f64> = rows[best * k..(best + 1) * k]
            .iter()
            .map(|v| v / bn.sqrt())
            .collect();
        for r in rows.chunks_exact_mut(k) {
            let p: f64 = r.iter().zip(&q).map(|(a, b)| a * b).sum();
            for (a, b) in r.iter_mut().zip(&q) {
                *a -= p * b;
            }
        }
    }
    chosen
}

#[cfg(test)]
pub(super) mod test_matrices {
    use crate::linalg::sparse::Csr;

    /// A 1D Laplacian chain of `n` DOFs, grounded at DOF 0 when `dirichlet`.
    pub fn lap1d(n: usize, dirichlet: bool) -> Csr {
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

    /// A 2D Laplacian on an nx×ny grid (5-point), Dirichlet on the left
    /// column unless `floating` (then singular, kernel = constants).
    pub fn lap2d(nx: usize, ny: usize, floating: bool) -> Csr {
        let id = |i: usize, j: usize| i * ny + j;
        let mut t = vec![];
        for i in 0..nx {
            for j in 0..ny {
                for (a, b) in [(i + 1, j), (i, j + 1)] {
                    if a < nx && b < ny {
                        let (p, q) = (id(i, j), id(a, b));
                        t.extend([(p, p, 1.0), (q, q, 1.0), (p, q, -1.0), (q, p, -1.0)]);
                    }
                }
                if !floating && i == 0 {
                    t.push((id(i, j), id(i, j), 1.0));
                }
            }
        }
        Csr::from_triplets(nx * ny, nx * ny, &t)
    }
}

#[cfg(test)]
mod tests {
    use super::test_matrices::lap1d;
    use super::*;

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
