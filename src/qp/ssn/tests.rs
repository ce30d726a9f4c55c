//! Tests of SSN: agreement with cgc/mprgp/asm on lattices and the shipped
//! examples, both linear-algebra paths, the Woodbury update, the growth limit,
//! determinism, the certificate. The generator, `reference` and `compare` are
//! `qp::testing`'s.

use super::*;
use crate::linalg::sparse::{norm, Csr};
use crate::qp::executor::Executor;
use crate::qp::testing::{compare, example, reference, two_blocks, Solution};
use crate::qp::{kkt, run_direct, SolveOptions};

fn opts() -> SolveOptions {
    {
        let mut o = SolveOptions::default();
        o.settings.tol = 1e-12;
        o
    }
}

fn nontrivial(r: &impl Solution) {
    let na = r.active().iter().filter(|b| **b).count();
    assert!(
        na > 0 && na < r.active().len(),
        "active {na} of {}",
        r.active().len()
    );
    // some active row with g > 0 would be nice but is not required
}

#[test]
fn coercive_agrees_with_cgc() {
    let qp = two_blocks(9, 5, false);
    let refr = reference(&qp);
    nontrivial(&refr);
    let r = run_direct(solve, &qp, &opts()).unwrap();
    compare(&qp, &r, &refr, 1e-6);
    assert!(r.iterations <= 15, "{} iterations", r.iterations);
    assert!(r.timings.iter().any(|(n, _)| n == "factor"));
}

#[test]
fn semicoercive_agrees_with_cgc() {
    let qp = two_blocks(9, 5, true);
    assert_eq!(qp.kernel.len(), 1);
    let cz = qp.c.mul(&qp.kernel[0]);
    assert!(
        norm(&cz) <= 1e-12 * norm(&qp.kernel[0]),
        "the kernel vector should be in ker C"
    );
    let refr = reference(&qp);
    nontrivial(&refr);
    let r = run_direct(solve, &qp, &opts()).unwrap();
    compare(&qp, &r, &refr, 1e-6);
    assert!(r.iterations <= 15, "{} iterations", r.iterations);
}

/// All gaps open: the glued start J is empty, which leaves the floating
/// block free; J is enlarged to all rows and the iteration proceeds.
#[test]
fn semicoercive_empty_start_is_enlarged() {
    let mut qp = two_blocks(9, 5, true);
    qp.g.iter_mut().for_each(|g| *g += 1e-3);
    let refr = reference(&qp);
    let r = run_direct(solve, &qp, &opts()).unwrap();
    compare(&qp, &r, &refr, 1e-6);
}

/// The anti-cycling fallback (single changes) on its own converges too.
#[test]
fn single_change_fallback_converges() {
    for (floating, augmented) in [(false, true), (true, true), (false, false), (true, false)] {
        let qp = two_blocks(9, 5, floating);
        let refr = reference(&qp);
        let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
        let ws_st = Workspace::new();
        let mut st = Ssn::new(&qp, r, 1e-12, augmented, &ws_st);
        st.single = true;
        let mut exec = Executor::new(200, None);
        let (status, iters) = exec.run(&mut st);
        let res = st.into_result(status, iters, exec.log, vec![]);
        compare(&qp, &res, &refr, 1e-6);
    }
}

/// The augmented-factor path and the Schur-complement path give the same
/// answer, and the augmented path refactors on one symbolic analysis.
#[test]
fn augmented_and_schur_paths_agree() {
    for floating in [false, true] {
        let qp = two_blocks(12, 6, floating);
        let refr = reference(&qp);
        let ws = Workspace::new();
        let (_, s0) = ws.reuse_counts();
        let a = solve_traced(&qp, &mut Context::new(&opts(), &ws), Path::Refactor)
            .unwrap()
            .0;
        let (_, s1) = ws.reuse_counts();
        let u = solve_with(&qp, &opts(), Path::Augmented).unwrap();
        compare(&qp, &u, &refr, 1e-6);
        assert_eq!(a.active, u.active);
        let b = solve_with(&qp, &opts(), Path::Schur).unwrap();
        let c = solve_with(&qp, &opts(), Path::Auto).unwrap();
        compare(&qp, &c, &refr, 1e-6);
        assert_eq!(a.active, c.active);
        compare(&qp, &a, &refr, 1e-6);
        compare(&qp, &b, &refr, 1e-6);
        assert_eq!(a.active, b.active);
        let dx =
            a.x.iter()
                .zip(&b.x)
                .map(|(u, v)| (u - v).abs())
                .fold(0.0, f64::max);
        assert!(dx <= 1e-8 * norm_inf(&b.x), "{dx}");
        if a.iterations > 1 {
            assert!(
                s1 > s0,
                "no symbolic reuse over {} iterations",
                a.iterations
            );
        }
        // A handful of solves per Newton step, not one per active row.
        assert!(
            a.inner_iterations <= 12 * a.iterations,
            "{} solves",
            a.inner_iterations
        );
    }
}

