//! Compressed sparse row matrices: C (symmetric, both triangles stored, so a
//! row is a whole row for Gauss–Seidel) and A (rows accessed one at a time,
//! as the report's CSR of §3).

/// Below this many stored entries a product runs on one thread.
pub const PAR_MIN_NNZ: usize = 1 << 16;
/// Rows per parallel chunk of a product.
pub const PAR_ROWS: usize = 4096;

/// A real sparse matrix in CSR form with sorted, unique column indices.
/// A clone shares the arrays ([`Shared`]): the model of every load step
/// holds the prepared C without a copy (docs/methods.md §8.5).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Csr {
    pub nrows: usize,
    pub ncols: usize,
    pub indptr: Shared<usize>,
    pub indices: Shared<usize>,
    pub data: Shared<f64>,
}

impl Csr {
    /// Whether `other` is this matrix: the same arrays (the clones a load
    /// step's model shares), else equal sizes, pattern and values. What a
    /// workspace keeps for a matrix is reused only for the same one.
    pub fn same_as(&self, other: &Csr) -> bool {
        (self.nrows == other.nrows
            && self.ncols == other.ncols
            && self.indptr.ptr_eq(&other.indptr)
            && self.indices.ptr_eq(&other.indices)
            && self.data.ptr_eq(&other.data))
            || self == other
    }
}

/// A vector shared by its clones and copied on the first write through
/// one of them (`Arc::make_mut`): reads see a `Vec`, writes too.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Shared<T>(std::sync::Arc<Vec<T>>);

impl<T> From<Vec<T>> for Shared<T> {
    fn from(v: Vec<T>) -> Shared<T> {
        Shared(std::sync::Arc::new(v))
    }
}

impl<T> std::ops::Deref for Shared<T> {
    type Target = Vec<T>;
    fn deref(&self) -> &Vec<T> {
        &self.0
    }
}

impl<T: Clone> std::ops::DerefMut for Shared<T> {
    fn deref_mut(&mut self) -> &mut Vec<T> {
        std::sync::Arc::make_mut(&mut self.0)
    }
}

impl<'a, T> IntoIterator for &'a Shared<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

impl<T: PartialEq> PartialEq<Vec<T>> for Shared<T> {
    fn eq(&self, other: &Vec<T>) -> bool {
        *self.0 == *other
    }
}

impl<T: PartialEq> PartialEq<Shared<T>> for Vec<T> {
    fn eq(&self, other: &Shared<T>) -> bool {
        *self == *other.0
    }
}

