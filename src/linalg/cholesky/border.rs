//! Solves on a bordered factor, whose border DOFs are eliminated last:
//! the trailing block of L is then the factor of the Schur complement on
//! them, read in place (docs/methods.md §7).

use super::Cholesky;
use crate::linalg::sparse::Csr;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Conj, Mat, MatMut};

/// The DOFs a bordered factor eliminates last (its trailing block of L is
/// read in place from the factor's values).
pub(super) struct Border {
    /// Position of each DOF in the border (usize::MAX: not in it).
    pos: Vec<usize>,
    /// Size of the border.
    nb: usize,
}

impl Border {
    pub(super) fn of(border: &[usize], n: usize) -> Border {
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

impl Cholesky {
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
                let par = crate::linalg::par();
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
        let par = crate::linalg::par();
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
        let par = crate::linalg::par();
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
    // H accumulated row-major: a chunk adds along its rows of H, which
    // stay in cache (column-major, each add was a stride of m).
    let mut h = vec![0.0f64; m * m];
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
                let hrow = &mut h[a[i].1 * m..(a[i].1 + 1) * m];
                for (j, &(_, aj)) in a[..=i].iter().enumerate() {
                    hrow[aj] += g[(i - q0, j)];
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
    Mat::from_fn(m, m, |i, j| {
        if i == j {
            h[i * m + i]
        } else {
            let (i, j) = (i.max(j), i.min(j));
            h[i * m + j] + h[j * m + i]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_matrices::lap2d;
    use super::super::Workspace;
    use super::*;
    use crate::linalg::ordering::Ordering;

    /// B K⁻¹ Bᵀ from the trailing block of a bordered factor equals the one
    /// from solves with the ordinary factor, for SPD and for semicoercive C
    /// (same springs), and the bordered factor solves as well as the other.
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