/// The Woodbury update of K' (rows leaving and entering J) solves the
/// KKT system of the new J exactly as a fresh factorization does.
#[test]
fn low_rank_update_matches_refactorization() {
    for floating in [false, true] {
        let qp = two_blocks(10, 6, floating);
        let m = qp.m();
        let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
        let j1: Vec<bool> = vec![true; m];
        let mut j2 = j1.clone();
        j2[0] = false;
        j2[m / 2] = false;
        let ws_st = Workspace::new();
        let mut st = Ssn::new(&qp, r.clone(), 1e-12, true, &ws_st);
        st.kkt_solve_aug(&j1).expect("J1");
        st.costs.fac_k = 1e300; // make the update look cheap
        let solves = st.solves;
        let (l_up, x_up) = st.kkt_solve_aug(&j2).expect("J2 by update");
        assert!(st.kfac_set.as_ref().unwrap() == &j1, "K' was refactored");
        assert!(st.solves > solves);
        let ws_fresh = Workspace::new();
        let mut fresh = Ssn::new(&qp, r, 1e-12, true, &ws_fresh);
        let (l_ref, x_ref) = fresh.kkt_solve_aug(&j2).expect("J2 fresh");
        let dx = x_up
            .iter()
            .zip(&x_ref)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let dl = l_up
            .iter()
            .zip(&l_ref)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(dx <= 1e-8 * norm_inf(&x_ref), "x: {dx}");
        assert!(dl <= 1e-6 * norm_inf(&l_ref), "λ: {dl}");
        assert_eq!(l_up[0], 0.0);
        // Now back to J1: the update is empty (r = 0), the factor is K' itself.
        let (_, x_back) = st.kkt_solve_aug(&j1).expect("J1 again");
        let ws_fresh1 = Workspace::new();
        let mut fresh1 = Ssn::new(
            &qp,
            orthonormal_kernel(&qp.c, &qp.kernel).unwrap(),
            1e-12,
            true,
            &ws_fresh1,
        );
        let (_, x1) = fresh1.kkt_solve_aug(&j1).unwrap();
        let d1 = x_back
            .iter()
            .zip(&x1)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(d1 <= 1e-8 * norm_inf(&x1), "{d1}");
    }
}

#[test]
fn semicoercive_without_any_contact_row_fails_cleanly() {
    let mut qp = two_blocks(5, 3, true);
    qp.a = Csr::zeros(0, qp.n());
    qp.g.clear();
    let r = run_direct(solve, &qp, &opts()).unwrap();
    assert!(matches!(r.status, Status::Failed(_)), "{:?}", r.status);
}

#[test]
fn no_contact_rows_coercive() {
    let mut qp = two_blocks(5, 3, false);
    qp.a = Csr::zeros(0, qp.n());
    qp.g.clear();
    let r = run_direct(solve, &qp, &opts()).unwrap();
    assert!(r.status.converged());
    let k = kkt::residuals(&qp, &r.x, &r.lambda);
    assert!(k.max() <= 1e-10, "{k:?}");
}

#[test]
fn wrong_kernel_is_rejected() {
    let mut qp = two_blocks(5, 3, true);
    qp.kernel[0][0] += 1.0;
    assert!(matches!(
        run_direct(solve, &qp, &opts()),
        Err(QpError::BadParameter(_))
    ));
}

/// A string (n interior nodes, both ends fixed) pressed by a uniform
/// load onto a parabolic obstacle touching it at the middle node: the
/// 1D analogue of Hertz. With only the middle row glued, the first
/// solve penetrates far more rows than end in contact; the growth limit
/// (at most max(GROW_MIN, |J|) rows enter per step) keeps the Schur
/// path from computing a column for each of them.
fn string_on_parabola(n: usize) -> QpProblem {
    let h = 1.0 / (n + 1) as f64;
    let mut trip = vec![];
    for i in 0..n {
        trip.push((i, i, 2.0 / h));
        if i > 0 {
            trip.push((i, i - 1, -1.0 / h));
            trip.push((i - 1, i, -1.0 / h));
        }
    }
    let c = Csr::from_triplets(n, n, &trip);
    let d = vec![-h; n];
    // −x_i ≤ g_i with g_i = κ(s_i − ½)², zero at the middle node.
    let mid = n / 2;
    let s_of = |i: usize| (i + 1) as f64 * h;
    let a = Csr::from_triplets(n, n, &(0..n).map(|i| (i, i, -1.0)).collect::<Vec<_>>());
    let g = (0..n)
        .map(|i| 4.0 * (s_of(i) - s_of(mid)).powi(2))
        .collect();
    QpProblem {
        c,
        d,
        a,
        g,
        kernel: vec![],
        friction: None,
        near: None,
    }
}

