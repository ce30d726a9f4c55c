//! Every method (each CGC preconditioner a variant) on one problem, and the
//! comparison table: probe displacements, iterations, time per phase, KKT
//! residuals, energy, agreement with the most accurate result. A failing
//! variant says so in its row; the others go on. `signorini compare` is this
//! API plus flag parsing and printing (README "Comparing methods").
//!
//! Load steps (docs/problem-format.md §4): frictionless elastic contact does
//! not depend on the loading path, so each variant solves the last step from
//! a cold start. With friction the answer does (docs/methods.md §9.1: the
//! slip of a step is measured from the previous step), so each variant
//! follows the load path as [`Run`] does and the last step is compared.

use super::prepare::{options, probes, solve_model, step_model, Prepared};
use super::steps::{Run, Step, Verdict};
use super::{RunError, StepObserver};
use crate::fem::Model;
use crate::qp::method::Certificate;
use crate::qp::{
    precond::PrecondKind, registry, Kkt, MethodChoice, MethodId, Note, ProgressDisplay, QpResult,
    SolverSection,
};
use crate::qp::{QpProblem, SolveOptions};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// One variant: a method and, for a preconditioned one, its preconditioner.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Variant {
    pub method: MethodId,
    pub preconditioner: Option<PrecondKind>,
}

impl Variant {
    /// `method` or `method:preconditioner`, as `--methods` spells it.
    pub fn name(&self) -> String {
        match self.preconditioner {
            Some(p) => format!("{}:{}", self.method, p.name()),
            None => self.method.name().to_string(),
        }
    }

    /// The preconditioner column: its name, or `-`.
    pub fn preconditioner_label(&self) -> String {
        self.preconditioner
            .map_or_else(|| "-".to_string(), |k| k.name().to_string())
    }
}

/// The variants named by `spec`, a comma-separated list of method names
/// (a preconditioned method alone: every preconditioner) or
/// `method:preconditioner`; None: every method.
pub fn variants(spec: Option<&str>) -> Result<Vec<Variant>, RunError> {
    let items: Vec<String> = match spec {
        None => registry::names().iter().map(|s| s.to_string()).collect(),
        Some(s) => s
            .split(',')
            .map(|x| x.trim().to_string())
            .filter(|x| !x.is_empty())
            .collect(),
    };
    let mut out = vec![];
    for it in items {
        let (name, pc) = match it.split_once(':') {
            Some((n, p)) => (n.to_string(), Some(p.to_string())),
            None => (it.clone(), None),
        };
        let m = MethodId::parse(&name).ok_or_else(|| {
            RunError::Settings(format!(
                "unknown method \"{name}\"; known: {}",
                MethodId::known()
            ))
        })?;
        if m.capabilities().preconditioned {
            match pc {
                Some(p) => out.push(Variant {
                    method: m,
                    preconditioner: Some(PrecondKind::parse(&p).ok_or_else(|| {
                        RunError::Settings(format!("unknown preconditioner \"{p}\""))
                    })?),
                }),
                None => out.extend(PrecondKind::ALL.iter().map(|k| Variant {
                    method: m,
                    preconditioner: Some(*k),
                })),
            }
        } else {
            out.push(Variant {
                method: m,
                preconditioner: None,
            });
        }
    }
    Ok(out)
}

/// What to compare and how.
#[derive(Debug, Clone, Default)]
pub struct CompareSpec {
    /// The variants as [`variants`] reads them. None: every method, or with
    /// friction every method that solves it (the others would all be
    /// refused, docs/methods.md §9.2).
    pub methods: Option<String>,
    /// Laid over the problem's `[solver]` for every variant (its method and
    /// preconditioner replaced by the variant's); its `kkt_target` is the
    /// certificate's target of every row.
    pub solver: SolverSection,
    /// Wall-clock budget per variant in seconds (the whole load path with
    /// friction); a budget too large for a [`Duration`] or an [`Instant`]
    /// is no deadline.
    pub time_limit: Option<f64>,
    /// The display of the methods' progress (the command line's spinner
    /// on stderr); None: none.
    pub progress: Option<Arc<dyn ProgressDisplay>>,
}

