//! Post-processing: from the QP solution back to the mesh. Stresses per
//! triangle (σ = D B u_e, §2.2), the report's τe, principal stresses,
//! contact pressure (λ / tributary length), current gap and active flag.

pub mod forces;
pub mod friction;
pub mod plot;
pub mod solid_friction;

use crate::fem::element::Point;
use crate::fem::{element, Model};
use crate::output::{ContactGeometry, OutMesh, StepInfo, StepOutput};
use crate::problem::Material;
use crate::qp::QpResult;
use std::collections::BTreeMap;

/// The output mesh of a model (geometry only; no solution).
pub fn out_mesh(model: &Model, mesh: &crate::mesh::Mesh) -> OutMesh {
    let t = &model.topo;
    let contact = ContactGeometry {
        points: t.contact.iter().map(|r| t.points[r.first]).collect(),
        first: t.contact.iter().map(|r| r.first).collect(),
        second: t.contact.iter().map(|r| r.second).collect(),
        normal: t.contact.iter().map(|r| r.normal).collect(),
        gap0: t.contact.iter().map(|r| r.gap0).collect(),
        segments: t.contact_segments.clone(),
        interface: t.contact.iter().map(|r| r.interface).collect(),
        interface_names: t.interface_names.clone(),
        interface_discretizations: t
            .interface_kinds
            .iter()
            .map(|k| k.discretization().to_string())
            .collect(),
        nonmatching: t
            .contact
            .iter()
            .map(|r| r.kind != crate::fem::topology::RowKind::Conforming)
            .collect(),
    };
    OutMesh {
        points: t.points.clone(),
        point_tags: t.point_node.iter().map(|&v| mesh.node_tags[v]).collect(),
        point_body: t.point_body.clone(),
        triangles: t.triangles.clone(),
        material: t.tri_material.clone(),
        material_names: t.material_names.clone(),
        kind: model.kind,
        contact,
    }
}

/// Fields of one solved step of a model whose `[materials]` are
/// `materials`.
pub fn step_output(
    model: &Model,
    materials: &BTreeMap<String, Material>,
    res: &QpResult,
    time: f64,
) -> StepOutput {
    step_output_with_forces(model, materials, res, time).0
}

/// [`step_output`] and the forces it computed (reactions per group, contact
/// resultants per interface) for the summary: one pass over the elements.
pub fn step_output_with_forces(
    model: &Model,
    materials: &BTreeMap<String, Material>,
    res: &QpResult,
    time: f64,
) -> (StepOutput, forces::Forces) {
    let mut lap = crate::fem::Lap::new("post");
    let t = &model.topo;
    let u = model.displacements(&res.x);
    lap.lap("displacements");
    // Stresses and the element forces of the reactions in one pass.
    let (stress, ku) = forces::element_pass(model, materials, &u, true);
    lap.lap("stresses and element forces");
    let nrow = t.contact.len();
    let mut multipliers = vec![0.0; nrow];
    let mut active = vec![0u8; nrow];
    for (qi, &r) in model.qp_rows.iter().enumerate() {
        multipliers[r] = res.lambda[qi];
        active[r] = res.active[qi] as u8;
    }
    let te = model.t_eff();
    let contact_pressure: Vec<f64> = t
        .contact
        .iter()
        .zip(&multipliers)
        .map(|(r, l)| if r.trib > 0.0 { l / (te * r.trib) } else { 0.0 })
        .collect();
    let gap = t
        .contact
        .iter()
        .map(|r| {
            let s: f64 = r
                .coefficients()
                .iter()
                .map(|(p, c)| c[0] * u[*p][0] + c[1] * u[*p][1])
                .sum();
            r.gap0 - s
        })
        .collect::<Vec<f64>>();
    let lambda_t = friction::friction_output(model, res)
        .map(|f| f.lambda_t)
        .unwrap_or_default();
    lap.lap("contact fields");
    let mut forces =
        forces::compute_from(model, &u, &ku, &multipliers, &lambda_t, &contact_pressure);
    lap.lap("forces");
    let step = StepOutput {
        time,
        reaction: std::mem::take(&mut forces.point_reaction),
        von_mises: {
            use rayon::prelude::*;
            let kind = model.kind;
            stress.par_iter().map(|s| kind.von_mises(s)).collect()
        },
        principal: {
            use rayon::prelude::*;
            stress.par_iter().map(element::principal).collect()
        },
        stress,
        displacement: u,
        multipliers,
        contact_pressure,
        gap,
        active,
        change: None,
        info: StepInfo {
            converged: res.status.converged(),
            iterations: res.iterations,
            energy: res.energy,
            kkt: res.kkt,
            ..Default::default()
        },
    };
    lap.lap("von Mises, principal stresses");
    (step, forces)
}

