//! Tests of ssn on discs (the parent module, docs/methods.md §12.3).
use crate::qp::testing::friction_point3;
use crate::qp::{registry, SlipBound, SolveOptions};

fn solve(q: &crate::qp::QpProblem) -> crate::qp::QpResult {
    let r = registry::solve("ssn", q, &SolveOptions::default()).unwrap();
    if r.status.converged() {
        assert!(r.kkt.within(1e-10), "{:?}", r.kkt);
    }
    r
}

/// Points i on a floor below (row i: −u_z ≤ gᵢ), their tangential rows
/// along x and y, stiffness C from `trip` and loads `d` (3 unknowns a point).
fn points_on_a_floor(
    trip: &[(usize, usize, f64)],
    d: Vec<f64>,
    g: Vec<f64>,
    bound: SlipBound,
) -> crate::qp::QpProblem {
    use crate::qp::{Csr, Friction, QpProblem};
    let p = g.len();
    let a: Vec<_> = (0..p).map(|i| (i, 3 * i + 2, -1.0)).collect();
    let t: Vec<_> = (0..p)
        .flat_map(|i| [(2 * i, 3 * i, 1.0), (2 * i + 1, 3 * i + 1, 1.0)])
        .collect();
    QpProblem {
        c: Csr::from_triplets(3 * p, 3 * p, trip),
        d,
        a: Csr::from_triplets(p, 3 * p, &a),
        g,
        kernel: vec![],
        friction: Some(Friction {
            t: Csr::from_triplets(2 * p, 3 * p, &t),
            t0: vec![0.0; 2 * p],
            bound,
            frame: crate::qp::Frame::Plane,
        }),
        near: None,
    }
}

/// A point on a floor under an oblique load, at angles off the frame's
/// axes: it sticks below μN with λ_t the load, and above it slips along
/// the load with ‖λ_t‖ = μN exactly (the test a polygonal cone fails).
#[test]
fn a_point_sticks_below_mu_n_and_slips_along_the_load_above() {
    for deg in [0.0f64, 17.0, 30.0, 45.0, 133.0, 250.0] {
        let a = deg.to_radians();
        let dir = [a.cos(), a.sin()];
        for (q_load, mu) in [(0.8, 0.5), (1.5, 0.5), (3.0, 1.0)] {
            let n = 2.0;
            let f = [q_load * dir[0], q_load * dir[1], -n];
            for bound in [
                SlipBound::Coulomb(vec![mu]),
                SlipBound::Tresca(vec![mu * n]),
            ] {
                let r = solve(&friction_point3(4.0, f, bound.clone()));
                assert!(r.status.converged(), "{deg}° {bound:?}: {:?}", r.status);
                assert!((r.lambda[0] - n).abs() < 1e-12, "{:?}", r.lambda);
                let s = mu * n;
                let lt = &r.lambda_t;
                if q_load <= s {
                    assert!((lt[0] - f[0]).abs() < 1e-12 && (lt[1] - f[1]).abs() < 1e-12);
                    assert!(r.x[0].abs() < 1e-12 && r.x[1].abs() < 1e-12, "{:?}", r.x);
                } else {
                    let ln = lt[0].hypot(lt[1]);
                    assert!((ln - s).abs() < 1e-12 * s, "{deg}°: {lt:?}");
                    let cross = lt[0] * dir[1] - lt[1] * dir[0];
                    assert!(cross.abs() < 1e-12, "{deg}°: {lt:?}");
                    let u = (q_load - s) / 4.0;
                    assert!((r.x[0] - u * dir[0]).abs() < 1e-12, "{:?}", r.x);
                    assert!((r.x[1] - u * dir[1]).abs() < 1e-12, "{:?}", r.x);
                }
            }
        }
    }
}

