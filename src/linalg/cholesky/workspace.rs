//! Making factors: the [`Workspace`] that keeps the last factorization and
//! the latest symbolic analyses for reuse (module doc of
//! [`crate::linalg::cholesky`]), the orderings it asks for, and the lower
//! triangle handed to faer.

use super::border::Border;
use super::memory::fits_in_memory;
use super::{cost_of, fixing_dofs, Cholesky, Factor, FactorCost};
use crate::linalg::error::LinalgError;
use crate::linalg::ordering::{self, Ordering};
use crate::linalg::rotation::{Rotation, RowBorder};
use crate::linalg::sparse::Csr;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::Side;
use std::any::Any;
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::Arc;

/// How many symbolic analyses a [`Workspace`] keeps (C and C + AᵀA for ssn).
const SYMBOLIC_KEPT: usize = 2;

/// Factor reuse across solves: the last factorization and its symbolic
/// analysis (see the module doc). Owned by the caller — one per load-step
/// sequence, a fresh one per method in `compare` — and shared by reference;
/// single-threaded (interior mutability, not `Sync`).
pub struct Workspace {
    /// The fill-reducing ordering of every factor made here.
    ordering: Ordering,
    last: RefCell<Option<CacheEntry>>,
    /// The latest symbolic analyses (most recent first), by size and pattern.
    symbolic: RefCell<Vec<SymbolicEntry>>,
    numeric_reused: Cell<usize>,
    symbolic_reused: Cell<usize>,
    /// At most this many bytes for one numeric factor, below what the
    /// machine reports (`None`: the machine's figure alone).
    memory_limit: Option<u64>,
    /// What a method derived from the matrices alone, under the key of
    /// those matrices ([`matrix_key`]): the next solve of the same C and A
    /// (a load step) takes it instead of deriving it again.
    kept: RefCell<Option<(u64, Rc<dyn Any>)>>,
    /// How often [`Workspace::kept`] found data under its key.
    kept_found: Cell<usize>,
}

impl Default for Workspace {
    fn default() -> Workspace {
        Workspace::new()
    }
}

impl Workspace {
    pub fn new() -> Workspace {
        Workspace::with_ordering(Ordering::default())
    }

    /// A workspace whose factors use `ordering` (docs/methods.md §3).
    /// Fixes faer's parallelism ([`crate::linalg::fix_parallelism`]): the bits of
    /// every factor and solve are then the same on any number of cores.
    pub fn with_ordering(ordering: Ordering) -> Workspace {
        crate::linalg::fix_parallelism();
        Workspace {
            ordering,
            last: RefCell::new(None),
            symbolic: RefCell::new(vec![]),
            numeric_reused: Cell::new(0),
            symbolic_reused: Cell::new(0),
            memory_limit: None,
            kept: RefCell::new(None),
            kept_found: Cell::new(0),
        }
    }

    /// The data kept under `key` by [`Workspace::keep`], if it is a `T`.
    pub fn kept<T: Any>(&self, key: u64) -> Option<Rc<T>> {
        let kept = self.kept.borrow();
        let (k, v) = kept.as_ref()?;
        let found = (*k == key)
            .then(|| v.clone().downcast::<T>().ok())
            .flatten();
        if found.is_some() {
            self.kept_found.set(self.kept_found.get() + 1);
        }
        found
    }

    /// How often [`Workspace::kept`] found data under its key (the caller
    /// may still find it made from other matrices and drop it).
    pub fn kept_found(&self) -> usize {
        self.kept_found.get()
    }

    /// Keep `value` under `key` (one slot: what was kept before is dropped).
    pub fn keep<T: Any>(&self, key: u64, value: Rc<T>) {
        self.kept.replace(Some((key, value)));
    }

    pub fn ordering(&self) -> Ordering {
        self.ordering
    }

    /// The same workspace, its numeric factors limited to `bytes` (values
    /// and scratch) besides the machine's free memory: for a machine
    /// shared with other jobs, and for tests of the refusal.
    pub fn with_memory_limit(mut self, bytes: u64) -> Workspace {
        self.memory_limit = Some(bytes);
        self
    }

