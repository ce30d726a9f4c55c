//! The iterative path of ssn (`ssn_path = "iterative"`, docs/methods.md
//! §7.2): the same primal–dual active-set loop, with no sparse factor of
//! the size of C. The KKT system of a working set J is solved by the
//! augmented Lagrangian on K_J = C + A_JᵀΡA_J — x = K_J⁻¹(d + A_Jᵀ(Ρg_J − μ)),
//! μ ← μ + Ρ(A_J x − g_J) — each K_J solve by CG preconditioned with a
//! smoothed-aggregation multigrid of K_J ([`crate::linalg::amg`]) whose
//! coarse spaces carry the rigid motions of the bodies
//! ([`crate::qp::NearKernel`]). Memory is O(nnz C); work per step is a few
//! multigrid-preconditioned solves. Every tolerance is relative and every
//! decision is from counts and values, so the same input gives the same
//! bits. A J that leaves a rigid motion of a floating body free (A_J R rank
//! deficient) is refused as singular and the loop enlarges J, as on the
//! Schur path; a motion free on every row (a rolling body) is not solved
//! here (the direct paths are).

use super::coarse_start::{self, coarse_start};
use super::{
    candidates, free_modes, hold_free_modes, limit_changes, nested_set, next_set, stiffness_scale,
};
use crate::linalg::amg::{pcg_stall, Amg, AmgSettings, NearNull, PCG_STALL};
use crate::linalg::augmented::AugPattern;
use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::ordering::block_rcm;
use crate::linalg::sparse::Csr;
use crate::linalg::sparse::{norm, norm_inf};
use crate::qp::executor::{Iterative, Step};
use crate::qp::kkt::CONTACT_FLOOR;
use crate::qp::Failure;
use crate::qp::{Context, IterRecord, NearKernel, Output, QpError, QpProblem, Status};
use std::cell::RefCell;
use std::collections::HashSet;
use std::rc::Rc;
use std::time::Instant;

/// Relative residual of the K_J solves while J still moves (the set only
/// needs the signs of λ and of the gaps); the settled J is solved to the
/// settings' tolerance and certified.
const LOOSE: f64 = 1e-6;
/// ρ = RHO_ITERATIVE · max diag C. The direct paths take 100 (an exact
/// factor does not mind); here Ρ A_JᵀA_J x cancels against Ρ A_Jᵀg_J in the
/// residual of every CG step, and a larger ρ costs CG more steps than the
/// augmented-Lagrangian rounds it saves (three-body, 178 k DOFs: 147 CG
/// steps at 1, 220 at 10, 696 at 100; the rollers failed at 100).
pub(super) const RHO_ITERATIVE: f64 = 1.0;
/// Relative residual of the K_J solves of a working set far from the
/// answer (docs/methods.md §7.2, "Rough steps"; solid models): the first
/// J, and one that the last step moved by more than 1/ROUGH_MOVE of its
/// rows. Such a solve only has to rank the rows that enter or leave next;
/// at LOOSE the augmented Lagrangian spends ~12 rounds on it. A J that
/// settles on a rough solve is solved at LOOSE_SOLID before it is
/// certified. Hertz at 45 k / 163 k unknowns: 279 / 363 CG steps in all,
/// 105 / 97 with rough steps at 10⁻² and RHO_SOLID, 65 / 68 at 10⁻¹ with
/// inexact rounds and LOOSE_SOLID, the same J at the end.
const ROUGH: f64 = 1e-1;
/// LOOSE on a solid model: the rows' signs of a J near the answer are
/// decided at 10⁻⁴ (a misjudged sign shows in the certificate's tighter
/// solves, and the loop goes on; docs/methods.md §7.2).
const LOOSE_SOLID: f64 = 1e-4;
/// The loosest K_J solve of an inexact round (solid models, [`State::kkt`]).
const ROUND_LOOSEST: f64 = 1e-2;
/// See [`ROUGH`].
const ROUGH_MOVE: usize = 4;
/// ρ_j = RHO_SOLID · max diag C over row j's unknowns on a solid model
/// ([`rho_rows`]): with ρ per row the AL rounds converge faster at 10 than
/// at 1 and CG does not pay it back (Hertz 163 k: 363 → 256 CG steps;
/// the stack 114 → 92; docs/methods.md §7.2).
const RHO_SOLID: f64 = 10.0;
/// Augmented-Lagrangian updates of μ per KKT solve, at most.
const AL_MAX: usize = 60;
/// CG steps per K_J solve, at most (a multigrid-preconditioned CG on an
/// elastic body takes tens).
pub(super) const PCG_MAX: usize = 2000;
/// The multigrid of a set J' serves J when at most
/// max(STALE_MIN, |J|/STALE_DIV) rows differ.
const STALE_MIN: usize = 8;
const STALE_DIV: usize = 8;
/// Certification rounds of a settled J (each tightens the solves ×100).
const TIGHTEN_MAX: usize = 4;