/// Held by friction alone (no spring in the plane): below μN it
/// sticks; above, the point slides away (unbounded, along the load).
#[test]
fn a_floating_point_sticks_or_slides_away() {
    let f = [0.3, 0.4, -2.0];
    let r = solve(&friction_point3(0.0, f, SlipBound::Coulomb(vec![0.5])));
    assert!(r.status.converged(), "{:?}", r.status);
    assert!((r.lambda_t[0] - 0.3).abs() < 1e-12 && (r.lambda_t[1] - 0.4).abs() < 1e-12);
    let r = solve(&friction_point3(0.0, f, SlipBound::Tresca(vec![0.4])));
    match &r.status {
        crate::qp::Status::Unbounded { direction } => {
            let c = direction[0] * 0.4 - direction[1] * 0.3;
            assert!(c.abs() < 1e-9 * direction[0].abs().max(direction[1].abs()));
        }
        s => panic!("{s:?}"),
    }
}

/// A ring of p points on a floor, each tied by a spring k to a driver
/// turned by θ (loads k·θ ẑ × rᵢ) and to its neighbours by springs kc
/// in each component, with tangent frames turned by a different angle
/// at each point: the slip and the friction force are circumferential
/// at every point, of size s when kθρ > s (by symmetry every point
/// slips alike, its load s plus the springs' force on the slip), and
/// every point sticks with λ_t its load when kθρ ≤ s.
#[test]
fn a_ring_turned_on_a_floor_slips_around_the_circle() {
    use crate::qp::{Csr, Friction, QpProblem};
    let (p, rho, k, kc, n) = (12usize, 0.5, 3.0, 40.0, 2.0);
    for (theta, mu) in [(1.0, 0.25), (0.2, 0.5)] {
        let mut trip = vec![];
        let mut d = vec![0.0; 3 * p];
        let (mut a, mut t) = (vec![], vec![]);
        for i in 0..p {
            let phi = 2.0 * std::f64::consts::PI * i as f64 / p as f64;
            let (x, y) = (rho * phi.cos(), rho * phi.sin());
            d[3 * i] = k * (-theta * y);
            d[3 * i + 1] = k * (theta * x);
            d[3 * i + 2] = -n;
            for c in 0..2 {
                trip.push((3 * i + c, 3 * i + c, k));
            }
            trip.push((3 * i + 2, 3 * i + 2, 3.0));
            let j = (i + 1) % p;
            for c in 0..3 {
                let (u, v) = (3 * i + c, 3 * j + c);
                trip.extend([(u, u, kc), (v, v, kc), (u, v, -kc), (v, u, -kc)]);
            }
            a.push((i, 3 * i + 2, -1.0));
            let f = 0.7 * i as f64;
            t.push((2 * i, 3 * i, f.cos()));
            t.push((2 * i, 3 * i + 1, f.sin()));
            t.push((2 * i + 1, 3 * i, -f.sin()));
            t.push((2 * i + 1, 3 * i + 1, f.cos()));
        }
        let q = QpProblem {
            c: Csr::from_triplets(3 * p, 3 * p, &trip),
            d,
            a: Csr::from_triplets(p, 3 * p, &a),
            g: vec![0.1; p],
            kernel: vec![],
            friction: Some(Friction {
                t: Csr::from_triplets(2 * p, 3 * p, &t),
                t0: vec![0.0; 2 * p],
                bound: SlipBound::Coulomb(vec![mu; p]),
                frame: crate::qp::Frame::Plane,
            }),
            near: None,
        };
        let r = solve(&q);
        assert!(r.status.converged(), "{:?}", r.status);
        // The floor 0.1 below: λ_n = n − 3·0.1 (a point at rest would
        // be judged against max|x| = rounding, docs/methods.md §9.4).
        let s = mu * (n - 0.3);
        for i in 0..p {
            let phi = 2.0 * std::f64::consts::PI * i as f64 / p as f64;
            let e = [-phi.sin(), phi.cos()];
            let f = 0.7 * i as f64;
            let (l1, l2) = (r.lambda_t[2 * i], r.lambda_t[2 * i + 1]);
            let lg = [l1 * f.cos() - l2 * f.sin(), l1 * f.sin() + l2 * f.cos()];
            let load = k * theta * rho;
            // The ring's springs resist a turn of every point by a
            // along its circle with kc·a·(2 − 2cos(2π/p)) along it.
            let ring = kc * (2.0 - 2.0 * (2.0 * std::f64::consts::PI / p as f64).cos());
            let (size, slip) = if load > s {
                (s, (load - s) / (k + ring))
            } else {
                (load, 0.0)
            };
            for c in 0..2 {
                assert!((lg[c] - size * e[c]).abs() < 1e-10, "{i}: {lg:?}");
                assert!(
                    (r.x[3 * i + c] - slip * e[c]).abs() < 1e-10,
                    "{i}: {:?}",
                    r.x
                );
            }
        }
    }
}

