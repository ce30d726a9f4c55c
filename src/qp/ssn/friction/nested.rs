//! The coarse start of frictional ssn (docs/methods.md §9.2): the working
//! sets of coarser contact discretisations, solved in the dual space alone,
//! start the Newton steps on the problem's own rows.
//!
//! Why: a sticking row is released only when its own force exceeds its
//! bound, and releasing it loads its neighbour. From the glued start the
//! front of a slip zone therefore moves one or two rows per Newton step,
//! so the count followed the number of rows in the slip zone (the floating
//! punch: 3 / 5 / 7 steps at 21 / 46 / 101 rows). A coarse level places
//! the front to within its own rows' width; taken row by row, its sets
//! leave the next finer level a front one or two rows off. Each level thus
//! needs a bounded number of steps: nested iteration, as the full
//! multigrid cycle starts each grid from the one below it.
//!
//! A coarse level pairs rows (greedy heavy-edge matching on the
//! correlation (|H_ij| + |H_tij|)/√(w_i w_j) of the normal and tangential
//! blocks, w the diagonal sums: rows that are neighbours along an
//! interface couple most) and restricts the multipliers to λ = PΛ, P with
//! one 1 per fine row. Its H is PᵀHP in each block, its B K⁻¹d, BR and
//! c = [g; t0] are P-sums of the fine ones (PᵀB x ≤ Pᵀc: the summed gaps and
//! slips), its bounds (μ or s) the means, and its c, c_t the harmonic sums
//! (the stiffness a summed row meets). Levels are formed until 12 rows or
//! until pairing no longer reduces the rows by a quarter. The coarsest
//! level starts as the problem does (glued); each finer one starts from the
//! sets of the one below (as the coarsest does if those are singular there)
//! and runs the working-set rule ([`Rule`]) until its sets settle, repeat,
//! or the cycling budget is spent. Nothing of a
//! coarse level enters the answer or its certificate: it only chooses where
//! the problem's own Newton steps start.

use super::dual::{DenseDual, Law};
use super::{cycle_budget, start_tang, Rule, Tangential};
use crate::qp::coulomb_bound;
use faer::Mat;
use std::collections::HashSet;

/// A level with at most this many rows is not coarsened further.
const MIN_ROWS: usize = 12;

/// A row is paired only with a row it couples with at least this fraction
/// of its strongest coupling: a row whose neighbours are taken stays alone
/// rather than being summed with a distant one.
const PAIR_FRACTION: f64 = 0.5;

/// The rows' data of one level (the problem's own, or a coarse one), per
/// contact point: `t0` holds the point's tangential rows (one in 2D, two on
/// discs, `plane_nested.rs`).
pub(super) struct Rows {
    pub(super) g: Vec<f64>,
    pub(super) t0: Vec<f64>,
    pub(super) cn: Vec<f64>,
    pub(super) ct: Vec<f64>,
    /// μ (Coulomb) or s (Tresca) per point.
    pub(super) bound: Vec<f64>,
    /// The points in normal contact at the start.
    pub(super) in_n: Vec<bool>,
}

/// One coarse level: its dual form, its rows, and the points of the level
/// above (finer) that each of its points sums.
pub(super) struct Level {
    pub(super) dense: DenseDual,
    pub(super) rows: Rows,
    pub(super) groups: Vec<Vec<usize>>,
}

/// What the coarse start reads of the problem's own rows.
pub(super) struct Fine<'a> {
    pub(super) dense: &'a DenseDual,
    pub(super) g: &'a [f64],
    pub(super) t0: &'a [f64],
    pub(super) cn: &'a [f64],
    pub(super) ct: &'a [f64],
    /// Coulomb's problem (bound = μ) or a Tresca problem (bound = s).
    pub(super) coulomb: bool,
    pub(super) bound: &'a [f64],
    pub(super) in_n: &'a [bool],
}

/// The sets the coarse levels predict for the problem's points (`T`: a
/// point's tangential kind, [`Tangential`] in 2D, `Disc` on discs), and the
/// Newton steps each level took (finest coarse level first).
pub(super) struct CoarseStart<T> {
    pub(super) in_n: Vec<bool>,
    pub(super) tang: Vec<T>,
    /// (points, Newton steps) per coarse level.
    pub(super) levels: Vec<(usize, usize)>,
}

