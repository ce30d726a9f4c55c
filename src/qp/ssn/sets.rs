//! Working-set rules of ssn (docs/methods.md §4.10, §7): the next set
//! from the complementarity function, the candidates, the limit on changes
//! and the rigid motions a set leaves free.

use super::*;

/// The primal–dual active-set rule with each side's zero in its own
/// units: a row of J stays unless λᵢ < −τ_λ, τ_λ = tol·‖λ‖∞; a row outside
/// J enters when (Ax − g)ᵢ > τ_g, τ_g = tol·max(‖Ax‖∞, ‖g‖∞)
/// (docs/methods.md §7). One threshold on F = λ + c(Ax − g), c the mean
/// stiffness, mixed forces and lengths through c: under a stiffness
/// contrast of 1e7 the loaded rows of the soft body had λ below it, left J,
/// penetrated, came back, and the loop never settled.
pub(super) fn next_set(in_j: &[bool], lam: &[f64], ax: &[f64], g: &[f64], tol: f64) -> Vec<bool> {
    let tau_l = tol * norm_inf(lam);
    let tau_g = tol * norm_inf(ax).max(norm_inf(g));
    (0..in_j.len())
        .map(|i| {
            if in_j[i] {
                lam[i] >= -tau_l
            } else {
                ax[i] - g[i] > tau_g
            }
        })
        .collect()
}

/// The working set a nested start predicts (docs/methods.md §7.2, "The
/// nested start"): from x0 and λ̂ interpolated from a coarser mesh's
/// answer, the rows with F = λ̂ + c(Ax0 − g) > 0, c the stiffness scale.
pub(super) fn nested_set(qp: &QpProblem, x0: &[f64], lam: &[f64], c: f64) -> Vec<bool> {
    (0..qp.m())
        .map(|i| lam[i] + c * (qp.a.row_dot(i, x0) - qp.g[i]) > 0.0)
        .collect()
}

/// The working sets a step tries, in order: J, J ∪ J_prev (the last set
/// that was solved), every row; the first whose KKT system is not singular
/// is taken. Shared by the direct and the iterative paths.
pub(super) fn candidates(in_j: &[bool], last_ok: Option<&[bool]>) -> Vec<Vec<bool>> {
    let mut cands = vec![in_j.to_vec()];
    if let Some(prev) = last_ok {
        cands.push(in_j.iter().zip(prev).map(|(a, b)| *a || *b).collect());
    }
    cands.push(vec![true; in_j.len()]);
    cands.dedup();
    cands
}

/// From the predicted working set `new_j`, the next one: at most
/// max(GROW_MIN, `grow`·|J|) rows enter (`grow` = 1 but after the iterative
/// path's coarse start, docs/methods.md §7.2), the most violated by F = `fval`; once a set
/// repeats (`history`), `single` is set and from then on one row changes per
/// step — the most negative λ in J or the most violated row outside it
/// (anti-cycling). Shared by the direct and the iterative paths.
pub(super) fn limit_changes(
    in_j: &[bool],
    mut new_j: Vec<bool>,
    fval: &[f64],
    history: &HashSet<Vec<bool>>,
    single: &mut bool,
    grow: usize,
) -> Vec<bool> {
    let m = in_j.len();
    let size = in_j.iter().filter(|&&b| b).count();
    let mut entering: Vec<usize> = (0..m).filter(|&i| new_j[i] && !in_j[i]).collect();
    let cap = GROW_MIN.max(grow * size);
    if entering.len() > cap {
        entering.sort_unstable_by(|&a, &b| fval[b].total_cmp(&fval[a]).then(a.cmp(&b)));
        for &i in &entering[cap..] {
            new_j[i] = false;
        }
    }
    if !*single && history.contains(&new_j) {
        log::debug!("ssn: a working set repeats; switching to single changes");
        *single = true;
    }
    if *single {
        let mut drop = (0.0f64, usize::MAX);
        let mut add = (0.0f64, usize::MAX);
        for (i, (&f, &inj)) in fval.iter().zip(in_j).enumerate() {
            if inj && !new_j[i] && -f >= drop.0 {
                drop = (-f, i);
            }
            if !inj && new_j[i] && f > add.0 {
                add = (f, i);
            }
        }
        new_j = in_j.to_vec();
        if drop.1 != usize::MAX && (add.1 == usize::MAX || drop.0 >= add.0) {
            new_j[drop.1] = false;
        } else if add.1 != usize::MAX {
            new_j[add.1] = true;
        }
    }
    new_j
}

