//! The Coulomb loop's steps on discs (docs/methods.md §12.3): the
//! [`TrescaStep`] of the shared loop ([`crate::qp::coulomb`]) and where
//! each solve starts (the glued start with its normal start, the coarse
//! start, a load step's last multipliers).

use super::{State, FLOOR_MAX};
use crate::qp::coulomb::{Bound, Tresca, TrescaStep};
use crate::qp::{Context, Failure, QpError, Status};

pub(super) struct PlaneTresca<'c, 'a> {
    pub(super) st: State<'a>,
    pub(super) ctx: &'c Context<'a>,
    /// Steps of all solves so far (they share one MAXIT).
    pub(super) steps: usize,
}

impl TrescaStep for PlaneTresca<'_, '_> {
    fn resolution(&self) -> f64 {
        self.st.tol
    }

    fn solve(&mut self, bound: Bound<'_>) -> Result<Tresca, QpError> {
        let st = &mut self.st;
        match bound {
            Bound::Glued => {
                st.s = vec![0.0; st.qp.m()];
                st.glued = true;
                if !st.solved {
                    st.normal_start();
                }
            }
            Bound::Given(s) => {
                st.tresca_tol = st.tresca_tol_for(s);
                st.s = s.to_vec();
                st.glued = false;
                // A Tresca problem's first solve starts from the coarse
                // levels' kinds (docs/methods.md §12.3); if that does not
                // end at its tolerance, from its own start.
                if !st.solved {
                    st.coulomb = None;
                    if let Some(r) = self.start_from_coarse(None) {
                        let r = r?;
                        if r.status.converged() {
                            return Ok(r);
                        }
                        let mut own = self.run()?;
                        own.iterations += r.iterations;
                        own.inner_iterations += r.inner_iterations;
                        return Ok(own);
                    }
                }
            }
        }
        self.st.coulomb = None;
        self.run()
    }

    /// A load step's start on the dual path: the direct iteration from the
    /// last step's multipliers (docs/methods.md §12.3).
    fn coulomb_first(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        let st = &mut self.st;
        // The dual path, or the multigrid's with the bound inside the
        // augmented-Lagrangian sweeps; not the factor's sparse path.
        if st.dual.is_none() && st.iter.is_none() {
            return None;
        }
        let Some(l) = st.warm.clone() else {
            return self.coarse_first(mu);
        };
        let saved = (st.x.clone(), st.ax.clone(), st.tx.clone(), st.tang.clone());
        st.in_n = l.normal.iter().map(|&v| v > 0.0).collect();
        st.ln = l.normal;
        st.lt = l.tangential;
        st.solved = true;
        st.glued = false;
        // The dual path's exact steps only: the multigrid's direct
        // iteration, its bound held inside inexact sweeps, stalled from the
        // rim start (docs/methods.md §12.3).
        st.rim_slips = st.dual.is_some();
        st.coulomb = Some(mu.to_vec());
        st.s = crate::qp::coulomb_bound(mu, &st.ln);
        // Coulomb's own problem: solved to tol, not a fixed point's step.
        st.tresca_tol = st.tol;
        let r = self.run();
        let st = &mut self.st;
        st.coulomb = None;
        st.rim_slips = false;
        if matches!(&r, Ok(t) if t.status.converged()) {
            st.warm = None;
        } else {
            (st.x, st.ax, st.tx, st.tang) = saved;
            st.x_stale = false;
        }
        Some(r)
    }

    /// A load step's fixed point from the last step's multipliers and
    /// their bound μλ_n, not the glued start (docs/methods.md §12.3).
    fn warm_bound(&mut self, mu: &[f64]) -> Option<Vec<f64>> {
        let st = &mut self.st;
        let l = st.warm.take()?;
        log::debug!("ssn: discs: the fixed point starts from the last step's bound μλ_n");
        st.in_n = l.normal.iter().map(|&v| v > 0.0).collect();
        st.ln = l.normal;
        st.lt = l.tangential;
        st.solved = true;
        Some(crate::qp::coulomb_bound(mu, &st.ln))
    }

