//! The numerical range: Young's modulus from 10³ to 10¹² Pa, lengths from
//! 10⁻³ to 10⁵ m, sliver triangles (aspect ratio ~10³) and ν = 0.499.
//!
//! The problem is two_blocks_eccentric (a floating upper block that tilts, the
//! interface partly open) with its mesh scaled in the library. With zero
//! prescribed displacements and zero initial gaps the QP is homogeneous:
//! C ∝ E (and, in 2D, independent of a uniform length scale s), the traction
//! load d ∝ s, the constraints Ax ≤ 0 are cones. So u(E, s) = (s/E)·û exactly
//! (û at E = 1, s = 1), with the same active set. Every solve (CGC + Cholesky,
//! SSN, ASM) must converge, certify its KKT residuals and follow this scaling
//! to 10⁻⁸ relative.

use signorini::mesh::Mesh;
use signorini::problem::Problem;
use signorini::qp::precond::PrecondKind;
use signorini::qp::{registry, SolveOptions};
use std::path::Path;

const METHODS: [&str; 3] = ["cgc", "ssn", "asm"];
const KKT_TARGET: f64 = 1e-6;
const REL: f64 = 1e-8;

mod common;

use common::root;

/// two_blocks_eccentric.toml with its materials replaced.
fn problem_text(e: f64, nu: f64) -> String {
    format!(
        r#"
[mesh]
file = "two_blocks_eccentric.msh"
[model]
plane = "strain"
[materials.lower]
E = {e:e}
nu = {nu}
[materials.upper]
E = {e:e}
nu = {nu}
[[dirichlet]]
on = "bottom"
u = [0.0, 0.0]
[[dirichlet]]
on = "top_mid"
ux = 0.0
[[traction]]
on = "top_right"
pn = -1.0e6
[[contact]]
on = "interface"
"#
    )
}

/// The shipped mesh, coordinates mapped by (x, y) ↦ s·(x, a·y).
fn mesh(s: f64, a: f64) -> Mesh {
    let mut m = signorini::mesh::read_msh(&root().join("meshes/two_blocks_eccentric.msh")).unwrap();
    for p in m.nodes.iter_mut() {
        *p = [s * p[0], s * a * p[1]];
    }
    m
}

/// Largest aspect ratio (longest edge² / (2·area), ~ longest edge / height).
fn max_aspect(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| m.nodes[i]);
            let area2 = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
                .abs();
            let l2 = (0..3)
                .map(|k| {
                    let (a, b) = (p[k], p[(k + 1) % 3]);
                    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
                })
                .fold(0.0f64, f64::max);
            l2 / area2
        })
        .fold(0.0f64, f64::max)
}

struct Solved {
    u: Vec<[f64; 2]>,
    active: Vec<bool>,
}

fn solve(mesh: &Mesh, e: f64, nu: f64, method: &str, label: &str) -> Result<Solved, String> {
    let problem = Problem::parse(Path::new("range.toml"), &problem_text(e, nu))
        .map_err(|err| format!("{label}: {err}"))?;
    let model = signorini::fem::build(mesh, &problem).map_err(|err| format!("{label}: {err}"))?;
    let opts = {
        let mut o = SolveOptions::default();
        o.settings.cgc.preconditioner = PrecondKind::Cholesky;
        o
    };
    let r = registry::solve(method, &model.qp, &opts).map_err(|err| format!("{label}: {err}"))?;
    if !r.status.converged() {
        return Err(format!("{label}: {}", r.status.describe()));
    }
    if !r.kkt.within(KKT_TARGET) {
        return Err(format!("{label}: KKT {:?} not certified", r.kkt));
    }
    Ok(Solved {
        u: model.displacements(&r.x),
        active: r.solution.active,
    })
}

/// Solves over the grid of E and s for one mesh shape (`aspect` = y-scale)
/// and ν, and checks u·E/s against the reference (CGC at E = 1e9, s = 1).
fn check_range(aspect: f64, nu: f64, es: &[f64], ss: &[f64]) {
    let (e0, s0) = (1e9, 1.0);
    let base =
        solve(&mesh(s0, aspect), e0, nu, "cgc", "reference").unwrap_or_else(|e| panic!("{e}"));
    let u_hat: Vec<[f64; 2]> = base.u.iter().map(|u| u.map(|v| v * e0 / s0)).collect();
    let scale = u_hat
        .iter()
        .fold(0.0f64, |m, u| m.max(u[0].abs()).max(u[1].abs()));
    let na = base.active.iter().filter(|a| **a).count();
    assert!(
        na > 0 && na < base.active.len(),
        "the reference must be partly open: {na} of {} active",
        base.active.len()
    );
    let mut failures = vec![];
    for &s in ss {
        let m = mesh(s, aspect);
        for &e in es {
            for method in METHODS {
                let label = format!("{method}, E = {e:e}, s = {s:e}, aspect {aspect}, nu = {nu}");
                match solve(&m, e, nu, method, &label) {
                    Err(msg) => failures.push(msg),
                    Ok(r) => {
                        let err = r.u.iter().zip(&u_hat).fold(0.0f64, |w, (u, h)| {
                            w.max((u[0] * e / s - h[0]).abs())
                                .max((u[1] * e / s - h[1]).abs())
                        });
                        // A NaN error is not within the tolerance either.
                        let within = err <= REL * scale;
                        if !within {
                            failures.push(format!(
                                "{label}: u·E/s differs from the reference by {:.2e} (relative)",
                                err / scale
                            ));
                        }
                        if r.active != base.active {
                            failures.push(format!("{label}: another active set"));
                        }
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

const ES: [f64; 5] = [1e3, 1e6, 1e9, 1e11, 1e12];
const SS: [f64; 4] = [1e-3, 1.0, 1e2, 1e5];

#[test]
fn regular_triangles_scale_exactly_over_e_and_length() {
    check_range(1.0, 0.25, &ES, &SS);
}

#[test]
fn nearly_incompressible_nu_0499_scales_exactly() {
    check_range(1.0, 0.499, &ES, &SS);
}

#[test]
fn sliver_triangles_scale_exactly() {
    // y squeezed by 10³: every triangle becomes a sliver.
    let aspect = 1e-3;
    let a = max_aspect(&mesh(1.0, aspect));
    assert!(a > 3e2, "aspect ratio only {a:.1}");
    eprintln!("sliver mesh: largest aspect ratio {a:.3e}");
    check_range(aspect, 0.25, &[1e3, 1e12], &[1e-3, 1e5]);
    check_range(aspect, 0.499, &[1e3, 1e12], &[1e-3, 1e5]);
}
