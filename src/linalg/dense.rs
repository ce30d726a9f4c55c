//! Small dense kernels (k × k, k = rigid modes or active rows of a block):
//! symmetric eigen-decomposition, SPD factor and solve ([`SpdFactor`]), LU
//! with partial pivoting, on faer. Hand-written: the packed LLᵀ with O(k²)
//! row append and delete ([`PackedChol`], ASM-E's face factor, docs/methods.md
//! §4.7; faer has no updatable factor in that form) and the row-major
//! in-place LLᵀ the dual methods keep their coarse factor in ([`chol_factor`]).
//!
//! Singularity is decided in one place for every LLᵀ: a pivot d_j = L_jj² at
//! or below [`PIVOT_REL`] times the original diagonal entry a_jj means the
//! matrix is singular to working precision (a dependent row, a rigid motion
//! left free); the factorisation then returns `None`/`false`, never a factor
//! with huge entries. Matrices are passed as row-major slices or faer views.

use crate::linalg::sparse::dot;
use faer::linalg::solvers::{Llt, PartialPivLu, Solve};
use faer::{ColMut, Mat, MatRef, Side};

/// Relative pivot threshold of every dense LLᵀ (module doc): a matrix with
/// κ up to about 1/PIVOT_REL is factored; a pivot at rounding level (≈ ε·κ
/// of the data it came from) is refused.
pub const PIVOT_REL: f64 = 1e-10;

/// Relative pivot threshold of [`Lu`]: |U_kk| ≤ LU_PIVOT_REL · max|W_ij|
/// means singular to working precision.
pub const LU_PIVOT_REL: f64 = 1e-13;

/// Symmetric eigen-decomposition of a small dense matrix (rows `a[i]`; the
/// lower triangle is read): (eigenvalues, unit eigenvectors as rows) on
/// faer's self-adjoint eigen-solver, in the convention of cyclic Jacobi
/// from the identity, which the FEM's rigid-mode basis (and `R.mtx`) was
/// built with: the k-th pair is the one whose eigenvector lies nearest the
/// k-th coordinate axis (greedy on |v_i|; ties within 1e-12 go to the lower
/// eigenvalue, then the lower axis), signed so that its k-th component is
/// positive. A diagonal matrix gives the identity.
/// Non-finite input gives NaN.
pub fn sym_eigen(a: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = a.len();
    let m = Mat::from_fn(n, n, |i, j| a[i][j]);
    let nan = || (vec![f64::NAN; n], vec![vec![f64::NAN; n]; n]);
    if !m.as_ref().is_all_finite() {
        return nan();
    }
    let Ok(e) = m.self_adjoint_eigen(Side::Lower) else {
        return nan();
    };
    let (s, u) = (e.S().column_vector(), e.U());
    // Greedy assignment of eigenvectors (columns c of U) to axes (rows i).
    let mut slot: Vec<Option<usize>> = vec![None; n];
    let mut used = vec![false; n];
    for _ in 0..n {
        let mut best: Option<(f64, usize, usize)> = None;
        for c in (0..n).filter(|&c| !used[c]) {
            for i in (0..n).filter(|&i| slot[i].is_none()) {
                let v = u[(i, c)].abs();
                if best.is_none_or(|(b, _, _)| v > b * (1.0 + 1e-12)) {
                    best = Some((v, c, i));
                }
            }
        }
        let (_, c, i) = best.expect("a free pair");
        used[c] = true;
        slot[i] = Some(c);
    }
    let mut vals = Vec::with_capacity(n);
    let mut vecs = Vec::with_capacity(n);
    for (k, c) in slot.into_iter().enumerate() {
        let c = c.expect("every axis assigned");
        let sign = if u[(k, c)] < 0.0 { -1.0 } else { 1.0 };
        vals.push(s[c]);
        vecs.push((0..n).map(|i| sign * u[(i, c)]).collect());
    }
    (vals, vecs)
}

