//! ssn on discs in the dual space (docs/methods.md §12.3): the working
//! sets of a plane frame solved on the one bordered factor of C that 2D's
//! dual path keeps ([`Dual`], B = [A; T] with each contact row's
//! tangential pair), a dense system on the set's rows per Newton step, x
//! formed once a solve ends. The sparse path refactored K = C + ρBᵀB at
//! every Newton step: 37 times the frictionless run on the coarse
//! Cattaneo–Mindlin sphere (docs/verification_3d.md §7g).

use super::super::dual::{unfinished, DualRow};
use super::{BRow, Disc, Of, State};
use crate::linalg::sparse::Csr;
use crate::qp::QpError;

/// The most steps of [`State::normal_start`].
const NORMAL_START_MAX: usize = 50;

impl State<'_> {
    /// Solve the working set whose rows of B are `rows`, under the known
    /// slip forces −`known` on T's rows, in the dual space: a stick row
    /// holds its tangential pair, a slipping row e⊥·T_i with its
    /// compliance κ (the Newton step of the disc law across the slip)
    /// exactly, where the sparse path chose between a spring and a
    /// constraint. Returns false (the step goes to the sparse path) when
    /// there is no dual form or the set's system is singular.
    pub(super) fn solve_set_dual(&mut self, rows: &[BRow], known: &[f64]) -> bool {
        let Some(d) = self.dual.as_ref() else {
            return false;
        };
        let m = self.qp.m();
        let mut known = known.to_vec();
        let mut drows = Vec::with_capacity(rows.len());
        let coulomb = self.coulomb.as_deref().filter(|_| !self.glued);
        for b in rows {
            // A row of B that moves nothing K⁻¹ reaches but holds a rigid
            // motion (it touches only a floating body's fixing unknowns: a
            // single point) has no place in H_JJ.
            if let Some(&(j, _)) = of_terms(b.of, &self.tang, m)
                .0
                .iter()
                .find(|&&(j, w)| w != 0.0 && d.null[j] && holds_motion(d, j))
            {
                log::debug!(
                    "ssn: discs: row {j} holds a rigid motion K⁻¹ does not reach: the sparse path"
                );
                return false;
            }
            if let Some(r) = dual_row(b.of, b.rhs, &self.tang, coulomb, &d.null, &mut known) {
                drows.push(r);
            }
        }
        let f = known_forces(&known, m);
        let Some((w, alpha)) = d.solve_rows(&drows, &f) else {
            log::debug!("ssn: discs: the working set's dual system is singular: the sparse path");
            return false;
        };
        let mu = set_multipliers(&drows, &w, f);
        let bx = d.bx(&mu, &alpha);
        self.ax = bx[..m].to_vec();
        self.tx = bx[m..].to_vec();
        self.ln = mu[..m].to_vec();
        self.lt = mu[m..].to_vec();
        self.mu = mu;
        self.alpha = alpha;
        self.x_stale = true;
        true
    }

    /// The glued solve's normal set from the frictionless problem's, found
    /// as the frictionless path's dense start finds it (docs/methods.md §7,
    /// §12.3): active-set steps on the normal rows alone, each a dense
    /// system of |N| rows of H, until N repeats. The glued Newton steps
    /// that did this each held 3|N| rows (Cattaneo hc 0.0075: 1 103 → 630
    /// rows in 7 steps, 0.9 s; here 0.08 s). Only without rigid modes: a
    /// floating body's start is [`State::hold_free_bodies`]'s. Counted as
    /// inner iterations, not Newton steps, as the frictionless path counts
    /// its dense start.
    pub(super) fn normal_start(&mut self) {
        let Some(d) = self.dual.as_ref() else {
            return;
        };
        if !self.r.is_empty() {
            return;
        }
        let (qp, m) = (self.qp, self.qp.m());
        let mut seen = std::collections::HashSet::new();
        let mut steps = 0;
        while steps < NORMAL_START_MAX && seen.insert(self.in_n.clone()) {
            let rows: Vec<DualRow> = (0..m)
                .filter(|&i| self.in_n[i] && !d.null[i])
                .map(|i| DualRow {
                    terms: vec![(i, 1.0)],
                    c: qp.g[i],
                    kappa: 0.0,
                    force: vec![],
                })
                .collect();
            let f = vec![0.0; 3 * m];
            let Some((w, alpha)) = d.solve_rows(&rows, &f) else {
                break;
            };
            steps += 1;
            let mut mu = f;
            for (r, wj) in rows.iter().zip(&w) {
                mu[r.terms[0].0] = *wj;
            }
            let ax = d.bx(&mu, &alpha);
            let next: Vec<bool> = (0..m)
                .map(|i| mu[i] + self.cn[i] * (ax[i] - qp.g[i]) > 0.0)
                .collect();
            if next == self.in_n {
                break;
            }
            self.in_n = next;
        }
        self.inner += steps;
        log::debug!(
            "ssn: discs: normal start: {steps} steps in the dual space, |N| = {}",
            self.in_n.iter().filter(|a| **a).count()
        );
    }

    /// Form x from the last dual-space answer if it is not yet: one
    /// backward pass on the bordered factor, x = K⁻¹(d − Bᵀμ) + Rα.
    pub(super) fn ensure_x(&mut self) -> Result<(), QpError> {
        if !self.x_stale {
            return Ok(());
        }
        let d = self.dual.as_ref().ok_or_else(unfinished)?;
        self.x = d.x(&self.mu, &self.alpha, &self.r).ok_or_else(unfinished)?;
        self.inner += 1;
        self.x_stale = false;
        Ok(())
    }
}

