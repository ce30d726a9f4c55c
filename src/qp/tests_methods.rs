//! Cross-checks of the QP methods (preelim, penalty, uzawa, dual, asm, asm-cgh)
//! against CGC with the Cholesky preconditioner on small two-body contact
//! problems: 2D trusses on a square grid (with diagonals, hence rigid), one
//! contact row per pair of facing nodes, g = 0 and g > 0, coercive and
//! semicoercive (a floating body resting in a V-shaped contact). The
//! reference is `qp::testing::reference`.

use crate::linalg::sparse::{norm, norm_inf};
use crate::qp::precond::PrecondKind;
use crate::qp::testing::reference;
use crate::qp::{primal::cgc, registry, Csr, QpError, QpProblem, QpResult, SolveOptions, Status};

#[derive(Clone, Copy, Debug)]
enum Variant {
    /// Body 1 fixed at the bottom, body 2 fixed at the top; normals (0, 1).
    Coercive { gaps: bool },
    /// Body 2 floating (3 rigid modes in `kernel`), pushed into a V-shaped contact.
    Floating { gaps: bool },
}

/// Two nx×ny truss grids, body 2 above body 1.
fn two_bodies(v: Variant) -> QpProblem {
    let (nx, ny) = (9usize, 4usize);
    let h = 1.0;
    let floating = matches!(v, Variant::Floating { .. });
    let gaps = match v {
        Variant::Coercive { gaps } | Variant::Floating { gaps } => gaps,
    };
    // nodes: (body, i, j) → coordinates; body 2 sits one unit above body 1.
    let mut coords = vec![];
    let mut fixed = vec![];
    for b in 0..2 {
        for j in 0..ny {
            for i in 0..nx {
                let y = if b == 0 {
                    j as f64 * h
                } else {
                    (ny as f64) * h + j as f64 * h
                };
                coords.push((i as f64 * h, y));
                fixed.push((b == 0 && j == 0) || (b == 1 && !floating && j == ny - 1));
            }
        }
    }
    let node = |b: usize, i: usize, j: usize| b * nx * ny + j * nx + i;
    let mut dof = vec![usize::MAX; 2 * coords.len()];
    let mut n = 0;
    for (k, &f) in fixed.iter().enumerate() {
        if !f {
            dof[2 * k] = n;
            dof[2 * k + 1] = n + 1;
            n += 2;
        }
    }
    let mut trip = vec![];
    let mut count = 0usize;
    let mut spring = |a: usize, b: usize, trip: &mut Vec<(usize, usize, f64)>| {
        count += 1;
        let k = 1e4 * (1.0 + 0.3 * (count as f64 * 0.7).sin());
        let (dx, dy) = (coords[b].0 - coords[a].0, coords[b].1 - coords[a].1);
        let l = (dx * dx + dy * dy).sqrt();
        let e = [dx / l, dy / l];
        for (p, sp) in [(a, 1.0), (b, -1.0)] {
            for (q, sq) in [(a, 1.0), (b, -1.0)] {
                for r in 0..2 {
                    for c in 0..2 {
                        let (i, j) = (dof[2 * p + r], dof[2 * q + c]);
                        if i != usize::MAX && j != usize::MAX {
                            trip.push((i, j, sp * sq * k * e[r] * e[c]));
                        }
                    }
                }
            }
        }
    };
    for b in 0..2 {
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx {
                    spring(node(b, i, j), node(b, i + 1, j), &mut trip);
                }
                if j + 1 < ny {
                    spring(node(b, i, j), node(b, i, j + 1), &mut trip);
                }
                if i + 1 < nx && j + 1 < ny {
                    spring(node(b, i, j), node(b, i + 1, j + 1), &mut trip);
                    spring(node(b, i + 1, j), node(b, i, j + 1), &mut trip);
                }
            }
        }
    }
    let c = Csr::from_triplets(n, n, &trip);
    // Loads.
    let mut d = vec![0.0; n];
    for i in 0..nx {
        let t = i as f64 / (nx - 1) as f64;
        if floating {
            for j in 0..ny {
                let k = node(1, i, j);
                d[dof[2 * k]] += 0.3;
                d[dof[2 * k + 1]] += -1.0 - 0.8 * (3.0 * t).sin();
            }
        } else {
            let k = node(1, i, 0);
            d[dof[2 * k + 1]] += -3.0 * (std::f64::consts::PI * t).cos() - 0.5;
            d[dof[2 * k]] += 0.2;
        }
        let k = node(0, i, ny - 1);
        d[dof[2 * k + 1]] += 0.4 * (1.0 + t);
    }
    // Contact rows (u1 − u2)·n ≤ g between facing nodes.
    let mut atrip = vec![];
    let mut g = vec![];
    for i in 0..nx {
        let nrm = if floating {
            let s: f64 = if 2 * i < nx - 1 { 0.35 } else { -0.35 };
            (s.sin(), s.cos())
        } else {
            (0.0, 1.0)
        };
        let (a, b) = (node(0, i, ny - 1), node(1, i, 0));
        atrip.push((i, dof[2 * a], nrm.0));
        atrip.push((i, dof[2 * a + 1], nrm.1));
        atrip.push((i, dof[2 * b], -nrm.0));
        atrip.push((i, dof[2 * b + 1], -nrm.1));
        g.push(if gaps {
            1e-5 * ((i * 5 % 3) as f64)
        } else {
            0.0
        });
    }
    let a = Csr::from_triplets(nx, n, &atrip);
    let mut kernel = vec![];
    if floating {
        let mut tx = vec![0.0; n];
        let mut ty = vec![0.0; n];
        let mut rot = vec![0.0; n];
        for j in 0..ny {
            for i in 0..nx {
                let k = node(1, i, j);
                let (x, y) = coords[k];
                tx[dof[2 * k]] = 1.0;
                ty[dof[2 * k + 1]] = 1.0;
                rot[dof[2 * k]] = -(y - 5.5);
                rot[dof[2 * k + 1]] = x - 4.0;
            }
        }
        kernel = vec![tx, ty, rot];
    }
    QpProblem {
        c,
        d,
        a,
        g,
        kernel,
        friction: None,
        near: None,
    }
}

