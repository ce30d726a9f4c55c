//! A hierarchy kept for a changed operator (docs/methods.md §7.2, "The
//! hierarchy across working sets"): K' = K + Σ δ_j u_juⱼᵀ with sparse u_j
//! (a contact row entering or leaving K_J = C + A_JᵀΡA_J). The prolongators
//! stay; every level's operator becomes the Galerkin one of K' with them,
//! A'_{l+1} = A_{l+1} + Σ δ_j v_jv_jᵀ, v_j = P_lᵀ…P_0ᵀ u_j, added in place
//! (the patterns already hold these entries: K's pattern holds every row's
//! u_juⱼᵀ, and the coarse patterns are the structural Galerkin products).
//! The cycle stays symmetric positive definite, so CG may use it.

use super::coarse::Scratch;
use super::{inv_diagonal, Amg, AmgError, SeqChol};
use crate::linalg::sparse::Csr;

impl Amg {
    /// Make the hierarchy that of `k` (the fine operator it was built for
    /// plus `changes`: weight δ, columns and values of u) with the same
    /// prolongators. `k` must have the pattern of the fine operator.
    pub fn update(&mut self, k: &Csr, changes: &[(f64, &[usize], &[f64])]) -> Result<(), AmgError> {
        let bad = |what: &str| Err(AmgError::BadInput(format!("update: {what}")));
        if self.levels.is_empty() {
            return bad("a single-level hierarchy is refactored, not updated");
        }
        if k.nnz() != self.levels[0].a.nnz() || k.nrows != self.levels[0].a.nrows {
            return bad("K's pattern is not that of the hierarchy");
        }
        self.levels[0].a.data.copy_from_slice(&k.data);
        self.levels[0].inv_diag = inv_diagonal(k, 0)?;
        let nl = self.levels.len();
        let mut scratch = Scratch::default();
        for &(delta, cols, vals) in changes {
            let mut u: Vec<(usize, f64)> = cols.iter().copied().zip(vals.iter().copied()).collect();
            for l in 0..nl {
                // v = P_lᵀ u, columns sorted.
                let v = self.restrict_row_one(l, &u, &mut scratch);
                // A_{l+1} += δ v vᵀ.
                for &(i, vi) in &v {
                    let ok = if let Some(next) = self.levels.get_mut(l + 1) {
                        add_row32(&mut next.a, i, delta * vi, &v)
                    } else {
                        add_row(&mut self.coarse_a, i, delta * vi, &v)
                    };
                    if !ok {
                        return bad("an entry outside the coarse pattern");
                    }
                }
                u = v;
            }
        }
        for l in 1..nl {
            let lev = &mut self.levels[l];
            lev.inv_diag = (0..lev.a.nrows)
                .map(|i| {
                    let (c, v) = lev.a.row(i);
                    let d = v[c.partition_point(|&j| (j as usize) < i)];
                    if d > 0.0 && d.is_finite() {
                        Ok(1.0 / d)
                    } else {
                        Err(AmgError::NonPositiveDiagonal {
                            level: l,
                            row: i,
                            value: d,
                        })
                    }
                })
                .collect::<Result<_, _>>()?;
        }
        let nc = self.coarse_n;
        let mut dense = vec![0.0; nc * nc];
        for i in 0..nc {
            let (c, v) = self.coarse_a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                dense[i * nc + j] = x;
            }
        }
        self.coarse = SeqChol::new(&dense, nc).ok_or(AmgError::CoarseSingular { n: nc })?;
        Ok(())
    }
}

/// Row i of `a` += w·v (v's columns sorted, all in the row's pattern).
fn add_row32(a: &mut super::Mat32, i: usize, w: f64, v: &[(usize, f64)]) -> bool {
    let (s, e) = (a.indptr[i], a.indptr[i + 1]);
    for &(j, vj) in v {
        match a.indices[s..e].binary_search(&(j as u32)) {
            Ok(p) => a.data[s + p] += w * vj,
            Err(_) => return false,
        }
    }
    true
}

/// [`add_row32`] on a [`Csr`].
fn add_row(a: &mut Csr, i: usize, w: f64, v: &[(usize, f64)]) -> bool {
    let (s, e) = (a.indptr[i], a.indptr[i + 1]);
    for &(j, vj) in v {
        match a.indices[s..e].binary_search(&j) {
            Ok(p) => a.data[s + p] += w * vj,
            Err(_) => return false,
        }
    }
    true
}
