//! The yardstick of the iterative path (`signorini limit --path
//! iterative`, docs/methods.md §7.2): one multigrid-preconditioned CG solve
//! of the elasticity of the model, set up exactly as a K_J solve of
//! `iterative` is (the same bandwidth-reducing order, near-null space,
//! multigrid settings and stall test), to the settings' tolerance.

use super::iterative::{permuted, rho_rows, PCG_MAX};
use crate::linalg::amg::{pcg_stall, Amg, AmgSettings, NearNull, PCG_STALL};
use crate::linalg::ordering::block_rcm;
use crate::linalg::sparse::norm_inf;
use crate::qp::{QpError, QpProblem};
use std::time::Instant;

/// One measured solve (times in seconds).
#[derive(Debug, Clone)]
pub struct Yardstick {
    /// The ordering and the permuted copy of the problem.
    pub t_order: f64,
    /// The multigrid hierarchy.
    pub t_setup: f64,
    /// PCG.
    pub t_solve: f64,
    pub iterations: usize,
    /// ‖b − Kx‖/‖b‖ of the answer.
    pub rel_residual: f64,
    pub converged: bool,
    /// Unknowns per level, finest first.
    pub levels: Vec<usize>,
    pub operator_complexity: f64,
    /// Contact rows added to C as springs ρ a_jᵀa_j (every row when C has
    /// a kernel, so K is definite; none otherwise).
    pub springs: usize,
}

/// Solve K x = d once by AMG-PCG to relative residual `rtol` from x = 0:
/// K = C when C is definite, else K = C + ρAᵀA over every contact row
/// (K_J of the iterative path with J all rows; on a solid model ρ_j = max c_kk of the row, 1/RHO_SOLID of the path's).
pub fn yardstick(qp: &QpProblem, rtol: f64) -> Result<Yardstick, QpError> {
    let t0 = Instant::now();
    let unit: Vec<usize>;
    let blocks = match &qp.near {
        Some(nk) => nk.block_ptr.as_slice(),
        None => {
            unit = (0..=qp.n()).collect();
            &unit
        }
    };
    let perm = block_rcm(&qp.c, blocks);
    let (qpp, mut aug) = permuted(qp, &perm);
    let springs = if qp.kernel.is_empty() { 0 } else { qp.m() };
    if springs > 0 {
        let diag = qp.c.diag();
        // Springs as stiff as the rows' own unknowns (factor 1), not the
        // iterative path's RHO_SOLID: a stiffer spring on every row is a
        // harder elasticity problem (Hertz 45 k: 28 → 36 CG steps), and the
        // yardstick must not move with the contact solver's tuning.
        let rho = rho_rows(qp, &diag, norm_inf(&diag), 1.0);
        aug.assemble(0..qp.m(), &rho);
    }
    let t_order = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let near = qpp.near.as_ref().map(|nk| NearNull {
        block_ptr: &nk.block_ptr,
        modes: &nk.modes,
    });
    let nm = qpp.near.as_ref().map_or(1, |nk| nk.modes.len());
    let amg = Amg::new(aug.matrix(), near, &AmgSettings::for_modes(nm))
        .map_err(|e| QpError::Unsupported(format!("no multigrid of K: {e}")))?;
    let t_setup = t1.elapsed().as_secs_f64();
    log::debug!(
        "yardstick: order {t_order:.3} s, multigrid {t_setup:.3} s, levels {:?}",
        amg.sizes()
    );
    let t2 = Instant::now();
    let mut x = vec![0.0; qp.n()];
    let prec = |r: &[f64], z: &mut [f64]| amg.apply(r, z);
    let rep = pcg_stall(
        aug.matrix(),
        &qpp.d,
        &mut x,
        &prec,
        rtol,
        PCG_MAX,
        PCG_STALL,
    );
    Ok(Yardstick {
        t_order,
        t_setup,
        t_solve: t2.elapsed().as_secs_f64(),
        iterations: rep.iterations,
        rel_residual: rep.rel_residual,
        converged: rep.converged,
        levels: amg.sizes(),
        operator_complexity: amg.operator_complexity(),
        springs,
    })
}