#[test]
fn growth_limit_computes_few_columns() {
    let qp = string_on_parabola(2001);
    let refr = run_direct(crate::qp::dual::mprgp::solve, &qp, &opts()).unwrap();
    assert!(refr.status.converged(), "mprgp: {:?}", refr.status);
    let r = solve_with(&qp, &opts(), Path::Schur).unwrap();
    compare(&qp, &r, &refr, 1e-6);
    let active = r.active.iter().filter(|&&b| b).count();
    // Penetrated after the first solve: every row where the string held
    // at its middle node (x_mid = 0) is below the obstacle.
    let x0 = {
        let k = Cholesky::new(&qp.c, &[]).unwrap();
        let y = k.solve(&qp.d);
        let mut e = vec![0.0; qp.n()];
        e[qp.n() / 2] = 1.0;
        let z = k.solve(&e);
        let t = y[qp.n() / 2] / z[qp.n() / 2];
        y.iter()
            .zip(&z)
            .map(|(a, b)| a - t * b)
            .collect::<Vec<f64>>()
    };
    let penetrated = (0..qp.m())
        .filter(|&i| qp.a.row_dot(i, &x0) > qp.g[i])
        .count();
    assert!(
        penetrated > active + 2 * GROW_MIN + 10,
        "test premise: {penetrated} penetrated, {active} active"
    );
    // One solve for K⁻¹d and one per row that ever entered J.
    assert!(
        r.inner_iterations <= active + 2 * GROW_MIN,
        "{} solves for {active} active rows ({penetrated} penetrated at first)",
        r.inner_iterations
    );
}

/// The shipped examples (floating bodies in all but cantilevers and
/// geodynamic): ssn converges in few iterations and agrees with cgc (where
/// cgc at tol 1e-12 is cheap) or with mprgp (the others).
#[test]
fn shipped_examples() {
    for name in [
        "floating_block",
        "two_blocks",
        "three_bodies",
        "hip",
        "cantilevers",
        "geodynamic",
        "hertz",
    ] {
        let prep = example(name);
        let qp = &prep.model.qp;
        let r = run_direct(solve, qp, &opts()).unwrap();
        // cantilevers: the glued start is far from the solution (half the
        // interface opens), PDAS releases it in 17 steps.
        let maxit = if name == "cantilevers" { 20 } else { 15 };
        assert!(r.iterations <= maxit, "{name}: {} iterations", r.iterations);
        let refr: Output = if ["floating_block", "two_blocks", "three_bodies"].contains(&name) {
            reference(qp).solution
        } else {
            let m = run_direct(crate::qp::dual::mprgp::solve, qp, &opts()).unwrap();
            assert!(m.status.converged(), "{name}: mprgp {:?}", m.status);
            m
        };
        compare(qp, &r, &refr, 1e-6);
    }
}

#[test]
fn floating_block_in_few_iterations() {
    let prep = example("floating_block");
    let qp = &prep.model.qp;
    assert_eq!(qp.kernel.len(), 1);
    let r = run_direct(solve, qp, &SolveOptions::default()).unwrap();
    assert!(r.status.converged(), "{:?}", r.status);
    assert!(r.iterations <= 15, "{} iterations", r.iterations);
    // total vertical contact force = 1e5 + 2500·9.81 N/m (meshes/floating_block.toml)
    let f: f64 = r.lambda.iter().sum();
    assert!(
        (f - 1.24525e5).abs() <= 1e-6 * 1.24525e5,
        "contact force {f}"
    );
    assert!(kkt::residuals(qp, &r.x, &r.lambda).max() <= 1e-8);
}

/// Two lattice blocks of unit width (bars along the grid lines and both
/// diagonals, as in [`two_blocks`]): the lower one, stiffness 1, with
/// `nx_lo` nodes per row, clamped at its bottom; the upper one, stiffness
/// `contrast`, with `nx_up` nodes per row, held only by u_x = 0 at its top
/// left node (kernel: its vertical translation and its rotation about that
/// node, in `qp.kernel`). Non-matching contact rows: every bottom node of
/// the upper block against the linear interpolation of the lower block's
/// top row, n = (0, 1); the upper block's bottom is curved (gap
/// 0.02(s − 0.45)²), the load presses it down off-centre.
pub(crate) fn contrast_blocks(nx_lo: usize, nx_up: usize, ny: usize, contrast: f64) -> QpProblem {
    contrast_blocks_with(nx_lo, nx_up, ny, contrast, None)
}

