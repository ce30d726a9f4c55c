//! The driver: the one place that runs a method (docs/methods.md §8).
//!
//! A method is a type implementing [`Method`]: it gets the problem and a
//! [`Context`] (its validated [`Settings`], the caller's [`Workspace`] for
//! factor reuse, the checked warm start, an [`Executor`] with the caller's
//! observers, a phase timer) and returns an [`Output`]. Everything that is the
//! same for every method happens here, once ([`run`]); the caller's
//! observers ([`SolveOptions::observers`]) see every iteration: the data check, the
//! boundedness decision on the kernel (§8.2), the free motions held while the
//! method runs and removed from its answer (§1.7), the warm-start check (§8.3),
//! the fallback when an unbounded claim fails its certificate, and the KKT
//! certificate and energy (§8.4) that turn an [`Output`] into a [`QpResult`].
//! A method cannot return a certificate of its own: [`Output`] has none, so a
//! sub-solver's result (preelim's inner CGC) never carries a blank one.

use super::executor::{Executor, Observer};
use super::method::{Certificate, FallbackCause, Method, MethodId};
use super::recession::{self, Boundedness};
use super::settings::Settings;
use super::{kkt, Failure, IterRecord, Kkt, QpError, QpProblem, QpResult, SolveOptions, Status};
use crate::linalg::cholesky::Workspace;
use std::borrow::Cow;
use std::time::Instant;

/// What a method returns: the iterate and how it got there, no certificate.
#[derive(Debug, Clone)]
pub struct Output {
    pub x: Vec<f64>,
    /// The normal contact forces λ (λ_n with friction), one per row of A.
    pub lambda: Vec<f64>,
    /// The tangential forces λ_t, one per contact row (empty without
    /// friction, docs/methods.md §9).
    pub lambda_t: Vec<f64>,
    pub active: Vec<bool>,
    pub status: Status,
    /// Outer iterations (faces, active-set changes, Uzawa steps, …).
    pub iterations: usize,
    /// Inner iterations (CG steps, inner solves).
    pub inner_iterations: usize,
    pub log: Vec<IterRecord>,
    /// Wall time per phase in seconds, e.g. ("factor", 0.1), ("iterate", 0.5):
    /// the phases the method timed itself and those of [`Context::phase`].
    pub timings: Vec<(String, f64)>,
}

/// What the driver hands a method.
pub struct Context<'a> {
    /// The validated settings ([`Settings::validate`] has passed).
    pub settings: &'a Settings,
    /// Factor reuse, owned by the caller (load steps share one).
    pub ws: &'a Workspace,
    /// The warm start, checked by the driver (finite, plausible size).
    pub x0: Option<&'a [f64]>,
    /// The working-set warm start, one flag per row (checked by the driver).
    pub active0: Option<&'a [bool]>,
    /// The multiplier warm start (checked by the driver: one finite pair
    /// per row, the problem frictional).
    pub lambda0: Option<&'a crate::qp::Multipliers>,
    /// λ_n of a nested start, one finite value per row, with `x0`
    /// ([`SolveOptions::nested_lambda`]; checked by the driver).
    pub nested_lambda: Option<&'a [f64]>,
    opts: &'a SolveOptions,
    timings: Vec<(String, f64)>,
}

impl<'a> Context<'a> {
    pub fn new(opts: &'a SolveOptions, ws: &'a Workspace) -> Context<'a> {
        Context {
            settings: &opts.settings,
            ws,
            x0: opts.x0.as_deref(),
            active0: opts.active0.as_deref(),
            lambda0: opts.lambda0.as_ref(),
            nested_lambda: opts.nested_lambda.as_deref(),
            opts,
            timings: vec![],
        }
    }

    /// The context of an injected sub-solver: the same workspace, deadline
    /// and progress, other settings, no warm start.
    pub fn sub<'b>(&'b self, settings: &'b Settings) -> Context<'b> {
        Context {
            settings,
            ws: self.ws,
            x0: None,
            active0: None,
            lambda0: None,
            nested_lambda: None,
            opts: self.opts,
            timings: vec![],
        }
    }

    /// The executor of method `name`: MAXIT, the caller's deadline and
    /// progress display, labelled with the caller's label (or `name`).
    pub fn executor(&self, name: &str) -> Executor {
        let label = self.opts.label.as_deref().unwrap_or(name);
        let progress = self.opts.progress.as_ref().map(|p| p.start(label));
        let mut e = Executor::new(self.settings.max_iter, progress);
        e.deadline = self.opts.deadline;
        e.stop = self.opts.stop;
        for o in &self.opts.observers {
            e.observers.push(Box::new(Forward(o.clone())));
        }
        e
    }

    /// Run `f` as the phase `name` (its wall time goes to the report only;
    /// no decision depends on it).
    pub fn phase<T>(&mut self, name: &str, f: impl FnOnce(&Self) -> T) -> T {
        let t = Instant::now();
        let r = f(self);
        self.timings
            .push((name.to_string(), t.elapsed().as_secs_f64()));
        r
    }

    /// The phases timed so far (taken: a second call returns none).
    pub fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.timings)
    }
}