/// What [`compare`] reports while it runs (the CLI prints it on stderr).
pub enum Event<'a> {
    /// Before the first variant: which step is compared and how, and with
    /// friction (no `methods` given) the variants kept.
    Plan {
        steps: &'a TableSteps,
        /// Pseudo-time of the compared step.
        time: f64,
        friction_only: Option<&'a [Variant]>,
    },
    /// Variant `index` (0-based) of `total` starts.
    Start {
        index: usize,
        total: usize,
        variant: &'a Variant,
    },
    /// It ended, after `seconds`.
    Done {
        index: usize,
        total: usize,
        variant: &'a Variant,
        outcome: &'a Result<VariantResult, String>,
        seconds: f64,
    },
}

/// The progress label of variant `index` of `total`: `[k/n] method[:pc]`.
pub fn label(index: usize, total: usize, v: &Variant) -> String {
    format!("[{}/{total}] {}", index + 1, v.name())
}

/// One variant's answer on the compared step.
#[derive(Debug, Clone)]
pub struct VariantResult {
    /// The compared (last) step's result.
    pub result: QpResult,
    /// Probe displacements of that step.
    pub probes: BTreeMap<String, Vec<f64>>,
    /// Wall time of the variant (the whole path when it follows one).
    pub time_s: f64,
    /// Outer and inner iterations, time per phase: summed over the steps
    /// solved (one, or the whole path).
    pub iterations: usize,
    pub inner_iterations: usize,
    pub phases: BTreeMap<String, f64>,
    /// Every earlier step of the path converged and was certified (true
    /// without a path); a row whose path broke down is not certified.
    pub path_certified: bool,
    /// The result's notes, then one per earlier step that failed.
    pub notes: Vec<String>,
    /// The note of a fallback: the row's numbers are that method's.
    pub fallback: Option<String>,
}

/// The text of a fallback among `notes` (the driver solved by another
/// method, docs/methods.md §8.2).
fn fallback_of(notes: &[Note]) -> Option<String> {
    notes
        .iter()
        .find(|n| matches!(n, Note::Fallback { .. }))
        .map(ToString::to_string)
}

/// The variants of `spec` on `prep`, and the table. Errors are bad input
/// (an unknown method, a time limit or KKT target that is no positive
/// number, a step model that cannot be built); a variant that fails says so
/// in its row.
/// A prepared model as [`compare`] sees it, whichever its dimension: what
/// the yardstick reads ([`super::limit::Assembled`]: the problem, the
/// QP, the times), the model of the compared (last) step, and the load path when
/// every variant must follow it (friction with several steps,
/// docs/methods.md §9.1). The plane `Prepared` and the solid
/// `SolidPrepared` each give one; `compare` asks nothing else of them.
pub trait Comparable: super::limit::Assembled {
    /// The problem as written (its loads at factor 1, no step applied):
    /// what `export` writes and solves.
    fn written(&self) -> Result<Box<dyn ComparedStep + '_>, RunError>;
    /// The model of the compared step (with `[[steps]]`, the last one's
    /// loads and prescribed displacements).
    fn compared_step(&self) -> Result<Box<dyn ComparedStep + '_>, RunError>;
    /// Every step of the load path by `method`, warm-started as `solve`
    /// does, the last one's answer and probes (only asked when the compared
    /// step has friction and the problem several steps).
    fn solve_path(
        &self,
        method: MethodId,
        opts: &SolveOptions,
        t: Instant,
    ) -> Result<VariantResult, String>;
}

/// The compared step of a model: its QP, a solve by one method (an
/// unbounded answer described in the model's words), the probe
/// displacements of an answer x.
pub trait ComparedStep {
    fn qp(&self) -> &QpProblem;
    fn solve(&self, method: MethodId, opts: &SolveOptions) -> Result<QpResult, RunError>;
    /// Each probe's displacement components (2 or 3), by name.
    fn probes(&self, x: &[f64]) -> BTreeMap<String, Vec<f64>>;
}

