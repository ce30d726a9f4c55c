//! The KKT certificate computed after every solve, independently of the method
//! (docs/methods.md §8, docs/problem-format.md §8): relative, unit-free
//! residuals of (x, λ).
//!
//! The four residuals of the problem-format contract are kept as the contract
//! defines them. A fifth, `contact_balance`, measures the force balance at the
//! contact unknowns against the contact forces themselves: when most of the
//! load goes to the supports, ‖d‖ is large and a relative error of 10⁻⁶ in the
//! contact forces would hide behind it in `stationarity` alone.
//!
//! NaN or Inf anywhere (x, λ, a residual) makes every residual infinite:
//! such an answer is never certified.

use crate::linalg::sparse::{norm, norm_inf};
use crate::qp::{Kkt, QpProblem};
use rayon::prelude::*;

/// A rounding floor above this (relative) certifies nothing: rounding alone
/// could then move the force balance by more than 10⁻⁴ (docs/methods.md §8.4).
pub const FLOOR_CAP: f64 = 1e-4;

/// The share of ‖e‖ (see [`residuals`]) that counts as the rounding floor.
pub const FLOOR_SHARE: f64 = 0.6;

/// A residual at its rounding floor counts as resolved only if the gaps are
/// exact to rounding too (primal and complementarity at most this): under a
/// stiff floating body the contact forces are fixed by gaps far below any
/// relative tolerance. On the rubber slope at a contrast of 2.1e8, mprgp
/// stopped with gaps right to 2·10⁻¹⁰ of max|x| and contact forces on the
/// stop 20 % off per row (resultant exact); ssn and asm, exact to 10⁻¹⁵,
/// agree with each other to 8·10⁻⁶.
pub const EXACT_GAPS: f64 = 1e-13;

/// Floor of the contact-force scale, relative to the load scale: contact
/// forces below 10⁻⁴ of the loads are measured against 10⁻⁴ of the loads.
pub const CONTACT_FLOOR: f64 = 1e-4;

/// Residuals of (x, λ) for `qp`, with r = Cx − d + Aᵀλ and S = max(‖d‖, ‖Cx‖):
/// * stationarity ‖r‖ / S;
/// * contact_balance ‖r_Γ‖ / max(‖Aᵀλ‖, 10⁻⁴·S), Γ = the unknowns A touches;
/// * primal max((Ax − g)⁺) / max|x|;
/// * dual max((−λ)⁺) / max(max|λ|, 1);
/// * complementarity |λᵀ(Ax − g)| / max(max|λ|·max|x|, tiny).
///
/// A zero denominator gives the raw numerator.
///
/// Each of stationarity and contact balance comes with its rounding floor:
/// [`FLOOR_SHARE`]·‖e‖ over the same scale, eᵢ = ε·((|C||x|)ᵢ + |dᵢ| + (|A|ᵀ|λ|)ᵢ), the size
/// of the residual that rounding x to f64 and forming r leave of an exact
/// answer. A stiff body floating on a soft one moves rigidly by far more
/// than it deforms; its unknowns hold the deformation only to ε·|x|, and
/// C times that is ε·|C||x|. On a steel block on a rubber slope (tests/trust.rs)
/// this put every method's stationarity at 7·10⁻⁷ × (contrast / 2·10⁷),
/// ‖r‖ ≈ 0.25‖e‖ whatever the contrast.
pub fn residuals(qp: &QpProblem, x: &[f64], lambda: &[f64]) -> Kkt {
    residuals_with_friction(qp, x, lambda, &[])
}

