//! `ssn` on discs and cones (docs/methods.md §12.3): the Tresca problem of
//! a plane frame (two tangential rows per contact row, ‖λ_tᵢ‖ ≤ sᵢ) by
//! working sets, and Coulomb by the outer loop shared with 2D
//! ([`crate::qp::coulomb`]).
//!
//! The prediction is Hüeber, Stadler & Wohlmuth's (SISC 30, 2008) in 3D,
//! with ξᵢ = λ_tᵢ + c_tᵢ vᵢ ∈ ℝ² (v = T x − t0):
//! * N = {i : λ_nᵢ + cᵢ(Ax − g)ᵢ > 0} as in 2D;
//! * stick where ‖ξᵢ‖ ≤ sᵢ: both tangential rows are constraints, T_i x = t0_i;
//! * slip elsewhere (sᵢ > 0), along eᵢ = ξᵢ/‖ξᵢ‖: the force along eᵢ is
//!   known, sᵢ, and the slip is held to eᵢ's line, e⊥ᵢ·(T_i x − t0_i) = 0
//!   with e⊥ = (−e₂, e₁) and its own multiplier λ⊥ᵢ, so that
//!   λ_tᵢ = sᵢeᵢ + λ⊥ᵢe⊥ᵢ;
//! * free where sᵢ = 0 (no force, no constraint).
//!
//! Each step is one equality-constrained solve, on the sparse path of 2D
//! (K = C + ρBᵀB and augmented Lagrangian sweeps, one factor a step on a
//! pattern fixed for the whole solve). At the answer of a step, λ⊥ᵢ is
//! the force the slip's direction still lacks: the next prediction turns eᵢ
//! by atan(λ⊥ᵢ/(sᵢ + c_tᵢ αᵢ)), and the sets are settled when they repeat
//! and the residual of the disc law (λ⊥ = 0 on slipping rows, weighted by
//! the slip as in the certificate) is at `tol`. A direction is a real
//! number, so settling is judged on the residual, not on sets seen before;
//! a budget of steps without a better residual stops a cycle, as in 2D.
//! Rigid motions a working set leaves free are tested for unboundedness
//! with the disc's dissipation Σ sᵢ‖(T z)ᵢ‖ and otherwise regularised for
//! the step, as in 2D (§9.3).

use super::dual::Dual;
use super::{cycle_budget, row_stiffness, AL_MAX, AL_STALL, CT_FACTOR, RHO};
use crate::linalg::sparse::{norm_inf, Csr};
use crate::qp::coulomb;
use crate::qp::executor::{Iterative, Step};
use crate::qp::settings::SsnPath;
use crate::qp::{
    tangential_norm, Context, Failure, Friction, IterRecord, Output, QpError, QpProblem, Status,
};
use dual_space::combine;
use plane_loop::PlaneTresca;

/// Steps without a better residual after which the direct Coulomb
/// iteration ([`PlaneTresca::coulomb`]) gives way to the shared loop.
const DIRECT_STALL: usize = 8;

/// Steps in a row that repeat their sets without halving the residual
/// after which a solve ends at its rounding floor (docs/methods.md §12.3).
const FLOOR_STEPS: usize = 3;

/// A residual above this is no rounding floor: the default certificate's
/// target. Newton's steps on the slip directions can gain only ×0.7 a
/// step (a Tresca problem started from the coarse kinds: 3.4·10⁻² →
/// 3.3·10⁻³ in four steps); ended there as at a floor, the answer was
/// not certified (friction residual 2·10⁻³).
const FLOOR_MAX: f64 = 1e-6;

/// Newton steps a solve started from the coarse kinds is given to reach
/// its tolerance before the method's own start takes over (a start, as
/// the glued start and the direct iteration are): a row the coarse levels
/// class as slipping where the answer has it on the disc's rim slips by
/// ever less and Newton's steps on its direction gain only ×0.7–0.9 a step
/// (a soft cube sheared under Tresca: 83 steps from the coarse kinds, 10
/// from the method's own start).
const COARSE_STEPS: usize = 12;

/// How a contact row's tangential pair is held in a working set.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Disc {
    /// T_i x = t0_i: both rows constraints.
    Stick,
    /// The force sᵢe along the unit e (in the row's frame); across e, the
    /// Newton step's compliance κ: the slip across is κ times the force
    /// across (κ = 0: held to e's line).
    Slip([f64; 2], f64),
    /// No force, no constraint (sᵢ = 0, or an open row of the glued start).
    Free,
}

