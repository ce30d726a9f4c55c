//! The dual of a frictional problem with box constraints (docs/methods.md
//! §9.2; Dostál, Kozubek, Markopoulos et al., "Scalable TFETI algorithm for
//! two-dimensional multibody contact problems with friction", JCAM 2010).
//!
//! The Tresca problem min ½xᵀCx − xᵀd + Σ sᵢ|(Tx − t0)ᵢ| s.t. Ax ≤ g has the
//! dual min ½μᵀBC⁻¹Bᵀμ − μᵀ(BC⁻¹d − c) over λ_n ≥ 0, −s ≤ λ_t ≤ s, with
//! B = [A; T], c = [g; t0], μ = [λ_n; λ_t] (and Rᵀ(d − Bᵀμ) = 0 for a
//! floating body, SMALBE's equality): the frictionless host with the
//! tangential rows stacked under the contact rows and an upper bound on
//! them. Coulomb is a sequence of such Tresca problems, s = μ_f·λ_n of the
//! previous one, the first one glued (s = ∞), each warm-started from the
//! last multipliers: the outer loop of §9.1 shared with `ssn`
//! ([`crate::qp::coulomb`]), of which this file is the Tresca solve.

use super::{dense_h, row_scaling_of, row_weights_of, BoundStep, BoxBounds, DualOp, Smalbe};
use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::sparse::Csr;
use crate::qp::coulomb::{self, Bound, Tresca, TrescaStep};
use crate::qp::{Context, Output, QpError, QpProblem};
use std::time::Instant;

/// The Coulomb loop stops at a relative change of s ≤ COULOMB_TOL_FACTOR·tol
/// ([`TrescaStep::resolution`]): each Tresca solve is accurate to tol in
/// the dual gradient only, and on the inclined plane of tests/friction.rs
/// at tol = 10⁻¹⁰ the change stagnated at 4.7·tol.
const COULOMB_TOL_FACTOR: f64 = 100.0;

/// The dual Hessian H = B K⁻¹ Bᵀ of the stacked rows is formed once
/// ([`dense_h`], 2m solves' worth) when B has at most DENSE_RATIO·√n rows
/// (ssn's frictional dual form takes the same border, docs/methods.md
/// §9.2) and at most DENSE_MAX (8·DENSE_MAX² bytes): then every step of
/// every Tresca solve is a dense product instead of a solve with K.
const DENSE_RATIO: f64 = 48.0;
/// See [`DENSE_RATIO`].
const DENSE_MAX: usize = 4096;

/// Solve the frictional `qp` on the box-constrained dual with the bound
/// steps `make` builds (one per Tresca solve); returns x and [λ_n; λ_t].
pub(crate) fn solve_friction<S: BoundStep>(
    qp: &QpProblem,
    ctx: &mut Context,
    make: impl FnMut() -> S,
    name: &'static str,
) -> Result<Output, QpError> {
    let Some(fr) = qp.friction.as_ref() else {
        return Err(QpError::BadParameter(format!(
            "{name}: the box-constrained dual needs friction"
        )));
    };
    let m = qp.m();
    let t_start = Instant::now();
    // B = [A; T], c = [g; t0], rows scaled as in the frictionless host.
    let mut trip = Vec::with_capacity(qp.a.data.len() + fr.t.data.len());
    for (off, mat) in [(0, &qp.a), (m, &fr.t)] {
        for i in 0..mat.nrows {
            let (cols, vals) = mat.row(i);
            trip.extend(cols.iter().zip(vals).map(|(&j, &v)| (off + i, j, v)));
        }
    }
    let k = fr.frame.rows();
    let mut b = Csr::from_triplets(m + fr.t.nrows, qp.n(), &trip);
    let mut sc = row_scaling_of(&qp.c, &b);
    if k == 2 {
        pair_scaling(&qp.c, &b, m, &mut sc);
    }
    for (i, si) in sc.iter().enumerate() {
        for v in &mut b.data[b.indptr[i]..b.indptr[i + 1]] {
            *v *= si;
        }
    }
    let mut g: Vec<f64> =
        qp.g.iter()
            .chain(&fr.t0)
            .zip(&sc)
            .map(|(g, s)| g * s)
            .collect();
    // A tangential row whose unknowns are all prescribed (B's row is empty:
    // where a fault ends on a boundary that moves it, as the geodynamic
    // model's plates do) has a prescribed slip v = −t0 ≠ 0 in a load step.
    // In the dual its gradient is the constant t0 (H's row is zero): its
    // multiplier can only run to its bound, ᾱ·|t0| an expansion step
    // (~10¹² away, never when glued), while the constant stays in ‖gᴾ‖:
    // at 1.7–6.8·10⁻¹⁰ of its scale it held the Tresca solves of the
    // geodynamic model's load steps above tol = 10⁻¹⁰ until they
    // stagnated, and at μ = 0.1, 0.2 and 0.3 the Coulomb loop gave up
    // (docs/methods.md §9.1). Its answer is known: it slips,
    // λ_t = s·sign v (0 when glued). So the host sees it with a zero
    // offset (it holds nothing and moves nothing) and its λ_t is set after
    // each solve ([`DualTresca::prescribed`]). A zero row without an
    // offset (a symmetry line) is left as it was.
    // In 3D the pair of a contact point is prescribed when both its rows
    // are empty: v = −t0 (a 2-vector), λ_t = s·v/‖v‖; a pair with one empty
    // row is left to the host (docs/methods.md §12.4).
    let mut prescribed = vec![];
    for (c, rows) in (m..m + fr.t.nrows)
        .collect::<Vec<_>>()
        .chunks(k)
        .enumerate()
    {
        let empty = rows.iter().all(|&i| b.row(i).1.iter().all(|&v| v == 0.0));
        if empty && rows.iter().any(|&i| g[i] != 0.0) {
            let dir: Vec<f64> = match rows {
                [i] => vec![-g[*i].signum()],
                _ => {
                    // One scale for the pair: the direction of the scaled
                    // offsets is that of t0.
                    let v: Vec<f64> = rows.iter().map(|&i| -g[i]).collect();
                    let n = crate::qp::tangential_norm(&v);
                    v.iter().map(|e| e / n).collect()
                }
            };
            prescribed.push((c, dir));
            for &i in rows {
                g[i] = 0.0;
            }
        }
    }
    let sq = QpProblem {
        c: Csr::zeros(0, 0),
        d: qp.d.clone(),
        a: b,
        g,
        kernel: vec![],
        friction: None,
        near: None,
    };
    let mut step = DualTresca {
        qp,
        frame: fr.frame,
        sq: &sq,
        sc,
        ctx,
        make,
        name,
        lam0: None,
        prescribed,
        kernel: None,
        hnorm: None,
        dense: None,
    };
    let target = ctx.settings.kkt_target;
    let proven = coulomb::certificate(qp);
    let mut out = coulomb::solve(fr, &mut step, name, &proven, target)?;
    out.timings = vec![("iterate".into(), t_start.elapsed().as_secs_f64())];
    Ok(out)
}