fn opts(tol: f64) -> SolveOptions {
    {
        let mut o = SolveOptions::default();
        o.settings.tol = tol;
        o.settings.max_iter = 1_000_000;
        o.settings.cgc.preconditioner = PrecondKind::Cholesky;
        o
    }
}

fn rel_err(x: &[f64], y: &[f64]) -> f64 {
    let d: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    norm(&d) / norm(y).max(1e-300)
}

const VARIANTS: [Variant; 4] = [
    Variant::Coercive { gaps: false },
    Variant::Coercive { gaps: true },
    Variant::Floating { gaps: false },
    Variant::Floating { gaps: true },
];

#[test]
fn test_problems_are_nondegenerate() {
    for v in VARIANTS {
        let qp = two_bodies(v);
        let r = reference(&qp);
        let ax = qp.a.mul(&r.x);
        let lmax = norm_inf(&r.lambda);
        let xmax = norm_inf(&r.x);
        let nact = r.active.iter().filter(|b| **b).count();
        assert!(
            nact > 0 && nact < qp.m(),
            "{v:?}: {nact} of {} active",
            qp.m()
        );
        for i in 0..qp.m() {
            let slack = qp.g[i] - ax[i];
            assert!(
                r.lambda[i] > 1e-4 * lmax || slack > 1e-4 * xmax,
                "{v:?}: constraint {i} weakly active (λ {:e}, slack {slack:e})",
                r.lambda[i]
            );
            assert_eq!(r.active[i], r.lambda[i] > 1e-4 * lmax, "{v:?} row {i}");
        }
    }
}

/// x, active set, KKT and λ ≥ 0 against the reference.
fn check_exact(name: &str, v: Variant, qp: &QpProblem, r: &QpResult, refr: &QpResult) {
    assert!(
        r.status.converged(),
        "{name} {v:?}: {}",
        r.status.describe()
    );
    let e = rel_err(&r.x, &refr.x);
    assert!(e < 1e-6, "{name} {v:?}: relative error {e:e}");
    assert_eq!(r.active, refr.active, "{name} {v:?}: active set");
    assert!(r.kkt.within(1e-8), "{name} {v:?}: KKT {:?}", r.kkt);
    assert!(r.lambda.iter().all(|&l| l >= 0.0), "{name} {v:?}: λ < 0");
    let le = rel_err(&r.lambda, &refr.lambda);
    assert!(le < 1e-6, "{name} {v:?}: λ relative error {le:e}");
    assert!((r.energy - qp.energy(&r.x)).abs() <= 1e-12 * r.energy.abs().max(1.0));
    assert!(
        !r.timings.is_empty() && r.iterations > 0,
        "{name}: bookkeeping"
    );
}

