//! Semismooth Newton / primal–dual active set method (Hintermüller, Ito &
//! Kunisch 2002, SIAM J. Optim. 13; docs/methods.md §7): Newton's method on
//! λ − max(0, λ + c(Ax − g)) = 0. One step (`Executor` step) solves the KKT
//! system of the working set J (`Cx + A_Jᵀλ_J = d, A_J x = g_J, λ_{J^c} = 0`),
//! predicts `J ← {i : λᵢ + c(Ax − g)ᵢ > τ}` and stops when J did not change.
//! Start: the working-set warm start if given (the last load step's
//! active rows, `Context::active0`; not on the iterative path), else the
//! glued set {gᵢ = 0};
//! c = mean diag C (a stiffness), and τ = tol·(‖λ‖∞ + c·max(‖x‖∞, ‖g‖∞)).
//!
//! The KKT solve takes, per step and from counts only (`path`), the
//! augmented factor C + A_JᵀΡA_J (`augmented`, Woodbury updates in
//! `lowrank`) or the Schur complement on one factor of C (`schur`, with
//! the FETI coarse problem for floating bodies). A settled J is certified by
//! the KKT residual and refined (at most `REFINE_MAX` steps, then once on
//! the Schur path); at most max(`GROW_MIN`, |J|) rows enter per step; a
//! repeated J switches to single changes (anti-cycling). When the unknowns
//! A touches are few (`small_border`), C is factored with them last and the
//! trailing block gives all of A K⁻¹Aᵀ at once (docs/methods.md §7): J is
//! then found by dual-space steps with no sparse solve (`dense_start`; from
//! every row when the glued set does not hold the floating bodies), and the
//! Newton loop only confirms it. Counts: `iterations` = KKT solves (the
//! dual-space steps are not counted), `inner_iterations` = sparse solves.
//! `ssn_path = "iterative"` runs the same loop in `iterative` with no factor
//! of C's size: multigrid-preconditioned CG (docs/methods.md §7.2); on a
//! solid model it starts from the contact problem solved on a coarse level
//! of its multigrid (`coarse_start`).

mod augmented;
mod coarse_start;
mod friction;
mod iterative;
mod lowrank;
mod path;
mod schur;
mod sets;
#[cfg(test)]
mod tests;
mod yardstick;

use crate::linalg::augmented::AugPattern;
use crate::linalg::cholesky::{Cholesky, Workspace};
use crate::linalg::dense::SpdFactor;
/// The checked basis of ker C (re-exported for `qp::primal::cgc`).
pub(crate) use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::rotation::RowBorder;
use crate::linalg::sparse::{dot, norm_inf};
use crate::qp::executor::{Iterative, Step};
use crate::qp::method::{Capabilities, Factor, FallbackCause, MethodId};
use crate::qp::settings::SsnPath;
use crate::qp::Failure;
use crate::qp::{Context, IterRecord, Method, Output, QpError, QpProblem, Status};
/// The message start of a frictional ssn stopped for cycling working sets.
use path::{Costs, Path};
use std::collections::{HashMap, HashSet};
use std::rc::Rc;
use std::time::Instant;
pub use yardstick::{yardstick, Yardstick};

/// ρ = RHO_FACTOR · max diag C in K_J = C + ρA_JᵀA_J (one ρ_j = ρ per row;
/// the code keeps a weight per row, Ρ = diag(ρ_j)).
pub(crate) const RHO_FACTOR: f64 = 1e2;
/// Right-hand sides per multi-column solve when columns of H are computed.
const BLOCK: usize = 32;
/// Growth limit of J per step: at most max(GROW_MIN, |J|) rows enter.
const GROW_MIN: usize = BLOCK;
/// Refinement steps of the final KKT solve (module doc).
const REFINE_MAX: usize = 3;
/// A border of at most BORDER_RATIO·√n unknowns is eliminated last ([`small_border`]).
pub(crate) const BORDER_RATIO: f64 = 12.0;
/// And at most this many (the dense trailing block: 8·BORDER_MAX² bytes,
/// 2 GiB). 10 000 sent the three-body model at 5 M nodes (12 296 border
/// unknowns) to the path of C + AᵀA: 7 Newton steps and 3 refactors (with
/// AMD killed at 22.6 GiB; with nested dissection 316 s of solve); bordered,
/// 1 step: 109 s with AMD (BENCHMARKS.md, Notes).
const BORDER_MAX: usize = 16384;
/// Dual-space steps at most in [`Ssn::dense_start`].
use sets::{
    candidates, free_modes, hold_free_modes, limit_changes, nested_set, next_set, stiffness_scale,
};