/// The coarse start of `fine`, or None when it has too few rows to
/// coarsen or a coarse system is singular (the problem then starts as
/// without it).
pub(super) fn coarse_start(fine: &Fine<'_>) -> Option<CoarseStart<Tangential>> {
    let top = Rows {
        g: fine.g.to_vec(),
        t0: fine.t0.to_vec(),
        cn: fine.cn.to_vec(),
        ct: fine.ct.to_vec(),
        bound: fine.bound.to_vec(),
        in_n: fine.in_n.to_vec(),
    };
    let levels = levels(fine.dense, &top, 1);
    descend(&levels, |dense, rows, start| {
        settle(dense, rows, fine.coulomb, start)
    })
}

/// The coarse levels of the dual form `fine` and its rows `top`, `tdim`
/// tangential rows per point (B = [A; T]: m normal rows, then `tdim` per
/// point), finest first: pairs are summed until [`MIN_ROWS`] points remain
/// or pairing no longer removes a quarter of them.
pub(super) fn levels(fine: &DenseDual, top: &Rows, tdim: usize) -> Vec<Level> {
    let mut levels: Vec<Level> = vec![];
    loop {
        let (dense, rows) = levels.last().map_or((fine, top), |l| (&l.dense, &l.rows));
        let m = rows.g.len();
        if m <= MIN_ROWS {
            break;
        }
        let groups = pair(dense, m, tdim);
        if 4 * groups.len() > 3 * m {
            break;
        }
        let level = aggregate(dense, rows, groups, tdim);
        levels.push(level);
    }
    levels
}

/// Nested iteration down the `levels` (module head): the coarsest settles
/// from the problem's own start, each finer one from the sets of the one
/// below (from its own start if those are singular there), and the
/// problem's points take the finest coarse level's sets. `settle` runs one
/// level's working-set steps from a start (None: the problem's own) and
/// returns its sets and steps, None when that start is singular.
pub(super) fn descend<T: Copy>(
    levels: &[Level],
    settle: impl Fn(
        &DenseDual,
        &Rows,
        Option<(Vec<bool>, Vec<T>)>,
    ) -> Option<(Vec<bool>, Vec<T>, usize)>,
) -> Option<CoarseStart<T>> {
    let coarsest = levels.last()?;
    let mut counts = vec![0; levels.len()];
    let (mut in_n, mut tang, steps) = settle(&coarsest.dense, &coarsest.rows, None)?;
    counts[levels.len() - 1] = steps;
    for l in (0..levels.len() - 1).rev() {
        let start = prolong(&levels[l + 1].groups, &in_n, &tang);
        let (dense, rows) = (&levels[l].dense, &levels[l].rows);
        let (mut n1, mut t1, mut steps) = settle(dense, rows, Some(start))?;
        if steps == 0 {
            // The sets from below are singular here (the level below was
            // too coarse to hold a body: one row under a disc leaves its
            // rotation free): this level starts as the coarsest does.
            (n1, t1, steps) = settle(dense, rows, None)?;
        }
        counts[l] = steps;
        (in_n, tang) = (n1, t1);
    }
    let (in_n, tang) = prolong(&levels[0].groups, &in_n, &tang);
    Some(CoarseStart {
        in_n,
        tang,
        levels: levels
            .iter()
            .zip(counts)
            .map(|(l, c)| (l.groups.len(), c))
            .collect(),
    })
}

/// The sets of a level's points taken by the points of the level above.
fn prolong<T: Copy>(groups: &[Vec<usize>], in_n: &[bool], tang: &[T]) -> (Vec<bool>, Vec<T>) {
    let m: usize = groups.iter().map(Vec::len).sum();
    let mut owner = vec![0; m];
    for (a, g) in groups.iter().enumerate() {
        for &i in g {
            owner[i] = a;
        }
    }
    (
        owner.iter().map(|&a| in_n[a]).collect(),
        owner.iter().map(|&a| tang[a]).collect(),
    )
}

