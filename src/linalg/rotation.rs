//! The border of a bordered factor chosen from the rows of a constraint
//! matrix B, with the rows whose unknowns no other row touches rotated onto
//! one unknown each (docs/methods.md §7, "Rotated rows").
//!
//! A node-to-node row of a conforming pair touches four unknowns (two nodes ×
//! two components), and no other row touches them. Eliminating all four last
//! makes the dense trailing block of L (4m)² for m rows. A change of
//! variables x = T y on those four unknowns, T = S H with S = diag(c_kk)^{-1/2}
//! (so that a stiff and a soft body mix on equal terms) and H a Householder
//! reflection, turns the row into a multiple of one unknown: aᵀx = (Tᵀa)ᵀy =
//! −σ y_p. The factor is then of K' = TᵀKT with y_p in the border, and
//! K⁻¹ = T K'⁻¹ Tᵀ. One reflection per part of the row that C couples (a
//! node's two unknowns; the two bodies of a pair are not coupled): T then
//! mixes unknowns of one node only, K' has the pattern of C, and the border
//! is one unknown per node instead of two (2m for m node-to-node rows).
//! One reflection across both nodes would make it m but couple the bodies
//! in K': 18.4 M entries in L against 15.5 M at 178 k DOFs (BENCHMARKS.md).

use crate::linalg::cholesky::fixing_dofs;
use crate::linalg::sparse::Csr;
use std::sync::Arc;

/// At most this many unknowns per rotated row (the row's unknowns become a
/// dense clique of K'; a node-to-node row has 4).
const ROTATE_MAX: usize = 8;

/// "Not in a group" in [`Rotation::group_of`].
const NONE: u32 = u32::MAX;

/// The change of variables x = T y, block diagonal over disjoint groups of
/// unknowns (identity elsewhere): on group G, T_G = diag(s_G)(I − 2u_G u_Gᵀ).
#[derive(Debug, Clone, Default)]
pub struct Rotation {
    /// Group k is `dof[start[k]..start[k + 1]]` (and the same range of s, u).
    start: Vec<usize>,
    dof: Vec<usize>,
    /// c_kk^{-1/2} of each unknown of a group.
    s: Vec<f64>,
    /// The unit Householder vector of each group.
    u: Vec<f64>,
    /// Group of each unknown (NONE: not rotated); length n when non-empty.
    group_of: Vec<u32>,
}

/// The border of a bordered factor: the unknowns eliminated last (in the
/// rotated basis) and the rotation that made them few.
#[derive(Debug, Clone)]
pub struct RowBorder {
    /// Distinct; body by body (components of C), each ascending (docs/methods.md §7).
    pub dofs: Vec<usize>,
    pub rotation: Arc<Rotation>,
    /// Rows whose unknowns were rotated (one border unknown per part).
    rotated_rows: usize,
}