/// Solve `qp` by ssn on the iterative path (module doc).
pub(super) fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    if qp.friction.is_some() {
        return Err(QpError::Unsupported(
            "ssn_path = \"iterative\" solves frictionless contact only; \
             use ssn_path = \"auto\" for friction (docs/methods.md §7.2)"
                .into(),
        ));
    }
    let t0 = Instant::now();
    // Everything below runs on the unknowns in a bandwidth-reducing order
    // (memory-bound sweeps; a mesh generator's numbering scatters
    // neighbours), and x is put back in the caller's order at the end.
    let unit: Vec<usize>;
    let blocks = match &qp.near {
        Some(nk) => nk.block_ptr.as_slice(),
        None => {
            unit = (0..=qp.n()).collect();
            &unit
        }
    };
    // A load step of the same C and A takes the last solve's order, kernel,
    // K_J pattern and multigrid from the workspace ([`Kept`]).
    let kernel_key = crate::linalg::cholesky::matrix_key(&[], &qp.kernel);
    let kept = ctx
        .ws
        .kept::<RefCell<Option<Kept>>>(KEPT_TAG)
        .and_then(|k| k.borrow_mut().take())
        .filter(|k| k.kernel_key == kernel_key && k.c.same_as(&qp.c) && k.a.same_as(&qp.a));
    let (perm, r, qpp, aug, hierarchy) = match kept {
        Some(k) => {
            let gather = |v: &[f64]| -> Vec<f64> { k.perm.iter().map(|&o| v[o]).collect() };
            let qpp = QpProblem {
                d: gather(&qp.d),
                g: qp.g.clone(),
                ..k.qpp
            };
            (k.perm, k.r, qpp, k.aug, Some(k.hierarchy))
        }
        None => {
            let perm = block_rcm(&qp.c, blocks);
            let r: Vec<Vec<f64>> = orthonormal_kernel(&qp.c, &qp.kernel)?
                .iter()
                .map(|z| perm.iter().map(|&o| z[o]).collect())
                .collect();
            // The permuted C lives only in the pattern of K_J (AugPattern); the
            // certificate reads the caller's C (one copy of C less: 2 GiB at 5 M nodes).
            let (qpp, aug) = permuted(qp, &perm);
            (perm, r, qpp, aug, None)
        }
    };
    let x0 = ctx
        .x0
        .map(|x| perm.iter().map(|&o| x[o]).collect::<Vec<f64>>());
    let diag = qp.c.diag();
    let mut st = State::new(
        (&qpp, qp, &perm),
        aug,
        &diag,
        &r,
        ctx.settings.tol,
        x0.as_deref(),
    );
    st.target = ctx.settings.kkt_target;
    st.reuse(hierarchy);
    if let (Some(lam), Some(_)) = (ctx.nested_lambda, ctx.x0) {
        st.start_nested(lam);
    }
    let mut exec = ctx.executor("ssn");
    let (status, iters) = exec.run(&mut st);
    log::debug!(
        "ssn iterative: {} multigrid hierarchies ({} updates), {} CG steps, {:.3} s of setup",
        st.builds,
        st.updates,
        st.cg_steps,
        st.t_setup
    );
    let t_all = t0.elapsed().as_secs_f64();
    let x = unpermute(&perm, &st.x);
    let (lambda, active) = (std::mem::take(&mut st.lam), std::mem::take(&mut st.in_j));
    let (cg_steps, t_setup) = (st.cg_steps, st.t_setup);
    let State {
        aug,
        amg,
        assembled,
        ..
    } = st;
    let qpp = QpProblem {
        d: vec![],
        g: vec![],
        ..qpp
    };
    ctx.ws.keep(
        KEPT_TAG,
        Rc::new(RefCell::new(Some(Kept {
            c: qp.c.clone(),
            a: qp.a.clone(),
            kernel_key,
            perm,
            r,
            qpp,
            aug,
            hierarchy: Hierarchy { amg, assembled },
        }))),
    );
    Ok(Output {
        x,
        lambda,
        lambda_t: vec![],
        active,
        status,
        iterations: iters,
        inner_iterations: cg_steps,
        log: exec.log,
        timings: vec![
            ("multigrid setup".into(), t_setup),
            ("iterate".into(), t_all - t_setup),
        ],
    })
}

