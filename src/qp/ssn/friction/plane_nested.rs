//! The coarse start of ssn on discs (docs/methods.md §12.3): 2D's nested
//! iteration (§9.2, [`super::super::nested`]) on a plane frame's rows. The
//! working sets of coarser contact discretisations, solved in the dual
//! space alone, choose where the problem's own Newton steps start.
//!
//! A coarse level pairs contact points (greedy heavy-edge matching on the
//! correlation (|H_ij| + |H_t1,ij| + |H_t2,ij|)/√(w_i w_j) of the normal and
//! the two tangential blocks, w the diagonal sums) and sums their rows of
//! B = [A; T] component by component: the normal rows, the first
//! tangential rows, the second ones. A pair's frames differ by the turn of
//! the surface between two neighbours, so the summed tangential rows are
//! those of a mean frame; the level only predicts each point's kind
//! (open, stick, slip) and its slip direction, and nothing of it enters
//! the answer or its certificate. Its H is PᵀHP in each block, B K⁻¹d and
//! BR the P-sums, c = [g; t0] the P-sums (the summed gaps and slips), the
//! bounds (μ or s) the means, c and c_t the harmonic sums. Levels are
//! formed until 12 points remain or until pairing no longer removes a
//! quarter of them. The coarsest starts as the problem does (glued for
//! Coulomb, every point with a bound sticking for Tresca); each finer one
//! starts from the kinds and directions of the one below and runs the
//! working-set rule until its kinds settle, repeat, or the cycling budget
//! is spent.

use super::super::dual::DenseDual;
use super::super::nested::{descend, levels, Rows};
use super::dual_space::{dual_row, known_forces, set_multipliers};
use super::{cycle_budget, of_rhs, pattern, predict_disc, set_rows, Disc};
use crate::qp::coulomb_bound;
use std::collections::HashSet;

impl super::State<'_> {
    /// Start the next Newton steps from the kinds of the coarse levels on
    /// the dual path: Coulomb's direct iteration (`mu`) before any glued
    /// solve, or a Tresca problem's first solve at its bound `s`. Their
    /// steps count as inner iterations. Returns whether it did.
    pub(super) fn coarse_start(&mut self, mu: Option<&[f64]>) -> bool {
        let Some(d) = self.dual.as_ref() else {
            return false;
        };
        let rows = Rows {
            g: self.qp.g.clone(),
            t0: self.fr.t0.clone(),
            cn: self.cn.clone(),
            ct: self.ct.clone(),
            bound: mu.map_or_else(|| self.s.clone(), <[f64]>::to_vec),
            in_n: self.in_n.clone(),
        };
        let t = std::time::Instant::now();
        let coulomb = mu.is_some();
        let levels = levels(&d.dense, &rows, 2);
        let Some(cs) = descend(&levels, |dense, rows, start| {
            settle(dense, rows, coulomb, start)
        }) else {
            log::debug!("ssn: discs: no coarse start (too few rows to coarsen, or a coarse system is singular): the method's own start");
            return false;
        };
        log::debug!(
            "ssn: discs: coarse start: (rows, Newton steps) per level {:?}, {:.3} s",
            cs.levels,
            t.elapsed().as_secs_f64()
        );
        self.inner += cs.levels.iter().map(|l| l.1).sum::<usize>();
        // N stays the problem's own where the normal start found it (the
        // frictionless answer's: a summed row is closed when either of
        // its rows is, and a coarse level's N is wider at the contact's
        // edge); the coarse levels give the tangential kinds.
        if self.r.is_empty() {
            self.tang = (0..self.in_n.len())
                .map(|i| match (self.in_n[i], cs.tang[i]) {
                    (false, _) => Disc::Free,
                    (true, Disc::Free) => Disc::Stick,
                    (true, t) => t,
                })
                .collect();
        } else {
            self.in_n = cs.in_n;
            self.tang = cs.tang;
        }
        self.preset = true;
        true
    }
}

