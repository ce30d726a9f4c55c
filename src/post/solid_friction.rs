//! The friction outputs of a solid model per contact row (docs/methods.md
//! §12.6, docs/problem-format.md §12): the tangential force and traction
//! and the step's slip as global 3-vectors, and the state open / stick /
//! slip, from the solution of a frictional problem (`Frame::Plane`).

use crate::fem::contact3d::friction::frames;
use crate::fem::solid::SolidModel;
use crate::output::SolidContactOutput;
use crate::post::friction::{row_state, RowState};
use crate::qp::{tangential_norm, QpResult};

/// a·t1 + b·t2.
fn combine(t: &[[f64; 3]; 2], a: f64, b: f64) -> [f64; 3] {
    [0, 1, 2].map(|k| a * t[0][k] + b * t[1][k])
}

/// Fill `c`'s friction fields from `res` on `model` (left empty without
/// friction or for a result without tangential forces, e.g. unbounded).
/// A tangential row without unknowns and offset (the second of a row on a
/// plane of symmetry, `contact3d::friction::friction_frame`, or both on a
/// symmetry edge) carries no force: its λ_t is left out. The state is
/// [`row_state`]'s.
/// Returns the rows that stick and that slip per interface (empty without
/// friction).
pub fn solid_friction_output(
    model: &SolidModel,
    res: &QpResult,
    c: &mut SolidContactOutput,
) -> Vec<(usize, usize)> {
    let Some(f) = model.qp.friction.as_ref() else {
        return vec![];
    };
    let m = model.qp.m();
    if res.lambda_t.len() != 2 * m || res.lambda.len() != m {
        return vec![];
    }
    let s = f.slip_bound(&res.lambda);
    let v = f.slip(&res.x);
    let fr = frames(model);
    let nrow = model.contact.len();
    c.tangential_force = vec![[0.0; 3]; nrow];
    c.tangential_traction = vec![[0.0; 3]; nrow];
    c.slip = vec![[0.0; 3]; nrow];
    c.friction_state = vec![0; nrow];
    c.multiplier_t = vec![[0.0; 2]; nrow];
    let nif = model.interface_names.len();
    let mut counts = vec![(0, 0); nif];
    for (qi, &r) in model.qp_rows.iter().enumerate() {
        let row = &model.contact[r];
        let (t, _) = &fr[r];
        // A tangential row without unknowns or offset (a plane of symmetry,
        // an edge of two) carries no force: its λ is whatever the method
        // left, and is left out.
        let idle = |k: usize| {
            let i = 2 * qi + k;
            f.t.indptr[i] == f.t.indptr[i + 1] && f.t0[i] == 0.0
        };
        let l1 = if idle(0) { 0.0 } else { res.lambda_t[2 * qi] };
        let l2 = if idle(1) {
            0.0
        } else {
            res.lambda_t[2 * qi + 1]
        };
        c.multiplier_t[r] = [res.lambda_t[2 * qi], res.lambda_t[2 * qi + 1]];
        let ft = combine(t, l1, l2);
        c.tangential_force[r] = ft;
        if row.area > 0.0 {
            c.tangential_traction[r] = ft.map(|x| x / row.area);
        }
        c.slip[r] = combine(t, v[2 * qi], v[2 * qi + 1]);
        let active = res.active.get(qi).copied().unwrap_or(false);
        let k = &mut counts[row.interface as usize];
        let state = row_state(
            res.lambda[qi],
            tangential_norm(&[l1, l2]),
            s[qi],
            active,
            false,
        );
        c.friction_state[r] = state as u8;
        match state {
            RowState::Stick => k.0 += 1,
            RowState::Slip => k.1 += 1,
            RowState::Open => {}
        }
    }
    counts
}