/// Hands an executor's records to an observer the caller shares.
struct Forward(super::SharedObserver);

impl Observer for Forward {
    fn observe(&mut self, rec: &IterRecord) {
        self.0.borrow_mut().observe(rec);
    }
    fn finish(&mut self) {
        self.0.borrow_mut().finish();
    }
}

/// What the driver did beyond the method, kept in [`QpResult::notes`]:
/// printed as warnings and written to the JSON as text
/// ([`std::fmt::Display`]); tests and rules match on the variant.
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    /// `from`'s answer was not kept (`cause`, detailed in `failure`);
    /// `to` solved the problem instead (docs/methods.md §8.2, §9.2).
    Fallback {
        from: MethodId,
        to: MethodId,
        cause: FallbackCause,
        failure: Failure,
    },
    /// The warm start was refused (the reason, docs/methods.md §8.3).
    WarmStartUnused(String),
    /// `count` rigid motions slide along every contact without opening it
    /// and the loads do no work on them: held while the method ran, the
    /// answer has no component along them (docs/methods.md §1.7).
    FreeMotions { count: usize },
    /// `count` motions are free on the rows carrying a force; the answer
    /// has the least component along them that the other rows allow.
    SettledOnActive { count: usize },
    /// As [`Note::SettledOnActive`], but moving the answer would have lost
    /// its certificate: it is one point of the set of solutions.
    NotSettled { count: usize },
    /// `method` stopped without converging (`stopped`: its iteration
    /// limit, stagnation, an unsettled Coulomb loop, cycling, a
    /// breakdown), but its answer meets the certificate at `target`, so it
    /// counts as converged: the certificate, not a method's stopping rule,
    /// decides (docs/methods.md §8.4).
    StalledButCertified {
        method: MethodId,
        stopped: Status,
        target: f64,
    },
}

/// "1 rigid motion", "2 rigid motions" (the notes).
fn motions(n: usize) -> String {
    format!("{n} rigid motion{}", if n > 1 { "s" } else { "" })
}

/// "it" or "them" for `n` motions (the notes).
fn them(n: usize) -> &'static str {
    if n > 1 {
        "them"
    } else {
        "it"
    }
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Note::Fallback {
                from, to, failure, ..
            } => {
                let cite = match failure {
                    Failure::Cycling { .. } => " (docs/methods.md §9.2)",
                    _ => "",
                };
                match failure {
                    Failure::RefusedClaim { .. } => write!(f, "{failure}; solved by {to} instead"),
                    _ => write!(f, "{from}: {failure}{cite}; solved by {to} instead"),
                }
            }
            Note::WarmStartUnused(why) => write!(f, "warm start not used: {why}"),
            Note::FreeMotions { count } => write!(
                f,
                "the solution is unique only up to {} that slide{} along every contact without opening it and on which the loads do no work; the answer returned has no component along {} (docs/methods.md §1.7)",
                motions(*count),
                if *count > 1 { "" } else { "s" },
                them(*count),
            ),
            Note::SettledOnActive { count } => write!(
                f,
                "the solution is unique only up to {} that the rows carrying a force leave free (the others stop {} at their gaps); the answer returned has the least component along {} that they allow (docs/methods.md §1.7)",
                motions(*count),
                them(*count),
                them(*count),
            ),
            Note::NotSettled { count } => write!(
                f,
                "the solution is unique only up to {} that the rows carrying a force leave free (the others stop {} at their gaps); the answer returned is one of those solutions, not the one with the least component along {}: moved there it would lose its certificate (its gaps are exact at the scale of that motion, not of the deformation; ssn or asm return the least one, docs/methods.md §1.7)",
                motions(*count),
                them(*count),
                them(*count),
            ),
            Note::StalledButCertified {
                method,
                stopped,
                target,
            } => {
                let how = match stopped {
                    Status::Failed(failure) => failure.to_string(),
                    other => other.describe(),
                };
                write!(
                    f,
                    "{method} stopped on {how}; its answer meets the KKT certificate (≤ {target:e}, docs/methods.md §8.4), so it counts as converged"
                )
            }
        }
    }
}

