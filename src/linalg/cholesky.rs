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

use crate::linalg::ordering::{self, Ordering};
use crate::linalg::rotation::{Rotation, RowBorder};
use crate::linalg::sparse::Csr;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Mat, MatMut, Side};
use std::cell::{Cell, RefCell};

/// A factorization that failed: C not positive definite or a bad pattern,
/// or (`memory`) a factor that does not fit in the memory available.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{message}")]
pub struct FactorError {
    pub message: String,
    /// The failure is one of resources, not of the matrix: a method must
    /// not read it as "this matrix cannot be factored" and take another
    /// path, or the bits of an answer would depend on the machine's free
    /// memory. It ends the solve with the message.
    pub memory: bool,
}

impl FactorError {
    /// A failure of the matrix (not positive definite, a bad pattern).
    pub fn new(message: impl Into<String>) -> FactorError {
        FactorError {
            message: message.into(),
            memory: false,
        }
    }

    /// A factor that does not fit in memory.
    pub fn memory(message: impl Into<String>) -> FactorError {
        FactorError {
            message: message.into(),
            memory: true,
        }
    }
}
use std::sync::Arc;

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

/// The DOFs a bordered factor eliminates last (its trailing block of L is
/// read in place from the factor's values).
struct Border {
    /// Position of each DOF in the border (usize::MAX: not in it).
    pos: Vec<usize>,
    /// Size of the border.
    nb: usize,
}

impl Border {
    fn of(border: &[usize], n: usize) -> Border {
        let mut pos = vec![usize::MAX; n];
        for (k, &i) in border.iter().enumerate() {
            pos[i] = k;
        }
        Border {
            pos,
            nb: border.len(),
        }
    }
}

/// W ← L_bb⁻¹ W for the trailing nb×nb block of the factor (`w` has nb
/// rows): forward substitution over the trailing columns only, supernode by
/// supernode (dense triangular solve on the diagonal block, then the update
/// of the rows below), reading L where the factorization left it.
fn trailing_forward(s: &SymbolicCholesky<usize>, values: &[f64], w: &mut Mat<f64>, par: faer::Par) {
    let n = s.nrows();
    let nb = w.nrows();
    let off = n - nb;
    let m = w.ncols();
    match s.raw() {
        SymbolicCholeskyRaw::Simplicial(t) => {
            let (cp, ri) = (t.col_ptr(), t.row_idx());
            for j in off..n {
                let (k0, k1) = (cp[j], cp[j + 1]);
                // The diagonal comes first in each column of L.
                let d = values[k0];
                for c in 0..m {
                    let x = w[(j - off, c)] / d;
                    w[(j - off, c)] = x;
                    for k in k0 + 1..k1 {
                        w[(ri[k] - off, c)] -= values[k] * x;
                    }
                }
            }
        }
        SymbolicCholeskyRaw::Supernodal(t) => {
            let l = faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::new(t, values);
            let (b, e) = (t.supernode_begin(), t.supernode_end());
            let mut tmp = Mat::<f64>::zeros(0, 0);
            for sn in 0..t.n_supernodes() {
                if e[sn] <= off {
                    continue;
                }
                let node = l.supernode(sn);
                let (val, pattern) = (node.val(), node.pattern());
                let ncols = e[sn] - b[sn];
                // Columns of the supernode before the border have zero
                // right-hand sides (B touches the border only): skipped.
                let c0 = off.max(b[sn]) - b[sn];
                let (r0, r1) = (b[sn] + c0 - off, e[sn] - off);
                let diag = val.submatrix(c0, c0, ncols - c0, ncols - c0);
                faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                    diag,
                    w.as_mut().subrows_mut(r0, r1 - r0),
                    par,
                );
                if pattern.is_empty() {
                    continue;
                }
                let below = val.submatrix(ncols, c0, pattern.len(), ncols - c0);
                tmp.resize_with(pattern.len(), m, |_, _| 0.0);
                faer::linalg::matmul::matmul(
                    tmp.as_mut(),
                    faer::Accum::Replace,
                    below,
                    w.as_ref().subrows(r0, r1 - r0),
                    1.0,
                    par,
                );
                for c in 0..m {
                    for (p, &i) in pattern.iter().enumerate() {
                        w[(i - off, c)] -= tmp[(p, c)];
                    }
                }
            }
        }
    }
}