/// What a solve leaves in the workspace for the next solve of the same C
/// and A (a load step; docs/methods.md §7.2, "Load steps"): the unknowns'
/// order, the basis of ker C, the permuted A with the near-null space, the
/// pattern of K_J and the multigrid with the working set it was last
/// updated for. Taken out of the workspace by the solve that uses it and
/// put back at its end.
struct Kept {
    c: Csr,
    a: Csr,
    kernel_key: u64,
    perm: Vec<usize>,
    r: Vec<Vec<f64>>,
    /// The permuted problem without d and g.
    qpp: QpProblem,
    aug: AugPattern,
    hierarchy: Hierarchy,
}

/// The multigrid of a [`Kept`] and the working set K_J was assembled for.
struct Hierarchy {
    amg: Option<(Vec<bool>, Amg)>,
    assembled: Option<Vec<bool>>,
}

/// The workspace slot of [`Kept`].
const KEPT_TAG: u64 = 0x7373_6e5f_6974_6572;

struct State<'a> {
    /// The permuted problem; its C is empty (see `aug`).
    qp: &'a QpProblem,
    /// The caller's problem, on which the certificate is measured, and the
    /// order (new → old) `qp` is in.
    orig: &'a QpProblem,
    perm: &'a [usize],
    aug: AugPattern,
    rho: Vec<f64>,
    /// (A R)ᵢ for every row: J holds the floating bodies iff these rows of J
    /// span ℝᵏ.
    ar: Vec<Vec<f64>>,
    tol: f64,
    /// The certificate's target (`Settings::kkt_target`).
    target: f64,
    /// The stiffness scale c (mean positive diagonal of C).
    cpar: f64,
    x: Vec<f64>,
    lam: Vec<f64>,
    in_j: Vec<bool>,
    last_ok: Option<Vec<bool>>,
    history: HashSet<Vec<bool>>,
    single: bool,
    /// A solid model (six near-null modes): per-row ρ, the hierarchy
    /// follows J, and growth-limited steps are solved ROUGH-ly.
    solid: bool,
    /// Solve the next K_J ROUGH-ly: the first J, and a J that the last step
    /// moved by more than 1/ROUGH_MOVE of its rows (solid models).
    rough: bool,
    cg_steps: usize,
    /// The multigrid of K_J for the working set it was built for.
    amg: Option<(Vec<bool>, Amg)>,
    /// The working set K_J was last assembled for (in `aug`).
    assembled: Option<Vec<bool>>,
    /// Multigrid hierarchies built, and updated (`follow_j`).
    builds: usize,
    updates: usize,
    /// The most CG steps one loose K_J solve took.
    pcg_max_seen: usize,
    t_setup: f64,
    /// The coarse start was tried (solid models, before the first step).
    coarse_tried: bool,
    /// At most max(GROW_MIN, grow·|J|) rows enter J per step: 1, and
    /// [`coarse_start::GROW`] from a coarse start (J then grows from a set
    /// that is short of the answer, not from a point spring).
    grow: usize,
}

/// How one KKT solve ended.
enum Kkt {
    /// (λ, x) to the asked tolerance.
    Solved(Vec<f64>, Vec<f64>),
    /// J leaves a rigid motion free (or K_J is not positive definite).
    Singular,
    /// The solves did not reach the tolerance (message).
    Stalled(String),
}

impl<'a> State<'a> {
    /// The first argument: (the permuted QP without C, which lives in `aug`; the
    /// caller's QP; the order new → old), `diag` = diag C (any order).
    fn new(
        (qp, orig, perm): (&'a QpProblem, &'a QpProblem, &'a [usize]),
        aug: AugPattern,
        diag: &[f64],
        r: &[Vec<f64>],
        tol: f64,
        x0: Option<&[f64]>,
    ) -> State<'a> {
        let m = qp.m();
        let cmax = norm_inf(diag);
        let rho = rho_rows(orig, diag, cmax, RHO_SOLID);
        let cpar = stiffness_scale(diag);
        let solid = orig.has_solid_modes();
        let ar = (0..m)
            .map(|i| r.iter().map(|rl| qp.a.row_dot(i, rl)).collect())
            .collect();
        State {
            qp,
            aug,
            orig,
            perm,
            rho,
            ar,
            tol,
            target: crate::qp::settings::DEFAULT_KKT_TARGET,
            cpar,
            x: x0.map_or_else(|| vec![0.0; qp.n()], <[f64]>::to_vec),
            lam: vec![0.0; m],
            in_j: qp.g.iter().map(|&g| g <= 0.0).collect(),
            last_ok: None,
            history: HashSet::new(),
            single: false,
            solid,
            rough: solid,
            cg_steps: 0,
            pcg_max_seen: 0,
            amg: None,
            assembled: None,
            builds: 0,
            updates: 0,
            t_setup: 0.0,
            coarse_tried: false,
            grow: 1,
        }
    }