/// Whether a result of `method` with residuals `kkt` is certified at
/// `target`: by its [`Certificate`] kind. A penalised certificate (unless
/// `strict`) leaves out the O(ε_p) violation of Ax ≤ g and the
/// complementarity it implies (docs/methods.md §4.4); NaN anywhere fails.
pub fn certified(method: MethodId, kkt: &Kkt, target: f64, strict: bool) -> bool {
    match method.capabilities().certificate {
        Certificate::Penalised if !strict => {
            let own = Kkt {
                primal: 0.0,
                complementarity: 0.0,
                ..*kkt
            };
            own.within(target) && !kkt.max().is_nan() && kkt.max().is_finite()
        }
        _ => kkt.within(target),
    }
}

/// Solve `qp` by `fb` instead of `r`'s method (`from`), whose answer is
/// not kept (`cause`, `failure`): the note says so, and `from`'s phase
/// timings are kept with its name as prefix.
struct Fallback<'a> {
    qs: &'a QpProblem,
    opts: &'a SolveOptions,
    ws: &'a Workspace,
}

impl Fallback<'_> {
    fn run(
        &self,
        from: MethodId,
        to: MethodId,
        cause: FallbackCause,
        failure: Failure,
        mut r: Output,
        notes: &mut Vec<Note>,
    ) -> Result<Output, QpError> {
        let note = Note::Fallback {
            from,
            to,
            cause,
            failure,
        };
        log::warn!("{note}");
        notes.push(note);
        let t = std::mem::take(&mut r.timings);
        let mut out = solve_once(to.method(), self.qs, self.opts, self.ws)?;
        out.timings = t
            .into_iter()
            .map(|(k, v)| (format!("{from}-{k}"), v))
            .chain(out.timings)
            .collect();
        Ok(out)
    }
}

/// Refuse a problem the method does not solve, naming those that do.
fn check_capabilities(method: &dyn Method, qp: &QpProblem) -> Result<(), QpError> {
    if !method.capabilities().friction.solves(qp) {
        let able: Vec<&str> = MethodId::ALL
            .into_iter()
            .filter(|m| m.capabilities().friction.solves(qp))
            .map(MethodId::name)
            .collect();
        let what = match qp.friction.as_ref().map(|f| f.frame) {
            Some(crate::qp::Frame::Plane) => {
                "3D contact with friction (a disc or cone per contact point, docs/methods.md §12)"
            }
            _ => "contact with friction",
        };
        return Err(QpError::Unsupported(format!(
            "method \"{}\" does not solve {what}; the problem has friction ([[contact]] friction or tresca): use {} (or method = \"auto\")",
            method.id(),
            able.join(" or ")
        )));
    }
    Ok(())
}

