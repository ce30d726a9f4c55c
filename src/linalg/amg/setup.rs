//! The setup of the hierarchy (module doc of [`crate::linalg::amg`], steps
//! 1–5): strength of connection, aggregation, the tentative prolongator
//! and its smoothing, and the sparse products of the Galerkin operator.

use super::NONE;
use crate::linalg::sparse::{axpy, dot, norm, Csr};

/// Strong neighbours of every block as a CSR graph (blocks ascending) with
/// the normalised strength ‖K_IJ‖_F / sqrt(‖K_II‖_F ‖K_JJ‖_F) of each.
pub(super) fn strength(
    a: &Csr,
    bp: &[usize],
    block_of: &[usize],
    theta: f64,
) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let nb = bp.len() - 1;
    let mut dnorm = vec![0.0f64; nb];
    for (blk, w) in bp.windows(2).enumerate() {
        let mut s = 0.0;
        for i in w[0]..w[1] {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                if block_of[j] == blk {
                    s += x * x;
                }
            }
        }
        dnorm[blk] = s.sqrt();
    }
    let mut acc = vec![0.0f64; nb];
    let mut mark = vec![NONE; nb];
    let mut touched: Vec<usize> = Vec::new();
    let mut ptr = Vec::with_capacity(nb + 1);
    let mut idx = Vec::new();
    let mut val = Vec::new();
    ptr.push(0);
    for (blk, w) in bp.windows(2).enumerate() {
        touched.clear();
        for i in w[0]..w[1] {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                let jb = block_of[j];
                if jb == blk {
                    continue;
                }
                if mark[jb] != blk {
                    mark[jb] = blk;
                    acc[jb] = 0.0;
                    touched.push(jb);
                }
                acc[jb] += x * x;
            }
        }
        touched.sort_unstable();
        for &jb in &touched {
            let den = (dnorm[blk] * dnorm[jb]).sqrt();
            if den > 0.0 {
                let st = acc[jb].sqrt() / den;
                if st >= theta {
                    idx.push(jb);
                    val.push(st);
                }
            }
        }
        ptr.push(idx.len());
    }
    (ptr, idx, val)
}

/// Vaněk's three aggregation passes over the strength graph; returns the
/// aggregate of every block (NONE for empty blocks) and their count.
pub(super) fn aggregate(
    bp: &[usize],
    sp: &[usize],
    si: &[usize],
    sv: &[f64],
) -> (Vec<usize>, usize) {
    let nb = bp.len() - 1;
    let empty = |b: usize| bp[b] == bp[b + 1];
    let nbrs = |b: usize| &si[sp[b]..sp[b + 1]];
    let mut agg = vec![NONE; nb];
    let mut nagg = 0;
    // Pass 1: a block whose whole neighbourhood is free seeds an aggregate.
    for b in 0..nb {
        if empty(b) || agg[b] != NONE {
            continue;
        }
        if nbrs(b).iter().all(|&j| agg[j] == NONE) {
            agg[b] = nagg;
            for &j in nbrs(b) {
                agg[j] = nagg;
            }
            nagg += 1;
        }
    }
    // Pass 2: join the seed aggregate of the strongest neighbour (against
    // the pass-1 state, so aggregates do not creep along chains).
    let seeded = agg.clone();
    for b in 0..nb {
        if empty(b) || seeded[b] != NONE {
            continue;
        }
        let mut best: Option<(f64, usize)> = None;
        for k in sp[b]..sp[b + 1] {
            let j = si[k];
            if seeded[j] != NONE && best.is_none_or(|(s, _)| sv[k] > s) {
                best = Some((sv[k], seeded[j]));
            }
        }
        if let Some((_, a)) = best {
            agg[b] = a;
        }
    }
    // Pass 3: what is left groups with its still-free neighbours.
    for b in 0..nb {
        if empty(b) || agg[b] != NONE {
            continue;
        }
        agg[b] = nagg;
        for &j in nbrs(b) {
            if agg[j] == NONE {
                agg[j] = nagg;
            }
        }
        nagg += 1;
    }
    (agg, nagg)
}