impl Disc {
    fn kind(self) -> u8 {
        match self {
            Disc::Stick => 0,
            Disc::Slip(..) => 1,
            Disc::Free => 2,
        }
    }
}

/// One row of B: its coefficients (sorted columns) and right-hand side.
struct BRow {
    cols: Vec<usize>,
    vals: Vec<f64>,
    rhs: f64,
    rho: f64,
    /// A compliant row (a slipping row's force across its direction): a
    /// spring of this stiffness 1/κ in K, no multiplier.
    spring: Option<f64>,
    /// What its multiplier is: the normal force of row i, a tangential
    /// component k of row i, or the λ⊥ of a slipping row i.
    of: Of,
}

impl BRow {
    /// The slip direction of the contact row this normal row belongs to,
    /// if that row slips.
    fn of_slip(&self, tang: &[Disc]) -> Option<[f64; 2]> {
        match (self.of, self.spring) {
            (Of::Normal(i), None) => match tang[i] {
                Disc::Slip(e, _) => Some(e),
                _ => None,
            },
            _ => None,
        }
    }
}

#[derive(Clone, Copy)]
enum Of {
    Normal(usize),
    Tangential(usize, usize),
    Across(usize),
}

/// Solve the frictional `qp` of a plane frame (`fr.frame` = Plane).
pub(super) fn solve(qp: &QpProblem, fr: &Friction, ctx: &mut Context) -> Result<Output, QpError> {
    if fr.t.nrows != 2 * qp.m() || fr.t0.len() != 2 * qp.m() {
        return Err(QpError::BadParameter(format!(
            "ssn: a plane frame needs 2 tangential rows per contact row: T has {} rows and t0 {} for {} rows",
            fr.t.nrows,
            fr.t0.len(),
            qp.m()
        )));
    }
    let r = crate::linalg::kernel::orthonormal_kernel(&qp.c, &qp.kernel)?;
    let path = ctx.settings.ssn.path;
    // `auto` takes the multigrid on a solid model of ITERATIVE_3D_FROM
    // unknowns or more, as without friction (docs/methods.md §12.3).
    let by_size = super::super::iterative_by_default(qp, path);
    if path == SsnPath::Iterative || by_size {
        match run(qp, fr, r.clone(), None, ctx, true) {
            Err(QpError::Unsupported(why)) if by_size => {
                log::info!(
                    "ssn: discs: the multigrid path gave up ({why}); the direct paths take over"
                );
            }
            out => return out,
        }
    }
    let dual = match path {
        SsnPath::Auto | SsnPath::Schur => Dual::new(qp, fr, &r, ctx.ws)?,
        _ => None,
    };
    run(qp, fr, r, dual, ctx, false)
}

/// One run of the fixed point on the discs: on the dual path (`dual`),
/// the sparse factor or, `iterative`, AMG-PCG (docs/methods.md §12.3,
/// "The iterative path").
fn run(
    qp: &QpProblem,
    fr: &Friction,
    r: Vec<Vec<f64>>,
    dual: Option<Dual>,
    ctx: &mut Context,
    iterative: bool,
) -> Result<Output, QpError> {
    if dual.is_none() {
        log::debug!(
            "ssn: discs: the sparse path (ssn_path = {:?}, multigrid {iterative})",
            ctx.settings.ssn.path
        );
    }
    let mut st = State::new(qp, fr, r, ctx);
    if iterative {
        st.iter = Some(plane_k::IterK::default());
        st.rho
            .iter_mut()
            .flatten()
            .for_each(|r| *r *= plane_k::RHO_ITERATIVE);
    }
    st.hold_free_bodies();
    if let Some(d) = dual {
        st.inner += d.solves;
        st.dual = Some(d);
    }
    let mut step = PlaneTresca { st, ctx, steps: 0 };
    let proven = coulomb::certificate(qp);
    let out = coulomb::solve(fr, &mut step, "ssn", &proven, ctx.settings.kkt_target);
    if let Some(it) = &step.st.iter {
        log::debug!(
            "ssn: discs: {} multigrid hierarchies ({} updates, {:.3} s), {} CG steps",
            it.builds,
            it.updates,
            it.t_setup,
            it.cg_steps
        );
    }
    out
}

