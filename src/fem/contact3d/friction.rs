//! Friction on the 3D contact rows (docs/methods.md §12.2): two tangential
//! rows per QP contact row, the row's own coefficients ([`Row3::coefficients`])
//! with its normal n replaced by the tangents t1 and t2 of its friction
//! frame — t·(Σ w u_master − u_slave), the tangential relative displacement
//! along t, whose increment over a load step is the slip. The bound is on
//! the Euclidean norm of the pair (`Frame::Plane`): a disc of radius
//! s × area (Tresca) or the cone μλ_n (Coulomb).

use super::super::conditions::PointDofs;
use super::super::element::Vector3;
use super::super::solid::SolidModel;
use super::super::FemError;
use super::{cross, dot, Row3};
use crate::problem::{Contact, FrictionLaw};
use crate::qp::{Csr, Frame, Friction, SlipBound};
use std::path::Path;

/// A fixed direction e of the slave point within this cosine of the
/// tangent plane makes the row's frame a symmetry frame ([`friction_frame`]).
const ACROSS: f64 = 1e-9;

/// Which of a row's two tangential rows a plane of symmetry holds
/// ([`friction_frame`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Held {
    /// Neither: the slave point slides freely in its tangent plane.
    None,
    /// The second (t2, across one plane of symmetry).
    Second,
    /// Both (a point on a symmetry edge, two planes through n).
    Both,
}

/// The friction frame of `row` whose slave point has the unknowns `slave`
/// (docs/methods.md §12.2): the row's own (t1, t2) of §11.4, unless the slave
/// point is held at zero along directions lying in the tangent plane (a
/// `[[slip]]` plane of symmetry, or a zero Dirichlet component):
/// - along one direction e: t2 = e and t1 = t2 × n, and the second
///   tangential row is held ([`Held::Second`]);
/// - along two (a symmetry edge, n along the free direction): t1 the first
///   held direction, t2 = n × t1, both rows held ([`Held::Both`]).
///
/// A held row is left empty, as 2D's mortar rows on a line of symmetry,
/// since the mirrored half cancels any force across the plane. An empty
/// row still shares the disc with t1, so without this rotation an arbitrary
/// λ_t2 on it could take capacity from λ_t1.
pub fn friction_frame(row: &Row3, slave: &PointDofs<3>) -> ([Vector3; 2], Held) {
    let n = row.normal;
    if slave.u0 != [0.0; 3] {
        return (row.tangents, Held::None);
    }
    match slave.ndof {
        2 => {
            let e = cross(slave.t[0], slave.t[1]);
            let l = dot(e, e).sqrt();
            if l > 0.5 && (dot(e, n) / l).abs() <= ACROSS {
                let t2 = e.map(|c| c / l);
                return ([cross(t2, n), t2], Held::Second);
            }
        }
        1 => {
            // The free direction f along n: the held ones span the tangent
            // plane.
            let f = slave.t[0];
            let l = dot(f, f).sqrt();
            let across = cross(f, n);
            if l > 0.5 && dot(across, across).sqrt() / l <= ACROSS {
                return (row.tangents, Held::Both);
            }
        }
        _ => {}
    }
    (row.tangents, Held::None)
}

/// Coefficients c_p of the tangential relative displacement Σ c_p·u_p of
/// `row` along `t` (its coefficients with n replaced by t).
pub fn tangential_coefficients(row: &Row3, t: Vector3) -> Vec<(usize, Vector3)> {
    Row3 {
        normal: t,
        ..row.clone()
    }
    .coefficients()
}

/// The two tangential rows' coefficients of `row` (the second empty when
/// the frame holds it), and the frame.
fn rows_of(row: &Row3, dofs: &[PointDofs<3>]) -> ([Vec<(usize, Vector3)>; 2], [Vector3; 2]) {
    let (t, held) = friction_frame(row, &dofs[row.slave]);
    let along = |k: usize| match (held, k) {
        (Held::Both, _) | (Held::Second, 1) => vec![],
        _ => tangential_coefficients(row, t[k]),
    };
    ([along(0), along(1)], t)
}

