//! The Coulomb outer loop of every frictional method (docs/methods.md
//! §9.1): Coulomb's bound s = μλ_n depends on the answer, so the problem is
//! solved as successive Tresca problems, the first glued, each later one
//! with s moved towards μλ_n of the last ([`CoulombRelaxation`]), until s
//! no longer changes. A method supplies the Tresca solve ([`TrescaStep`])
//! and keeps between solves what it needs (ssn its working sets, the dual
//! its multipliers); the loop, its stopping rule and its limit
//! ([`MAX_UPDATES`], then [`Failure::CoulombUnsettled`]) are the same for
//! every method.

use crate::linalg::sparse::norm_inf;
use crate::qp::{Failure, Friction, IterRecord, Output, QpError, QpProblem, SlipBound, Status};

/// The most Tresca solves of one Coulomb loop (the glued one included).
/// Both methods settle in far fewer: the keystone of tests/trust.rs, the
/// hardest model here, in 35–37 Newton steps (ssn by this loop; 7–9 by its
/// direct iteration, [`TrescaStep::coulomb`]) and 17–25 solves (mprgp). Before the loop was shared, ssn stopped after 500 Newton steps
/// and the dual after 200 Tresca solves.
pub const MAX_UPDATES: usize = 200;

/// The bound of one Tresca solve.
#[derive(Debug, Clone, Copy)]
pub enum Bound<'a> {
    /// Coulomb's start: every row in contact sticks, whatever the force
    /// (s = ∞ on closed rows, 0 on open ones).
    Glued,
    /// The slip bound sᵢ of each row.
    Given(&'a [f64]),
}

/// What a method returns for one Tresca problem.
#[derive(Debug, Clone)]
pub struct Tresca {
    pub x: Vec<f64>,
    pub lambda_n: Vec<f64>,
    pub lambda_t: Vec<f64>,
    pub active: Vec<bool>,
    /// Converged: a KKT point of the Tresca problem (to the method's
    /// accuracy); anything else ends the Coulomb loop with this status.
    pub status: Status,
    pub iterations: usize,
    pub inner_iterations: usize,
    pub log: Vec<IterRecord>,
}

/// One Tresca solve of a frictional method.
pub trait TrescaStep {
    /// The relative change of s (to max s) below which this method's
    /// Tresca answers cannot tell two bounds apart: the loop stops there.
    /// ssn solves each Tresca problem exactly (to rounding): `tol`; the
    /// dual only to `tol` in its projected gradient: 100·`tol` (on the
    /// inclined plane of tests/friction.rs at tol = 10⁻¹⁰ the change of s
    /// stagnated at 4.7·tol).
    fn resolution(&self) -> f64;