impl Comparable for Prepared {
    fn written(&self) -> Result<Box<dyn ComparedStep + '_>, RunError> {
        // The prepared plane model is the problem as written.
        Ok(Box::new(PlaneStep {
            prep: self,
            model: None,
        }))
    }

    fn compared_step(&self) -> Result<Box<dyn ComparedStep + '_>, RunError> {
        let file = &self.problem.file;
        // The last step's model (with [[steps]], its loads and prescribed
        // displacements; the reference slip t0 = 0).
        let model = if file.steps.is_empty() {
            None
        } else {
            Some(step_model(self, file.nsteps() - 1)?)
        };
        Ok(Box::new(PlaneStep { prep: self, model }))
    }

    fn solve_path(
        &self,
        m: MethodId,
        opts: &SolveOptions,
        t: Instant,
    ) -> Result<VariantResult, String> {
        let mut work = PathWork::new(self.problem.file.nsteps());
        let out = Run::new(self, m, opts)
            .started(t)
            .solve(&mut [&mut work], None)
            .map_err(|e| e.to_string())?;
        let last = out
            .last
            .ok_or_else(|| "no load step was solved".to_string())?;
        let probes = plane_probes(self, &last.output.displacement);
        Ok(work.finish(last.result, probes, t))
    }
}

/// The compared step of a plane or axisymmetric model.
struct PlaneStep<'a> {
    prep: &'a Prepared,
    /// The step's own model (None: the prepared one, no `[[steps]]`).
    model: Option<Model>,
}

impl PlaneStep<'_> {
    fn model(&self) -> &Model {
        self.model.as_ref().unwrap_or(&self.prep.model)
    }
}

impl ComparedStep for PlaneStep<'_> {
    fn qp(&self) -> &QpProblem {
        &self.model().qp
    }

    fn solve(&self, method: MethodId, opts: &SolveOptions) -> Result<QpResult, RunError> {
        solve_model(self.prep, self.model(), method, opts)
    }

    fn probes(&self, x: &[f64]) -> BTreeMap<String, Vec<f64>> {
        plane_probes(self.prep, &self.model().displacements(x))
    }
}

fn plane_probes(prep: &Prepared, u: &[[f64; 2]]) -> BTreeMap<String, Vec<f64>> {
    probes(prep, u)
        .into_iter()
        .map(|(n, _, _, u)| (n, u.to_vec()))
        .collect()
}

