//! The dual family (docs/methods.md §4.5, §4.6, §7): minimise
//! θ(λ) = ½λᵀHλ − λᵀh over λ ≥ 0, H = A C⁻¹ Aᵀ, h = A C⁻¹ d − g, and recover
//! x(λ) = C⁻¹(d − Aᵀλ). H is never formed: Hv = A K⁻¹(Aᵀv) with one sparse
//! Cholesky factor K of C (`DualOp`).
//!
//! This module is the host the three methods share: the row scaling, the
//! dual operator and, for a semicoercive C (TFETI), the SMALBE-M loop that
//! enforces the equality Gλ = e (G = RᵀAᵀ, e = Rᵀd) on the homogenised
//! problem min ½λ̂ᵀ(PHP + ρQ)λ̂ − λ̂ᵀb over λ̂ ≥ −λ̃ (methods.md §7). Inside
//! that loop a `BoundStep` does one step on the bounds: MPRGP
//! ([`mprgp`]), Polyak's CG with constraints ([`polyak`], the `dual`
//! method) or projected gradient / accelerated Uzawa ([`uzawa`]). With an
//! empty kernel the loop reduces to the bound-constrained solver alone.
//! Counts: `iterations` = steps + multiplier updates, `inner_iterations` =
//! solves with the factor.

mod bounds;
#[cfg(test)]
mod disc_tests;
mod friction;
pub mod mprgp;
mod op;
#[cfg(test)]
pub(crate) mod partial_kernel;
pub mod polyak;
pub mod uzawa;

pub(crate) use friction::solve_friction;
pub(crate) use op::{dense_h, DualOp};
pub use polyak::{solve, DualMethod};

use crate::linalg::dense::{chol_backward, chol_forward};
use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::sparse::{dot, norm, norm_inf};
use crate::qp::executor::{Iterative, Step};
use crate::qp::Failure;
use crate::qp::{Context, IterRecord, Output, QpError, QpProblem, Status};
use std::time::Instant;

/// Power iterations for ‖PHP‖ (and for Uzawa's ρ).
pub const POWER_ITERS: usize = 30;
/// SMALBE: ρ = RHO_FACTOR·‖PHP‖_est (unless the step asks otherwise).
pub const RHO_FACTOR: f64 = 30.0;
/// SMALBE: M ← M/β.
const SMALBE_BETA: f64 = 10.0;
/// The rigid part of x: directions of the rows' Gram below this fraction of
/// its largest eigenvalue are not fitted (`Smalbe::primal`).
const ALPHA_REL: f64 = 1e-10;
/// At most this many hundredfold tightenings of `tol` when a converged
/// answer fails the certificate ([`Smalbe::certified`]).
const TIGHTEN: usize = 3;
/// `tol` is not tightened below this (rounding of the dual gradient).
const TOL_MIN: f64 = 1e-15;
/// SMALBE: η = ETA_FACTOR·‖h‖.
const ETA_FACTOR: f64 = 0.1;

/// One step of a bound-constrained solver for min ½λ̂ᵀHλ̂ − λ̂ᵀb, λ̂ ≥ ℓ,
/// run by the SMALBE host (one executor iteration per step).
pub(crate) trait BoundStep {
    /// SMALBE's ρ as a multiple of ‖PHP‖_est.
    fn rho_factor(&self) -> f64 {
        RHO_FACTOR
    }
    /// Prepare the first step: `h_norm` = ‖PHP + ρQ‖_est, `s.g` is exact.
    fn start(&mut self, s: &DualState, h_norm: f64);
    /// One step: moves `s.lam` within the bounds and keeps
    /// `s.g` = Hλ̂ − b up to date.
    fn step(&mut self, s: &mut DualState) -> Result<StepKind, String>;
    /// The host recomputed `s.g` from scratch or changed `s.b` (SMALBE
    /// update): drop what was built on the old gradient.
    fn restart(&mut self, s: &DualState);
}

/// What a [`BoundStep`] did (counted for the debug log).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum StepKind {
    /// A conjugate-gradient step on the free set.
    Cg,
    /// MPRGP's expansion (feasible CG part, then projected gradient step).
    Expansion,
    /// MPRGP's proportioning step along the chopped gradient.
    Proportioning,
    /// Polyak: CG stopped on a blocking bound.
    Blocked,
    /// Polyak: release of bounds with negative multipliers.
    Release,
    /// Uzawa: projected (possibly extrapolated) gradient step.
    Gradient,
}

const KINDS: [(StepKind, &str); 6] = [
    (StepKind::Cg, "CG"),
    (StepKind::Expansion, "expansion"),
    (StepKind::Proportioning, "proportioning"),
    (StepKind::Blocked, "blocked"),
    (StepKind::Release, "release"),
    (StepKind::Gradient, "gradient"),
];

