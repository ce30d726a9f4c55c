//! K = C + Aᵀ diag(w) A on one sparsity pattern, that of C + AᵀA, whatever
//! the weights: rows with w_j = 0 keep their entries as stored zeros. Every
//! K assembled here therefore shares one symbolic analysis of the sparse
//! Cholesky (the [`crate::linalg::cholesky`] cache), and assembling is a
//! copy of C's values plus, per weighted row j, its |a_j|² products added at
//! precomputed positions. Used by SSN's augmented KKT factor
//! C + A_JᵀΡA_J (docs/methods.md §7) and by the penalty method's subspace
//! correction C + A_JᵀA_J/ε (§4.4).

use crate::linalg::sparse::Csr;

/// The pattern of C + AᵀA, C's values, and for every row j of A the
/// positions in K's values of its products a_jk·a_jl.
pub struct AugPattern {
    k: Csr,
    base: Vec<f64>,
    rows: Vec<Vec<(usize, f64)>>,
}

impl AugPattern {
    /// The pattern of C + AᵀA (C n×n with sorted rows, A m×n); K's values
    /// start as C's.
    pub fn new(c: &Csr, a: &Csr) -> AugPattern {
        let n = c.nrows;
        // Columns that AᵀA adds to each row, merged row by row into C's
        // (sorted) pattern: O(nnz) with no global sort.
        let mut extra: Vec<Vec<usize>> = vec![vec![]; n];
        for j in 0..a.nrows {
            let (cols, _) = a.row(j);
            for &k in cols {
                extra[k].extend_from_slice(cols);
            }
        }
        let mut indptr = Vec::with_capacity(n + 1);
        let mut indices = Vec::with_capacity(c.nnz() + 4 * a.nnz());
        let mut data = Vec::with_capacity(c.nnz() + 4 * a.nnz());
        indptr.push(0);
        for (i, ex) in extra.iter_mut().enumerate() {
            let (cc, v) = c.row(i);
            ex.sort_unstable();
            ex.dedup();
            let (mut p, mut q) = (0, 0);
            while p < cc.len() || q < ex.len() {
                if q == ex.len() || (p < cc.len() && cc[p] <= ex[q]) {
                    if q < ex.len() && cc[p] == ex[q] {
                        q += 1;
                    }
                    indices.push(cc[p]);
                    data.push(v[p]);
                    p += 1;
                } else {
                    indices.push(ex[q]);
                    data.push(0.0);
                    q += 1;
                }
            }
            indptr.push(indices.len());
        }
        drop(extra);
        let k = Csr {
            nrows: n,
            ncols: n,
            indptr: indptr.into(),
            indices: indices.into(),
            data: data.into(),
        };
        let rows = (0..a.nrows)
            .map(|j| {
                let (cols, v) = a.row(j);
                let mut out = Vec::with_capacity(cols.len() * cols.len());
                for (&kk, &ak) in cols.iter().zip(v) {
                    let (kcols, _) = k.row(kk);
                    for (&l, &al) in cols.iter().zip(v) {
                        let pos = k.indptr[kk] + kcols.binary_search(&l).expect("in pattern");
                        out.push((pos, ak * al));
                    }
                }
                out
            })
            .collect();
        AugPattern {
            base: k.data.to_vec(),
            k,
            rows,
        }
    }

    /// K as last assembled (C's values before the first [`AugPattern::assemble`]).
    pub fn matrix(&self) -> &Csr {
        &self.k
    }

    /// K = C + Σ_{j ∈ rows} w_j a_jᵀa_j (`w` indexed by row of A; the rows
    /// are added in the order given).
    pub fn assemble(&mut self, rows: impl IntoIterator<Item = usize>, w: &[f64]) -> &Csr {
        self.k.data.copy_from_slice(&self.base);
        for j in rows {
            for &(pos, v) in &self.rows[j] {
                self.k.data[pos] += w[j] * v;
            }
        }
        &self.k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense (C + Aᵀ diag(w) A)_ij.
    fn dense(c: &Csr, a: &Csr, w: &[f64]) -> Vec<Vec<f64>> {
        let n = c.nrows;
        let mut k = vec![vec![0.0; n]; n];
        for (i, ki) in k.iter_mut().enumerate() {
            let (cols, v) = c.row(i);
            for (&j, &x) in cols.iter().zip(v) {
                ki[j] += x;
            }
        }
        for (j, &wj) in w.iter().enumerate() {
            let (cols, v) = a.row(j);
            for (&p, &ap) in cols.iter().zip(v) {
                for (&q, &aq) in cols.iter().zip(v) {
                    k[p][q] += wj * ap * aq;
                }
            }
        }
        k
    }

    #[test]
    fn matches_dense_sum_on_one_pattern() {
        // C tridiagonal 6×6, A with rows coupling distant unknowns.
        let n = 6;
        let mut t = vec![];
        for i in 0..n {
            t.push((i, i, 2.0 + i as f64));
            if i > 0 {
                t.push((i, i - 1, -1.0));
                t.push((i - 1, i, -1.0));
            }
        }
        let c = Csr::from_triplets(n, n, &t);
        let a = Csr::from_triplets(
            3,
            n,
            &[
                (0, 0, 1.0),
                (0, 4, -0.5),
                (1, 2, 0.3),
                (1, 5, 2.0),
                (2, 1, -1.5),
            ],
        );
        let mut p = AugPattern::new(&c, &a);
        let nnz = p.matrix().nnz();
        assert_eq!(
            p.matrix().data.iter().filter(|v| **v != 0.0).count(),
            c.nnz()
        );
        for (rows, w) in [
            (vec![0, 1, 2], vec![1.0, 2.0, 3.0]),
            (vec![1], vec![0.0, 7.0, 0.0]),
            (vec![], vec![0.0; 3]),
        ] {
            let k = p.assemble(rows, &w);
            assert_eq!(k.nnz(), nnz, "the pattern never changes");
            let kd = dense(&c, &a, &w);
            for (i, kdi) in kd.iter().enumerate() {
                let (cols, v) = k.row(i);
                let mut row = vec![0.0; n];
                for (&j, &x) in cols.iter().zip(v) {
                    row[j] = x;
                }
                for j in 0..n {
                    assert!((row[j] - kdi[j]).abs() <= 1e-14, "({i}, {j})");
                }
            }
        }
    }
}