/// Every variant of `spec` on `prep`'s compared step (or load path), and
/// the table.
pub fn compare(
    prep: &(impl Comparable + ?Sized),
    spec: &CompareSpec,
    on: &mut dyn FnMut(Event<'_>),
) -> Result<Table, RunError> {
    let problem = prep.problem();
    let bad = |msg: String| RunError::Solver {
        path: problem.path.clone(),
        msg,
    };
    let list = variants(spec.methods.as_deref()).map_err(|e| bad(e.to_string()))?;
    if let Some(t) = spec.time_limit {
        if !(t > 0.0 && t.is_finite()) {
            return Err(bad(format!(
                "time limit {t}: must be a positive number of seconds"
            )));
        }
    }
    // The settings every variant shares: the certificate's target and
    // penalty's ε_p (a bad value is bad input before any variant runs).
    let (_, shared) = options(problem, &spec.solver)?;
    let kkt_target = shared.settings.kkt_target;
    let file = &problem.file;
    let nsteps = file.nsteps();
    let multi = !file.steps.is_empty();
    let step = prep.compared_step()?;
    let friction = step.qp().friction.is_some();
    let path = multi && nsteps > 1 && friction;
    let steps = TableSteps {
        count: nsteps,
        compared: nsteps,
        path,
    };
    // With friction only the methods that solve it are run (unless named).
    let list: Vec<Variant> = if friction && spec.methods.is_none() {
        list.into_iter()
            .filter(|v| v.method.capabilities().friction.any())
            .collect()
    } else {
        list
    };
    on(Event::Plan {
        steps: &steps,
        time: file.step_time(nsteps - 1),
        friction_only: (friction && spec.methods.is_none()).then_some(&list[..]),
    });
    let total = list.len();
    let mut runs = vec![];
    for (index, v) in list.iter().enumerate() {
        on(Event::Start {
            index,
            total,
            variant: v,
        });
        let t = Instant::now();
        let outcome = solve_variant(prep, &*step, spec, v, path, t, label(index, total, v));
        on(Event::Done {
            index,
            total,
            variant: v,
            outcome: &outcome,
            seconds: t.elapsed().as_secs_f64(),
        });
        runs.push((v.clone(), outcome));
    }
    let penalty_eps = shared.settings.penalty.eps;
    let mut table = table(&problem.name, step.qp(), &runs, kkt_target, penalty_eps);
    table.steps = steps;
    table.time_limit_s = spec.time_limit;
    Ok(table)
}

/// The deadline `seconds` after `t`; None (no deadline) when it cannot be
/// represented (a budget of 10¹⁹ s outlives any run).
pub fn deadline(t: Instant, seconds: f64) -> Option<Instant> {
    Duration::try_from_secs_f64(seconds)
        .ok()
        .and_then(|d| t.checked_add(d))
}

/// Sums the work of every step of a path and notes the steps before the
/// last that did not converge or certify (plane and solid paths alike).
pub(crate) struct PathWork {
    nsteps: usize,
    iterations: usize,
    inner_iterations: usize,
    phases: BTreeMap<String, f64>,
    failed: Vec<String>,
}

impl PathWork {
    pub(crate) fn new(nsteps: usize) -> Self {
        PathWork {
            nsteps,
            iterations: 0,
            inner_iterations: 0,
            phases: BTreeMap::new(),
            failed: vec![],
        }
    }

    /// Add step `index` (0-based), solved to `r` with `verdict`.
    pub(crate) fn add(&mut self, index: usize, r: &QpResult, verdict: Verdict) {
        self.iterations += r.iterations;
        self.inner_iterations += r.inner_iterations;
        for (k, v) in &r.timings {
            *self.phases.entry(k.clone()).or_default() += v;
        }
        if index + 1 < self.nsteps {
            let s = index + 1;
            match verdict {
                Verdict::Certified | Verdict::Penalised => {}
                Verdict::NotConverged => self.failed.push(format!(
                    "step {s}/{}: not converged: {}",
                    self.nsteps,
                    r.status.describe()
                )),
                Verdict::NotCertified => self.failed.push(format!(
                    "step {s}/{}: not certified (KKT {:.2e})",
                    self.nsteps,
                    r.kkt.max()
                )),
            }
        }
    }

    /// The row of a path whose last step answered `result` with the probe
    /// displacements `probes`, begun at `t`.
    pub(crate) fn finish(
        self,
        result: QpResult,
        probes: BTreeMap<String, Vec<f64>>,
        t: Instant,
    ) -> VariantResult {
        let fallback = fallback_of(&result.notes);
        let mut notes: Vec<String> = result.notes.iter().map(ToString::to_string).collect();
        notes.extend(self.failed.iter().cloned());
        VariantResult {
            probes,
            time_s: t.elapsed().as_secs_f64(),
            iterations: self.iterations,
            inner_iterations: self.inner_iterations,
            phases: self.phases,
            path_certified: self.failed.is_empty(),
            notes,
            fallback,
            result,
        }
    }
}

impl StepObserver for PathWork {
    fn on_step(&mut self, step: &Step<'_>) -> Result<Vec<String>, RunError> {
        self.add(step.index, step.result, step.verdict);
        Ok(vec![])
    }
}

fn solve_variant(
    prep: &(impl Comparable + ?Sized),
    step: &dyn ComparedStep,
    spec: &CompareSpec,
    v: &Variant,
    path: bool,
    t: Instant,
    label: String,
) -> Result<VariantResult, String> {
    let mut c = spec.solver.clone();
    c.method = Some(MethodChoice::Named(v.method));
    c.preconditioner = v.preconditioner;
    let (m, mut opts) = options(prep.problem(), &c).map_err(|e| e.to_string())?;
    // Each method pays for its own factorization: every variant gets a
    // fresh workspace (a Run makes one for its steps).
    opts.progress = spec.progress.clone();
    opts.label = Some(label);
    opts.deadline = spec.time_limit.and_then(|s| deadline(t, s));
    if path {
        return prep.solve_path(m, &opts, t);
    }
    let q = step.solve(m, &opts).map_err(|e| e.to_string())?;
    Ok(VariantResult {
        probes: step.probes(&q.x),
        time_s: t.elapsed().as_secs_f64(),
        iterations: q.iterations,
        inner_iterations: q.inner_iterations,
        phases: q.timings.iter().cloned().collect(),
        path_certified: true,
        notes: q.notes.iter().map(ToString::to_string).collect(),
        fallback: fallback_of(&q.notes),
        result: q,
    })
}

/// The rule that a method's answer is that of a penalised problem, O(ε_p)
/// from the exact one (docs/methods.md §4.4, §8.4): it is never the
/// reference and agrees within its own tolerances.
pub(crate) fn penalised(method: MethodId) -> bool {
    method.capabilities().certificate == Certificate::Penalised
}

/// ‖a − b‖ / ‖b‖ (0 when both vanish).
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let den = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    if den > 0.0 {
        num / den
    } else {
        num
    }
}