/// One working set of a level solved in the dual space: the multipliers
/// on its rows of B and Bx; None if the set's system is singular.
fn set_solve(
    dense: &DenseDual,
    rows: &Rows,
    in_n: &[bool],
    tang: &[Disc],
    s: &[f64],
    law: Option<&[f64]>,
    glued: bool,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let m = rows.g.len();
    let mut known = vec![0.0; 2 * m];
    if !glued {
        for (i, d) in tang.iter().enumerate() {
            if let Disc::Slip(e, _) = d {
                known[2 * i] = -s[i] * e[0];
                known[2 * i + 1] = -s[i] * e[1];
            }
        }
    }
    let drows: Vec<_> = set_rows(in_n, tang)
        .into_iter()
        .filter_map(|of| {
            let c = of_rhs(of, tang, &rows.g, &rows.t0);
            dual_row(of, c, tang, law, &dense.null, &mut known)
        })
        .collect();
    let f = known_forces(&known, m);
    let (w, alpha) = dense.solve_rows(&drows, &f)?;
    let mu = set_multipliers(&drows, &w, f);
    let bx = dense.bx(&mu, &alpha);
    Some((mu, bx))
}

/// The kinds predicted from a level's multipliers `mu` and Bx at bound `s`.
fn predict(rows: &Rows, mu: &[f64], bx: &[f64], s: &[f64], glued: bool) -> (Vec<bool>, Vec<Disc>) {
    let m = rows.g.len();
    let in_n: Vec<bool> = (0..m)
        .map(|i| mu[i] + rows.cn[i] * (bx[i] - rows.g[i]) > 0.0)
        .collect();
    let tang = (0..m)
        .map(|i| {
            let lt = [mu[m + 2 * i], mu[m + 2 * i + 1]];
            let v = [
                bx[m + 2 * i] - rows.t0[2 * i],
                bx[m + 2 * i + 1] - rows.t0[2 * i + 1],
            ];
            predict_disc(in_n[i], glued, s[i], lt, v, rows.ct[i])
        })
        .collect();
    (in_n, tang)
}

/// Working-set steps on one level from `start` (None: the problem's own
/// start) until the kinds settle, repeat, a working set's system is
/// singular or the cycling budget is spent. None if the glued start's
/// system is singular.
fn settle(
    dense: &DenseDual,
    rows: &Rows,
    coulomb: bool,
    start: Option<(Vec<bool>, Vec<Disc>)>,
) -> Option<(Vec<bool>, Vec<Disc>, usize)> {
    let m = rows.g.len();
    let mut steps = 0;
    let mut s = if coulomb {
        vec![0.0; m]
    } else {
        rows.bound.clone()
    };
    let (mut in_n, mut tang) = match start {
        Some(st) => st,
        None if coulomb => {
            // Coulomb's glued start, then s = μλ_n of its answer.
            let tang: Vec<Disc> = rows
                .in_n
                .iter()
                .map(|&a| if a { Disc::Stick } else { Disc::Free })
                .collect();
            let (mu, bx) = set_solve(dense, rows, &rows.in_n, &tang, &s, None, true)?;
            steps += 1;
            s = coulomb_bound(&rows.bound, &mu[..m]);
            predict(rows, &mu, &bx, &s, false)
        }
        None => {
            let tang = s
                .iter()
                .map(|&b| if b > 0.0 { Disc::Stick } else { Disc::Free })
                .collect();
            (rows.in_n.clone(), tang)
        }
    };
    let law = coulomb.then_some(rows.bound.as_slice());
    let mut seen = HashSet::new();
    while steps < cycle_budget(m) && seen.insert(pattern(&in_n, &tang)) {
        // A singular system (a set that leaves a body free) ends the
        // level: its sets so far start the next one.
        let Some((mu, bx)) = set_solve(dense, rows, &in_n, &tang, &s, law, false) else {
            break;
        };
        steps += 1;
        if coulomb {
            s = coulomb_bound(&rows.bound, &mu[..m]);
        }
        let (n1, mut t1) = predict(rows, &mu, &bx, &s, false);
        stick_reversals(&tang, &mut t1);
        let same = pattern(&n1, &t1) == pattern(&in_n, &tang);
        (in_n, tang) = (n1, t1);
        if same {
            break;
        }
    }
    Some((in_n, tang, steps))
}