const DENSE_STEPS_MAX: usize = 100;
/// Semismooth Newton / primal–dual active set (docs/methods.md §7).
pub struct SsnMethod;

impl Method for SsnMethod {
    fn id(&self) -> MethodId {
        MethodId::Ssn
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            friction: crate::qp::method::FrictionSupport::Planes,
            factor: Factor::BySettings,
            warm_start: true,
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "semismooth Newton / primal–dual active set, Schur complement with one Cholesky factor (§7)"
    }
    /// A refused unbounded claim is solved by asm (ssn is every other
    /// method's fallback); frictional working sets that cycle by mprgp,
    /// which solves the same Tresca problem on the dual (docs/methods.md
    /// §8.2, §9.2).
    fn fallback(&self, cause: FallbackCause) -> Option<MethodId> {
        match cause {
            FallbackCause::RefusedClaim => Some(MethodId::Asm),
            FallbackCause::Cycling => Some(MethodId::Mprgp),
        }
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        if qp.friction.is_some() {
            return friction::solve(qp, ctx);
        }
        let path = ctx.settings.ssn.path;
        if path == SsnPath::Iterative || iterative_by_default(qp, path) {
            return iterative::solve(qp, ctx);
        }
        solve(qp, ctx)
    }
}

/// Unknowns from which `ssn_path = "auto"` takes the iterative path on a
/// solid (3D) model (docs/methods.md §7.2, "The default path in 3D"):
/// with rough steps Hertz at 98 k unknowns ties (8.8 s either way, 0.58
/// against 1.54 GB), at 163 k the iterative path is 1.7× faster.
pub const ITERATIVE_3D_FROM: usize = 100_000;

/// `path` is `"auto"` and the model is solid (its near-null space holds the
/// six rigid motions of 3D elasticity) with at least [`ITERATIVE_3D_FROM`]
/// unknowns: the multigrid solve beats the sparse factor from there on,
/// with or without friction (docs/methods.md §7.2, §12.3). Plane models
/// (three motions) never take it.
pub(crate) fn iterative_by_default(qp: &QpProblem, path: SsnPath) -> bool {
    path == SsnPath::Auto && qp.has_solid_modes() && qp.n() >= ITERATIVE_3D_FROM
}

/// Solve `qp` by the semismooth Newton (primal–dual active set) method.
pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let path = match ctx.settings.ssn.path {
        SsnPath::Auto => Path::Auto,
        SsnPath::Augmented => Path::Augmented,
        SsnPath::Refactor => Path::Refactor,
        SsnPath::Schur => Path::Schur,
        SsnPath::Iterative => return iterative::solve(qp, ctx),
    };
    solve_traced(qp, ctx, path).map(|(r, _)| r)
}

/// [`solve`] with the linear-algebra path fixed (tests).
#[cfg(test)]
pub(crate) fn solve_with(
    qp: &QpProblem,
    opts: &crate::qp::SolveOptions,
    path: Path,
) -> Result<Output, QpError> {
    let ws = Workspace::new();
    solve_traced(qp, &mut Context::new(opts, &ws), path).map(|(r, _)| r)
}

