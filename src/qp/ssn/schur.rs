//! The KKT system of J by exact elimination on one sparse factor K of C
//! (C + springs at fixing DOFs when C is semicoercive: K⁻¹ is then a
//! generalised inverse on range C), docs/methods.md §7. The columns
//! hⱼ = A K⁻¹aⱼ are computed only for rows that enter J, [`BLOCK`] per
//! blocked solve, and cached (O(m·|J|) memory); S_J = A_J K⁻¹A_Jᵀ is formed
//! densely and factored (dense LLᵀ, O(|J|³)). With ker C = span R, as in
//! TFETI, x = K⁻¹(d − A_Jᵀλ_J) + Rα and the solvability condition
//! Rᵀ(d − A_Jᵀλ_J) = 0 joins A_J x = g_J; the coarse matrix
//! F = G_J S_J⁻¹ G_Jᵀ (G_J = RᵀA_Jᵀ) is singular iff J leaves a rigid
//! motion free. If the loads do no work on it the system is consistent and
//! α = F⁺(e − G_J w) (docs/methods.md §1.7, "free on the active rows");
//! otherwise the step returns None (the caller enlarges J).

use super::{Ssn, BLOCK};
use crate::linalg::dense::SpdFactor;
use crate::linalg::sparse::dot;
use faer::Mat;
use std::rc::Rc;

/// The last system [`Ssn::schur_dense`] solved and its answer (compared
/// by value: the same inputs give the same bits).
#[derive(Default)]
pub(super) struct DenseMemo {
    jset: Vec<usize>,
    ax0: Vec<f64>,
    e: Vec<f64>,
    gj: Vec<f64>,
    w: Vec<f64>,
    alpha: Vec<f64>,
}