/// A probe lies in the mesh when it is within this fraction of an
/// element's size (its longest edge) of that element: on the boundary, and
/// a little past a curved boundary that the mesh's chords cut
/// (docs/problem-format.md §5, probes).
pub const PROBE_TOLERANCE: f64 = 0.05;

/// Where a point lies against the triangles: the triangle nearest to it
/// relative to its size, the distance to it (0 inside) and its size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Located {
    pub triangle: usize,
    pub distance: f64,
    pub size: f64,
}

impl Located {
    /// Within [`PROBE_TOLERANCE`] × the size of its triangle.
    pub fn inside(&self) -> bool {
        self.distance <= PROBE_TOLERANCE * self.size
    }
}

/// The triangle of `triangles` (point indices into `points`) that `x` lies
/// in, or else the one it is nearest to relative to that triangle's size
/// (None without triangles). Deterministic: the first of equals wins.
pub fn locate(points: &[Point], triangles: &[[usize; 3]], x: Point) -> Option<Located> {
    let mut best: Option<(f64, Located)> = None;
    for (t, tri) in triangles.iter().enumerate() {
        let v = tri.map(|i| points[i]);
        let size = (0..3)
            .map(|k| {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                (a[0] - b[0]).hypot(a[1] - b[1])
            })
            .fold(0.0f64, f64::max);
        let distance = distance_to_triangle(v, x);
        let rel = if size > 0.0 {
            distance / size
        } else {
            f64::INFINITY
        };
        if best.as_ref().is_none_or(|(r, _)| rel < *r) {
            best = Some((
                rel,
                Located {
                    triangle: t,
                    distance,
                    size,
                },
            ));
            if distance == 0.0 {
                break;
            }
        }
    }
    best.map(|(_, l)| l)
}

/// The distance from `x` to the closed triangle `v` (0 inside or on it).
fn distance_to_triangle(v: [Point; 3], x: Point) -> f64 {
    let cross = |a: Point, b: Point, p: Point| {
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    };
    let orient = cross(v[0], v[1], v[2]);
    let sides = [
        cross(v[0], v[1], x),
        cross(v[1], v[2], x),
        cross(v[2], v[0], x),
    ];
    if sides.iter().all(|s| s * orient >= 0.0) {
        return 0.0;
    }
    (0..3)
        .map(|k| {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let e = [b[0] - a[0], b[1] - a[1]];
            let len2 = e[0] * e[0] + e[1] * e[1];
            let s = if len2 > 0.0 {
                (((x[0] - a[0]) * e[0] + (x[1] - a[1]) * e[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a[0] + s * e[0] - x[0]).hypot(a[1] + s * e[1] - x[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// The point nearest to (x, y).
pub fn nearest_point(points: &[Point], x: Point) -> usize {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| (i, (p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2)))
        .fold((0, f64::MAX), |a, b| if b.1 < a.1 { b } else { a })
        .0
}

/// The output arrays of a solved solid model from its QP unknowns `x`:
/// displacements, and per tetrahedron the six stresses, von Mises and the
/// principal stresses.
pub fn solid_output(
    model: &crate::fem::solid::SolidModel,
    materials: &BTreeMap<String, Material>,
    x: &[f64],
) -> crate::output::SolidOutput {
    let displacement = model.displacements(x);
    let stress = model.stresses(materials, &displacement);
    crate::output::SolidOutput {
        points: model.points.clone(),
        point_body: model.point_body.clone(),
        tets: model.tets.clone(),
        material: model.tet_material.clone(),
        material_names: model.material_names.clone(),
        von_mises: stress.iter().map(element::von_mises_solid).collect(),
        principal: stress.iter().map(element::principal_solid).collect(),
        displacement,
        stress,
        reaction: vec![],
        change: None,
    }
}
