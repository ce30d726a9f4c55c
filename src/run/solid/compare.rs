//! `compare` on a 3D model: the solid model's compared step (docs/design.md,
//! "Where it stands"). Frictionless, every variant solves the last step
//! from a cold start; with friction and several steps each variant follows
//! the load path ([`march`], the loop of `solve`), since a frictional
//! answer depends on the path (docs/methods.md §9.1), as in 2D.

use super::steps::{march, Carry};
use super::{probes, solve_in, step_model, written_model, SolidPrepared};
use crate::fem::solid::SolidModel;
use crate::qp::{MethodId, QpProblem, QpResult, SolveOptions};
use crate::run::compare::{Comparable, ComparedStep, PathWork, VariantResult};
use crate::run::steps::Verdict;
use crate::run::RunError;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::time::Instant;

impl Comparable for SolidPrepared {
    fn written(&self) -> Result<Box<dyn ComparedStep + '_>, RunError> {
        Ok(Box::new(SolidStep {
            prep: self,
            model: written_model(self)?,
        }))
    }

    fn compared_step(&self) -> Result<Box<dyn ComparedStep + '_>, RunError> {
        let last = self.problem.file.nsteps() - 1;
        Ok(Box::new(SolidStep {
            prep: self,
            model: step_model(self, last)?,
        }))
    }

    fn solve_path(
        &self,
        method: MethodId,
        opts: &SolveOptions,
        t: Instant,
    ) -> Result<VariantResult, String> {
        let nsteps = self.problem.file.nsteps();
        let target = opts.settings.kkt_target;
        let mut work = PathWork::new(nsteps);
        let last = march(
            self,
            method,
            opts,
            0..nsteps,
            Carry::default(),
            None,
            |st, _| {
                let verdict = Verdict::of(method, &st.result, target, false);
                work.add(st.index, &st.result, verdict);
                Ok(())
            },
        )
        .map_err(|e| e.to_string())?
        .ok_or_else(|| "no load step was solved".to_string())?;
        let probes = probes(self, &last.model.displacements(&last.result.x))
            .into_iter()
            .map(|(n, p)| (n, p.u.to_vec()))
            .collect();
        Ok(work.finish(last.result, probes, t))
    }
}

/// The compared step of a solid model.
struct SolidStep<'a> {
    prep: &'a SolidPrepared,
    model: Cow<'a, SolidModel>,
}

impl ComparedStep for SolidStep<'_> {
    fn qp(&self) -> &QpProblem {
        &self.model.qp
    }

    fn solve(&self, method: MethodId, opts: &SolveOptions) -> Result<QpResult, RunError> {
        solve_in(
            self.prep,
            &self.model,
            method,
            opts,
            &opts.settings.workspace(),
        )
    }

    fn probes(&self, x: &[f64]) -> BTreeMap<String, Vec<f64>> {
        probes(self.prep, &self.model.displacements(x))
            .into_iter()
            .map(|(n, p)| (n, p.u.to_vec()))
            .collect()
    }
}