/// LLᵀ factor of a dense SPD matrix (faer); matrices singular to working
/// precision are refused by the [`PIVOT_REL`] test.
#[derive(Debug)]
pub struct SpdFactor {
    llt: Llt<f64>,
}

impl SpdFactor {
    /// Factor the n×n SPD matrix `a` (the lower triangle is read); None if a
    /// pivot fails the [`PIVOT_REL`] test or anything is not finite.
    pub fn new(a: MatRef<'_, f64>) -> Option<SpdFactor> {
        let llt = a.llt(Side::Lower).ok()?;
        let l = llt.L();
        for j in 0..a.nrows() {
            let d = l[(j, j)] * l[(j, j)];
            if !(d.is_finite() && d > PIVOT_REL * a[(j, j)].abs()) {
                return None;
            }
        }
        if !l.is_all_finite() {
            return None;
        }
        Some(SpdFactor { llt })
    }

    /// [`SpdFactor::new`] of the row-major n×n slice `a`.
    pub fn from_row_major(a: &[f64], n: usize) -> Option<SpdFactor> {
        Self::new(MatRef::from_row_major_slice(a, n, n))
    }

    /// The factor L (lower triangular).
    pub fn l(&self) -> MatRef<'_, f64> {
        self.llt.L()
    }

    /// b ← L⁻¹ b
    pub fn forward_in_place(&self, b: &mut [f64]) {
        self.l()
            .solve_lower_triangular_in_place(ColMut::from_slice_mut(b));
    }

    /// b ← L⁻ᵀ b
    pub fn backward_in_place(&self, b: &mut [f64]) {
        self.l()
            .transpose()
            .solve_upper_triangular_in_place(ColMut::from_slice_mut(b));
    }

    /// B ← (LLᵀ)⁻¹ B for every column of B at once (one pass over L).
    pub fn solve_mat_in_place(&self, b: faer::MatMut<'_, f64>) {
        let mut b = b;
        self.l().solve_lower_triangular_in_place(b.as_mut());
        self.l()
            .transpose()
            .solve_upper_triangular_in_place(b.as_mut());
    }

    /// b ← (LLᵀ)⁻¹ b
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.forward_in_place(b);
        self.backward_in_place(b);
    }
}

/// Solve the small SPD system K x = b (row-major q×q); None if K fails the
/// [`PIVOT_REL`] test.
pub fn spd_solve(k: &[f64], q: usize, b: &[f64]) -> Option<Vec<f64>> {
    let f = SpdFactor::from_row_major(k, q)?;
    let mut x = b.to_vec();
    f.solve_in_place(&mut x);
    Some(x)
}

/// In-place LLᵀ of the row-major n×n SPD matrix `a` (the lower triangle
/// receives L), for callers that keep L in a row-major slice (the dual
/// methods' G̃ = L⁻¹G). False if a pivot fails the [`PIVOT_REL`] test or is
/// not finite. Hand-written, not faer: the dual methods' iteration counts
/// are tested for exact invariance under scaling of C and d
/// (`partial_kernel::scale_invariance`), and faer's triangular kernels round
/// differently (mprgp then took 40 iterations on one scaling, 39 on the other).
pub fn chol_factor(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let orig = a[j * n + j];
        let mut d = orig;
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !d.is_finite() || d <= PIVOT_REL * orig.abs() {
            return false;
        }
        let l = d.sqrt();
        a[j * n + j] = l;
        for i in j + 1..n {
            let mut v = a[i * n + j];
            for k in 0..j {
                v -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = v / l;
        }
    }
    true
}

/// b ← L⁻¹ b for the row-major factor of [`chol_factor`].
pub fn chol_forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut v = b[i];
        for k in 0..i {
            v -= l[i * n + k] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
}

/// b ← L⁻ᵀ b for the row-major factor of [`chol_factor`].
pub fn chol_backward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= l[k * n + i] * b[k];
        }
        b[i] = v / l[i * n + i];
    }
}