struct State<'a> {
    qp: &'a QpProblem,
    fr: &'a Friction,
    ws: &'a crate::linalg::cholesky::Workspace,
    /// Orthonormal basis of ker C.
    r: Vec<Vec<f64>>,
    /// cᵢ and c_tᵢ of the predictions (c_t: the softer tangential row).
    cn: Vec<f64>,
    ct: Vec<f64>,
    /// ρ of a normal and of a tangential row of B, per contact row.
    rho: Vec<[f64; 2]>,
    tol: f64,
    /// The residual that ends this Tresca problem: `tol`, or on the
    /// iterative path a fraction of the bound's last change
    /// (`State::tresca_tol_for`).
    tresca_tol: f64,
    x: Vec<f64>,
    ln: Vec<f64>,
    /// (λ_t1, λ_t2) per contact row.
    lt: Vec<f64>,
    s: Vec<f64>,
    glued: bool,
    /// Coulomb's coefficients while the direct iteration runs (s = μλ_n
    /// of the current iterate).
    coulomb: Option<Vec<f64>>,
    /// The caller's multipliers of a load step's start, until taken.
    warm: Option<crate::qp::Multipliers>,
    in_n: Vec<bool>,
    tang: Vec<Disc>,
    /// A step of the current solve has been taken (the first takes the
    /// sets as they stand).
    started: bool,
    /// The sets are set for the next solve's first step (the coarse
    /// start's): it neither predicts nor starts them afresh.
    preset: bool,
    /// The current solve started from the coarse kinds ([`COARSE_STEPS`]).
    coarse_run: bool,
    /// The next prediction is a load step's first from the last step's
    /// multipliers: a row on its disc's rim there keeps slipping
    /// ([`State::predict`]).
    rim_slips: bool,
    /// Newton steps of the current solve.
    run_steps: usize,
    /// The patterns (N, each row's kind) of this solve's steps.
    visited: std::collections::HashSet<(Vec<bool>, Vec<u8>)>,
    /// A solve has ended before (the next starts from its answer).
    solved: bool,
    /// Steps of all solves, for the log.
    outer: usize,
    /// Ax and Tx of the current iterate.
    ax: Vec<f64>,
    tx: Vec<f64>,
    inner: usize,
    best: (f64, usize),
    /// The last residual and the steps in a row at it ([`FLOOR_STEPS`]).
    floor: (f64, usize),
    error: Option<QpError>,
    /// The dual-space solves (None: the sparse path, K = C + ρBᵀB).
    dual: Option<Dual>,
    /// K solved by multigrid-preconditioned CG (ssn_path = "iterative").
    iter: Option<plane_k::IterK>,
    /// The multipliers on B = [A; T] and α of the last dual-space solve.
    mu: Vec<f64>,
    alpha: Vec<f64>,
    /// x is not yet formed from (μ, α) ([`State::ensure_x`]).
    x_stale: bool,
    /// The certificate's floor of the length scale (docs/methods.md §8.4, §12.3).
    x_floor: f64,
}

impl<'a> State<'a> {
    fn new(qp: &'a QpProblem, fr: &'a Friction, r: Vec<Vec<f64>>, ctx: &Context<'a>) -> Self {
        let (n, m) = (qp.n(), qp.m());
        let diag = qp.c.diag();
        let cmean = (diag.iter().sum::<f64>() / n.max(1) as f64).max(f64::MIN_POSITIVE);
        let cn = row_stiffness(&qp.a, &diag, cmean, 1.0);
        let kt = row_stiffness(&fr.t, &diag, cmean, 1.0);
        let kt: Vec<f64> = (0..m).map(|i| kt[2 * i].min(kt[2 * i + 1])).collect();
        let rho = cn
            .iter()
            .zip(&kt)
            .map(|(a, b)| [RHO * a, RHO * b])
            .collect();
        let ct = kt.iter().map(|k| CT_FACTOR * k).collect();
        let x = ctx.x0.map_or_else(|| vec![0.0; n], |x0| x0.to_vec());
        let ax = qp.a.mul(&x);
        let tx = fr.t.mul(&x);
        let scale = norm_inf(&x).max(norm_inf(&qp.g)).max(f64::MIN_POSITIVE);
        let in_n = (0..m).map(|i| ax[i] - qp.g[i] >= -1e-12 * scale).collect();
        State {
            qp,
            fr,
            ws: ctx.ws,
            r,
            cn,
            ct,
            rho,
            tol: ctx.settings.tol,
            tresca_tol: ctx.settings.tol,
            x,
            ln: vec![0.0; m],
            lt: vec![0.0; 2 * m],
            s: vec![0.0; m],
            glued: true,
            coulomb: None,
            warm: ctx.lambda0.cloned(),
            in_n,
            tang: vec![Disc::Stick; m],
            started: false,
            preset: false,
            coarse_run: false,
            rim_slips: false,
            run_steps: 0,
            visited: std::collections::HashSet::new(),
            solved: false,
            outer: 0,
            ax,
            tx,
            inner: 0,
            best: (f64::INFINITY, 0),
            floor: (f64::INFINITY, 0),
            error: None,
            x_floor: crate::qp::kkt::length_floor(qp),
            dual: None,
            iter: None,
            mu: vec![],
            alpha: vec![],
            x_stale: false,
        }
    }