/// The rows of B a working-set row `of` combines, with their weights, and
/// its compliance κ (a slipping row's force across its direction).
fn of_terms(of: Of, tang: &[Disc], m: usize) -> (Vec<(usize, f64)>, f64) {
    match of {
        Of::Normal(i) => (vec![(i, 1.0)], 0.0),
        Of::Tangential(i, k) => (vec![(m + 2 * i + k, 1.0)], 0.0),
        Of::Across(i) => match tang[i] {
            Disc::Slip(e, kappa) => (vec![(m + 2 * i, -e[1]), (m + 2 * i + 1, e[0])], kappa),
            _ => (vec![], 0.0),
        },
    }
}

/// The dual-space row of the working-set row `of` (right-hand side `c`),
/// None when it holds nothing: a row of B with H_jj = 0 (`null`) is left
/// out, its multiplier 0, as in 2D. With Coulomb's coefficients
/// (`coulomb`: the direct iteration), a slipping row's force along ê is
/// μλ_n of the step's own λ_n, a force its normal row's multiplier sets on
/// the tangential pair, not the last iterate's s in `known` (Newton's step
/// on s = μλ_n; before, a fixed point inside the step, by about 10× an
/// update; docs/methods.md §12.3).
pub(super) fn dual_row(
    of: Of,
    c: f64,
    tang: &[Disc],
    coulomb: Option<&[f64]>,
    null: &[bool],
    known: &mut [f64],
) -> Option<DualRow> {
    let m = tang.len();
    let (terms, kappa) = of_terms(of, tang, m);
    let terms: Vec<(usize, f64)> = terms
        .into_iter()
        .filter(|&(j, w)| !null[j] && w != 0.0)
        .collect();
    if terms.is_empty() {
        return None;
    }
    let mut force = vec![];
    if let (Of::Normal(i), Some(mu_c), Disc::Slip(e, _)) = (of, coulomb, tang[of_row(of)]) {
        force = (0..2)
            .map(|k| (m + 2 * i + k, mu_c[i] * e[k]))
            .filter(|&(j, w)| !null[j] && w != 0.0)
            .collect();
        known[2 * i] = 0.0;
        known[2 * i + 1] = 0.0;
    }
    Some(DualRow {
        terms,
        c,
        kappa,
        force,
    })
}

/// The contact row a working-set row belongs to.
fn of_row(of: Of) -> usize {
    match of {
        Of::Normal(i) | Of::Tangential(i, _) | Of::Across(i) => i,
    }
}

/// The known forces on B's rows: −`known` on T's rows (2 per contact row).
pub(super) fn known_forces(known: &[f64], m: usize) -> Vec<f64> {
    let mut f = vec![0.0; 3 * m];
    for (fj, k) in f[m..].iter_mut().zip(known) {
        *fj = -k;
    }
    f
}

/// The multipliers on B's rows of a dual-space set solve: the known forces
/// `f` plus each row's multiplier `w` on the rows it combines and the
/// forces it sets.
pub(super) fn set_multipliers(rows: &[DualRow], w: &[f64], f: Vec<f64>) -> Vec<f64> {
    let mut mu = f;
    for (r, wj) in rows.iter().zip(w) {
        for &(j, c) in r.terms.iter().chain(&r.force) {
            mu[j] += c * wj;
        }
    }
    mu
}

/// Whether row j of B moves a rigid motion: |(B R)_j| beyond round-off of
/// the row's size (R is orthonormal).
fn holds_motion(d: &super::super::dual::Dual, j: usize) -> bool {
    let size = d.b.row(j).1.iter().map(|v| v * v).sum::<f64>().sqrt();
    d.br[j].iter().any(|v| v.abs() > 1e-12 * size)
}

/// Σ_k w_k T_{2i+k}: one combination of row i's tangential pair, columns
/// sorted (the two rows touch the same points; a column one of them lacks
/// counts as 0 there).
pub(super) fn combine(t: &Csr, i: usize, w: [f64; 2]) -> (Vec<usize>, Vec<f64>) {
    let mut e: Vec<(usize, f64)> = vec![];
    for (k, wk) in w.iter().enumerate() {
        let (c, v) = t.row(2 * i + k);
        e.extend(c.iter().zip(v).map(|(&j, &a)| (j, wk * a)));
    }
    e.sort_by_key(|p| p.0);
    let mut cols: Vec<usize> = vec![];
    let mut vals: Vec<f64> = vec![];
    for (j, a) in e {
        if cols.last() == Some(&j) {
            *vals.last_mut().unwrap_or(&mut 0.0) += a;
        } else {
            cols.push(j);
            vals.push(a);
        }
    }
    (cols, vals)
}
