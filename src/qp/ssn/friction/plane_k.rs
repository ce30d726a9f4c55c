//! The K solves of a working set on the discs' sparse paths
//! (docs/methods.md §12.3, "The iterative path"): x = K⁻¹(d' + Σ_B b(ρ r − μ))
//! with K = C + Σ_B ρ bᵀb, μ ← μ + ρ(b x − r), by one sparse factor of K a
//! step (`ssn_path = "augmented"`) or by CG preconditioned with a
//! smoothed-aggregation multigrid of K whose coarse spaces carry the rigid
//! motions (`ssn_path = "iterative"`, as the frictionless path of §7.2).
//! The iterative solves are inexact in Newton's sense: a step is solved to
//! a fraction of the residual it starts from, so the last steps are the
//! exact ones and the memory stays O(nnz C).

use super::{BRow, State, AL_MAX, AL_STALL};
use crate::linalg::amg::{pcg_stall, Amg, AmgSettings, NearNull, PCG_STALL};
use crate::linalg::sparse::{norm, norm_inf};
use crate::qp::kkt::CONTACT_FLOOR;
use crate::qp::QpError;
use std::time::Instant;

/// A step's solve on the iterative path reaches INEXACT × the residual the
/// step starts from (an inexact Newton step keeps Newton's rate).
const INEXACT: f64 = 1e-2;
/// The loosest and the tightest relative tolerance of a step's solve.
const LOOSEST: f64 = 1e-3;
const TIGHTEST: f64 = 1e-12;
/// CG steps per K solve, at most.
const PCG_MAX: usize = 2000;
/// ρ on the iterative path is this times the direct paths' (ρ ~ 10 × the
/// row's stiffness, as the frictionless iterative path takes: a larger ρ
/// costs CG more steps than the augmented-Lagrangian sweeps it saves).
pub(super) const RHO_ITERATIVE: f64 = 0.1;

/// How K is solved.
enum Ksolve {
    Factor(crate::linalg::cholesky::Cholesky),
    /// The hierarchy in [`IterK`].
    Multigrid,
}

/// A row of K's Σ_B w bᵀb as the hierarchy holds it: weight, columns,
/// values (bits, so that rows compare exactly).
type Held = (u64, Vec<usize>, Vec<u64>);

fn held(b: &BRow) -> Held {
    (
        b.spring.unwrap_or(b.rho).to_bits(),
        b.cols.clone(),
        b.vals.iter().map(|v| v.to_bits()).collect(),
    )
}

/// A slipping row whose force along its direction is μλ_n of its normal
/// row's multiplier inside the step (the direct Coulomb iteration,
/// docs/methods.md §12.3): the row of B of the normal row, μ, ê, the
/// contact row.
pub(super) struct Coupled {
    pub(super) row: usize,
    pub(super) mu: f64,
    pub(super) e: [f64; 2],
    pub(super) i: usize,
}

/// The iterative path's counters (ssn_path = "iterative").
#[derive(Default)]
pub(super) struct IterK {
    pub(super) cg_steps: usize,
    pub(super) builds: usize,
    pub(super) updates: usize,
    pub(super) t_setup: f64,
    /// The multigrid of the last K, and the rows of B it holds.
    amg: Option<Amg>,
    rows: Vec<Held>,
}

/// The hierarchy is rebuilt, not updated, when more than this fraction of
/// the rows of B changed (counts only).
const UPDATE_FRACTION: usize = 2;

/// The loosest residual that ends a Tresca problem of the fixed point on
/// the iterative path (after the glued start, whose bound is all new).
const OUTER_LOOSEST: f64 = 1e-2;