    /// Multipliers and sets as before any solve (x, Ax, Tx and N are the
    /// caller's to put back): the next solve takes the method's own start.
    fn reset_multipliers(&mut self) {
        let m = self.qp.m();
        (self.ln, self.lt) = (vec![0.0; m], vec![0.0; 2 * m]);
        self.tang = vec![Disc::Stick; m];
        self.x_stale = false;
        self.solved = false;
        self.preset = false;
    }

    /// v = T x − t0 of row i.
    fn v(&self, i: usize) -> [f64; 2] {
        [
            self.tx[2 * i] - self.fr.t0[2 * i],
            self.tx[2 * i + 1] - self.fr.t0[2 * i + 1],
        ]
    }

    /// The sets predicted at the current iterate.
    fn predict(&self) -> (Vec<bool>, Vec<Disc>) {
        let qp = self.qp;
        let m = qp.m();
        let in_n: Vec<bool> = (0..m)
            .map(|i| self.ln[i] + self.cn[i] * (self.ax[i] - qp.g[i]) > 0.0)
            .collect();
        let tang = (0..m)
            .map(|i| {
                let lt = [self.lt[2 * i], self.lt[2 * i + 1]];
                let d = predict_disc(in_n[i], self.glued, self.s[i], lt, self.v(i), self.ct[i]);
                if self.rim_slips && d == Disc::Stick {
                    rim_slip(lt, self.s[i]).unwrap_or(d)
                } else {
                    d
                }
            })
            .collect();
        (in_n, tang)
    }

    /// Move the sets one row towards the prediction (`n_set`, `tang`): the
    /// row whose prediction is violated most (normal: |λ_n + c(Ax − g)|,
    /// tangential: |‖λ_t + c_t v‖ − s|); rows that slip in both keep the
    /// predicted direction.
    fn single_change(&mut self, n_set: &[bool], tang: &[Disc]) {
        let qp = self.qp;
        let mut best: Option<(f64, usize, bool)> = None;
        for i in 0..qp.m() {
            if n_set[i] != self.in_n[i] {
                let sc = (self.ln[i] + self.cn[i] * (self.ax[i] - qp.g[i])).abs();
                if best.is_none_or(|b| sc > b.0) {
                    best = Some((sc, i, false));
                }
            }
            // Glued, a row's kind follows its N (set below).
            if tang[i].kind() != self.tang[i].kind() && !self.glued {
                let v = self.v(i);
                let xi = [
                    self.lt[2 * i] + self.ct[i] * v[0],
                    self.lt[2 * i + 1] + self.ct[i] * v[1],
                ];
                let sc = (tangential_norm(&xi) - self.s[i]).abs();
                if best.is_none_or(|b| sc > b.0) {
                    best = Some((sc, i, true));
                }
            } else if matches!(tang[i], Disc::Slip(..)) {
                self.tang[i] = tang[i];
            }
        }
        match best {
            Some((_, i, false)) => self.in_n[i] = n_set[i],
            Some((_, i, true)) => self.tang[i] = tang[i],
            None => {}
        }
        if self.glued {
            // Glued, a row sticks exactly when it is in N.
            for (t, &a) in self.tang.iter_mut().zip(&self.in_n) {
                *t = if a { Disc::Stick } else { Disc::Free };
            }
        }
    }

