//! Friction on the contact rows (docs/methods.md §9): one tangential row
//! per QP contact row, the row's own coefficients
//! ([`ContactRow::coefficients`]) with the normal n replaced by the tangent
//! t = (−n_y, n_x), n turned by +90°. A conforming row measures
//! t·(u_first − u_second), a non-matching one t·(Σ w u_master − u_slave):
//! the tangential relative displacement, whose increment over a load step is
//! the slip. The tangential force λ_t enters the balance like λ_n
//! (Cx − d + Aᵀλ_n + Tᵀλ_t = 0) and opposes that slip.

use super::conditions::PointDofs;
use super::contact::{ContactRow, RowKind};
use super::element::Vector;
use super::topology::Topology;
use super::{FemError, Model};
use crate::problem::{Contact, ContactPair, Dirichlet, FrictionLaw, LoadStep, Prescribed};
use crate::qp::{Csr, Friction, SlipBound};
use std::path::Path;

/// The row with its normal turned by +90°: its coefficients are those of
/// the tangential relative displacement.
fn tangential(row: &ContactRow) -> ContactRow {
    let n = row.normal;
    ContactRow {
        normal: [-n[1], n[0]],
        ..row.clone()
    }
}

/// Coefficients c_p of the tangential relative displacement Σ c_p·u_p of
/// `row` (its own coefficients with n turned by +90°).
pub fn tangential_coefficients(row: &ContactRow) -> Vec<(usize, Vector)> {
    tangential(row).coefficients()
}

/// Whether mortar row `r` sits at the end of its slave curve on a line of
/// symmetry: its slave point cannot move along the tangent (a `[[slip]]`
/// or zero `[[dirichlet]]` component across the line, or the axis r = 0 of
/// an axisymmetric model). Its mortar weights reach master points on one
/// side of the line only, so its tangential row measures a one-sided
/// average of the master's motion and would carry a friction force μp of
/// either sign; the mirrored half cancels it, so by symmetry the row has no
/// tangential force (NTS rows there have no unknowns and are left out
/// alike). Such rows get an empty tangential row and bound 0 (docs/methods.md §9).
/// Decided once per problem (`symmetry_rows`, kept in the model).
pub fn on_symmetry_line(model: &Model, r: usize) -> bool {
    model.symmetry_rows.get(r).copied().unwrap_or(false)
}