/// Working-set steps on one level from `start` (None: the problem's own
/// start, glued for Coulomb, every row with a bound sticking for Tresca)
/// until the sets settle, repeat, a working set's system is singular or
/// the cycling budget is spent. None if the glued start's system is
/// singular.
fn settle(
    dense: &DenseDual,
    rows: &Rows,
    coulomb: bool,
    start: Option<(Vec<bool>, Vec<Tangential>)>,
) -> Option<(Vec<bool>, Vec<Tangential>, usize)> {
    let m = rows.g.len();
    let mut c = rows.g.clone();
    c.extend_from_slice(&rows.t0);
    let rule = Rule {
        g: &rows.g,
        t0: &rows.t0,
        cn: &rows.cn,
        ct: &rows.ct,
        forced: Some(&dense.null[m..]),
    };
    let slip_bound = |ln: &[f64]| coulomb_bound(&rows.bound, ln);
    let mut steps = 0;
    let (mut in_n, mut tang) = match start {
        Some(s) => s,
        None if coulomb => {
            // Coulomb's glued start, then s = μλ_n of its answer.
            let zero = vec![0.0; m];
            let tang = start_tang(&rows.in_n, &zero, true);
            let law = Law::Tresca {
                s: &zero,
                glued: true,
            };
            let sol = dense.set_solve(&rows.in_n, &tang, law, &c)?;
            steps += 1;
            let (ln, lt) = sol.mu.split_at(m);
            let bx = dense.bx(&sol.mu, &sol.alpha);
            rule.predict(&bx, ln, lt, &slip_bound(ln), false)
        }
        None => (
            rows.in_n.clone(),
            start_tang(&rows.in_n, &rows.bound, false),
        ),
    };
    let law = if coulomb {
        Law::Coulomb(&rows.bound)
    } else {
        Law::Tresca {
            s: &rows.bound,
            glued: false,
        }
    };
    let mut seen: HashSet<(Vec<bool>, Vec<Tangential>)> = HashSet::new();
    while steps < cycle_budget(m) && seen.insert((in_n.clone(), tang.clone())) {
        // A singular system (a set that leaves a body free under Coulomb's
        // law) ends the level: its sets so far start the next one.
        let Some(sol) = dense.set_solve(&in_n, &tang, law, &c) else {
            break;
        };
        steps += 1;
        let (ln, lt) = sol.mu.split_at(m);
        let s = if coulomb {
            slip_bound(ln)
        } else {
            rows.bound.clone()
        };
        let bx = dense.bx(&sol.mu, &sol.alpha);
        let mut next = rule.predict(&bx, ln, lt, &s, false);
        stick_reversals(&tang, &mut next.1);
        if next.0 == in_n && next.1 == tang {
            break;
        }
        (in_n, tang) = next;
    }
    Some((in_n, tang, steps))
}

/// A row predicted to slip against the direction it was solved with
/// sticks instead (docs/methods.md §9.2): a coarse level only chooses where
/// the Newton steps start, and when the friction forces of the whole
/// interface move it more than the loads do, the reversed prediction flips
/// back the next step (a shrink fit pushed out: every row slipping one way,
/// then the other, for ever; its answer sticks on 283 of 401 rows).
fn stick_reversals(solved: &[Tangential], next: &mut [Tangential]) {
    for (t, n) in solved.iter().zip(next.iter_mut()) {
        if let (Tangential::Slip(a), Tangential::Slip(b)) = (*t, *n) {
            if a != b {
                *n = Tangential::Stick;
            }
        }
    }
}

/// Pairs of points that couple most: [`heavy_edge_pairs`] on the
/// correlation (Σ|H_ab|)/√(w_i w_j) over the point's normal row and its
/// `tdim` tangential rows (B = [A; T]: m normal rows, then `tdim` per
/// point), w the sums of their diagonal entries.
pub(super) fn pair(d: &DenseDual, m: usize, tdim: usize) -> Vec<Vec<usize>> {
    let h = &d.h;
    let idx = |i: usize| std::iter::once(i).chain((0..tdim).map(move |k| m + tdim * i + k));
    let w: Vec<f64> = (0..m).map(|i| idx(i).map(|a| h[(a, a)]).sum()).collect();
    let corr = |i: usize, j: usize| -> f64 {
        let den = (w[i] * w[j]).sqrt();
        if den > 0.0 {
            idx(i)
                .zip(idx(j))
                .map(|(a, b)| h[(a, b)].abs())
                .sum::<f64>()
                / den
        } else {
            0.0
        }
    };
    heavy_edge_pairs(m, corr)
}