/// [`contrast_blocks`], with `tilt = Some(θ)` (nx_lo = nx_up): node-to-node
/// rows instead, bottom node of the upper block against the top node below
/// it, along n = (sin θ, cos θ): each row touches four unknowns no other row
/// touches (docs/methods.md §7, "Rotated rows").
fn contrast_blocks_with(
    nx_lo: usize,
    nx_up: usize,
    ny: usize,
    contrast: f64,
    tilt: Option<f64>,
) -> QpProblem {
    let h = 0.5 / (ny - 1) as f64;
    // global node numbers and coordinates
    let lo = |i: usize, j: usize| j * nx_lo + i;
    let up = |i: usize, j: usize| nx_lo * ny + j * nx_up + i;
    let nn = (nx_lo + nx_up) * ny;
    let mut xy = vec![[0.0; 2]; nn];
    for j in 0..ny {
        for i in 0..nx_lo {
            xy[lo(i, j)] = [i as f64 / (nx_lo - 1) as f64, j as f64 * h];
        }
        for i in 0..nx_up {
            xy[up(i, j)] = [i as f64 / (nx_up - 1) as f64, 0.5 + j as f64 * h];
        }
    }
    let mut trip_full: Vec<(usize, usize, f64)> = vec![];
    let mut bar = |p: usize, q: usize, k: f64| {
        let dir = [xy[q][0] - xy[p][0], xy[q][1] - xy[p][1]];
        let l = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
        let e = [dir[0] / l, dir[1] / l];
        for a in 0..2 {
            for b in 0..2 {
                let v = k * e[a] * e[b];
                trip_full.push((2 * p + a, 2 * p + b, v));
                trip_full.push((2 * q + a, 2 * q + b, v));
                trip_full.push((2 * p + a, 2 * q + b, -v));
                trip_full.push((2 * q + a, 2 * p + b, -v));
            }
        }
    };
    for (nx, k, node) in [
        (nx_lo, 1.0, &lo as &dyn Fn(usize, usize) -> usize),
        (nx_up, contrast, &up),
    ] {
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx {
                    bar(node(i, j), node(i + 1, j), k);
                }
                if j + 1 < ny {
                    bar(node(i, j), node(i, j + 1), k);
                }
                if i + 1 < nx && j + 1 < ny {
                    bar(node(i, j), node(i + 1, j + 1), 0.5 * k);
                    bar(node(i + 1, j), node(i, j + 1), 0.5 * k);
                }
            }
        }
    }
    let mut fixed = vec![false; 2 * nn];
    for i in 0..nx_lo {
        fixed[2 * lo(i, 0)] = true;
        fixed[2 * lo(i, 0) + 1] = true;
    }
    fixed[2 * up(0, ny - 1)] = true;
    let mut map = vec![usize::MAX; 2 * nn];
    let mut n = 0;
    for (dof, f) in fixed.iter().enumerate() {
        if !f {
            map[dof] = n;
            n += 1;
        }
    }
    let trip: Vec<(usize, usize, f64)> = trip_full
        .iter()
        .filter(|(i, j, _)| map[*i] != usize::MAX && map[*j] != usize::MAX)
        .map(|&(i, j, v)| (map[i], map[j], v))
        .collect();
    let c = Csr::from_triplets(n, n, &trip);
    // Loads: the upper block's top row pressed down, more on the left;
    // gravity-like load on the lower block (in its own stiffness scale).
    let mut d = vec![0.0; n];
    for i in 0..nx_up {
        let s = i as f64 / (nx_up - 1) as f64;
        d[map[2 * up(i, ny - 1) + 1]] -= 0.02 * (1.5 - s) / nx_up as f64;
    }
    for j in 1..ny {
        for i in 0..nx_lo {
            d[map[2 * lo(i, j) + 1]] -= 1e-4;
        }
    }
    let mut at = vec![];
    let mut g = vec![];
    for i in 0..nx_up {
        let s = i as f64 / (nx_up - 1) as f64;
        let r = g.len();
        if let Some(th) = tilt {
            assert_eq!(nx_lo, nx_up);
            let (sn, cs) = th.sin_cos();
            at.push((r, map[2 * lo(i, ny - 1)], sn));
            at.push((r, map[2 * lo(i, ny - 1) + 1], cs));
            at.push((r, map[2 * up(i, 0)], -sn));
            at.push((r, map[2 * up(i, 0) + 1], -cs));
        } else {
            let t = s * (nx_lo - 1) as f64;
            let k = (t.floor() as usize).min(nx_lo - 2);
            let w = t - k as f64;
            at.push((r, map[2 * lo(k, ny - 1) + 1], 1.0 - w));
            at.push((r, map[2 * lo(k + 1, ny - 1) + 1], w));
            at.push((r, map[2 * up(i, 0) + 1], -1.0));
        }
        g.push(0.02 * (s - 0.45) * (s - 0.45));
    }
    let a = Csr::from_triplets(g.len(), n, &at);
    // ker C: the upper block's vertical translation and its rotation
    // about the held node (x0, y0) = its top left corner.
    let (x0, y0) = (xy[up(0, ny - 1)][0], xy[up(0, ny - 1)][1]);
    let mut tz = vec![0.0; n];
    let mut rot = vec![0.0; n];
    for j in 0..ny {
        for i in 0..nx_up {
            let p = up(i, j);
            tz[map[2 * p + 1]] = 1.0;
            if map[2 * p] != usize::MAX {
                rot[map[2 * p]] = -(xy[p][1] - y0);
            }
            rot[map[2 * p + 1]] = xy[p][0] - x0;
        }
    }
    QpProblem {
        c,
        d,
        a,
        g,
        kernel: vec![tz, rot],
        friction: None,
        near: None,
    }
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d = a
        .iter()
        .zip(b)
        .map(|(u, v)| (u - v).abs())
        .fold(0.0, f64::max);
    d / norm_inf(b).max(f64::MIN_POSITIVE)
}

