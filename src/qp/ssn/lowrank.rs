//! K_J⁻¹ from the factor of an earlier K' = C + A_{J'}ᵀΡA_{J'} when few rows
//! changed (docs/methods.md §7): K_J = K' + UᵀΣU (σ = +ρ_j entering, −ρ_j
//! leaving), Sherman–Morrison–Woodbury K_J⁻¹ = K'⁻¹ − Z W⁻¹ Zᵀ with
//! Z = K'⁻¹Uᵀ (n×r, columns cached per row) and the r×r capacitance
//! W = Σ⁻¹ + U Z, factored by LU with partial pivoting (indefinite when rows
//! leave; singular to working precision ⇒ refactor instead).

use super::BLOCK;
use crate::linalg::cholesky::Cholesky;
use crate::linalg::dense::Lu;
use crate::qp::QpProblem;
use std::collections::HashMap;
use std::rc::Rc;

/// Low-rank updates of K': at most this many changed rows, and at most
/// this many bytes for the n×r block K'⁻¹Uᵀ.
pub(super) const LOWRANK_MAX: usize = 256;
pub(super) const LOWRANK_BYTES: f64 = 1.0e9;

/// K_J = K' + UᵀΣU for the rows whose membership changed since K' was
/// factored (σ = +ρ_j entering, −ρ_j leaving): Sherman–Morrison–Woodbury,
/// K_J⁻¹ = K'⁻¹ − Z W⁻¹ Zᵀ with Z = K'⁻¹Uᵀ (n×r, kept) and the small
/// capacitance W = Σ⁻¹ + U Z (r×r, LU with partial pivoting; indefinite
/// when rows leave).
pub(super) struct LowRank {
    /// (row of A, σ/ρ ∈ {+1, −1}).
    pub(super) rows: Vec<(usize, f64)>,
    /// Columns of Z = K'⁻¹Uᵀ, shared with the cache of the current K'.
    z: Vec<Rc<Vec<f64>>>,
    /// LU of W.
    lu: Lu,
}

impl LowRank {
    /// The update for `rows`; columns K'⁻¹a_j missing from `cache` are
    /// computed (BLOCK per solve) and added. Returns the update and the
    /// number of new columns.
    pub(super) fn new(
        qp: &QpProblem,
        fac: &Cholesky,
        rows: Vec<(usize, f64)>,
        rho: &[f64],
        cache: &mut HashMap<usize, Rc<Vec<f64>>>,
    ) -> (Option<LowRank>, usize) {
        let n = qp.n();
        let missing: Vec<usize> = rows
            .iter()
            .map(|&(j, _)| j)
            .filter(|j| !cache.contains_key(j))
            .collect();
        let mut buf = vec![];
        for chunk in missing.chunks(BLOCK) {
            buf.clear();
            buf.resize(n * chunk.len(), 0.0);
            for (c, &j) in chunk.iter().enumerate() {
                let (cols, v) = qp.a.row(j);
                for (&k, &a) in cols.iter().zip(v) {
                    buf[c * n + k] = a;
                }
            }
            fac.solve_many_in_place(&mut buf, chunk.len());
            for (c, &j) in chunk.iter().enumerate() {
                cache.insert(j, Rc::new(buf[c * n..(c + 1) * n].to_vec()));
            }
        }
        let z: Vec<Rc<Vec<f64>>> = rows.iter().map(|(j, _)| cache[j].clone()).collect();
        (Self::with_columns(qp, rows, z, rho), missing.len())
    }

    fn with_columns(
        qp: &QpProblem,
        rows: Vec<(usize, f64)>,
        z: Vec<Rc<Vec<f64>>>,
        rho: &[f64],
    ) -> Option<LowRank> {
        let r = rows.len();
        // W = Σ⁻¹ + U Z
        let mut w = vec![0.0; r * r];
        for (a, &(ja, sa)) in rows.iter().enumerate() {
            for b in 0..r {
                w[a * r + b] = qp.a.row_dot(ja, &z[b]);
            }
            w[a * r + a] += sa / rho[ja];
        }
        // symmetrise, then LU with partial pivoting (None: K_J singular to
        // working precision, refactor instead)
        for a in 0..r {
            for b in 0..a {
                let v = 0.5 * (w[a * r + b] + w[b * r + a]);
                w[a * r + b] = v;
                w[b * r + a] = v;
            }
        }
        let lu = Lu::from_row_major(&w, r)?;
        Some(LowRank { rows, z, lu })
    }

    /// y ← y − Z W⁻¹ (U y), turning K'⁻¹b into K_J⁻¹b.
    pub(super) fn correct(&self, qp: &QpProblem, y: &mut [f64]) {
        let n = y.len();
        let uy: Vec<f64> = self.rows.iter().map(|&(j, _)| qp.a.row_dot(j, y)).collect();
        let mut t = uy;
        self.lu.solve_in_place(&mut t);
        debug_assert!(self.z.iter().all(|z| z.len() == n));
        for (c, &tc) in t.iter().enumerate() {
            if tc != 0.0 {
                for (yi, zi) in y.iter_mut().zip(self.z[c].iter()) {
                    *yi -= tc * zi;
                }
            }
        }
    }
}