    /// Start from the last load step's multigrid (`hierarchy`; [`State::prepare`]
    /// updates or rebuilds it for the first J). The last step's working set
    /// (`Context::active0`) is not a start here: it falls short of this
    /// step's, the first prediction from it overshoots, and the overshoot
    /// shrinks by a ring of rows per step (Hertz 163 k in three load steps:
    /// 7 and 7 Newton steps on the second and third where the coarse start
    /// takes 5 and 5; docs/methods.md §7.2, "Load steps").
    fn reuse(&mut self, hierarchy: Option<Hierarchy>) {
        if let Some(h) = hierarchy {
            (self.amg, self.assembled) = (h.amg, h.assembled);
        }
    }

    /// The nested start (docs/methods.md §7.2, "The nested start"): x0 and
    /// λ̂ interpolated from the answer on a coarser mesh of the same model.
    /// J0 is the set the loop's own rule predicts from that pair,
    /// F = λ̂ + c(Ax0 − g) > 0, and replaces the coarse start; since J0 is
    /// near the answer, its first K_J is solved at the loop's loose
    /// tolerance, not ROUGH-ly (a rough solve that settles is solved again).
    fn start_nested(&mut self, lam: &[f64]) {
        let qp = self.qp;
        self.in_j = nested_set(qp, &self.x, lam, self.cpar);
        self.lam = (0..qp.m())
            .map(|i| if self.in_j[i] { lam[i].max(0.0) } else { 0.0 })
            .collect();
        self.coarse_tried = true;
        self.rough = false;
        self.grow = coarse_start::GROW;
        log::debug!(
            "ssn iterative: nested start, |J0| = {}",
            self.in_j.iter().filter(|b| **b).count()
        );
    }

    /// True when the rows of J restrain every rigid motion of ker C
    /// ([`free_modes`] finds none free).
    fn holds_kernel(&self, in_j: &[bool]) -> bool {
        free_modes(&self.ar, in_j).is_empty()
    }