/// Dual solve with the given bound step; `name` prefixes messages.
pub(crate) fn solve_with<S: BoundStep>(
    qp: &QpProblem,
    ctx: &mut Context,
    step: S,
    name: &'static str,
) -> Result<Output, QpError> {
    let opts = ctx.settings;
    let t0 = Instant::now();
    let r = orthonormal_kernel(&qp.c, &qp.kernel)?;
    let fac = ctx.ws.cholesky(&qp.c, &qp.kernel)?;
    let t_factor = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    // The dual host sees the rows scaled by sᵢ (see [`row_scaling`]); C, d
    // and the kernel are the caller's (C is not needed past the factor).
    let s = row_scaling(qp);
    let mut a = qp.a.clone();
    for (i, si) in s.iter().enumerate() {
        for v in &mut a.data[a.indptr[i]..a.indptr[i + 1]] {
            *v *= si;
        }
    }
    let sq = QpProblem {
        c: crate::qp::Csr::zeros(0, 0),
        d: qp.d.clone(),
        a,
        g: qp.g.iter().zip(&s).map(|(g, s)| g * s).collect(),
        kernel: vec![],
        friction: None,
        near: None,
    };
    let op = DualOp::new(&sq, fac, r, name)?;
    let mut st = Smalbe::new(op, opts.tol, step, name, None)?;
    st.s.target = opts.kkt_target;
    st.judge = Some((qp, &s));
    let t_setup = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let mut exec = ctx.executor(name);
    let (status, iters) = exec.run(&mut st);
    let t_it = t2.elapsed().as_secs_f64();
    let mut res = st.into_result(
        status,
        iters,
        exec.log,
        vec![
            ("factor".into(), t_factor),
            ("setup".into(), t_setup),
            ("iterate".into(), t_it),
        ],
    );
    // Aᵀλ = Ãᵀμ with Ã = diag(s)A: λ = diag(s)μ.
    for (l, si) in res.lambda.iter_mut().zip(&s) {
        *l *= si;
    }
    Ok(res)
}

/// Row scaling sᵢ = 1/√(aᵢᵀ diag(C)⁻¹ aᵢ): Jacobi scaling of H by the cheap
/// estimate of its diagonal. Same feasible set (λ ≥ 0 ⇔ μ ≥ 0), but Hᵢᵢ ≈ 1
/// in every body's own stiffness scale, so a row whose compliance comes
/// from a stiff body only no longer stalls the fixed-step methods, and the
/// result is invariant under scaling C (BENCHMARKS.md, "Dual family notes").
fn row_scaling(qp: &QpProblem) -> Vec<f64> {
    row_scaling_of(&qp.c, &qp.a)
}

/// [`row_scaling`] of the rows of `a` against the diagonal of `c`.
fn row_scaling_of(c: &crate::qp::Csr, a: &crate::qp::Csr) -> Vec<f64> {
    row_weights_of(c, a)
        .into_iter()
        .map(|h| {
            if h > 0.0 && h.is_finite() {
                1.0 / h.sqrt()
            } else {
                1.0
            }
        })
        .collect()
}

/// hᵢ = aᵢᵀ diag(C)⁻¹ aᵢ of each row of `a` (over the positive diagonal).
fn row_weights_of(c: &crate::qp::Csr, a: &crate::qp::Csr) -> Vec<f64> {
    let diag = c.diag();
    (0..a.nrows)
        .map(|i| {
            let (cols, vals) = a.row(i);
            cols.iter()
                .zip(vals)
                .filter(|(&j, _)| diag[j] > 0.0)
                .map(|(&j, &a)| a * a / diag[j])
                .sum()
        })
        .collect()
}