impl Ssn<'_> {
    /// Compute the missing columns hⱼ, j ∈ `js`, BLOCK right-hand sides at a time.
    pub(super) fn columns(&mut self, js: &[usize]) {
        let n = self.qp.n();
        let missing: Vec<usize> = js
            .iter()
            .copied()
            .filter(|&j| self.h[j].is_none())
            .collect();
        let mut buf = vec![];
        for chunk in missing.chunks(BLOCK) {
            buf.clear();
            buf.resize(n * chunk.len(), 0.0);
            for (c, &j) in chunk.iter().enumerate() {
                let (cols, v) = self.qp.a.row(j);
                for (&k, &a) in cols.iter().zip(v) {
                    buf[c * n + k] = a;
                }
            }
            self.fac
                .as_ref()
                .expect("ensure_dense before columns")
                .solve_many_in_place(&mut buf, chunk.len());
            self.solves += chunk.len();
            for (c, &j) in chunk.iter().enumerate() {
                Rc::make_mut(&mut self.h)[j] = Some(self.qp.a.mul(&buf[c * n..(c + 1) * n]));
            }
        }
    }

    /// The multipliers of the KKT system of J = `jset` in the dual space
    /// alone, from the cached columns: λ_J = S_J⁻¹(A_J K⁻¹d − g_J + G_Jᵀα)
    /// and the coarse α (module doc), given `ax0` = A_J K⁻¹d and e = Rᵀd.
    /// None if S_J or the coarse matrix is singular. `exact`: S_J is
    /// factored itself; else S_J⁻¹ may come from the factor of S over every
    /// row when that is cheaper ([`SjSolver`]: the dual-space steps, which
    /// only choose J; such answers are not memorised).
    pub(super) fn schur_dense(
        &self,
        jset: &[usize],
        ax0: &[f64],
        e: &[f64],
        g: &[f64],
        exact: bool,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        // The Newton loop's first KKT solve repeats the dual-space steps'
        // last system (same J, same right-hand sides): answered from memory.
        let gj: Vec<f64> = jset.iter().map(|&j| g[j]).collect();
        let key = |m: &DenseMemo| m.jset == jset && m.ax0 == ax0 && m.e == e && m.gj == gj;
        if let Some(m) = self.dense_memo.borrow().as_ref().filter(|m| key(m)) {
            return Some((m.w.clone(), m.alpha.clone()));
        }
        let out = self.schur_dense_new(jset, ax0, e, g, exact);
        if let Some((w, alpha)) = &out {
            self.dense_memo.replace(Some(DenseMemo {
                jset: jset.to_vec(),
                ax0: ax0.to_vec(),
                e: e.to_vec(),
                gj,
                w: w.clone(),
                alpha: alpha.clone(),
            }));
        }
        out
    }

    /// [`Ssn::schur_dense`] without the memory.
    fn schur_dense_new(
        &self,
        jset: &[usize],
        ax0: &[f64],
        e: &[f64],
        g: &[f64],
        exact: bool,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let s = self.sj_solver(jset, exact)?;
        match self.schur_dense_with(&s, jset, ax0, e, g) {
            Ok(out) => out,
            // The complement's residual was refused: factor S_J.
            Err(Refused) => {
                let s = self.sj_solver(jset, true)?;
                self.schur_dense_with(&s, jset, ax0, e, g).ok().flatten()
            }
        }
    }

    /// The solver of S_J = A_J K⁻¹A_Jᵀ, by flop count (never by time);
    /// one made before for the same J and kind is taken from [`SjCache`].
    fn sj_solver(&self, jset: &[usize], exact: bool) -> Option<Rc<SjSolver>> {
        let m = self.qp.m();
        let nj = jset.len();
        let k = self.r.len();
        let cap = SJ_CACHE_FACTORS * m * m * 8;
        let full = self.s_full.borrow().clone();
        if let (false, Some(full)) = (exact, full) {
            let nn = m - nj;
            let (mf, njf, nnf) = (m as f64, nj as f64, nn as f64);
            // |N| + 1 + k solves with the full factor against one factor of S_J.
            if 2.0 * (nnf + 1.0 + k as f64) * mf * mf + nnf.powi(3) < njf.powi(3) / 3.0 {
                if let Some(c) = self.sj_cache.borrow().get(true, jset) {
                    return Some(c);
                }
                if let Some(c) = SjSolver::complement(full, jset, m) {
                    let c = Rc::new(c);
                    self.sj_cache.borrow_mut().put(true, jset, c.clone(), cap);
                    return Some(c);
                }
            }
        }
        let kept = self.sj_cache.borrow().get(false, jset);
        let (solver, s) = match kept {
            Some(solver) => match &*solver {
                SjSolver::Direct(s) => (solver.clone(), s.clone()),
                SjSolver::Complement { .. } => unreachable!("kept under the direct kind"),
            },
            None => {
                let hs: Vec<&Vec<f64>> = jset
                    .iter()
                    .map(|&j| self.h[j].as_ref().expect("column cached"))
                    .collect();
                // S_J (symmetrised; the lower triangle is read) and its factor.
                let s = Mat::from_fn(nj, nj, |a, b| {
                    if b <= a {
                        0.5 * (hs[b][jset[a]] + hs[a][jset[b]])
                    } else {
                        0.0
                    }
                });
                let s = Rc::new(SpdFactor::new(s.as_ref())?);
                let solver = Rc::new(SjSolver::Direct(s.clone()));
                self.sj_cache
                    .borrow_mut()
                    .put(false, jset, solver.clone(), cap);
                (solver, s)
            }
        };
        if nj == m && m > 0 {
            self.s_full.replace(Some(s));
        }
        Some(solver)
    }

    fn schur_dense_with(
        &self,
        s: &SjSolver,
        jset: &[usize],
        ax0: &[f64],
        e: &[f64],
        g: &[f64],
    ) -> Result<Option<DualAnswer>, Refused> {
        let k = self.r.len();
        let hs: Vec<&Vec<f64>> = jset
            .iter()
            .map(|&j| self.h[j].as_ref().expect("column cached"))
            .collect();
        // w = S⁻¹(A_J K⁻¹ d − g_J) and Y = S⁻¹ G_Jᵀ (columns 1..=k), one
        // multi-column solve.
        let nj = jset.len();
        let mut rhs = Mat::from_fn(nj, 1 + k, |t, c| {
            if c == 0 {
                ax0[t] - g[jset[t]]
            } else {
                self.ar[jset[t]][c - 1]
            }
        });
        s.solve_mat_in_place(rhs.as_mut(), &hs, jset)?;
        let mut w: Vec<f64> = rhs.col(0).iter().copied().collect();
        let mut alpha = vec![0.0; k];
        if k > 0 {
            // F = G_J Y.
            let y: Vec<Vec<f64>> = (1..=k)
                .map(|c| rhs.col(c).iter().copied().collect())
                .collect();
            let mut f = vec![0.0; k * k];
            for a in 0..k {
                for b in 0..k {
                    let v: f64 = jset
                        .iter()
                        .enumerate()
                        .map(|(t, &j)| self.ar[j][a] * y[b][t])
                        .sum();
                    f[a * k + b] = v;
                }
            }
            for a in 0..k {
                for b in 0..a {
                    let v = 0.5 * (f[a * k + b] + f[b * k + a]);
                    f[a * k + b] = v;
                    f[b * k + a] = v;
                }
            }
            // F α = e − G_J w
            let mut scale = 0.0f64;
            for (l, al) in alpha.iter_mut().enumerate() {
                let gw: f64 = jset
                    .iter()
                    .enumerate()
                    .map(|(t, &j)| self.ar[j][l] * w[t])
                    .sum();
                *al = e[l] - gw;
                scale = scale.max(e[l].abs()).max(gw.abs());
            }
            match SpdFactor::from_row_major(&f, k) {
                Some(f) => f.solve_in_place(&mut alpha),
                None => {
                    if !coarse_pseudo_solve(&f, k, &mut alpha, scale) {
                        return Ok(None);
                    }
                }
            }
            for (l, yl) in y.iter().enumerate() {
                for (wt, yt) in w.iter_mut().zip(yl) {
                    *wt += alpha[l] * yt;
                }
            }
        }
        Ok(Some((w, alpha)))
    }

    /// The KKT system `Cx + A_Jᵀλ_J = d, A_J x = g_J` by the Schur complement
    /// on the factor of C; None if it is singular (or C cannot be factored:
    /// then `error` is set).
    pub(super) fn schur_solve(
        &mut self,
        in_j: &[bool],
        d: &[f64],
        g: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        if let Err(e) = self.ensure_dense() {
            self.error = Some(e);
            return None;
        }
        let qp = self.qp;
        // A K⁻¹d and e = Rᵀd: cached for the problem's own d.
        let own = std::ptr::eq(d.as_ptr(), qp.d.as_ptr());
        let ax0_all: Vec<f64> = if own {
            self.ax0.clone()
        } else {
            self.solves += 1;
            let x0 = self.fac.as_ref().expect("factored").solve(d);
            (0..qp.m()).map(|i| qp.a.row_dot(i, &x0)).collect()
        };
        let e: Vec<f64> = if own {
            self.e.clone()
        } else {
            self.r.iter().map(|rl| dot(rl, d)).collect()
        };
        let jset: Vec<usize> = (0..qp.m()).filter(|&i| in_j[i]).collect();
        self.columns(&jset);
        // A_J K⁻¹ d
        let ax0: Vec<f64> = jset.iter().map(|&j| ax0_all[j]).collect();
        let (w, alpha) = self.schur_dense(&jset, &ax0, &e, g, true)?;
        let mut lam = vec![0.0; qp.m()];
        for (t, &j) in jset.iter().enumerate() {
            lam[j] = w[t];
        }
        // x = K⁻¹(d − A_Jᵀλ_J) + Rα: one solve, or the second half of the
        // one whose forward half gave A K⁻¹d.
        let fac = self.fac.as_ref().expect("ensure_dense before kkt_solve");
        let finished = match (&self.fwd_d, own) {
            (Some(f), true) => fac.finish(f, &qp.a, &lam),
            _ => None,
        };
        let mut x = match finished {
            Some(x) => x,
            None => {
                let mut x = d.to_vec();
                for (t, &j) in jset.iter().enumerate() {
                    let (cols, v) = qp.a.row(j);
                    for (&c, &a) in cols.iter().zip(v) {
                        x[c] -= w[t] * a;
                    }
                }
                fac.solve_in_place(&mut x);
                x
            }
        };
        self.solves += 1;
        for (rl, &al) in self.r.iter().zip(&alpha) {
            for (xi, ri) in x.iter_mut().zip(rl) {
                *xi += al * ri;
            }
        }
        if lam.iter().chain(&x).any(|v| !v.is_finite()) {
            return None;
        }
        Some((lam, x))
    }
}

