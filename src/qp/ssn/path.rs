//! Which linear algebra an SSN step uses (docs/methods.md §7), decided from
//! counts only, so that the same input takes the same path on every run.
//! The symbolic analyses of C and of C + AᵀA (AMD order), kept in the
//! workspace for the factorizations that follow, give nnz(L) and Σⱼcⱼ² per
//! factor. In entries of L read by a solve: a
//! factorisation costs Σⱼcⱼ²/[`FLOPS_PER_ENTRY`], a solve nnz(L), one column
//! of a blocked solve [`COL_FRACTION`]·nnz(L). The first step takes the Schur
//! path when fac(C) + |J|·col(C) ≤ fac(K) + 6·solve(K). Later the Schur path
//! costs [C not factored]·fac(C) + (rows new to J)·col(C), the augmented one
//! min(fac(K), (changed rows)·col(K)) + 6·solve(K), and Schur is taken when it
//! is at most k times that, k = 1 in the second step and 3 later (J still
//! moving: more steps follow, and Schur's columns are paid once).
//! the setting `ssn_path` forces a path; `iterative` leaves this module for
//! `iterative` (no factor at all).

use super::lowrank::LOWRANK_MAX;
use super::Ssn;
use crate::linalg::augmented::AugPattern;
use crate::linalg::cholesky::Workspace;
use crate::qp::{QpError, QpProblem};

/// Cost of one column in a blocked solve of BLOCK right-hand sides, as a
/// fraction of one single solve (32 columns took ≈ 5.6 single solves on the
/// 43k-node three-body model).
const COL_FRACTION: f64 = 0.2;
/// Multiply–adds of a supernodal factorization done in the time a solve
/// reads one entry of L (dense BLAS-3 kernels against a memory-bound
/// triangular solve: on a 69k-DOF punch model, 9.6e8 multiply–adds took
/// 0.56 s and a solve over 5.3e6 entries ≈ 0.05 s, a ratio of ≈ 17; 10 is
/// used, between that and the smaller shipped models).
const FLOPS_PER_ENTRY: f64 = 10.0;

/// Which linear algebra the KKT solves use (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Path {
    /// Chosen per step by the count-based cost model.
    Auto,
    /// Always K_J = C + A_JᵀΡA_J (falls back to Schur only when it fails).
    Augmented,
    /// Augmented, refactoring K_J at every step (no low-rank updates).
    Refactor,
    /// Always the Schur complement on one factor of C.
    Schur,
}

/// Counted costs of the two paths (module doc), in entries of L read by a solve.
#[derive(Debug, Clone, Copy)]
pub(super) struct Costs {
    pub(super) fac_c: f64,
    pub(super) solve_c: f64,
    pub(super) fac_k: f64,
    pub(super) solve_k: f64,
}

impl Costs {
    /// The counts from the symbolic analyses, which `ws` keeps for the
    /// factorizations that follow.
    pub(super) fn new(
        qp: &QpProblem,
        aug: Option<&AugPattern>,
        ws: &Workspace,
    ) -> Result<Costs, QpError> {
        let k = match aug {
            Some(a) => ws.factor_cost(a.matrix())?,
            None => ws.factor_cost(&qp.c)?,
        };
        // C last: the most recent analysis kept (the next factor is C's).
        let c = ws.factor_cost(&qp.c)?;
        log::debug!(
            "ssn: counts: C: nnz(L) {:.3e}, Σc² {:.3e}; C + AᵀA: nnz(L) {:.3e}, Σc² {:.3e}",
            c.nnz,
            c.flops,
            k.nnz,
            k.flops
        );
        Ok(Costs {
            fac_c: c.flops / FLOPS_PER_ENTRY,
            solve_c: c.nnz,
            fac_k: k.flops / FLOPS_PER_ENTRY,
            solve_k: k.nnz,
        })
    }
    pub(super) fn col_c(&self) -> f64 {
        COL_FRACTION * self.solve_c
    }
    pub(super) fn col_k(&self) -> f64 {
        COL_FRACTION * self.solve_k
    }
}

impl Ssn<'_> {
    /// The cost model of the module doc (counts only): true to take the
    /// Schur path for `in_j`.
    pub(super) fn prefer_schur(&self, in_j: &[bool]) -> bool {
        if !self.auto {
            return false;
        }
        let c = &self.costs;
        let nj = in_j.iter().filter(|b| **b).count() as f64;
        if self.fac.is_none() && self.kfac.is_none() {
            // Nothing factored yet: both paths need one factorization.
            return c.fac_c + nj * c.col_c() <= c.fac_k + 6.0 * c.solve_k;
        }
        let new_rows = in_j
            .iter()
            .zip(self.h.iter())
            .filter(|(j, h)| **j && h.is_none())
            .count();
        let schur = if self.fac.is_some() { 0.0 } else { c.fac_c } + new_rows as f64 * c.col_c();
        // The augmented step: a refactor, or a low-rank update of K' when few
        // rows changed since it was factored.
        let changed = self.kfac_set.as_ref().map_or(usize::MAX, |jb| {
            (0..jb.len())
                .filter(|&i| jb[i] != in_j[i] && !self.zcache.contains_key(&i))
                .count()
        });
        let aug_fac = if changed <= LOWRANK_MAX {
            c.fac_k.min(changed as f64 * c.col_k())
        } else {
            c.fac_k
        };
        // steps_done counts this step: k = 1 in the second, 3 from the third.
        let k = if self.steps_done >= 3 { 3.0 } else { 1.0 };
        schur <= k * (aug_fac + 6.0 * c.solve_k)
    }
}