#[test]
fn exact_methods_match_cgc_coercive() {
    for v in [VARIANTS[0], VARIANTS[1]] {
        let qp = two_bodies(v);
        let refr = reference(&qp);
        for name in ["preelim", "uzawa", "dual", "asm", "asm-cgh"] {
            let tol = if name == "asm-cgh" { 1e-11 } else { 1e-12 };
            let r =
                registry::solve(name, &qp, &opts(tol)).unwrap_or_else(|e| panic!("{name}: {e}"));
            check_exact(name, v, &qp, &r, &refr);
        }
        // The report's plain Uzawa (no momentum) converges to the same pair, slower.
        let plain = {
            let mut o = opts(1e-12);
            o.settings.penalty.accelerate = false;
            o.settings.uzawa.accelerate = false;
            o
        };
        let r = registry::solve("uzawa", &qp, &plain).unwrap();
        check_exact("uzawa (plain)", v, &qp, &r, &refr);
        let fast = registry::solve("uzawa", &qp, &opts(1e-12)).unwrap();
        assert!(
            fast.iterations < r.iterations,
            "{v:?}: accelerated {} vs plain {} iterations",
            fast.iterations,
            r.iterations
        );
    }
}

#[test]
fn semicoercive_solved() {
    for v in [VARIANTS[2], VARIANTS[3]] {
        let qp = two_bodies(v);
        let refr = reference(&qp);
        for name in ["preelim", "uzawa", "dual", "asm", "asm-cgh", "penalty"] {
            // preelim runs CGC on the reduced problem: its floor applies.
            let mut o = opts(match name {
                "asm-cgh" => 1e-11,
                "preelim" => 1e-10,
                _ => 1e-12,
            });
            if name == "penalty" {
                o.settings.penalty.eps = Some(1e-3 / norm_inf(&qp.c.diag()));
                o.settings.cgc.omega = 1.5;
                o.settings.penalty.omega = 1.5;
            }
            match registry::solve(name, &qp, &o) {
                Err(e) => panic!("{name} {v:?}: unexpected error {e}"),
                Ok(r) if name == "penalty" => {
                    assert!(r.status.converged(), "{name}: {}", r.status.describe());
                    let e = rel_err(&r.x, &refr.x);
                    assert!(e < 1e-2, "penalty semicoercive error {e:e}");
                    assert!(r.kkt.stationarity < 1e-7, "{:?}", r.kkt);
                }
                Ok(r) => check_exact(name, v, &qp, &r, &refr),
            }
        }
    }
}

#[test]
fn semicoercive_unbounded_is_detected() {
    // Pull the floating body away from the contact: no solution.
    let mut qp = two_bodies(Variant::Floating { gaps: true });
    for v in qp.d.iter_mut() {
        *v = 0.0;
    }
    let n = qp.n();
    for k in (n - 2 * 9 * 4..n).skip(1).step_by(2) {
        qp.d[k] = 1.0; // +y on every node of body 2
    }
    for name in ["asm", "asm-cgh"] {
        let r = registry::solve(name, &qp, &opts(1e-11)).unwrap();
        match &r.status {
            Status::Unbounded { direction } => {
                assert!(
                    norm(&qp.c.mul(direction)) <= 1e-8 * norm(direction) * norm_inf(&qp.c.diag())
                );
                assert!(
                    crate::linalg::sparse::dot(direction, &qp.d) > 0.0,
                    "{name}: not a descent direction"
                );
            }
            s => panic!("{name}: expected Unbounded, got {}", s.describe()),
        }
    }
}