/// The table of `runs` on `model` (the compared step's; its friction says
/// whether λ_t is compared). `reference` = the converged, certified row
/// with the smallest KKT residual; each row's `rel_diff` =
/// ‖x − x_ref‖/‖x_ref‖, `rel_diff_lambda` = ‖λ − λ_ref‖/‖λ_ref‖ (the
/// contact forces) and, with friction, `rel_diff_lambda_t` the same for the
/// tangential forces; `agrees` = converged, certified (KKT ≤ `kkt_target`,
/// and every earlier step of its path too), every difference ≤ its
/// tolerance and the same active set. The tolerances are 1e-6 (or the
/// rounding floor of the row's or the reference's stationarity, if larger:
/// docs/methods.md §8.4), except for a penalised method, whose minimiser
/// x_ε is O(ε_p) away from x: its x tolerance (`agree_tol`) is max(that,
/// 10·its relative constraint violation), the violation being the
/// observable O(ε_p) scale of that run; its contact forces are those of
/// contact springs of compliance ε_j, off by about ε_j·c_kk relative per
/// row (10⁻³ by default, methods.md §4.4) and by more at the edge of a
/// contact zone (2.4·10⁻² measured on the floating punch of tests/hard), so
/// its force tolerance (`agree_tol_lambda`, λ and λ_t) is 100·ε_p·max diag C
/// for a given ε_p, or 100/PENALTY_FACTOR for the default one.
pub fn table(
    problem: &str,
    qp: &QpProblem,
    runs: &[(Variant, Result<VariantResult, String>)],
    kkt_target: f64,
    penalty_eps: Option<f64>,
) -> Table {
    let friction = qp.friction.is_some();
    let penalty_lambda_tol = match penalty_eps {
        Some(e) => 100.0 * e * qp.c.diag().iter().fold(0.0f64, |a, b| a.max(*b)),
        None => 100.0 / crate::qp::primal::penalty::PENALTY_FACTOR,
    };
    let certified = |v: &Variant, s: &VariantResult| {
        let q = &s.result;
        q.status.converged()
            && s.path_certified
            && registry::certified(v.method, &q.kkt, kkt_target, false)
    };
    let best = runs
        .iter()
        .enumerate()
        .filter_map(|(i, (v, o))| {
            o.as_ref()
                .ok()
                .filter(|s| certified(v, s) && !penalised(v.method))
                .map(|s| (i, s.result.kkt.max()))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|x| x.0);
    let reference = best
        .and_then(|i| runs[i].1.as_ref().ok())
        .map(|s| &s.result);
    let mut out = vec![];
    for (v, o) in runs {
        let row = match o {
            Err(e) => TableRow {
                method: v.method.name().to_string(),
                preconditioner: v.preconditioner_label(),
                error: Some(e.clone()),
                converged: false,
                certified: false,
                agrees: false,
                solved: None,
            },
            Ok(s) => {
                let q = &s.result;
                // Two answers at the rounding floor differ by about the
                // floor, relative (docs/methods.md §8.4).
                let base = reference
                    .map_or(0.0, |rf| rf.kkt.stationarity_floor)
                    .max(q.kkt.stationarity_floor)
                    .clamp(1e-6, crate::qp::kkt::FLOOR_CAP);
                let (agree_tol, agree_tol_lambda) = if penalised(v.method) {
                    (
                        (10.0 * q.kkt.primal).max(base),
                        penalty_lambda_tol.max(base),
                    )
                } else {
                    (base, base)
                };
                let cert = certified(v, s);
                let (rel, rel_l, rel_t, disagrees) = match reference {
                    Some(rf) => {
                        let rel = rel_diff(&q.x, &rf.x);
                        let rel_l = rel_diff(&q.lambda, &rf.lambda);
                        let rel_t = if q.lambda_t.len() == rf.lambda_t.len() {
                            rel_diff(&q.lambda_t, &rf.lambda_t)
                        } else {
                            f64::INFINITY
                        };
                        let rows = if q.active.len() == rf.active.len() {
                            q.active
                                .iter()
                                .zip(&rf.active)
                                .filter(|(a, b)| a != b)
                                .count()
                        } else {
                            q.active.len().max(rf.active.len())
                        };
                        let over = |diff: f64, tol: f64| !(diff <= tol);
                        let why = if over(rel, agree_tol) {
                            Some(Disagreement::X {
                                diff: rel,
                                tol: agree_tol,
                            })
                        } else if over(rel_l, agree_tol_lambda) {
                            Some(Disagreement::Lambda {
                                diff: rel_l,
                                tol: agree_tol_lambda,
                            })
                        } else if over(rel_t, agree_tol_lambda) {
                            Some(Disagreement::LambdaT {
                                diff: rel_t,
                                tol: agree_tol_lambda,
                            })
                        } else if rows > 0 {
                            Some(Disagreement::ActiveSet { rows })
                        } else {
                            None
                        };
                        (rel, rel_l, rel_t, why)
                    }
                    None => (f64::NAN, f64::NAN, f64::NAN, None),
                };
                let agrees = cert && reference.is_some() && disagrees.is_none();
                TableRow {
                    method: v.method.name().to_string(),
                    preconditioner: v.preconditioner_label(),
                    error: None,
                    converged: q.status.converged(),
                    certified: cert,
                    agrees,
                    solved: Some(SolvedRow {
                        status: q.status.describe(),
                        iterations: s.iterations,
                        inner_iterations: s.inner_iterations,
                        time_s: s.time_s,
                        phases: s.phases.clone(),
                        kkt: q.kkt,
                        kkt_max: q.kkt.max(),
                        energy: q.energy,
                        active: q.active.iter().filter(|a| **a).count(),
                        probes: s.probes.clone(),
                        rel_diff: rel,
                        rel_diff_lambda: rel_l,
                        rel_diff_lambda_t: friction.then_some(rel_t),
                        agree_tol,
                        agree_tol_lambda,
                        disagrees: disagrees.filter(|_| cert),
                        notes: s.notes.clone(),
                        fallback: s.fallback.clone(),
                    }),
                }
            }
        };
        out.push(row);
    }
    Table {
        problem: problem.to_string(),
        dofs: qp.n(),
        constraints: qp.m(),
        kkt_target,
        rows: out,
        steps: TableSteps {
            count: 1,
            compared: 1,
            path: false,
        },
        time_limit_s: None,
    }
}

/// The comparison table (`--json`; keys in alphabetical order).
#[derive(Debug, Clone, Serialize)]
pub struct Table {
    pub problem: String,
    pub dofs: usize,
    pub constraints: usize,
    pub kkt_target: f64,
    pub rows: Vec<TableRow>,
    /// Load steps of the problem; the last is compared.
    pub steps: TableSteps,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_limit_s: Option<f64>,
}

/// The load steps: how many, which one is compared (1-based), and whether
/// every variant followed the load path to it (friction) or solved it from
/// a cold start.
#[derive(Debug, Clone, Serialize)]
pub struct TableSteps {
    pub count: usize,
    pub compared: usize,
    pub path: bool,
}

/// One variant: its error, or its result ([`SolvedRow`]).
#[derive(Debug, Clone, Serialize)]
pub struct TableRow {
    pub method: String,
    pub preconditioner: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub converged: bool,
    pub certified: bool,
    pub agrees: bool,
    #[serde(flatten)]
    pub solved: Option<SolvedRow>,
}

/// A variant that returned a result (converged or not).
#[derive(Debug, Clone, Serialize)]
pub struct SolvedRow {
    pub status: String,
    pub iterations: usize,
    pub inner_iterations: usize,
    pub time_s: f64,
    pub phases: BTreeMap<String, f64>,
    pub kkt: Kkt,
    pub kkt_max: f64,
    pub energy: f64,
    pub active: usize,
    pub probes: BTreeMap<String, Vec<f64>>,
    pub rel_diff: f64,
    pub rel_diff_lambda: f64,
    /// With friction: ‖λ_t − λ_t,ref‖/‖λ_t,ref‖.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rel_diff_lambda_t: Option<f64>,
    pub agree_tol: f64,
    pub agree_tol_lambda: f64,
    /// A certified row that does not agree: the first check it fails.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disagrees: Option<Disagreement>,
    pub notes: Vec<String>,
    /// The driver's note when another method solved the row (its
    /// numbers are that method's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback: Option<String>,
}

/// Why a certified row does not agree with the reference ([`table`]): the
/// first check it fails, in the order x, λ, λ_t, active set; in the JSON
/// `{"on": "x" | "lambda" | "lambda_t", "diff", "tol"}` or
/// `{"on": "active_set", "rows"}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "on")]
pub enum Disagreement {
    /// ‖x − x_ref‖/‖x_ref‖ above its tolerance.
    X { diff: f64, tol: f64 },
    /// ‖λ − λ_ref‖/‖λ_ref‖ above its tolerance.
    Lambda { diff: f64, tol: f64 },
    /// ‖λ_t − λ_t,ref‖/‖λ_t,ref‖ above its tolerance (friction).
    LambdaT { diff: f64, tol: f64 },
    /// The active sets differ in this many rows.
    ActiveSet { rows: usize },
}

impl std::fmt::Display for Disagreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Disagreement::X { diff, tol } => write!(f, "x {diff:.2e} > {tol:.0e}"),
            Disagreement::Lambda { diff, tol } => write!(f, "λ {diff:.2e} > {tol:.0e}"),
            Disagreement::LambdaT { diff, tol } => write!(f, "λ_t {diff:.2e} > {tol:.0e}"),
            Disagreement::ActiveSet { rows } => write!(f, "active set: {rows} rows differ"),
        }
    }
}