/// Greedy heavy-edge matching of `m` rows (or points) on the coupling
/// `corr` (module head): taken in the order of their strongest coupling,
/// ties by index, each paired with its strongest free partner if that is
/// at least [`PAIR_FRACTION`] of its strongest, else a group of its own.
/// The same pairs for the same couplings. Shared by 2D's rows and the
/// discs' points (`plane_nested.rs`).
pub(super) fn heavy_edge_pairs(m: usize, corr: impl Fn(usize, usize) -> f64) -> Vec<Vec<usize>> {
    let best: Vec<f64> = (0..m)
        .map(|i| {
            (0..m)
                .filter(|&j| j != i)
                .map(|j| corr(i, j))
                .fold(0.0, f64::max)
        })
        .collect();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| best[b].total_cmp(&best[a]).then(a.cmp(&b)));
    let mut taken = vec![false; m];
    let mut groups = vec![];
    for i in order {
        if taken[i] {
            continue;
        }
        taken[i] = true;
        let partner = (0..m)
            .filter(|&j| !taken[j])
            .map(|j| (corr(i, j), j))
            .filter(|(c, _)| *c > 0.0 && *c >= PAIR_FRACTION * best[i])
            .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
        match partner {
            Some((_, j)) => {
                taken[j] = true;
                groups.push(vec![i, j]);
            }
            None => groups.push(vec![i]),
        }
    }
    groups
}

/// Per group, the harmonic sum 1/Σ 1/vᵢ of its members' values (the
/// stiffness a summed row meets).
fn harmonic_sums(groups: &[Vec<usize>], v: &[f64]) -> Vec<f64> {
    groups
        .iter()
        .map(|g| 1.0 / g.iter().map(|&i| 1.0 / v[i]).sum::<f64>())
        .collect()
}

/// Per group, the mean of its members' values.
fn means(groups: &[Vec<usize>], v: &[f64]) -> Vec<f64> {
    groups
        .iter()
        .map(|g| g.iter().map(|&i| v[i]).sum::<f64>() / g.len() as f64)
        .collect()
}