/// The friction of the QP rows `qp_rows` of `rows` (None without a friction
/// key; t0 = 0, the reference configuration, see [`offset`] for load steps):
/// T with rows 2i, 2i + 1 of QP row i in the reduced unknowns, as A
/// (`reduced_rows`), and one bound per QP row: s × area (Tresca) or μ. A
/// row without a tangent frame (a normal not unit: a degenerate facet) and
/// a frictional pair with no QP row are refused naming the pair; a Tresca
/// bound that overflows names the pair too. `node_tag` of a point.
pub(in crate::fem) fn build(
    rows: &[Row3],
    qp_rows: &[usize],
    dofs: &[PointDofs<3>],
    n: usize,
    contacts: &[Contact],
    path: &Path,
    node_tag: impl Fn(usize) -> u64,
) -> Result<Option<Friction>, FemError> {
    if !contacts.iter().any(Contact::has_friction) {
        return Ok(None);
    }
    let what = |ci: usize| format!("[[contact]] #{} ({})", ci + 1, contacts[ci].keys());
    let tresca = contacts
        .iter()
        .any(|c| matches!(c.friction, FrictionLaw::Tresca(_)));
    let mut trip = vec![];
    let mut bound = Vec::with_capacity(qp_rows.len());
    let mut count = vec![0usize; contacts.len()];
    for (qi, &r) in qp_rows.iter().enumerate() {
        let row = &rows[r];
        let ci = row.interface as usize;
        count[ci] += 1;
        let c = &contacts[ci];
        let unit = dot(row.normal, row.normal);
        if !unit.is_finite() || (unit - 1.0).abs() > 1e-6 {
            return Err(FemError::new(
                path,
                format!(
                    "{}: friction needs a tangent plane, but the contact row at node {} has no normal (a degenerate, zero-area triangle of the surface there)",
                    what(ci),
                    node_tag(row.slave)
                ),
            ));
        }
        bound.push(match c.friction {
            FrictionLaw::Tresca(s) => {
                let b = s * row.area;
                if !b.is_finite() {
                    return Err(FemError::new(
                        path,
                        format!(
                            "{}: tresca = {s:e} times the tributary area {:.3e} overflows; change the units",
                            what(ci),
                            row.area
                        ),
                    ));
                }
                b
            }
            FrictionLaw::Coulomb(mu) => mu,
            FrictionLaw::Frictionless => 0.0,
        });
        let (coef, _) = rows_of(row, dofs);
        for (k, cs) in coef.iter().enumerate() {
            for &(p, cv) in cs {
                let pd = dofs[p];
                for j in 0..pd.ndof {
                    let v = dot(cv, pd.t[j]);
                    if v.abs() > 1e-14 {
                        trip.push((2 * qi + k, pd.start + j, v));
                    }
                }
            }
        }
    }
    for (ci, c) in contacts.iter().enumerate() {
        if c.has_friction() && count[ci] == 0 {
            return Err(FemError::new(
                path,
                format!(
                    "{}: friction is given but the pair has no contact rows (every point fixed, or no slave node projects onto the master)",
                    what(ci)
                ),
            ));
        }
    }
    Ok(Some(Friction {
        t: Csr::from_triplets(2 * qp_rows.len(), n, &trip),
        t0: vec![0.0; 2 * qp_rows.len()],
        bound: if tresca {
            SlipBound::Tresca(bound)
        } else {
            SlipBound::Coulomb(bound)
        },
        frame: Frame::Plane,
    }))
}

/// The tangential relative displacement (two per QP row, along its friction
/// frame) for the point displacements `u` (docs/methods.md §12.2).
pub fn tangential_displacement(model: &SolidModel, u: &[Vector3]) -> Vec<f64> {
    let mut out = Vec::with_capacity(2 * model.qp_rows.len());
    for &r in &model.qp_rows {
        let (coef, _) = rows_of(&model.contact[r], &model.dofs);
        for cs in &coef {
            out.push(cs.iter().map(|(p, c)| dot(*c, u[*p])).sum());
        }
    }
    out
}