    /// Forget the kept factorization and symbolic analyses (frees their memory).
    pub fn clear(&self) {
        self.last.replace(None);
        self.symbolic.borrow_mut().clear();
        self.kept.replace(None);
    }

    /// How often this workspace reused a numeric factor and a symbolic analysis.
    pub fn reuse_counts(&self) -> (usize, usize) {
        (self.numeric_reused.get(), self.symbolic_reused.get())
    }

    /// The symbolic analysis of the lower pattern `sym` (key `hp`), kept or
    /// made and kept; true if it was kept. The ordering is the workspace's
    /// (AMD or nested dissection), or with a `border`, that ordering of the
    /// other DOFs followed by the border DOFs in order.
    fn symbolic_of(
        &self,
        sym: &SymbolicSparseColMat<usize>,
        hp: u64,
        border: Option<&[usize]>,
    ) -> Result<(Arc<SymbolicCholesky<usize>>, bool), LinalgError> {
        let n = sym.nrows();
        let mut kept = self.symbolic.borrow_mut();
        if let Some(k) = kept.iter().position(|e| e.n == n && e.pattern == hp) {
            let e = kept.remove(k);
            let s = e.symbolic.clone();
            kept.insert(0, e);
            return Ok((s, true));
        }
        let fail = |e: faer::sparse::FaerError| match e {
            faer::sparse::FaerError::OutOfMemory => LinalgError::OutOfMemory {
                stage: "symbolic analysis",
            },
            e => LinalgError::Symbolic(format!("{e:?}")),
        };
        let t0 = std::time::Instant::now();
        let s = match (border, self.ordering) {
            // faer's own AMD on the whole pattern (the plain factor of old).
            (None, Ordering::Amd) => factorize_symbolic_cholesky(
                sym.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            ),
            (border, o) => {
                let (fwd, inv) = match border {
                    None => ordering::order(sym, o)?,
                    Some(b) => bordered_order(sym, b, o)?,
                };
                log::debug!(
                    "Cholesky: {}{} ordering {:.3} s",
                    if border.is_some() { "bordered " } else { "" },
                    o.name(),
                    t0.elapsed().as_secs_f64()
                );
                factorize_symbolic_cholesky(
                    sym.as_ref(),
                    Side::Lower,
                    SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv, n)),
                    Default::default(),
                )
            }
        }
        .map_err(fail)?;
        let s = Arc::new(s);
        kept.insert(
            0,
            SymbolicEntry {
                n,
                pattern: hp,
                symbolic: s.clone(),
            },
        );
        kept.truncate(SYMBOLIC_KEPT);
        Ok((s, false))
    }

    /// [`FactorCost`] of the pattern of `c` from its symbolic analysis, which
    /// the workspace keeps: a later [`Workspace::cholesky`] of a matrix with
    /// this pattern does not repeat it.
    pub fn factor_cost(&self, c: &Csr) -> Result<FactorCost, LinalgError> {
        let (sym, _) = lower_csc(c, &[]);
        let hp = pattern_hash(&sym);
        let (s, _) = self.symbolic_of(&sym, hp, None)?;
        Ok(cost_of(&s))
    }

    /// Factor C, regularised along `kernel` (may be empty), reusing the kept
    /// factor or symbolic analysis when the matrix or its pattern is the same.
    pub fn cholesky(&self, c: &Csr, kernel: &[Vec<f64>]) -> Result<Cholesky, LinalgError> {
        self.factor(c, kernel, None, None)
    }

    /// [`Workspace::cholesky`] with the DOFs `border` (distinct, in range)
    /// eliminated last, in the order given: the trailing block of L is then
    /// the factor of the Schur complement of K on them, and
    /// [`Cholesky::border_inverse`] gives B K⁻¹ Bᵀ for any B that touches
    /// only border DOFs at dense cost (docs/methods.md §7). Worth it when the
    /// border is small against the factor (a dense |border|² block is added).
    pub fn cholesky_bordered(
        &self,
        c: &Csr,
        kernel: &[Vec<f64>],
        border: &[usize],
    ) -> Result<Cholesky, LinalgError> {
        self.factor(c, kernel, Some(border), None)
    }

    /// [`Workspace::cholesky_bordered`] on the border of rows `rb`: the
    /// factor is of TᵀKT with its rotation T, solves and
    /// [`Cholesky::border_inverse`] map back, so the result is used as the
    /// factor of K (docs/methods.md §7, "Rotated rows").
    pub fn cholesky_rows(
        &self,
        c: &Csr,
        kernel: &[Vec<f64>],
        rb: &RowBorder,
    ) -> Result<Cholesky, LinalgError> {
        let rot = (!rb.rotation.is_empty()).then_some(&rb.rotation);
        self.factor(c, kernel, Some(&rb.dofs), rot)
    }

    fn factor(
        &self,
        c: &Csr,
        kernel: &[Vec<f64>],
        border: Option<&[usize]>,
        rot: Option<&Arc<Rotation>>,
    ) -> Result<Cholesky, LinalgError> {
        let t0 = std::time::Instant::now();
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
        let (sym, vals) = match rot {
            None => lower_csc(c, &shift),
            Some(r) => {
                let mut extra = vec![0.0; c.nrows];
                for &(i, v) in &shift {
                    extra[i] += v;
                }
                let (cp, ri, vals) = r.lower_csc(c, &extra);
                let n = c.nrows;
                (SymbolicSparseColMat::new_checked(n, n, cp, None, ri), vals)
            }
        };
        // A bordered analysis is another ordering of the same pattern: keyed apart.
        let hp = match border {
            None => pattern_hash(&sym),
            Some(b) => hash_words(
                [pattern_hash(&sym), b.len() as u64]
                    .into_iter()
                    .chain(b.iter().map(|&i| i as u64)),
            ),
        };
        let hv = hash_words(
            vals.iter()
                .map(|v| v.to_bits())
                .chain(rot.into_iter().flat_map(|r| r.words())),
        );
        let hit = self
            .last
            .borrow()
            .as_ref()
            .filter(|e| e.n == c.nrows && e.pattern == hp && e.values == hv)
            .map(|e| e.llt.clone());
        if let Some(llt) = hit {
            self.numeric_reused.set(self.numeric_reused.get() + 1);
            return Ok(Cholesky {
                n: c.nrows,
                llt,
                fixing,
            });
        }
        let t_prep = t0.elapsed().as_secs_f64();
        // Drop the kept factor before allocating a new one (peak memory),
        // and what a method kept of it (`Workspace::keep`): a new factor
        // is another matrix's, and the kept data would hold the old one.
        self.last.replace(None);
        self.kept.replace(None);
        let (symbolic, reused) = self.symbolic_of(&sym, hp, border)?;
        if reused {
            self.symbolic_reused.set(self.symbolic_reused.get() + 1);
        }
        let t_sym = t0.elapsed().as_secs_f64() - t_prep;
        let mat = SparseColMatRef::new(sym.as_ref(), &vals);
        let par = crate::linalg::par();
        let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
        // The values are allocated lazily (calloc) and touched as the
        // factorization proceeds: without this check a factor that cannot
        // fit ends in the kernel's OOM killer, with no message, minutes in.
        fits_in_memory(
            8 * symbolic.len_val() + scratch.size_bytes(),
            symbolic.len_val(),
            self.ordering,
            self.memory_limit,
        )?;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut mem = MemBuffer::try_new(scratch).map_err(|_| LinalgError::OutOfMemory {
            stage: "numeric factorization",
        })?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                mat,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| LinalgError::NotPositiveDefinite {
                detail: format!("{e:?}"),
            })?;
        let border = border.map(|b| Border::of(b, c.nrows));
        let llt = Arc::new(Factor {
            symbolic,
            values,
            border,
            rot: rot.cloned(),
        });
        log::debug!(
            "Cholesky: n = {}, nnz(lower C) = {}, nnz(L) = {}, prepare {t_prep:.3} s, symbolic {t_sym:.3} s{}, numeric {:.3} s",
            c.nrows,
            vals.len(),
            llt.values.len(),
            if reused { " (reused)" } else { "" },
            t0.elapsed().as_secs_f64() - t_prep - t_sym
        );
        self.last.replace(Some(CacheEntry {
            n: c.nrows,
            pattern: hp,
            values: hv,
            llt: llt.clone(),
        }));
        Ok(Cholesky {
            n: c.nrows,
            llt,
            fixing,
        })
    }
}