/// LU with partial pivoting of a small square matrix (faer), for systems
/// that may be indefinite (ssn's Woodbury capacitance).
#[derive(Debug)]
pub struct Lu {
    lu: PartialPivLu<f64>,
}

impl Lu {
    /// Factor the row-major n×n `w`; None if a pivot |U_kk| is at or below
    /// [`LU_PIVOT_REL`]·max|w_ij| (singular to working precision) or not finite.
    pub fn from_row_major(w: &[f64], n: usize) -> Option<Lu> {
        let m = MatRef::from_row_major_slice(w, n, n);
        if !m.is_all_finite() {
            return None;
        }
        let scale = w.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let lu = m.partial_piv_lu();
        let u = lu.U();
        if (0..n).any(|k| !(u[(k, k)].is_finite() && u[(k, k)].abs() > LU_PIVOT_REL * scale)) {
            return None;
        }
        Some(Lu { lu })
    }

    /// b ← W⁻¹ b
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.lu.solve_in_place(ColMut::from_slice_mut(b));
    }

    /// B ← W⁻¹ B for a block of right-hand sides (one blocked solve).
    pub fn solve_mat_in_place(&self, b: faer::MatMut<'_, f64>) {
        self.lu.solve_in_place(b);
    }
}

/// Dense lower Cholesky factor S = LLᵀ in packed rows (row i has i+1 entries),
/// with O(n²) append and delete of a row/column.
#[derive(Debug, Default, Clone)]
pub struct PackedChol {
    rows: Vec<Vec<f64>>,
}

impl PackedChol {
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Append a row/column: `col` = S[old, new] (length len()), `diag` = S[new, new].
    /// Returns false (and leaves the factor unchanged) if the new pivot fails
    /// the [`PIVOT_REL`] test (the new row depends on the old ones).
    pub fn push(&mut self, col: &[f64], diag: f64) -> bool {
        let n = self.len();
        debug_assert_eq!(col.len(), n);
        let mut w = Vec::with_capacity(n + 1);
        for i in 0..n {
            let r = &self.rows[i];
            let s: f64 = r[..i].iter().zip(&w).map(|(a, b)| a * b).sum();
            w.push((col[i] - s) / r[i]);
        }
        let d2 = diag - dot(&w, &w);
        if !(d2.is_finite() && d2 > PIVOT_REL * diag.abs()) {
            return false;
        }
        w.push(d2.sqrt());
        self.rows.push(w);
        true
    }

    /// Delete row/column `k` (Givens rotations restore the triangle).
    pub fn remove(&mut self, k: usize) {
        self.rows.remove(k);
        let n = self.rows.len();
        for i in k..n {
            // Row i (old row i+1) has a superdiagonal entry (i, i+1): rotate
            // columns i and i+1 of rows i..n to annihilate it.
            let a = self.rows[i][i];
            let b = self.rows[i][i + 1];
            let h = a.hypot(b);
            let (c, s) = if h > 0.0 { (a / h, b / h) } else { (1.0, 0.0) };
            for r in self.rows[i..].iter_mut() {
                let (x, y) = (r[i], r[i + 1]);
                r[i] = c * x + s * y;
                r[i + 1] = -s * x + c * y;
            }
            self.rows[i][i] = self.rows[i][i].abs();
            self.rows[i].truncate(i + 1);
        }
    }

