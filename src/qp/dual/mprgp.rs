//! MPRGP on the dual (Dostál & Schöberl 2005; docs/methods.md §4.6, §7):
//! modified proportioning with reduced gradient projections for
//! min ½λ̂ᵀHλ̂ − λ̂ᵀb, λ̂ ≥ ℓ, run by the dual host of [`crate::qp::dual`]
//! (SMALBE-M for a semicoercive C).
//!
//! With the free gradient φ, the chopped gradient β and the reduced free
//! gradient φ̃ᵢ = min((λ̂ᵢ − ℓᵢ)/ᾱ, φᵢ): if the iterate is proportional,
//! ‖β‖² ≤ Γ²φ̃ᵀφ, take a CG step on the free set when it stays feasible,
//! otherwise an *expansion* step (the feasible part of the CG step, then
//! λ̂ ← P_Ω(λ̂ − ᾱφ)); if not, a *proportioning* step (exact line search
//! along β, which releases bounds). Γ = 1 ([`GAMMA`]); ᾱ = 1.9/‖H‖_est
//! ([`STEP_FACTOR`]; the theory needs ᾱ ∈ (0, 2/‖H‖], the power estimate is
//! from below). The stop ‖gᴾ‖ ≤ tol·‖h‖, the check of the recovered x and
//! the SMALBE parameters are the host's.

use crate::linalg::sparse::{axpy, dot};
use crate::qp::dual::{solve_friction, solve_with, BoundStep, DualState, StepKind};
use crate::qp::method::{Capabilities, MethodId};
use crate::qp::{Context, Method, Output, QpError, QpProblem};

/// Proportioning parameter Γ.
pub const GAMMA: f64 = 1.0;
/// ᾱ = STEP_FACTOR / ‖H‖_est.
pub const STEP_FACTOR: f64 = 1.9;

/// MPRGP on the dual, SMALBE-M for a semicoercive C (docs/methods.md §7).
pub struct MprgpMethod;

impl Method for MprgpMethod {
    fn id(&self) -> MethodId {
        MethodId::Mprgp
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            // Tresca and Coulomb on the dual with boxes (2D) and discs (3D)
            // (docs/methods.md §9.2, §12.4).
            friction: crate::qp::method::FrictionSupport::Planes,
            friction_caveat: Some(
                "with friction, mprgp solves every Tresca problem of the Coulomb loop by projected gradients on the dual, whose steps grow in number with the mesh (NAFEMS 1 with μ = 0.1: 5 400 steps at 7.5 k nodes, 10 000 at 80 k, 2.4–4.8 times ssn's time; BENCHMARKS.md); past 48·√n contact and tangential rows the dual Hessian is not formed and every step solves with the factor, tens of times slower; the default method (ssn) solves it exactly in a few Newton steps",
            ),
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "MPRGP on the dual, H through one Cholesky factor; SMALBE for floating bodies (§7)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

/// Solve `qp` by MPRGP on the dual (SMALBE-M for a semicoercive C).
pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    if qp.friction.is_some() {
        return solve_friction(qp, ctx, Mprgp::default, "mprgp");
    }
    solve_with(qp, ctx, Mprgp::default(), "mprgp")
}

/// The MPRGP step and its own state.
#[derive(Default)]
pub(crate) struct Mprgp {
    /// Fixed step length ᾱ of the expansion step.
    abar: f64,
    /// CG direction on the free set.
    p: Vec<f64>,
}

impl BoundStep for Mprgp {
    fn start(&mut self, s: &DualState, h_norm: f64) {
        self.abar = STEP_FACTOR / h_norm;
        self.p = s.phi();
    }

    fn restart(&mut self, s: &DualState) {
        self.p = s.phi();
    }