/// z ← L_zzᵀ⁻¹ z for the trailing block of the factor with as many rows
/// as `z` (the whole factor when z has n rows): backward substitution over
/// those columns only, supernode by supernode from the last.
fn trailing_backward(s: &SymbolicCholesky<usize>, values: &[f64], z: &mut [f64]) {
    let n = s.nrows();
    let off = n - z.len();
    match s.raw() {
        SymbolicCholeskyRaw::Simplicial(t) => {
            let (cp, ri) = (t.col_ptr(), t.row_idx());
            for j in (off..n).rev() {
                let (k0, k1) = (cp[j], cp[j + 1]);
                let mut acc = z[j - off];
                for k in k0 + 1..k1 {
                    acc -= values[k] * z[ri[k] - off];
                }
                z[j - off] = acc / values[k0];
            }
        }
        SymbolicCholeskyRaw::Supernodal(t) => {
            let l = faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::new(t, values);
            let (b, e) = (t.supernode_begin(), t.supernode_end());
            for sn in (0..t.n_supernodes()).rev() {
                if e[sn] <= off {
                    break;
                }
                let node = l.supernode(sn);
                let (val, pattern) = (node.val(), node.pattern());
                let ncols = e[sn] - b[sn];
                let c0 = off.max(b[sn]) - b[sn];
                let rows = ncols - c0;
                let r0 = b[sn] + c0 - off;
                // z_top −= L_belowᵀ z_pattern, then the diagonal block.
                let below = val.submatrix(ncols, c0, pattern.len(), rows);
                for c in 0..rows {
                    let col = below.col(c);
                    let mut acc = 0.0;
                    for (p, &i) in pattern.iter().enumerate() {
                        acc += col[p] * z[i - off];
                    }
                    z[r0 + c] -= acc;
                }
                let diag = val.submatrix(c0, c0, rows, rows);
                faer::linalg::triangular_solve::solve_upper_triangular_in_place(
                    diag.transpose(),
                    MatMut::from_column_major_slice_mut(&mut z[r0..r0 + rows], rows, 1),
                    faer::Par::Seq,
                );
            }
        }
    }
}

/// The first half of a solve on a bordered factor ([`Cholesky::forward`]).
pub struct Forward {
    /// L⁻¹P Tᵀb, in the factor's order.
    y: Vec<f64>,
}

/// How many symbolic analyses a [`Workspace`] keeps (C and C + AᵀA for ssn).
const SYMBOLIC_KEPT: usize = 2;