    /// Solve the Tresca problem with `bound`, warm-started from the state
    /// the previous call left (the first call: the method's own start).
    fn solve(&mut self, bound: Bound<'_>) -> Result<Tresca, QpError>;

    /// Fill in what [`TrescaStep::solve`] may leave out of an answer that
    /// only feeds the next bound (ssn's dual path: x, a sparse solve):
    /// called once, on the answer the loop returns.
    fn complete(&mut self, _r: &mut Tresca) -> Result<(), QpError> {
        Ok(())
    }

    /// Coulomb's problem with friction coefficients `mu` solved directly,
    /// the slip bound μλ_n inside the iteration (ssn: the semismooth Newton
    /// method of Hüeber, Stadler & Wohlmuth 2008 on the Coulomb problem),
    /// warm-started from the glued answer the last call left; None when
    /// the method solves Tresca problems only. An answer that is not
    /// converged sends the loop to the fixed point.
    fn coulomb(&mut self, _mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        None
    }

    /// Coulomb's problem solved directly as [`TrescaStep::coulomb`], but
    /// from a start of the method's own instead of the glued answer (ssn:
    /// the sets of its coarse levels, docs/methods.md §9.2), before any
    /// glued solve; None when the method has no such start. An answer that
    /// is not converged sends the loop to the glued start.
    fn coulomb_first(&mut self, _mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        None
    }

    /// A first bound of the fixed point that is better than the glued
    /// answer's, with the method's state set to start from it; None: the
    /// glued start. ssn: μλ_n of the best iterate of a direct iteration
    /// that did not settle, or of the last load step (its sets kept,
    /// docs/methods.md §9.5).
    fn warm_bound(&mut self, _mu: &[f64]) -> Option<Vec<f64>> {
        None
    }
}

/// Solve the frictional problem of `fr` by `step`: one Tresca solve with
/// the given bound, or Coulomb's problem (docs/methods.md §9.1): the
/// method's direct iteration from its own start if it has one
/// ([`TrescaStep::coulomb_first`]); else (or if that does not settle) the
/// glued solve, then the direct iteration from it if the method has one
/// ([`TrescaStep::coulomb`]), else (or if that does not settle) the fixed
/// point from the glued answer. A method's warm bound
/// ([`TrescaStep::warm_bound`]: ssn's sparse path in a load step, the last
/// step's μλ_n) replaces the glued solve, unless its Tresca problem is
/// unbounded (the loads grew beyond what the last step's bound holds). Each solve's log follows the last one's
/// (iterations numbered on).
///
/// The fixed point stops at an iterate that `proven` (the driver's KKT
/// certificate of Coulomb's problem, docs/methods.md §9.4, at the target
/// it is given) passes at the method's resolution, or at the caller's
/// `kkt_target` once the change of s no longer falls (by half an update):
/// whatever the change of s, since a sticking row's bound may move without
/// moving the answer and the change of s cannot fall below the rounding of
/// λ_n in the Tresca solves (docs/methods.md §9.1, "When the loop stops").
/// A change of s at the method's resolution also ends it; the driver then
/// certifies the answer as any other.
pub fn solve(
    fr: &Friction,
    step: &mut impl TrescaStep,
    name: &str,
    proven: &dyn Fn(&Tresca, f64) -> bool,
    kkt_target: f64,
) -> Result<Output, QpError> {
    let mu = match &fr.bound {
        SlipBound::Tresca(s) => {
            let mut r = step.solve(Bound::Given(s))?;
            step.complete(&mut r)?;
            return Ok(Counts::default().output(r));
        }
        SlipBound::Coulomb(mu) => mu,
    };
    let mut counts = Counts::default();
    let first = step.coulomb_first(mu);
    if let Some(d) = direct(
        first,
        step,
        &mut counts,
        name,
        "a warm bound or the glued start",
        proven,
        kkt_target,
    )? {
        return Ok(counts.output(d));
    }
    let mut stalled = 0;
    // The first Tresca answer of the fixed point, when a warm bound gave it.
    let mut warm_answer = None;
    let warm = match step.warm_bound(mu) {
        Some(s) => {
            log::debug!("{name}: the fixed point from a warm bound, not the glued start");
            let mut r = step.solve(Bound::Given(&s))?;
            if matches!(r.status, Status::Unbounded { .. }) {
                // The last step's bound cannot hold this step's larger
                // loads (a Tresca problem, not Coulomb's): the glued start.
                log::debug!(
                    "{name}: the warm bound's Tresca problem is unbounded: the glued start"
                );
                counts.add(&mut r);
                None
            } else {
                warm_answer = Some(r);
                Some(s)
            }
        }
        None => None,
    };
    let (mut s, mut outer) = match warm {
        Some(s) => (s, 0),
        None => match glued_start(
            fr,
            step,
            name,
            mu,
            &mut counts,
            &mut stalled,
            proven,
            kkt_target,
        )? {
            Start::Done(out) => return Ok(out),
            Start::From(s) => (s, 1),
        },
    };
    let mut relax = CoulombRelaxation::default();
    let mut last_change = f64::INFINITY;
    loop {
        outer += 1;
        let mut r = match warm_answer.take() {
            Some(r) => r,
            None => step.solve(Bound::Given(&s))?,
        };
        match usable(&mut r, step, &mut stalled, proven, kkt_target)? {
            Use::Next => {}
            Use::Stop => return Ok(counts.output(r)),
            Use::Proven => {
                log::debug!("{name}: Coulomb update {outer} stopped but passes the certificate");
                r.status = Status::Converged;
                return Ok(counts.output(r));
            }
        }
        let target = fr.slip_bound(&r.lambda_n);
        let smax = norm_inf(&target).max(f64::MIN_POSITIVE);
        let change = target
            .iter()
            .zip(&s)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / smax;
        log::debug!(
            "{name}: Coulomb update {outer}: change of s {change:.3e}, ω = {}",
            relax.omega()
        );
        step.complete(&mut r)?;
        if change <= step.resolution() {
            return Ok(counts.output(r));
        }
        let stalled = change > 0.5 * last_change;
        last_change = change;
        if proven(&r, step.resolution()) || stalled && proven(&r, kkt_target) {
            log::debug!(
                "{name}: Coulomb update {outer} passes the certificate (change of s {change:.3e})"
            );
            r.status = Status::Converged;
            return Ok(counts.output(r));
        }
        if outer >= MAX_UPDATES {
            r.status = Status::Failed(Failure::CoulombUnsettled {
                outer: MAX_UPDATES,
                change,
            });
            return Ok(counts.output(r));
        }
        counts.add(&mut r);
        s = relax.next(&s, target, false);
    }
}

/// A direct iteration's answer `d`: returned if it converged, or if it
/// stopped otherwise (a singular working set after an iterate exact to
/// 10⁻¹², the geodynamic faults of docs/methods.md §9.1) but its last
/// iterate passes the certificate at `kkt_target`, as [`usable`] takes a
/// Tresca answer; else counted and the loop goes on to `next`.
fn direct(
    d: Option<Result<Tresca, QpError>>,
    step: &mut dyn TrescaStep,
    counts: &mut Counts,
    name: &str,
    next: &str,
    proven: &dyn Fn(&Tresca, f64) -> bool,
    kkt_target: f64,
) -> Result<Option<Tresca>, QpError> {
    let Some(d) = d else { return Ok(None) };
    let mut d = d?;
    if d.status.converged() {
        step.complete(&mut d)?;
        return Ok(Some(d));
    }
    step.complete(&mut d)?;
    if proven(&d, kkt_target) {
        log::debug!(
            "{name}: the direct Coulomb iteration stopped ({}) but its last iterate passes the certificate",
            d.status.describe()
        );
        d.status = Status::Converged;
        return Ok(Some(d));
    }
    log::debug!(
        "{name}: the direct Coulomb iteration stopped ({}): {next}",
        d.status.describe()
    );
    counts.add(&mut d);
    Ok(None)
}

/// How the fixed point starts after the glued solve ([`glued_start`]).
enum Start {
    /// The glued answer (or the direct iteration from it) ends the loop.
    Done(Output),
    /// The first bound of the fixed point: μλ_n of the glued answer.
    From(Vec<f64>),
}

/// The glued solve, then the method's direct iteration from it if it has
/// one: Coulomb's answer, or the fixed point's first bound.
#[allow(clippy::too_many_arguments)]
fn glued_start(
    fr: &Friction,
    step: &mut dyn TrescaStep,
    name: &str,
    mu: &[f64],
    counts: &mut Counts,
    stalled: &mut usize,
    proven: &dyn Fn(&Tresca, f64) -> bool,
    kkt_target: f64,
) -> Result<Start, QpError> {
    let mut r = step.solve(Bound::Glued)?;
    match usable(&mut r, step, stalled, proven, kkt_target)? {
        Use::Next => {}
        Use::Stop => return Ok(Start::Done(std::mem::take(counts).output(r))),
        Use::Proven => {
            r.status = Status::Converged;
            return Ok(Start::Done(std::mem::take(counts).output(r)));
        }
    }
    // The glued answer is Coulomb's when every closed row's force is
    // within μλ_n (a large μ).
    step.complete(&mut r)?;
    if proven(&r, step.resolution()) {
        log::debug!("{name}: the glued answer passes the certificate");
        r.status = Status::Converged;
        return Ok(Start::Done(std::mem::take(counts).output(r)));
    }
    // s = μλ_n of the glued answer: the first bound of the fixed point.
    let s = fr.slip_bound(&r.lambda_n);
    log::debug!("{name}: Coulomb update 1: change of s inf, ω = 1");
    counts.add(&mut r);
    let after_glued = step.coulomb(mu);
    let next = "the fixed point from the glued answer";
    if let Some(d) = direct(after_glued, step, counts, name, next, proven, kkt_target)? {
        return Ok(Start::Done(std::mem::take(counts).output(d)));
    }
    Ok(Start::From(s))
}

/// The driver's certificate of Coulomb's problem `qp` (docs/methods.md
/// §9.4) on a Tresca answer, at a given target: the `proven` of [`solve`]
/// for every method.
pub fn certificate(qp: &QpProblem) -> impl Fn(&Tresca, f64) -> bool + '_ {
    move |t: &Tresca, at: f64| {
        crate::qp::kkt::residuals_with_friction(qp, &t.x, &t.lambda_n, &t.lambda_t).within(at)
    }
}