    /// The KKT system of J (module doc) from the current (x, λ), the K_J
    /// solves to relative residual `rtol`; the gaps of J to `rtol` of their
    /// scale.
    fn kkt(&mut self, in_j: &[bool], rtol: f64) -> Kkt {
        // A tightened solve that needs more than this has met its rounding
        // floor (counts only: the same on every run).
        let max_iter = if rtol < LOOSE {
            (4 * self.pcg_max_seen + 50).min(PCG_MAX)
        } else {
            PCG_MAX
        };
        let jset = match self.prepare(in_j) {
            Ok(jset) => jset,
            Err(k) => return k,
        };
        let qp = self.qp;
        let Some((_, amg)) = self.amg.as_ref() else {
            return Kkt::Singular; // not reached: built above
        };
        let k = self.aug.matrix();
        let prec = |r: &[f64], z: &mut [f64]| amg.apply(r, z);
        let mut mu: Vec<f64> = jset.iter().map(|&j| self.lam[j]).collect();
        let mut x = self.x.clone();
        // Scale of the gaps: max(|A_J x|, |g_J|) through |A|.
        let gscale = |x: &[f64]| -> f64 {
            jset.iter()
                .map(|&j| {
                    let (c, v) = qp.a.row(j);
                    let ax: f64 = c.iter().zip(v).map(|(&kk, &a)| (a * x[kk]).abs()).sum();
                    ax.max(qp.g[j].abs())
                })
                .fold(0.0, f64::max)
        };
        // b = d + A_Jᵀ(Ρg_J − μ): the part without μ once, A_Jᵀμ per round.
        let mut row_w = vec![0.0; qp.m()];
        for &j in &jset {
            row_w[j] = self.rho[j] * qp.g[j];
        }
        let mut b0 = qp.d.clone();
        qp.a.mul_t_add(&row_w, &mut b0);
        let dnorm = norm(&qp.d);
        // On a solid model each round's K_J solve is only as accurate as the
        // gaps the last round left (relative; at the start, J's gaps at the
        // warm x), within [rtol, ROUND_LOOSEST]: inexact rounds
        // (docs/methods.md §7.2, "Inexact rounds").
        let mut gap_rel = {
            let g0 = jset
                .iter()
                .map(|&j| (qp.a.row_dot(j, &x) - qp.g[j]).abs())
                .fold(0.0, f64::max);
            g0 / gscale(&x).max(f64::MIN_POSITIVE)
        };
        for round in 0..AL_MAX {
            let rround = if self.solid {
                gap_rel.min(ROUND_LOOSEST).max(rtol)
            } else {
                rtol
            };
            for (&j, &m) in jset.iter().zip(&mu) {
                row_w[j] = m;
            }
            let atmu = qp.a.mul_t(&row_w);
            let b: Vec<f64> = b0.iter().zip(&atmu).map(|(b, t)| b - t).collect();
            // The tolerance is on the contact forces, the scale of the
            // certificate's contact balance (max(‖A_Jᵀμ‖, 10⁻⁴‖d‖), §8.4),
            // not on b, whose A_JᵀΡg_J part cancels against Ρ A_JᵀA_J x and
            // whose loads spread over every unknown.
            let (fscale, bn) = (norm(&atmu).max(CONTACT_FLOOR * dnorm), norm(&b));
            let rt = if fscale > 0.0 && bn > 0.0 {
                (rround * fscale / bn).min(rround).max(rround.min(1e-13))
            } else {
                rround
            };
            let rep = pcg_stall(k, &b, &mut x, &prec, rt, max_iter, PCG_STALL);
            self.cg_steps += rep.iterations;
            if rtol >= LOOSE {
                self.pcg_max_seen = self.pcg_max_seen.max(rep.iterations);
            }
            // A solve stopped at its rounding floor still decides signs
            // (the certificate judges the end); anything else is a failure.
            // (pcg_stall only stalls below √rtol of ‖b‖).
            let floor_ok = rep.stalled;
            if !(rep.converged || floor_ok) || !rep.rel_residual.is_finite() {
                return Kkt::Stalled(format!(
                    "ssn iterative: CG on K_J stopped at relative residual {:.2e} after {} steps \
                     (a stiffness contrast beyond what the multigrid resolves; ssn_path = \"auto\" factors K_J instead)",
                    rep.rel_residual, rep.iterations
                ));
            }
            let gap: Vec<f64> = jset
                .iter()
                .map(|&j| qp.a.row_dot(j, &x) - qp.g[j])
                .collect();
            for ((m, &j), gj) in mu.iter_mut().zip(&jset).zip(&gap) {
                *m += self.rho[j] * gj;
            }
            let worst = norm_inf(&gap);
            let scale = gscale(&x).max(f64::MIN_POSITIVE);
            log::trace!(
                "ssn iterative: AL round {round} (tol {rround:.0e}): {} CG steps, gap {:.2e} of {:.2e}",
                rep.iterations,
                worst,
                scale
            );
            gap_rel = worst / scale;
            // A round solved looser than rtol does not end the solve.
            if (worst <= rtol * scale && rround <= rtol) || jset.is_empty() || floor_ok {
                let mut lam = vec![0.0; qp.m()];
                for (&j, &m) in jset.iter().zip(&mu) {
                    lam[j] = m;
                }
                if lam.iter().chain(&x).any(|v| !v.is_finite()) {
                    return Kkt::Stalled("ssn iterative: the KKT solve is not finite".into());
                }
                return Kkt::Solved(lam, x);
            }
        }
        Kkt::Stalled(format!(
            "ssn iterative: the gaps of J did not close in {AL_MAX} augmented-Lagrangian rounds"
        ))
    }

    /// A multigrid of K_J for J = `in_j` (K_J assembled, |J| = `nj`):
    /// the hierarchy kept, updated (solid models) or rebuilt.
    fn ensure_amg(&mut self, in_j: &[bool], nj: usize) -> Result<(), String> {
        let qp = self.qp;
        // The multigrid is rebuilt only when J has moved by more than
        // `stale_max` rows from the set it was built for: K_J then differs
        // from that K by a low-rank term, which costs CG a few steps where
        // a rebuild costs tens of V-cycles (counts only: same bits on every run).
        // On a solid model (six near-null modes) the hierarchy follows J
        // instead: its operators are updated by the rows that moved with
        // the prolongators kept (`Amg::update`, docs/methods.md §7.2), a
        // fraction of a rebuild (163 k unknowns: 4–5 s a rebuild).
        if self.solid {
            self.follow_j(in_j);
        }
        let moved = self
            .amg
            .as_ref()
            .map(|(set, _)| set.iter().zip(in_j).filter(|(a, b)| a != b).count());
        let stale_max = STALE_MIN.max(nj / STALE_DIV);
        if moved.is_none_or(|c| c > stale_max) {
            self.amg = None; // free the old hierarchy first
            let t = Instant::now();
            let near = qp.near.as_ref().map(|nk| NearNull {
                block_ptr: &nk.block_ptr,
                modes: &nk.modes,
            });
            let nm = qp.near.as_ref().map_or(1, |nk| nk.modes.len());
            let amg = match Amg::new(self.aug.matrix(), near, &AmgSettings::for_modes(nm)) {
                Ok(a) => a,
                // Not a free motion (that is `holds_kernel`'s verdict
                // above): say what failed instead of blaming the bodies.
                Err(e) => {
                    return Err(format!(
                        "ssn iterative: no multigrid of K_J ({e}; at a large stiffness contrast rounding makes it so); ssn_path = \"auto\" factors K_J instead"
                    ))
                }
            };
            self.t_setup += t.elapsed().as_secs_f64();
            self.builds += 1;
            log::debug!(
                "ssn iterative: multigrid of K_J ({} rows in J): levels {:?}, operator complexity {:.2}, {:.3} s",
                nj,
                amg.sizes(),
                amg.operator_complexity(),
                t.elapsed().as_secs_f64()
            );
            self.amg = Some((in_j.to_vec(), amg));
        }
        Ok(())
    }