    /// The rows of B for the sets (`in_n`, `tang`).
    fn brows(&self, in_n: &[bool], tang: &[Disc]) -> Vec<BRow> {
        let (a, t) = (&self.qp.a, &self.fr.t);
        set_rows(in_n, tang)
            .into_iter()
            .map(|of| {
                let rhs = of_rhs(of, tang, &self.qp.g, &self.fr.t0);
                match of {
                    Of::Normal(i) => {
                        let (c, v) = a.row(i);
                        BRow {
                            cols: c.to_vec(),
                            vals: v.to_vec(),
                            rhs,
                            rho: self.rho[i][0],
                            spring: None,
                            of,
                        }
                    }
                    Of::Tangential(i, k) => {
                        let (c, v) = t.row(2 * i + k);
                        BRow {
                            cols: c.to_vec(),
                            vals: v.to_vec(),
                            rhs,
                            rho: self.rho[i][1],
                            spring: None,
                            of,
                        }
                    }
                    Of::Across(i) => {
                        let Disc::Slip(e, kappa) = tang[i] else {
                            unreachable!("set_rows: Across only for a slipping row")
                        };
                        let (cols, vals) = combine(t, i, [-e[1], e[0]]);
                        // A spring 1/κ softer than the row's ρ goes into K as
                        // it is; a stiffer one is held as a constraint (the
                        // step is then Newton's to κ/ρ⁻¹, no worse conditioned).
                        let k_s = 1.0 / kappa;
                        BRow {
                            cols,
                            vals,
                            rhs,
                            rho: self.rho[i][1],
                            spring: (k_s <= self.rho[i][1]).then_some(k_s),
                            of,
                        }
                    }
                }
            })
            .collect()
    }

    /// Solve the working set's equality-constrained problem; Ok(Some) when
    /// it ends the solve (unbounded, or a breakdown).
    fn solve_set(&mut self) -> Result<Option<Status>, QpError> {
        let qp = self.qp;
        let m = qp.m();
        let rows = self.brows(&self.in_n, &self.tang);
        let mut known = vec![0.0; 2 * m];
        for (i, d) in self.tang.iter().enumerate() {
            if let (Disc::Slip(e, _), false) = (d, self.glued) {
                known[2 * i] = -self.s[i] * e[0];
                known[2 * i + 1] = -self.s[i] * e[1];
            }
        }
        let free = self.free_motions(&rows);
        if !free.is_empty() {
            if let Some(z) = self.unbounded_along(&free) {
                return Ok(Some(Status::Unbounded { direction: z }));
            }
        }
        // A body held tangentially by friction alone slides away when the
        // loads along a motion the normal rows leave free outwork the discs
        // (Σ sᵢ‖T_i z‖): tested whatever the tangential sets, which may
        // cycle between stick and slip on such a body and never free it.
        if !self.glued {
            let slide = self.free_motions(rows.iter().filter(|b| matches!(b.of, Of::Normal(_))));
            if !slide.is_empty() && slide.len() > free.len() {
                if let Some(z) = self.unbounded_along(&slide) {
                    return Ok(Some(Status::Unbounded { direction: z }));
                }
            }
        }
        if free.is_empty() && self.solve_set_dual(&rows, &known) {
            return Ok(None);
        }
        // On the iterative path the direct Coulomb iteration holds the
        // bound inside the step as the dual path does: a slipping row's
        // force μᵢλ_nᵢêᵢ follows its normal row's multiplier, sweep by
        // sweep (docs/methods.md §12.3), and leaves the known loads.
        let coupled: Vec<plane_k::Coupled> = match (&self.coulomb, &self.iter) {
            (Some(mu_c), Some(_)) if !self.glued => rows
                .iter()
                .enumerate()
                .filter_map(|(p, b)| match (b.of, b.of_slip(&self.tang)) {
                    (Of::Normal(i), Some(e)) => Some(plane_k::Coupled {
                        row: p,
                        mu: mu_c[i],
                        e,
                        i,
                    }),
                    _ => None,
                })
                .collect(),
            _ => vec![],
        };
        for c in &coupled {
            known[2 * c.i] = 0.0;
            known[2 * c.i + 1] = 0.0;
        }
        // d' = d − Σ_slip sᵢ T_iᵀ eᵢ.
        let mut dp = qp.d.clone();
        self.fr.t.mul_t_add(&known, &mut dp);
        let mu0: Vec<f64> = rows
            .iter()
            .map(|b| match b.of {
                _ if b.spring.is_some() => 0.0,
                Of::Normal(i) => self.ln[i],
                Of::Tangential(i, k) => self.lt[2 * i + k],
                Of::Across(_) => 0.0,
            })
            .collect();
        let (x, mu) = self.al_solve(&rows, &dp, &free, mu0, &coupled)?;
        if !x.iter().all(|v| v.is_finite()) {
            return Ok(Some(Status::Failed(Failure::Breakdown(
                "the KKT solve of a working set gave a non-finite iterate".into(),
            ))));
        }
        self.ax = qp.a.mul(&x);
        self.tx = self.fr.t.mul(&x);
        self.x = x;
        self.x_stale = false;
        self.ln = vec![0.0; m];
        self.lt = known.iter().map(|k| -k).collect();
        for (b, mk) in rows.iter().zip(&mu) {
            match b.of {
                Of::Normal(i) => self.ln[i] = *mk,
                Of::Tangential(i, k) => self.lt[2 * i + k] = *mk,
                Of::Across(i) => {
                    if let Disc::Slip(e, _) = self.tang[i] {
                        self.lt[2 * i] -= mk * e[1];
                        self.lt[2 * i + 1] += mk * e[0];
                    }
                }
            }
        }
        for c in &coupled {
            let f = c.mu * mu[c.row];
            self.lt[2 * c.i] += f * c.e[0];
            self.lt[2 * c.i + 1] += f * c.e[1];
        }
        Ok(None)
    }