/// [`solve`] with the path fixed, also returning the path of every KKT
/// solve (true = augmented), refinements included.
pub(crate) fn solve_traced(
    qp: &QpProblem,
    ctx: &mut Context,
    path: Path,
) -> Result<(Output, Vec<bool>), QpError> {
    // A small border: the Schur path on a bordered factor of C, which gives
    // every column of A K⁻¹Aᵀ at once (no cost model needed). What that
    // path derives from C, A and ker C alone is kept in the workspace for
    // the next solve of the same matrices (a load step, [`Kept`]).
    let keeps = matches!(path, Path::Auto | Path::Schur);
    let kernel_key = crate::linalg::cholesky::matrix_key(&[], &qp.kernel);
    let kept = keeps
        .then(|| ctx.ws.kept::<Kept>(KEPT_TAG))
        .flatten()
        .filter(|k| k.matches(qp, kernel_key));
    let border = match &kept {
        Some(_) => None,
        None if keeps => small_border(qp),
        None => None,
    };
    let bordered = kept
        .as_ref()
        .map_or(border.is_some(), |k| k.dense.is_some());
    let augmented = path != Path::Schur && !bordered;
    let t0 = Instant::now();
    let r = match kept.as_ref().and_then(|k| k.dense.as_ref()) {
        Some(kd) => kd.r.clone(),
        None => orthonormal_kernel(&qp.c, &qp.kernel)?,
    };
    let mut st = Ssn::new(qp, r, ctx.settings.tol, augmented, ctx.ws);
    st.target = ctx.settings.kkt_target;
    st.border = border;
    st.auto = path == Path::Auto;
    st.lowrank = path != Path::Refactor;
    // A working-set warm start (the last load step's active rows) replaces
    // the glued start: the dense start then confirms it in one step.
    if let Some(a) = ctx.active0.filter(|a| a.len() == qp.m()) {
        st.in_j = a.to_vec();
    } else if let (Some(lam), Some(x0)) = (ctx.nested_lambda, ctx.x0) {
        // A nested start (docs/methods.md §7.2): the set the rule predicts
        // from the interpolated pair.
        st.in_j = nested_set(qp, x0, lam, st.cpar);
    }
    if let Some(kd) = kept.as_ref().and_then(|k| k.dense.as_ref()) {
        log::debug!("ssn: the bordered factor and A K⁻¹Aᵀ of the last solve reused");
        st.fac = Some(kd.fac.clone());
        st.h = kd.h.clone();
        st.sj_cache = kd.sj_cache.clone();
    }
    if st.aug.is_some() {
        st.costs = Costs::new(qp, st.aug.as_ref(), ctx.ws)?;
    }
    if !augmented {
        st.ensure_dense()?;
    }
    if bordered {
        st.dense_start();
    }
    let mut exec = ctx.executor("ssn");
    let (status, iters) = exec.run(&mut st);
    if let Some(e) = st.error.take() {
        return Err(e);
    }
    if keeps && kept.is_none() {
        st.keep(kernel_key);
    }
    let t_all = t0.elapsed().as_secs_f64();
    let t_factor = st.t_factor;
    let trace = std::mem::take(&mut st.trace);
    Ok((
        st.into_result(
            status,
            iters,
            exec.log,
            vec![
                ("factor".into(), t_factor),
                ("iterate".into(), t_all - t_factor),
            ],
        ),
        trace,
    ))
}

/// The border of a bordered factor (docs/methods.md §7): the unknowns A
/// touches, a row whose unknowns no other row touches rotated onto one
/// ([`RowBorder`]), if few enough that eliminating them last costs little,
/// i.e. at most [`BORDER_RATIO`]·√n of them (a 2D mesh's largest separators
/// have O(√n) unknowns) and at most [`BORDER_MAX`] (a dense |border|² block).
/// Counts and values only, so the choice is the same on every run.
pub(crate) fn small_border(qp: &QpProblem) -> Option<RowBorder> {
    if qp.m() == 0 {
        return None;
    }
    let rb = RowBorder::new(&qp.c, &qp.kernel, &qp.a);
    let nb = rb.len() as f64;
    log::debug!(
        "ssn: border of {} unknowns ({} rows rotated, one unknown per coupled part)",
        rb.len(),
        rb.rotated()
    );
    (nb <= BORDER_RATIO * (qp.n() as f64).sqrt() && rb.len() <= BORDER_MAX).then_some(rb)
}

/// What ssn derives from C, A and ker C alone, kept in the workspace
/// ([`Workspace::keep`]) under the key of those matrices: a load step
/// changes only d, g and the prescribed values (docs/methods.md §8.5), so
/// its solve is the forward half of K⁻¹d, the dual-space steps on the
/// kept H (with the factors of S_J of the sets the last solves visited),
/// one backward pass and the certificate. Every kept value is the one a
/// fresh solve computes (same inputs, same bits), so a step's answer does
/// not depend on the steps before it.
pub(crate) struct Kept {
    /// C and A (clones share their arrays, [`crate::linalg::sparse::Shared`]).
    c: crate::linalg::sparse::Csr,
    a: crate::linalg::sparse::Csr,
    /// [`crate::linalg::cholesky::matrix_key`] of ker C's basis.
    kernel_key: u64,
    /// None: the border was too large ([`small_border`]); nothing else kept.
    dense: Option<KeptDense>,
}