/// The warm starts if they pass [`check_warm_start`] (x0) and have one
/// flag per row (active0); else the options without them, said in `notes`.
fn checked_start<'a>(
    qp: &QpProblem,
    opts: &'a SolveOptions,
    notes: &mut Vec<Note>,
) -> Cow<'a, SolveOptions> {
    let bad_x0 = opts
        .x0
        .as_ref()
        .and_then(|x0| check_warm_start(qp, x0).err());
    let bad_active0 = opts
        .active0
        .as_ref()
        .filter(|a| a.len() != qp.m())
        .map(|a| format!("{} working-set flags for {} contact rows", a.len(), qp.m()));
    let bad_lambda0 = opts.lambda0.as_ref().and_then(|l| {
        let m = qp.m();
        let mt = qp.friction.as_ref().map_or(0, |f| m * f.frame.rows());
        if qp.friction.is_none() {
            Some("multipliers of a frictional start for a frictionless problem".to_string())
        } else if l.normal.len() != m || l.tangential.len() != mt {
            Some(format!(
                "{} normal and {} tangential multipliers for {m} contact rows ({mt} tangential)",
                l.normal.len(),
                l.tangential.len()
            ))
        } else if !l.normal.iter().chain(&l.tangential).all(|v| v.is_finite()) {
            Some("a multiplier of the start is not finite".to_string())
        } else {
            None
        }
    });
    let bad_nested = opts.nested_lambda.as_ref().and_then(|l| {
        if opts.x0.is_none() || bad_x0.is_some() {
            Some("a nested start's multipliers without its displacements".to_string())
        } else if l.len() != qp.m() {
            Some(format!(
                "{} nested-start multipliers for {} contact rows",
                l.len(),
                qp.m()
            ))
        } else if !l.iter().all(|v| v.is_finite()) {
            Some("a multiplier of the nested start is not finite".to_string())
        } else {
            None
        }
    });
    if bad_x0.is_none() && bad_active0.is_none() && bad_lambda0.is_none() && bad_nested.is_none() {
        return Cow::Borrowed(opts);
    }
    let mut o = opts.clone();
    let mut refuse = |why: String| {
        let note = Note::WarmStartUnused(why);
        log::warn!("{note}");
        notes.push(note);
    };
    if let Some(why) = bad_x0 {
        o.x0 = None;
        refuse(why);
    }
    if let Some(why) = bad_active0 {
        o.active0 = None;
        refuse(why);
    }
    if let Some(why) = bad_lambda0 {
        o.lambda0 = None;
        refuse(why);
    }
    if let Some(why) = bad_nested {
        o.nested_lambda = None;
        refuse(why);
    }
    Cow::Owned(o)
}

/// Run `method` on `qp`: check the problem and the settings, decide
/// boundedness from the kernel ([`recession::boundedness`]), check the warm
/// start, solve with the free motions held, check any unbounded claim
/// ([`recession::certify`]; a claim that fails is not trusted and the solve
/// falls back, said in `notes`), and attach the KKT certificate and the
/// energy (`certify`).
pub fn run(
    method: &dyn Method,
    qp: &QpProblem,
    opts: &SolveOptions,
    ws: &Workspace,
) -> Result<QpResult, QpError> {
    opts.settings.validate().map_err(QpError::BadParameter)?;
    check_problem(qp)?;
    check_capabilities(method, qp)?;
    if let Some(caveat) = method.capabilities().friction_caveat {
        if qp.friction.is_some() && qp.n() > crate::qp::method::SLOW_FRICTION_DOFS {
            log::warn!("{}: {} unknowns: {caveat}", method.id(), qp.n());
        }
    }
    // With friction the tangential loads a floating body carries may be held
    // by friction: the frictionless decision does not apply, the method
    // decides (docs/methods.md §9.3).
    if qp.friction.is_none() {
        match recession::boundedness(qp) {
            Boundedness::Unbounded(c) => return Ok(unbounded_result(qp, c.direction)),
            Boundedness::Undecided(why) => log::debug!(
                "boundedness undecided ({why}); the method decides, its claim is checked"
            ),
            Boundedness::Bounded => {}
        }
    }
    let mut notes = vec![];
    let opts = checked_start(qp, opts, &mut notes);
    // Rigid motions along which the solution is not unique (a ring between
    // two flat plates): held by springs while the method runs, and the
    // answer returned without them (docs/methods.md §1.7).
    let t_free = Instant::now();
    let free = recession::free_motions(qp);
    log::debug!(
        "driver: free motions {} in {:.3} s",
        free.len(),
        t_free.elapsed().as_secs_f64()
    );
    let held;
    let qs = if free.is_empty() {
        qp
    } else {
        let note = Note::FreeMotions { count: free.len() };
        log::info!("{note}");
        notes.push(note);
        held = recession::pinned(qp, &free);
        &held
    };
    let fallback = Fallback {
        qs,
        opts: &opts,
        ws,
    };
    let r = solve_once(method, qs, &opts, ws)?;
    let mut r = match judge_claim(method, qp, r, &fallback, &mut notes)? {
        Claim::Unbounded(res) => return Ok(res),
        Claim::Answer(r) => r,
    };
    if let Status::Failed(failure @ Failure::Cycling { .. }) = &r.status {
        // An answer the certificate proves is kept whatever the sets did
        // ([`certify`] says so in a note); only an unproven one falls back.
        let proven = {
            let mut x = r.x.clone();
            recession::without_free(&mut x, &free);
            kkt::residuals_with_friction(qp, &x, &r.lambda, &r.lambda_t)
                .within(opts.settings.kkt_target)
        };
        let to = method
            .fallback(FallbackCause::Cycling)
            .filter(|to| to.capabilities().friction.solves(qp));
        if let (false, Some(to)) = (proven, to) {
            let failure = failure.clone();
            r = fallback.run(
                method.id(),
                to,
                FallbackCause::Cycling,
                failure,
                r,
                &mut notes,
            )?;
        }
    }
    recession::without_free(&mut r.x, &free);
    let res = certify(method.id(), qp, r, &free, &opts.settings, notes);
    // A Tresca problem a method did not solve may have no solution: its
    // rigid motions' loads beyond what the rows can resist, decided and
    // checked independently of the method (docs/methods.md §9.3).
    if qp.friction.is_some()
        && !res.status.converged()
        && !matches!(res.status, Status::Unbounded { .. })
    {
        if let Some(c) = super::recession_tresca::tresca_recession(qp) {
            log::info!(
                "{}: not converged; the Tresca problem is unbounded: a rigid motion on which the loads' work exceeds what friction dissipates",
                method.id()
            );
            return Ok(unbounded_result(qp, c.direction));
        }
    }
    Ok(res)
}

