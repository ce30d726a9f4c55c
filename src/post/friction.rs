//! The friction outputs per contact row (docs/problem-format.md §6): the
//! tangential traction, the slip of the step and the state open / stick /
//! slip, from the solution of a frictional problem (docs/methods.md §9).

use crate::fem::friction::on_symmetry_line;
use crate::fem::Model;
use crate::qp::QpResult;

pub use crate::qp::STICK_MARGIN;

/// Friction fields per contact row (rows left out of the QP: 0).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrictionOutput {
    /// λ_t (N) per row.
    pub lambda_t: Vec<f64>,
    /// λ_t / (tributary length × thickness) (Pa).
    pub tangential_traction: Vec<f64>,
    /// T x − t0: the tangential relative displacement increment of the step (m).
    pub slip: Vec<f64>,
    /// 0 open, 1 stick, 2 slip.
    pub state: Vec<u8>,
    /// Rows in contact that stick, and that slip.
    pub stick_count: usize,
    pub slip_count: usize,
}

/// The friction fields of `res` on `model` (None: a frictionless problem,
/// or a result without tangential forces, e.g. unbounded).
pub fn friction_output(model: &Model, res: &QpResult) -> Option<FrictionOutput> {
    let f = model.qp.friction.as_ref()?;
    let m = model.qp.m();
    if res.lambda_t.len() != m || res.lambda.len() != m {
        return None;
    }
    let s = f.slip_bound(&res.lambda);
    let v = f.slip(&res.x);
    let nrow = model.topo.contact.len();
    let mut out = FrictionOutput {
        lambda_t: vec![0.0; nrow],
        tangential_traction: vec![0.0; nrow],
        slip: vec![0.0; nrow],
        state: vec![0; nrow],
        ..Default::default()
    };
    let te = model.t_eff();
    for (qi, &r) in model.qp_rows.iter().enumerate() {
        let row = &model.topo.contact[r];
        let lt = res.lambda_t[qi];
        out.lambda_t[r] = lt;
        out.tangential_traction[r] = if row.trib > 0.0 {
            lt / (te * row.trib)
        } else {
            0.0
        };
        out.slip[r] = v[qi];
        let in_contact = res.active.get(qi).copied().unwrap_or(false) || res.lambda[qi] > 0.0;
        // A mortar row on a line of symmetry has no tangential row (bound 0):
        // the line holds its slave point, so it sticks (docs/methods.md §9).
        let held = on_symmetry_line(model, r);
        out.state[r] = if !in_contact {
            0
        } else if !held && lt.abs() >= (1.0 - STICK_MARGIN) * s[qi] {
            out.slip_count += 1;
            2
        } else {
            out.stick_count += 1;
            1
        };
    }
    Some(out)
}