/// The most Tresca solves of one Coulomb loop that may stop on
/// stagnation or cycling and still feed the next bound (docs/methods.md §9.1).
pub const MAX_STALLED: usize = 3;

/// What the loop makes of a Tresca answer ([`usable`]).
enum Use {
    /// Go on from it (converged, or an inexact answer that feeds the next
    /// bound).
    Next,
    /// Return it as it is (its status ends the loop).
    Stop,
    /// Return it as Coulomb's answer: it passes the certificate.
    Proven,
}

/// What the loop does with the Tresca answer `r`: go on from a converged
/// one; return one that stopped otherwise but passes the certificate at
/// `kkt_target` (docs/methods.md §9.1: the certificate, not the Tresca
/// solve's own rule, decides the end); go on (at most [`MAX_STALLED`]
/// times) from one that stagnated (a method returns its best iterate:
/// mprgp stalled at 5·10⁻¹⁰ against its 10⁻¹⁰ on the geodynamic model's
/// rows of prescribed slip before their λ_t was set outside the dual,
/// docs/methods.md §9.1) or whose sets cycled (ssn's sets flipped one
/// of the dependent rows where three faults meet at a KKT residual of
/// 3·10⁻¹²): an inexact Tresca answer still moves s towards μλ_n. Any
/// other stop ends the loop with its status. `r` is completed unless it
/// converged.
fn usable(
    r: &mut Tresca,
    step: &mut (impl TrescaStep + ?Sized),
    stalled: &mut usize,
    proven: &dyn Fn(&Tresca, f64) -> bool,
    kkt_target: f64,
) -> Result<Use, QpError> {
    if r.status.converged() {
        return Ok(Use::Next);
    }
    step.complete(r)?;
    if proven(r, kkt_target) {
        return Ok(Use::Proven);
    }
    let inexact = matches!(
        r.status,
        Status::Failed(Failure::Stagnation { .. } | Failure::Cycling { .. })
    );
    if inexact && *stalled < MAX_STALLED {
        *stalled += 1;
        return Ok(Use::Next);
    }
    Ok(Use::Stop)
}