/// A floating stiff block on a soft clamped one, contrast 1e4 and 1e8,
/// non-matching rows: every path is certified by the force-sensitive
/// certificate and agrees with the Schur path and with `asm` on x and λ
/// to 1e-8 (at 1e4; at 1e8 to the rounding floor 100·ε·1e8). (Before λ = μ + ρ(A_J x − g_J), the augmented path returned
/// "converged" with stationarity far above 1e-6 here.)
#[test]
fn stiffness_contrast_is_certified() {
    for contrast in [1e4, 1e8] {
        let qp = contrast_blocks(17, 11, 6, contrast);
        assert_eq!(orthonormal_kernel(&qp.c, &qp.kernel).unwrap().len(), 2);
        let o = SolveOptions::default();
        let schur = solve_with(&qp, &o, Path::Schur).unwrap();
        assert!(schur.status.converged(), "{contrast:e}: {:?}", schur.status);
        nontrivial(&schur);
        let asm = run_direct(crate::qp::active_set::solve, &qp, &o).unwrap();
        assert!(asm.status.converged(), "asm {contrast:e}: {:?}", asm.status);
        // Rounding floor: C x of the stiff body (a rigid motion plus a
        // deformation 1/contrast as large) is known to ε·contrast only,
        // for every method (asm and the Schur path give 1.2e-7 and 1.4e-7
        // at 1e8): agreement to 1e-8, or to 100·ε·contrast above that.
        let agree = 1e-8f64.max(1e2 * f64::EPSILON * contrast);
        for path in [Path::Auto, Path::Augmented, Path::Refactor, Path::Schur] {
            let r = solve_with(&qp, &o, path).unwrap();
            assert!(
                r.status.converged(),
                "{contrast:e} {path:?}: {:?}",
                r.status
            );
            let cert = certificate(&qp, &r.x, &r.lambda);
            assert!(
                cert <= crate::qp::settings::DEFAULT_KKT_TARGET,
                "{contrast:e} {path:?}: certificate {cert:e}"
            );
            assert_eq!(r.active, schur.active, "{contrast:e} {path:?}");
            for (name, refr) in [("schur", &schur), ("asm", &asm)] {
                let dx = max_rel_diff(&r.x, &refr.x);
                let dl = max_rel_diff(&r.lambda, &refr.lambda);
                assert!(
                    dx <= agree && dl <= agree,
                    "{contrast:e} {path:?} vs {name}: x {dx:e}, λ {dl:e}"
                );
            }
            // The floating block carries its load by contact alone.
            let load: f64 = -qp
                .d
                .iter()
                .zip(&qp.kernel[0])
                .map(|(a, b)| a * b)
                .sum::<f64>();
            let f: f64 = r.lambda.iter().sum();
            assert!(
                (f - load).abs() <= agree * load,
                "{contrast:e} {path:?}: Σλ = {f}, load {load}"
            );
        }
    }
}

/// Same input ⇒ the same path at every step and bit-identical x, λ,
/// iterations, whatever else the machine does (a busy thread runs
/// during the second solve), on problems whose sizes make the cost
/// model choose differently (Schur from the start, augmented, switches).
#[test]
fn deterministic_paths_and_results() {
    let probs = [
        two_blocks(9, 5, false),
        two_blocks(40, 12, true),
        contrast_blocks(33, 21, 8, 1e6),
        string_on_parabola(3001),
        {
            // A wide interface glued from the start: |J| = 200 rows.
            let mut qp = two_blocks(200, 20, false);
            qp.g.iter_mut().for_each(|g| *g = 0.0);
            qp
        },
    ];
    let mut kinds = HashSet::new();
    for qp in &probs {
        let o = opts();
        let (a, ta) =
            solve_traced(qp, &mut Context::new(&o, &Workspace::new()), Path::Auto).unwrap();
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let s2 = stop.clone();
        let busy = std::thread::spawn(move || {
            let mut v = 0u64;
            while !s2.load(std::sync::atomic::Ordering::Relaxed) {
                v = v.wrapping_mul(6364136223846793005).wrapping_add(1);
            }
            v
        });
        let (b, tb) =
            solve_traced(qp, &mut Context::new(&o, &Workspace::new()), Path::Auto).unwrap();
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        busy.join().unwrap();
        assert!(a.status.converged(), "{:?}", a.status);
        assert_eq!(ta, tb, "paths differ");
        assert_eq!(a.iterations, b.iterations);
        assert_eq!(a.inner_iterations, b.inner_iterations);
        assert_eq!(a.active, b.active);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&a.x), bits(&b.x), "x not bit-identical");
        assert_eq!(bits(&a.lambda), bits(&b.lambda), "λ not bit-identical");
        kinds.insert((ta.contains(&true), ta.contains(&false)));
    }
    // The sizes exercise both paths.
    assert!(kinds.iter().any(|k| k.0), "augmented path never taken");
    assert!(kinds.iter().any(|k| k.1), "Schur path never taken");
}