    /// K = C + Σ_B ρ bᵀb on the pattern of C, AᵀA and each contact row's
    /// tangential pair (the same pattern every step: one symbolic factor).
    fn k_matrix(&self, rows: &[BRow]) -> Csr {
        let qp = self.qp;
        let n = qp.n();
        let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(qp.c.nnz());
        for i in 0..n {
            let (cols, vals) = qp.c.row(i);
            trip.extend(cols.iter().zip(vals).map(|(&j, &v)| (i, j, v)));
        }
        // The pattern: zero-weight products of every row's columns.
        for i in 0..qp.m() {
            let (c, _) = qp.a.row(i);
            for &j in c {
                trip.extend(c.iter().map(|&k| (j, k, 0.0)));
            }
            let (c, _) = combine(&self.fr.t, i, [1.0, 1.0]);
            for &j in &c {
                trip.extend(c.iter().map(|&k| (j, k, 0.0)));
            }
        }
        for b in rows {
            let w = b.spring.unwrap_or(b.rho);
            for (&j, &a) in b.cols.iter().zip(&b.vals) {
                for (&k, &c) in b.cols.iter().zip(&b.vals) {
                    trip.push((j, k, w * a * c));
                }
            }
        }
        Csr::from_triplets(n, n, &trip)
    }

    /// The residual of the current iterate against the Tresca problem at
    /// its bound: the normal conditions and the disc law (§12.5), forces
    /// relative to the largest multiplier and bound, lengths to the
    /// largest of |Ax|, |Tx|, g, t0.
    fn residual(&self) -> f64 {
        let qp = self.qp;
        let fs = norm_inf(&self.ln)
            .max(norm_inf(&self.lt))
            .max(if self.glued { 0.0 } else { norm_inf(&self.s) })
            .max(f64::MIN_POSITIVE);
        // A dual-space step forms x only when the solve ends.
        let xn = if self.x_stale { 0.0 } else { norm_inf(&self.x) };
        let xs = xn
            .max(self.x_floor)
            .max(norm_inf(&self.ax))
            .max(norm_inf(&self.tx))
            .max(norm_inf(&qp.g))
            .max(norm_inf(&self.fr.t0))
            .max(f64::MIN_POSITIVE);
        let mut r = 0.0f64;
        for i in 0..qp.m() {
            let gap = self.ax[i] - qp.g[i];
            let ln = self.ln[i];
            r = r
                .max(gap.max(0.0) / xs)
                .max((-ln).max(0.0) / fs)
                .max((ln * gap).abs() / (fs * xs));
            let lt = &self.lt[2 * i..2 * i + 2];
            let v = self.v(i);
            r = r.max(match self.tang[i] {
                // Glued: T_i x = t0_i is the law, its force unbounded.
                Disc::Stick if self.glued => tangential_norm(&v) / xs,
                _ => crate::qp::kkt::disc_residual(self.s[i], lt, &v, fs, xs),
            });
        }
        r
    }

    fn record(&self, iter: usize) -> IterRecord {
        IterRecord {
            iter,
            residual: self.residual(),
            active: self.in_n.iter().filter(|a| **a).count(),
            inner: self.inner,
        }
    }
}