/// The workspace slot of [`Kept`].
const KEPT_TAG: u64 = 0x7373_6e5f_6b65_7074;

impl Kept {
    /// Whether `qp` has the matrices the data were derived from: the same
    /// arrays (a load step's model shares them), else equal values.
    fn matches(&self, qp: &QpProblem, kernel_key: u64) -> bool {
        self.kernel_key == kernel_key && self.c.same_as(&qp.c) && self.a.same_as(&qp.a)
    }
}

/// The bordered path's data ([`Kept`]).
struct KeptDense {
    /// The orthonormal basis of ker C.
    r: Vec<Vec<f64>>,
    /// The bordered factor of C (+ springs).
    fac: Cholesky,
    /// Every column of H = A K⁻¹Aᵀ.
    h: Rc<Vec<Option<Vec<f64>>>>,
    /// The factors of S_J made by the solves so far.
    sj_cache: Rc<std::cell::RefCell<schur::SjCache>>,
}

/// The largest KKT residual of (x, λ) as the driver computes it
/// ([`crate::qp::kkt::residuals`], docs/methods.md §8.4); +∞ if anything is not finite.
pub(crate) fn certificate(qp: &QpProblem, x: &[f64], lam: &[f64]) -> f64 {
    // ssn refines until its answer passes the test the driver applies.
    crate::qp::kkt::residuals(qp, x, lam).judged()
}

/// The state of the iteration.
struct Ssn<'a> {
    qp: &'a QpProblem,
    /// Where factorizations reuse the symbolic analysis of the same pattern.
    ws: &'a Workspace,
    /// Factor of C (+ springs) for the Schur-complement path, made on demand.
    fac: Option<Cholesky>,
    /// The unknowns that factor eliminates last, when it is bordered.
    border: Option<RowBorder>,
    /// The augmented path: pattern of C + AᵀA, ρ_j per row, the factor of K_J.
    aug: Option<AugPattern>,
    rho: Vec<f64>,
    kfac: Option<Cholesky>,
    /// The working set J' that `kfac` was built for.
    kfac_set: Option<Vec<bool>>,
    /// Columns K'⁻¹a_j of the current K' (low-rank updates); looked up by
    /// row only, never iterated (the order of a HashMap is not deterministic).
    zcache: HashMap<usize, Rc<Vec<f64>>>,
    /// Time spent in sparse factorizations (reported, never used to decide).
    t_factor: f64,
    /// Counted costs of the two paths (module doc).
    costs: Costs,
    /// KKT solves done (Newton steps).
    steps_done: usize,
    /// Choose the path per step (else: augmented whenever it is available).
    auto: bool,
    /// Allow low-rank updates of K'.
    lowrank: bool,
    error: Option<QpError>,
    /// Orthonormal basis of ker C (k vectors of length n).
    r: Vec<Vec<f64>>,
    /// (A R)[i][l] = (A r_l)_i, m×k.
    ar: Vec<Vec<f64>>,
    /// e = Rᵀd.
    e: Vec<f64>,
    /// A K⁻¹d, every row.
    ax0: Vec<f64>,
    /// Whether `ax0` (and `fwd_d`) are computed (the factor may be kept).
    ax0_done: bool,
    /// The forward half of K⁻¹d on a bordered factor.
    fwd_d: Option<crate::linalg::cholesky::Forward>,
    /// Cached columns hⱼ = A K⁻¹aⱼ (length m) of the dual Hessian (shared
    /// with [`Kept`] on the bordered path).
    h: Rc<Vec<Option<Vec<f64>>>>,
    /// The last dense Schur solve (`schur::DenseMemo`).
    dense_memo: std::cell::RefCell<Option<schur::DenseMemo>>,
    /// The factor of S over every row, once a working set held them all
    /// (`schur::SjSolver`).
    s_full: std::cell::RefCell<Option<Rc<SpdFactor>>>,
    /// The solvers of S_J made so far (shared with [`Kept`]).
    sj_cache: Rc<std::cell::RefCell<schur::SjCache>>,
    tol: f64,
    /// The certificate's target (`Settings::kkt_target`).
    target: f64,
    /// The stiffness scale c.
    cpar: f64,
    in_j: Vec<bool>,
    /// The last working set whose KKT system was solved.
    last_ok: Option<Vec<bool>>,
    history: HashSet<Vec<bool>>,
    single: bool,
    x: Vec<f64>,
    lam: Vec<f64>,
    solves: usize,
    /// Path of every KKT solve (true = augmented), refinements included.
    trace: Vec<bool>,
    /// Whether the last solve of the current J used the augmented path.
    last_aug: bool,
}

