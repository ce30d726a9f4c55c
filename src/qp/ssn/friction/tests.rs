use crate::qp::{registry, SlipBound, SolveOptions, Status};

use crate::qp::testing::friction_point as point;

#[test]
fn a_point_sticks_and_slips_by_coulomb_and_tresca() {
    let opts = SolveOptions::default();
    for (fx, mu) in [(0.3, 0.5), (-0.3, 0.5), (0.7, 0.5), (-0.7, 0.5), (0.5, 0.0)] {
        for bound in [
            SlipBound::Coulomb(vec![mu]),
            SlipBound::Tresca(vec![mu * 1.0]),
        ] {
            let qp = point(2.0, fx, -1.0, bound.clone());
            let r = registry::solve("ssn", &qp, &opts).unwrap();
            assert!(r.status.converged(), "{fx} {mu}: {:?}", r.status);
            assert!(r.kkt.within(1e-10), "{:?}", r.kkt);
            assert!((r.lambda[0] - 1.0).abs() < 1e-12);
            let lt = if fx.abs() <= mu { fx } else { mu * fx.signum() };
            assert!(
                (r.lambda_t[0] - lt).abs() < 1e-12,
                "{fx} {mu}: {:?}",
                r.lambda_t
            );
            assert!((r.x[0] - (fx - lt) / 2.0).abs() < 1e-12, "{:?}", r.x);
        }
    }
}

/// A point free along x (a floating body) held by friction alone: it
/// sticks below the bound and is unbounded above it. At rest (x = 0,
/// t0 = 0) the answer is checked to rounding: the certificate measures
/// slips against max|x|, itself rounding there (the dual path leaves
/// |x| ≈ 10⁻³³), so it is judged on the same point with a slip offset
/// t0 = 0.2 (x = (0.2, 0)).
#[test]
fn a_floating_point_sticks_or_is_unbounded() {
    let opts = SolveOptions::default();
    let r = registry::solve(
        "ssn",
        &point(0.0, 0.3, -1.0, SlipBound::Coulomb(vec![0.5])),
        &opts,
    )
    .unwrap();
    assert!(r.status.converged(), "{:?}", r.status);
    assert!((r.lambda[0] - 1.0).abs() < 1e-12, "{:?}", r.lambda);
    assert!((r.lambda_t[0] - 0.3).abs() < 1e-12 && r.x[0].abs() < 1e-12);
    let mut qp = point(0.0, 0.3, -1.0, SlipBound::Coulomb(vec![0.5]));
    if let Some(f) = qp.friction.as_mut() {
        f.t0 = vec![0.2];
    }
    let r = registry::solve("ssn", &qp, &opts).unwrap();
    assert!(
        r.status.converged() && r.kkt.within(1e-10),
        "{:?} {:?}",
        r.status,
        r.kkt
    );
    assert!((r.lambda[0] - 1.0).abs() < 1e-12, "{:?}", r.lambda);
    assert!((r.lambda_t[0] - 0.3).abs() < 1e-12, "{:?}", r.lambda_t);
    assert!(
        (r.x[0] - 0.2).abs() < 1e-12 && r.x[1].abs() < 1e-12,
        "{:?}",
        r.x
    );
    let r = registry::solve(
        "ssn",
        &point(0.0, 0.7, -1.0, SlipBound::Coulomb(vec![0.5])),
        &opts,
    )
    .unwrap();
    assert!(
        matches!(r.status, Status::Unbounded { .. }),
        "{:?}",
        r.status
    );
}

/// Huge but finite bounds: the point, resting on a floor 0.5 below it,
/// sticks (λ_t = fx, certified, finite energy) with ssn and mprgp, also
/// where μλ_n overflows (μ = f64::MAX, λ_n = 1.5); a Tresca bound whose force on the unknowns
/// overflows (f64::MAX on a tangential row of coefficient 10) is
/// refused naming the slip bound s. Never a NaN or an infinity.
#[test]
fn a_huge_bound_sticks_or_is_refused_by_name() {
    for (bound, fy, tscale) in [
        (SlipBound::Tresca(vec![1e307]), -3.0, 1.0),
        (SlipBound::Tresca(vec![f64::MAX]), -3.0, 1.0),
        (SlipBound::Tresca(vec![1e307]), -3.0, 10.0),
        (SlipBound::Coulomb(vec![f64::MAX]), -3.0, 1.0),
        (SlipBound::Tresca(vec![f64::MAX]), -3.0, 10.0),
    ] {
        let mut qp = point(2.0, 0.3, fy, bound.clone());
        qp.g = vec![0.5];
        if let Some(f) = qp.friction.as_mut() {
            f.t.data.iter_mut().for_each(|v| *v *= tscale);
        }
        let refused = match &bound {
            SlipBound::Tresca(s) => !(s[0] * tscale).is_finite(),
            SlipBound::Coulomb(_) => false,
        };
        for m in ["ssn", "mprgp"] {
            let what = format!("{bound:?}, T × {tscale}, {m}");
            match registry::solve(m, &qp, &SolveOptions::default()) {
                Ok(r) => {
                    assert!(!refused, "{what}: solved");
                    assert!(
                        r.status.converged() && r.kkt.within(1e-10),
                        "{what}: {:?}",
                        r.kkt
                    );
                    assert!(
                        (r.lambda_t[0] * tscale - 0.3).abs() < 1e-12,
                        "{what}: {:?}",
                        r.lambda_t
                    );
                    assert!(
                        r.x[0].abs() < 1e-12 && r.energy.is_finite(),
                        "{what}: {:?}",
                        r.x
                    );
                }
                Err(e) => {
                    assert!(refused, "{what}: {e}");
                    assert!(
                        e.to_string().contains("slip bound s of contact row 0"),
                        "{what}: {e}"
                    );
                }
            }
        }
    }
}

#[test]
fn other_methods_refuse_friction_and_nan_fails_the_certificate() {
    let qp = point(2.0, 0.3, -1.0, SlipBound::Coulomb(vec![0.5]));
    let e = registry::solve("cgc", &qp, &SolveOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains("does not solve contact with friction"),
        "{e}"
    );
    let k = crate::qp::kkt::residuals_with_friction(&qp, &[0.0, 0.0], &[1.0], &[f64::NAN]);
    assert!(!k.within(1e300));
    // A tangential force above the bound fails the friction residual.
    let k = crate::qp::kkt::residuals_with_friction(&qp, &[0.0, 0.0], &[1.0], &[0.6]);
    assert!(k.friction > 1e-3, "{k:?}");
    // A slip against λ_t fails it too.
    let k = crate::qp::kkt::residuals_with_friction(&qp, &[0.1, 0.0], &[1.0], &[-0.5]);
    assert!(k.friction > 1e-3, "{k:?}");
}