/// What [`judge_claim`] makes of a method's answer.
enum Claim {
    /// A verified recession direction: the problem is unbounded.
    Unbounded(QpResult),
    /// An answer to certify (the method's, or its fallback's).
    Answer(Output),
}

/// Check an unbounded claim of `r` ([`recession::certify`]). A claim that
/// fails the certificate is not trusted: the method's fallback solves the
/// problem ([`Method::fallback`]); with friction, or without a fallback,
/// the failure stands (docs/methods.md §8.2).
fn judge_claim(
    method: &dyn Method,
    qp: &QpProblem,
    mut r: Output,
    fallback: &Fallback,
    notes: &mut Vec<Note>,
) -> Result<Claim, QpError> {
    let Status::Unbounded { direction } = &r.status else {
        return Ok(Claim::Answer(r));
    };
    let why = match recession::certify(qp, direction) {
        Ok(c) => return Ok(Claim::Unbounded(unbounded_result(qp, c.direction))),
        Err(why) => why,
    };
    let id = method.id();
    let failure = Failure::RefusedClaim { method: id, why };
    let to = method.fallback(FallbackCause::RefusedClaim);
    let (Some(to), None) = (to, &qp.friction) else {
        r.status = Status::Failed(failure);
        return Ok(Claim::Answer(r));
    };
    r = fallback.run(id, to, FallbackCause::RefusedClaim, failure, r, notes)?;
    if let Status::Unbounded { direction } = &r.status {
        let why = recession::certify(qp, direction).err().unwrap_or_default();
        r.status = Status::Failed(Failure::RefusedClaim { method: to, why });
    }
    Ok(Claim::Answer(r))
}