impl<'a> Ssn<'a> {
    fn new(
        qp: &'a QpProblem,
        r: Vec<Vec<f64>>,
        tol: f64,
        augmented: bool,
        ws: &'a Workspace,
    ) -> Ssn<'a> {
        let m = qp.m();
        let ar: Vec<Vec<f64>> = (0..m)
            .map(|i| r.iter().map(|rl| qp.a.row_dot(i, rl)).collect())
            .collect();
        let e: Vec<f64> = r.iter().map(|rl| dot(rl, &qp.d)).collect();
        let diag = qp.c.diag();
        let cpar = stiffness_scale(&diag);
        let aug = (augmented && m > 0).then(|| {
            let t = Instant::now();
            let p = AugPattern::new(&qp.c, &qp.a);
            log::debug!(
                "ssn: pattern of C + AᵀA in {:.3} s",
                t.elapsed().as_secs_f64()
            );
            p
        });
        Ssn {
            qp,
            ws,
            fac: None,
            border: None,
            rho: if aug.is_some() {
                let cmax = norm_inf(&diag);
                vec![RHO_FACTOR * if cmax > 0.0 { cmax } else { 1.0 }; m]
            } else {
                vec![]
            },
            aug,
            kfac: None,
            kfac_set: None,
            zcache: HashMap::new(),
            t_factor: 0.0,
            // Until counted (Schur-only runs never need it): equal costs.
            costs: Costs {
                fac_c: 1.0,
                solve_c: 1.0,
                fac_k: 1.0,
                solve_k: 1.0,
            },
            steps_done: 0,
            auto: true,
            lowrank: true,
            error: None,
            r,
            ar,
            e,
            x: vec![0.0; qp.n()],
            ax0: vec![],
            ax0_done: false,
            fwd_d: None,
            h: Rc::new(vec![None; m]),
            dense_memo: Default::default(),
            s_full: Default::default(),
            sj_cache: Default::default(),
            tol,
            target: crate::qp::settings::DEFAULT_KKT_TARGET,
            cpar,
            in_j: qp.g.iter().map(|&g| g <= 0.0).collect(),
            last_ok: None,
            history: HashSet::new(),
            single: false,
            lam: vec![0.0; m],
            solves: 0,
            trace: vec![],
            last_aug: false,
        }
    }

    /// Factor C (+ springs) and A K⁻¹d for the Schur-complement path.
    fn ensure_dense(&mut self) -> Result<(), QpError> {
        if self.fac.is_none() {
            let t = Instant::now();
            let (c, kernel) = (&self.qp.c, &self.qp.kernel);
            let fac = match &self.border {
                Some(b) => self.ws.cholesky_rows(c, kernel, b)?,
                None => self.ws.cholesky(c, kernel)?,
            };
            // A bordered factor gives all of A K⁻¹Aᵀ at dense cost.
            let tb = Instant::now();
            let h = fac.border_inverse(&self.qp.a);
            if h.is_some() {
                log::debug!(
                    "ssn: H = A K⁻¹Aᵀ from the border in {:.3} s",
                    tb.elapsed().as_secs_f64()
                );
            }
            if let Some(h) = h {
                for (j, hj) in Rc::make_mut(&mut self.h).iter_mut().enumerate() {
                    *hj = Some(h.col(j).iter().copied().collect());
                }
            }
            self.t_factor += t.elapsed().as_secs_f64();
            self.fac = Some(fac);
        }
        if !self.ax0_done {
            self.ax0_done = true;
            let fac = self.fac.as_ref().expect("factored above");
            // On a bordered factor A K⁻¹d needs only the forward half of the
            // solve; the KKT answer finishes it (`Cholesky::forward`).
            let half = fac
                .forward(&self.qp.d)
                .and_then(|f| fac.border_product(&f, &self.qp.a).map(|ax| (f, ax)));
            match half {
                Some((f, ax)) => {
                    self.ax0 = ax;
                    self.fwd_d = Some(f);
                }
                None => {
                    let x0 = fac.solve(&self.qp.d);
                    self.solves += 1;
                    self.ax0 = (0..self.qp.m())
                        .map(|i| self.qp.a.row_dot(i, &x0))
                        .collect();
                }
            }
        }
        Ok(())
    }

    /// With every column of H = A K⁻¹Aᵀ known (a bordered factor): primal–
    /// dual active-set steps in the dual space alone — λ_J and α from
    /// [`Ssn::schur_dense`], Ax = A K⁻¹d − H_{·J}λ_J + ARα from the columns —
    /// with no sparse solve. The working set they settle on starts the
    /// Newton loop, whose own steps (with x) decide and certify; τ here uses
    /// ‖Ax‖∞ for the ‖x‖∞ it cannot see.
    fn dense_start(&mut self) {
        let qp = self.qp;
        let m = qp.m();
        if m == 0 || self.h.iter().any(Option::is_none) {
            return;
        }
        let k = self.r.len();
        let t0 = Instant::now();
        let ax0 = self.ax0.clone();
        let mut in_j = self.in_j.clone();
        let mut seen: HashSet<Vec<bool>> = HashSet::new();
        let mut steps = 0;
        while steps < DENSE_STEPS_MAX && seen.insert(in_j.clone()) {
            steps += 1;
            let jset: Vec<usize> = (0..m).filter(|&i| in_j[i]).collect();
            let ax0j: Vec<f64> = jset.iter().map(|&j| ax0[j]).collect();
            let Some((w, alpha)) = self.schur_dense(&jset, &ax0j, &self.e, &qp.g, false) else {
                // J does not hold the floating bodies (the glued start of
                // rollers.toml: one row under each roller, which leaves its
                // rotation free): restart from every row, which does when
                // the problem is bounded, as the Newton loop would.
                if in_j.iter().all(|b| *b) {
                    break;
                }
                in_j = vec![true; m];
                continue;
            };
            let mut lam = vec![0.0; m];
            for (t, &j) in jset.iter().enumerate() {
                lam[j] = w[t];
            }
            let ax: Vec<f64> = (0..m)
                .map(|i| {
                    let hi = self.h[i].as_ref().expect("every column known");
                    let coupled: f64 = jset.iter().zip(&w).map(|(&j, wj)| hi[j] * wj).sum();
                    let rigid: f64 = (0..k).map(|l| self.ar[i][l] * alpha[l]).sum();
                    ax0[i] - coupled + rigid
                })
                .collect();
            let next = next_set(&in_j, &lam, &ax, &qp.g, self.tol);
            if next == in_j {
                break;
            }
            in_j = next;
        }
        log::debug!(
            "ssn: dense start: {steps} steps in the dual space, |J| = {}, {:.3} s",
            in_j.iter().filter(|b| **b).count(),
            t0.elapsed().as_secs_f64()
        );
        self.in_j = in_j;
    }

    /// Solve the KKT system on `in_j` (the path by the cost model); None if
    /// it is singular. Returns (λ over all rows, x).
    fn kkt_solve(&mut self, in_j: &[bool]) -> Option<(Vec<f64>, Vec<f64>)> {
        self.steps_done += 1;
        if self.aug.is_some() && !self.prefer_schur(in_j) {
            if let Some(s) = self.kkt_solve_aug(in_j) {
                self.trace.push(true);
                self.last_aug = true;
                return Some(s);
            }
            if self.error.is_some() {
                return None;
            }
        }
        self.kfac = None;
        self.kfac_set = None;
        self.zcache.clear();
        let (d, g) = (&self.qp.d, &self.qp.g);
        let s = self.schur_solve(in_j, d, g);
        if s.is_some() {
            self.trace.push(false);
            self.last_aug = false;
        }
        s
    }

    /// The correction of (x, λ) on J = `in_j` for the residuals
    /// (d − Cx − A_Jᵀλ_J, g_J − A_J x), on the path of the last solve.
    fn correction(&mut self, aug: bool) -> Option<(Vec<f64>, Vec<f64>)> {
        let qp = self.qp;
        let mut r1 = qp.c.mul(&self.x);
        for (ri, di) in r1.iter_mut().zip(&qp.d) {
            *ri = di - *ri;
        }
        let lam_j: Vec<f64> = (0..qp.m())
            .map(|i| if self.in_j[i] { self.lam[i] } else { 0.0 })
            .collect();
        let mut atl = vec![0.0; qp.n()];
        qp.a.mul_t_add(&lam_j, &mut atl);
        for (ri, ai) in r1.iter_mut().zip(&atl) {
            *ri -= ai;
        }
        let r2: Vec<f64> = (0..qp.m())
            .map(|i| {
                if self.in_j[i] {
                    qp.g[i] - qp.a.row_dot(i, &self.x)
                } else {
                    0.0
                }
            })
            .collect();
        let in_j = self.in_j.clone();
        let nj = in_j.iter().filter(|b| **b).count();
        let s = if aug {
            self.aug_solve(&in_j, &r1, &r2, vec![0.0; nj])
        } else {
            self.schur_solve(&in_j, &r1, &r2)
        };
        if s.is_some() {
            self.trace.push(aug);
        }
        s
    }

    /// Measure the certificate of (x, λ) and refine the KKT solve of J until
    /// it meets tol (module doc). Returns the final certificate.
    fn refine(&mut self) -> f64 {
        let qp = self.qp;
        let mut cert = certificate(qp, &self.x, &self.lam);
        let mut fresh_schur = false;
        loop {
            let mut steps = 0;
            while cert > self.tol && steps < REFINE_MAX {
                steps += 1;
                let Some((dl, dx)) = self.correction(self.last_aug) else {
                    break;
                };
                let x: Vec<f64> = self.x.iter().zip(&dx).map(|(a, b)| a + b).collect();
                let lam: Vec<f64> = self.lam.iter().zip(&dl).map(|(a, b)| a + b).collect();
                let c = certificate(qp, &x, &lam);
                log::debug!("ssn: refinement: KKT residual {cert:.2e} → {c:.2e}");
                if c.is_nan() || c >= cert {
                    break;
                }
                let improved = c < 0.5 * cert;
                (self.x, self.lam, cert) = (x, lam, c);
                if !improved {
                    break;
                }
            }
            // Still far from tol on the augmented path: recompute on the
            // Schur path (one factor of C, exact elimination), once.
            if cert <= self.target.min(1e2 * self.tol)
                || !self.last_aug
                || fresh_schur
                || self.error.is_some()
            {
                return cert;
            }
            fresh_schur = true;
            log::debug!(
                "ssn: KKT residual {cert:.2e} on the augmented path; recomputing on the Schur path"
            );
            let in_j = self.in_j.clone();
            let (d, g) = (&qp.d, &qp.g);
            match self.schur_solve(&in_j, d, g) {
                Some((lam, x)) => {
                    self.trace.push(false);
                    self.last_aug = false;
                    let c = certificate(qp, &x, &lam);
                    if c < cert {
                        (self.x, self.lam, cert) = (x, lam, c);
                    }
                }
                None => return cert,
            }
        }
    }

    /// The next working set ([`next_set`]), the complementarity function
    /// F = λ + c(Ax − g) (which orders the rows that change), the
    /// relative residual of the complementarity equation (reported only)
    /// and Ax.
    fn predict(&self) -> (Vec<bool>, Vec<f64>, f64, Vec<f64>) {
        let qp = self.qp;
        let m = qp.m();
        let c = self.cpar;
        let ax: Vec<f64> = (0..m).map(|i| qp.a.row_dot(i, &self.x)).collect();
        let next = next_set(&self.in_j, &self.lam, &ax, &qp.g, self.tol);
        let scale = norm_inf(&self.lam) + c * norm_inf(&self.x).max(norm_inf(&qp.g));
        let scale = if scale > 0.0 { scale } else { 1.0 };
        let fval: Vec<f64> = (0..m)
            .map(|i| self.lam[i] + c * (ax[i] - qp.g[i]))
            .collect();
        let residual = (0..m)
            .map(|i| (self.lam[i] - fval[i].max(0.0)).abs())
            .fold(0.0f64, f64::max)
            / scale;
        (next, fval, residual, ax)
    }

    /// Keep in the workspace what this solve derived from the matrices
    /// ([`Kept`]; `kernel_key` that of ker C's basis).
    fn keep(&self, kernel_key: u64) {
        let dense = match (&self.border, &self.fac) {
            (Some(_), Some(fac)) if self.h.iter().all(Option::is_some) => Some(KeptDense {
                r: self.r.clone(),
                fac: fac.clone(),
                h: self.h.clone(),
                sj_cache: self.sj_cache.clone(),
            }),
            (Some(_), _) => return,
            (None, _) => None,
        };
        let kept = Kept {
            c: self.qp.c.clone(),
            a: self.qp.a.clone(),
            kernel_key,
            dense,
        };
        self.ws.keep(KEPT_TAG, Rc::new(kept));
    }

    fn n_active(&self) -> usize {
        self.in_j.iter().filter(|b| **b).count()
    }

    fn record(&self, residual: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual,
            active: self.n_active(),
            inner: self.solves,
        }
    }

    fn into_result(
        self,
        status: Status,
        iterations: usize,
        log: Vec<IterRecord>,
        timings: Vec<(String, f64)>,
    ) -> Output {
        Output {
            x: self.x,
            lambda: self.lam,
            lambda_t: vec![],
            active: self.in_j,
            status,
            iterations,
            inner_iterations: self.solves,
            log,
            timings,
        }
    }
}