/// The state the bound steps share with the host.
pub(crate) struct DualState<'a> {
    /// The operator H = PHP + ρQ of the inner problem.
    pub(crate) op: DualOp<'a>,
    /// Lower bounds ℓ = −λ̃ of λ̂ (zero without a kernel); −s − λ̃ on the
    /// tangential rows of a frictional problem.
    pub(crate) lb: Vec<f64>,
    /// Upper bounds u of λ̂: +∞ on the contact rows, s − λ̃ on the
    /// tangential rows of a frictional problem (docs/methods.md §9.2).
    pub(crate) ub: Vec<f64>,
    /// Rows from here on are in pairs, each pair a disc of `discs`
    /// (docs/methods.md §12.4; `lb`, `ub` unused there); the length of λ̂
    /// when there is none.
    pub(crate) disc_start: usize,
    /// The discs ‖λ̂ₖ + λ̃ₖ‖ ≤ rₖ of the tangential pairs of a 3D frictional
    /// dual, pair k on rows disc_start + 2k, disc_start + 2k + 1.
    pub(crate) discs: Vec<bounds::Disc>,
    /// The iterate λ̂ (λ = λ̂ + λ̃), always in [ℓ, u] and in the discs.
    pub(crate) lam: Vec<f64>,
    /// The gradient g = (PHP + ρQ)λ̂ − b, kept current by every step.
    pub(crate) g: Vec<f64>,
    /// The linear term b = b̂ − G̃ᵀμ (changed by the SMALBE update only).
    pub(crate) b: Vec<f64>,
    /// g was recomputed from scratch and not updated since.
    pub(crate) fresh: bool,
    /// Relative tolerance: the loop stops at ‖gᴾ‖ ≤ tol·ref_g.
    pub(crate) tol: f64,
    /// The certificate's target (`Settings::kkt_target`).
    pub(crate) target: f64,
    /// The scale of the gradient: the loads' response at the rows
    /// ([`Smalbe::new`]).
    pub(crate) ref_g: f64,
    /// max(‖h‖, ‖b̂‖), open gaps included: the scale of the check of the
    /// recovered x in `Smalbe::into_result` (a coarse guard; the
    /// certificate is the judge).
    pub(crate) ref_h: f64,
    /// Precision SMALBE asks of the current inner solve, min(M‖G̃λ̂‖, η)
    /// (0 without a kernel); set by the host before each step.
    pub(crate) smalbe_tol: f64,
    /// Method name for messages.
    pub(crate) name: &'static str,
}

impl DualState<'_> {
    /// g ← (PHP + ρQ)λ̂ − b from scratch.
    pub(crate) fn refresh(&mut self) {
        let ax = self.op.apply(&self.lam);
        self.g = ax.iter().zip(&self.b).map(|(a, b)| a - b).collect();
        self.fresh = true;
    }
}

/// SMALBE-M host (methods.md §7): a [`BoundStep`] on the augmented
/// Lagrangian, multiplier updates μ ← μ + ρG̃λ̂ when ‖gᴾ‖ ≤ max(min(M‖G̃λ̂‖,
/// η), 0.1·tol·‖h‖), M ← M/β when the Lagrangian did not grow by ρ/2‖G̃λ̂‖².
struct Smalbe<'a, S> {
    s: DualState<'a>,
    step: S,
    /// λ̃ (the homogenising shift).
    shift: Vec<f64>,
    /// Multiplier μ of G̃λ̂ = 0.
    mu: Vec<f64>,
    /// ‖ẽ‖
    e_norm: f64,
    /// SMALBE's M.
    mpar: f64,
    /// ‖PHP‖ (power iteration, ρ = 0), kept for [`BoxBounds::hnorm`].
    pub(crate) hnorm: f64,
    /// SMALBE's η.
    eta: f64,
    /// The augmented Lagrangian at the previous update.
    lag_prev: Option<f64>,
    /// Multiplier updates so far.
    outer: usize,
    /// Steps by kind, in the order of [`KINDS`].
    counts: [usize; 6],
    /// Rows 0..m_n are contact rows (λ ≥ 0), the rest tangential rows.
    m_n: usize,
    /// Slip bounds s of the tangential rows (|λ| ≤ s).
    upper: Vec<f64>,
    /// The caller's QP and the row scaling, to judge a converged answer by
    /// the driver's certificate ([`Smalbe::certified`]); None for friction.
    judge: Option<(&'a QpProblem, &'a [f64])>,
    /// Tightenings of `tol` so far ([`TIGHTEN`]).
    tightened: usize,
    /// (λ, x) of the current λ̂ as [`Smalbe::certified`] recovered them
    /// (rows scaled), for `into_result` not to recover them again.
    recovered: Option<(Vec<f64>, Vec<f64>)>,
    /// λ̂ at the best residual so far ([`Iterative::best`]): a run that
    /// stagnates returns it, not the last λ̂ (on the geodynamic model,
    /// before its rows of prescribed slip were set outside the dual,
    /// docs/methods.md §9.1, the last was 10⁻⁷–10⁻³ where the best was
    /// 5·10⁻¹⁰).
    best_lam: Option<Vec<f64>>,
    /// λ̂ where the current step measured its residual (the record's
    /// iterate: the step moves λ̂ after measuring).
    measured_lam: Vec<f64>,
}