impl RowBorder {
    /// The border for the rows of `b` on the stiffness `c` (kernel: the basis
    /// of ker C whose fixing unknowns get springs, see
    /// [`crate::linalg::cholesky`]). A row is rotated when it has 2 to
    /// ROTATE_MAX unknowns, no other row of `b` touches them, none is a
    /// fixing unknown and each has c_kk > 0; it then adds one unknown to the
    /// border, the others all of theirs. Counts and values only: the same
    /// border on every run.
    pub fn new(c: &Csr, kernel: &[Vec<f64>], b: &Csr) -> RowBorder {
        let n = c.nrows;
        let mut count = vec![0u8; n];
        for &k in &b.indices {
            count[k] = count[k].saturating_add(1);
        }
        for k in fixing_dofs(kernel, n) {
            count[k] = u8::MAX;
        }
        let diag = c.diag();
        let mut dofs = vec![];
        let mut rotated_rows = 0;
        let mut rot = Rotation {
            start: vec![0],
            ..Rotation::default()
        };
        for r in 0..b.nrows {
            let (cols, v) = b.row(r);
            let private = (2..=ROTATE_MAX).contains(&cols.len())
                && cols.iter().all(|&k| count[k] == 1 && diag[k] > 0.0);
            if !private {
                dofs.extend_from_slice(cols);
                continue;
            }
            rotated_rows += 1;
            // One reflection per part of the row that C couples: on a
            // conforming pair the slave's and the master's unknowns, so that
            // T mixes unknowns of one node only, K' = TᵀKT has the pattern
            // of C and the bodies stay apart in the factor (a reflection
            // across both bodies coupled them: 42 % more fill at 178 k DOFs).
            for part in coupled_parts(c, cols) {
                let (pc, pv): (Vec<usize>, Vec<f64>) =
                    part.iter().map(|&i| (cols[i], v[i])).unzip();
                match reflection(&pc, &pv, &diag) {
                    Some((p, u)) => {
                        if pc.len() > 1 {
                            rot.dof.extend_from_slice(&pc);
                            rot.s.extend(pc.iter().map(|&k| 1.0 / diag[k].sqrt()));
                            rot.u.extend(u);
                            rot.start.push(rot.dof.len());
                        }
                        dofs.push(pc[p]);
                    }
                    None => dofs.extend_from_slice(&pc),
                }
            }
        }
        dofs.sort_unstable();
        dofs.dedup();
        group_by_body(c, &mut dofs);
        if rot.dof.is_empty() {
            rot = Rotation::default();
        } else {
            rot.group_of = vec![NONE; n];
            for g in 0..rot.start.len() - 1 {
                for &k in &rot.dof[rot.start[g]..rot.start[g + 1]] {
                    rot.group_of[k] = g as u32;
                }
            }
        }
        RowBorder {
            dofs,
            rotation: Arc::new(rot),
            rotated_rows,
        }
    }

    /// Size of the border.
    pub fn len(&self) -> usize {
        self.dofs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dofs.is_empty()
    }

    /// Rows rotated onto one unknown per part that C couples.
    pub fn rotated(&self) -> usize {
        self.rotated_rows
    }
}

/// Reorder the sorted border `dofs` so that the unknowns of each connected
/// component of C's pattern (a body, with its rotation, which mixes one
/// node's unknowns only) are consecutive, components in the order of their
/// first unknown, each in ascending order. The bodies are apart in K, so
/// the trailing block of L is then one dense diagonal block per body, each
/// a few wide supernodes; in DOF order the bodies' interface unknowns
/// alternate, every switch starts a supernode, and the stack of
/// BENCHMARKS.md (B = [A; T], a border of 2 982) had 1 022 supernodes of
/// three columns whose rank-3 updates made H memory-bound (5.7 s against
/// the factor's 4.5 s). A border already grouped keeps its order.
fn group_by_body(c: &Csr, dofs: &mut [usize]) {
    let (body, nb) = c.components();
    let mut rank: Vec<usize> = vec![usize::MAX; nb];
    let mut next = 0;
    let mut key: Vec<(usize, usize)> = Vec::with_capacity(dofs.len());
    for &k in dofs.iter() {
        let b = body[k];
        if rank[b] == usize::MAX {
            rank[b] = next;
            next += 1;
        }
        key.push((rank[b], k));
    }
    key.sort_unstable();
    for (d, (_, k)) in dofs.iter_mut().zip(key) {
        *d = k;
    }
}

/// The parts of a row's unknowns `cols` that the pattern of C couples
/// (connected components of C restricted to them), as positions in `cols`,
/// each sorted, in the order of their first position.
fn coupled_parts(c: &Csr, cols: &[usize]) -> Vec<Vec<usize>> {
    let k = cols.len();
    let mut part: Vec<usize> = (0..k).collect();
    for i in 0..k {
        let row = c.row(cols[i]).0;
        for j in i + 1..k {
            if row.binary_search(&cols[j]).is_ok() {
                let (pi, pj) = (part[i], part[j]);
                let (lo, hi) = (pi.min(pj), pi.max(pj));
                for q in part.iter_mut() {
                    if *q == hi {
                        *q = lo;
                    }
                }
            }
        }
    }
    let mut out: Vec<Vec<usize>> = vec![];
    let mut label: Vec<usize> = vec![];
    for (i, &q) in part.iter().enumerate() {
        match label.iter().position(|&l| l == q) {
            Some(t) => out[t].push(i),
            None => {
                label.push(q);
                out.push(vec![i]);
            }
        }
    }
    out
}