/// The cost model's inputs are counts: the same pattern gives the same
/// counts, a larger one larger counts, and a factor costs more than a solve.
#[test]
fn cost_model_counts() {
    let small = two_blocks(9, 5, false);
    let big = two_blocks(30, 10, false);
    let ws = Workspace::new();
    let cs = Costs::new(&small, Some(&AugPattern::new(&small.c, &small.a)), &ws).unwrap();
    let cs2 = Costs::new(
        &small,
        Some(&AugPattern::new(&small.c, &small.a)),
        &Workspace::new(),
    )
    .unwrap();
    let cb = Costs::new(&big, Some(&AugPattern::new(&big.c, &big.a)), &ws).unwrap();
    assert_eq!(
        (cs.fac_c, cs.solve_c, cs.fac_k, cs.solve_k),
        (cs2.fac_c, cs2.solve_c, cs2.fac_k, cs2.solve_k)
    );
    assert!(cb.fac_c > cs.fac_c && cb.solve_c > cs.solve_c);
    assert!(cs.solve_c >= small.n() as f64, "nnz(L) ≥ n");
    assert!(
        cs.fac_k >= cs.fac_c && cs.solve_k >= cs.solve_c,
        "C + AᵀA fills more"
    );
}

/// The path is a setting: an unknown name is refused when the settings
/// are read, a known one is taken.
#[test]
fn path_option() {
    let qp = two_blocks(9, 5, false);
    assert!("diagonal".parse::<crate::qp::settings::SsnPath>().is_err());
    let mut o = opts();
    o.settings.ssn.path = crate::qp::settings::SsnPath::Schur;
    let (r, trace) =
        solve_traced(&qp, &mut Context::new(&o, &Workspace::new()), Path::Schur).unwrap();
    assert!(r.status.converged());
    assert!(trace.iter().all(|aug| !aug), "{trace:?}");
    let r = run_direct(solve, &qp, &o).unwrap();
    assert!(r.status.converged());
}

/// NaN anywhere is never certified.
#[test]
fn certificate_rejects_nan() {
    let qp = two_blocks(9, 5, false);
    let r = run_direct(solve, &qp, &opts()).unwrap();
    assert!(certificate(&qp, &r.x, &r.lambda) <= 1e-8);
    let mut x = r.x.clone();
    x[3] = f64::NAN;
    assert_eq!(certificate(&qp, &x, &r.lambda), f64::INFINITY);
    let mut l = r.lambda.clone();
    l[0] = f64::INFINITY;
    assert_eq!(certificate(&qp, &r.x, &l), f64::INFINITY);
}

/// A small border (the unknowns A touches): the bordered factor gives every
/// column of A K⁻¹Aᵀ, the dual-space steps find J, and the Newton loop
/// needs only K⁻¹d, one KKT solve and at most a refinement: the answer of
/// the augmented path, coercive or floating, in a few sparse solves.
#[test]
fn bordered_factor_needs_no_column_solves() {
    for floating in [false, true] {
        let qp = two_blocks(16, 8, floating);
        let border = small_border(&qp).expect("a small border");
        assert!(border.len() < qp.n() / 4);
        let refr = reference(&qp);
        nontrivial(&refr);
        let o = opts();
        let (b, trace) =
            solve_traced(&qp, &mut Context::new(&o, &Workspace::new()), Path::Auto).unwrap();
        compare(&qp, &b, &refr, 1e-6);
        assert!(trace.iter().all(|aug| !aug), "the Schur path: {trace:?}");
        assert!(
            b.inner_iterations <= 3 && b.iterations <= 2,
            "{} KKT solves, {} sparse solves",
            b.iterations,
            b.inner_iterations
        );
        let a = solve_with(&qp, &o, Path::Augmented).unwrap();
        assert_eq!(a.active, b.active, "floating {floating}");
    }
    // A border of more than 12√n unknowns is not bordered.
    let mut qp = two_blocks(16, 8, false);
    let n = qp.n();
    let all: Vec<(usize, usize, f64)> = (0..n).map(|j| (0, j, 1e-3)).collect();
    qp.a = Csr::from_triplets(1, n, &all);
    qp.g = vec![1.0];
    assert!(small_border(&qp).is_none());
}