/// The tangential kind a row is predicted to take (Hüeber, Stadler &
/// Wohlmuth in 3D, docs/methods.md §12.3) from its force λ_t, slip v, bound
/// s and c_t: glued, a row sticks exactly when it is in N (`in_n`).
fn predict_disc(in_n: bool, glued: bool, s: f64, lt: [f64; 2], v: [f64; 2], ct: f64) -> Disc {
    if glued {
        return if in_n { Disc::Stick } else { Disc::Free };
    }
    if !(s > 0.0) {
        return Disc::Free;
    }
    let xi = [lt[0] + ct * v[0], lt[1] + ct * v[1]];
    let nx = tangential_norm(&xi);
    if nx <= s {
        Disc::Stick
    } else {
        // Newton on λ_t = s ξ/‖ξ‖ at ξ: along ê the force is s; across,
        // λ⊥ = (s/‖ξ‖)(λ⊥ + c_t v⊥), so v⊥ = κλ⊥.
        let kappa = (nx - s) / (s * ct);
        Disc::Slip([xi[0] / nx, xi[1] / nx], kappa)
    }
}

/// A load step's first prediction from the last step's multipliers
/// (docs/methods.md §12.3, "The rows that slipped keep slipping"): there the slip increment v is
/// zero, so ξ = λ_t and a row that slipped sits on its disc's rim, ‖ξ‖ = s
/// to rounding, which `predict_disc` calls sticking. Under a load that
/// keeps growing such a row keeps slipping, and from "sticking" the slip
/// zone walked back out a ring of rows per Newton step (a rubber cube
/// sheared between steel plates, 1 024 rows: stick 859 → 395 → 278 → … →
/// 126 over 12 steps). A row within RIM of its rim slips along λ_t, with
/// κ = 0 (Newton's step at ξ on the rim); a load that turns back makes it
/// stick at the next prediction.
fn rim_slip(lt: [f64; 2], s: f64) -> Option<Disc> {
    const RIM: f64 = 1e-6;
    let nl = tangential_norm(&lt);
    (s > 0.0 && nl >= (1.0 - RIM) * s).then(|| Disc::Slip([lt[0] / nl, lt[1] / nl], 0.0))
}

/// What the multipliers of the working set (`in_n`, `tang`) are: the
/// normal rows in N, a sticking row's tangential pair, a slipping row's
/// force across its direction (in this order).
fn set_rows(in_n: &[bool], tang: &[Disc]) -> Vec<Of> {
    let normal = (0..in_n.len()).filter(|&i| in_n[i]).map(Of::Normal);
    let tangential = tang.iter().enumerate().flat_map(|(i, d)| match d {
        Disc::Stick => vec![Of::Tangential(i, 0), Of::Tangential(i, 1)],
        Disc::Slip(..) => vec![Of::Across(i)],
        Disc::Free => vec![],
    });
    normal.chain(tangential).collect()
}

/// The right-hand side of the working-set row `of` with gaps `g` and
/// tangential offsets `t0` (2 per row): g, t0, or e⊥·t0 across a slip.
fn of_rhs(of: Of, tang: &[Disc], g: &[f64], t0: &[f64]) -> f64 {
    match of {
        Of::Normal(i) => g[i],
        Of::Tangential(i, k) => t0[2 * i + k],
        Of::Across(i) => match tang[i] {
            Disc::Slip(e, _) => -e[1] * t0[2 * i] + e[0] * t0[2 * i + 1],
            _ => 0.0,
        },
    }
}

/// A working set's pattern: N and each row's kind (directions left out).
fn pattern(in_n: &[bool], tang: &[Disc]) -> (Vec<bool>, Vec<u8>) {
    (in_n.to_vec(), tang.iter().map(|d| d.kind()).collect())
}