/// The tentative prolongator T (n × n_c), the coarse block pointers (one
/// block per aggregate) and the coarse near-null modes R.
pub(super) fn tentative(
    a: &Csr,
    bp: &[usize],
    modes: &[Vec<f64>],
    theta: f64,
) -> (Csr, Vec<usize>, Vec<Vec<f64>>) {
    let n = a.nrows;
    let nm = modes.len();
    let mut block_of = vec![NONE; n];
    for (blk, w) in bp.windows(2).enumerate() {
        block_of[w[0]..w[1]].fill(blk);
    }
    let (sp, si, sv) = strength(a, bp, &block_of, theta);
    let (agg, nagg) = aggregate(bp, &sp, &si, &sv);
    drop((sp, si, sv));

    // Blocks of each aggregate, ascending.
    let mut mptr = vec![0usize; nagg + 1];
    for &g in agg.iter().filter(|&&g| g != NONE) {
        mptr[g + 1] += 1;
    }
    for g in 0..nagg {
        mptr[g + 1] += mptr[g];
    }
    let mut fill = mptr.clone();
    let mut members = vec![0usize; mptr[nagg]];
    for (blk, &g) in agg.iter().enumerate() {
        if g != NONE {
            members[fill[g]] = blk;
            fill[g] += 1;
        }
    }

    // QR per aggregate. T's row i holds the kept columns of its aggregate,
    // so T's pattern is known once every aggregate's rank is.
    let mut rows: Vec<usize> = Vec::new();
    let mut q: Vec<f64> = Vec::new();
    let mut r = vec![0.0f64; nm * nm];
    let mut kept_cols: Vec<usize> = Vec::new();
    let mut cptr = vec![0usize; nagg + 1];
    // T's row pointers need every aggregate's rank before any value goes
    // in, so Q (kept columns only, nnz(T) numbers) and R wait here.
    let mut q_store: Vec<f64> = Vec::new();
    let mut q_ptr = vec![0usize; nagg + 1];
    let mut r_store: Vec<f64> = Vec::new();
    for g in 0..nagg {
        rows.clear();
        for &blk in &members[mptr[g]..mptr[g + 1]] {
            rows.extend(bp[blk]..bp[blk + 1]);
        }
        let m = rows.len();
        q.clear();
        q.resize(m * nm, 0.0);
        for (c, mode) in modes.iter().enumerate() {
            for (l, &i) in rows.iter().enumerate() {
                q[c * m + l] = mode[i];
            }
        }
        let kept = mgs(&mut q, m, nm, &mut r, &mut kept_cols);
        cptr[g + 1] = cptr[g] + kept;
        for &c in &kept_cols {
            q_store.extend_from_slice(&q[c * m..(c + 1) * m]);
        }
        q_ptr[g + 1] = q_store.len();
        r_store.extend_from_slice(&r[..kept * nm]);
    }
    let nc = cptr[nagg];

    // T row by row.
    let mut indptr = vec![0usize; n + 1];
    for i in 0..n {
        let g = agg[block_of[i]];
        indptr[i + 1] = indptr[i] + if g == NONE { 0 } else { cptr[g + 1] - cptr[g] };
    }
    let nnz = indptr[n];
    let mut indices = vec![0usize; nnz];
    let mut data = vec![0.0f64; nnz];
    for g in 0..nagg {
        let kept = cptr[g + 1] - cptr[g];
        let qg = &q_store[q_ptr[g]..q_ptr[g + 1]];
        let m = qg.len().checked_div(kept).unwrap_or(0);
        let mut l = 0;
        for &blk in &members[mptr[g]..mptr[g + 1]] {
            for i in bp[blk]..bp[blk + 1] {
                for c in 0..kept {
                    indices[indptr[i] + c] = cptr[g] + c;
                    data[indptr[i] + c] = qg[c * m + l];
                }
                l += 1;
            }
        }
    }
    let t = Csr {
        nrows: n,
        ncols: nc,
        indptr: indptr.into(),
        indices: indices.into(),
        data: data.into(),
    };

    let mut cmodes = vec![vec![0.0f64; nc]; nm];
    for g in 0..nagg {
        let kept = cptr[g + 1] - cptr[g];
        let rg = &r_store[cptr[g] * nm..(cptr[g] + kept) * nm];
        for k in 0..kept {
            for (c, cm) in cmodes.iter_mut().enumerate() {
                cm[cptr[g] + k] = rg[k * nm + c];
            }
        }
    }
    (t, cptr, cmodes)
}

/// Thin QR of the m × nm column-major `q` by modified Gram–Schmidt, two
/// passes (one pass loses orthogonality on nearly dependent modes). A column
/// whose norm falls below 1e-10 of its original norm is dropped. On return
/// `kept` lists the surviving column slots of `q` (orthonormal) and `r`
/// holds the R rows (kept × nm, row-major) in the same order. Returns the
/// rank.
pub(super) fn mgs(
    q: &mut [f64],
    m: usize,
    nm: usize,
    r: &mut [f64],
    kept: &mut Vec<usize>,
) -> usize {
    kept.clear();
    r.fill(0.0);
    for c in 0..nm {
        let (before, this) = q.split_at_mut(c * m);
        let v = &mut this[..m];
        let n0 = norm(v);
        for _pass in 0..2 {
            for (k, &qc) in kept.iter().enumerate() {
                let qk = &before[qc * m..(qc + 1) * m];
                let h = dot(qk, v);
                axpy(-h, qk, v);
                r[k * nm + c] += h;
            }
        }
        let n1 = norm(v);
        if n0 == 0.0 || n1 == 0.0 || n1 < 1e-10 * n0 {
            continue;
        }
        for x in v.iter_mut() {
            *x /= n1;
        }
        r[kept.len() * nm + c] = n1;
        kept.push(c);
    }
    kept.len()
}