/// The rigid motions of ker C (coordinates β of Rβ, unit rows) that the
/// rows of `in_j` leave free: the null space of (AR)_J, `ar` = AR by rows.
/// Zero is judged against max ‖(AR)ᵢ‖² over every row, so the test does
/// not depend on the units of A or on the bodies' sizes.
pub(super) fn free_modes(ar: &[Vec<f64>], in_j: &[bool]) -> Vec<Vec<f64>> {
    let k = ar.first().map_or(0, Vec::len);
    if k == 0 {
        return vec![];
    }
    let scale = ar
        .iter()
        .map(|row| row.iter().map(|v| v * v).sum::<f64>())
        .fold(0.0f64, f64::max);
    let mut gram = vec![vec![0.0; k]; k];
    for (row, _) in ar.iter().zip(in_j).filter(|(_, b)| **b) {
        for a in 0..k {
            for b in 0..k {
                gram[a][b] += row[a] * row[b];
            }
        }
    }
    let (vals, vecs) = crate::linalg::dense::sym_eigen(&gram);
    vals.iter()
        .zip(vecs)
        .filter(|(v, _)| !(**v > FREE_REL * scale))
        .map(|(_, u)| u)
        .collect()
}

/// Zero of a Gram eigenvalue relative to the largest row of AR ([`free_modes`]).
pub(super) const FREE_REL: f64 = 1e-12;

/// A working set `new_j` that leaves a rigid motion free (its KKT system is
/// singular) made one that holds every body, the way a primal active-set
/// step would (docs/methods.md §7): from (x, λ) solved on `solved_j`, move
/// along the free motion s = Rβ on which the energy falls fastest
/// (β the free part of Rᵀ(d − Cx) = (AR)ᵀλ), until a row outside `new_j`
/// closes (the least (g − Ax)ᵢ / (As)ᵢ over (As)ᵢ > 0), and add that row;
/// again until nothing is free. With no descent along a free motion, both
/// of its directions are tried. PDAS alone dropped the rows with λ < 0,
/// found the rest singular, fell back to the last set and repeated it
/// forever (a tilting block under a nearly horizontal load,
/// tests/agreement.rs `two_blocks_eccentric_ci_case`). Motions that every
/// row leaves free are not held (the driver reports them). Returns `new_j`
/// unchanged if no row blocks (the fallbacks of the step then decide).
pub(super) fn hold_free_modes(
    mut new_j: Vec<bool>,
    solved_j: &[bool],
    ar: &[Vec<f64>],
    lam: &[f64],
    ax: &[f64],
    g: &[f64],
) -> Vec<bool> {
    let k = ar.first().map_or(0, Vec::len);
    let m = new_j.len();
    // Motions that every row leaves free (a ring sliding along flat plates)
    // are the driver's to report (docs/methods.md §1.7), not to hold; a
    // direction whose rows move by less than this is one of them.
    let genuinely_free = free_modes(ar, &vec![true; m]).len();
    let row_max = ar
        .iter()
        .map(|row| row.iter().map(|v| v * v).sum::<f64>())
        .fold(0.0f64, f64::max)
        .sqrt();
    // e = (AR)_Jᵀλ_J: the load the dropped rows carried, in kernel coordinates.
    let mut e = vec![0.0; k];
    for i in (0..m).filter(|&i| solved_j[i]) {
        for (el, a) in e.iter_mut().zip(&ar[i]) {
            *el += a * lam[i];
        }
    }
    for _ in 0..=k {
        let free = free_modes(ar, &new_j);
        if free.len() <= genuinely_free {
            break;
        }
        // The free part of e, and the directions to search.
        let mut beta = vec![0.0; k];
        for u in &free {
            let c = dot(u, &e);
            for (b, ul) in beta.iter_mut().zip(u) {
                *b += c * ul;
            }
        }
        let e_norm = norm_inf(&e);
        let dirs: Vec<Vec<f64>> = if norm_inf(&beta) > 1e-10 * e_norm && e_norm > 0.0 {
            vec![beta]
        } else {
            free.iter()
                .flat_map(|u| [u.clone(), u.iter().map(|v| -v).collect()])
                .collect()
        };
        let mut added = false;
        for dir in dirs {
            let a_s: Vec<f64> = ar.iter().map(|row| dot(row, &dir)).collect();
            let s_max = norm_inf(&a_s);
            if s_max <= 1e-8 * row_max {
                continue;
            }
            let mut best: Option<(f64, usize)> = None;
            for i in (0..m).filter(|&i| !new_j[i] && a_s[i] > 1e-10 * s_max) {
                let t = ((g[i] - ax[i]) / a_s[i]).max(0.0);
                if best.is_none_or(|(bt, _)| t < bt) {
                    best = Some((t, i));
                }
            }
            if let Some((_, i)) = best {
                new_j[i] = true;
                added = true;
            }
        }
        if !added {
            break;
        }
    }
    new_j
}

/// c = the mean of C's positive diagonal entries (1 if none): the stiffness
/// that turns gaps into forces in F = λ + c(Ax − g).
pub(super) fn stiffness_scale(diag: &[f64]) -> f64 {
    let pos: Vec<f64> = diag.iter().copied().filter(|v| *v > 0.0).collect();
    if pos.is_empty() {
        1.0
    } else {
        pos.iter().sum::<f64>() / pos.len() as f64
    }
}
