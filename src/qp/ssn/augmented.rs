//! The KKT system of J through K_J = C + A_JᵀΡA_J, Ρ = diag(ρ_j), ρ_j =
//! [`super::RHO_FACTOR`]·max diag C (docs/methods.md §7). K_J is SPD as soon
//! as J holds every floating body and has the pattern of C + AᵀA for every J
//! ([`AugPattern`]): one numeric refactorisation per step on one symbolic
//! analysis, or a Woodbury update ([`super::lowrank`]). The system
//! `K_J x + A_Jᵀμ = d + A_JᵀΡg_J, A_J x = g_J` is solved by CG on its Schur
//! complement (condition ≤ 1 + 1/(ρ·λ_min(A_J C⁻¹A_Jᵀ)), warm-started from
//! the last λ). The multiplier is λ_J = μ + Ρ(A_J x − g_J), for which
//! Cx − d + A_Jᵀλ = 0 holds to the backward error of the K_J solve whatever
//! gap error remains (taking λ = μ lost accuracy under stiffness contrast).
//! None when K_J is not positive definite or CG stalls: the caller falls
//! back to the Schur path. A factor refused for memory sets `error` instead
//! and ends the solve.

use super::lowrank::{LowRank, LOWRANK_BYTES, LOWRANK_MAX};
use super::Ssn;
use crate::linalg::sparse::{dot, norm};
use std::time::Instant;

/// CG on the Schur complement of K_J: at most this many steps.
const AL_MAX_CG: usize = 200;