    /// Solve S x = b in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.len();
        for i in 0..n {
            let r = &self.rows[i];
            let s: f64 = r[..i].iter().zip(&b[..i]).map(|(a, x)| a * x).sum();
            b[i] = (b[i] - s) / r[i];
        }
        for i in (0..n).rev() {
            let bi = b[i] / self.rows[i][i];
            b[i] = bi;
            for (bj, &l) in b[..i].iter_mut().zip(&self.rows[i][..i]) {
                *bj -= l * bi;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random numbers in [−1, 1) (LCG).
    fn rand(seed: u64, len: usize) -> Vec<f64> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        (0..len)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
            })
            .collect()
    }

    /// S = BᵀB + shift·I (row-major n×n), B random.
    fn spd(n: usize, seed: u64, shift: f64) -> Vec<f64> {
        let b = rand(seed, n * n);
        let mut s = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                s[i * n + j] = (0..n).map(|k| b[k * n + i] * b[k * n + j]).sum::<f64>()
                    + if i == j { shift } else { 0.0 };
            }
        }
        s
    }

    fn matvec(a: &[f64], n: usize, x: &[f64]) -> Vec<f64> {
        (0..n).map(|i| dot(&a[i * n..(i + 1) * n], x)).collect()
    }

    fn norm(v: &[f64]) -> f64 {
        dot(v, v).sqrt()
    }

    /// ‖A x − b‖ / (‖A‖_F ‖x‖ + ‖b‖)
    fn rel_residual(a: &[f64], n: usize, x: &[f64], b: &[f64]) -> f64 {
        let ax = matvec(a, n, x);
        let r: Vec<f64> = ax.iter().zip(b).map(|(p, q)| p - q).collect();
        norm(&r) / (norm(a) * norm(x) + norm(b))
    }

    /// (Moved from ssn's tests.)
    #[test]
    fn dense_cholesky() {
        let a0 = vec![4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let mut l = a0.clone();
        assert!(chol_factor(&mut l, 3));
        let mut b = vec![1.0, -2.0, 0.5];
        chol_forward(&l, 3, &mut b);
        chol_backward(&l, 3, &mut b);
        for i in 0..3 {
            let v: f64 = (0..3).map(|j| a0[i * 3 + j] * b[j]).sum();
            assert!((v - [1.0, -2.0, 0.5][i]).abs() < 1e-14);
        }
        let mut sing = vec![1.0, 1.0, 1.0, 1.0];
        assert!(!chol_factor(&mut sing, 2));
    }

    #[test]
    fn spd_solve_random() {
        for (n, seed) in [(1, 1), (3, 2), (8, 3), (40, 4), (150, 5)] {
            let a = spd(n, seed, 0.1);
            let b = rand(seed + 100, n);
            let x = spd_solve(&a, n, &b).expect("SPD");
            assert!(rel_residual(&a, n, &x, &b) <= 1e-12, "n = {n}");
            // The row-major in-place kernels agree.
            let mut l = a.clone();
            assert!(chol_factor(&mut l, n));
            let mut y = b.clone();
            chol_forward(&l, n, &mut y);
            chol_backward(&l, n, &mut y);
            assert!(rel_residual(&a, n, &y, &b) <= 1e-12, "n = {n}");
            // L Lᵀ = A
            let f = SpdFactor::from_row_major(&a, n).unwrap();
            let llt = f.l() * f.l().transpose();
            for i in 0..n {
                for j in 0..n {
                    assert!((llt[(i, j)] - a[i * n + j]).abs() <= 1e-12 * norm(&a));
                }
            }
        }
    }

    #[test]
    fn singular_and_semidefinite_are_refused() {
        // Rank one.
        assert!(spd_solve(&[1.0, 1.0, 1.0, 1.0], 2, &[1.0, 2.0]).is_none());
        let mut s = vec![1.0, 1.0, 1.0, 1.0];
        assert!(!chol_factor(&mut s, 2));
        // Semidefinite with a rounding-level pivot: BᵀB with B of rank n − 1.
        let n = 6;
        let mut b = rand(7, n * n);
        for j in 0..n {
            b[(n - 1) * n + j] = 0.0;
        }
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..n).map(|k| b[k * n + i] * b[k * n + j]).sum();
            }
        }
        assert!(SpdFactor::from_row_major(&a, n).is_none());
        // Indefinite, zero, NaN.
        assert!(spd_solve(&[1.0, 2.0, 2.0, 1.0], 2, &[1.0, 0.0]).is_none());
        assert!(spd_solve(&[0.0], 1, &[1.0]).is_none());
        assert!(spd_solve(&[f64::NAN], 1, &[1.0]).is_none());
        // Empty: nothing to solve.
        assert_eq!(spd_solve(&[], 0, &[]), Some(vec![]));
    }

    #[test]
    fn lu_solves_indefinite_and_refuses_singular() {
        for (n, seed) in [(1, 11), (4, 12), (30, 13)] {
            // Symmetric indefinite: S − 2·I with S ≈ BᵀB.
            let a = spd(n, seed, -2.0);
            let b = rand(seed + 1, n);
            let lu = Lu::from_row_major(&a, n).expect("nonsingular");
            let mut x = b.clone();
            lu.solve_in_place(&mut x);
            assert!(rel_residual(&a, n, &x, &b) <= 1e-12, "n = {n}");
        }
        assert!(Lu::from_row_major(&[1.0, 2.0, 2.0, 4.0], 2).is_none());
        assert!(Lu::from_row_major(&[0.0, 0.0, 0.0, 0.0], 2).is_none());
        assert!(Lu::from_row_major(&[f64::INFINITY], 1).is_none());
    }

    #[test]
    fn eigen_random_and_semidefinite() {
        for (n, seed) in [(1, 21), (2, 22), (3, 23), (9, 24)] {
            // BᵀB − I: indefinite; and a rank-deficient semidefinite one.
            for shift in [-1.0, 0.0] {
                let a = spd(n, seed, shift);
                let rows: Vec<Vec<f64>> = a.chunks(n).map(|r| r.to_vec()).collect();
                let (vals, vecs) = sym_eigen(&rows);
                let scale = norm(&a);
                for (k, v) in vecs.iter().enumerate() {
                    assert!(v[k] > 0.0, "k-th component positive");
                }
                for (l, v) in vals.iter().zip(&vecs) {
                    let av = matvec(&a, n, v);
                    let r: Vec<f64> = av.iter().zip(v).map(|(p, q)| p - l * q).collect();
                    assert!(norm(&r) <= 1e-12 * scale, "A v = λ v");
                }
                for (i, u) in vecs.iter().enumerate() {
                    for (j, v) in vecs.iter().enumerate() {
                        let e = if i == j { 1.0 } else { 0.0 };
                        assert!((dot(u, v) - e).abs() <= 1e-12, "orthonormal");
                    }
                }
            }
        }
        let a = [2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0];
        let rows: Vec<Vec<f64>> = a.chunks(3).map(|r| r.to_vec()).collect();
        let (vals, vecs) = sym_eigen(&rows);
        // The Jacobi convention: (1, −1)/√2 (λ = 1), (1, 1)/√2 (λ = 3), e_2 (λ = 0).
        let h = 0.5f64.sqrt();
        let want = [
            (1.0, [h, -h, 0.0]),
            (3.0, [h, h, 0.0]),
            (0.0, [0.0, 0.0, 1.0]),
        ];
        for (k, (l, v)) in want.iter().enumerate() {
            assert!((vals[k] - l).abs() < 1e-14, "{vals:?}");
            for i in 0..3 {
                assert!((vecs[k][i] - v[i]).abs() < 1e-14, "{vecs:?}");
            }
        }
        // A diagonal matrix: the identity, in place.
        let (vals, vecs) = sym_eigen(&[vec![5.0, 0.0], vec![0.0, -1.0]]);
        assert_eq!(vals, vec![5.0, -1.0]);
        assert_eq!(vecs, vec![vec![1.0, 0.0], vec![0.0, 1.0]]);
        let (vals, vecs) = sym_eigen(&[vec![f64::NAN]]);
        assert!(vals[0].is_nan() && vecs[0][0].is_nan());
    }

    #[test]
    fn packed_cholesky_random() {
        let n = 7;
        let s = spd(n, 31, 1.0);
        let mut idx: Vec<usize> = vec![];
        let mut f = PackedChol::default();
        for j in 0..n {
            let col: Vec<f64> = idx.iter().map(|&i| s[i * n + j]).collect();
            assert!(f.push(&col, s[j * n + j]));
            idx.push(j);
        }
        f.remove(2);
        idx.remove(2);
        f.remove(0);
        idx.remove(0);
        let col: Vec<f64> = idx.iter().map(|&i| s[i * n + 2]).collect();
        assert!(f.push(&col, s[2 * n + 2]));
        idx.push(2);
        let b: Vec<f64> = (0..idx.len()).map(|i| i as f64 - 1.5).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x);
        let q = idx.len();
        let sub: Vec<f64> = idx
            .iter()
            .flat_map(|&i| idx.iter().map(move |&j| (i, j)))
            .map(|(i, j)| s[i * n + j])
            .collect();
        assert!(rel_residual(&sub, q, &x, &b) <= 1e-12);
        // The same answer as the faer factor.
        let y = spd_solve(&sub, q, &b).unwrap();
        assert!(
            norm(&x.iter().zip(&y).map(|(a, b)| a - b).collect::<Vec<_>>()) <= 1e-12 * norm(&y)
        );
        // A dependent row is refused.
        let mut g = PackedChol::default();
        assert!(g.push(&[], 2.0));
        assert!(!g.push(&[2.0], 2.0));
        assert_eq!(g.len(), 1);
    }

    /// S = BᵀB + I with a deterministic B (moved from active_set's tests).
    fn spd_fixed(n: usize) -> Vec<f64> {
        let b: Vec<f64> = (0..n * n)
            .map(|i| ((i * 7 + 3) % 11) as f64 / 5.0 - 1.0)
            .collect();
        let mut s = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                s[i * n + j] = (0..n).map(|k| b[k * n + i] * b[k * n + j]).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
        }
        s
    }

    #[test]
    fn packed_cholesky_append_delete_solve() {
        let n = 7;
        let s = spd_fixed(n);
        let mut idx: Vec<usize> = vec![];
        let mut f = PackedChol::default();
        for j in 0..n {
            let col: Vec<f64> = idx.iter().map(|&i| s[i * n + j]).collect();
            assert!(f.push(&col, s[j * n + j]));
            idx.push(j);
        }
        f.remove(2);
        idx.remove(2);
        f.remove(0);
        idx.remove(0);
        let col: Vec<f64> = idx.iter().map(|&i| s[i * n + 2]).collect();
        assert!(f.push(&col, s[2 * n + 2]));
        idx.push(2);
        let b: Vec<f64> = (0..idx.len()).map(|i| i as f64 - 1.5).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x);
        for (a, &i) in idx.iter().enumerate() {
            let sx: f64 = idx.iter().zip(&x).map(|(&j, xj)| s[i * n + j] * xj).sum();
            assert!((sx - b[a]).abs() < 1e-10, "{sx} {}", b[a]);
        }
        // A dependent row is refused.
        let mut g = PackedChol::default();
        assert!(g.push(&[], 2.0));
        assert!(!g.push(&[2.0], 2.0));
        assert_eq!(g.len(), 1);
    }

    /// (Moved from active_set's tests, where it checked the Jacobi version.)
    #[test]
    fn jacobi_eigen() {
        let a = [2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0];
        let rows: Vec<Vec<f64>> = a.chunks(3).map(|r| r.to_vec()).collect();
        let (vals, vecs) = sym_eigen(&rows);
        let mut v = vals.clone();
        v.sort_by(f64::total_cmp);
        assert!((v[0]).abs() < 1e-14 && (v[1] - 1.0).abs() < 1e-12 && (v[2] - 3.0).abs() < 1e-12);
        for (l, x) in vals.iter().zip(&vecs) {
            for i in 0..3 {
                let ax: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
                assert!((ax - l * x[i]).abs() < 1e-12);
            }
        }
    }
}