/// The counts and the log of the solves before the one returned.
#[derive(Default)]
struct Counts {
    iterations: usize,
    inner: usize,
    log: Vec<IterRecord>,
}

impl Counts {
    /// Add the counts of `r` and move its log after the others.
    fn add(&mut self, r: &mut Tresca) {
        self.iterations += r.iterations;
        self.inner += r.inner_iterations;
        let at = self.log.last().map_or(0, |l: &IterRecord| l.iter);
        self.log
            .extend(std::mem::take(&mut r.log).into_iter().map(|mut l| {
                l.iter += at;
                l
            }));
    }

    /// The last solve `r` with the counts and the log of those before.
    fn output(self, r: Tresca) -> Output {
        into_output(r, self.iterations, self.inner, self.log)
    }
}

/// The last Tresca solve with the counts and the log of those before.
fn into_output(r: Tresca, iterations: usize, inner: usize, mut log: Vec<IterRecord>) -> Output {
    let at = log.last().map_or(0, |l| l.iter);
    log.extend(r.log.into_iter().map(|mut l| {
        l.iter += at;
        l
    }));
    Output {
        x: r.x,
        lambda: r.lambda_n,
        lambda_t: r.lambda_t,
        active: r.active,
        status: r.status,
        iterations: iterations + r.iterations,
        inner_iterations: inner + r.inner_iterations,
        log,
        timings: vec![],
    }
}