/// F α = b for the coarse matrix F (k×k, row-major, symmetric positive
/// semidefinite) when F is singular: J leaves the rigid motions β of
/// null F unrestrained (A_J Rβ = 0). The system is consistent iff the loads
/// do no work on them (βᵀb = dᵀRβ = 0, to 10⁻⁹ of `scale`, the size of the
/// terms of b); then α = F⁺b, which has no component along them: the KKT
/// system of J is solved, its answer unique up to those motions, and the
/// Newton loop's next working set decides whether an inactive row stops
/// them (docs/methods.md §7). False (and `b` unchanged in meaning) if
/// inconsistent: the caller enlarges J.
fn coarse_pseudo_solve(f: &[f64], k: usize, b: &mut [f64], scale: f64) -> bool {
    let rows: Vec<Vec<f64>> = (0..k).map(|i| f[i * k..(i + 1) * k].to_vec()).collect();
    let (vals, vecs) = crate::linalg::dense::sym_eigen(&rows);
    let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if !(top > 0.0) || !top.is_finite() {
        return false;
    }
    let mut out = vec![0.0; k];
    for (lam, v) in vals.iter().zip(&vecs) {
        let p: f64 = v.iter().zip(b.iter()).map(|(a, c)| a * c).sum();
        if lam.abs() <= 1e-12 * top {
            if p.abs() > 1e-9 * scale {
                return false;
            }
            continue;
        }
        for (o, vi) in out.iter_mut().zip(v) {
            *o += p / lam * vi;
        }
    }
    b.copy_from_slice(&out);
    true
}