/// The bounds of a frictional dual (docs/methods.md §9.2, §12.4): rows
/// `0..m_n` of the stacked B = [A; T] are contact rows with λ ≥ 0; with
/// `Frame::Line` row m_n + i is tangential with |λ| ≤ `upper[i]`, with
/// `Frame::Plane` rows m_n + 2i, m_n + 2i + 1 are a pair with ‖λ‖ ≤
/// `upper[i]` (a disc); `lam0` (all rows) is a warm start.
pub(crate) struct BoxBounds {
    pub(crate) m_n: usize,
    pub(crate) upper: Vec<f64>,
    pub(crate) frame: crate::qp::Frame,
    pub(crate) lam0: Option<Vec<f64>>,
    /// ‖PHP‖ as the last solve of the same operator estimated it: the
    /// Tresca solves of one Coulomb loop share H (only the box moves), and
    /// the estimate (30 applications of H, a tenth of a solve on the
    /// geodynamic model) is the same number every time.
    pub(crate) hnorm: Option<f64>,
}

impl<'a, S: BoundStep> Smalbe<'a, S> {
    fn new(
        mut op: DualOp<'a>,
        tol: f64,
        mut step: S,
        name: &'static str,
        boxed: Option<&BoxBounds>,
    ) -> Result<Smalbe<'a, S>, QpError> {
        let m = op.qp.m();
        let k = op.k();
        let mut et: Vec<f64> = op.r.iter().map(|rl| dot(rl, &op.qp.d)).collect();
        chol_forward(&op.l, k, &mut et);
        let mut shift = vec![0.0; m];
        op.gt_add(&et, &mut shift);
        let h = op.h_vec();
        let mut bhat = h.clone();
        if k > 0 {
            let hs = op.h(&shift);
            for (b, v) in bhat.iter_mut().zip(&hs) {
                *b -= v;
            }
            op.project(&mut bhat);
        }
        // ‖PHP‖ by power iteration (ρ = 0 here).
        let hnorm = match boxed.and_then(|b| b.hnorm) {
            Some(h) => h,
            None if m == 0 => 1.0,
            None => op.norm_estimate(),
        };
        if !(hnorm > 0.0 && hnorm.is_finite()) {
            return Err(QpError::Factor(format!(
                "{name}: ‖H‖ estimate {hnorm} is not positive"
            )));
        }
        op.rho = if k > 0 {
            step.rho_factor() * hnorm
        } else {
            0.0
        };
        // The gradient's scale: the loads' response at the rows,
        // P·A K⁺(d − Aᵀλ̃) = b̂ + Pg (A K⁻¹d without a kernel), or an initial
        // penetration min(g, 0), not ‖h‖: the open gaps of rows far from
        // contact (geometry, any size) made it 5e7 times the response of a
        // ring under 1 mPa, whose solve then stopped short at every SMALBE
        // step and stagnated (docs/methods.md §7, "Floating bodies in the dual").
        let mut resp = bhat.clone();
        let mut gq = op.qp.g.clone();
        op.project(&mut gq);
        for (r, gi) in resp.iter_mut().zip(&gq) {
            *r += gi;
        }
        let pen = op
            .qp
            .g
            .iter()
            .map(|g| g.min(0.0).powi(2))
            .sum::<f64>()
            .sqrt();
        let ref_g = norm(&resp).max(pen).max(f64::MIN_POSITIVE);
        let ref_h = norm(&h).max(norm(&bhat)).max(ref_g);
        let e_norm = norm(&et);
        let mut lb: Vec<f64> = shift.iter().map(|s| -s).collect();
        let mut ub = vec![f64::INFINITY; m];
        let m_n = boxed.map_or(m, |b| b.m_n);
        let plane = boxed.is_some_and(|b| b.frame == crate::qp::Frame::Plane);
        let (disc_start, mut discs) = (if plane { m_n } else { m }, vec![]);
        if let Some(b) = boxed {
            if plane {
                // The disc ‖λ̂ + λ̃‖ ≤ u of each pair (docs/methods.md §12.4).
                for (k, &u) in b.upper.iter().enumerate() {
                    let j = m_n + 2 * k;
                    discs.push(bounds::Disc {
                        shift: [shift[j], shift[j + 1]],
                        radius: u,
                    });
                    lb[j..j + 2].fill(f64::NEG_INFINITY);
                }
            } else {
                for i in m_n..m {
                    lb[i] = -b.upper[i - m_n] - shift[i];
                    ub[i] = b.upper[i - m_n] - shift[i];
                }
            }
        }
        let mut lam: Vec<f64> = lb.iter().map(|&l| l.max(0.0)).collect();
        if let Some(b) = boxed {
            for i in m_n..disc_start {
                lam[i] = lam[i].min(ub[i]);
            }
            if let Some(l0) = &b.lam0 {
                for i in 0..disc_start {
                    lam[i] = (l0[i] - shift[i]).max(lb[i]).min(ub[i]);
                }
            }
            // A disc starts at the projection of λ (of the warm start, or
            // λ = λ̃: λ̂ = 0) onto it.
            for (k, d) in discs.iter().enumerate() {
                let j = m_n + 2 * k;
                let z = match &b.lam0 {
                    Some(l0) => [l0[j], l0[j + 1]],
                    None => d.shift,
                };
                let p = bounds::Disc::project(z, d.radius);
                if p != z || b.lam0.is_some() {
                    lam[j] = p[0] - d.shift[0];
                    lam[j + 1] = p[1] - d.shift[1];
                } else {
                    lam[j..j + 2].fill(0.0);
                }
            }
        }
        // ‖PHP + ρQ‖ = max(‖PHP‖, ρ): PHP and ρQ act on orthogonal subspaces.
        let h_norm = hnorm.max(op.rho);
        let mut s = DualState {
            op,
            lb,
            ub,
            disc_start,
            discs,
            lam,
            g: vec![0.0; m],
            b: bhat,
            fresh: false,
            tol,
            target: crate::qp::settings::DEFAULT_KKT_TARGET,
            ref_g,
            ref_h,
            smalbe_tol: 0.0,
            name,
        };
        s.refresh();
        step.start(&s, h_norm);
        Ok(Smalbe {
            s,
            step,
            shift,
            mu: vec![0.0; k],
            e_norm,
            mpar: smalbe_m0(ref_g, e_norm, hnorm),
            hnorm,
            eta: ETA_FACTOR * ref_g,
            lag_prev: None,
            outer: 0,
            counts: [0; 6],
            m_n,
            upper: boxed.map_or(vec![], |b| b.upper.clone()),
            judge: None,
            tightened: 0,
            recovered: None,
            best_lam: None,
            measured_lam: vec![],
        })
    }

    /// (‖G̃λ̂‖, its reference max(‖ẽ‖, ‖λ‖))
    fn feas(&self) -> (f64, f64) {
        if self.s.op.k() == 0 {
            return (0.0, 1.0);
        }
        let lam_norm = self
            .s
            .lam
            .iter()
            .zip(&self.shift)
            .map(|(a, b)| (a + b) * (a + b))
            .sum::<f64>()
            .sqrt();
        (
            norm(&self.s.op.gmul(&self.s.lam)),
            self.e_norm.max(lam_norm).max(f64::MIN_POSITIVE),
        )
    }

    fn record(&self, residual: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual,
            active: (0..self.s.lam.len()).filter(|&i| self.s.is_free(i)).count(),
            inner: self.s.op.solves,
        }
    }

    /// SMALBE multiplier update μ ← μ + ρG̃λ̂ and the M update.
    fn smalbe_update(&mut self) {
        let s = &mut self.s;
        let gx = s.op.gmul(&s.lam);
        let rho = s.op.rho;
        let inc: Vec<f64> = gx.iter().map(|v| rho * v).collect();
        for (m, d) in self.mu.iter_mut().zip(&inc) {
            *m += d;
        }
        let neg: Vec<f64> = inc.iter().map(|v| -v).collect();
        s.op.gt_add(&neg, &mut s.b);
        s.op.gt_add(&inc, &mut s.g);
        let lag = 0.5
            * s.lam
                .iter()
                .zip(s.g.iter().zip(&s.b))
                .map(|(x, (g, b))| x * (g - b))
                .sum::<f64>();
        if let Some(prev) = self.lag_prev {
            if lag < prev + 0.5 * rho * dot(&gx, &gx) {
                self.mpar /= SMALBE_BETA;
            }
        }
        self.lag_prev = Some(lag);
        self.outer += 1;
        self.step.restart(&self.s);
    }

    /// λ (exact zeros at the bounds), x = K⁻¹(d − Aᵀλ) − Rα.
    fn primal(&mut self) -> (Vec<f64>, Vec<f64>) {
        let s = &mut self.s;
        let qp = s.op.qp;
        let m = qp.m();
        let m_n = self.m_n;
        let disc_start = s.disc_start;
        let mut lam: Vec<f64> = (0..disc_start)
            .map(|i| {
                if i >= m_n {
                    // A tangential row: exactly ±s at its bounds.
                    let u = self.upper[i - m_n];
                    if s.is_free(i) {
                        (s.lam[i] + self.shift[i]).max(-u).min(u)
                    } else if s.lam[i] <= s.lb[i] {
                        -u
                    } else {
                        u
                    }
                } else if s.is_free(i) {
                    (s.lam[i] + self.shift[i]).max(0.0)
                } else {
                    0.0
                }
            })
            .collect();
        // A disc: λ = λ̂ + λ̃ in the disc, exactly of norm s on its circle
        // (docs/methods.md §12.4).
        for (k, d) in s.discs.iter().enumerate() {
            let j = disc_start + 2 * k;
            let z = [s.lam[j] + self.shift[j], s.lam[j + 1] + self.shift[j + 1]];
            let u = d.radius;
            let n = z[0].hypot(z[1]);
            let free = s.is_free(j);
            let p = if !free && n > 0.0 && u < f64::INFINITY {
                [z[0] * (u / n), z[1] * (u / n)]
            } else {
                bounds::Disc::project(z, u)
            };
            lam.extend(p);
        }
        let mut x = s.op.x_of(&lam);
        let k = s.op.k();
        if k > 0 {
            // The rigid part Rα of x: the least-squares fit of the rows whose
            // equation holds (λ̂ strictly inside its bounds: a contact row
            // with λ > 0, a sticking tangential row), min ‖(Ax − g)_F‖ over
            // α, x = x̂ + Rα, in G̃'s coordinates α̃ = Lᵀα. The SMALBE
            // multiplier μ gives the same α in the limit, but as the
            // difference of two terms of the size of the open gaps: a ring
            // under 1 mPa with gaps of 5 cm came out rotated by 1.4e-3
            // (docs/methods.md §7). Directions no such row holds get no
            // component (a free slide; the driver reports it, §1.7).
            let r: Vec<f64> = qp.a.mul(&x).iter().zip(&qp.g).map(|(a, g)| a - g).collect();
            let mut gram = vec![vec![0.0; k]; k];
            let mut rhs = vec![0.0; k];
            for i in (0..m).filter(|&i| s.is_free(i)) {
                for a in 0..k {
                    let ga = s.op.gt[a][i];
                    rhs[a] -= ga * r[i];
                    for b in 0..k {
                        gram[a][b] += ga * s.op.gt[b][i];
                    }
                }
            }
            let (vals, vecs) = crate::linalg::dense::sym_eigen(&gram);
            let top = vals.iter().fold(0.0f64, |t, v| t.max(*v));
            let mut alpha = vec![0.0; k];
            for (v, u) in vals.iter().zip(&vecs) {
                if *v > ALPHA_REL * top {
                    let c = dot(u, &rhs) / v;
                    for (al, ul) in alpha.iter_mut().zip(u) {
                        *al += c * ul;
                    }
                }
            }
            chol_backward(&s.op.l, k, &mut alpha);
            for (rl, &al) in s.op.r.iter().zip(&alpha) {
                for (xi, ri) in x.iter_mut().zip(rl) {
                    *xi += al * ri;
                }
            }
        }
        (lam, x)
    }

    /// λ (exact zeros at the bounds) and the recovered x; a converged status
    /// becomes `Failed` when x violates Ax ≤ g or complementarity by more
    /// than 100·tol·‖h‖; `active` = λᵢ > 0 or (g − Ax)ᵢ ≤ 10·tol·‖h‖.
    fn into_result(
        mut self,
        status: Status,
        iterations: usize,
        log: Vec<IterRecord>,
        timings: Vec<(String, f64)>,
    ) -> Output {
        let qp = self.s.op.qp;
        let name = self.s.name;
        if log::log_enabled!(log::Level::Debug) {
            let steps: Vec<String> = KINDS
                .iter()
                .zip(&self.counts)
                .filter(|(_, &c)| c > 0)
                .map(|((_, label), c)| format!("{c} {label}"))
                .collect();
            log::debug!(
                "{name}: steps: {}; {} SMALBE updates, ρ = {:e}",
                steps.join(", "),
                self.outer,
                self.s.op.rho
            );
        }
        // λ̂ has not moved since `certified` recovered (λ, x) if it did.
        let (lambda, x) = match self.recovered.take() {
            Some(r) => r,
            None => self.primal(),
        };
        // The guard's scale is the one it had before the stopping scale
        // left the open gaps out: on two_blocks with gaps of 0.7 × the
        // deformation the new scale failed uzawa's certified answer
        // (primal 6e-11) at 2.7e-9 against 2.4e-9 (tests/agreement.rs).
        // (and the tol asked for, before any tightening by `certified`)
        let tol = self.s.tol * 1e2f64.powi(self.tightened as i32);
        let ref_g = self.s.ref_h;
        let s: Vec<f64> = qp.a.mul(&x).iter().zip(&qp.g).map(|(a, g)| a - g).collect();
        let gap_tol = 10.0 * tol * ref_g;
        let m_n = self.m_n;
        let active: Vec<bool> = (0..m_n)
            .map(|i| lambda[i] > 0.0 || s[i] >= -gap_tol)
            .collect();
        // Primal feasibility and complementarity of the recovered x (the
        // friction conditions are the driver's certificate).
        let viol = s[..m_n].iter().fold(0.0f64, |a, &v| a.max(v));
        let compl = (0..m_n)
            .filter(|&i| lambda[i] > 0.0)
            .fold(0.0f64, |a, i| a.max(s[i].abs()));
        let rounding = 1e-13 * (norm_inf(&x) + norm_inf(&qp.g));
        let limit = 100.0 * tol * ref_g + rounding;
        let status = if status.converged() && !(viol <= limit && compl <= limit) {
            Status::Failed(Failure::Breakdown(format!(
                "{name}: the dual converged but the recovered x violates Ax ≤ g by {viol:e} or complementarity \
                 by {compl:e} (limit 100·tol·‖h‖ = {limit:e})"
            )))
        } else {
            status
        };
        Output {
            x,
            lambda,
            lambda_t: vec![],
            active,
            status,
            iterations,
            inner_iterations: self.s.op.solves,
            log,
            timings,
        }
    }
}

