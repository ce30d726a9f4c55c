//! The JSON summary of a run (docs/problem-format.md §7) as a typed value:
//! the last step's result, certificate, contact, reactions, loads, probes,
//! timings and, with load steps, one row per step solved.

use super::prepare::{probes, Prepared};
use crate::fem::Model;
use crate::output::StepOutput;
use crate::post::forces::{Forces, GroupReaction, InterfaceForce, Resultant};
use crate::qp::{Kkt, QpResult};
use serde::Serialize;
use std::collections::BTreeMap;

/// `NAME.json`. Maps are keyed by name (a repeated name keeps the last).
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub problem: String,
    pub method: String,
    pub preconditioner: String,
    /// The fill-reducing ordering of the sparse Cholesky factors
    /// (`[solver] ordering`): it changes the bits of an answer.
    pub ordering: String,
    pub converged: bool,
    pub status: String,
    pub iterations: usize,
    pub inner_iterations: usize,
    /// Output points (interface nodes once per body).
    pub nodes: usize,
    pub mesh_nodes: usize,
    pub triangles: usize,
    pub bodies: usize,
    pub rigid_modes: usize,
    pub dofs: usize,
    pub constraints: usize,
    pub active: usize,
    /// The steps of this run that did not converge or are not certified
    /// (1-based; a single solve is step 1). `converged` and
    /// `kkt.certified` are false when any step of the run failed, not
    /// only the last (whose residuals `kkt` holds).
    pub failed_steps: Vec<usize>,
    pub energy: f64,
    pub strain_energy: f64,
    pub load_work: f64,
    pub kkt: KktSummary,
    pub contact: ContactSummary,
    pub loads: Resultant,
    pub reactions: BTreeMap<String, GroupReaction>,
    pub notes: Vec<String>,
    pub probes: BTreeMap<String, Probe>,
    #[serde(rename = "timings_s")]
    pub timings: Timings,
    /// One row per load step solved (only with `[[steps]]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<Vec<StepRow>>,
    /// `[output] reference_step`: the step the `*_change` fields refer to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_step: Option<usize>,
    /// Axisymmetric models only: "N/rad", the unit of every force
    /// (loads, reactions, contact forces) — per radian of the ring
    /// (docs/problem-format.md §11).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_unit: Option<&'static str>,
}

/// The KKT residuals of the last step (the one [`Kkt`] type, its keys
/// flattened) and the verdict (docs/methods.md §8.4).
#[derive(Debug, Clone, Serialize)]
pub struct KktSummary {
    #[serde(flatten)]
    pub residuals: Kkt,
    /// The friction residual of a frictional problem when it is 0 (e.g.
    /// every frictional row on a line of symmetry), which [`Kkt`] leaves
    /// out: a frictional problem always writes `kkt.friction`.
    #[serde(rename = "friction", skip_serializing_if = "Option::is_none")]
    pub friction_zero: Option<f64>,
    pub target: f64,
    pub certified: bool,
}

impl std::ops::Deref for KktSummary {
    type Target = Kkt;
    fn deref(&self) -> &Kkt {
        &self.residuals
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    /// The largest nodal pressure of any row: the peak of a P1 contact's
    /// node-to-node ripple (docs/problem-format.md §7).
    pub max_pressure: f64,
    /// Σλ / (t·Σ tributary length) over every active row: the mean
    /// pressure over the contact zones.
    pub mean_pressure: f64,
    /// Σ λ over the contact rows.
    pub total_force: f64,
    /// The moment of all contact forces (the interfaces' couples summed):
    /// loads + reactions + couple = 0 in moment (docs/methods.md §9.5).
    pub couple: f64,
    pub interfaces: BTreeMap<String, InterfaceForce>,
    /// With friction: the rows in contact that stick, and that slip.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stick: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip: Option<usize>,
}

/// The output point nearest to a requested probe and its displacement.
#[derive(Debug, Clone, Serialize)]
pub struct Probe {
    pub x: f64,
    pub y: f64,
    pub node: usize,
    /// Gmsh node tag.
    pub tag: u64,
    pub u: [f64; 2],
}

/// Wall time (s) of the run's phases (assemble, solve and write: the last
/// step's on plane and axisymmetric models, summed over the steps on solid
/// ones) and of the method's own phases.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Timings {
    pub read: f64,
    pub assemble: f64,
    pub solve: f64,
    pub write: f64,
    pub total: f64,
    pub phases: BTreeMap<String, f64>,
}

/// The cells of a model and their count, under the key of their kind in
/// the JSON (`"triangles": n` in 2D, `"tetrahedra": n` in 3D).
#[derive(Debug, Clone, Copy, Serialize)]
pub enum Cells {
    #[serde(rename = "triangles")]
    Triangles(usize),
    #[serde(rename = "tetrahedra")]
    Tetrahedra(usize),
}

impl Cells {
    /// How many.
    pub fn count(self) -> usize {
        match self {
            Cells::Triangles(n) | Cells::Tetrahedra(n) => n,
        }
    }

    /// Their key in the JSON files.
    pub fn key(self) -> &'static str {
        match self {
            Cells::Triangles(_) => "triangles",
            Cells::Tetrahedra(_) => "tetrahedra",
        }
    }

    /// Their name in a table header.
    pub fn name(self) -> &'static str {
        match self {
            Cells::Triangles(_) => "triangles",
            Cells::Tetrahedra(_) => "tets",
        }
    }
}

