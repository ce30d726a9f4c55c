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
        let active = res.active.get(qi).copied().unwrap_or(false);
        // A mortar row on a line of symmetry has no tangential row (bound 0):
        // the line holds its slave point, so it sticks (docs/methods.md §9).
        let held = on_symmetry_line(model, r);
        let state = row_state(res.lambda[qi], lt.abs(), s[qi], active, held);
        out.state[r] = state as u8;
        match state {
            RowState::Stick => out.stick_count += 1,
            RowState::Slip => out.slip_count += 1,
            RowState::Open => {}
        }
    }
    Some(out)
}

/// The state of a frictional row, written as its number (u8) in the
/// outputs (docs/problem-format.md §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowState {
    Open = 0,
    Stick = 1,
    Slip = 2,
}

/// The state of one frictional row. A row is in contact when it carries a
/// normal force, or is active and carries a tangential one: a row without
/// any force is open whatever a method's active set says (mprgp keeps a
/// closed gap at zero load active, ssn does not, and with s = μ·0 = 0 every
/// such row read "slip" under one and "open" under the other). In contact,
/// it slips when ‖λ_t‖ ≥ (1 − STICK_MARGIN)·s and is not `held` (a row
/// whose tangential motion a symmetry plane or line fixes).
pub fn row_state(lambda_n: f64, lt_norm: f64, s: f64, active: bool, held: bool) -> RowState {
    let in_contact = lambda_n > 0.0 || active && lt_norm > 0.0;
    if !in_contact {
        RowState::Open
    } else if !held && lt_norm >= (1.0 - STICK_MARGIN) * s {
        RowState::Slip
    } else {
        RowState::Stick
    }
}