/// The ordering of a bordered factor: `ordering` of the DOFs outside
/// `border` (their submatrix of the lower pattern `sym`), then `border` in
/// order. Returns (new → old, old → new).
fn bordered_order(
    sym: &SymbolicSparseColMat<usize>,
    border: &[usize],
    ordering: Ordering,
) -> Result<(Vec<usize>, Vec<usize>), LinalgError> {
    let n = sym.nrows();
    let mut in_b = vec![false; n];
    for &i in border {
        if i >= n || in_b[i] {
            return Err(LinalgError::BadBorder { dof: i });
        }
        in_b[i] = true;
    }
    let interior: Vec<usize> = (0..n).filter(|&i| !in_b[i]).collect();
    let mut new_of = vec![usize::MAX; n];
    for (k, &i) in interior.iter().enumerate() {
        new_of[i] = k;
    }
    let ni = interior.len();
    let (cp, ri) = (sym.col_ptr(), sym.row_idx());
    let mut col_ptr = Vec::with_capacity(ni + 1);
    let mut row_idx = vec![];
    col_ptr.push(0);
    for &j in &interior {
        for &i in &ri[cp[j]..cp[j + 1]] {
            if !in_b[i] {
                row_idx.push(new_of[i]);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let sub = SymbolicSparseColMat::new_checked(ni, ni, col_ptr, None, row_idx);
    let (perm, _) = ordering::order(&sub, ordering)?;
    let fwd: Vec<usize> = perm
        .iter()
        .map(|&k| interior[k])
        .chain(border.iter().copied())
        .collect();
    let mut inv = vec![0usize; n];
    for (k, &i) in fwd.iter().enumerate() {
        inv[i] = k;
    }
    Ok((fwd, inv))
}

/// The last factorization (see the module doc).
struct CacheEntry {
    n: usize,
    pattern: u64,
    values: u64,
    llt: Arc<Factor>,
}

/// A kept symbolic analysis.
struct SymbolicEntry {
    n: usize,
    pattern: u64,
    symbolic: Arc<SymbolicCholesky<usize>>,
}

/// A key for data derived from the matrices `mats` and the vectors `vecs`
/// alone ([`Workspace::keep`]): their sizes, patterns and value bits.
pub fn matrix_key(mats: &[&Csr], vecs: &[Vec<f64>]) -> u64 {
    let words =
        mats.iter()
            .flat_map(|c| {
                [c.nrows as u64, c.ncols as u64, c.data.len() as u64]
                    .into_iter()
                    .chain(c.indptr.iter().chain(&c.indices).map(|&i| i as u64))
                    .chain(c.data.iter().map(|v| v.to_bits()))
            })
            .chain(vecs.iter().flat_map(|v| {
                std::iter::once(v.len() as u64).chain(v.iter().map(|x| x.to_bits()))
            }));
    hash_words(words)
}

/// The hash of a lower CSC pattern.
fn pattern_hash(sym: &SymbolicSparseColMat<usize>) -> u64 {
    hash_words(sym.col_ptr().iter().chain(sym.row_idx()).map(|&v| v as u64))
}

/// A 64-bit hash of a word stream (multiply–rotate, as FxHash; collisions of
/// two different matrices of the same size are astronomically unlikely and
/// would give a wrong factor, so the pattern and the values are hashed apart
/// and the size is compared too).
fn hash_words(it: impl Iterator<Item = u64>) -> u64 {
    const K: u64 = 0x51_7c_c1_b7_27_22_0a_95;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut len = 0u64;
    for w in it {
        h = (h.rotate_left(5) ^ w).wrapping_mul(K);
        len += 1;
    }
    (h.rotate_left(5) ^ len).wrapping_mul(K)
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

#[cfg(test)]
mod tests {
    use super::super::factor_cost;
    use super::super::test_matrices::lap1d;
    use super::*;

    #[test]
    fn reuses_numeric_factor_and_symbolic_analysis() {
        let c = lap1d(40, true);
        let ws = Workspace::new();
        let reuse_counts = || ws.reuse_counts();
        let (n0, s0) = reuse_counts();
        let f1 = ws.cholesky(&c, &[]).unwrap();
        let f2 = ws.cholesky(&c, &[]).unwrap();
        assert!(Arc::ptr_eq(&f1.llt, &f2.llt));
        assert_eq!(reuse_counts(), (n0 + 1, s0));
        // Same pattern, other values: a new numeric factor on the old analysis.
        let mut c2 = c.clone();
        c2.data.iter_mut().for_each(|v| *v *= 3.0);
        let f3 = ws.cholesky(&c2, &[]).unwrap();
        assert_eq!(reuse_counts(), (n0 + 1, s0 + 1));
        let x: Vec<f64> = (0..40).map(|i| (i as f64).cos()).collect();
        let y = f3.solve(&c2.mul(&x));
        for (a, b) in x.iter().zip(&y) {
            assert!((a - b).abs() < 1e-9, "{a} {b}");
        }
        // The old factor is still valid after the cache moved on.
        let y = f1.solve(&c.mul(&x));
        assert!(x.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-9));
        // Another pattern: nothing reused.
        let f4 = ws.cholesky(&lap1d(41, true), &[]).unwrap();
        assert_eq!(reuse_counts(), (n0 + 1, s0 + 1));
        drop(f4);
        ws.clear();
        let _ = ws.cholesky(&c, &[]).unwrap();
        assert_eq!(reuse_counts(), (n0 + 1, s0 + 1));
        // A fresh factorization reuses nothing and shares no factor.
        let f5 = Cholesky::new(&c, &[]).unwrap();
        assert!(!Arc::ptr_eq(&f1.llt, &f5.llt));
        assert_eq!(reuse_counts(), (n0 + 1, s0 + 1));
    }

    /// A cost model's symbolic analyses are the factorizations' (ssn counts
    /// C and C + AᵀA, then factors one of them): two patterns are kept.
    #[test]
    fn factor_cost_shares_its_analysis_with_the_factorization() {
        let (a, b) = (lap1d(30, true), lap1d(31, true));
        let ws = Workspace::new();
        let ca = ws.factor_cost(&a).unwrap();
        let cb = ws.factor_cost(&b).unwrap();
        assert_eq!(ca, factor_cost(&a).unwrap());
        assert!(cb.nnz > ca.nnz && ca.nnz >= 30.0);
        let fa = ws.cholesky(&a, &[]).unwrap();
        let fb = ws.cholesky(&b, &[]).unwrap();
        assert_eq!(ws.reuse_counts(), (0, 2));
        let x: Vec<f64> = (0..31).map(|i| 1.0 + i as f64).collect();
        let y = fb.solve(&b.mul(&x));
        assert!(x.iter().zip(&y).all(|(p, q)| (p - q).abs() < 1e-9));
        let y = fa.solve(&a.mul(&x[..30]));
        assert!(x.iter().zip(&y).all(|(p, q)| (p - q).abs() < 1e-9));
        // A third pattern evicts the oldest analysis.
        let _ = ws.factor_cost(&lap1d(32, true)).unwrap();
        let _ = ws.factor_cost(&a).unwrap();
        let mut b2 = b.clone();
        b2.data.iter_mut().for_each(|v| *v *= 2.0);
        let _ = ws.cholesky(&b2, &[]).unwrap();
        assert_eq!(ws.reuse_counts(), (0, 2));
    }
}