impl Iterative for Ssn<'_> {
    fn step(&mut self) -> Step {
        let mut solved = None;
        for cand in candidates(&self.in_j, self.last_ok.as_deref()) {
            if let Some(s) = self.kkt_solve(&cand) {
                solved = Some((cand, s));
                break;
            }
            if let Some(e) = &self.error {
                // a factor refused for memory (or C not factored): no
                // other candidate can do better
                return Step::Done(
                    Status::Failed(Failure::Breakdown(e.to_string())),
                    self.record(f64::NAN),
                );
            }
        }
        let Some((jused, (lam, x))) = solved else {
            return Step::Done(
                Status::Failed(Failure::Breakdown(
                    "ssn: the KKT system is singular even with every contact row active: a rigid motion of a \
                     floating body is not restrained by the contact rows (A·R rank deficient) or the contact \
                     rows are linearly dependent"
                        .into(),
                )),
                self.record(f64::NAN),
            );
        };
        self.in_j = jused.clone();
        self.last_ok = Some(jused.clone());
        self.history.insert(jused.clone());
        self.lam = lam;
        self.x = x;
        let (mut new_j, mut fval, mut residual, mut ax) = self.predict();
        if new_j == self.in_j {
            // J has settled: certify (x, λ), refining the solve if needed.
            let cert = self.refine();
            if cert.is_nan() || cert > self.target.max(self.tol) {
                return Step::Done(
                    Status::Failed(Failure::Uncertified {
                        residual: cert,
                        target: self.target,
                    }),
                    self.record(residual),
                );
            }
            (new_j, fval, residual, ax) = self.predict();
            if new_j == self.in_j {
                return Step::Done(Status::Converged, self.record(residual));
            }
            log::debug!("ssn: the refined solution moves J; continuing");
        }
        let new_j = limit_changes(&self.in_j, new_j, &fval, &self.history, &mut self.single, 1);
        let new_j = hold_free_modes(new_j, &self.in_j, &self.ar, &self.lam, &ax, &self.qp.g);
        log::debug!(
            "ssn: step {}: |J| = {}, next |J| = {} ({} enter, {} leave), residual {:.2e}",
            self.history.len(),
            self.in_j.iter().filter(|&&b| b).count(),
            new_j.iter().filter(|&&b| b).count(),
            new_j
                .iter()
                .zip(&self.in_j)
                .filter(|(n, o)| **n && !**o)
                .count(),
            new_j
                .iter()
                .zip(&self.in_j)
                .filter(|(n, o)| !**n && **o)
                .count(),
            residual
        );
        self.in_j = new_j;
        Step::Continue(self.record(residual))
    }
}
