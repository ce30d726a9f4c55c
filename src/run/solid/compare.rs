//! `compare` on a 3D model: the solid model's compared step (docs/design.md,
//! "Where it stands"). Without friction in 3D (issue 46) there is no load
//! path to follow: every variant solves the last step from a cold start, as
//! frictionless 2D steps do (docs/methods.md §9.1).

use super::{probes, solve_in, step_model, SolidPrepared};
use crate::fem::solid::SolidModel;
use crate::qp::{MethodId, QpProblem, QpResult, SolveOptions};
use crate::run::compare::{Comparable, ComparedStep, VariantResult};
use crate::run::RunError;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::time::Instant;

impl Comparable for SolidPrepared {
    fn compared_step(&self) -> Result<Box<dyn ComparedStep + '_>, RunError> {
        let last = self.problem.file.nsteps() - 1;
        Ok(Box::new(SolidStep {
            prep: self,
            model: step_model(self, last)?,
        }))
    }

    fn solve_path(
        &self,
        _method: MethodId,
        _opts: &SolveOptions,
        _t: Instant,
    ) -> Result<VariantResult, String> {
        // `compare` follows a path only for a step with friction, which a
        // 3D model refuses when it is read (fem::solid_input).
        Err(format!(
            "{}: a load path with friction is not in yet for 3D models",
            self.problem.path.display()
        ))
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