/// One scale for the two tangential rows of each contact point (rows m + 2i,
/// m + 2i + 1 of `b`), so that the disc ‖λ_t‖ ≤ s stays a disc in the
/// scaled multipliers (docs/methods.md §12.4): 1/√h̄ with h̄ the mean of the
/// pair's Jacobi estimates hᵢ = bᵢᵀdiag(C)⁻¹bᵢ (of those that are
/// positive; 1 when neither is).
fn pair_scaling(c: &Csr, b: &Csr, m: usize, sc: &mut [f64]) {
    let h = row_weights_of(c, b);
    for j in (m..b.nrows.saturating_sub(1)).step_by(2) {
        let ok: Vec<f64> = h[j..j + 2]
            .iter()
            .copied()
            .filter(|h| *h > 0.0 && h.is_finite())
            .collect();
        let s = if ok.is_empty() {
            1.0
        } else {
            1.0 / (ok.iter().sum::<f64>() / ok.len() as f64).sqrt()
        };
        sc[j] = s;
        sc[j + 1] = s;
    }
}

/// What the frictional dual derives from C, B and ker C alone, kept in the
/// workspace for the next solve of the same matrices (a load step).
struct KeptHessian {
    /// C and the scaled stacked rows B (clones share their arrays).
    c: Csr,
    b: Csr,
    /// [`crate::linalg::cholesky::matrix_key`] of ker C's basis.
    kernel_key: u64,
    /// H = B K⁻¹ Bᵀ ([`dense_h`]).
    h: std::sync::Arc<Vec<f64>>,
    /// ‖PHP‖ ([`BoxBounds::hnorm`]).
    hnorm: f64,
}

/// The workspace slot of [`KeptHessian`].
const KEPT_HESSIAN_TAG: u64 = 0x6d70_7267_705f_6873;

/// The Tresca solve of the dual: the host on the stacked rows [A; T] with
/// the box |λ_t| ≤ s, warm-started from the last multipliers.
struct DualTresca<'q, 'c, 'a, F> {
    qp: &'q QpProblem,
    /// One tangential row per contact row (2D) or a pair (3D).
    frame: crate::qp::Frame,
    /// The scaled stacked problem (B = [A; T], c = [g; t0]).
    sq: &'q QpProblem,
    /// The row scaling of B: λ = sc·μ for the host's multiplier μ.
    sc: Vec<f64>,
    ctx: &'c Context<'a>,
    make: F,
    name: &'static str,
    /// The scaled multipliers of the last solve (the next one's start).
    lam0: Option<Vec<f64>>,
    /// Contact points whose slip is prescribed (empty rows of B with an
    /// offset): (contact row, the slip's direction −t0/‖t0‖, one entry per
    /// tangential row: its sign in 2D). Their λ_t is s·that (0 in the glued
    /// solve), not the host's.
    prescribed: Vec<(usize, Vec<f64>)>,
    /// The orthonormal kernel basis, the same for every Tresca solve.
    kernel: Option<Vec<Vec<f64>>>,
    /// ‖PHP‖ of the first solve ([`BoxBounds::hnorm`]).
    hnorm: Option<f64>,
    /// H = B K⁻¹ Bᵀ of the stacked rows, formed at the first solve when
    /// B is small ([`DENSE_RATIO`]).
    dense: Option<std::sync::Arc<Vec<f64>>>,
}