/// How S_J⁻¹ is applied: its own factor, or from the factor of S over all
/// m rows with N = the rows outside J, by the identity for the inverse of a
/// principal block, S_JJ⁻¹ = P_JJ − P_JN P_NN⁻¹ P_NJ with P = S⁻¹: |N| solves
/// with the full factor and a |N|×|N| system instead of a new |J|³/3 factor
/// (the dual-space steps of a conforming interface start from every row and
/// drop a few per step).
/// The largest relative residual (∞-norm, per column) accepted from the
/// complement before S_J is factored itself; a direct factor leaves about
/// 1e-14 on the three-body crust.
const COMPLEMENT_RESIDUAL: f64 = 1e-10;

/// At most this many m×m dense factors' worth of bytes in an [`SjCache`].
const SJ_CACHE_FACTORS: usize = 2;

/// The solvers of S_J made so far, by kind (complement or not) and J, most
/// recent first: the same J gives the same matrix and the same bits, so a
/// working set seen again (within a solve, or in the next load step's
/// dual-space steps, which retrace the last one's, `super::Kept`) is not
/// factored again. Bounded in bytes, the oldest dropped first.
#[derive(Default)]
pub(super) struct SjCache {
    entries: Vec<(bool, Vec<usize>, Rc<SjSolver>)>,
}

impl SjCache {
    fn get(&self, complement: bool, jset: &[usize]) -> Option<Rc<SjSolver>> {
        self.entries
            .iter()
            .find(|e| e.0 == complement && e.1 == jset)
            .map(|e| e.2.clone())
    }