/// Attach the KKT certificate (docs/methods.md §8.4) and the energy to `r`,
/// after moving it along the motions free on the rows carrying a force
/// (§1.7) when that keeps the certificate; a stalled answer that meets the
/// certificate counts as converged.
fn certify(
    id: MethodId,
    qp: &QpProblem,
    mut r: Output,
    free: &[Vec<f64>],
    settings: &Settings,
    mut notes: Vec<Note>,
) -> QpResult {
    let target = settings.kkt_target;
    zero_on_empty_rows(qp, &r.x, &mut r.lambda_t);
    let (mut kkt, mut cx) = kkt::residuals_and_cx(qp, &r.x, &r.lambda, &r.lambda_t);
    // Motions free on the rows carrying a force (docs/methods.md §1.7): the
    // move keeps Cx, those rows (and their slip) and dᵀx. It is taken only
    // from a certified answer and only if it keeps the certificate (a gap
    // it opens under a small λ).
    if kkt.within(target) {
        let t_settle = Instant::now();
        let mut settled = r.x.clone();
        let rolled = recession::settle_on_active(qp, &mut settled, &r.lambda, free);
        log::debug!(
            "driver: {rolled} motions free on the active rows in {:.3} s",
            t_settle.elapsed().as_secs_f64()
        );
        if rolled > 0 {
            let (moved, moved_cx) = kkt::residuals_and_cx(qp, &settled, &r.lambda, &r.lambda_t);
            if moved.within(target) {
                r.x = settled;
                kkt = moved;
                cx = moved_cx;
                notes.push(Note::SettledOnActive { count: rolled });
            } else {
                // The move would lose the certificate: the method's answer
                // is exact only at the scale of its own rigid motion, not at
                // that of the deformation. It is still a solution; say that
                // it is one point of the set, not the least.
                notes.push(Note::NotSettled { count: rolled });
            }
        }
    }
    let energy = match &cx {
        Some(cx) => qp.energy_with_friction_cx(&r.x, cx, &r.lambda),
        None => qp.energy_with_friction(&r.x, &r.lambda),
    };
    if !energy.is_finite() {
        kkt = Kkt::not_finite();
    }
    // A method that stops above its own tolerance may still have an answer
    // the certificate proves (the dual family stalling on a body free to
    // roll, a Coulomb loop whose change of s sits at the Tresca solves'
    // rounding, an exact start a relative stopping rule cannot measure):
    // the certificate decides, and the note says how the method stopped.
    // The caller's own stops (a time limit, a signal) stand.
    if promotable(&r.status) && kkt.within(target) {
        notes.push(Note::StalledButCertified {
            method: id,
            stopped: std::mem::replace(&mut r.status, Status::Converged),
            target,
        });
    }
    QpResult {
        solution: r,
        kkt,
        energy,
        notes,
    }
}

/// λ_t on a tangential row of T without entries and without offset (a
/// tangent held by a plane of symmetry, docs/methods.md §12.2, §12.5)
/// enters no balance and no slip: any value the bound admits is as good,
/// and a method may leave one there (the dual methods do: nothing moves
/// it). Its one representative is 0, which also leaves the row's partner
/// the whole disc; so every method reports the same λ_t, and the
/// certificate is taken of that. An empty row with an offset has the slip
/// −t0 prescribed, and its λ_t is the slip rule's: it is left alone. An
/// offset below 10⁻¹² of the length scale X of the certificate (§9.4) is
/// rounding (a point held on a plane whose normal is a computed one keeps
/// displacements of 10⁻²³ m across it), not a slip: the slip rule weighs
/// it by |t0|/X, so either λ_t passes, and 0 is taken.
fn zero_on_empty_rows(qp: &QpProblem, x: &[f64], lambda_t: &mut [f64]) {
    let Some(f) = &qp.friction else {
        return;
    };
    let xmax = crate::linalg::sparse::norm_inf(x).max(kkt::length_floor(qp));
    for (i, l) in lambda_t.iter_mut().enumerate().take(f.t.nrows) {
        // A zero stays as it is (its sign too: the same bits as before).
        if *l != 0.0
            && f.t0.get(i).is_some_and(|t0| t0.abs() <= 1e-12 * xmax)
            && f.t.row(i).1.iter().all(|&v| v == 0.0)
        {
            *l = 0.0;
        }
    }
}

/// Whether a method's unconverged `status` is judged by the certificate
/// alone ([`certify`]): every stop of the method's own (MAXIT, stagnation,
/// cycling, an unsettled Coulomb loop, its own refinement's miss, a
/// breakdown), not a stop the caller made (a time limit, a signal), nor an
/// answer that is not one (NaN, an unbounded claim).
fn promotable(status: &Status) -> bool {
    match status {
        Status::Converged | Status::Unbounded { .. } => false,
        Status::MaxIter => true,
        Status::Failed(f) => matches!(
            f,
            Failure::Stagnation { .. }
                | Failure::Cycling { .. }
                | Failure::CoulombUnsettled { .. }
                | Failure::Uncertified { .. }
                | Failure::Breakdown(_)
        ),
    }
}

/// One call of `method` with its own context; the phases it timed through
/// the context come first in the output's timings.
fn solve_once(
    method: &dyn Method,
    qp: &QpProblem,
    opts: &SolveOptions,
    ws: &Workspace,
) -> Result<Output, QpError> {
    let mut ctx = Context::new(opts, ws);
    let mut out = method.solve(qp, &mut ctx)?;
    let mut t = ctx.take_timings();
    t.append(&mut out.timings);
    out.timings = t;
    Ok(out)
}