/// Rotated rows (docs/methods.md §7): tilted node-to-node rows touch four
/// unknowns each, a floating block 10⁴ and 10⁸ times stiffer than its
/// foundation. The border is one unknown per node, two per row (the rows
/// holding a fixing unknown keep theirs), the bordered path needs no column solve, and its
/// answer is certified and agrees with the augmented path and `asm` to the
/// rounding floor of [`stiffness_contrast_is_certified`].
#[test]
fn rotated_rows_under_stiffness_contrast() {
    for contrast in [1e4, 1e8] {
        let qp = contrast_blocks_with(14, 14, 6, contrast, Some(0.3));
        let m = qp.m();
        let rb = small_border(&qp).expect("a small border");
        // Two kernel vectors: two fixing unknowns, on two rows at most.
        assert!(rb.rotated() >= m - 2, "{} of {m} rotated", rb.rotated());
        assert!(rb.len() <= 2 * m + 6, "border {} for {m} rows", rb.len());
        let o = SolveOptions::default();
        let (b, trace) =
            solve_traced(&qp, &mut Context::new(&o, &Workspace::new()), Path::Auto).unwrap();
        assert!(b.status.converged(), "{contrast:e}: {:?}", b.status);
        nontrivial(&b);
        assert!(trace.iter().all(|aug| !aug), "the Schur path: {trace:?}");
        // K⁻¹d and the KKT solve; at 10⁸ two refinements (as unrotated).
        let most = if contrast < 1e5 { 2 } else { 4 };
        assert!(
            b.iterations == 1 && b.inner_iterations <= most,
            "{contrast:e}: {} KKT solves, {} sparse solves",
            b.iterations,
            b.inner_iterations
        );
        let cert = certificate(&qp, &b.x, &b.lambda);
        assert!(
            cert <= crate::qp::settings::DEFAULT_KKT_TARGET,
            "{contrast:e}: certificate {cert:e}"
        );
        let aug = solve_with(&qp, &o, Path::Augmented).unwrap();
        let asm = run_direct(crate::qp::active_set::solve, &qp, &o).unwrap();
        let agree = 1e-8f64.max(1e2 * f64::EPSILON * contrast);
        for (name, r) in [("augmented", &aug), ("asm", &asm)] {
            assert_eq!(b.active, r.active, "{contrast:e} vs {name}");
            let (dx, dl) = (max_rel_diff(&b.x, &r.x), max_rel_diff(&b.lambda, &r.lambda));
            assert!(
                dx <= agree && dl <= agree,
                "{contrast:e} vs {name}: x {dx:e}, λ {dl:e}"
            );
        }
    }
}

/// The iterative path (multigrid-preconditioned CG, no factor of C) agrees
/// with the reference on the lattices, coercive and floating, with open
/// gaps (an empty glued start that must be enlarged), without a near-null
/// space (scalar aggregation), and on the same input gives the same bits.
#[test]
fn iterative_path_agrees_with_the_reference() {
    let iterative = || {
        let mut o = opts();
        o.settings.ssn.path = crate::qp::settings::SsnPath::Iterative;
        o
    };
    for (floating, open) in [(false, false), (true, false), (true, true)] {
        let mut qp = two_blocks(12, 6, floating);
        if open {
            qp.g.iter_mut().for_each(|g| *g += 1e-3);
        }
        assert!(qp.near.is_none(), "the lattices carry no mesh");
        let refr = reference(&qp);
        let r = crate::qp::registry::solve("ssn", &qp, &iterative()).unwrap();
        compare(&qp, &r, &refr, 1e-6);
        assert!(r.kkt.within(1e-9), "{:?}", r.kkt);
        assert!(
            r.timings.iter().any(|(n, _)| n == "multigrid setup"),
            "{:?}",
            r.timings
        );
        let again = crate::qp::registry::solve("ssn", &qp, &iterative()).unwrap();
        assert_eq!(r.x, again.x, "not deterministic");
        assert_eq!(r.inner_iterations, again.inner_iterations);
    }
}