impl Cholesky {
    /// Factor C, regularised along `kernel` (may be empty), reusing nothing.
    pub fn new(c: &Csr, kernel: &[Vec<f64>]) -> Result<Cholesky, FactorError> {
        Workspace::new().cholesky(c, kernel)
    }
}

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
    /// Fixes faer's parallelism ([`super::fix_parallelism`]): the bits of
    /// every factor and solve are then the same on any number of cores.
    pub fn with_ordering(ordering: Ordering) -> Workspace {
        super::fix_parallelism();
        Workspace {
            ordering,
            last: RefCell::new(None),
            symbolic: RefCell::new(vec![]),
            numeric_reused: Cell::new(0),
            symbolic_reused: Cell::new(0),
            memory_limit: None,
        }
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
    ) -> Result<(Arc<SymbolicCholesky<usize>>, bool), FactorError> {
        let n = sym.nrows();
        let mut kept = self.symbolic.borrow_mut();
        if let Some(k) = kept.iter().position(|e| e.n == n && e.pattern == hp) {
            let e = kept.remove(k);
            let s = e.symbolic.clone();
            kept.insert(0, e);
            return Ok((s, true));
        }
        let fail = |e: faer::sparse::FaerError| match e {
            faer::sparse::FaerError::OutOfMemory => {
                FactorError::memory("out of memory for the symbolic analysis")
            }
            e => FactorError::new(format!("symbolic analysis: {e:?}")),
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
                    None => ordering::order(sym, o).map_err(FactorError::new)?,
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
    pub fn factor_cost(&self, c: &Csr) -> Result<FactorCost, FactorError> {
        let (sym, _) = lower_csc(c, &[]);
        let hp = pattern_hash(&sym);
        let (s, _) = self.symbolic_of(&sym, hp, None)?;
        Ok(cost_of(&s))
    }

    /// Factor C, regularised along `kernel` (may be empty), reusing the kept
    /// factor or symbolic analysis when the matrix or its pattern is the same.
    pub fn cholesky(&self, c: &Csr, kernel: &[Vec<f64>]) -> Result<Cholesky, FactorError> {
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
    ) -> Result<Cholesky, FactorError> {
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
    ) -> Result<Cholesky, FactorError> {
        let rot = (!rb.rotation.is_empty()).then_some(&rb.rotation);
        self.factor(c, kernel, Some(&rb.dofs), rot)
    }

    fn factor(
        &self,
        c: &Csr,
        kernel: &[Vec<f64>],
        border: Option<&[usize]>,
        rot: Option<&Arc<Rotation>>,
    ) -> Result<Cholesky, FactorError> {
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
        // Drop the kept factor before allocating a new one (peak memory).
        self.last.replace(None);
        let (symbolic, reused) = self.symbolic_of(&sym, hp, border)?;
        if reused {
            self.symbolic_reused.set(self.symbolic_reused.get() + 1);
        }
        let t_sym = t0.elapsed().as_secs_f64() - t_prep;
        let mat = SparseColMatRef::new(sym.as_ref(), &vals);
        let par = super::par();
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
        let mut mem = MemBuffer::try_new(scratch)
            .map_err(|_| FactorError::memory("out of memory for the numeric factorization"))?;
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
            .map_err(|e| {
                FactorError::new(format!(
                    "C is not positive definite ({e:?}); a body may be free to move without the kernel being known"
                ))
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

    /// Column r of (BT)_bᵀ for each row r of `b` as (border position,
    /// value), summed; None without a border or when B touches another DOF
    /// ([`Cholesky::border_inverse`]).
    fn border_columns(&self, b: &Csr) -> Option<Vec<Vec<(usize, f64)>>> {
        let border = self.llt.border.as_ref()?;
        let mut cols: Vec<Vec<(usize, f64)>> = Vec::with_capacity(b.nrows);
        for r in 0..b.nrows {
            let (idx, v) = b.row(r);
            let bt;
            let entries: Vec<(usize, f64)> = match &self.llt.rot {
                Some(rot) => {
                    bt = rot.row_of_bt(idx, v);
                    let big = bt.iter().fold(0.0f64, |m, e| m.max(e.1.abs()));
                    bt.iter()
                        .copied()
                        .filter(|&(k, a)| {
                            a.abs() > 1e-12 * big
                                || border.pos.get(k).is_some_and(|&p| p != usize::MAX)
                        })
                        .collect()
                }
                None => idx.iter().copied().zip(v.iter().copied()).collect(),
            };
            let mut col: Vec<(usize, f64)> = Vec::with_capacity(entries.len());
            for (k, a) in entries {
                let p = *border.pos.get(k)?;
                if p == usize::MAX {
                    return None;
                }
                match col.iter_mut().find(|e| e.0 == p) {
                    Some(e) => e.1 += a,
                    None => col.push((p, a)),
                }
            }
            cols.push(col);
        }
        Some(cols)
    }

    /// The first half of x = K⁻¹b on a bordered factor: y = L⁻¹P Tᵀb (P
    /// the ordering, T the rotation), None without a border. With it,
    /// [`Cholesky::border_product`] gives B K⁻¹b from the trailing block
    /// alone and [`Cholesky::finish`] gives K⁻¹(b − Bᵀλ) with one backward
    /// pass: one solve's work where a solve for K⁻¹b and another for the
    /// KKT answer took two (docs/methods.md §7).
    pub fn forward(&self, b: &[f64]) -> Option<Forward> {
        self.llt.border.as_ref()?;
        let mut x = b.to_vec();
        if let Some(r) = &self.llt.rot {
            r.apply_tt(&mut x);
        }
        let mut y = self.permute(&x);
        let s = &self.llt.symbolic;
        let values = &self.llt.values;
        match s.raw() {
            SymbolicCholeskyRaw::Supernodal(t) => {
                let par = super::par();
                let mut mem = MemBuffer::new(s.solve_in_place_scratch::<f64>(1, par));
                faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::new(t, values)
                    .l_solve_with_conj(
                        Conj::No,
                        MatMut::from_column_major_slice_mut(&mut y, self.n, 1),
                        par,
                        MemStack::new(&mut mem),
                    );
            }
            SymbolicCholeskyRaw::Simplicial(t) => {
                let (cp, ri) = (t.col_ptr(), t.row_idx());
                for j in 0..self.n {
                    let (k0, k1) = (cp[j], cp[j + 1]);
                    let xj = y[j] / values[k0];
                    y[j] = xj;
                    for k in k0 + 1..k1 {
                        y[ri[k]] -= values[k] * xj;
                    }
                }
            }
        }
        Some(Forward { y })
    }

    /// B K⁻¹b for the `b` of `f` and a B on the border: z_b = L_bb⁻ᵀ y_b
    /// is the border part of the rotated, ordered solution, and B T reads
    /// only it. None when B touches another DOF.
    pub fn border_product(&self, f: &Forward, b: &Csr) -> Option<Vec<f64>> {
        let cols = self.border_columns(b)?;
        let nb = self.llt.border.as_ref()?.nb;
        let off = self.n - nb;
        let mut z = f.y[off..].to_vec();
        trailing_backward(&self.llt.symbolic, &self.llt.values, &mut z);
        Some(
            cols.iter()
                .map(|col| col.iter().map(|&(p, a)| a * z[p]).sum())
                .collect(),
        )
    }

    /// x = K⁻¹(b − Bᵀλ) for the `b` of `f`: L⁻¹ of the border vector
    /// (BT)_bᵀλ touches the trailing block only, so y − [0; L_bb⁻¹(BT)_bᵀλ]
    /// then one backward pass. None when B touches another DOF.
    pub fn finish(&self, f: &Forward, b: &Csr, lam: &[f64]) -> Option<Vec<f64>> {
        let cols = self.border_columns(b)?;
        let nb = self.llt.border.as_ref()?.nb;
        let off = self.n - nb;
        let mut v = Mat::<f64>::zeros(nb, 1);
        for (col, &l) in cols.iter().zip(lam) {
            if l != 0.0 {
                for &(p, a) in col {
                    v[(p, 0)] += a * l;
                }
            }
        }
        let par = super::par();
        trailing_forward(&self.llt.symbolic, &self.llt.values, &mut v, par);
        let mut y = f.y.clone();
        for (i, yi) in y[off..].iter_mut().enumerate() {
            *yi -= v[(i, 0)];
        }
        let s = &self.llt.symbolic;
        let values = &self.llt.values;
        match s.raw() {
            SymbolicCholeskyRaw::Supernodal(t) => {
                let mut mem = MemBuffer::new(s.solve_in_place_scratch::<f64>(1, par));
                faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::new(t, values)
                    .l_transpose_solve_with_conj(
                        Conj::No,
                        MatMut::from_column_major_slice_mut(&mut y, self.n, 1),
                        par,
                        MemStack::new(&mut mem),
                    );
            }
            SymbolicCholeskyRaw::Simplicial(_) => {
                trailing_backward(s, values, &mut y);
            }
        }
        let mut x = self.unpermute(&y);
        if let Some(r) = &self.llt.rot {
            r.apply_t(&mut x);
        }
        Some(x)
    }

    /// x in the factor's order: x_new[i] = x[fwd[i]].
    fn permute(&self, x: &[f64]) -> Vec<f64> {
        match self.llt.symbolic.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| x[i]).collect(),
            None => x.to_vec(),
        }
    }

    /// The inverse of [`Cholesky::permute`].
    fn unpermute(&self, y: &[f64]) -> Vec<f64> {
        match self.llt.symbolic.perm() {
            Some(p) => p.arrays().1.iter().map(|&k| y[k]).collect(),
            None => y.to_vec(),
        }
    }

    /// H = B K⁻¹ Bᵀ (dense, rows × rows) for a B that touches only the
    /// border DOFs of a bordered factor: with K's rows and columns ordered
    /// interior then border, [K⁻¹]_bb is the inverse of the Schur complement
    /// L_bb L_bbᵀ, so H = WᵀW with W = L_bb⁻¹ B_bᵀ. None without a border or
    /// when B touches another DOF. On a rotated factor B is taken to BT,
    /// whose rotated rows touch their border unknown only (entries below
    /// 1e-12 of the row's largest, rounding of the reflection, are dropped).
    pub fn border_inverse(&self, b: &Csr) -> Option<Mat<f64>> {
        let nb = self.llt.border.as_ref()?.nb;
        let cols = self.border_columns(b)?;
        let par = super::par();
        let s = &self.llt.symbolic;
        let values = &self.llt.values;
        Some(match s.raw() {
            SymbolicCholeskyRaw::Supernodal(t) => border_gram(t, values, &cols, nb, par),
            SymbolicCholeskyRaw::Simplicial(_) => {
                let mut w = Mat::<f64>::zeros(nb, b.nrows);
                for (r, col) in cols.iter().enumerate() {
                    for &(p, a) in col {
                        w[(p, r)] += a;
                    }
                }
                trailing_forward(s, values, &mut w, par);
                let mut h = Mat::<f64>::zeros(b.nrows, b.nrows);
                faer::linalg::matmul::matmul(
                    h.as_mut(),
                    faer::Accum::Replace,
                    w.transpose(),
                    w.as_ref(),
                    1.0,
                    par,
                );
                h
            }
        })
    }
}

/// Columns of the forward substitution handled together in [`border_gram`]
/// (one triangular solve and one product per chunk).
const GRAM_CHUNK: usize = 64;

/// H = WᵀW, W = L_bb⁻¹ B_bᵀ, on a supernodal factor, touching only what is
/// structurally nonzero: a column of W is nonzero in a trailing supernode
/// only if B_bᵀ is, or a descendant updated it; within a supernode it is
/// zero above its first nonzero of B_bᵀ (lower-triangular solve). With the
/// bodies apart in the factor each body's border is its own supernode, and
/// a rotated row has one unknown in each of its two bodies, so a body's W is
/// triangular up to a permutation: the flops fall from nb²m + m²nb (dense
/// solve and product) to about a third of each body's nb_b³. `cols[r]` is
/// column r of B_bᵀ as (border position, value).
fn border_gram(
    t: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
    values: &[f64],
    cols: &[Vec<(usize, f64)>],
    nb: usize,
    par: faer::Par,
) -> Mat<f64> {
    let m = cols.len();
    let n = t.nrows();
    let off = n - nb;
    let l = faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::new(t, values);
    let (b, e) = (t.supernode_begin(), t.supernode_end());
    // The trailing supernodes, their first border position, and the
    // supernode of each border position.
    let sns: Vec<usize> = (0..t.n_supernodes()).filter(|&sn| e[sn] > off).collect();
    let start: Vec<usize> = sns.iter().map(|&sn| off.max(b[sn]) - off).collect();
    let mut sn_of = vec![0usize; nb];
    for (si, &sn) in sns.iter().enumerate() {
        for p in start[si]..e[sn] - off {
            sn_of[p] = si;
        }
    }
    // The parent of a supernode holds the first row of its pattern.
    let parent: Vec<Option<usize>> = sns
        .iter()
        .map(|&sn| l.supernode(sn).pattern().first().map(|&i| sn_of[i - off]))
        .collect();
    // Active columns of each supernode with their first nonzero row in it
    // (0 when a descendant's update reaches it).
    let ns = sns.len();
    let mut act: Vec<Vec<(usize, usize)>> = vec![vec![]; ns];
    let mut stamp = vec![usize::MAX; ns];
    let mut first = vec![0usize; ns];
    let mut touched: Vec<usize> = vec![];
    for (r, col) in cols.iter().enumerate() {
        touched.clear();
        for &(p, _) in col {
            let si = sn_of[p];
            let f = p - start[si];
            if stamp[si] != r {
                stamp[si] = r;
                first[si] = f;
                touched.push(si);
            } else {
                first[si] = first[si].min(f);
            }
        }
        let mut i = 0;
        while i < touched.len() {
            if let Some(pa) = parent[touched[i]] {
                if stamp[pa] != r {
                    stamp[pa] = r;
                    touched.push(pa);
                }
                first[pa] = 0;
            }
            i += 1;
        }
        for &si in &touched {
            act[si].push((first[si], r));
        }
    }
    // W accumulates B_bᵀ minus the updates of earlier supernodes.
    let mut w = Mat::<f64>::zeros(nb, m);
    for (r, col) in cols.iter().enumerate() {
        for &(p, a) in col {
            w[(p, r)] += a;
        }
    }
    let mut h = Mat::<f64>::zeros(m, m);
    for (si, &sn) in sns.iter().enumerate() {
        let a = &mut act[si];
        if a.is_empty() {
            continue;
        }
        a.sort_unstable();
        let k = a.len();
        let node = l.supernode(sn);
        let (val, pattern) = (node.val(), node.pattern());
        let ncols = e[sn] - b[sn];
        let c0 = off.max(b[sn]) - b[sn];
        let rows = ncols - c0;
        let r0 = start[si];
        let diag = val.submatrix(c0, c0, rows, rows);
        let below = val.submatrix(ncols, c0, pattern.len(), rows);
        let mut x = Mat::<f64>::zeros(rows, k);
        for (c, &(_, col)) in a.iter().enumerate() {
            x.col_mut(c).copy_from(w.col(col).subrows(r0, rows));
        }
        let mut g = Mat::<f64>::zeros(0, 0);
        let mut upd = Mat::<f64>::zeros(0, 0);
        for q0 in (0..k).step_by(GRAM_CHUNK) {
            let q1 = (q0 + GRAM_CHUNK).min(k);
            let f = a[q0].0;
            let h_rows = rows - f;
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                diag.submatrix(f, f, h_rows, h_rows),
                x.as_mut().submatrix_mut(f, q0, h_rows, q1 - q0),
                par,
            );
            // This chunk's rows of W are final: its part of H (local
            // columns up to its own; rows above f are zero in the chunk).
            g.resize_with(q1 - q0, q1, |_, _| 0.0);
            faer::linalg::matmul::matmul(
                g.as_mut(),
                faer::Accum::Replace,
                x.as_ref().submatrix(f, q0, h_rows, q1 - q0).transpose(),
                x.as_ref().submatrix(f, 0, h_rows, q1),
                1.0,
                par,
            );
            for i in q0..q1 {
                let hi = a[i].1;
                for j in 0..=i {
                    h[(hi, a[j].1)] += g[(i - q0, j)];
                }
            }
            if !pattern.is_empty() {
                upd.resize_with(pattern.len(), q1 - q0, |_, _| 0.0);
                faer::linalg::matmul::matmul(
                    upd.as_mut(),
                    faer::Accum::Replace,
                    below.subcols(f, h_rows),
                    x.as_ref().submatrix(f, q0, h_rows, q1 - q0),
                    1.0,
                    par,
                );
                for c in q0..q1 {
                    let col = a[c].1;
                    for (p, &i) in pattern.iter().enumerate() {
                        w[(i - off, col)] -= upd[(p, c - q0)];
                    }
                }
            }
        }
    }
    // Each pair landed in one triangle or the other (local order): sum.
    for j in 0..m {
        for i in j + 1..m {
            let v = h[(i, j)] + h[(j, i)];
            h[(i, j)] = v;
            h[(j, i)] = v;
        }
    }
    h
}

/// Refuse a numeric factor of `bytes` (values and scratch; `nnz` entries of
/// L) that exceeds the memory and swap the kernel reports available
/// (`/proc/meminfo`: MemAvailable + SwapFree; no check where that file is
/// missing). This decides only whether to start, never the bits of an
/// answer: a factor that cannot fit would be killed midway, and a refusal
/// ends the solve ([`FactorError::memory`]). `limit`: the workspace's own.
fn fits_in_memory(
    bytes: usize,
    nnz: usize,
    ordering: Ordering,
    limit: Option<u64>,
) -> Result<(), FactorError> {
    let machine = available_memory();
    // (bytes available, whether the user's limit is the tighter bound)
    let (avail, by_limit) = match (machine, limit) {
        (Some(a), Some(l)) if l < a => (l, true),
        (Some(a), _) => (a, false),
        (None, Some(l)) => (l, true),
        (None, None) => return Ok(()),
    };
    let what = if by_limit {
        "the limit set for the factors"
    } else {
        "the memory and swap available"
    };
    if (bytes as u64) <= avail {
        return Ok(());
    }
    let size = |b: u64| {
        let (v, unit) = match b {
            b if b >= 1 << 30 => (b as f64 / (1u64 << 30) as f64, "GiB"),
            b if b >= 1 << 20 => (b as f64 / (1u64 << 20) as f64, "MiB"),
            b if b >= 1 << 10 => (b as f64 / 1024.0, "KiB"),
            b => return format!("{b} bytes"),
        };
        format!("{v:.1} {unit}")
    };
    let hint = match ordering {
        Ordering::Amd => "try [solver] ordering = \"nested-dissection\" (about a quarter less fill on 2D meshes, docs/methods.md §3), method ssn with [solver] ssn_path = \"iterative\" (no factor, docs/methods.md §7.2), a coarser mesh or a larger machine",
        Ordering::NestedDissection => "try method ssn with [solver] ssn_path = \"iterative\" (no factor, docs/methods.md §7.2), a coarser mesh or a larger machine",
    };
    let hint = if by_limit {
        format!(
            "raise [solver] memory_limit, or {}",
            hint.trim_start_matches("try ")
        )
    } else {
        hint.to_string()
    };
    Err(FactorError::memory(format!(
        "the Cholesky factor ({} ordering, nnz(L) = {nnz}) needs {}, more than {what} ({}): {hint}",
        ordering.name(),
        size(bytes as u64),
        size(avail)
    )))
}

/// MemAvailable + SwapFree of `/proc/meminfo`, in bytes.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(name))?;
        let kb: u64 = line[name.len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()?;
        Some(kb * 1024)
    };
    Some(field("MemAvailable:")? + field("SwapFree:").unwrap_or(0))
}

