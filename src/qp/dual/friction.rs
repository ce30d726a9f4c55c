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
//! last multipliers, until s is stationary (the outer loop of §9.1, as in
//! `ssn`), under-relaxed when it stops contracting ([`CoulombRelaxation`]).

use super::{row_scaling_of, BoundStep, BoxBounds, DualOp, Smalbe};
use crate::linalg::kernel::orthonormal_kernel;
use crate::linalg::sparse::{norm_inf, Csr};
use crate::qp::Failure;
use crate::qp::{
    Context, CoulombRelaxation, IterRecord, Output, QpError, QpProblem, SlipBound, Status,
};
use std::time::Instant;

/// The Coulomb loop stops at a relative change of s ≤ COULOMB_TOL_FACTOR·tol:
/// each Tresca solve is accurate to tol in the dual gradient only, and on
/// the inclined plane of tests/friction.rs at tol = 10⁻¹⁰ the change
/// stagnated at 4.7·tol.
const COULOMB_TOL_FACTOR: f64 = 100.0;
/// Largest number of Tresca solves of the Coulomb loop.
const OUTER_MAX: usize = 200;

/// Solve the frictional `qp` on the box-constrained dual with the bound
/// steps `make` builds (one per Tresca solve); returns x and [λ_n; λ_t].
pub(crate) fn solve_friction<S: BoundStep>(
    qp: &QpProblem,
    ctx: &mut Context,
    mut make: impl FnMut() -> S,
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
    let mut b = Csr::from_triplets(2 * m, qp.n(), &trip);
    let sc = row_scaling_of(&qp.c, &b);
    for (i, si) in sc.iter().enumerate() {
        for v in &mut b.data[b.indptr[i]..b.indptr[i + 1]] {
            *v *= si;
        }
    }
    let g: Vec<f64> =
        qp.g.iter()
            .chain(&fr.t0)
            .zip(&sc)
            .map(|(g, s)| g * s)
            .collect();
    let sq = QpProblem {
        c: Csr::zeros(0, 0),
        d: qp.d.clone(),
        a: b,
        g,
        kernel: vec![],
        friction: None,
        near: None,
    };
    // Slip bounds of the rows in force units (∞: glued).
    let mut s_bound: Vec<f64> = match &fr.bound {
        SlipBound::Tresca(s) => s.clone(),
        SlipBound::Coulomb(_) => vec![f64::INFINITY; m],
    };
    let mut lam0: Option<Vec<f64>> = None;
    let (mut iterations, mut inner) = (0, 0);
    let mut log: Vec<IterRecord> = vec![];
    let mut outer = 0;
    let mut relax = CoulombRelaxation::default();
    loop {
        outer += 1;
        let r = orthonormal_kernel(&qp.c, &qp.kernel)?;
        let fac = ctx.ws.cholesky(&qp.c, &qp.kernel)?;
        let op = DualOp::new(&sq, fac, r, name)?;
        // |λ_t| ≤ s ⇔ |μ| ≤ s/sc for the scaled multiplier μ = λ/sc.
        let upper: Vec<f64> = s_bound.iter().zip(&sc[m..]).map(|(s, c)| s / c).collect();
        let boxed = BoxBounds {
            m_n: m,
            upper,
            lam0: lam0.take(),
        };
        let mut st = Smalbe::new(op, ctx.settings.tol, make(), name, Some(&boxed))?;
        st.s.target = ctx.settings.kkt_target;
        let mut exec = ctx.executor(name);
        let (status, iters) = exec.run(&mut st);
        let out = st.into_result(status, iters, exec.log, vec![]);
        iterations += out.iterations;
        inner += out.inner_iterations;
        log.extend(out.log);
        let mu_scaled = out.lambda;
        let lambda: Vec<f64> = mu_scaled.iter().zip(&sc).map(|(l, s)| l * s).collect();
        let mut status = out.status;
        let done = match (&fr.bound, status.converged()) {
            (_, false) | (SlipBound::Tresca(_), true) => true,
            (SlipBound::Coulomb(mu), true) => {
                let s_new: Vec<f64> = mu
                    .iter()
                    .zip(&lambda[..m])
                    .map(|(f, l)| f * l.max(0.0))
                    .collect();
                let change = s_new
                    .iter()
                    .zip(&s_bound)
                    .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                let smax = norm_inf(&s_new).max(f64::MIN_POSITIVE);
                log::debug!(
                    "{name}: Coulomb update {outer}: change of s {:.3e}, ω = {}",
                    change / smax,
                    relax.omega()
                );
                if change <= COULOMB_TOL_FACTOR * ctx.settings.tol * smax {
                    true
                } else if outer >= OUTER_MAX {
                    status = Status::Failed(Failure::CoulombUnsettled {
                        outer: OUTER_MAX,
                        change: change / smax,
                    });
                    true
                } else {
                    s_bound = relax.next(&s_bound, s_new, outer == 1);
                    lam0 = Some(mu_scaled);
                    false
                }
            }
        };
        if done {
            // The host solved the stacked rows [A; T] (docs/methods.md §9.2).
            let mut lambda = lambda;
            let lambda_t = lambda.split_off(m);
            return Ok(Output {
                x: out.x,
                lambda,
                lambda_t,
                active: out.active,
                status,
                iterations,
                inner_iterations: inner,
                log,
                timings: vec![("iterate".into(), t_start.elapsed().as_secs_f64())],
            });
        }
    }
}