/// [`residuals`] with the tangential forces `lambda_t` of a frictional
/// problem (docs/methods.md §9.4): r = Cx − d + Aᵀλ + Tᵀλ_t, Γ also holds
/// the unknowns T touches, and `friction` = the largest over the rows of
/// * the bound (|λ_tᵢ| − sᵢ)⁺ / Fᵢ;
/// * the slip rule |vᵢ|/X · |sᵢ − λ_tᵢ sign vᵢ| / Fᵢ, zero iff the row
///   sticks or slips along λ_tᵢ = sᵢ·sign vᵢ,
///
/// with Fᵢ = max(sᵢ, |λ_tᵢ|, max|λ|, max|λ_t|) (the row's bound or the
/// contact-force scale, whichever is larger), X = max(max|x|,
/// ‖d‖∞/max Cᵢᵢ, maxᵢ (|T||x| + |t0|)ᵢ) (the displacements, their floor
/// `length_floor` and the scale the slips are formed at), s
/// the slip bound at λ and v = T x − t0 (docs/methods.md §9.4). Both are
/// unitless and do not grow with μ or s: a row far below a huge bound
/// (μ = 10⁶, a Tresca bound of 10¹²: glued) is judged by its slip alone,
/// |vᵢ|/X, where the sum Σ sᵢ|vᵢ| of the former rule turned a slip at
/// rounding level into a residual of 4·10⁻⁵ (mprgp). Without friction
/// `lambda_t` must be empty and the result is [`residuals`]'s.
pub fn residuals_with_friction(qp: &QpProblem, x: &[f64], lambda: &[f64], lambda_t: &[f64]) -> Kkt {
    residuals_and_cx(qp, x, lambda, lambda_t).0
}

/// ‖d‖∞ / max Cᵢᵢ: the certificate's floor of the length scale max|x|
/// (0 with no loads or no stiffness), so that a point at rest is not
/// judged rounding against rounding (docs/methods.md §8.4).
pub(crate) fn length_floor(qp: &QpProblem) -> f64 {
    let cmax = qp.c.diag().iter().fold(0.0f64, |m, v| m.max(*v));
    let f = norm_inf(&qp.d) / cmax;
    if f.is_finite() {
        f
    } else {
        0.0
    }
}