/// A line of points pressed onto a curved floor (gaps xᵢ²/2R, a
/// parabolic obstacle as under a sphere) by a load at its middle and
/// pulled sideways: the unconstrained answer penetrates far more rows
/// than touch. The glued solve starts from the frictionless normal set
/// (`State::normal_start`, docs/methods.md §12.3), so its Newton steps
/// only settle the stick rows; the answer is certified and agrees with
/// mprgp's on the same discs.
#[test]
fn a_line_pressed_on_a_curved_floor_starts_from_the_frictionless_set() {
    let (p, h, radius, kc) = (41usize, 0.05, 1.0, 20.0);
    let mut trip = vec![];
    let mut d = vec![0.0; 3 * p];
    let mut g = vec![];
    for i in 0..p {
        let x = (i as f64 - 20.0) * h;
        for c in 0..3 {
            trip.push((3 * i + c, 3 * i + c, if c == 2 { 0.05 } else { 1.0 }));
        }
        if i + 1 < p {
            for c in 0..3 {
                let (u, v) = (3 * i + c, 3 * i + 3 + c);
                trip.extend([(u, u, kc), (v, v, kc), (u, v, -kc), (v, u, -kc)]);
            }
        }
        if (18..=22).contains(&i) {
            d[3 * i + 2] = -3.0;
            d[3 * i] = 0.4;
        }
        g.push(x * x / (2.0 * radius));
    }
    let q = points_on_a_floor(&trip, d, g, SlipBound::Coulomb(vec![0.3; p]));
    let r = solve(&q);
    assert!(r.status.converged(), "{:?}", r.status);
    let touching = r.lambda.iter().filter(|l| **l > 0.0).count();
    // The unconstrained answer (the glued start's first set before)
    // penetrates more rows than end in contact.
    let x0 = {
        let f = crate::linalg::cholesky::Workspace::default()
            .cholesky(&q.c, &[])
            .unwrap();
        f.solve(&q.d)
    };
    let penetrating = (0..p).filter(|&i| -x0[3 * i + 2] > q.g[i]).count();
    assert!(penetrating > touching + 5, "{penetrating} {touching}");
    // 1 step (15 when the glued steps found N themselves).
    assert!(r.iterations <= 4, "{} Newton steps", r.iterations);
    let m = registry::solve("mprgp", &q, &SolveOptions::default()).unwrap();
    assert!(m.status.converged(), "{:?}", m.status);
    let scale = r.x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for (u, v) in r.x.iter().zip(&m.x) {
        assert!((u - v).abs() < 1e-6 * scale, "ssn {u}, mprgp {v}");
    }
}

/// A chain of `p` points on a floor (unit normal stiffness, a unit load
/// pressing each), neighbours tied by springs `kc` in x and y, the last
/// point held by a unit spring, the first pulled by `pull` along `dir`:
/// (the triplets of C, d).
fn chain(p: usize, kc: f64, pull: f64, dir: [f64; 2]) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let mut trip = vec![];
    let mut d = vec![0.0; 3 * p];
    for i in 0..p {
        let own = if i + 1 == p { 1.0 } else { 0.0 };
        for c in 0..3 {
            trip.push((3 * i + c, 3 * i + c, if c == 2 { 1.0 } else { own }));
        }
        if i + 1 < p {
            for c in 0..2 {
                let (u, v) = (3 * i + c, 3 * i + 3 + c);
                trip.extend([(u, u, kc), (v, v, kc), (u, v, -kc), (v, u, -kc)]);
            }
        }
        d[3 * i + 2] = -1.0;
    }
    d[0] = pull * dir[0];
    d[1] = pull * dir[1];
    (trip, d)
}