impl Iterative for State<'_> {
    /// One step: the sets predicted at the last answer (the first step of
    /// a solve: the sets as they stand, glued or predicted at the new
    /// bound), their solve, and the end when they repeat at a residual of
    /// `tol`.
    fn step(&mut self) -> Step {
        if std::mem::take(&mut self.preset) {
            // The coarse start's sets, as they stand.
        } else if self.started || self.solved && !self.glued {
            let (n_set, tang) = self.predict();
            self.rim_slips = false;
            let key = pattern(&n_set, &tang);
            let seen = key != pattern(&self.in_n, &self.tang) && self.visited.contains(&key);
            // The glued solve is a start: a pattern met again ends it,
            // where a row at the contact zone's edge flipped until
            // DIRECT_STALL (Cattaneo hc 0.0075: ten steps, 0.7 s; then
            // three with one single change before the end; docs/methods.md §12.3).
            if seen && (self.coulomb.is_some() || self.glued) {
                // The direct Coulomb iteration flips a row at the stick
                // zone's border as s moves with λ_n: the shared loop's
                // Tresca problems settle it (each step here is a factor).
                return Step::Done(
                    Status::Failed(Failure::Cycling {
                        best: self.best.0,
                        steps: self.best.1,
                    }),
                    self.record(self.outer),
                );
            }
            if seen {
                // A pattern seen before (the full step cycles: a normal set
                // flipping between two where a glued block tilts): only
                // the row that violates its prediction most changes, the
                // directions of the rows that keep slipping are updated.
                self.single_change(&n_set, &tang);
            } else {
                self.in_n = n_set;
                self.tang = tang;
            }
        } else {
            // The start: the rows in N stick (glued), or every row with a
            // positive bound sticks (a first Tresca problem); the others
            // are free.
            self.tang = self
                .in_n
                .iter()
                .zip(&self.s)
                .map(|(&a, &s)| {
                    if self.glued && a || !self.glued && s > 0.0 {
                        Disc::Stick
                    } else {
                        Disc::Free
                    }
                })
                .collect();
        }
        self.started = true;
        self.visited.insert(pattern(&self.in_n, &self.tang));
        self.outer += 1;
        self.run_steps += 1;
        let it = self.outer;
        match self.solve_set() {
            Ok(None) => {
                if let Some(mu) = &self.coulomb {
                    self.s = crate::qp::coulomb_bound(mu, &self.ln);
                }
                let rec = self.record(it);
                log::debug!(
                    "ssn: discs: |N| = {}, stick {}, slip {}: residual {:.3e}",
                    rec.active,
                    self.tang.iter().filter(|d| **d == Disc::Stick).count(),
                    self.tang
                        .iter()
                        .filter(|d| matches!(d, Disc::Slip(..)))
                        .count(),
                    rec.residual
                );
                if rec.residual < self.best.0 * (1.0 - 1e-9) {
                    self.best = (rec.residual, 0);
                } else {
                    self.best.1 += 1;
                }
                // The direct Coulomb iteration and the glued start are
                // starts and give up sooner (docs/methods.md §12.3).
                let budget = if self.coulomb.is_some() || self.glued {
                    DIRECT_STALL
                } else {
                    cycle_budget(self.qp.m())
                };
                if self.best.1 > budget || self.coarse_run && self.run_steps > COARSE_STEPS {
                    return Step::Done(
                        Status::Failed(Failure::Cycling {
                            best: self.best.0,
                            steps: budget,
                        }),
                        rec,
                    );
                }
                let (n_set, tang) = self.predict();
                let same = n_set == self.in_n
                    && tang
                        .iter()
                        .zip(&self.tang)
                        .all(|(a, b)| a.kind() == b.kind());
                // At the rounding floor (docs/methods.md §12.3); the
                // driver's certificate judges the answer.
                self.floor =
                    if same && rec.residual > 0.5 * self.floor.0 && rec.residual <= FLOOR_MAX {
                        (rec.residual, self.floor.1 + 1)
                    } else {
                        (rec.residual, 0)
                    };
                if same && self.floor.1 >= FLOOR_STEPS && rec.residual > self.tol {
                    log::debug!(
                        "ssn: discs: the sets repeat at a residual of {:.3e} that no longer falls: its rounding floor",
                        rec.residual
                    );
                }
                // The glued start ends when its sets repeat: it is a start,
                // and the same sets give the same solve (the stack at
                // h = 0.05 spent 3 more steps proving its floor).
                if same
                    && (rec.residual <= self.tresca_tol
                        || self.floor.1 >= FLOOR_STEPS
                        || self.glued)
                {
                    Step::Done(Status::Converged, rec)
                } else {
                    Step::Continue(rec)
                }
            }
            Ok(Some(status)) => Step::Done(status, self.record(it)),
            Err(e) => {
                let msg = e.to_string();
                self.error = Some(e);
                Step::Done(
                    Status::Failed(Failure::Breakdown(msg)),
                    IterRecord::default(),
                )
            }
        }
    }
}

#[path = "plane_dual.rs"]
mod dual_space;
#[path = "plane_free.rs"]
mod plane_free;
#[path = "plane_k.rs"]
mod plane_k;
#[path = "plane_loop.rs"]
mod plane_loop;
#[path = "plane_nested.rs"]
mod plane_nested;

#[cfg(test)]
#[path = "plane_tests.rs"]
mod tests;