/// λ_max(D⁻¹A) by 15 power steps from the fixed start (1 + i mod 7); the
/// estimate is the Rayleigh quotient in the D inner product (D⁻¹A is
/// self-adjoint there), which lies below λ_max.
pub(super) fn lambda_max_dinv_k(a: &Csr, inv_d: &[f64]) -> f64 {
    let n = a.nrows;
    let mut v: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
    let mut w = vec![0.0; n];
    let mut lam = 0.0;
    for _ in 0..15 {
        a.mul_vec(&v, &mut w);
        // Rayleigh quotient (v, Av) / (v, Dv).
        let vav = dot(&v, &w);
        let vdv: f64 = v.iter().zip(inv_d).map(|(x, id)| x * x / id).sum();
        if vdv > 0.0 {
            lam = vav / vdv;
        }
        for (wi, id) in w.iter_mut().zip(inv_d) {
            *wi *= id;
        }
        let nw = norm(&w);
        if !(nw > 0.0) || !nw.is_finite() {
            break;
        }
        for (vi, wi) in v.iter_mut().zip(&w) {
            *vi = wi / nw;
        }
    }
    if lam > 0.0 && lam.is_finite() {
        lam
    } else {
        // No usable estimate (a degenerate start vector): λ_max(D⁻¹A) ≤ 2
        // holds for diagonally dominant A, a safe guess otherwise.
        2.0
    }
}

/// Dense accumulator for Gustavson products: one row at a time, the columns
/// touched kept in a list and sorted when the row is emitted.
pub(super) struct RowAcc {
    val: Vec<f64>,
    mark: Vec<usize>,
    cols: Vec<usize>,
}

impl RowAcc {
    fn new(ncols: usize) -> RowAcc {
        RowAcc {
            val: vec![0.0; ncols],
            mark: vec![NONE; ncols],
            cols: Vec::new(),
        }
    }

    /// acc += w · (row of B given as columns and values); `row` tags the
    /// current output row.
    #[inline]
    fn add(&mut self, row: usize, w: f64, c: &[usize], v: &[f64]) {
        for (&j, &x) in c.iter().zip(v) {
            if self.mark[j] != row {
                self.mark[j] = row;
                self.val[j] = 0.0;
                self.cols.push(j);
            }
            self.val[j] += w * x;
        }
    }

    /// Append the row (sorted) to `out` and clear the accumulator.
    fn emit(&mut self, out: &mut Csr) {
        self.cols.sort_unstable();
        for &j in &self.cols {
            out.indices.push(j);
            out.data.push(self.val[j]);
        }
        out.indptr.push(out.indices.len());
        self.cols.clear();
    }
}

/// P = (I − ω D⁻¹A) T in one Gustavson pass.
pub(super) fn smooth_prolongator(a: &Csr, inv_d: &[f64], t: &Csr, omega: f64) -> Csr {
    let mut out = Csr::zeros(a.nrows, t.ncols);
    out.indptr.truncate(1);
    let mut acc = RowAcc::new(t.ncols);
    for i in 0..a.nrows {
        let (tc, tv) = t.row(i);
        acc.add(i, 1.0, tc, tv);
        let w = -omega * inv_d[i];
        let (c, v) = a.row(i);
        for (&j, &aij) in c.iter().zip(v) {
            let (tc, tv) = t.row(j);
            acc.add(i, w * aij, tc, tv);
        }
        acc.emit(&mut out);
    }
    out
}

/// C = A B (Gustavson, columns sorted, nothing dropped).
pub(super) fn spgemm(a: &Csr, b: &Csr) -> Csr {
    let mut out = Csr::zeros(a.nrows, b.ncols);
    out.indptr.truncate(1);
    let mut acc = RowAcc::new(b.ncols);
    for i in 0..a.nrows {
        let (c, v) = a.row(i);
        for (&j, &aij) in c.iter().zip(v) {
            let (bc, bv) = b.row(j);
            acc.add(i, aij, bc, bv);
        }
        acc.emit(&mut out);
    }
    out
}

/// Mᵀ by a counting sort: O(nnz) without the triplet list of
/// [`Csr::transpose`] (which would be 24 bytes per entry of P); rows are
/// visited in order, so the columns come out sorted.
pub(super) fn transpose(m: &Csr) -> Csr {
    let mut indptr = vec![0usize; m.ncols + 1];
    for &j in &m.indices {
        indptr[j + 1] += 1;
    }
    for j in 0..m.ncols {
        indptr[j + 1] += indptr[j];
    }
    let mut next = indptr.clone();
    let mut indices = vec![0usize; m.nnz()];
    let mut data = vec![0.0f64; m.nnz()];
    for i in 0..m.nrows {
        let (c, v) = m.row(i);
        for (&j, &x) in c.iter().zip(v) {
            indices[next[j]] = i;
            data[next[j]] = x;
            next[j] += 1;
        }
    }
    Csr {
        nrows: m.ncols,
        ncols: m.nrows,
        indptr: indptr.into(),
        indices: indices.into(),
        data: data.into(),
    }
}
