//! The coarse start of the iterative path (docs/methods.md §7.2, "The
//! coarse start"; solid models): the working set the Newton loop starts
//! from, found on a coarse level of the multigrid instead of grown from
//! the rows that touch.
//!
//! Grown from the one row that touches, J doubles per step under the growth
//! limit, so the loop took log₂(|J|/32) steps more on every refinement
//! (Hertz 45 k / 163 k / 306 k / 946 k unknowns: 6 / 8 / 8 / 11 Newton
//! steps). Here the contact problem is first solved in the coarse space of
//! the hierarchy built for the first K_J (P the composite prolongator,
//! K_c = PᵀK_JP dense, on the finest level of at most 4 000 unknowns):
//! every row restricted, v_j = Pᵀa_jᵀ, and each row that penetrates held
//! by its own penalty spring ρ_j (the rows of the first J are already
//! springs in K_J). The
//! restricted rows outnumber the coarse unknowns, so they cannot all be
//! equalities (the gaps of a set of them need not be reachable); a penalty
//! asks no such thing. Its active-set Newton steps (a row is active iff it
//! penetrates) each factor one dense matrix of the coarse size. The fine
//! loop then starts from the rows that penetrate there, with x = Py and
//! λ_j = ρ_j·(v_jᵀy − g_j) on them, and decides and certifies as before: no
//! coarse answer enters the result.

use super::limit_changes;
use crate::linalg::amg::Amg;
use crate::linalg::dense::SpdFactor;
use crate::qp::QpProblem;
use std::collections::HashSet;

/// Active-set steps on the coarse level, at most (a repeated set ends them
/// earlier).
const COARSE_STEPS: usize = 40;
/// The coarse level is the finest with at most this many unknowns (a dense
/// factor of it per step).
const DENSE_MAX: usize = 4000;
/// Growth of J per step, on the coarse level and in the fine loop after a
/// coarse start: at most max(32, GROW·|J|) rows enter (`limit_changes`). The coarse J
/// falls short of the answer (a coarse space is stiffer: Hertz 45 k / 163 k
/// / 306 k, 38 / 95 / 120 rows of 161 / 388 / 594), and from there tripling
/// reaches it in two steps; the fine rows' first prediction overshoots by
/// half, and an overshoot shrinks by a ring of rows per step (Hertz 163 k
/// with no limit: 8 Newton steps and 93 CG steps; doubling 5 and 48;
/// tripling 5 and 42; where the coarse set is over a third of the answer
/// tripling overshoots, docs/methods.md §7.2).
pub(super) const GROW: usize = 2;

/// The start found on the coarse level.
pub(super) struct CoarseStart {
    pub in_j: Vec<bool>,
    pub x: Vec<f64>,
    pub lam: Vec<f64>,
    /// Coarse active-set steps taken.
    pub steps: usize,
    /// Unknowns of the level it was found on.
    pub unknowns: usize,
}

/// The coarse start (module doc) from the hierarchy `amg` of
/// K_J = C + Σ_{j∈J0} ρ_j a_ja_jᵀ, J0 = `j0`; `qp` supplies d, A and g
/// (its C is not read). None when the hierarchy has no coarse level of at
/// most DENSE_MAX unknowns or a coarse matrix is not positive definite.
pub(super) fn coarse_start(
    amg: &Amg,
    qp: &QpProblem,
    j0: &[bool],
    rho: &[f64],
) -> Option<CoarseStart> {
    let sizes = amg.sizes();
    // The finest coarse level a dense factor takes (the coarsest may hold
    // a few aggregates only: Hertz at 946 k unknowns has levels of 92 892,
    // 3 390 and 132).
    let l = (1..sizes.len()).find(|&l| sizes[l] <= DENSE_MAX)?;
    let nc = sizes[l];
    let m = qp.m();
    let kc = amg.level_dense(l);
    // The right side of K_J x = d + Σ_{J0} ρ_j g_j a_jᵀ, restricted.
    let mut w = vec![0.0; m];
    for j in (0..m).filter(|&j| j0[j]) {
        w[j] = rho[j] * qp.g[j];
    }
    let mut f = qp.d.clone();
    qp.a.mul_t_add(&w, &mut f);
    let fc = amg.restrict_to_level(l, &f);
    let v: Vec<Vec<(usize, f64)>> = (0..m)
        .map(|j| {
            let (c, a) = qp.a.row(j);
            amg.restrict_row_to_level(l, c, a)
        })
        .collect();
    let mut in_j = j0.to_vec();
    let mut seen: HashSet<Vec<bool>> = HashSet::new();
    let mut steps = 0;
    let (mut y, mut gaps);
    loop {
        let mut mat = kc.clone();
        let mut rhs = fc.clone();
        for j in (0..m).filter(|&j| in_j[j] && !j0[j]) {
            for &(a, va) in &v[j] {
                rhs[a] += rho[j] * qp.g[j] * va;
                for &(b, vb) in &v[j] {
                    mat[a * nc + b] += rho[j] * va * vb;
                }
            }
        }
        y = rhs;
        SpdFactor::from_row_major(&mat, nc)?.solve_in_place(&mut y);
        steps += 1;
        seen.insert(in_j.clone());
        gaps = (0..m)
            .map(|j| v[j].iter().map(|&(k, vk)| vk * y[k]).sum::<f64>() - qp.g[j])
            .collect::<Vec<f64>>();
        // Rows that penetrate are active; at most max(GROW_MIN, GROW·|J|)
        // enter, the deepest first (the fine loop's growth limit,
        // `limit_changes`, with no anti-cycling: a repeated set ends the
        // steps): from the first J's point springs every row near the
        // contact penetrates, and the set would then shrink by a ring of
        // rows per step.
        let predicted: Vec<bool> = (0..m).map(|j| j0[j] || gaps[j] > 0.0).collect();
        let next = limit_changes(&in_j, predicted, &gaps, &HashSet::new(), &mut false, GROW);
        if next == in_j || seen.contains(&next) || steps >= COARSE_STEPS {
            break;
        }
        in_j = next;
    }
    if y.iter().any(|t| !t.is_finite()) {
        return None;
    }
    let lam = (0..m)
        .map(|j| {
            if in_j[j] {
                rho[j] * gaps[j].max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    Some(CoarseStart {
        in_j,
        x: amg.prolong_from_level(l, &y),
        unknowns: nc,
        lam,
        steps,
    })
}