/// A chain of points pressed onto a flat floor and pulled at one end,
/// obliquely: the slip zone runs in from the pulled end, its points
/// carrying s = μN each along the pull, the first sticking point the rest,
/// the spring between points j and j+1 stretched by the pull less the
/// friction of points 0..=j (exact: the chain is tied in the plane only at
/// its far end, which sticks). From the glued start the front moved a row
/// or two a Newton step; the coarse start (`plane_nested`, docs/methods.md
/// §12.3) places it, so the steps stay bounded as the chain grows.
#[test]
fn a_chain_pulled_at_one_end_slips_in_a_bounded_number_of_steps() {
    let (kc, mu) = (10.0, 0.3);
    let dir = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
    let mut counts = vec![];
    for p in [40usize, 80, 160] {
        let k = p / 2;
        let pull = mu * (k as f64 + 0.5);
        let (trip, d) = chain(p, kc, pull, dir);
        let q = points_on_a_floor(&trip, d, vec![0.0; p], SlipBound::Coulomb(vec![mu; p]));
        let r = solve(&q);
        assert!(r.status.converged(), "{p}: {:?}", r.status);
        let mut u = 0.0;
        for i in (0..p).rev() {
            // λ_t along the pull: s on 0..k, the rest at k, 0 beyond.
            let lt = match i {
                _ if i < k => mu,
                _ if i == k => pull - mu * k as f64,
                _ => 0.0,
            };
            if i < k {
                u += (pull - mu * (i + 1) as f64) / kc;
            }
            for c in 0..2 {
                let (got, want) = (r.lambda_t[2 * i + c], lt * dir[c]);
                assert!(
                    (got - want).abs() < 1e-9,
                    "{p}: point {i}: λ_t {got}, want {want}"
                );
                let (got, want) = (r.x[3 * i + c], u * dir[c]);
                assert!(
                    (got - want).abs() < 1e-9 * (1.0 + u),
                    "{p}: point {i}: u {got}, want {want}"
                );
            }
        }
        counts.push(r.iterations);
    }
    // Bounded under refinement.
    assert!(counts.iter().all(|&c| c <= 12), "Newton steps {counts:?}");
    eprintln!("Newton steps {counts:?}");
}

/// Points pressed onto a floor through a stiffness that couples the slip
/// along x with the normal force (C_xz ≠ 0: λ_n = 2 + c·u_x, so each slip
/// changes its own bound μλ_n), under tangential loads from below to well
/// above μN at several angles. On the multigrid path
/// (`ssn_path = "iterative"`) the direct Coulomb iteration holds the bound
/// inside the augmented-Lagrangian sweeps (docs/methods.md §12.3), so it
/// ends in a few Newton steps where the Coulomb fixed point gained about
/// a factor μc a bound update; the answer is the dual path's.
#[test]
fn the_multigrid_path_holds_the_coulomb_bound_inside_its_steps() {
    let (p, c, mu) = (8usize, 0.6, 0.5);
    let mut trip = vec![];
    let mut d = vec![0.0; 3 * p];
    for i in 0..p {
        let (x, y, z) = (3 * i, 3 * i + 1, 3 * i + 2);
        trip.extend([(x, x, 1.0), (y, y, 1.0), (z, z, 1.0), (x, z, c), (z, x, c)]);
        let (q, ang) = (0.2 + 0.2 * i as f64, (40.0 * i as f64).to_radians());
        d[x] = q * ang.cos();
        d[y] = q * ang.sin();
        d[z] = -2.0;
    }
    let q = points_on_a_floor(&trip, d, vec![0.0; p], SlipBound::Coulomb(vec![mu; p]));
    let dual = solve(&q);
    assert!(dual.status.converged(), "{:?}", dual.status);
    let mut o = SolveOptions::default();
    o.settings.ssn.path = crate::qp::settings::SsnPath::Iterative;
    let r = registry::solve("ssn", &q, &o).unwrap();
    assert!(r.status.converged(), "{:?}", r.status);
    assert!(r.kkt.within(1e-10), "{:?}", r.kkt);
    let slipping = (0..p)
        .filter(|&i| {
            let lt = r.lambda_t[2 * i].hypot(r.lambda_t[2 * i + 1]);
            lt > mu * r.lambda[i] * (1.0 - 1e-9)
        })
        .count();
    assert!(slipping > 1 && slipping < p, "{slipping} of {p} slip");
    for (u, v) in r.x.iter().zip(&dual.x) {
        assert!((u - v).abs() < 1e-8, "multigrid {u}, dual {v}");
    }
    // 5 Newton steps; 40 with the bound of the last iterate.
    assert!(r.iterations <= 8, "{} Newton steps", r.iterations);
}