/// [`residuals_with_friction`] and the product Cx it formed (the same bits
/// as `Csr::mul`; None when x was refused before it), so that the caller's
/// energy takes no second pass over C.
pub(crate) fn residuals_and_cx(
    qp: &QpProblem,
    x: &[f64],
    lambda: &[f64],
    lambda_t: &[f64],
) -> (Kkt, Option<Vec<f64>>) {
    let finite = |v: &[f64]| v.iter().all(|e| e.is_finite());
    let mt = qp.friction.as_ref().map_or(0, |f| qp.m() * f.frame.rows());
    if x.len() != qp.n()
        || lambda.len() != qp.m()
        || lambda_t.len() != mt
        || !finite(x)
        || !finite(lambda)
        || !finite(lambda_t)
    {
        return (Kkt::not_finite(), None);
    }
    // Cx and |C||x| in one pass (Cx summed as Csr::mul does: the same bits).
    // Rows in parallel, each summed alone: the same bits on any thread count.
    let (cx, c_abs_x): (Vec<f64>, Vec<f64>) = (0..qp.n())
        .into_par_iter()
        .map(|i| {
            let (cols, vals) = qp.c.row(i);
            let s: f64 = cols.iter().zip(vals).map(|(&j, &a)| a * x[j]).sum();
            let t: f64 = cols.iter().zip(vals).map(|(&j, &a)| (a * x[j]).abs()).sum();
            (s, t)
        })
        .unzip();
    let mut alam = qp.a.mul_t(lambda);
    if let Some(f) = &qp.friction {
        f.t.mul_t_add(lambda_t, &mut alam);
    }
    let r: Vec<f64> = cx
        .iter()
        .zip(&qp.d)
        .zip(&alam)
        .map(|((c, d), a)| c - d + a)
        .collect();
    let scale = norm(&qp.d).max(norm(&cx));
    let stationarity = ratio(norm(&r), scale);
    // Γ: the columns of A (contact unknowns).
    let mut on_gamma = vec![false; qp.n()];
    for &c in &qp.a.indices {
        on_gamma[c] = true;
    }
    if let Some(f) = &qp.friction {
        for &c in &f.t.indices {
            on_gamma[c] = true;
        }
    }
    let r_gamma = norm_on(&r, &on_gamma);
    let balance_scale = norm(&alam).max(CONTACT_FLOOR * scale);
    let contact_balance = ratio(r_gamma, balance_scale);
    // The gross external and contact forces |d| + |A|ᵀ|λ| (+ |T|ᵀ|λ_t|).
    let mut gross: Vec<f64> = qp.d.iter().map(|d| d.abs()).collect();
    let mut abs_t_add = |m: &crate::linalg::sparse::Csr, v: &[f64]| {
        for (i, vi) in v.iter().enumerate() {
            let (cols, vals) = m.row(i);
            for (&j, a) in cols.iter().zip(vals) {
                gross[j] += (a * vi).abs();
            }
        }
    };
    abs_t_add(&qp.a, lambda);
    if let Some(f) = &qp.friction {
        abs_t_add(&f.t, lambda_t);
    }
    // Each rigid motion z of ker C in equilibrium: zᵀC = 0, so zᵀr =
    // zᵀ(Aᵀλ (+ Tᵀλ_t) − d), against the gross forces |z|ᵀ(|d| + |A|ᵀ|λ|)
    // acting along it: a floating body judged at its own force scale, not
    // at the stiffest body's (S), and with no Cx in it, no rounding floor.
    // A motion along which only rounding-sized forces act (a ring's slide
    // along frictionless plates: λ_t ~ 10⁻²⁰) is measured against
    // CONTACT_FLOOR × the largest gross force along any motion instead.
    let along: Vec<(f64, f64)> = qp
        .kernel
        .iter()
        .map(|z| {
            let (mut net, mut den) = (0.0, 0.0);
            for (((zi, ai), di), gi) in z.iter().zip(&alam).zip(&qp.d).zip(&gross) {
                net += zi * (ai - di);
                den += zi.abs() * gi;
            }
            (net.abs(), den)
        })
        .collect();
    let den_max = along.iter().fold(0.0f64, |m, v| m.max(v.1));
    let rigid_balance = along
        .iter()
        .map(|(net, den)| ratio(*net, den.max(CONTACT_FLOOR * den_max)))
        .fold(0.0f64, |m, v| if v.is_nan() { v } else { m.max(v) });
    // e = ε(|C||x| + |d| + |A|ᵀ|λ| (+ |T|ᵀ|λ_t|)).
    let mut e: Vec<f64> = c_abs_x.iter().zip(&gross).map(|(a, g)| a + g).collect();
    e.iter_mut().for_each(|v| *v *= f64::EPSILON);
    let e_gamma = norm_on(&e, &on_gamma);
    // 0.6‖e‖: ssn and asm left 0.25–0.36‖e‖ (slope, stack_floating at 1e8),
    // frictional ssn 0.51‖e‖ (its augmented Lagrangian solves with
    // C + ρBᵀB; x 4·10⁻⁷ from mprgp on the slope with μ = 0.6 at 2.1e7);
    // cgc:jacobi stopped at 0.97‖e‖ with x 2·10⁻⁶ off on the stack.
    let stationarity_floor = FLOOR_SHARE * ratio(norm(&e), scale);
    let balance_floor = FLOOR_SHARE * ratio(e_gamma, balance_scale);
    let ax = qp.a.mul(x);
    let viol: Vec<f64> = ax.iter().zip(&qp.g).map(|(a, g)| a - g).collect();
    // Gaps and displacements share units. The length scale is floored at
    // ‖d‖∞ / max Cᵢᵢ, what the largest load moves the stiffest unknown
    // (invariant under the units and the bodies' stiffness, below any
    // loaded answer's max|x|): a point at rest (x = 0) left Ax − g = 10⁻¹⁶
    // from λ_n's rounding, judged against |x| = 10⁻¹⁶ (docs/methods.md
    // §8.4). A zero solution of zero loads has no scale.
    let xmax = norm_inf(x).max(length_floor(qp));
    let pmax = viol.iter().fold(0.0f64, |m, v| m.max(*v));
    let primal = ratio(pmax, xmax);
    let lmax = norm_inf(lambda);
    let dual = lambda.iter().fold(0.0f64, |m, l| m.max(-l)) / lmax.max(1.0);
    let compl: f64 = lambda.iter().zip(&viol).map(|(l, v)| l * v).sum();
    let complementarity = compl.abs() / (lmax * xmax).max(f64::MIN_POSITIVE);
    let friction = match &qp.friction {
        None => 0.0,
        Some(f) => {
            let s = f.slip_bound(lambda);
            let v = f.slip(x);
            // The contact-force scale, and the slip's: max|x| or the largest
            // (|T||x| + |t0|)ᵢ, what vᵢ is formed from.
            let force = lmax.max(norm_inf(lambda_t));
            let disp = (0..f.t.nrows).fold(xmax, |m, i| {
                let (cols, vals) = f.t.row(i);
                let tx: f64 = cols.iter().zip(vals).map(|(&j, a)| (a * x[j]).abs()).sum();
                m.max(tx + f.t0[i].abs())
            });
            let k = f.frame.rows();
            s.iter()
                .zip(lambda_t.chunks(k))
                .zip(v.chunks(k))
                .map(|((&si, li), vi)| match (li, vi) {
                    (&[li], &[vi]) => {
                        // Never a product with s: a huge bound cannot overflow.
                        let den = si.max(li.abs()).max(force);
                        let bound = ratio((li.abs() - si).max(0.0), den);
                        let slip =
                            ratio(vi.abs(), disp) * ratio((si - li * vi.signum()).abs(), den);
                        bound.max(slip)
                    }
                    _ => disc_residual(si, li, vi, force, disp),
                })
                .fold(0.0f64, |m, r| if r.is_nan() { r } else { m.max(r) })
        }
    };
    let k = Kkt {
        primal,
        dual,
        complementarity,
        stationarity,
        contact_balance,
        rigid_balance,
        friction,
        stationarity_floor,
        balance_floor,
    };
    if k.max().is_finite() {
        (k, Some(cx))
    } else {
        (Kkt::not_finite(), Some(cx))
    }
}