    /// K_J assembled for J = `in_j` and its multigrid ready (kept, updated
    /// or rebuilt); J's rows. Singular when J leaves a rigid motion free,
    /// Stalled when no multigrid can be built.
    fn prepare(&mut self, in_j: &[bool]) -> Result<Vec<usize>, Kkt> {
        if !self.holds_kernel(in_j) {
            return Err(Kkt::Singular);
        }
        let jset: Vec<usize> = (0..in_j.len()).filter(|&i| in_j[i]).collect();
        if self.assembled.as_deref() != Some(in_j) {
            self.aug.assemble(jset.iter().copied(), &self.rho);
            self.assembled = Some(in_j.to_vec());
        }
        self.ensure_amg(in_j, jset.len()).map_err(Kkt::Stalled)?;
        Ok(jset)
    }

    /// The coarse start (solid models; [`coarse_start`]): J, x and λ from
    /// the contact problem on a coarse level of the hierarchy of the first
    /// K_J (the coarsest with at least a thousandth of the unknowns). Left as it was when
    /// that J leaves a body free or no hierarchy is built (the first KKT
    /// solve then says why).
    fn start_coarse(&mut self) {
        self.coarse_tried = true;
        let in_j = self.in_j.clone();
        if self.prepare(&in_j).is_err() {
            return;
        }
        let Some((_, amg)) = self.amg.as_ref() else {
            return;
        };
        let t = Instant::now();
        match coarse_start(amg, self.qp, &in_j, &self.rho) {
            Some(cs) => {
                log::debug!(
                    "ssn iterative: coarse start on {} unknowns: {} steps, |J| = {}, {:.3} s",
                    cs.unknowns,
                    cs.steps,
                    cs.in_j.iter().filter(|b| **b).count(),
                    t.elapsed().as_secs_f64()
                );
                (self.in_j, self.x, self.lam) = (cs.in_j, cs.x, cs.lam);
                self.grow = coarse_start::GROW;
            }
            None => log::debug!(
                "ssn iterative: no coarse start (a coarse matrix is not positive definite, or a row falls outside the sparse level's pattern)"
            ),
        }
        self.t_setup += t.elapsed().as_secs_f64();
    }

    /// Update the hierarchy, if any, from its set to `in_j` (K_J is
    /// assembled for `in_j`); a failed update drops it (a rebuild follows).
    fn follow_j(&mut self, in_j: &[bool]) {
        let Some((set, amg)) = self.amg.as_mut() else {
            return;
        };
        let qp = self.qp;
        let changes: Vec<(f64, &[usize], &[f64])> = (0..qp.m())
            .filter(|&j| set[j] != in_j[j])
            .map(|j| {
                let (c, v) = qp.a.row(j);
                (if in_j[j] { self.rho[j] } else { -self.rho[j] }, c, v)
            })
            .collect();
        if changes.is_empty() {
            return;
        }
        let t = Instant::now();
        match amg.update(self.aug.matrix(), &changes) {
            Ok(()) => {
                set.copy_from_slice(in_j);
                self.updates += 1;
            }
            Err(e) => {
                log::debug!("ssn iterative: multigrid not updated ({e}); rebuilt");
                self.amg = None;
            }
        }
        self.t_setup += t.elapsed().as_secs_f64();
    }

    fn record(&self, residual: f64) -> IterRecord {
        IterRecord {
            iter: 0,
            residual,
            active: self.in_j.iter().filter(|b| **b).count(),
            inner: self.cg_steps,
        }
    }

    /// The KKT residuals of (x, λ) on the caller's problem (x put back).
    fn residuals(&self, x: &[f64], lam: &[f64]) -> crate::qp::Kkt {
        crate::qp::kkt::residuals(self.orig, &unpermute(self.perm, x), lam)
    }