impl State<'_> {
    /// The residual that ends the Tresca problem at bound `s`: `tol` on a
    /// factor and for Tresca friction; in the Coulomb loop on the iterative path the square of the bound's relative
    /// change δ = ‖s − s_last‖∞/‖s‖∞ (at most OUTER_LOOSEST), never below
    /// `tol`: an inexact fixed point whose error, O(δ²), stays below the
    /// next change (the fixed point gains a factor of 2–10 a step), so the
    /// loop's sequence and end are the exact loop's. With 10⁻²δ instead
    /// the tail stalled and Cattaneo at 163 k ended on the certificate's
    /// target (a friction residual of 9·10⁻⁷, 26 rows classed otherwise).
    pub(super) fn tresca_tol_for(&self, s: &[f64]) -> f64 {
        // Tresca's one problem is the answer: no loop tightens it.
        if self.iter.is_none() || matches!(self.fr.bound, crate::qp::SlipBound::Tresca(_)) {
            return self.tol;
        }
        let change = if self.glued || self.s.len() != s.len() {
            1.0
        } else {
            let ds = self
                .s
                .iter()
                .zip(s)
                .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
            (ds / norm_inf(s).max(f64::MIN_POSITIVE)).min(1.0)
        };
        self.tol.max((change * change).min(OUTER_LOOSEST))
    }

    /// Make the kept hierarchy that of `kmat` (K of `rows`): updated by the
    /// rows that changed since it was made (a slipping row turns every
    /// step; docs/methods.md §7.2, "The hierarchy across working sets"),
    /// rebuilt when none is kept or most rows changed.
    fn multigrid(
        &mut self,
        kmat: &crate::linalg::sparse::Csr,
        rows: &[BRow],
    ) -> Result<(), QpError> {
        let qp = self.qp;
        let Some(it) = self.iter.as_mut() else {
            return Ok(());
        };
        let now: Vec<Held> = rows.iter().map(held).collect();
        if let Some(amg) = it.amg.as_mut() {
            let mut old: std::collections::HashMap<&Held, usize> = std::collections::HashMap::new();
            for h in &it.rows {
                *old.entry(h).or_default() += 1;
            }
            let mut added: Vec<&Held> = vec![];
            for h in &now {
                match old.get_mut(h) {
                    Some(c) if *c > 0 => *c -= 1,
                    _ => added.push(h),
                }
            }
            // Removed rows in the order the hierarchy holds them (the same
            // bits on every run; a HashMap's order is not).
            let mut left = old;
            let mut removed: Vec<&Held> = vec![];
            for h in &it.rows {
                if let Some(c) = left.get_mut(h) {
                    if *c > 0 {
                        *c -= 1;
                        removed.push(h);
                    }
                }
            }
            let changed = added.len() + removed.len();
            if changed * UPDATE_FRACTION <= now.len().max(1) {
                let vals: Vec<(f64, Vec<f64>)> = added
                    .iter()
                    .map(|h| (f64::from_bits(h.0), h))
                    .chain(removed.iter().map(|h| (-f64::from_bits(h.0), h)))
                    .map(|(w, h)| (w, h.2.iter().map(|v| f64::from_bits(*v)).collect()))
                    .collect();
                let cols: Vec<&[usize]> = added
                    .iter()
                    .chain(&removed)
                    .map(|h| h.1.as_slice())
                    .collect();
                let changes: Vec<(f64, &[usize], &[f64])> = vals
                    .iter()
                    .zip(&cols)
                    .map(|((w, v), c)| (*w, *c, v.as_slice()))
                    .collect();
                if amg.update(kmat, &changes).is_ok() {
                    it.updates += 1;
                    it.rows = now;
                    return Ok(());
                }
            }
        }
        it.amg = None; // free the old hierarchy first
        let near = qp.near.as_ref().map(|nk| NearNull {
            block_ptr: &nk.block_ptr,
            modes: &nk.modes,
        });
        let nm = qp.near.as_ref().map_or(1, |nk| nk.modes.len());
        let amg = Amg::new(kmat, near, &AmgSettings::for_modes(nm)).map_err(|e| {
            QpError::Unsupported(format!(
                "ssn_path = \"iterative\": no multigrid of K ({e}); ssn_path = \"auto\" factors it"
            ))
        })?;
        it.builds += 1;
        it.amg = Some(amg);
        it.rows = now;
        Ok(())
    }

    /// ‖C x − d + Aᵀλ_n + Tᵀλ_t‖ over max(‖d‖, ‖C x‖) at the last iterate:
    /// the certificate's stationarity (docs/methods.md §8.4; ∞ for a
    /// non-finite iterate).
    fn balance(&self) -> f64 {
        crate::qp::kkt::residuals_with_friction(self.qp, &self.x, &self.ln, &self.lt).stationarity
    }

    /// (x, μ) of the working set whose rows of B are `rows` under the
    /// loads `dp` (d less the known slip forces), from the multipliers
    /// `mu` of the rows (their last values); `free`: the rigid motions
    /// the rows leave free (the factor regularises them; the multigrid
    /// cannot, and the iterative path refuses them).
    pub(super) fn al_solve(
        &mut self,
        rows: &[BRow],
        dp: &[f64],
        free: &[Vec<f64>],
        mut mu: Vec<f64>,
        coupled: &[Coupled],
    ) -> Result<(Vec<f64>, Vec<f64>), QpError> {
        let kmat = self.k_matrix(rows);
        let bscale = rows.iter().fold(0.0f64, |a, b| a.max(b.rhs.abs()));
        // The accuracy of this step: exact on a factor; on the multigrid a
        // fraction of the residual the step starts from.
        let (ptol, solver) = if self.iter.is_some() {
            if !free.is_empty() {
                return Err(QpError::Unsupported(format!(
                    "ssn_path = \"iterative\": a working set leaves {} rigid motion(s) of a body free \
                     (held by friction alone), which the multigrid cannot solve; \
                     ssn_path = \"auto\" regularises them on a factor (docs/methods.md §12.3)",
                    free.len()
                )));
            }
            let t = Instant::now();
            self.multigrid(&kmat, rows)?;
            let it = self.iter.as_mut().expect("checked above");
            it.t_setup += t.elapsed().as_secs_f64();
            // The step starts from the last iterate: its distance from the
            // answer is the rows' residual and the balance's, which the
            // rows' residual alone misses (zero at the start x = 0, λ = 0,
            // and at a load step's start: the glued step of the stack at
            // 119 k unknowns was solved to 10⁻¹² from zero, 13 s).
            let r0 = self.residual().max(self.balance());
            let ptol = if r0.is_finite() {
                (INEXACT * r0).clamp(TIGHTEST, LOOSEST)
            } else {
                LOOSEST
            };
            (ptol, Ksolve::Multigrid)
        } else {
            (1e-14, Ksolve::Factor(self.ws.cholesky(&kmat, free)?))
        };
        let dnorm = norm(dp);
        let mut x = match &solver {
            // A warm start: the last step's answer.
            Ksolve::Multigrid => self.x.clone(),
            Ksolve::Factor(_) => vec![0.0; self.qp.n()],
        };
        let (mut last, mut stalled) = (f64::INFINITY, 0);
        for _ in 0..AL_MAX {
            let mut rhs = dp.to_vec();
            let mut force = vec![0.0; self.qp.n()];
            for (b, mk) in rows.iter().zip(&mu) {
                let w = match b.spring {
                    Some(k_s) => k_s * b.rhs,
                    None => b.rho * b.rhs - mk,
                };
                for (&j, &a) in b.cols.iter().zip(&b.vals) {
                    rhs[j] += w * a;
                    if b.spring.is_none() {
                        force[j] += mk * a;
                    }
                }
            }
            // The coupled slip forces at this sweep's normal multipliers.
            for c in coupled {
                let f = c.mu * mu[c.row];
                for k in 0..2 {
                    let (cols, vals) = self.fr.t.row(2 * c.i + k);
                    for (&j, &a) in cols.iter().zip(vals) {
                        rhs[j] -= f * c.e[k] * a;
                        force[j] += f * c.e[k] * a;
                    }
                }
            }
            match &solver {
                Ksolve::Factor(f) => {
                    x = f.solve(&rhs);
                    self.inner += 1;
                }
                Ksolve::Multigrid => {
                    let Some(amg) = self.iter.as_ref().and_then(|it| it.amg.as_ref()) else {
                        return Err(QpError::Unsupported(
                            "ssn_path = \"iterative\": no multigrid".into(),
                        ));
                    };
                    // The tolerance is on the contact forces (the scale of
                    // the certificate's balance, §8.4), not on the rhs,
                    // whose Σ ρ b r part cancels against K's ρ bᵀb x.
                    let (fscale, bn) = (norm(&force).max(CONTACT_FLOOR * dnorm), norm(&rhs));
                    let rt = if fscale > 0.0 && bn > 0.0 {
                        (ptol * fscale / bn).min(ptol).max(1e-14)
                    } else {
                        ptol
                    };
                    let prec = |r: &[f64], z: &mut [f64]| amg.apply(r, z);
                    let rep = pcg_stall(&kmat, &rhs, &mut x, &prec, rt, PCG_MAX, PCG_STALL);
                    if let Some(it) = self.iter.as_mut() {
                        it.cg_steps += rep.iterations;
                    }
                    self.inner += rep.iterations;
                    if !(rep.converged || rep.stalled) || !rep.rel_residual.is_finite() {
                        return Err(QpError::Unsupported(format!(
                            "ssn_path = \"iterative\": CG on K stopped at relative residual {:.2e} \
                             after {} steps; ssn_path = \"auto\" factors K instead",
                            rep.rel_residual, rep.iterations
                        )));
                    }
                }
            }
            let mut res = 0.0f64;
            for (b, mk) in rows.iter().zip(mu.iter_mut()) {
                let bx: f64 = b.cols.iter().zip(&b.vals).map(|(&j, &a)| a * x[j]).sum();
                match b.spring {
                    // The spring's force λ⊥ = (w x − r)/κ.
                    Some(k_s) => *mk = k_s * (bx - b.rhs),
                    None => {
                        *mk += b.rho * (bx - b.rhs);
                        res = res.max((bx - b.rhs).abs());
                    }
                }
            }
            let xs = norm_inf(&x).max(bscale).max(f64::MIN_POSITIVE);
            stalled = if res > 0.5 * last * xs {
                stalled + 1
            } else {
                0
            };
            last = res / xs;
            if res <= ptol * xs || stalled >= AL_STALL {
                break;
            }
        }
        Ok((x, mu))
    }
}