    /// One MPRGP step (CG, expansion or proportioning), on intervals and
    /// discs alike ([`super::bounds`], docs/methods.md §4.11, §12.4).
    fn step(&mut self, s: &mut DualState) -> Result<StepKind, String> {
        let phi = s.phi();
        let beta = s.beta();
        let phit_phi = s.reduced_dot(&phi, self.abar);
        s.fresh = false;
        if dot(&beta, &beta) <= GAMMA * GAMMA * phit_phi {
            if dot(&self.p, &self.p) == 0.0 {
                self.p = phi.clone();
            }
            let ap = s.op.apply(&self.p);
            let pap = dot(&self.p, &ap);
            if !pap.is_finite() || pap <= 0.0 {
                return Err(format!(
                    "{}: non-positive curvature pᵀHp = {pap:e} (H should be SPD)",
                    s.name
                ));
            }
            let acg = dot(&s.g, &self.p) / pap;
            let af = s.feasible_step(&self.p);
            if acg <= af {
                axpy(-acg, &self.p, &mut s.lam);
                axpy(-acg, &ap, &mut s.g);
                let phin = s.phi();
                let gamma = dot(&phin, &ap) / pap;
                for (pi, fi) in self.p.iter_mut().zip(&phin) {
                    *pi = fi - gamma * *pi;
                }
                Ok(StepKind::Cg)
            } else {
                // Feasible part of the CG step, then a projected gradient step.
                s.step_projected(af, &self.p);
                axpy(-af, &ap, &mut s.g);
                let phih = s.phi();
                s.step_projected(self.abar, &phih);
                s.refresh();
                self.p = s.phi();
                Ok(StepKind::Expansion)
            }
        } else if s.slides(&beta) {
            // On a disc's circle with −g leaving it β is tangential, and
            // every step along it leaves the disc: the projected gradient
            // step of fixed length ᾱ on the factors at their bounds, which
            // lowers θ for ᾱ ≤ 2/‖H‖ (docs/methods.md §12.4).
            let at_bound: Vec<f64> = (0..s.lam.len())
                .map(|i| if s.is_free(i) { 0.0 } else { s.g[i] })
                .collect();
            s.step_projected(self.abar, &at_bound);
            s.refresh();
            self.p = s.phi();
            Ok(StepKind::Proportioning)
        } else {
            let ad = s.op.apply(&beta);
            let dad = dot(&beta, &ad);
            if !dad.is_finite() || dad <= 0.0 {
                return Err(format!(
                    "{}: non-positive curvature βᵀHβ = {dad:e} (H should be SPD)",
                    s.name
                ));
            }
            let a = dot(&s.g, &beta) / dad;
            let before = (!s.discs.is_empty()).then(|| (s.lam.clone(), s.g.clone()));
            if s.step_projected(a, &beta) {
                // A step across a whole disc came out on its far side: the
                // gradient from scratch, and where θ rose, the step of fixed
                // length ᾱ along β instead (docs/methods.md §12.4).
                s.refresh();
                if let Some((lam0, g0)) = before {
                    if !lowers(&lam0, &g0, &s.lam, &s.g) {
                        s.lam = lam0;
                        s.step_projected(self.abar, &beta);
                        s.refresh();
                    }
                }
            } else {
                for (gi, adi) in s.g.iter_mut().zip(&ad) {
                    *gi -= a * adi;
                }
            }
            self.p = s.phi();
            Ok(StepKind::Proportioning)
        }
    }
}

/// Whether the move from λ₀ (gradient g₀) to λ₁ (g₁) lowered θ:
/// θ(λ₁) − θ(λ₀) = ½(g₀ + g₁)ᵀ(λ₁ − λ₀) for a quadratic θ.
fn lowers(l0: &[f64], g0: &[f64], l1: &[f64], g1: &[f64]) -> bool {
    let change: f64 = l0
        .iter()
        .zip(l1)
        .zip(g0.iter().zip(g1))
        .map(|((a, b), (c, d))| 0.5 * (c + d) * (b - a))
        .sum();
    change <= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::cholesky::Cholesky;
    use crate::linalg::kernel::orthonormal_kernel;
    use crate::linalg::sparse::{dot, norm_inf};
    use crate::qp::testing::{compare, reference, two_blocks};
    use crate::qp::{kkt, run_direct, SolveOptions};

    fn opts() -> SolveOptions {
        {
            let mut o = SolveOptions::default();
            o.settings.tol = 1e-12;
            o
        }
    }

    #[test]
    fn spring_factor_is_a_generalised_inverse() {
        let qp = two_blocks(9, 5, true);
        let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
        let fac = Cholesky::new(&qp.c, &qp.kernel).unwrap();
        let n = qp.n();
        let mut b: Vec<f64> = (0..n).map(|i| ((i * 37 % 17) as f64) - 8.0).collect();
        for rl in &r {
            let p = dot(&b, rl);
            for (a, z) in b.iter_mut().zip(rl) {
                *a -= p * z;
            }
        }
        let y = fac.solve(&b);
        let cy = qp.c.mul(&y);
        let err: f64 = cy
            .iter()
            .zip(&b)
            .map(|(a, c)| (a - c).abs())
            .fold(0.0, f64::max);
        assert!(err <= 1e-10 * norm_inf(&b), "C K⁻¹ b − b = {err:e}");
    }

    #[test]
    fn coercive_agrees_with_cgc() {
        let qp = two_blocks(9, 5, false);
        let refr = reference(&qp);
        let r = run_direct(solve, &qp, &opts()).unwrap();
        compare(&qp, &r, &refr, 1e-6);
        assert!(r.timings.iter().any(|(n, _)| n == "factor"));
    }

    #[test]
    fn semicoercive_agrees_with_cgc() {
        let qp = two_blocks(9, 5, true);
        let refr = reference(&qp);
        let r = run_direct(solve, &qp, &opts()).unwrap();
        compare(&qp, &r, &refr, 1e-6);
    }

    #[test]
    fn semicoercive_without_contact_is_unsupported() {
        let mut qp = two_blocks(5, 3, true);
        qp.a = crate::qp::Csr::zeros(0, qp.n());
        qp.g.clear();
        assert!(matches!(
            run_direct(solve, &qp, &opts()),
            Err(QpError::Unsupported(_))
        ));
    }

    #[test]
    fn no_contact_rows_coercive() {
        let mut qp = two_blocks(5, 3, false);
        qp.a = crate::qp::Csr::zeros(0, qp.n());
        qp.g.clear();
        let r = run_direct(solve, &qp, &opts()).unwrap();
        assert!(r.status.converged(), "{:?}", r.status);
        assert!(kkt::residuals(&qp, &r.x, &r.lambda).max() <= 1e-10);
    }

    /// The point of `ssn::friction`'s tests on a floor, held by springs
    /// (kx, 3) and loaded by (fx, −1): it sticks (λ_t = fx, u_x = 0) while
    /// |fx| ≤ μ, else slips with λ_t = μ·sign fx, u_x = (fx − λ_t)/kx;
    /// floating (kx = 0) it sticks through SMALBE's equality.
    #[test]
    fn a_point_sticks_and_slips_on_the_box_constrained_dual() {
        use crate::qp::{registry, SlipBound};
        for kx in [2.0, 0.0] {
            for (fx, mu) in [
                (0.3f64, 0.5),
                (-0.3, 0.5),
                (0.7, 0.5),
                (-0.7, 0.5),
                (0.5, 0.0),
            ] {
                if kx == 0.0 && fx.abs() > mu {
                    continue;
                }
                for bound in [SlipBound::Coulomb(vec![mu]), SlipBound::Tresca(vec![mu])] {
                    let qp = crate::qp::testing::friction_point(kx, fx, -1.0, bound);
                    let r = registry::solve("mprgp", &qp, &opts()).unwrap();
                    let lt = if fx.abs() <= mu { fx } else { mu * fx.signum() };
                    let ux = if kx > 0.0 { (fx - lt) / kx } else { 0.0 };
                    assert!(r.status.converged(), "{kx} {fx} {mu}: {:?}", r.status);
                    assert!(r.kkt.within(1e-10), "{:?}", r.kkt);
                    assert!((r.lambda[0] - 1.0).abs() < 1e-10, "{:?}", r.lambda);
                    assert!((r.lambda_t[0] - lt).abs() < 1e-10, "{:?}", r.lambda_t);
                    assert!((r.x[0] - ux).abs() < 1e-10, "{kx} {fx} {mu}: {:?}", r.x);
                }
            }
        }
    }

    /// Shipped examples with a cheap CGC reference (all semicoercive);
    /// the others are compared with ssn in `ssn::tests::shipped_examples`.
    #[test]
    fn shipped_examples_agree_with_cgc() {
        for name in ["two_blocks", "floating_block", "three_bodies"] {
            let prep = crate::qp::testing::example(name);
            let qp = &prep.model.qp;
            assert!(!qp.kernel.is_empty(), "{name} should be semicoercive");
            let refr = reference(qp);
            let r = run_direct(solve, qp, &opts()).unwrap();
            compare(qp, &r, &refr, 1e-6);
        }
    }
}