/// A point predicted to slip against the direction it was solved with
/// (ê·ê' < 0) sticks instead, as in 2D (docs/methods.md §9.2): when the
/// friction forces of the whole interface move it more than the loads do,
/// the reversed prediction flips back the next step.
fn stick_reversals(solved: &[Disc], next: &mut [Disc]) {
    for (t, n) in solved.iter().zip(next.iter_mut()) {
        if let (Disc::Slip(a, _), Disc::Slip(b, _)) = (*t, *n) {
            if a[0] * b[0] + a[1] * b[1] < 0.0 {
                *n = Disc::Stick;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::ssn::friction::nested::{aggregate, pair};
    use faer::Mat;

    /// Points on a line listed out of order, H decaying with distance in
    /// each of the three blocks: every pair is two neighbours, and the
    /// coarse rows sum the fine ones component by component.
    #[test]
    fn points_are_paired_with_their_neighbours_and_summed_by_component() {
        let xs: [f64; 8] = [5.0, 0.0, 3.0, 1.0, 7.0, 2.0, 6.0, 4.0];
        let m = xs.len();
        // Row j of B's point and block (0 normal, 1 and 2 tangential).
        let of = |j: usize| {
            if j < m {
                (j, 0)
            } else {
                ((j - m) / 2, 1 + (j - m) % 2)
            }
        };
        let h = Mat::from_fn(3 * m, 3 * m, |i, j| {
            let ((p, bi), (q, bj)) = (of(i), of(j));
            if bi == bj {
                (-(xs[p] - xs[q]).abs()).exp()
            } else {
                0.0
            }
        });
        let d = DenseDual {
            h: std::rc::Rc::new(h),
            bk0: (0..3 * m).map(|j| j as f64).collect(),
            br: vec![vec![]; 3 * m],
            e: vec![],
            null: (0..3 * m).map(|j| j == m + 2 * 3 + 1).collect(),
            last_lu: Default::default(),
        };
        let groups = pair(&d, m, 2);
        assert_eq!(groups.len(), 5, "{groups:?}");
        for g in groups.iter().filter(|g| g.len() == 2) {
            assert!((xs[g[0]] - xs[g[1]]).abs() == 1.0, "{groups:?}");
        }
        let rows = Rows {
            g: vec![0.0; m],
            t0: (0..2 * m).map(|j| j as f64).collect(),
            cn: vec![2.0; m],
            ct: vec![1.0; m],
            bound: (0..m).map(|i| i as f64).collect(),
            in_n: (0..m).map(|i| i == 3).collect(),
        };
        let l = aggregate(&d, &rows, groups.clone(), 2);
        let mc = groups.len();
        let pair = groups.iter().position(|g| g.len() == 2).unwrap();
        let g = &groups[pair];
        // The second tangential row of a pair sums its members' second rows.
        let want: f64 = g.iter().map(|&i| (m + 2 * i + 1) as f64).sum();
        assert_eq!(l.dense.bk0[mc + 2 * pair + 1], want);
        assert_eq!(
            l.rows.t0[2 * pair + 1],
            g.iter().map(|&i| (2 * i + 1) as f64).sum::<f64>()
        );
        let mut hw = 0.0;
        for &i in g {
            for &j in g {
                hw += d.h[(m + 2 * i, m + 2 * j)];
            }
        }
        assert_eq!(l.dense.h[(mc + 2 * pair, mc + 2 * pair)], hw);
        // No coupling across blocks survives the sums.
        assert_eq!(l.dense.h[(pair, mc + 2 * pair)], 0.0);
        // A coarse row holds nothing only if all its members' rows do.
        let holds3 = groups.iter().position(|g| g.contains(&3)).unwrap();
        assert_eq!(l.dense.null[mc + 2 * holds3 + 1], groups[holds3].len() == 1);
        assert!(l.rows.in_n[holds3] && l.rows.in_n.iter().filter(|b| **b).count() == 1);
        assert_eq!((l.rows.cn[pair], l.rows.ct[pair]), (1.0, 0.5));
    }

    /// Slips predicted against the direction solved with stick instead;
    /// a turn of less than a right angle keeps slipping.
    #[test]
    fn reversed_slips_stick() {
        let solved = [Disc::Slip([1.0, 0.0], 0.0), Disc::Slip([0.0, 1.0], 0.0)];
        let mut next = [Disc::Slip([-0.9, 0.1], 1.0), Disc::Slip([0.5, 0.5], 1.0)];
        stick_reversals(&solved, &mut next);
        assert_eq!(next[0], Disc::Stick);
        assert!(matches!(next[1], Disc::Slip(..)));
    }
}