impl Ssn<'_> {
    /// The KKT system of `in_j` through K_J (module doc), warm-started from
    /// the last λ.
    pub(super) fn kkt_solve_aug(&mut self, in_j: &[bool]) -> Option<(Vec<f64>, Vec<f64>)> {
        let mu0: Vec<f64> = (0..self.qp.m())
            .filter(|&i| in_j[i])
            .map(|j| self.lam[j])
            .collect();
        let (d, g) = (&self.qp.d, &self.qp.g);
        self.aug_solve(in_j, d, g, mu0)
    }

    /// The factor of K_J = C + A_JᵀΡA_J for `in_j` (rows `jset`): the kept
    /// factor of K' = C + A_{J'}ᵀΡA_{J'} with a low-rank correction for the
    /// rows that changed (Some(update)), or a new factor (None); None
    /// outside if K_J cannot be factored (a memory refusal is kept in
    /// `self.error`).
    fn factor_for(&mut self, in_j: &[bool], jset: &[usize]) -> Option<Option<LowRank>> {
        let qp = self.qp;
        let n = qp.n();
        // Reuse K' = C + A_{J'}ᵀΡA_{J'} with a low-rank correction, or refactor.
        let mut update = None;
        if let (Some(fac), Some(jb), true) = (&self.kfac, &self.kfac_set, self.lowrank) {
            let changed: Vec<(usize, f64)> = (0..qp.m())
                .filter(|&i| jb[i] != in_j[i])
                .map(|i| (i, if in_j[i] { 1.0 } else { -1.0 }))
                .collect();
            let r = changed.len();
            let r_max = ((LOWRANK_BYTES / (8.0 * n.max(1) as f64)) as usize).min(LOWRANK_MAX);
            if r == 0 {
                update = Some(None);
            } else if r <= r_max && {
                let new_cols = changed
                    .iter()
                    .filter(|(j, _)| !self.zcache.contains_key(j))
                    .count();
                new_cols as f64 * self.costs.col_k() <= 0.5 * self.costs.fac_k
            } {
                let (lr, new_cols) = LowRank::new(qp, fac, changed, &self.rho, &mut self.zcache);
                self.solves += new_cols;
                update = lr.map(Some);
            }
        }
        Some(match update {
            Some(u) => u,
            None => {
                let aug = self.aug.as_mut()?;
                let k = aug.assemble(jset.iter().copied(), &self.rho);
                self.kfac = None; // free the old factor first
                self.kfac_set = None;
                self.zcache.clear();
                let t = Instant::now();
                let fac = match self.ws.cholesky(k, &[]) {
                    Ok(f) => Some(f),
                    // Memory is not a property of K_J: end the solve, do
                    // not fall back (QpError::Memory).
                    Err(e) if e.is_memory() => {
                        self.error = Some(e.into());
                        None
                    }
                    Err(_) => None,
                };
                self.t_factor += t.elapsed().as_secs_f64();
                self.kfac = Some(fac?);
                self.kfac_set = Some(in_j.to_vec());
                None
            }
        })
    }

    /// The KKT system `Cx + A_Jᵀλ_J = d, A_J x = g_J` through
    /// K_J = C + A_JᵀΡA_J, CG on its Schur complement started from `mu0`
    /// (one value per row of J); None if K_J is not positive definite or CG
    /// does not converge. Returns (λ over all rows, x).
    pub(super) fn aug_solve(
        &mut self,
        in_j: &[bool],
        d: &[f64],
        g: &[f64],
        mu0: Vec<f64>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let qp = self.qp;
        let jset: Vec<usize> = (0..qp.m()).filter(|&i| in_j[i]).collect();
        let n = qp.n();
        let update = self.factor_for(in_j, &jset)?;
        let fac = self.kfac.as_ref().expect("factor of K'");
        // x ← K_J⁻¹x: the factor of K', then the Woodbury correction.
        let kinv = |x: &mut Vec<f64>| {
            fac.solve_in_place(x);
            if let Some(lr) = &update {
                lr.correct(qp, x);
            }
        };
        // y0 = K⁻¹(d + A_JᵀΡg_J − A_Jᵀμ0): then A_J y0 − g_J is the residual
        // of S μ = A_J K⁻¹(d + A_JᵀΡg_J) − g_J at μ0.
        let mut y0 = d.to_vec();
        for (&j, &m0) in jset.iter().zip(&mu0) {
            let (c, v) = qp.a.row(j);
            for (&k, &a) in c.iter().zip(v) {
                y0[k] += a * (self.rho[j] * g[j] - m0);
            }
        }
        kinv(&mut y0);
        self.solves += 1;
        // s(μ) = K⁻¹A_Jᵀμ (n-vector), S μ = A_J s(μ).
        let mut solves = 0usize;
        let mut apply = |mu: &[f64]| -> Vec<f64> {
            let mut t = vec![0.0; n];
            for (&j, &m) in jset.iter().zip(mu) {
                let (c, v) = qp.a.row(j);
                for (&k, &a) in c.iter().zip(v) {
                    t[k] += a * m;
                }
            }
            kinv(&mut t);
            solves += 1;
            t
        };
        let aj = |t: &[f64]| -> Vec<f64> { jset.iter().map(|&j| qp.a.row_dot(j, t)).collect() };
        // CG on S δ = r0 = A_J y0 − g_J; μ = μ0 + δ, x = y0 − K⁻¹A_Jᵀδ.
        let ay0 = aj(&y0);
        let mut r: Vec<f64> = ay0.iter().zip(&jset).map(|(v, &j)| v - g[j]).collect();
        // Scale of the terms that cancel in A_J x − g_J: ‖|A_J||y0|‖ + ‖g_J‖.
        let abs_ay: Vec<f64> = jset
            .iter()
            .map(|&j| {
                let (c, v) = qp.a.row(j);
                c.iter()
                    .zip(v)
                    .map(|(&k, &a)| (a * y0[k]).abs())
                    .sum::<f64>()
            })
            .collect();
        let gj: Vec<f64> = jset.iter().map(|&j| g[j]).collect();
        let bnorm = norm(&abs_ay) + norm(&gj);
        let mut mu = mu0;
        let mut z = vec![0.0; n];
        let goal = (1e-2 * self.tol).min(1e-12) * bnorm.max(f64::MIN_POSITIVE);
        let mut p = r.clone();
        let mut rr = dot(&r, &r);
        let mut ok = rr.sqrt() <= goal || jset.is_empty();
        for _ in 0..AL_MAX_CG {
            if ok {
                break;
            }
            let sp_full = apply(&p);
            let sp = aj(&sp_full);
            let psp = dot(&p, &sp);
            if psp <= 0.0 || psp.is_nan() {
                break;
            }
            let alpha = rr / psp;
            for i in 0..mu.len() {
                mu[i] += alpha * p[i];
                r[i] -= alpha * sp[i];
            }
            for (zi, si) in z.iter_mut().zip(&sp_full) {
                *zi += alpha * si;
            }
            let rr_new = dot(&r, &r);
            let beta = rr_new / rr;
            rr = rr_new;
            if rr.sqrt() <= goal {
                ok = true;
                break;
            }
            for (pi, ri) in p.iter_mut().zip(&r) {
                *pi = ri + beta * *pi;
            }
        }
        self.solves += solves;
        log::debug!(
            "ssn: |J| = {}, K' {}, CG {} solves, ‖r‖/‖b‖ = {:.2e}",
            jset.len(),
            match &update {
                Some(u) => format!("+ rank-{} update", u.rows.len()),
                None => "factored".into(),
            },
            solves,
            rr.sqrt() / bnorm.max(f64::MIN_POSITIVE)
        );
        if !ok {
            log::debug!("ssn: CG on the augmented Schur complement did not converge; falling back");
            return None;
        }
        // x = y0 − K⁻¹A_Jᵀμ
        let x: Vec<f64> = y0.iter().zip(&z).map(|(y, z)| y - z).collect();
        // λ_J = μ + Ρ(A_J x − g_J): the first block row K_J x + A_Jᵀμ =
        // d + A_JᵀΡg_J is Cx − d + A_Jᵀλ = 0 exactly for this λ, whatever
        // gap error CG and the rounding in K_J⁻¹ left (module doc).
        let mut lam = vec![0.0; qp.m()];
        for (&j, &m) in jset.iter().zip(&mu) {
            lam[j] = m + self.rho[j] * (qp.a.row_dot(j, &x) - g[j]);
        }
        if lam.iter().chain(&x).any(|v| !v.is_finite()) {
            return None;
        }
        Some((lam, x))
    }
}