/// The friction frame of each contact row of `model` (its §11.4 frame for
/// rows left out of the QP), and which of its tangents are held.
pub fn frames(model: &SolidModel) -> Vec<([Vector3; 2], Held)> {
    model
        .contact
        .iter()
        .map(|row| friction_frame(row, &model.dofs[row.slave]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::contact::RowKind;

    fn row(n: Vector3) -> Row3 {
        Row3 {
            kind: RowKind::NonMatching,
            slave: 0,
            masters: vec![(1, 0.25), (2, 0.75)],
            normal: n,
            tangents: super::super::tangent_frame(n),
            gap0: 0.0,
            area: 2.0,
            interface: 0,
        }
    }

    /// A free slave keeps the frame of §11.4; one held at zero across a
    /// plane containing n gets t2 along the held direction, a right-handed
    /// frame, and its second row held; one free along n alone (a symmetry
    /// edge) both rows.
    #[test]
    fn symmetry_frame() {
        let r = row([0.0, 0.0, 1.0]);
        let free = PointDofs::<3> {
            start: 0,
            ndof: 3,
            t: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            u0: [0.0; 3],
        };
        assert_eq!(friction_frame(&r, &free), (r.tangents, Held::None));
        let s = 0.5f64.sqrt();
        // Held along e = (s, s, 0) (a plane x + y = 0 through the normal).
        let held = PointDofs::<3> {
            start: 0,
            ndof: 2,
            t: [[s, -s, 0.0], [0.0, 0.0, 1.0], [0.0; 3]],
            u0: [0.0; 3],
        };
        let ([t1, t2], h) = friction_frame(&r, &held);
        assert_eq!(h, Held::Second);
        assert!((dot(t2, [s, s, 0.0]).abs() - 1.0).abs() < 1e-15);
        let c = [
            t1[1] * t2[2] - t1[2] * t2[1],
            t1[2] * t2[0] - t1[0] * t2[2],
            t1[0] * t2[1] - t1[1] * t2[0],
        ];
        assert!((0..3).all(|k| (c[k] - r.normal[k]).abs() < 1e-15), "{c:?}");
        // Held along the normal itself (a support, not a symmetry plane).
        let support = PointDofs::<3> {
            t: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]],
            ..held
        };
        assert_eq!(friction_frame(&r, &support).1, Held::None);
        // Held at a non-zero value: no symmetry.
        let moved = PointDofs::<3> {
            u0: [0.1, 0.1, 0.0],
            ..held
        };
        assert_eq!(friction_frame(&r, &moved).1, Held::None);
        // On a symmetry edge (free along n only): both held; free across n
        // (an edge along the tangent plane): neither.
        let edge = PointDofs::<3> {
            ndof: 1,
            t: [[0.0, 0.0, 1.0], [0.0; 3], [0.0; 3]],
            ..held
        };
        assert_eq!(friction_frame(&r, &edge), (r.tangents, Held::Both));
        let across = PointDofs::<3> {
            t: [[1.0, 0.0, 0.0], [0.0; 3], [0.0; 3]],
            ..edge
        };
        assert_eq!(friction_frame(&r, &across).1, Held::None);
    }

    /// A row without a normal (a degenerate facet) is refused naming the
    /// file, the pair and the node; a Tresca bound that overflows too.
    #[test]
    fn rows_without_a_frame_are_refused() {
        use crate::problem::{ContactPair, NormalKind};
        let c = Contact {
            pair: ContactPair::Conforming {
                on: "face".into(),
                normals: NormalKind::Averaged,
            },
            friction: FrictionLaw::Coulomb(0.2),
        };
        let free = PointDofs::<3> {
            start: 0,
            ndof: 3,
            t: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            u0: [0.0; 3],
        };
        let dofs: Vec<PointDofs<3>> = (0..3)
            .map(|p| PointDofs {
                start: 3 * p,
                ..free
            })
            .collect();
        let mut bad = row([f64::NAN; 3]);
        bad.tangents = [[f64::NAN; 3]; 2];
        let path = Path::new("p.toml");
        let e = build(
            &[bad],
            &[0],
            &dofs,
            9,
            std::slice::from_ref(&c),
            path,
            |p| 100 + p as u64,
        )
        .unwrap_err();
        assert_eq!(e.path, path);
        assert!(
            e.msg.contains("[[contact]] #1 (on = \"face\")") && e.msg.contains("node 100"),
            "{}",
            e.msg
        );
        let ok = build(
            &[row([0.0, 0.0, 1.0])],
            &[0],
            &dofs,
            9,
            std::slice::from_ref(&c),
            path,
            |p| p as u64,
        )
        .unwrap()
        .unwrap();
        assert_eq!(ok.t.nrows, 2);
        let big = Contact {
            friction: FrictionLaw::Tresca(1e308),
            ..c
        };
        let e = build(&[row([0.0, 0.0, 1.0])], &[0], &dofs, 9, &[big], path, |p| {
            p as u64
        })
        .unwrap_err();
        assert!(e.msg.contains("overflows"), "{}", e.msg);
    }

    /// The tangential coefficients are the row's with n replaced by t.
    #[test]
    fn tangential_coefficients_replace_the_normal() {
        let r = row([0.0, 0.0, 1.0]);
        let t = r.tangents[0];
        let c = tangential_coefficients(&r, t);
        assert_eq!(c.len(), 3);
        assert_eq!(c[0], (0, t.map(|x| -x)));
        assert_eq!(c[2], (2, t.map(|x| 0.75 * x)));
    }
}