    /// Solve J tighter until (x, λ) is certified or the solves stop gaining.
    fn certify(&mut self) -> Result<f64, String> {
        let mut cert = self.residuals(&self.x, &self.lam).judged();
        let mut rtol = LOOSE;
        for _ in 0..TIGHTEN_MAX {
            if cert <= self.tol {
                break;
            }
            rtol = (rtol * 1e-2).max(1e-15);
            let in_j = self.in_j.clone();
            match self.kkt(&in_j, rtol) {
                Kkt::Solved(lam, x) => {
                    let k = self.residuals(&x, &lam);
                    let c = k.judged();
                    log::debug!(
                        "ssn iterative: tightened to {rtol:.0e}: KKT residual {cert:.2e} → {c:.2e} ({k:?})"
                    );
                    if c.is_nan() || c >= cert {
                        break;
                    }
                    (self.x, self.lam, cert) = (x, lam, c);
                }
                Kkt::Singular => return Err("ssn iterative: K_J became singular".into()),
                // The rounding floor of K_J's solves (a soft body under a
                // stiff one): keep the last answer, the certificate judges.
                Kkt::Stalled(msg) => {
                    log::debug!("{msg}; keeping the answer of {:.0e}", rtol * 1e2);
                    break;
                }
            }
        }
        Ok(cert)
    }
}

impl Iterative for State<'_> {
    fn step(&mut self) -> Step {
        let m = self.qp.m();
        if self.solid && !self.coarse_tried {
            self.start_coarse();
        }
        let mut solved = None;
        for cand in candidates(&self.in_j, self.last_ok.as_deref()) {
            let rtol = match (self.rough, self.solid) {
                (true, _) => ROUGH,
                (false, true) => LOOSE_SOLID,
                (false, false) => LOOSE,
            };
            match self.kkt(&cand, rtol) {
                Kkt::Solved(lam, x) => {
                    solved = Some((cand, lam, x));
                    break;
                }
                Kkt::Singular => continue,
                Kkt::Stalled(msg) => {
                    return Step::Done(
                        Status::Failed(Failure::Breakdown(msg)),
                        self.record(f64::NAN),
                    );
                }
            }
        }
        let Some((jused, lam, x)) = solved else {
            return Step::Done(
                Status::Failed(Failure::Breakdown(
                    "ssn iterative: even with every contact row active, a rigid motion of a floating body \
                     is free (A·R rank deficient) or K_J is not positive definite; the direct paths \
                     (ssn_path = \"auto\") solve models whose bodies may roll"
                        .into(),
                )),
                self.record(f64::NAN),
            );
        };
        self.in_j = jused.clone();
        self.last_ok = Some(jused.clone());
        self.history.insert(jused);
        self.lam = lam;
        self.x = x;
        let qp = self.qp;
        let mut ax: Vec<f64> = (0..m).map(|i| qp.a.row_dot(i, &self.x)).collect();
        let mut new_j = next_set(&self.in_j, &self.lam, &ax, &qp.g, self.tol);
        let changed = new_j.iter().zip(&self.in_j).filter(|(a, b)| a != b).count();
        let residual = changed as f64 / m.max(1) as f64;
        log::debug!(
            "ssn iterative: step {}: |J| = {}, {changed} rows change, {} CG steps so far",
            self.history.len(),
            self.in_j.iter().filter(|b| **b).count(),
            self.cg_steps
        );
        if new_j == self.in_j && self.rough {
            // Settled on a rough solve: solve the same J loosely first.
            self.rough = false;
            return Step::Continue(self.record(residual));
        }
        if new_j == self.in_j {
            let cert = match self.certify() {
                Ok(c) => c,
                Err(msg) => {
                    return Step::Done(
                        Status::Failed(Failure::Breakdown(msg)),
                        self.record(f64::NAN),
                    )
                }
            };
            ax = (0..m).map(|i| qp.a.row_dot(i, &self.x)).collect();
            new_j = next_set(&self.in_j, &self.lam, &ax, &qp.g, self.tol);
            if new_j != self.in_j {
                // The loose solve misjudged a row's sign: go on from the
                // tightened answer.
                log::debug!("ssn iterative: the tightened solution moves J; continuing");
            } else if cert.is_nan() || cert > self.target.max(self.tol) {
                return Step::Done(
                    Status::Failed(Failure::Uncertified {
                        residual: cert,
                        target: self.target,
                    }),
                    self.record(cert),
                );
            } else {
                return Step::Done(Status::Converged, self.record(cert));
            }
        }
        // The growth limit and the anti-cycling rule of the direct paths,
        // on F = λ + c(Ax − g), c the mean stiffness.
        let fval: Vec<f64> = (0..m)
            .map(|i| self.lam[i] + self.cpar * (ax[i] - qp.g[i]))
            .collect();
        // A J that moves by more than a quarter is far from the answer: on
        // a solid model the next K_J is solved only ROUGH-ly (counts only).
        let size = self.in_j.iter().filter(|&&b| b).count();
        self.rough = self.solid && changed * ROUGH_MOVE > size;
        let new_j = limit_changes(
            &self.in_j,
            new_j,
            &fval,
            &self.history,
            &mut self.single,
            self.grow,
        );
        self.in_j = hold_free_modes(new_j, &self.in_j, &self.ar, &self.lam, &ax, &qp.g);
        Step::Continue(self.record(residual))
    }
}