impl<S: BoundStep, F: FnMut() -> S> TrescaStep for DualTresca<'_, '_, '_, F> {
    fn resolution(&self) -> f64 {
        COULOMB_TOL_FACTOR * self.ctx.settings.tol
    }

    fn solve(&mut self, bound: Bound<'_>) -> Result<Tresca, QpError> {
        let (qp, ctx, name) = (self.qp, self.ctx, self.name);
        let m = qp.m();
        let r = match &self.kernel {
            Some(r) => r.clone(),
            None => {
                let r = orthonormal_kernel(&qp.c, &qp.kernel)?;
                self.kernel = Some(r.clone());
                r
            }
        };
        let fac = ctx.ws.cholesky(&qp.c, &qp.kernel)?;
        let sm = self.sq.m();
        let small = sm as f64 <= DENSE_RATIO * (qp.n() as f64).sqrt() && sm <= DENSE_MAX;
        if small && self.dense.is_none() {
            // H depends on C, B and ker C alone: a load step of the same
            // model takes the last step's (the same bits a fresh one has).
            let kernel_key = crate::linalg::cholesky::matrix_key(&[], &qp.kernel);
            let kept = ctx.ws.kept::<KeptHessian>(KEPT_HESSIAN_TAG).filter(|k| {
                k.kernel_key == kernel_key && k.c.same_as(&qp.c) && k.b.same_as(&self.sq.a)
            });
            let h = match kept {
                Some(k) => {
                    log::debug!("{name}: the dual Hessian of the last solve of the same matrices");
                    self.hnorm = Some(k.hnorm);
                    k.h.clone()
                }
                None => {
                    log::debug!("{name}: the dual Hessian formed ({sm} stacked rows)");
                    std::sync::Arc::new(dense_h(self.sq, &fac))
                }
            };
            self.dense = Some(h);
        }
        let mut op = DualOp::new(self.sq, fac, r, name)?;
        if let Some(h) = &self.dense {
            op.with_dense(h.clone());
        }
        // |λ_t| ≤ s ⇔ |μ| ≤ s/sc for the scaled multiplier μ = λ/sc; glued:
        // no bound (s = ∞).
        // ‖λ_t‖ ≤ s likewise in 3D, the pair sharing one scale.
        let k = self.frame.rows();
        let upper: Vec<f64> = match bound {
            Bound::Glued => vec![f64::INFINITY; m],
            Bound::Given(s) => s
                .iter()
                .zip(self.sc[m..].iter().step_by(k))
                .map(|(s, c)| s / c)
                .collect(),
        };
        let boxed = BoxBounds {
            m_n: m,
            upper,
            frame: self.frame,
            lam0: self.lam0.take(),
            hnorm: self.hnorm,
        };
        let mut st = Smalbe::new(op, ctx.settings.tol, (self.make)(), name, Some(&boxed))?;
        st.s.target = ctx.settings.kkt_target;
        if self.hnorm.is_none() {
            if let Some(h) = &self.dense {
                ctx.ws.keep(
                    KEPT_HESSIAN_TAG,
                    std::rc::Rc::new(KeptHessian {
                        c: qp.c.clone(),
                        b: self.sq.a.clone(),
                        kernel_key: crate::linalg::cholesky::matrix_key(&[], &qp.kernel),
                        h: h.clone(),
                        hnorm: st.hnorm,
                    }),
                );
            }
        }
        self.hnorm = Some(st.hnorm);
        let mut exec = ctx.executor(name);
        let (status, iters) = exec.run(&mut st);
        let out = st.into_result(status, iters, exec.log, vec![]);
        let mut lambda: Vec<f64> = out
            .lambda
            .iter()
            .zip(&self.sc)
            .map(|(l, s)| l * s)
            .collect();
        self.lam0 = Some(out.lambda);
        // The host solved the stacked rows [A; T] (docs/methods.md §9.2).
        let mut lambda_t = lambda.split_off(m);
        for (c, dir) in &self.prescribed {
            for (r, e) in dir.iter().enumerate() {
                lambda_t[c * k + r] = match bound {
                    Bound::Glued => 0.0,
                    Bound::Given(s) => e * s[*c],
                };
            }
        }
        Ok(Tresca {
            x: out.x,
            lambda_n: lambda,
            lambda_t,
            active: out.active,
            status: out.status,
            iterations: out.iterations,
            inner_iterations: out.inner_iterations,
            log: out.log,
        })
    }
}