/// The Coulomb outer loop's update of the slip bound (docs/methods.md
/// §9.1): s ← s + ω r with the residual r = μλ_n − s. The plain fixed
/// point (ω = 1) can settle into a 2-cycle: a soft keystone wedged between
/// abutments 10²–10⁷ times stiffer alternated between two bounds 55 % and
/// 84 % apart for 200 Tresca solves. ω follows Aitken's Δ² rule (Irons &
/// Tuck 1969; as in partitioned fluid–structure coupling, Küttler & Wall,
/// Comput. Mech. 43, 2008), ω_k = −ω_{k−1} r_{k−1}ᵀ(r_k − r_{k−1}) /
/// ‖r_k − r_{k−1}‖², clamped to [[`CoulombRelaxation::OMEGA_MIN`], 1]: a
/// rule on the residuals only, so the same input takes the same path.
#[derive(Debug, Clone)]
pub struct CoulombRelaxation {
    omega: f64,
    last: Option<Vec<f64>>,
}

impl Default for CoulombRelaxation {
    fn default() -> Self {
        CoulombRelaxation {
            omega: 1.0,
            last: None,
        }
    }
}

impl CoulombRelaxation {
    /// The smallest ω.
    pub const OMEGA_MIN: f64 = 1.0 / 64.0;

    /// The next bound from the current `s` and `target` = μλ_n; `glued`
    /// for the first update after the glued start (then s = target and
    /// no residual is kept).
    pub fn next(&mut self, s: &[f64], target: Vec<f64>, glued: bool) -> Vec<f64> {
        if glued {
            self.last = None;
            return target;
        }
        let r: Vec<f64> = target.iter().zip(s).map(|(t, s)| t - s).collect();
        if let Some(prev) = &self.last {
            let (mut num, mut den) = (0.0, 0.0);
            for (rk, rp) in r.iter().zip(prev) {
                let dr = rk - rp;
                num += rp * dr;
                den += dr * dr;
            }
            let w = -self.omega * num / den;
            if den > 0.0 && w.is_finite() {
                self.omega = w.clamp(Self::OMEGA_MIN, 1.0);
            }
        }
        let w = self.omega;
        let next = s.iter().zip(&r).map(|(si, ri)| si + w * ri).collect();
        self.last = Some(r);
        next
    }