/// A proportional load step: the chain above at twice its loads (normal
/// and tangential), started as a run's second step is (x0, the last
/// step's multipliers, t₀ = T x of the first step). Its answer is twice the
/// first (the slip increment is along the first step's slip, where
/// λ_t = s ê), and the rows that slipped sit on their discs' rims at the
/// start: they keep slipping ([`super::rim_slip`]), so the step ends in
/// two Newton steps. Predicted as sticking there, the slip zone walked back
/// out a row or two per step (160 points: 81 Newton steps).
#[test]
fn a_proportional_load_step_keeps_the_rows_that_slipped_slipping() {
    let (p, kc, mu) = (160usize, 10.0, 0.3);
    let k = p / 2;
    let pull = mu * (k as f64 + 0.5);
    let dir = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
    let (trip, d) = chain(p, kc, pull, dir);
    let q1 = points_on_a_floor(
        &trip,
        d.clone(),
        vec![0.0; p],
        SlipBound::Coulomb(vec![mu; p]),
    );
    let r1 = solve(&q1);
    assert!(r1.status.converged(), "{:?}", r1.status);
    let mut q2 = points_on_a_floor(
        &trip,
        d.iter().map(|v| 2.0 * v).collect(),
        vec![0.0; p],
        SlipBound::Coulomb(vec![mu; p]),
    );
    let fr = q2.friction.as_mut().unwrap();
    fr.t0 = fr.t.mul(&r1.x);
    let o = SolveOptions {
        x0: Some(r1.x.clone()),
        lambda0: Some(crate::qp::Multipliers {
            normal: r1.lambda.clone(),
            tangential: r1.lambda_t.clone(),
        }),
        ..Default::default()
    };
    let r2 = registry::solve("ssn", &q2, &o).unwrap();
    assert!(r2.status.converged(), "{:?}", r2.status);
    assert!(r2.kkt.within(1e-10), "{:?}", r2.kkt);
    let slipping = (0..p)
        .filter(|&i| {
            let lt = (r1.lambda_t[2 * i].powi(2) + r1.lambda_t[2 * i + 1].powi(2)).sqrt();
            lt > (1.0 - 1e-9) * mu * r1.lambda[i]
        })
        .count();
    assert!(slipping >= k - 1, "{slipping} rows slip in step 1");
    for (a, b) in r2.x.iter().zip(&r1.x) {
        assert!(
            (a - 2.0 * b).abs() < 1e-9 * (1.0 + b.abs()),
            "{a} against 2·{b}"
        );
    }
    for (a, b) in r2.lambda_t.iter().zip(&r1.lambda_t) {
        assert!((a - 2.0 * b).abs() < 1e-9, "λ_t {a} against 2·{b}");
    }
    assert!(r2.iterations <= 2, "{} Newton steps", r2.iterations);
}