/// The report's plain relaxation (no subspace correction).
fn penalty_run(qp: &QpProblem, eps: Option<f64>, omega: f64, tol: f64) -> QpResult {
    let mut o = opts(tol);
    o.settings.penalty.eps = eps;
    o.settings.cgc.omega = omega;
    o.settings.penalty.omega = omega;
    o.settings.penalty.accelerate = false;
    o.settings.uzawa.accelerate = false;
    let r = registry::solve("penalty", qp, &o).expect("penalty");
    assert!(r.status.converged(), "penalty: {}", r.status.describe());
    r
}

#[test]
fn penalty_error_is_first_order_in_eps() {
    let qp = two_bodies(Variant::Coercive { gaps: true });
    let refr = reference(&qp);
    let cmax = norm_inf(&qp.c.diag());
    let mut errs = vec![];
    for k in 1..=3 {
        let eps = 10f64.powi(-k) / cmax;
        let r = penalty_run(&qp, Some(eps), 1.6, 1e-12);
        let e = rel_err(&r.x, &refr.x);
        let le = rel_err(&r.lambda, &refr.lambda);
        // Stationarity is exact for λ = (Ax − g)⁺/ε; the violation is O(ε).
        assert!(r.kkt.stationarity < 1e-7, "{:?}", r.kkt);
        assert!(
            r.kkt.primal < 1e3 * eps * cmax,
            "ε {eps:e}: primal {:e}",
            r.kkt.primal
        );
        assert!(r.lambda.iter().all(|&l| l >= 0.0));
        assert!(le < 100.0 * eps * cmax, "λ error {le:e}");
        errs.push(e);
    }
    for w in errs.windows(2) {
        let ratio = w[1] / w[0];
        assert!((0.05..0.2).contains(&ratio), "errors {errs:?} not O(ε)");
    }
    // Small enough ε: the active set is exact as well.
    let r = penalty_run(&qp, Some(1e-3 / cmax), 1.6, 1e-12);
    assert_eq!(r.active, refr.active);
}

#[test]
fn penalty_default_eps_and_gauss_seidel() {
    let qp = two_bodies(Variant::Coercive { gaps: false });
    let refr = reference(&qp);
    let gs = penalty_run(&qp, None, 1.0, 1e-13);
    let sor = penalty_run(&qp, None, 1.7, 1e-13);
    assert!(
        rel_err(&gs.x, &refr.x) < 1e-2,
        "{}",
        rel_err(&gs.x, &refr.x)
    );
    assert!(rel_err(&gs.x, &sor.x) < 1e-8);
    assert!(
        sor.iterations < gs.iterations,
        "SOR {} vs GS {}",
        sor.iterations,
        gs.iterations
    );
}

#[test]
fn penalty_subspace_correction_finds_the_same_minimiser() {
    for v in VARIANTS {
        let qp = two_bodies(v);
        let cmax = norm_inf(&qp.c.diag());
        let eps = 1e-3 / cmax;
        let fast = registry::solve("penalty", &qp, &{
            let mut o = opts(1e-13);
            o.settings.penalty.eps = Some(eps);
            o
        })
        .unwrap();
        assert!(fast.status.converged(), "{v:?}: {}", fast.status.describe());
        assert!(fast.inner_iterations > 0, "{v:?}: no correction was made");
        let mut o = opts(1e-13);
        o.settings.penalty.eps = Some(eps);
        o.settings.cgc.omega = 1.6;
        o.settings.penalty.omega = 1.6;
        o.settings.penalty.accelerate = false;
        o.settings.uzawa.accelerate = false;
        let plain = registry::solve("penalty", &qp, &o).unwrap();
        if plain.status.converged() {
            let e = rel_err(&fast.x, &plain.x);
            assert!(e < 1e-8, "{v:?}: corrected vs plain x_ε differ by {e:e}");
            assert!(fast.iterations < plain.iterations);
        }
        // x_ε is O(ε) from x: within 10× its own relative violation.
        let refr = reference(&qp);
        let e = rel_err(&fast.x, &refr.x);
        assert!(
            e <= (10.0 * fast.kkt.primal).max(1e-6),
            "{v:?}: {e:e} vs {:?}",
            fast.kkt
        );
        assert_eq!(fast.active, refr.active, "{v:?}");
    }
}