impl<T> Shared<T> {
    /// Whether `self` and `other` hold the same array (not a copy).
    pub fn ptr_eq(&self, other: &Shared<T>) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

impl Csr {
    /// Connected components of the graph of a square matrix (C: its
    /// uncoupled diagonal blocks, the bodies): the component of every
    /// unknown, numbered in the order of their first unknown, and their
    /// count.
    pub fn components(&self) -> (Vec<usize>, usize) {
        let n = self.nrows;
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for i in 0..n {
            for &j in self.row(i).0 {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
        let mut id = vec![usize::MAX; n];
        let mut block = vec![0; n];
        let mut nb = 0;
        for i in 0..n {
            let r = root(&mut parent, i);
            if id[r] == usize::MAX {
                id[r] = nb;
                nb += 1;
            }
            block[i] = id[r];
        }
        (block, nb)
    }

    pub fn zeros(nrows: usize, ncols: usize) -> Csr {
        Csr {
            nrows,
            ncols,
            indptr: vec![0; nrows + 1].into(),
            indices: vec![].into(),
            data: vec![].into(),
        }
    }

    /// Build from (row, col, value) triplets; duplicates are summed, exact
    /// zeros kept (the pattern is what assembly produced).
    pub fn from_triplets(nrows: usize, ncols: usize, trip: &[(usize, usize, f64)]) -> Csr {
        let mut count = vec![0usize; nrows + 1];
        for &(i, _, _) in trip {
            count[i + 1] += 1;
        }
        for i in 0..nrows {
            count[i + 1] += count[i];
        }
        let mut pos = count.clone();
        let mut cols = vec![0usize; trip.len()];
        let mut vals = vec![0f64; trip.len()];
        for &(i, j, v) in trip {
            cols[pos[i]] = j;
            vals[pos[i]] = v;
            pos[i] += 1;
        }
        let mut indptr = Vec::with_capacity(nrows + 1);
        let mut indices = Vec::with_capacity(trip.len());
        let mut data = Vec::with_capacity(trip.len());
        indptr.push(0);
        let mut perm: Vec<usize> = Vec::new();
        for i in 0..nrows {
            let (s, e) = (count[i], count[i + 1]);
            perm.clear();
            perm.extend(s..e);
            perm.sort_unstable_by_key(|&k| cols[k]);
            let mut last = usize::MAX;
            for &k in &perm {
                if cols[k] == last {
                    if let Some(v) = data.last_mut() {
                        *v += vals[k];
                    }
                } else {
                    indices.push(cols[k]);
                    data.push(vals[k]);
                    last = cols[k];
                }
            }
            indptr.push(indices.len());
        }
        Csr {
            nrows,
            ncols,
            indptr: indptr.into(),
            indices: indices.into(),
            data: data.into(),
        }
    }

    pub fn nnz(&self) -> usize {
        self.data.len()
    }

    /// (column indices, values) of row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> (&[usize], &[f64]) {
        let (s, e) = (self.indptr[i], self.indptr[i + 1]);
        (&self.indices[s..e], &self.data[s..e])
    }

    /// y = M x
    /// y = M x. Rows are summed one by one in their stored order, in
    /// parallel chunks of rows when M is large: the same bits on any
    /// number of threads (a load step's certificate and refinement
    /// multiply by C several times).
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        let n = self.nrows.min(y.len());
        let row = |i: usize| -> f64 {
            let (c, v) = self.row(i);
            c.iter().zip(v).map(|(&j, &a)| a * x[j]).sum()
        };
        if self.nnz() < PAR_MIN_NNZ {
            for (i, yi) in y.iter_mut().enumerate().take(n) {
                *yi = row(i);
            }
            return;
        }
        y[..n]
            .par_chunks_mut(PAR_ROWS)
            .enumerate()
            .for_each(|(k, ys)| {
                for (o, yi) in ys.iter_mut().enumerate() {
                    *yi = row(k * PAR_ROWS + o);
                }
            });
    }

    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.nrows];
        self.mul_vec(x, &mut y);
        y
    }

    /// y += Mᵀ u
    pub fn mul_t_add(&self, u: &[f64], y: &mut [f64]) {
        for (i, &ui) in u.iter().enumerate().take(self.nrows) {
            if ui != 0.0 {
                let (c, v) = self.row(i);
                for (&j, &a) in c.iter().zip(v) {
                    y[j] += a * ui;
                }
            }
        }
    }

    pub fn mul_t(&self, u: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.ncols];
        self.mul_t_add(u, &mut y);
        y
    }

    /// (a_i, x)
    #[inline]
    pub fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        let (c, v) = self.row(i);
        c.iter().zip(v).map(|(&j, &a)| a * x[j]).sum()
    }

    /// Diagonal entries (0 where absent).
    pub fn diag(&self) -> Vec<f64> {
        (0..self.nrows)
            .map(|i| {
                let (c, v) = self.row(i);
                c.binary_search(&i).map(|k| v[k]).unwrap_or(0.0)
            })
            .collect()
    }

    pub fn transpose(&self) -> Csr {
        let mut trip = Vec::with_capacity(self.nnz());
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                trip.push((j, i, a));
            }
        }
        Csr::from_triplets(self.ncols, self.nrows, &trip)
    }

    /// Rows `rows` of the matrix, in that order.
    pub fn select_rows(&self, rows: &[usize]) -> Csr {
        let mut out = Csr::zeros(rows.len(), self.ncols);
        out.indptr.clear();
        out.indptr.push(0);
        for &r in rows {
            let (c, v) = self.row(r);
            out.indices.extend_from_slice(c);
            out.data.extend_from_slice(v);
            out.indptr.push(out.indices.len());
        }
        out
    }
}

#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
pub fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// y += α x
#[inline]
pub fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += alpha * xi;
    }
}

pub fn norm_inf(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triplets_sum_duplicates_and_sort() {
        let m = Csr::from_triplets(2, 3, &[(1, 2, 1.0), (0, 1, 2.0), (1, 0, 3.0), (1, 2, 4.0)]);
        assert_eq!(*m.indptr, vec![0, 1, 3]);
        assert_eq!(*m.indices, vec![1, 0, 2]);
        assert_eq!(*m.data, vec![2.0, 3.0, 5.0]);
        assert_eq!(m.mul(&[1.0, 1.0, 1.0]), vec![2.0, 8.0]);
        assert_eq!(m.mul_t(&[1.0, 2.0]), vec![6.0, 2.0, 10.0]);
        assert_eq!(m.transpose().transpose(), m);
    }
}