/// [`on_symmetry_line`] for every contact row. A `[[dirichlet]]` component
/// along the row's tangent holds the point as a symmetry line only if it is
/// zero in every load step: a clamped end that a later step moves along
/// the interface (a tube pushed out of its fit) is no symmetry line, and
/// its row keeps its friction in every step (the rows, T and the bounds,
/// are built once for all steps).
pub(super) fn symmetry_rows(
    topo: &Topology,
    dofs: &[PointDofs],
    conditions: &[(usize, Vector, u32)],
    groups: &[(&'static str, String)],
    dirichlet: &[Dirichlet],
    steps: &[LoadStep],
) -> Vec<bool> {
    // Whether Dirichlet group `name`'s component k (a turn: its angle) is
    // 0 as given and in every step that names it explicitly (factors keep
    // a zero zero; a turn takes no explicit step values).
    let zero_always = |name: &str, k: usize| {
        dirichlet
            .iter()
            .filter(|d| d.on == name)
            .all(|d| match d.value {
                Prescribed::Turn(t) => t.angle == 0.0,
                v => v.components()[k].unwrap_or(0.0) == 0.0,
            })
            && steps
                .iter()
                .all(|st| st.dirichlet.get(name).is_none_or(|u| u.xyz()[k] == 0.0))
    };
    let mut at: std::collections::HashMap<usize, Vec<(Vector, u32)>> =
        std::collections::HashMap::new();
    let firsts: std::collections::HashSet<usize> = topo
        .contact
        .iter()
        .filter(|row| row.kind == RowKind::Mortar)
        .map(|row| row.first)
        .collect();
    for &(p, dir, g) in conditions {
        if firsts.contains(&p) {
            at.entry(p).or_default().push((dir, g));
        }
    }
    (0..topo.contact.len())
        .map(|r| {
            let row = &topo.contact[r];
            if row.kind != RowKind::Mortar {
                return false;
            }
            let t = [-row.normal[1], row.normal[0]];
            let pd = &dofs[row.first];
            let fixed = (0..pd.ndof).all(|k| (t[0] * pd.t[k][0] + t[1] * pd.t[k][1]).abs() < 1e-12)
                && (t[0] * pd.u0[0] + t[1] * pd.u0[1]) == 0.0;
            let steady = at.get(&row.first).is_none_or(|cs| {
                cs.iter().all(|&(dir, g)| {
                    let (kind, name) = &groups[g as usize];
                    let along = (dir[0] * t[0] + dir[1] * t[1]).abs() > 1e-12;
                    let k = usize::from(dir[1].abs() > dir[0].abs());
                    *kind != "dirichlet" || !along || zero_always(name, k)
                })
            });
            fixed
                && steady
                && topo
                    .contact_segments
                    .iter()
                    .filter(|s| s[0] == r || s[1] == r)
                    .count()
                    <= 1
        })
        .collect()
}

/// Index of the `[[contact]]` entry of each interface id (conforming
/// pairs are numbered first, then the non-matching ones; `topology`, `pairs`).
fn contact_of_interface(c: &[Contact]) -> Vec<usize> {
    let conforming = |i: &usize| matches!(c[*i].pair, ContactPair::Conforming { .. });
    (0..c.len())
        .filter(conforming)
        .chain((0..c.len()).filter(|i| !conforming(i)))
        .collect()
}

/// The friction of the QP rows `qp_rows` (None without a friction key;
/// t0 = 0, the reference configuration; see [`offset`] for load steps).
pub(super) fn build(
    topo: &Topology,
    dofs: &[PointDofs],
    n: usize,
    path: &Path,
    contacts: &[Contact],
    qp_rows: &[usize],
    symmetry: &[bool],
) -> Result<Option<Friction>, FemError> {
    if !contacts.iter().any(Contact::has_friction) {
        return Ok(None);
    }
    let t_eff = topo.kind.thickness();
    let law = |l: fn(&FrictionLaw) -> bool| contacts.iter().any(|c| l(&c.friction));
    let tresca = law(|f| matches!(f, FrictionLaw::Tresca(_)));
    let coulomb = law(|f| matches!(f, FrictionLaw::Coulomb(_)));
    if tresca && coulomb {
        return Err(FemError::new(
            path,
            "[[contact]]: Tresca (tresca = s) and Coulomb (friction = μ) pairs in one problem are not supported; use one law for every pair".into(),
        ));
    }
    let owner = contact_of_interface(contacts);
    let mut trip = vec![];
    let mut bound = Vec::with_capacity(qp_rows.len());
    let mut rows_of = vec![0usize; contacts.len()];
    for (qi, &r) in qp_rows.iter().enumerate() {
        let row = &topo.contact[r];
        let ci = owner[row.interface as usize];
        rows_of[ci] += 1;
        let c = &contacts[ci];
        if symmetry[r] {
            bound.push(0.0);
            continue;
        }
        bound.push(match c.friction {
            FrictionLaw::Tresca(s) => {
                let b = s * row.trib * t_eff;
                if !b.is_finite() {
                    return Err(FemError::new(
                        path,
                        format!(
                            "[[contact]] #{} ({}): tresca = {s:e} times the tributary length {:.3e} and the thickness {t_eff:e} overflows; change the units",
                            ci + 1,
                            c.keys(),
                            row.trib
                        ),
                    ));
                }
                b
            }
            FrictionLaw::Coulomb(mu) => mu,
            FrictionLaw::Frictionless => 0.0,
        });
        for (p, cvec) in tangential(row).coefficients() {
            let pd = dofs[p];
            for k in 0..pd.ndof {
                let v = cvec[0] * pd.t[k][0] + cvec[1] * pd.t[k][1];
                if v.abs() > 1e-14 {
                    trip.push((qi, pd.start + k, v));
                }
            }
        }
    }
    for (ci, c) in contacts.iter().enumerate() {
        if c.has_friction() && rows_of[ci] == 0 {
            return Err(FemError::new(
                path,
                format!(
                    "[[contact]] #{} ({}): friction is given but the pair has no contact rows (every point fixed, or no slave node projects onto the master)",
                    ci + 1,
                    c.keys()
                ),
            ));
        }
    }
    Ok(Some(Friction {
        t: Csr::from_triplets(qp_rows.len(), n, &trip),
        t0: vec![0.0; qp_rows.len()],
        bound: if tresca {
            SlipBound::Tresca(bound)
        } else {
            SlipBound::Coulomb(bound)
        },
        frame: crate::qp::Frame::Line,
    }))
}

/// The tangential relative displacement of every QP row for the point
/// displacements `u` (docs/methods.md §9.5).
pub fn tangential_displacement(model: &Model, u: &[Vector]) -> Vec<f64> {
    model
        .qp_rows
        .iter()
        .map(|&r| {
            if on_symmetry_line(model, r) {
                return 0.0;
            }
            tangential(&model.topo.contact[r])
                .coefficients()
                .iter()
                .map(|(p, c)| c[0] * u[*p][0] + c[1] * u[*p][1])
                .sum()
        })
        .collect()
}
