//! The next Coulomb working-set system from the last one's LU
//! (docs/methods.md §9.2, "The LU of the last Newton step"): two Newton
//! steps of the direct iteration differ in a few rows (a row joins or
//! leaves the system, or a slipping row turns its slip direction), so the
//! new matrix is the last one plus a low-rank change, solved by
//! Sherman–Morrison–Woodbury on the last LU instead of a new one.
//!
//! The two systems live on the union S of their unknowns (each unknown is
//! named by a key: a row of B = [A; T], or 2m + l for the rigid motion l).
//! On S the last matrix Ŵ₀ is W₀ with h·I on the new unknowns, the new one
//! Ŵ is W with h·I on the unknowns it dropped, and Ŵ − Ŵ₀ = U Vᵀ has the
//! rows of the unknowns that came or went and the columns of those and of
//! the rows whose slip force changed (κ = μσ): every other entry is the
//! same function of H. Then Ŵ⁻¹b = y − Z (I + VᵀZ)⁻¹ Vᵀy with y = Ŵ₀⁻¹b and
//! Z = Ŵ₀⁻¹U (one block solve of rank columns), refined on the residual of
//! W itself; an answer whose residual is not at the LU's level is refused
//! and the caller factors afresh.

use crate::linalg::dense::Lu;
use faer::Mat;

/// Systems of at least this many unknowns keep their LU for the next
/// Newton step (a smaller one is factored again, in 30 ms or less: the
/// same bits as before the update existed).
pub(super) const UPDATE_MIN: usize = 1024;

/// The largest rank of a change solved on the last LU, and at most this
/// fraction of the unknowns (Z costs rank triangular solves).
const RANK_MAX: usize = 128;
const RANK_FRACTION: usize = 8;

/// Refinement steps of an updated solve.
const REFINE: usize = 2;

/// An updated answer's residual must be within this of
/// ‖W‖∞‖x‖∞ + ‖b‖∞ (an LU's backward error is a few ε).
const ACCEPT: f64 = 1e-13;

/// A factored Coulomb system (row-major W, its unknowns' keys and slip
/// factors κ, its LU) and the scale h of the identity rows on S.
pub(super) struct Factored {
    keys: Vec<usize>,
    kappa: Vec<f64>,
    w: Vec<f64>,
    lu: Lu,
    h: f64,
}

impl Factored {
    pub(super) fn new(keys: Vec<usize>, kappa: Vec<f64>, w: Vec<f64>, lu: Lu, h: f64) -> Self {
        Factored {
            keys,
            kappa,
            w,
            lu,
            h,
        }
    }

