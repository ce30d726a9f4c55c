//! The KKT system of J by exact elimination on one sparse factor K of C
//! (C + springs at fixing DOFs when C is semicoercive: K⁻¹ is then a
//! generalised inverse on range C), docs/methods.md §7. The columns
//! hⱼ = A K⁻¹aⱼ are computed only for rows that enter J, [`BLOCK`] per
//! blocked solve, and cached (O(m·|J|) memory); S_J = A_J K⁻¹A_Jᵀ is formed
//! densely and factored (dense LLᵀ, O(|J|³)). With ker C = span R, as in
//! TFETI, x = K⁻¹(d − A_Jᵀλ_J) + Rα and the solvability condition
//! Rᵀ(d − A_Jᵀλ_J) = 0 joins A_J x = g_J; the coarse matrix
//! F = G_J S_J⁻¹ G_Jᵀ (G_J = RᵀA_Jᵀ) is singular iff J leaves a rigid
//! motion free, and then the step returns None (the caller enlarges J).

use super::{Ssn, BLOCK};
use crate::linalg::dense::SpdFactor;
use crate::linalg::sparse::dot;
use faer::Mat;

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
                self.h[j] = Some(self.qp.a.mul(&buf[c * n..(c + 1) * n]));
            }
        }
    }

    /// The multipliers of the KKT system of J = `jset` in the dual space
    /// alone, from the cached columns: λ_J = S_J⁻¹(A_J K⁻¹d − g_J + G_Jᵀα)
    /// and the coarse α (module doc), given `ax0` = A_J K⁻¹d and e = Rᵀd.
    /// None if S_J or the coarse matrix is singular.
    pub(super) fn schur_dense(
        &self,
        jset: &[usize],
        ax0: &[f64],
        e: &[f64],
        g: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        // The Newton loop's first KKT solve repeats the dual-space steps'
        // last system (same J, same right-hand sides): answered from memory.
        let gj: Vec<f64> = jset.iter().map(|&j| g[j]).collect();
        let key = |m: &DenseMemo| m.jset == jset && m.ax0 == ax0 && m.e == e && m.gj == gj;
        if let Some(m) = self.dense_memo.borrow().as_ref().filter(|m| key(m)) {
            return Some((m.w.clone(), m.alpha.clone()));
        }
        let out = self.schur_dense_new(jset, ax0, e, g);
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

    fn schur_dense_new(
        &self,
        jset: &[usize],
        ax0: &[f64],
        e: &[f64],
        g: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let nj = jset.len();
        let k = self.r.len();
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
        let s = SpdFactor::new(s.as_ref())?;
        // w = S⁻¹(A_J K⁻¹ d − g_J)
        let mut w: Vec<f64> = jset.iter().zip(ax0).map(|(&j, a)| a - g[j]).collect();
        s.solve_in_place(&mut w);
        let mut alpha = vec![0.0; k];
        if k > 0 {
            // Y = S⁻¹ G_Jᵀ (columns l), F = G_J Y.
            let mut y: Vec<Vec<f64>> = Vec::with_capacity(k);
            for l in 0..k {
                let mut col: Vec<f64> = jset.iter().map(|&j| self.ar[j][l]).collect();
                s.solve_in_place(&mut col);
                y.push(col);
            }
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
            let f = SpdFactor::from_row_major(&f, k)?;
            // F α = e − G_J w
            for (l, al) in alpha.iter_mut().enumerate() {
                let gw: f64 = jset
                    .iter()
                    .enumerate()
                    .map(|(t, &j)| self.ar[j][l] * w[t])
                    .sum();
                *al = e[l] - gw;
            }
            f.solve_in_place(&mut alpha);
            for (l, yl) in y.iter().enumerate() {
                for (wt, yt) in w.iter_mut().zip(yl) {
                    *wt += alpha[l] * yt;
                }
            }
        }
        Some((w, alpha))
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
        // K⁻¹d and e = Rᵀd: cached for the problem's own d.
        let own = std::ptr::eq(d.as_ptr(), qp.d.as_ptr());
        let x0 = if own {
            self.x0.clone()
        } else {
            self.solves += 1;
            self.fac.as_ref().expect("factored").solve(d)
        };
        let e: Vec<f64> = if own {
            self.e.clone()
        } else {
            self.r.iter().map(|rl| dot(rl, d)).collect()
        };
        let jset: Vec<usize> = (0..qp.m()).filter(|&i| in_j[i]).collect();
        self.columns(&jset);
        // A_J K⁻¹ d
        let ax0: Vec<f64> = jset.iter().map(|&j| qp.a.row_dot(j, &x0)).collect();
        let (w, alpha) = self.schur_dense(&jset, &ax0, &e, g)?;
        let mut lam = vec![0.0; qp.m()];
        for (t, &j) in jset.iter().enumerate() {
            lam[j] = w[t];
        }
        // x = K⁻¹(d − A_Jᵀλ_J) + Rα: one solve.
        let mut x = d.to_vec();
        for (t, &j) in jset.iter().enumerate() {
            let (cols, v) = qp.a.row(j);
            for (&c, &a) in cols.iter().zip(v) {
                x[c] -= w[t] * a;
            }
        }
        self.fac
            .as_ref()
            .expect("ensure_dense before kkt_solve")
            .solve_in_place(&mut x);
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