#[test]
fn no_constraints() {
    let mut qp = two_bodies(Variant::Coercive { gaps: false });
    qp.a = Csr::zeros(0, qp.n());
    qp.g = vec![];
    let x = crate::linalg::cholesky::Cholesky::new(&qp.c, &[])
        .unwrap()
        .solve(&qp.d);
    for name in ["preelim", "uzawa", "dual", "asm", "asm-cgh", "penalty"] {
        let r = registry::solve(name, &qp, &opts(1e-12)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(r.status.converged(), "{name}: {}", r.status.describe());
        let tol = if name == "penalty" { 1e-6 } else { 1e-8 };
        assert!(rel_err(&r.x, &x) < tol, "{name}: {}", rel_err(&r.x, &x));
    }
}

#[test]
fn bad_parameters_do_not_panic() {
    let qp = two_bodies(Variant::Coercive { gaps: true });
    let names = ["preelim", "uzawa", "dual", "asm", "asm-cgh", "penalty"];
    let bad = [
        {
            let mut o = opts(1e-10);
            o.settings.uzawa.rho = Some(-1.0);
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.uzawa.rho = Some(f64::NAN);
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.uzawa.rho = Some(1e12);
            o.settings.max_iter = 50;
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.penalty.eps = Some(-1.0);
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.penalty.eps = Some(0.0);
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.cgc.omega = 3.0;
            o.settings.penalty.omega = 3.0;
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.tol = f64::NAN;
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.tol = -1.0;
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.max_iter = 0;
            o
        },
        {
            let mut o = opts(1e-10);
            o.settings.max_iter = 1;
            o
        },
    ];
    for o in &bad {
        for name in names {
            // Either an error or a result; never a panic.
            if let Ok(r) = registry::solve(name, &qp, o) {
                assert_eq!(r.x.len(), qp.n());
                assert_eq!(r.lambda.len(), qp.m());
            }
        }
    }
    // A huge ρ makes Uzawa diverge: reported as a status, not a panic.
    let r = registry::solve("uzawa", &qp, &bad[2]).unwrap();
    assert!(!r.status.converged());
}

#[test]
fn preelim_refuses_singular_c11() {
    // A floating body whose contact DOFs do not fix it: only the y-DOF of one
    // node constrained. Its motion is free (no row, no load on it): with the
    // kernel known the driver holds it and preelim solves (x0 = x1 = 0);
    // with the kernel unknown C₁₁ is singular and preelim refuses.
    let c = Csr::from_triplets(
        3,
        3,
        &[
            (0, 0, 1.0),
            (0, 1, -1.0),
            (1, 0, -1.0),
            (1, 1, 1.0),
            (2, 2, 1.0),
        ],
    );
    let a = Csr::from_triplets(1, 3, &[(0, 2, 1.0)]);
    let qp = QpProblem {
        c,
        d: vec![0.0, 0.0, 1.0],
        a,
        g: vec![0.0],
        kernel: vec![vec![1.0, 1.0, 0.0]],
        friction: None,
        near: None,
    };
    let r = registry::solve("preelim", &qp, &opts(1e-10)).unwrap();
    assert!(r.status.converged() && r.kkt.within(1e-8), "{:?}", r.kkt);
    assert!(
        r.x[0] == 0.0 && r.x[1] == 0.0 && r.x[2].abs() < 1e-12,
        "{:?}",
        r.x
    );
    let qp = QpProblem {
        kernel: vec![],
        ..qp
    };
    match registry::solve("preelim", &qp, &opts(1e-10)) {
        Err(QpError::Unsupported(msg)) => assert!(msg.contains("C11"), "{msg}"),
        Err(e) => panic!("unexpected error {e}"),
        Ok(r) => panic!("expected refusal, got {}", r.status.describe()),
    }
    // The reference copes (the energy is constant along the kernel).
    let qp = QpProblem {
        kernel: vec![vec![1.0, 1.0, 0.0]],
        ..qp
    };
    let r = crate::qp::run_direct(cgc::solve, &qp, &opts(1e-10)).unwrap();
    assert!(r.status.converged());
}

/// A factor refused for memory ends the solve with `QpError::Memory`,
/// whatever the method: it is never read as "this matrix cannot be
/// factored" and answered by another path (ssn's Schur path after its
/// augmented one, penalty going on without its correction), or the bits of
/// an answer would depend on the machine's free memory.
#[test]
fn a_factor_refused_for_memory_ends_every_method_without_another_path() {
    use crate::linalg::cholesky::Workspace;
    use crate::qp::settings::SsnPath;
    let qp = two_bodies(Variant::Coercive { gaps: true });
    let memory = |r: Result<QpResult, QpError>| match r {
        Err(QpError::Memory(msg)) => assert!(msg.contains("needs"), "{msg}"),
        Err(e) => panic!("not a memory error: {e}"),
        Ok(r) => panic!("solved ({}) under a refused factor", r.status.describe()),
    };
    // (asm-cgh factors nothing unless its CG with hyperbolic pairs fails)
    for name in [
        "cgc", "preelim", "penalty", "uzawa", "dual", "asm", "mprgp", "ssn",
    ] {
        let ws = Workspace::new().with_memory_limit(1);
        memory(registry::solve_in(name, &qp, &opts(1e-12), &ws));
    }
    // The smallest limit under which ssn's Schur path (one factor of C)
    // solves: the augmented path's factor of C + AᵀA is larger, so ssn
    // forced onto it must fail there, not fall back to the Schur path.
    let with_path = |path: SsnPath| {
        let mut o = opts(1e-12);
        o.settings.ssn.path = path;
        o
    };
    let solves = |limit: u64| {
        let ws = Workspace::new().with_memory_limit(limit);
        registry::solve_in("ssn", &qp, &with_path(SsnPath::Schur), &ws).is_ok()
    };
    let (mut lo, mut hi) = (1u64, 1u64 << 30);
    assert!(solves(hi) && !solves(lo));
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if solves(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let ws = Workspace::new().with_memory_limit(hi);
    memory(registry::solve_in(
        "ssn",
        &qp,
        &with_path(SsnPath::Augmented),
        &ws,
    ));
    // With room for both, the augmented path solves.
    let ws = Workspace::new().with_memory_limit(1 << 30);
    let r = registry::solve_in("ssn", &qp, &with_path(SsnPath::Augmented), &ws).unwrap();
    assert!(r.status.converged(), "{}", r.status.describe());
}

/// No method stalls on an exact start (docs/methods.md §8.4): started at
/// the answer (x0 and the working set of the reference), or on a problem
/// whose first iterate is already exact (no load, open gaps: x = 0, λ = 0),
/// every method is certified within 30 iterations. Before, the dual method
/// measured its residual against a best of −0 that no relative measure can
/// go below, ran to MAXIT or 10 000 iterations of stagnation, and exited
/// "not converged" with every KKT residual at rounding.
#[test]
fn every_method_is_certified_from_an_exact_start() {
    use crate::qp::method::MethodId;
    let mut unloaded = two_bodies(Variant::Coercive { gaps: true });
    unloaded.d.iter_mut().for_each(|d| *d = 0.0);
    unloaded.g.iter_mut().for_each(|g| *g = g.abs() + 1e-3);
    let cases: Vec<(&str, QpProblem, bool)> = vec![
        (
            "coercive, warm",
            two_bodies(Variant::Coercive { gaps: true }),
            true,
        ),
        (
            "floating, warm",
            two_bodies(Variant::Floating { gaps: true }),
            true,
        ),
        ("unloaded, cold", unloaded, false),
    ];
    for (case, qp, warm) in cases {
        let refr = reference(&qp);
        for m in MethodId::ALL {
            if warm && !m.capabilities().warm_start {
                continue;
            }
            let mut o = opts(1e-10);
            o.settings.max_iter = 30;
            if warm {
                o.x0 = Some(refr.x.clone());
                o.active0 = Some(refr.active.clone());
            }
            let r = registry::solve(m, &qp, &o).unwrap_or_else(|e| panic!("{m} {case}: {e}"));
            assert!(
                r.status.converged() && registry::certified(m, &r.kkt, 1e-6, false),
                "{m} {case}: {} after {} iterations, KKT {:?}",
                r.status.describe(),
                r.iterations,
                r.kkt
            );
            let e = rel_err(&r.x, &refr.x);
            let tol = if m == MethodId::Penalty { 1e-3 } else { 1e-6 };
            assert!(
                e <= tol || norm_inf(&refr.x) == 0.0 && norm_inf(&r.x) <= 1e-12,
                "{m} {case}: x off by {e:e}"
            );
        }
    }
}