/// The level whose points sum the `groups` of `rows` (module head), `tdim`
/// tangential rows per point: each coarse row sums its members' rows of
/// the same kind (normal, k-th tangential).
pub(super) fn aggregate(d: &DenseDual, rows: &Rows, groups: Vec<Vec<usize>>, tdim: usize) -> Level {
    let m = rows.g.len();
    let mc = groups.len();
    let nb = (1 + tdim) * m;
    let nc = (1 + tdim) * mc;
    let mut owner = vec![0; m];
    for (a, g) in groups.iter().enumerate() {
        for &i in g {
            owner[i] = a;
        }
    }
    // Row j of B on the coarse level.
    let to = |j: usize| {
        if j < m {
            owner[j]
        } else {
            let (p, k) = ((j - m) / tdim, (j - m) % tdim);
            mc + tdim * owner[p] + k
        }
    };
    let mut h = Mat::<f64>::zeros(nc, nc);
    for j in 0..nb {
        let cj = to(j);
        for (i, v) in d.h.col(j).iter().enumerate() {
            h[(to(i), cj)] += v;
        }
    }
    let k = d.e.len();
    let mut bk0 = vec![0.0; nc];
    let mut br = vec![vec![0.0; k]; nc];
    let mut null = vec![true; nc];
    for j in 0..nb {
        let c = to(j);
        bk0[c] += d.bk0[j];
        for (o, v) in br[c].iter_mut().zip(&d.br[j]) {
            *o += v;
        }
        null[c] &= d.null[j];
    }
    let sum = |v: &[f64], stride: usize, k: usize| -> Vec<f64> {
        groups
            .iter()
            .map(|g| g.iter().map(|&i| v[stride * i + k]).sum())
            .collect()
    };
    let t0: Vec<Vec<f64>> = (0..tdim).map(|k| sum(&rows.t0, tdim, k)).collect();
    let rows_c = Rows {
        g: sum(&rows.g, 1, 0),
        t0: (0..tdim * mc).map(|j| t0[j % tdim][j / tdim]).collect(),
        cn: harmonic_sums(&groups, &rows.cn),
        ct: harmonic_sums(&groups, &rows.ct),
        bound: means(&groups, &rows.bound),
        in_n: groups
            .iter()
            .map(|g| g.iter().any(|&i| rows.in_n[i]))
            .collect(),
    };
    Level {
        dense: DenseDual {
            h: std::rc::Rc::new(h),
            bk0,
            br,
            e: d.e.clone(),
            null,
            last_lu: Default::default(),
        },
        rows: rows_c,
        groups,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows at the points xᵢ of a line, listed out of order, with H
    /// decaying with distance: every pair is two neighbours.
    #[test]
    fn rows_are_paired_with_their_neighbours() {
        let xs: [f64; 8] = [5.0, 0.0, 3.0, 1.0, 7.0, 2.0, 6.0, 4.0];
        let m = xs.len();
        let h = Mat::from_fn(2 * m, 2 * m, |i, j| {
            let (a, b) = (xs[i % m], xs[j % m]);
            if (i < m) == (j < m) {
                (-(a - b).abs()).exp()
            } else {
                0.0
            }
        });
        let d = DenseDual {
            h: std::rc::Rc::new(h),
            bk0: (0..2 * m).map(|j| j as f64).collect(),
            br: vec![vec![]; 2 * m],
            e: vec![],
            null: vec![false; 2 * m],
            last_lu: Default::default(),
        };
        // Greedy: 5–6, 0–1, 2–3; then 7 and 4, whose neighbours are
        // taken, stay alone instead of being summed with each other.
        let groups = pair(&d, m, 1);
        assert_eq!(groups.len(), 5, "{groups:?}");
        for g in groups.iter().filter(|g| g.len() == 2) {
            assert!((xs[g[0]] - xs[g[1]]).abs() == 1.0, "{groups:?}");
        }
        assert_eq!(groups.iter().filter(|g| g.len() == 1).count(), 2);
        // The coarse H sums the blocks: its entries are the fine ones' sums.
        let rows = Rows {
            g: vec![0.0; m],
            t0: vec![0.0; m],
            cn: vec![2.0; m],
            ct: vec![1.0; m],
            bound: (0..m).map(|i| i as f64).collect(),
            in_n: (0..m).map(|i| i == 3).collect(),
        };
        let l = aggregate(&d, &rows, groups.clone(), 1);
        let (a, b) = (&groups[0], &groups[1]);
        let mut want = 0.0;
        for &i in a {
            for &j in b {
                want += d.h[(i, j)];
            }
        }
        assert_eq!(l.dense.h[(0, 1)], want);
        assert_eq!(l.dense.h[(0, 5 + 1)], 0.0);
        let pair = groups.iter().position(|g| g.len() == 2).unwrap();
        let alone = groups.iter().position(|g| g.len() == 1).unwrap();
        assert_eq!((l.rows.cn[pair], l.rows.cn[alone]), (1.0, 2.0));
        let holds3 = groups.iter().position(|g| g.contains(&3)).unwrap();
        assert!(l.rows.in_n[holds3] && l.rows.in_n.iter().filter(|b| **b).count() == 1);
        assert_eq!(l.rows.bound[0], (a[0] + a[1]) as f64 / 2.0);
        // The summed rows: B K⁻¹d and BR of a pair are the members' sums.
        let g = &groups[pair];
        assert_eq!(l.dense.bk0[pair], (g[0] + g[1]) as f64);
        assert_eq!(l.dense.bk0[5 + pair], (2 * m + g[0] + g[1]) as f64);
    }
}