/// The friction residual of one contact row with a disc or cone
/// (docs/methods.md §12.5): the bound (‖λ_t‖ − s)⁺/F and the slip rule
/// ‖v‖/X · ‖s v̂ − λ_t‖/F with v̂ = v/‖v‖, zero exactly when the row sticks
/// (v = 0) or slips with its force along its slip (λ_t = s v̂): the force's
/// direction is checked, not only its size. s v̂ is formed without a
/// product s·v, so a huge bound cannot overflow.
pub(crate) fn disc_residual(s: f64, lt: &[f64], v: &[f64], force: f64, disp: f64) -> f64 {
    let ln = crate::qp::tangential_norm(lt);
    let vn = crate::qp::tangential_norm(v);
    let den = s.max(ln).max(force);
    let bound = ratio((ln - s).max(0.0), den);
    if vn == 0.0 {
        return bound;
    }
    let miss: Vec<f64> = lt.iter().zip(v).map(|(l, vi)| s * (vi / vn) - l).collect();
    let slip = ratio(vn, disp) * ratio(crate::qp::tangential_norm(&miss), den);
    bound.max(slip)
}

/// ‖v‖₂ over the entries where `mask` holds.
fn norm_on(v: &[f64], mask: &[bool]) -> f64 {
    v.iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(a, _)| a * a)
        .sum::<f64>()
        .sqrt()
}

fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        num / den
    } else {
        num
    }
}