    fn put(&mut self, complement: bool, jset: &[usize], s: Rc<SjSolver>, cap: usize) {
        self.entries.insert(0, (complement, jset.to_vec(), s));
        let mut bytes = 0;
        let keep = self
            .entries
            .iter()
            .take_while(|e| {
                bytes += e.2.bytes();
                bytes <= cap
            })
            .count()
            .max(1);
        self.entries.truncate(keep);
    }
}

/// λ_J and the coarse α of a dual-space solve.
type DualAnswer = (Vec<f64>, Vec<f64>);

/// The complement's answer failed its residual test.
struct Refused;

enum SjSolver {
    Direct(Rc<SpdFactor>),
    Complement {
        full: Rc<SpdFactor>,
        /// Position of each row in J (usize::MAX: in N).
        pos: Vec<usize>,
        nset: Vec<usize>,
        /// P_·N, m×|N|.
        p_n: Mat<f64>,
        p_nn: SpdFactor,
    },
}

impl SjSolver {
    /// The bytes it holds (its dense matrices).
    fn bytes(&self) -> usize {
        8 * match self {
            SjSolver::Direct(f) => f.l().nrows() * f.l().nrows(),
            SjSolver::Complement { pos, p_n, p_nn, .. } => {
                pos.len() + p_n.nrows() * p_n.ncols() + p_nn.l().nrows() * p_nn.l().nrows()
            }
        }
    }

    fn complement(full: Rc<SpdFactor>, jset: &[usize], m: usize) -> Option<SjSolver> {
        let mut pos = vec![usize::MAX; m];
        for (t, &j) in jset.iter().enumerate() {
            pos[j] = t;
        }
        let nset: Vec<usize> = (0..m).filter(|&i| pos[i] == usize::MAX).collect();
        let nn = nset.len();
        let mut p_n = Mat::<f64>::zeros(m, nn);
        for (c, &i) in nset.iter().enumerate() {
            p_n[(i, c)] = 1.0;
        }
        full.solve_mat_in_place(p_n.as_mut());
        let p_nn = Mat::from_fn(nn, nn, |a, b| {
            if b <= a {
                0.5 * (p_n[(nset[a], b)] + p_n[(nset[b], a)])
            } else {
                0.0
            }
        });
        let p_nn = SpdFactor::new(p_nn.as_ref())?;
        Some(SjSolver::Complement {
            full,
            pos,
            nset,
            p_n,
            p_nn,
        })
    }