/// ρ of every row: RHO_ITERATIVE · max diag C; on a solid model (six
/// near-null modes) `factor` · max of diag C over the row's own unknowns instead
/// (docs/methods.md §7.2): diag C scales as E·h in 3D, so the largest
/// diagonal, on the coarsest elements, would make the rows of a fine
/// contact zone penalty springs (as E alone in 2D, where ρ stays global so
/// that plane models keep their bits). `diag` in the order of `qp`.
pub(super) fn rho_rows(qp: &QpProblem, diag: &[f64], cmax: f64, factor: f64) -> Vec<f64> {
    let global = RHO_ITERATIVE * if cmax > 0.0 { cmax } else { 1.0 };
    if !qp.has_solid_modes() {
        return vec![global; qp.m()];
    }
    (0..qp.m())
        .map(|j| {
            let c = qp.a.row(j).0.iter().map(|&k| diag[k]).fold(0.0, f64::max);
            if c > 0.0 {
                factor * c
            } else {
                global
            }
        })
        .collect()
}

/// `qp` on the unknowns in the order `perm` (new → old): A ↦ APᵀ, d, ker C
/// and the near-null space permuted alike, rows and g unchanged; PCPᵀ only
/// as the pattern of K_J = PCPᵀ + AᵀΡA (the returned QP's C is empty, n×n).
/// Blocks of `near` must be whole in `perm` ([`block_rcm`] keeps them).
pub(super) fn permuted(qp: &QpProblem, perm: &[usize]) -> (QpProblem, AugPattern) {
    let n = qp.n();
    let mut inv = vec![0usize; n];
    for (new, &old) in perm.iter().enumerate() {
        inv[old] = new;
    }
    let remap = |m: &Csr, rows: &mut dyn Iterator<Item = usize>| -> Csr {
        let mut indptr = vec![0usize];
        let mut indices = Vec::with_capacity(m.nnz());
        let mut data = Vec::with_capacity(m.nnz());
        let mut row: Vec<(usize, f64)> = Vec::new();
        for i in rows {
            let (c, v) = m.row(i);
            row.clear();
            row.extend(c.iter().map(|&j| inv[j]).zip(v.iter().copied()));
            row.sort_unstable_by_key(|e| e.0);
            for &(j, x) in &row {
                indices.push(j);
                data.push(x);
            }
            indptr.push(indices.len());
        }
        Csr {
            nrows: indptr.len() - 1,
            ncols: m.ncols,
            indptr: indptr.into(),
            indices: indices.into(),
            data: data.into(),
        }
    };
    let gather = |v: &[f64]| -> Vec<f64> { perm.iter().map(|&o| v[o]).collect() };
    let near = qp.near.as_ref().map(|nk| {
        let mut block_ptr = vec![0usize];
        let mut i = 0;
        while i < n {
            // the block of unknown perm[i] in the caller's blocks, whole
            let old = perm[i];
            let b = nk.block_ptr.partition_point(|&s| s <= old) - 1;
            i += nk.block_ptr[b + 1] - nk.block_ptr[b];
            block_ptr.push(i);
        }
        NearKernel {
            block_ptr,
            modes: nk.modes.iter().map(|z| gather(z)).collect(),
        }
    });
    let a = remap(&qp.a, &mut (0..qp.m()));
    let aug = AugPattern::new(&remap(&qp.c, &mut perm.iter().copied()), &a);
    let empty = Csr {
        nrows: n,
        ncols: n,
        indptr: vec![0; n + 1].into(),
        indices: vec![].into(),
        data: vec![].into(),
    };
    let qpp = QpProblem {
        c: empty,
        d: gather(&qp.d),
        a,
        g: qp.g.clone(),
        kernel: qp.kernel.iter().map(|z| gather(z)).collect(),
        friction: None,
        near,
    };
    (qpp, aug)
}

/// x in the caller's order from x in the order `perm` (new → old).
fn unpermute(perm: &[usize], x: &[f64]) -> Vec<f64> {
    let mut xo = vec![0.0; x.len()];
    for (&o, &v) in perm.iter().zip(x) {
        xo[o] = v;
    }
    xo
}