    /// The current relaxation factor ω.
    pub fn omega(&self) -> f64 {
        self.omega
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::Csr;

    /// A scalar "method": λ_n = 1 + 0.5·(s − 1) settles at s = μ(1 + …);
    /// counts each solve, records the bounds it was given.
    struct Scalar {
        seen: Vec<Option<f64>>,
        fail_at: Option<usize>,
        slope: f64,
        /// A direct iteration: Some(converges), None: none.
        direct: Option<bool>,
        direct_calls: usize,
        /// A start of the method's own: Some(converges), None: none.
        first: Option<bool>,
    }

    impl Scalar {
        fn new(
            slope: f64,
            fail_at: Option<usize>,
            direct: Option<bool>,
            first: Option<bool>,
        ) -> Self {
            Scalar {
                seen: vec![],
                fail_at,
                slope,
                direct,
                direct_calls: 0,
                first,
            }
        }
    }

    impl TrescaStep for Scalar {
        fn resolution(&self) -> f64 {
            1e-12
        }
        fn solve(&mut self, bound: Bound<'_>) -> Result<Tresca, QpError> {
            let s = match bound {
                Bound::Glued => None,
                Bound::Given(s) => Some(s[0]),
            };
            self.seen.push(s);
            let ln = 1.0 + self.slope * s.unwrap_or(0.0);
            let status = if self.fail_at == Some(self.seen.len()) {
                Status::MaxIter
            } else {
                Status::Converged
            };
            Ok(Tresca {
                x: vec![0.0],
                lambda_n: vec![ln],
                lambda_t: vec![s.unwrap_or(0.0)],
                active: vec![true],
                status,
                iterations: 2,
                inner_iterations: 3,
                log: vec![
                    IterRecord {
                        iter: 1,
                        ..Default::default()
                    },
                    IterRecord {
                        iter: 2,
                        ..Default::default()
                    },
                ],
            })
        }
        fn coulomb_first(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
            let ok = self.first?;
            let (direct, calls) = (self.direct, self.direct_calls);
            self.direct = Some(ok);
            let r = self.coulomb(mu);
            (self.direct, self.direct_calls) = (direct, calls);
            r
        }
        fn coulomb(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
            let ok = self.direct?;
            self.direct_calls += 1;
            // The fixed point λ_n = 1 + a μ λ_n, exactly.
            let ln = 1.0 / (1.0 - self.slope * mu[0]);
            Some(Ok(Tresca {
                x: vec![0.0],
                lambda_n: vec![ln],
                lambda_t: vec![mu[0] * ln],
                active: vec![true],
                status: if ok {
                    Status::Converged
                } else {
                    Status::Failed(Failure::Cycling {
                        best: 1.0,
                        steps: 5,
                    })
                },
                iterations: 5,
                inner_iterations: 1,
                log: vec![IterRecord {
                    iter: 1,
                    ..Default::default()
                }],
            }))
        }
    }

    /// A method's direct iteration ends the loop after the glued solve
    /// when it converges (its answer, the counts of both); when it does
    /// not, the fixed point runs from the glued answer as before, the
    /// direct iteration's counts added.
    #[test]
    fn a_direct_iteration_is_taken_when_it_settles() {
        let mut m = Scalar::new(0.5, None, Some(true), None);
        let out = solve_(&friction(SlipBound::Coulomb(vec![0.4])), &mut m, "t").unwrap();
        assert!(out.status.converged(), "{:?}", out.status);
        assert_eq!((m.seen.clone(), m.direct_calls), (vec![None], 1));
        assert_eq!((out.iterations, out.inner_iterations), (2 + 5, 3 + 1));
        assert!((out.lambda[0] - 1.25).abs() < 1e-15, "{:?}", out.lambda);
        let mut m = Scalar::new(0.5, None, Some(false), None);
        let out = solve_(&friction(SlipBound::Coulomb(vec![0.4])), &mut m, "t").unwrap();
        assert!(out.status.converged(), "{:?}", out.status);
        assert_eq!((m.seen[0], m.seen[1], m.direct_calls), (None, Some(0.4), 1));
        let k = m.seen.len();
        assert_eq!(
            (out.iterations, out.inner_iterations),
            (2 * k + 5, 3 * k + 1)
        );
    }

    /// A direct iteration from the method's own start comes first: taken
    /// with no glued solve when it settles; when it does not, its counts
    /// are added and the glued solve and the direct iteration from it
    /// follow.
    #[test]
    fn a_direct_iteration_from_the_methods_start_comes_first() {
        let mut m = Scalar::new(0.5, None, Some(true), Some(true));
        let out = solve_(&friction(SlipBound::Coulomb(vec![0.4])), &mut m, "t").unwrap();
        assert!(out.status.converged(), "{:?}", out.status);
        assert_eq!((m.seen.len(), m.direct_calls), (0, 0));
        assert_eq!((out.iterations, out.inner_iterations), (5, 1));
        assert!((out.lambda[0] - 1.25).abs() < 1e-15, "{:?}", out.lambda);
        m.first = Some(false);
        let out = solve_(&friction(SlipBound::Coulomb(vec![0.4])), &mut m, "t").unwrap();
        assert!(out.status.converged(), "{:?}", out.status);
        assert_eq!((m.seen.clone(), m.direct_calls), (vec![None], 1));
        assert_eq!(
            (out.iterations, out.inner_iterations),
            (5 + 2 + 5, 1 + 3 + 1)
        );
    }

    /// The loop with a certificate nothing passes (the change of s alone
    /// stops it).
    fn solve_(fr: &Friction, step: &mut Scalar, name: &str) -> Result<Output, QpError> {
        solve(fr, step, name, &|_, _| false, 1e-6)
    }

    fn friction(bound: SlipBound) -> Friction {
        Friction {
            t: Csr::zeros(1, 1),
            t0: vec![0.0],
            bound,
            frame: crate::qp::Frame::Line,
        }
    }

    /// The loop starts glued, moves s to the fixed point s = μ(1 + a s),
    /// adds up counts and numbers the log on; a Tresca bound is one solve
    /// with that bound; a failed solve ends the loop with its status.
    #[test]
    fn the_loop_starts_glued_and_settles_at_the_fixed_point() {
        let mut m = Scalar::new(0.5, None, None, None);
        let out = solve_(&friction(SlipBound::Coulomb(vec![0.4])), &mut m, "t").unwrap();
        assert!(out.status.converged(), "{:?}", out.status);
        assert_eq!(m.seen[0], None);
        assert_eq!(m.seen[1], Some(0.4));
        let s = 0.4 / (1.0 - 0.4 * 0.5);
        assert!((out.lambda_t[0] - s).abs() < 1e-11, "{:?}", out.lambda_t);
        let k = m.seen.len();
        assert_eq!((out.iterations, out.inner_iterations), (2 * k, 3 * k));
        let iters: Vec<usize> = out.log.iter().map(|l| l.iter).collect();
        assert_eq!(iters, (1..=2 * k).collect::<Vec<_>>());

        let mut m = Scalar::new(0.5, None, None, None);
        let out = solve_(&friction(SlipBound::Tresca(vec![7.0])), &mut m, "t").unwrap();
        assert_eq!(m.seen, vec![Some(7.0)]);
        assert_eq!(out.iterations, 2);

        let mut m = Scalar::new(0.5, Some(3), None, None);
        let out = solve_(&friction(SlipBound::Coulomb(vec![0.4])), &mut m, "t").unwrap();
        assert_eq!(out.status, Status::MaxIter);
        assert_eq!(m.seen.len(), 3);
    }

    /// A fixed point the relaxation cannot reach (λ_n = 1 + 2s with μ = 1
    /// runs away) stops after [`MAX_UPDATES`] solves, said as such.
    #[test]
    fn an_unsettled_loop_stops_at_the_limit() {
        let mut m = Scalar::new(2.0, None, None, None);
        let out = solve_(&friction(SlipBound::Coulomb(vec![1.0])), &mut m, "t").unwrap();
        assert!(
            matches!(
                out.status,
                Status::Failed(Failure::CoulombUnsettled {
                    outer: MAX_UPDATES,
                    ..
                })
            ),
            "{:?}",
            out.status
        );
        assert_eq!(m.seen.len(), MAX_UPDATES);
    }
}