impl Kkt {
    /// Every residual by its name in the JSON (`kkt.NAME`) and the
    /// checkpoint (`kkt_NAME` attributes, docs/problem-format.md §6).
    pub fn named(&self) -> [(&'static str, f64); 9] {
        [
            ("primal", self.primal),
            ("dual", self.dual),
            ("complementarity", self.complementarity),
            ("stationarity", self.stationarity),
            ("contact_balance", self.contact_balance),
            ("rigid_balance", self.rigid_balance),
            ("friction", self.friction),
            ("stationarity_floor", self.stationarity_floor),
            ("balance_floor", self.balance_floor),
        ]
    }

    /// The residual named `name` ([`Kkt::named`]) set to `v`; false for
    /// an unknown name.
    pub fn set(&mut self, name: &str, v: f64) -> bool {
        let slot = match name {
            "primal" => &mut self.primal,
            "dual" => &mut self.dual,
            "complementarity" => &mut self.complementarity,
            "stationarity" => &mut self.stationarity,
            "contact_balance" => &mut self.contact_balance,
            "rigid_balance" => &mut self.rigid_balance,
            "friction" => &mut self.friction,
            "stationarity_floor" => &mut self.stationarity_floor,
            "balance_floor" => &mut self.balance_floor,
            _ => return false,
        };
        *slot = v;
        true
    }

    /// Every residual infinite: NaN or Inf in the answer.
    pub fn not_finite() -> Kkt {
        Kkt {
            primal: f64::INFINITY,
            dual: f64::INFINITY,
            complementarity: f64::INFINITY,
            stationarity: f64::INFINITY,
            contact_balance: f64::INFINITY,
            rigid_balance: f64::INFINITY,
            friction: f64::INFINITY,
            stationarity_floor: 0.0,
            balance_floor: 0.0,
        }
    }
    /// The largest residual; NaN if any is NaN (`f64::max` would drop it).
    pub fn max(&self) -> f64 {
        let all = [
            self.primal,
            self.dual,
            self.complementarity,
            self.stationarity,
            self.contact_balance,
            self.rigid_balance,
            self.friction,
        ];
        if all.iter().any(|v| v.is_nan()) {
            return f64::NAN;
        }
        all.iter().fold(0.0f64, |m, v| m.max(*v))
    }
    /// The largest residual as the certificate judges it: stationarity and
    /// contact balance at or below their rounding floors count as resolved
    /// (0) when the floor is at most [`FLOOR_CAP`] and the gaps are exact
    /// ([`EXACT_GAPS`]); NaN if any is NaN.
    pub fn judged(&self) -> f64 {
        let m = self.max();
        if m.is_nan() {
            return m;
        }
        let exact_gaps = self.primal <= EXACT_GAPS && self.complementarity <= EXACT_GAPS;
        let resolved = |v: f64, floor: f64| {
            if exact_gaps && floor.is_finite() && floor <= FLOOR_CAP && v <= floor {
                0.0
            } else {
                v
            }
        };
        [
            self.primal,
            self.dual,
            self.complementarity,
            resolved(self.stationarity, self.stationarity_floor),
            resolved(self.contact_balance, self.balance_floor),
            self.rigid_balance,
            self.friction,
        ]
        .iter()
        .fold(0.0f64, |m, v| m.max(*v))
    }
    /// NaN-safe check against a target: certified iff every residual is
    /// finite and at most `target`, or (stationarity, contact balance) at
    /// most its rounding floor ([`Kkt::judged`]).
    pub fn within(&self, target: f64) -> bool {
        // judged() keeps NaN and ∞ (an infinite residual is never at a
        // finite floor).
        let m = self.judged();
        target.is_finite() && m.is_finite() && m <= target
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::Csr;

    /// The rigid balance of a floating block: ~ε for ssn's answer, the
    /// size of a force error on one row when λ is perturbed (whatever the
    /// stationarity says), and the same when loads, gaps, x and λ are
    /// scaled by 10⁻⁷ (a lighter load on the same bodies).
    #[test]
    fn rigid_balance_measures_each_floating_body_at_its_own_force_scale() {
        let qp = crate::qp::testing::two_blocks(9, 5, true);
        assert_eq!(qp.kernel.len(), 1);
        let r =
            crate::qp::registry::solve("ssn", &qp, &crate::qp::SolveOptions::default()).unwrap();
        let k = residuals(&qp, &r.x, &r.lambda);
        assert!(k.within(1e-8) && k.rigid_balance < 1e-13, "{k:?}");
        let (imax, lmax) =
            r.lambda
                .iter()
                .enumerate()
                .fold((0, 0.0f64), |m, (i, &l)| if l > m.1 { (i, l) } else { m });
        let mut lam = r.lambda.clone();
        lam[imax] += 1e-4 * lmax;
        let k = residuals(&qp, &r.x, &lam);
        assert!(k.rigid_balance > 1e-6 && !k.within(1e-6), "{k:?}");
        let s = 1e-7;
        let mut light = qp.clone();
        light.d.iter_mut().for_each(|v| *v *= s);
        light.g.iter_mut().for_each(|v| *v *= s);
        let xs: Vec<f64> = r.x.iter().map(|v| v * s).collect();
        let ls: Vec<f64> = lam.iter().map(|v| v * s).collect();
        let k2 = residuals(&light, &xs, &ls);
        assert!(
            (k2.rigid_balance - k.rigid_balance).abs() <= 1e-9 * k.rigid_balance,
            "{k2:?} vs {k:?}"
        );
    }

    /// Two springs: x0 free, x1 pressed against a wall x1 ≤ 0.
    fn qp(k_soft: f64, f: f64) -> QpProblem {
        QpProblem {
            c: Csr::from_triplets(2, 2, &[(0, 0, 1e4), (1, 1, k_soft)]),
            d: vec![1e4, f],
            a: Csr::from_triplets(1, 2, &[(0, 1, 1.0)]),
            g: vec![0.0],
            kernel: vec![],
            friction: None,
            near: None,
        }
    }

    #[test]
    fn exact_answer_is_certified() {
        let q = qp(1.0, 2.0);
        let k = residuals(&q, &[1.0, 0.0], &[2.0]);
        assert!(k.within(1e-14), "{k:?}");
    }

    #[test]
    fn a_contact_force_error_cannot_hide_behind_a_large_load() {
        // The load on the free unknown is 5000 × the contact force: a 10⁻³
        // relative error in λ is 2e-7 of ‖d‖ (certified by stationarity
        // alone) but 10⁻³ of the contact force.
        let q = qp(1.0, 2.0);
        let k = residuals(&q, &[1.0, 0.0], &[2.0 * (1.0 + 1e-3)]);
        assert!(k.stationarity < 1e-6, "{k:?}");
        assert!((k.contact_balance - 1e-3).abs() < 1e-6, "{k:?}");
        assert!(!k.within(1e-6));
    }

    /// A stiff bar (y0, y1; stiffness k, floating) pushed by a unit load on
    /// y1 against a spring z of stiffness 0.7 (z − y0 ≤ 0):
    /// z = y0 = −1/0.7, y1 = z − 1/k.
    fn floating_bar(k: f64, shortening: f64) -> (QpProblem, Vec<f64>) {
        let q = QpProblem {
            c: Csr::from_triplets(
                3,
                3,
                &[(0, 0, k), (0, 1, -k), (1, 0, -k), (1, 1, k), (2, 2, 0.7)],
            ),
            d: vec![0.0, -1.0, 0.0],
            a: Csr::from_triplets(1, 3, &[(0, 0, -1.0), (0, 2, 1.0)]),
            g: vec![0.0],
            kernel: vec![vec![1.0, 1.0, 0.0]],
            friction: None,
            near: None,
        };
        let z = -1.0 / 0.7;
        (q, vec![z, z - shortening / k, z])
    }

    #[test]
    fn a_stiff_floating_body_is_certified_at_its_rounding_floor_and_no_further() {
        // k = 1.3e11: y1 holds the bar's shortening 8e-12 only to ulp(1.4)
        // = 2.2e-16, which k turns into 3e-5 of the load per ulp. An answer
        // one ulp off in y1 is as close as f64 gets: certified at the floor.
        // A 1e-3 error in the contact force or in the shortening is not.
        let (q, mut x) = floating_bar(1.3e11, 1.0);
        x[1] = f64::from_bits(x[1].to_bits() + 1);
        let k = residuals(&q, &x, &[1.0]);
        assert!(k.stationarity > 1e-6, "{k:?}");
        assert!(k.stationarity <= k.stationarity_floor, "{k:?}");
        assert!(k.within(1e-6) && k.max() > 1e-6, "{k:?}");
        let k = residuals(&q, &x, &[1.0 + 1e-3]);
        assert!(!k.within(1e-6), "{k:?}");
        // The same answer with z − y0 = 1e-12 (a gap right to 7e-13 of
        // max|x|, within any relative tolerance): the floor no longer counts.
        let mut open = x.clone();
        open[2] += 1e-12;
        let k = residuals(&q, &open, &[1.0]);
        assert!(
            k.primal > EXACT_GAPS && k.stationarity > 1e-6 && !k.within(1e-6),
            "{k:?}"
        );
        let (q, wrong) = floating_bar(1.3e11, 1.001);
        let k = residuals(&q, &wrong, &[1.0]);
        assert!(!k.within(1e-6), "{k:?}");
        // k = 1.3e13: one ulp is 3e-3 of the load, the floor (7e-3) is
        // above FLOOR_CAP, and the floor certifies nothing.
        let (q, mut x) = floating_bar(1.3e13, 1.0);
        x[1] = f64::from_bits(x[1].to_bits() + 1);
        let k = residuals(&q, &x, &[1.0]);
        assert!(k.stationarity_floor > FLOOR_CAP && !k.within(1e-6), "{k:?}");
        // Without a floating body the floor is far below any target.
        let k = residuals(&qp(1.0, 2.0), &[1.0, 0.0], &[2.0]);
        assert!(
            k.stationarity_floor < 1e-14 && k.balance_floor < 1e-14,
            "{k:?}"
        );
    }

    /// The point of `ssn::friction`'s tests on a floor 0.5 below it
    /// (C = diag(2, 3), d = (0.3, −3)): it rests on the floor, x = (0,
    /// −0.5), λ_n = 1.5, and sticks with λ_t = 0.3 under any bound ≥ 0.3.
    fn resting_point(bound: crate::qp::SlipBound) -> QpProblem {
        let mut q = crate::qp::testing::friction_point(2.0, 0.3, -3.0, bound);
        q.g = vec![0.5];
        q
    }

    /// A disc (docs/methods.md §12.5): the exact slip along the load passes;
    /// the same force turned by 5° (what a 16-sided polygon of the cone can
    /// give), or above the bound, or a slip with no force fails; NaN fails.
    #[test]
    fn the_disc_residual_checks_the_direction_of_the_force() {
        use crate::qp::SlipBound;
        let (k, s) = (2.0, 1.0);
        let dir = [0.6f64, 0.8];
        // Load 3 along dir, μλ_n = 1 (λ_n = 2, μ = 0.5): u_t = (3 − 1)/k.
        let q = crate::qp::testing::friction_point3(
            k,
            [3.0 * dir[0], 3.0 * dir[1], -2.0],
            SlipBound::Coulomb(vec![0.5]),
        );
        let x = [dir[0], dir[1], 0.0];
        let lt = [s * dir[0], s * dir[1]];
        let r = residuals_with_friction(&q, &x, &[2.0], &lt);
        assert!(r.within(1e-14), "{r:?}");
        let a = 5f64.to_radians();
        let turned = [
            s * (dir[0] * a.cos() - dir[1] * a.sin()),
            s * (dir[0] * a.sin() + dir[1] * a.cos()),
        ];
        let r = residuals_with_friction(&q, &x, &[2.0], &turned);
        assert!(r.friction > 0.5 * a.sin(), "{r:?}");
        let r = residuals_with_friction(&q, &x, &[2.0], &[1.1 * lt[0], 1.1 * lt[1]]);
        assert!(r.friction > 0.05, "{r:?}");
        let r = residuals_with_friction(&q, &x, &[2.0], &[0.0, 0.0]);
        assert!(!r.within(1e-3), "{r:?}");
        let r = residuals_with_friction(&q, &x, &[2.0], &[f64::NAN, 0.0]);
        assert!(!r.within(1e-3) && !r.max().is_finite(), "{r:?}");
        // A length-m λ_t (a line's) is not a plane's answer.
        let r = residuals_with_friction(&q, &x, &[2.0], &[s]);
        assert!(!r.max().is_finite(), "{r:?}");
    }

    /// The friction residual of a sticking answer with a slip of 10⁻¹²
    /// (what a Tresca solve leaves) is the same whatever μ or s: before,
    /// s·|v| made it grow with the bound (1.3 at s = 10¹²), so a correct
    /// glued answer failed. A tangential force flipped on a slipping row,
    /// or above the bound, still fails.
    #[test]
    fn the_friction_residual_does_not_grow_with_mu_or_s() {
        use crate::qp::SlipBound;
        let v = 1e-12;
        let (x, ln, lt) = ([v, -0.5], [1.5], [0.3 - 2.0 * v]);
        let mut seen = vec![];
        for bound in [
            SlipBound::Coulomb(vec![0.3]),
            SlipBound::Coulomb(vec![1e3]),
            SlipBound::Coulomb(vec![1e6]),
            SlipBound::Tresca(vec![1.0]),
            SlipBound::Tresca(vec![1e12]),
            SlipBound::Tresca(vec![1e300]),
        ] {
            let k = residuals_with_friction(&resting_point(bound.clone()), &x, &ln, &lt);
            assert!(k.within(1e-10), "{bound:?}: {k:?}");
            assert!(
                k.friction > 0.0 && k.friction <= 4.1e-12,
                "{bound:?}: {k:?}"
            );
            seen.push(k.friction);
        }
        // Far below the bound the residual is the slip over the length
        // scale X = max(max|x| = 0.5, ‖d‖∞ / max Cᵢᵢ = 3/3) = 1.
        for f in &seen[1..3] {
            assert!((f - v).abs() < 1e-3 * v, "{seen:?}");
        }
        assert!((seen[4] - v).abs() < 1e-3 * v, "{seen:?}");
        // Slipping under s = 1 with fx = 3: λ_t = 1, x0 = 1; λ_t flipped.
        let mut q =
            crate::qp::testing::friction_point(2.0, 3.0, -3.0, SlipBound::Tresca(vec![1.0]));
        q.g = vec![0.5];
        let k = residuals_with_friction(&q, &[1.0, -0.5], &[1.5], &[1.0]);
        assert!(k.within(1e-12), "{k:?}");
        let k = residuals_with_friction(&q, &[1.0, -0.5], &[1.5], &[-1.0]);
        assert!(k.friction > 0.5, "{k:?}");
        // Above the bound.
        let k = residuals_with_friction(&q, &[0.0, -0.5], &[1.5], &[1.1]);
        assert!(k.friction > 0.05, "{k:?}");
    }

    #[test]
    fn nan_and_inf_are_never_certified() {
        let q = qp(1.0, 2.0);
        for bad in [f64::NAN, f64::INFINITY, 1e300] {
            let k = residuals(&q, &[1.0, bad], &[2.0]);
            assert!(!k.within(1e300), "{bad}: {k:?}");
            let k = residuals(&q, &[1.0, 0.0], &[bad]);
            assert!(!k.within(1e300), "{bad}: {k:?}");
        }
        let k = Kkt {
            stationarity: f64::NAN,
            ..Default::default()
        };
        assert!(k.max().is_nan() && !k.within(1.0));
        let k = Kkt {
            stationarity: f64::NAN,
            stationarity_floor: f64::INFINITY,
            ..Default::default()
        };
        assert!(k.judged().is_nan() && !k.within(1.0));
        assert!(!Kkt::default().within(f64::NAN));
    }
}