    /// Solve W x = b, W the row-major system on the unknowns `keys` with
    /// slip factors `kappa`, as a change of this one. None when the change
    /// has too high a rank, its capacitance matrix is singular, or the
    /// answer is not accurate; else the answer and the rank.
    pub(super) fn solve_changed(
        &self,
        keys: &[usize],
        kappa: &[f64],
        w: &[f64],
        b: &[f64],
        h: f64,
    ) -> Option<(Vec<f64>, usize)> {
        if h != self.h {
            return None;
        }
        let (n0, n) = (self.keys.len(), keys.len());
        let top = self.keys.iter().chain(keys).max().map_or(0, |k| k + 1);
        let mut old_at = vec![usize::MAX; top];
        for (p, &key) in self.keys.iter().enumerate() {
            old_at[key] = p;
        }
        // S: the last system's unknowns, then the new ones it lacks.
        let mut s_of_new = vec![0; n];
        let mut new_of_s = vec![usize::MAX; n0];
        let mut changed_cols = vec![];
        let mut changed_rows = vec![];
        for (j, &key) in keys.iter().enumerate() {
            let p = old_at[key];
            if p == usize::MAX {
                s_of_new[j] = new_of_s.len();
                new_of_s.push(j);
                changed_rows.push(s_of_new[j]);
            } else {
                s_of_new[j] = p;
                new_of_s[p] = j;
                if kappa[j].to_bits() != self.kappa[p].to_bits() {
                    changed_cols.push(p);
                }
            }
        }
        for (p, &j) in new_of_s.iter().enumerate().take(n0) {
            if j == usize::MAX {
                changed_rows.push(p);
            }
        }
        changed_rows.sort_unstable();
        changed_cols.extend_from_slice(&changed_rows);
        changed_cols.sort_unstable();
        let ns = new_of_s.len();
        let rank = changed_rows.len() + changed_cols.len();
        if rank > RANK_MAX || rank * RANK_FRACTION > n {
            return None;
        }
        let old_hat = |r: usize, c: usize| -> f64 {
            if r < n0 && c < n0 {
                self.w[r * n0 + c]
            } else if r == c {
                self.h
            } else {
                0.0
            }
        };
        let new_hat = |r: usize, c: usize| -> f64 {
            match (new_of_s[r], new_of_s[c]) {
                (a, b) if a != usize::MAX && b != usize::MAX => w[a * n + b],
                (a, b) if a == usize::MAX && b == usize::MAX && r == c => h,
                _ => 0.0,
            }
        };
        let mut in_rows = vec![false; ns];
        for &r in &changed_rows {
            in_rows[r] = true;
        }
        // U = [h E_R | D̃_C] (D̃: the changed columns off the changed rows),
        // Vᵀ = [D_R / h; E_Cᵀ]: every block of I + VᵀZ of order one (with
        // E_R unscaled they spanned 10⁻¹³–10¹⁰ on a shrink fit).
        let mut u = Mat::<f64>::zeros(ns, rank);
        for (a, &r) in changed_rows.iter().enumerate() {
            u[(r, a)] = self.h;
        }
        let nr = changed_rows.len();
        for (a, &c) in changed_cols.iter().enumerate() {
            for r in (0..ns).filter(|&r| !in_rows[r]) {
                u[(r, nr + a)] = new_hat(r, c) - old_hat(r, c);
            }
        }
        let d_rows: Vec<Vec<f64>> = changed_rows
            .iter()
            .map(|&r| {
                (0..ns)
                    .map(|c| (new_hat(r, c) - old_hat(r, c)) / self.h)
                    .collect()
            })
            .collect();
        // Z = Ŵ₀⁻¹U.
        let mut z = u;
        self.lu.solve_mat_in_place(z.as_mut().subrows_mut(0, n0));
        for r in n0..ns {
            for a in 0..rank {
                z[(r, a)] /= self.h;
            }
        }
        // Vᵀv for a vector v on S.
        let vt = |v: &dyn Fn(usize) -> f64| -> Vec<f64> {
            let mut out: Vec<f64> = d_rows
                .iter()
                .map(|row| row.iter().enumerate().map(|(c, x)| x * v(c)).sum())
                .collect();
            out.extend(changed_cols.iter().map(|&c| v(c)));
            out
        };
        let mut cap = vec![0.0; rank * rank];
        for a in 0..rank {
            let col = vt(&|c| z[(c, a)]);
            for (b_, v) in col.iter().enumerate() {
                cap[b_ * rank + a] = *v;
            }
            cap[a * rank + a] += 1.0;
        }
        let cap = Lu::from_row_major(&cap, rank)?;
        // x̂ = Ŵ⁻¹r̂ for r̂ on the new unknowns (zero on the dropped ones).
        let apply = |rhs: &[f64]| -> Vec<f64> {
            let mut y = vec![0.0; ns];
            for (j, &v) in rhs.iter().enumerate() {
                y[s_of_new[j]] = v;
            }
            self.lu.solve_in_place(&mut y[..n0]);
            for v in &mut y[n0..] {
                *v /= self.h;
            }
            let mut t = vt(&|c| y[c]);
            cap.solve_in_place(&mut t);
            for (r, yr) in y.iter_mut().enumerate() {
                *yr -= (0..rank).map(|a| z[(r, a)] * t[a]).sum::<f64>();
            }
            s_of_new.iter().map(|&p| y[p]).collect()
        };
        let residual = |x: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|r| {
                    b[r] - w[r * n..(r + 1) * n]
                        .iter()
                        .zip(x)
                        .map(|(a, v)| a * v)
                        .sum::<f64>()
                })
                .collect()
        };
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let wnorm = (0..n)
            .map(|r| w[r * n..(r + 1) * n].iter().map(|a| a.abs()).sum::<f64>())
            .fold(0.0f64, f64::max);
        let mut x = apply(b);
        let mut res = residual(&x);
        for _ in 0..REFINE {
            let dx = apply(&res);
            let next: Vec<f64> = x.iter().zip(&dx).map(|(a, d)| a + d).collect();
            let r2 = residual(&next);
            if !(inf(&r2) < inf(&res)) {
                break;
            }
            x = next;
            res = r2;
        }
        let ok = inf(&res) <= ACCEPT * (wnorm * inf(&x) + inf(b));
        (ok && x.iter().all(|v| v.is_finite())).then_some((x, rank))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random diagonally dominant nonsymmetric system on keys 0..n and
    /// one with two unknowns dropped, one added and one κ changed (the
    /// entries of a kept pair the same): the update solves it to the LU's
    /// accuracy, and refuses a change of too high a rank.
    #[test]
    fn a_changed_system_is_solved_on_the_last_lu() {
        let n = 80;
        let mut seed = 7u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 10_000) as f64 / 10_000.0 - 0.5
        };
        let big: Vec<Vec<f64>> = (0..n + 1)
            .map(|i| {
                (0..n + 1)
                    .map(|j| if i == j { 20.0 } else { rnd() })
                    .collect()
            })
            .collect();
        let entry = |i: usize, j: usize, kappa: f64| big[i][j] + kappa * big[j][i];
        let keys0: Vec<usize> = (0..n).collect();
        let kappa0 = vec![0.0; n];
        let w0: Vec<f64> = (0..n * n)
            .map(|e| entry(keys0[e / n], keys0[e % n], 0.0))
            .collect();
        let lu = Lu::from_row_major(&w0, n).unwrap();
        let f = Factored::new(keys0, kappa0, w0, lu, 20.0);
        // Drop 3 and 11, add n, κ of key 5 becomes 0.3.
        let keys: Vec<usize> = (0..n).filter(|k| *k != 3 && *k != 11).chain([n]).collect();
        let m = keys.len();
        let kappa: Vec<f64> = keys
            .iter()
            .map(|&k| if k == 5 { 0.3 } else { 0.0 })
            .collect();
        let w: Vec<f64> = (0..m * m)
            .map(|e| entry(keys[e / m], keys[e % m], kappa[e % m]))
            .collect();
        let b: Vec<f64> = (0..m).map(|_| rnd()).collect();
        let (x, rank) = f.solve_changed(&keys, &kappa, &w, &b, 20.0).unwrap();
        assert_eq!(rank, 3 + 4);
        let mut want = b.clone();
        Lu::from_row_major(&w, m).unwrap().solve_in_place(&mut want);
        let err = x
            .iter()
            .zip(&want)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        assert!(err <= 1e-13, "{err:e}");
        // A change of rank over an eighth of the unknowns is refused.
        let kappa_all = vec![0.1; m];
        assert!(f.solve_changed(&keys, &kappa_all, &w, &b, 20.0).is_none());
        // Another scale h: another H, refused.
        assert!(f.solve_changed(&keys, &kappa, &w, &b, 21.0).is_none());
    }
}