/// One load step in `steps`: the report's per-step table (its §3.4:
/// elements, equations, contact nodes, iterations, time) and the result.
#[derive(Debug, Clone, Serialize)]
pub struct StepRow {
    pub step: usize,
    pub t: f64,
    pub converged: bool,
    /// Converged and its KKT residual within the target (the step's verdict).
    pub certified: bool,
    pub iterations: usize,
    pub inner_iterations: usize,
    pub kkt_max: f64,
    pub energy: f64,
    /// Output points (interface nodes once per body), cells, unknowns.
    pub nodes: usize,
    #[serde(flatten)]
    pub cells: Cells,
    pub dofs: usize,
    /// Contact rows (constraints of the QP) and those active at the end.
    pub constraints: usize,
    pub active: usize,
    /// Rows that were active after the previous step and are not now (the
    /// interface opened there), and the reverse; null for the first step
    /// of a run that does not continue a checkpoint.
    pub opened: Option<usize>,
    pub closed: Option<usize>,
    /// Wall time of the solve and of the step (assemble, solve,
    /// post-process; its files are written beside the next step) \[s\].
    pub time_solve: f64,
    pub time_step: f64,
}

/// Σλ / (t·Σ tributary length) over the rows with λ > 0 (0 without one).
fn mean_pressure(model: &Model, lambda: &[f64]) -> f64 {
    let (mut sl, mut st) = (0.0, 0.0);
    for (row, &l) in model.topo.contact.iter().zip(lambda) {
        if l > 0.0 && row.trib > 0.0 {
            sl += l;
            st += row.trib;
        }
    }
    if st > 0.0 {
        sl / (model.t_eff() * st)
    } else {
        0.0
    }
}

impl Summary {
    /// The summary of the step `res` of `model`; `certified` and `target`
    /// are the run's verdict on it.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        prep: &Prepared,
        model: &Model,
        method: crate::qp::MethodId,
        ordering: &str,
        res: &QpResult,
        step: &StepOutput,
        forces: &Forces,
        target: f64,
        certified: bool,
        timings: Timings,
        steps: Option<Vec<StepRow>>,
    ) -> Summary {
        let probes = probes(prep, &step.displacement)
            .into_iter()
            .map(|(name, x, node, u)| {
                let tag = prep.mesh.node_tags[model.topo.point_node[node]];
                (
                    name,
                    Probe {
                        x: x[0],
                        y: x[1],
                        node,
                        tag,
                        u,
                    },
                )
            })
            .collect();
        let k = &res.kkt;
        let fo = crate::post::friction::friction_output(model, res);
        Summary {
            problem: prep.problem.name.clone(),
            method: method.name().to_string(),
            preconditioner: step.info.preconditioner.clone(),
            ordering: ordering.to_string(),
            converged: res.status.converged(),
            status: res.status.describe(),
            iterations: res.iterations,
            inner_iterations: res.inner_iterations,
            nodes: model.topo.points.len(),
            mesh_nodes: prep.mesh.nodes.len(),
            triangles: model.topo.triangles.len(),
            bodies: model.topo.nbodies,
            rigid_modes: model.qp.kernel.len(),
            force_unit: model.kind.force_unit(),
            dofs: model.qp.n(),
            constraints: model.qp.m(),
            active: res.active.iter().filter(|a| **a).count(),
            failed_steps: vec![],
            energy: res.energy,
            strain_energy: forces.strain_energy,
            load_work: forces.load_work,
            kkt: KktSummary {
                residuals: *k,
                friction_zero: (model.qp.friction.is_some() && k.friction == 0.0).then_some(0.0),
                target,
                certified,
            },
            contact: ContactSummary {
                max_pressure: step.contact_pressure.iter().fold(0.0f64, |a, b| a.max(*b)),
                mean_pressure: mean_pressure(model, &step.multipliers),
                total_force: step.multipliers.iter().sum(),
                couple: forces.couple,
                interfaces: forces
                    .interfaces
                    .iter()
                    .map(|i| (i.name.clone(), i.clone()))
                    .collect(),
                stick: fo.as_ref().map(|f| f.stick_count),
                slip: fo.as_ref().map(|f| f.slip_count),
            },
            loads: forces.loads,
            reactions: forces
                .groups
                .iter()
                .map(|g| (g.on.clone(), g.clone()))
                .collect(),
            notes: res.notes.iter().map(ToString::to_string).collect(),
            probes,
            timings: Timings {
                phases: res.timings.iter().cloned().collect(),
                ..timings
            },
            steps,
            reference_step: prep.problem.file.output.reference_step,
        }
    }

    /// The verdict of the whole run from its step rows: `converged` and
    /// `kkt.certified` are the conjunctions over the steps, `failed_steps`
    /// names those that failed.
    pub(crate) fn judge_steps(&mut self, rows: &[StepRow]) {
        self.failed_steps = rows
            .iter()
            .filter(|r| !(r.converged && r.certified))
            .map(|r| r.step)
            .collect();
        self.converged &= rows.iter().all(|r| r.converged);
        self.kkt.certified &= rows.iter().all(|r| r.certified);
    }

    /// The JSON text: pretty-printed, keys in alphabetical order at every
    /// level (the order of `NAME.json` since its first version).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(&serde_json::to_value(self)?)
    }
}