impl Table {
    /// The JSON text, keys in alphabetical order at every level.
    pub fn to_json(&self) -> String {
        serde_json::to_value(self)
            .and_then(|v| serde_json::to_string_pretty(&v))
            .unwrap_or_default()
    }

    /// The CSV text: one line per row, probes as `name=u1:u2` pairs.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("method,preconditioner,converged,certified,iterations,inner_iterations,time_s,kkt_max,energy,rel_diff,rel_diff_lambda,agrees,probes,error\n");
        for r in &self.rows {
            let o = r.solved.as_ref();
            let probes = o
                .map(|o| {
                    o.probes
                        .iter()
                        .map(|(k, v)| {
                            let u: Vec<String> = v.iter().map(js).collect();
                            format!("{k}={}", u.join(":"))
                        })
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_default();
            s += &format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"\n",
                r.method,
                r.preconditioner,
                r.converged,
                r.certified,
                js(&o.map(|o| o.iterations)),
                js(&o.map(|o| o.inner_iterations)),
                js(&o.map(|o| o.time_s)),
                js(&o.map(|o| o.kkt_max)),
                js(&o.map(|o| o.energy)),
                js(&o.map(|o| o.rel_diff)),
                js(&o.map(|o| o.rel_diff_lambda)),
                r.agrees,
                probes,
                r.error.as_deref().unwrap_or("").replace('"', "'")
            );
        }
        s
    }
}

/// A value as in the JSON (`null` for a missing or non-finite number).
fn js<T: Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_else(|_| "null".into())
}