/// The ordering of a bordered factor: `ordering` of the DOFs outside
/// `border` (their submatrix of the lower pattern `sym`), then `border` in
/// order. Returns (new → old, old → new).
fn bordered_order(
    sym: &SymbolicSparseColMat<usize>,
    border: &[usize],
    ordering: Ordering,
) -> Result<(Vec<usize>, Vec<usize>), FactorError> {
    let n = sym.nrows();
    let mut in_b = vec![false; n];
    for &i in border {
        if i >= n || in_b[i] {
            return Err(FactorError::new(format!(
                "bordered factor: border DOF {i} out of range or repeated"
            )));
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
    let (perm, _) = ordering::order(&sub, ordering).map_err(FactorError::new)?;
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
pub fn factor_cost(c: &Csr) -> Result<FactorCost, FactorError> {
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

    /// A 2D Laplacian on an nx×ny grid (5-point), Dirichlet on the left
    /// column unless `floating` (then singular, kernel = constants).
    fn lap2d(nx: usize, ny: usize, floating: bool) -> Csr {
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

    /// B K⁻¹ Bᵀ from the trailing block of a bordered factor equals the one
    /// from solves with the ordinary factor, for SPD and for semicoercive C
    /// (same springs), and the bordered factor solves as well as the other.
    #[test]
    fn a_factor_larger_than_the_memory_is_refused_before_it_starts() {
        let avail = available_memory().expect("/proc/meminfo on Linux");
        assert!(avail > 0);
        assert!(fits_in_memory(1 << 20, 1 << 17, Ordering::Amd, None).is_ok());
        assert!(fits_in_memory(1 << 20, 1 << 17, Ordering::Amd, Some(1 << 20)).is_ok());
        assert!(
            fits_in_memory(1 << 20, 1 << 17, Ordering::Amd, Some(1 << 19))
                .unwrap_err()
                .memory
        );
        let huge = (avail as usize).saturating_mul(2);
        let e = fits_in_memory(huge, huge / 8, Ordering::Amd, None).unwrap_err();
        assert!(e.memory);
        let e = e.message;
        assert!(
            e.contains("amd ordering") && e.contains("ordering = \"nested-dissection\""),
            "{e}"
        );
        let e = fits_in_memory(huge, huge / 8, Ordering::NestedDissection, None)
            .unwrap_err()
            .message;
        assert!(
            e.contains("coarser mesh") && !e.contains("ordering ="),
            "{e}"
        );
    }

    #[test]
    fn border_inverse_matches_solves() {
        // The small grid factors simplicially, the large one in supernodes;
        // the bordered factor under either ordering against AMD's plain one.
        for (ordering, floating, (nx, ny)) in [
            (Ordering::Amd, false, (12, 9)),
            (Ordering::Amd, true, (12, 9)),
            (Ordering::Amd, false, (300, 60)),
            (Ordering::Amd, true, (300, 60)),
            (Ordering::NestedDissection, false, (12, 9)),
            (Ordering::NestedDissection, true, (300, 60)),
            (Ordering::NestedDissection, false, (900, 150)),
        ] {
            let c = lap2d(nx, ny, floating);
            let n = nx * ny;
            let kernel = if floating { vec![vec![1.0; n]] } else { vec![] };
            // B: rows on the right column (weights as contact rows have).
            let right: Vec<usize> = (0..ny).map(|j| (nx - 1) * ny + j).collect();
            let mut tb = vec![];
            for (r, w) in right.windows(2).enumerate() {
                tb.push((r, w[0], 0.6));
                tb.push((r, w[1], -0.4 - 0.01 * r as f64));
            }
            let b = Csr::from_triplets(ny - 1, n, &tb);
            let mut border = right.clone();
            border.reverse(); // any order
            let ws = Workspace::with_ordering(ordering);
            let fb = ws.cholesky_bordered(&c, &kernel, &border).unwrap();
            let fp = Cholesky::new(&c, &kernel).unwrap();
            let supernodal = matches!(fb.llt.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_));
            // (nested dissection's fill makes faer pick simplicial storage
            // on the 300×60 grid too)
            assert_eq!(
                supernodal,
                nx > 20 && (ordering == Ordering::Amd || nx > 300),
                "{nx}×{ny} {ordering:?}"
            );
            assert_eq!(fb.fixing, fp.fixing);
            let h = fb.border_inverse(&b).unwrap();
            assert!(fp.border_inverse(&b).is_none(), "no border, no H");
            for j in 0..b.nrows {
                let mut aj = vec![0.0; n];
                let (cols, v) = b.row(j);
                for (&k, &a) in cols.iter().zip(v) {
                    aj[k] = a;
                }
                let z = fp.solve(&aj);
                let hj = b.mul(&z);
                for i in 0..b.nrows {
                    assert!(
                        (h[(i, j)] - hj[i]).abs() <= 1e-10 * hj[j].abs(),
                        "floating {floating}: H[{i},{j}] = {} vs {}",
                        h[(i, j)],
                        hj[i]
                    );
                }
            }
            let x: Vec<f64> = (0..n).map(|i| (0.3 * i as f64).sin()).collect();
            let rhs = fp.solve(&x);
            let rhs_b = fb.solve(&x);
            for (p, q) in rhs.iter().zip(&rhs_b) {
                assert!((p - q).abs() <= 1e-9 * (1.0 + p.abs()), "{p} vs {q}");
            }
            // The split solve: B K⁻¹x from the forward half and the
            // trailing block, K⁻¹(x − Bᵀλ) from one backward pass.
            let f = fb.forward(&x).unwrap();
            assert!(fp.forward(&x).is_none(), "no border, no split solve");
            let bx = fb.border_product(&f, &b).unwrap();
            for (p, q) in bx.iter().zip(b.mul(&rhs)) {
                assert!(
                    (p - q).abs() <= 1e-9 * (1.0 + q.abs()),
                    "B K⁻¹x: {p} vs {q}"
                );
            }
            let lam: Vec<f64> = (0..b.nrows).map(|i| 1.0 + (0.7 * i as f64).cos()).collect();
            let mut xl = x.clone();
            b.mul_t_add(&lam.iter().map(|l| -l).collect::<Vec<_>>(), &mut xl);
            let want = fp.solve(&xl);
            let got = fb.finish(&f, &b, &lam).unwrap();
            for (p, q) in got.iter().zip(&want) {
                assert!(
                    (p - q).abs() <= 1e-9 * (1.0 + q.abs()),
                    "K⁻¹(x − Bᵀλ): {p} vs {q}"
                );
            }
            // A row touching an interior DOF has no dense H.
            let inner = Csr::from_triplets(1, n, &[(0, 0, 1.0)]);
            assert!(fb.border_inverse(&inner).is_none());
            assert!(fb.border_product(&f, &inner).is_none());
            // The bordered analysis is kept apart from the plain one.
            let _ = ws.cholesky(&c, &kernel).unwrap();
            let again = ws.cholesky_bordered(&c, &kernel, &border).unwrap();
            assert!(again.border_inverse(&b).is_some());
            assert!(ws.cholesky_bordered(&c, &kernel, &[0, 0]).is_err());
        }
    }

    /// Two bodies apart in C (block diagonal) and rows coupling them, as
    /// rotated conforming rows do (one unknown in each body) and with three
    /// unknowns: the structured H ([`border_gram`]) equals the one from
    /// solves with the ordinary factor, over several trailing supernodes.
    #[test]
    fn border_gram_on_bodies_apart() {
        let (nx, ny) = (120, 120);
        let one = lap2d(nx, ny, false);
        let n1 = nx * ny;
        let mut t = vec![];
        for r in 0..n1 {
            let (cols, v) = one.row(r);
            for (&c, &x) in cols.iter().zip(v) {
                t.push((r, c, x));
                t.push((r + n1, c + n1, 2e4 * x));
            }
        }
        let n = 2 * n1;
        let c = Csr::from_triplets(n, n, &t);
        let right: Vec<usize> = (0..ny).map(|j| (nx - 1) * ny + j).collect();
        let left: Vec<usize> = (0..ny).map(|j| n1 + j).collect();
        let mut tb = vec![];
        for j in 0..ny {
            tb.push((j, right[j], 1.0 + 0.01 * j as f64));
            tb.push((j, left[ny - 1 - j], -0.5));
        }
        for j in 0..ny - 1 {
            tb.push((ny + j, right[j], 0.3));
            tb.push((ny + j, right[j + 1], 0.7));
            tb.push((ny + j, left[j], -1.0));
        }
        let b = Csr::from_triplets(2 * ny - 1, n, &tb);
        let border: Vec<usize> = left.iter().rev().chain(&right).copied().collect();
        let fb = Workspace::new()
            .cholesky_bordered(&c, &[], &border)
            .unwrap();
        let fp = Cholesky::new(&c, &[]).unwrap();
        let SymbolicCholeskyRaw::Supernodal(t) = fb.llt.symbolic.raw() else {
            panic!("expected a supernodal factor");
        };
        let off = n - border.len();
        let trailing = (0..t.n_supernodes())
            .filter(|&s| t.supernode_end()[s] > off)
            .count();
        assert!(trailing >= 2, "{trailing} trailing supernodes");
        let h = fb.border_inverse(&b).unwrap();
        let mut big = 0.0f64;
        let mut want = vec![];
        for j in 0..b.nrows {
            let mut aj = vec![0.0; n];
            let (cols, v) = b.row(j);
            for (&k, &a) in cols.iter().zip(v) {
                aj[k] = a;
            }
            let hj = b.mul(&fp.solve(&aj));
            big = hj.iter().fold(big, |m, x| m.max(x.abs()));
            want.push(hj);
        }
        for (j, hj) in want.iter().enumerate() {
            for (i, w) in hj.iter().enumerate() {
                assert!(
                    (h[(i, j)] - w).abs() <= 1e-10 * big,
                    "H[{i},{j}] = {} vs {w}",
                    h[(i, j)]
                );
                assert_eq!(h[(i, j)], h[(j, i)], "H symmetric to the bit");
            }
        }
    }
}