/// A result that carries a verified recession direction and no solution.
fn unbounded_result(qp: &QpProblem, direction: Vec<f64>) -> QpResult {
    QpResult {
        solution: Output {
            x: vec![0.0; qp.n()],
            lambda: vec![0.0; qp.m()],
            lambda_t: vec![],
            active: vec![false; qp.m()],
            status: Status::Unbounded { direction },
            iterations: 0,
            inner_iterations: 0,
            log: vec![],
            timings: vec![],
        },
        kkt: Kkt::not_finite(),
        energy: f64::NEG_INFINITY,
        notes: vec![],
    }
}

/// The QP's data must be finite and consistently sized.
pub fn check_problem(qp: &QpProblem) -> Result<(), QpError> {
    let (n, m) = (qp.n(), qp.m());
    if qp.c.nrows != n || qp.c.ncols != n || qp.a.nrows != m || qp.a.ncols != n {
        return Err(QpError::BadParameter(format!(
            "inconsistent sizes: C {}×{}, d {n}, A {}×{}, g {m}",
            qp.c.nrows, qp.c.ncols, qp.a.nrows, qp.a.ncols
        )));
    }
    for (what, v) in [
        ("the stiffness matrix C", &*qp.c.data),
        ("the load vector d", &qp.d),
        ("the contact matrix A", &*qp.a.data),
        ("the gaps g", &qp.g),
    ] {
        if let Some(i) = v.iter().position(|e| !e.is_finite()) {
            return Err(QpError::BadParameter(format!(
                "{what} has a non-finite entry ({}) at position {i}: loads, moduli or prescribed displacements overflow",
                v[i]
            )));
        }
    }
    if let Some(f) = &qp.friction {
        let (s, what) = match &f.bound {
            crate::qp::SlipBound::Tresca(s) => (s, "slip bound s"),
            crate::qp::SlipBound::Coulomb(mu) => (mu, "friction coefficient μ"),
        };
        let mt = m * f.frame.rows();
        if f.t.nrows != mt || f.t.ncols != n || f.t0.len() != mt || s.len() != m {
            return Err(QpError::BadParameter(format!(
                "inconsistent friction sizes: T {}×{}, t0 {}, {what} {} for {m} contact rows ({mt} tangential) and {n} unknowns",
                f.t.nrows, f.t.ncols, f.t0.len(), s.len()
            )));
        }
        for (w, v) in [
            ("the tangential matrix T", &*f.t.data),
            ("the slip offset t0", &f.t0),
        ] {
            if let Some(i) = v.iter().position(|e| !e.is_finite()) {
                return Err(QpError::BadParameter(format!(
                    "{w} has a non-finite entry ({}) at position {i}",
                    v[i]
                )));
            }
        }
        if let Some(i) = s.iter().position(|e| !(e.is_finite() && *e >= 0.0)) {
            return Err(QpError::BadParameter(format!(
                "the {what} of contact row {i} is {}: it must be finite and ≥ 0",
                s[i]
            )));
        }
        // The force a Tresca bound puts on the unknowns, sᵢ·Σⱼ|Tᵢⱼ|, must be
        // a number: the slip forces and the dissipation are formed from it.
        if let crate::qp::SlipBound::Tresca(s) = &f.bound {
            for (i, &si) in s.iter().enumerate() {
                let row: f64 = f.t.row(i).1.iter().map(|v| v.abs()).sum();
                if !(si * row).is_finite() {
                    return Err(QpError::BadParameter(format!(
                        "the slip bound s of contact row {i} is {si:e}: times its tangential row \
                         (Σ|T| = {row:e}) it overflows; a bound far above the contact forces \
                         glues the interface just as well (use a smaller tresca)"
                    )));
                }
            }
        }
    }
    if let Some((i, z)) = qp.kernel.iter().enumerate().find(|(_, z)| z.len() != n) {
        return Err(QpError::BadParameter(format!(
            "kernel vector {i} has {} entries for {n} unknowns",
            z.len()
        )));
    }
    Ok(())
}