impl<S: BoundStep> Smalbe<'_, S> {
    /// Whether the answer at the current λ̂ passes the driver's certificate
    /// (docs/methods.md §8.4), or `tol` may not be tightened further. The
    /// x recovered from λ has gaps exact only to about tol·‖h‖, and a
    /// residual at its rounding floor counts only with exact gaps: on a
    /// steel deck on rubber bearings (contrast 1e8) the dual family
    /// stopped with x within 1e-14 of ssn's and gaps at 2–5e-13 of max|x|,
    /// refused; with tol ÷ 100 (3 more iterations) it is certified.
    fn certified(&mut self) -> bool {
        let Some((qp, scale)) = self.judge else {
            return true;
        };
        if self.tightened >= TIGHTEN || self.s.tol < TOL_MIN {
            return true;
        }
        let (lam, x) = self.primal();
        let unscaled: Vec<f64> = lam.iter().zip(scale).map(|(l, si)| l * si).collect();
        let cert = crate::qp::kkt::residuals(qp, &x, &unscaled).judged();
        let ok = cert <= self.s.target.max(self.s.tol);
        if ok {
            self.recovered = Some((lam, x));
        }
        ok
    }
}

impl<S: BoundStep> Iterative for Smalbe<'_, S> {
    fn best(&mut self) {
        match &mut self.best_lam {
            Some(b) => b.copy_from_slice(&self.measured_lam),
            None => self.best_lam = Some(self.measured_lam.clone()),
        }
    }

    fn back_to_best(&mut self) {
        if let Some(b) = self.best_lam.take() {
            self.s.lam = b;
            self.s.refresh();
            self.recovered = None;
        }
    }

    fn step(&mut self) -> Step {
        if self.measured_lam.len() == self.s.lam.len() {
            self.measured_lam.copy_from_slice(&self.s.lam);
        } else {
            self.measured_lam = self.s.lam.clone();
        }
        let (tol, ref_g) = (self.s.tol, self.s.ref_g);
        let mut gp = self.s.gp_norm();
        let (mut fe, mut fe_ref) = self.feas();
        let res = |gp: f64, fe: f64, fe_ref: f64| (gp / ref_g).max(fe / fe_ref);
        if gp <= tol * ref_g && fe <= tol * fe_ref {
            if !self.s.fresh {
                // Accept the stop only with an exact gradient.
                self.s.refresh();
                gp = self.s.gp_norm();
                (fe, fe_ref) = self.feas();
                self.step.restart(&self.s);
            }
            if gp <= tol * ref_g && fe <= tol * fe_ref {
                if self.certified() {
                    return Step::Done(Status::Converged, self.record(res(gp, fe, fe_ref)));
                }
                self.tightened += 1;
                self.s.tol *= 1e-2;
                log::debug!(
                    "{}: converged but not certified; tol tightened to {:.0e}",
                    self.s.name,
                    self.s.tol
                );
                return Step::Continue(self.record(res(gp, fe, fe_ref)));
            }
        }
        let r = res(gp, fe, fe_ref);
        if self.s.op.k() > 0 {
            // The floor 0.1·tol·‖h‖: below it the inner problem is solved to
            // the final precision, and M may have shrunk until M‖G̃λ̂‖ is
            // under rounding.
            let smalbe_tol = (self.mpar * fe).min(self.eta);
            if gp <= smalbe_tol.max(0.1 * tol * ref_g) {
                self.smalbe_update();
                return Step::Continue(self.record(r));
            }
            self.s.smalbe_tol = smalbe_tol;
        }
        match self.step.step(&mut self.s) {
            Ok(kind) => {
                if let Some(i) = KINDS.iter().position(|(k, _)| *k == kind) {
                    self.counts[i] += 1;
                }
                Step::Continue(self.record(r))
            }
            Err(msg) => Step::Done(Status::Failed(Failure::Breakdown(msg)), self.record(r)),
        }
    }
}