    /// R ← S_J⁻¹ R (rows indexed by position in J). The complement's
    /// answer is checked on S_J itself (`hs`: the columns hⱼ, j ∈ J): None
    /// if its relative residual exceeds [`COMPLEMENT_RESIDUAL`] (the caller
    /// then factors S_J), a test on values only.
    fn solve_mat_in_place(
        &self,
        r: faer::MatMut<'_, f64>,
        hs: &[&Vec<f64>],
        jset: &[usize],
    ) -> Result<(), Refused> {
        let mut r = r;
        match self {
            SjSolver::Direct(f) => f.solve_mat_in_place(r),
            SjSolver::Complement {
                full,
                pos,
                nset,
                p_n,
                p_nn,
            } => {
                let (m, c) = (pos.len(), r.ncols());
                let b = r.to_owned();
                let mut u = Mat::<f64>::zeros(m, c);
                for (i, p) in pos.iter().enumerate() {
                    if *p != usize::MAX {
                        for l in 0..c {
                            u[(i, l)] = r[(*p, l)];
                        }
                    }
                }
                full.solve_mat_in_place(u.as_mut());
                let mut v = Mat::from_fn(nset.len(), c, |a, l| u[(nset[a], l)]);
                p_nn.solve_mat_in_place(v.as_mut());
                let mut pv = Mat::<f64>::zeros(m, c);
                faer::linalg::matmul::matmul(
                    pv.as_mut(),
                    faer::Accum::Replace,
                    p_n.as_ref(),
                    v.as_ref(),
                    1.0,
                    faer::Par::Seq,
                );
                for (i, p) in pos.iter().enumerate() {
                    if *p != usize::MAX {
                        for l in 0..c {
                            r[(*p, l)] = u[(i, l)] - pv[(i, l)];
                        }
                    }
                }
                // res = b − S_J r, S_J = (H_JJ + H_JJᵀ)/2 read by columns.
                let nj = jset.len();
                let mut sr = Mat::<f64>::zeros(nj, c);
                for (t, ht) in hs.iter().enumerate() {
                    for l in 0..c {
                        let rt = r[(t, l)];
                        let mut acc = 0.0;
                        for (a, &j) in jset.iter().enumerate() {
                            let h = ht[j];
                            sr[(a, l)] += 0.5 * h * rt;
                            acc += h * r[(a, l)];
                        }
                        sr[(t, l)] += 0.5 * acc;
                    }
                }
                for l in 0..c {
                    let (mut res, mut big) = (0.0f64, 0.0f64);
                    for a in 0..nj {
                        res = res.max((b[(a, l)] - sr[(a, l)]).abs());
                        big = big.max(b[(a, l)].abs());
                    }
                    if !(res <= COMPLEMENT_RESIDUAL * big) {
                        log::debug!(
                            "ssn: complement residual {res:.2e} of {big:.2e}: factoring S_J"
                        );
                        return Err(Refused);
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// S = MᵀM + I (m×m, SPD) as columns, from a fixed sequence.
    fn spd(m: usize) -> Vec<Vec<f64>> {
        let mm: Vec<f64> = (0..m * m).map(|k| (0.37 * k as f64).sin()).collect();
        (0..m)
            .map(|j| {
                (0..m)
                    .map(|i| {
                        let d: f64 = (0..m).map(|k| mm[k * m + i] * mm[k * m + j]).sum();
                        d + if i == j { 1.0 } else { 0.0 }
                    })
                    .collect()
            })
            .collect()
    }

    /// The complement (the factor of S over every row, N = the rows left
    /// out) solves S_J as its own factor does, and refuses an answer that
    /// does not satisfy S_J (here: columns of another matrix).
    #[test]
    fn complement_solves_s_j() {
        let m = 40;
        let s = spd(m);
        let full = Rc::new(SpdFactor::new(Mat::from_fn(m, m, |i, j| s[j][i]).as_ref()).unwrap());
        let jset: Vec<usize> = (0..m).filter(|i| ![3, 17, 18, 30].contains(i)).collect();
        let nj = jset.len();
        let hs: Vec<&Vec<f64>> = jset.iter().map(|&j| &s[j]).collect();
        let rhs = Mat::from_fn(nj, 2, |a, c| (1.3 * a as f64 + c as f64).cos());
        let direct =
            SpdFactor::new(Mat::from_fn(nj, nj, |a, b| s[jset[b]][jset[a]]).as_ref()).unwrap();
        let mut want = rhs.clone();
        direct.solve_mat_in_place(want.as_mut());
        let comp = SjSolver::complement(full.clone(), &jset, m).unwrap();
        let mut got = rhs.clone();
        assert!(comp.solve_mat_in_place(got.as_mut(), &hs, &jset).is_ok());
        for a in 0..nj {
            for c in 0..2 {
                assert!(
                    (got[(a, c)] - want[(a, c)]).abs() <= 1e-11 * (1.0 + want[(a, c)].abs()),
                    "{} vs {}",
                    got[(a, c)],
                    want[(a, c)]
                );
            }
        }
        let other = spd(m + 1);
        let hs_other: Vec<&Vec<f64>> = jset.iter().map(|&j| &other[j]).collect();
        let mut bad = rhs.clone();
        assert!(comp
            .solve_mat_in_place(bad.as_mut(), &hs_other, &jset)
            .is_err());
    }
}