/// The Householder vector u (unit) and pivot p that map the scaled row
/// part ã = diag(c_kk)^{-1/2} a onto −σ e_p, σ = sign(ã_p)‖ã‖ at the largest
/// |ã_p| (no cancellation); `None` if ã is zero or not finite.
fn reflection(cols: &[usize], v: &[f64], diag: &[f64]) -> Option<(usize, Vec<f64>)> {
    let scaled: Vec<f64> = cols
        .iter()
        .zip(v)
        .map(|(&k, &a)| a / diag[k].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let norm = scaled.iter().map(|a| a * a).sum::<f64>().sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return None;
    }
    let p = (0..cols.len()).fold(0, |p, i| {
        if scaled[i].abs() > scaled[p].abs() {
            i
        } else {
            p
        }
    });
    let mut hv = scaled;
    hv[p] += norm.copysign(hv[p]);
    let hn = hv.iter().map(|a| a * a).sum::<f64>().sqrt();
    Some((p, hv.iter().map(|a| a / hn).collect()))
}

impl Rotation {
    pub fn is_empty(&self) -> bool {
        self.dof.is_empty()
    }

    fn groups(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    fn range(&self, g: usize) -> std::ops::Range<usize> {
        self.start[g]..self.start[g + 1]
    }

    /// The group of unknown k, if rotated.
    pub(crate) fn group(&self, k: usize) -> Option<usize> {
        match self.group_of.get(k) {
            Some(&g) if g != NONE => Some(g as usize),
            _ => None,
        }
    }

    /// x ← T x (from the rotated basis to the original one).
    pub fn apply_t(&self, x: &mut [f64]) {
        for g in 0..self.groups() {
            let r = self.range(g);
            let (dof, s, u) = (&self.dof[r.clone()], &self.s[r.clone()], &self.u[r]);
            let t: f64 = dof.iter().zip(u).map(|(&k, ui)| x[k] * ui).sum();
            for ((&k, si), ui) in dof.iter().zip(s).zip(u) {
                x[k] = si * (x[k] - 2.0 * t * ui);
            }
        }
    }

    /// x ← Tᵀ x (a right-hand side into the rotated basis).
    pub fn apply_tt(&self, x: &mut [f64]) {
        for g in 0..self.groups() {
            let r = self.range(g);
            let (dof, s, u) = (&self.dof[r.clone()], &self.s[r.clone()], &self.u[r]);
            let t: f64 = dof
                .iter()
                .zip(s)
                .zip(u)
                .map(|((&k, si), ui)| x[k] * si * ui)
                .sum();
            for ((&k, si), ui) in dof.iter().zip(s).zip(u) {
                x[k] = si * x[k] - 2.0 * t * ui;
            }
        }
    }

    /// The sparse row vector r ← r T, in place in (`acc`, `mark`, `touched`):
    /// every rotated group r touches is filled in and transformed.
    fn row_times_t(&self, acc: &mut [f64], mark: &mut [bool], touched: &mut Vec<usize>) {
        let mut seen: Vec<usize> = vec![];
        for &k in touched.iter() {
            if let Some(g) = self.group(k) {
                if !seen.contains(&g) {
                    seen.push(g);
                }
            }
        }
        for g in seen {
            let r = self.range(g);
            let (dof, s, u) = (&self.dof[r.clone()], &self.s[r.clone()], &self.u[r]);
            let mut t = 0.0;
            for ((&k, si), ui) in dof.iter().zip(s).zip(u) {
                if !mark[k] {
                    mark[k] = true;
                    acc[k] = 0.0;
                    touched.push(k);
                }
                acc[k] *= si;
                t += acc[k] * ui;
            }
            for (&k, ui) in dof.iter().zip(u) {
                acc[k] -= 2.0 * t * ui;
            }
        }
    }

    /// The entries of row `r` of B T (sorted by column).
    pub fn row_of_bt(&self, cols: &[usize], vals: &[f64]) -> Vec<(usize, f64)> {
        let mut out: Vec<(usize, f64)> = cols.iter().copied().zip(vals.iter().copied()).collect();
        let groups: Vec<usize> = {
            let mut g: Vec<usize> = cols.iter().filter_map(|&k| self.group(k)).collect();
            g.sort_unstable();
            g.dedup();
            g
        };
        for g in groups {
            let r = self.range(g);
            let (dof, s, u) = (&self.dof[r.clone()], &self.s[r.clone()], &self.u[r]);
            let w: Vec<f64> = dof
                .iter()
                .zip(s)
                .map(|(&k, si)| si * cols.iter().position(|&c| c == k).map_or(0.0, |p| vals[p]))
                .collect();
            let t: f64 = w.iter().zip(u).map(|(a, b)| a * b).sum();
            out.retain(|(k, _)| self.group(*k) != Some(g));
            out.extend(
                dof.iter()
                    .zip(&w)
                    .zip(u)
                    .map(|((&k, wi), ui)| (k, wi - 2.0 * t * ui)),
            );
        }
        out.sort_unstable_by_key(|e| e.0);
        out
    }

    /// The lower triangle of K' = Tᵀ(C + diag(extra))T in CSC: (col_ptr,
    /// row_idx, values). Column j of the lower triangle is row j of K' from
    /// the diagonal on (K' is symmetric); rows neither in a group nor
    /// touching one are copied, the others are formed in a sparse
    /// accumulator.
    pub(crate) fn lower_csc(&self, c: &Csr, extra: &[f64]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let n = c.nrows;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(c.nnz() / 2 + n);
        let mut vals = Vec::with_capacity(c.nnz() / 2 + n);
        let mut acc = vec![0.0; n];
        let mut mark = vec![false; n];
        let mut touched: Vec<usize> = vec![];
        // Rows in a group or with a column in one: the group's unknowns and
        // their neighbours (C is symmetric).
        let mut near = vec![false; n];
        for &k in &self.dof {
            near[k] = true;
            for &i in c.row(k).0 {
                near[i] = true;
            }
        }
        col_ptr.push(0);
        for j in 0..n {
            let (cols, v) = c.row(j);
            let plain = !near[j];
            if plain {
                let mut has_diag = false;
                for (&i, &a) in cols.iter().zip(v) {
                    if i >= j {
                        if !has_diag {
                            row_idx.push(j);
                            vals.push(extra[j] + if i == j { a } else { 0.0 });
                            has_diag = true;
                            if i == j {
                                continue;
                            }
                        }
                        row_idx.push(i);
                        vals.push(a);
                    }
                }
                if !has_diag {
                    row_idx.push(j);
                    vals.push(extra[j]);
                }
                col_ptr.push(row_idx.len());
                continue;
            }
            // Row j of TᵀK: Σ_b (T_G)_{b,a} K_{G_b,·} for j = G_a, else K_{j,·}.
            let add_row =
                |i: usize, w: f64, acc: &mut [f64], mark: &mut [bool], t: &mut Vec<usize>| {
                    let (cols, v) = c.row(i);
                    for (&k, &a) in cols.iter().zip(v) {
                        if !mark[k] {
                            mark[k] = true;
                            acc[k] = 0.0;
                            t.push(k);
                        }
                        acc[k] += w * a;
                    }
                    if extra[i] != 0.0 {
                        if !mark[i] {
                            mark[i] = true;
                            acc[i] = 0.0;
                            t.push(i);
                        }
                        acc[i] += w * extra[i];
                    }
                };
            match self.group(j) {
                Some(g) => {
                    let r = self.range(g);
                    let (dof, s, u) = (&self.dof[r.clone()], &self.s[r.clone()], &self.u[r]);
                    let a = dof.iter().position(|&k| k == j).expect("j in its group");
                    for (b, &k) in dof.iter().enumerate() {
                        let h = if a == b { 1.0 } else { 0.0 } - 2.0 * u[a] * u[b];
                        add_row(k, s[b] * h, &mut acc, &mut mark, &mut touched);
                    }
                }
                None => add_row(j, 1.0, &mut acc, &mut mark, &mut touched),
            }
            self.row_times_t(&mut acc, &mut mark, &mut touched);
            if !mark[j] {
                mark[j] = true;
                acc[j] = 0.0;
                touched.push(j);
            }
            touched.sort_unstable();
            for &i in &touched {
                if i >= j {
                    row_idx.push(i);
                    vals.push(acc[i]);
                }
                mark[i] = false;
            }
            touched.clear();
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx, vals)
    }

    /// Words for the factor cache's key (the rotation changes the values).
    pub(crate) fn words(&self) -> impl Iterator<Item = u64> + '_ {
        self.dof
            .iter()
            .map(|&k| k as u64)
            .chain(self.s.iter().chain(&self.u).map(|v| v.to_bits()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The border comes body by body: two chains whose unknowns alternate
    /// (evens one body, odds the other), tied by rows that no rotation
    /// takes (each shares unknowns), give the odds first (unknown 1 is the
    /// border's first), then the evens;
    /// a border already grouped keeps its order.
    #[test]
    fn border_is_grouped_by_body() {
        let n = 10;
        let mut t = vec![];
        for i in 0..n {
            t.push((i, i, 4.0));
            if i + 2 < n {
                t.extend([(i, i + 2, -1.0), (i + 2, i, -1.0)]);
            }
        }
        let c = Csr::from_triplets(n, n, &t);
        let rows: Vec<(usize, usize, f64)> = (0..4)
            .flat_map(|r| {
                [
                    (r, 2 * r + 1, 1.0),
                    (r, 2 * r + 2, -1.0),
                    (r, 2 * r + 3, 0.5),
                ]
            })
            .collect();
        let b = Csr::from_triplets(4, n, &rows);
        let rb = RowBorder::new(&c, &[], &b);
        assert_eq!(rb.dofs, vec![1, 3, 5, 7, 9, 2, 4, 6, 8]);
        // Unknowns 0–4 one body, 5–9 another: already grouped.
        let mut t2 = vec![];
        for i in 0..n {
            t2.push((i, i, 4.0));
            if i + 1 < n && i != 4 {
                t2.extend([(i, i + 1, -1.0), (i + 1, i, -1.0)]);
            }
        }
        let rb2 = RowBorder::new(&Csr::from_triplets(n, n, &t2), &[], &b);
        assert_eq!(rb2.dofs, vec![1, 2, 3, 4, 5, 6, 7, 8, 9]);
    }

    /// T is what its parts say: Tᵀa = −σe_p for the rotated row, apply_t and
    /// apply_tt are transposes, and lower_csc is the lower triangle of TᵀKT.
    #[test]
    fn rotation_is_consistent() {
        // A 6×6 SPD K with contrast 10⁶ between two "bodies" (0–2, 3–5).
        let n = 6;
        let mut t = vec![];
        for i in 0..n {
            let s = if i < 3 { 1e6 } else { 1.0 };
            t.push((i, i, 4.0 * s));
            if i % 3 != 2 {
                t.extend([(i, i + 1, -s), (i + 1, i, -s)]);
            }
        }
        let c = Csr::from_triplets(n, n, &t);
        // One private row (unknowns 1, 2, 3, 4: 1–2 in one body, 3–4 in the
        // other), one on 0 and 5 (shared with a third row on 5): only the
        // first is rotated, one reflection per body.
        let b = Csr::from_triplets(
            3,
            n,
            &[
                (0, 1, 0.6),
                (0, 2, -0.8),
                (0, 3, -0.6),
                (0, 4, 0.8),
                (1, 0, 1.0),
                (1, 5, -1.0),
                (2, 5, 1.0),
            ],
        );
        let rb = RowBorder::new(&c, &[], &b);
        assert_eq!(rb.rotated(), 1);
        assert_eq!(rb.len(), 4, "{:?}", rb.dofs);
        let rot = &rb.rotation;
        let (cols, v) = b.row(0);
        let bt = rot.row_of_bt(cols, v);
        let big: Vec<_> = bt.iter().filter(|e| e.1.abs() > 1e-12).collect();
        assert_eq!(big.len(), 2, "{bt:?}");
        assert!(big.iter().all(|e| rb.dofs.contains(&e.0)));
        assert!(
            (1..3).contains(&big[0].0) && (3..5).contains(&big[1].0),
            "{big:?}"
        );
        // A row whose unknowns C couples all together: one reflection, one
        // border unknown.
        let mut t2 = t.clone();
        t2.extend([(2, 3, -1.0), (3, 2, -1.0)]);
        let rb2 = RowBorder::new(&Csr::from_triplets(n, n, &t2), &[], &b);
        assert_eq!((rb2.rotated(), rb2.len()), (1, 3), "{:?}", rb2.dofs);
        // Dense T from apply_t on unit vectors; apply_tt must give Tᵀ.
        let mut tm = vec![vec![0.0; n]; n];
        let mut ttm = vec![vec![0.0; n]; n];
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let mut f = e.clone();
            rot.apply_t(&mut e);
            rot.apply_tt(&mut f);
            for i in 0..n {
                tm[i][j] = e[i];
                ttm[i][j] = f[i];
            }
        }
        for i in 0..n {
            for j in 0..n {
                assert!((tm[i][j] - ttm[j][i]).abs() < 1e-15);
            }
        }
        // K' = TᵀKT densely, against the lower CSC.
        let extra = vec![0.0, 0.0, 0.0, 0.0, 0.0, 2.5];
        let mut k = vec![vec![0.0; n]; n];
        for i in 0..n {
            let (cols, v) = c.row(i);
            for (&j, &a) in cols.iter().zip(v) {
                k[i][j] = a;
            }
            k[i][i] += extra[i];
        }
        let mut kp = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..n {
                for p in 0..n {
                    for q in 0..n {
                        kp[i][j] += tm[p][i] * k[p][q] * tm[q][j];
                    }
                }
            }
        }
        // T mixes unknowns of one body only: K' couples the bodies nowhere.
        for i in 3..n {
            for j in 0..3 {
                assert_eq!(kp[i][j], 0.0, "K'[{i},{j}]");
            }
        }
        let (cp, ri, vals) = rot.lower_csc(&c, &extra);
        let mut seen = vec![vec![false; n]; n];
        for j in 0..n {
            assert_eq!(ri[cp[j]], j, "diagonal first");
            for p in cp[j]..cp[j + 1] {
                let i = ri[p];
                assert!(i >= j);
                seen[i][j] = true;
                assert!((vals[p] - kp[i][j]).abs() < 1e-9 * (1.0 + kp[i][j].abs()));
            }
        }
        for i in 0..n {
            for j in 0..=i {
                assert!(
                    seen[i][j] || kp[i][j].abs() < 1e-12,
                    "K'[{i},{j}] = {}",
                    kp[i][j]
                );
            }
        }
        // The rotated block mixes a stiff and a soft body on equal terms:
        // S K S has unit diagonal and H is orthogonal, so its entries are O(1).
        for i in 1..5 {
            for j in 1..5 {
                assert!(kp[i][j].abs() <= 1.5, "K'[{i},{j}] = {}", kp[i][j]);
            }
        }
    }
}