/// The initial SMALBE M, a compliance converting ‖G̃λ̂‖ (a force) into the
/// inner tolerance on ‖gᴾ‖ (a gap): ‖h‖/‖ẽ‖, capped by ‖PHP‖ so that it
/// stays finite when the loads do no work on the free rigid motions (ẽ = 0,
/// the rule for a partial kernel); invariant under scaling C, d or g.
fn smalbe_m0(ref_g: f64, e_norm: f64, hnorm: f64) -> f64 {
    ref_g / e_norm.max(ref_g / hnorm).max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::op::DENSE_CHUNK;
    use super::*;
    use crate::linalg::cholesky::Cholesky;
    use crate::qp::testing::two_blocks;

    /// The formed H (more rows than one pass of [`DENSE_CHUNK`]) applies as
    /// the solve with K does, to rounding, and is symmetric.
    #[test]
    fn the_formed_dual_hessian_applies_as_the_solves_do() {
        let qp = two_blocks(80, 6, true);
        let m = qp.m();
        assert!(m > DENSE_CHUNK, "{m} rows");
        let fac = Cholesky::new(&qp.c, &qp.kernel).unwrap();
        let h = std::sync::Arc::new(dense_h(&qp, &fac));
        let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
        let mut by_solves = DualOp::new(&qp, fac.clone(), r.clone(), "test").unwrap();
        let mut formed = DualOp::new(&qp, fac, r, "test").unwrap();
        formed.with_dense(h.clone());
        let v: Vec<f64> = (0..m).map(|i| ((i * 7 % 13) as f64) - 6.0).collect();
        let (a, b) = (by_solves.h(&v), formed.h(&v));
        let diff: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x - y).collect();
        assert!(
            norm(&diff) <= 1e-12 * norm(&a),
            "{:e} of {:e}",
            norm(&diff),
            norm(&a)
        );
        assert_eq!(formed.solves, 0, "the formed H solved with K");
        for i in 0..m {
            for j in 0..i {
                assert_eq!(h[i * m + j], h[j * m + i]);
            }
        }
    }

    /// G̃ has orthonormal rows, P annihilates them, PHP + ρQ is symmetric
    /// with eigenvalue ρ on range G̃ᵀ, and the power estimate of ‖PHP‖ is
    /// positive and at most trace H.
    #[test]
    fn dual_operator_structure() {
        let qp = two_blocks(6, 4, true);
        let r = orthonormal_kernel(&qp.c, &qp.kernel).unwrap();
        let fac = Cholesky::new(&qp.c, &qp.kernel).unwrap();
        let mut op = DualOp::new(&qp, fac, r, "test").unwrap();
        let (k, m) = (op.k(), qp.m());
        assert!(k > 0 && m > k);
        for a in 0..k {
            for b in 0..k {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((dot(&op.gt[a], &op.gt[b]) - want).abs() <= 1e-12);
            }
            let mut v = op.gt[a].clone();
            op.project(&mut v);
            assert!(norm(&v) <= 1e-12, "P G̃ᵀ ≠ 0");
        }
        let hnorm = op.norm_estimate();
        assert!(hnorm > 0.0);
        op.rho = 7.0 * hnorm;
        let u: Vec<f64> = (0..m).map(|i| ((i * 13 % 7) as f64) - 3.0).collect();
        let v: Vec<f64> = (0..m).map(|i| ((i * 5 % 11) as f64) - 4.5).collect();
        let (hu, hv) = (op.apply(&u), op.apply(&v));
        let asym = (dot(&u, &hv) - dot(&v, &hu)).abs();
        assert!(
            asym <= 1e-12 * norm(&u) * norm(&hv),
            "not symmetric: {asym:e}"
        );
        // (PHP + ρQ) G̃ᵀe₀ = ρ G̃ᵀe₀
        let g0 = op.gt[0].clone();
        let w = op.apply(&g0);
        let d: Vec<f64> = w.iter().zip(&g0).map(|(a, b)| a - op.rho * b).collect();
        assert!(norm(&d) <= 1e-10 * op.rho, "{:e}", norm(&d));
        // ‖PHP v‖ for a unit v: at most ‖PHP‖ ≤ ‖H‖ ≤ trace H (H ⪰ 0).
        op.rho = 0.0;
        let trace: f64 = (0..m)
            .map(|i| {
                let mut e = vec![0.0; m];
                e[i] = 1.0;
                op.h(&e)[i]
            })
            .sum();
        assert!(hnorm <= trace * (1.0 + 1e-12), "{hnorm} > trace {trace}");
    }
}