/// On a shipped mesh (three bodies, a floating wedge held by contact only)
/// the FEM's near-null space (point blocks, rigid motions) is used, and the
/// answer is the direct path's: same working set, x to 1e-7.
#[test]
fn iterative_path_on_the_three_body_mesh() {
    let m = example("three_bodies").model;
    let qp = &m.qp;
    let near = qp.near.as_ref().expect("the FEM gives the near-null space");
    assert_eq!(*near.block_ptr.last().unwrap(), qp.n());
    assert_eq!(near.modes.len(), 3);
    // Translations and rotation are near-null: C resists them only at the
    // clamped edges (exactly null on the floating wedge).
    let mean_diag = qp.c.diag().iter().sum::<f64>() / qp.n() as f64;
    for z in &near.modes {
        let rq = crate::linalg::sparse::dot(z, &qp.c.mul(z)) / crate::linalg::sparse::dot(z, z);
        assert!(
            rq <= 0.05 * mean_diag,
            "zᵀCz/zᵀz = {rq:e}, mean diag {mean_diag:e}"
        );
    }
    let mut o = opts();
    o.settings.tol = 1e-10;
    let direct = crate::qp::registry::solve("ssn", qp, &o).unwrap();
    o.settings.ssn.path = crate::qp::settings::SsnPath::Iterative;
    let it = crate::qp::registry::solve("ssn", qp, &o).unwrap();
    assert!(it.status.converged(), "{:?}", it.status);
    assert!(it.kkt.within(1e-9), "{:?}", it.kkt);
    assert_eq!(it.active, direct.active);
    let dx: Vec<f64> = it.x.iter().zip(&direct.x).map(|(a, b)| a - b).collect();
    assert!(
        norm(&dx) <= 1e-7 * norm(&direct.x),
        "{:e}",
        norm(&dx) / norm(&direct.x)
    );
    // With the rigid motions the multigrid needs far fewer CG steps than
    // with scalar aggregation (no near-null space).
    let mut bare = qp.clone();
    bare.near = None;
    let b = crate::qp::registry::solve("ssn", &bare, &o).unwrap();
    assert!(b.status.converged(), "{:?}", b.status);
    assert!(
        2 * it.inner_iterations < b.inner_iterations,
        "{} CG steps with rigid motions, {} without",
        it.inner_iterations,
        b.inner_iterations
    );
}

/// Friction is refused by the iterative path with a message that names
/// the setting, not solved wrongly.
#[test]
fn iterative_path_refuses_friction() {
    let qp = crate::qp::testing::friction_point(
        1.0,
        0.5,
        -1.0,
        crate::qp::SlipBound::Coulomb(vec![0.3]),
    );
    let mut o = opts();
    o.settings.ssn.path = crate::qp::settings::SsnPath::Iterative;
    let e = crate::qp::registry::solve("ssn", &qp, &o).unwrap_err();
    assert!(e.to_string().contains("ssn_path = \"iterative\""), "{e}");
}

/// A soft body floating under a stiff one (contrast 1e8): the K_J solves
/// meet their rounding floor above 1e-6 of the contact forces; CG stops on
/// the stall rule instead of running to its step limit, and the answer is
/// certified and is the direct path's working set.
#[test]
fn iterative_path_under_a_contrast_of_1e8() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/hard/stack_floating_soft_below_1e8.toml");
    let m = crate::run::prepare(&path, false).unwrap().model;
    let mut o = SolveOptions::default();
    let direct = crate::qp::registry::solve("ssn", &m.qp, &o).unwrap();
    o.settings.ssn.path = crate::qp::settings::SsnPath::Iterative;
    let it = crate::qp::registry::solve("ssn", &m.qp, &o).unwrap();
    assert!(it.status.converged(), "{:?}", it.status);
    assert!(it.kkt.within(1e-6), "{:?}", it.kkt);
    assert_eq!(it.active, direct.active);
    assert!(
        it.inner_iterations < 1000,
        "{} CG steps",
        it.inner_iterations
    );
}

/// Same input, same bits, whatever the number of threads: the iterative
/// path's products and sums run on rayon's threads above 20 000 rows, and
/// must not let the thread count reach the answer (24 000 unknowns here).
#[test]
fn iterative_path_bits_do_not_depend_on_the_thread_count() {
    let qp = two_blocks(100, 60, true);
    assert!(qp.n() > 20_000);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut o = opts();
                o.settings.tol = 1e-10;
                o.settings.ssn.path = crate::qp::settings::SsnPath::Iterative;
                let r = crate::qp::registry::solve("ssn", &qp, &o).unwrap();
                (
                    r.status.converged(),
                    r.inner_iterations,
                    r.solution.x,
                    r.solution.lambda,
                )
            })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.0, "not converged");
    assert_eq!(one.1, two.1, "CG steps differ");
    assert_eq!(one.2, two.2, "x differs between 1 and 2 threads");
    assert_eq!(one.3, two.3, "λ differs between 1 and 2 threads");
}

/// `hold_free_modes`: the dropped row (λ < 0) opens, the body turns until
/// the row on the other side closes, and that row joins J; a motion every
/// row leaves free (its column of AR rounding noise, as a ring sliding
/// along flat plates) is not held by a row picked from the noise.
#[test]
fn a_set_that_frees_a_body_is_completed_by_the_row_that_closes() {
    let ar = vec![vec![1.0, 1e-18], vec![0.5, -1e-18], vec![-1.0, 2e-18]];
    let (g, ax) = (vec![0.0, 0.3, 0.2], vec![0.0, 0.0, 0.0]);
    let solved = vec![true, false, false];
    let lam = vec![-1.0, 0.0, 0.0];
    let next = super::hold_free_modes(vec![false; 3], &solved, &ar, &lam, &ax, &g);
    assert_eq!(next, vec![false, false, true]);
    // Nothing to hold: unchanged.
    let held = vec![true, false, true];
    assert_eq!(
        super::hold_free_modes(held.clone(), &held, &ar, &[1.0, 0.0, 1.0], &ax, &g),
        held
    );
}