/// A warm start must be finite, of the right size, and of a plausible scale
/// (docs/methods.md §8.3), judged in O(n) from bounds, with no product by C:
/// its energy bound ½‖x‖∞²·max Cᵢᵢ·nnz(C) (|Cᵢⱼ| ≤ max Cᵢᵢ for C ⪰ 0) must
/// be finite, and the force scale ‖x‖∞·max Cᵢᵢ at most 10¹² times the
/// loads' ‖d‖∞ (a checkpoint holding 1e300; a load step's own answer is
/// within a few times its loads).
pub fn check_warm_start(qp: &QpProblem, x0: &[f64]) -> Result<(), String> {
    if x0.len() != qp.n() {
        return Err(format!("{} values for {} unknowns", x0.len(), qp.n()));
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(format!("value {i} is {}", x0[i]));
    }
    let xmax = crate::linalg::sparse::norm_inf(x0);
    let cmax = crate::linalg::sparse::norm_inf(&qp.c.diag());
    if !(0.5 * xmax * xmax * cmax * qp.c.data.len() as f64).is_finite() {
        return Err("its energy is not finite".into());
    }
    let force = xmax * cmax;
    let dmax = crate::linalg::sparse::norm_inf(&qp.d);
    if dmax > 0.0 && force > 1e12 * dmax {
        return Err(format!(
            "its force scale ‖x‖∞·max Cᵢᵢ is {force:.3e}, {:.1e} times the loads",
            force / dmax
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::testing::two_blocks;
    use std::cell::RefCell;
    use std::rc::Rc;

    /// Counts records and finishes.
    #[derive(Default)]
    struct Count {
        records: usize,
        finished: usize,
        last_iter: usize,
    }

    impl Observer for Count {
        fn observe(&mut self, rec: &IterRecord) {
            self.records += 1;
            self.last_iter = rec.iter;
        }
        fn finish(&mut self) {
            self.finished += 1;
        }
    }

    /// The caller's observer sees every iteration of the method it chose,
    /// for each family, and one `finish` per executor run.
    #[test]
    fn the_callers_observer_sees_every_iteration() {
        let qp = two_blocks(8, 4, true);
        for name in [
            MethodId::Cgc,
            MethodId::Asm,
            MethodId::Mprgp,
            MethodId::Ssn,
            MethodId::Penalty,
        ] {
            let count = Rc::new(RefCell::new(Count::default()));
            let opts = SolveOptions {
                observers: vec![count.clone()],
                ..Default::default()
            };
            let r = crate::qp::registry::solve(name, &qp, &opts).unwrap();
            assert!(r.status.converged(), "{name}: {:?}", r.status);
            let c = count.borrow();
            assert_eq!(c.records, r.iterations, "{name}");
            assert_eq!(c.last_iter, r.iterations, "{name}");
            assert_eq!(c.finished, 1, "{name}");
        }
    }

    /// A working-set warm start (docs/methods.md §8.3): its own answer's
    /// active set gives ssn the same working set and the answer to rounding,
    /// any set (none, every row) still the certified answer; one of the
    /// wrong length is not used, and the note says why.
    #[test]
    fn a_working_set_warm_start_is_checked_and_starts_ssn() {
        let qp = two_blocks(8, 4, true);
        let cold =
            crate::qp::registry::solve(MethodId::Ssn, &qp, &SolveOptions::default()).unwrap();
        assert!(cold.status.converged() && cold.kkt.within(1e-10));
        let m = qp.m();
        let starts = [
            cold.solution.active.clone(),
            vec![false; m],
            vec![true; m],
            vec![true; m + 1],
        ];
        for (k, a0) in starts.into_iter().enumerate() {
            let opts = SolveOptions {
                active0: Some(a0),
                ..Default::default()
            };
            let r = crate::qp::registry::solve(MethodId::Ssn, &qp, &opts).unwrap();
            assert!(r.status.converged() && r.kkt.within(1e-10), "start {k}");
            assert_eq!(r.solution.active, cold.solution.active, "start {k}");
            let dx = r
                .solution
                .x
                .iter()
                .zip(&cold.solution.x)
                .fold(0.0f64, |mx, (a, b)| mx.max((a - b).abs()));
            let xmax = crate::linalg::sparse::norm_inf(&cold.solution.x);
            assert!(dx <= 1e-12 * xmax, "start {k}: {dx:e}");
            let refused = r
                .notes
                .iter()
                .any(|n| matches!(n, Note::WarmStartUnused(w) if w.contains("working-set flags")));
            assert_eq!(refused, k == 3, "start {k}: {:?}", r.notes);
        }
    }
}