    /// Coulomb's problem directly: the Newton steps with the bound
    /// s = μλ_n of the current iterate, from the glued answer
    /// (docs/methods.md §12.3); not settled, the shared loop goes on
    /// with Tresca problems from the glued answer.
    fn coulomb(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        let st = &mut self.st;
        st.coulomb = Some(mu.to_vec());
        st.s = crate::qp::coulomb_bound(mu, &st.ln);
        st.glued = false;
        st.tresca_tol = st.tol;
        let r = self.run();
        self.st.coulomb = None;
        Some(r)
    }
}

impl PlaneTresca<'_, '_> {
    /// The first solve's start on the dual path: Coulomb's direct
    /// iteration from the coarse levels' kinds (docs/methods.md §12.3),
    /// before any glued solve; not settled, the glued start follows.
    fn coarse_first(&mut self, mu: &[f64]) -> Option<Result<Tresca, QpError>> {
        if self.st.solved {
            return None;
        }
        self.start_from_coarse(Some(mu))
    }

    /// A first solve from the coarse levels' kinds, after the normal
    /// start: Coulomb's direct iteration (`mu`) or the current Tresca
    /// problem. None if there is no coarse start. A solve that does not
    /// end at its tolerance within [`super::COARSE_STEPS`] is a start that failed:
    /// the state is put back (to the normal start's N) and its status says
    /// so, so that the method's own start follows.
    fn start_from_coarse(&mut self, mu: Option<&[f64]>) -> Option<Result<Tresca, QpError>> {
        let st = &mut self.st;
        st.normal_start();
        let saved = (st.x.clone(), st.ax.clone(), st.tx.clone(), st.in_n.clone());
        let glued = st.glued;
        if let Some(mu) = mu {
            st.coulomb = Some(mu.to_vec());
            st.s = vec![0.0; mu.len()];
            st.glued = false;
        }
        if !st.coarse_start(mu) {
            st.coulomb = None;
            st.glued = glued;
            return None;
        }
        st.coarse_run = true;
        let r = self.run();
        let st = &mut self.st;
        st.coulomb = None;
        st.coarse_run = false;
        let residual = st.residual();
        let target = if mu.is_some() { st.tol } else { st.tresca_tol };
        if matches!(&r, Ok(t) if t.status.converged()) && residual <= target.max(FLOOR_MAX) {
            return Some(r);
        }
        log::debug!(
            "ssn: discs: the coarse start ended at a residual of {residual:.3e}: the method's own start"
        );
        (st.x, st.ax, st.tx, st.in_n) = saved;
        st.reset_multipliers();
        st.glued = glued;
        Some(r.map(|mut t| {
            if t.status.converged() {
                t.status = Status::Failed(Failure::Cycling {
                    best: residual,
                    steps: t.iterations,
                });
            }
            t
        }))
    }

    /// Newton steps from the current state until the sets settle.
    fn run(&mut self) -> Result<Tresca, QpError> {
        let st = &mut self.st;
        st.started = false;
        st.run_steps = 0;
        st.visited.clear();
        st.best = (f64::INFINITY, 0);
        st.floor = (f64::INFINITY, 0);
        let mut exec = self.ctx.executor("ssn");
        exec.max_iter = exec.max_iter.saturating_sub(self.steps);
        let inner0 = st.inner;
        let (status, iters) = exec.run(st);
        st.solved = true;
        self.steps += iters;
        if let Some(e) = st.error.take() {
            return Err(e);
        }
        st.ensure_x()?;
        Ok(Tresca {
            x: st.x.clone(),
            lambda_n: st.ln.clone(),
            lambda_t: st.lt.clone(),
            active: st.in_n.clone(),
            status,
            iterations: iters,
            inner_iterations: st.inner - inner0,
            log: exec.log,
        })
    }
}
