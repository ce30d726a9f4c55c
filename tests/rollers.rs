//! meshes/rollers.toml, the benchmark's third family (issue 15): four
//! rollers pressed into a softer foundation, two of them held only by
//! contact (vertical translation and rotation free without it). Checked
//! against Hertz (per roller), against exact equilibrium, against another
//! method, and for the start of ssn's dual-space steps (docs/methods.md §7).

use signorini::qp::{QpResult, SolverSection};
use signorini::run::Prepared;
use std::f64::consts::PI;

mod common;

fn solve(method: &str) -> (Prepared, QpResult) {
    let choice = SolverSection {
        method: Some(method.parse().unwrap()),
        ..SolverSection::default()
    };
    let (prep, res) = common::solve_file(&common::root().join("meshes/rollers.toml"), &choice);
    assert!(
        signorini::qp::registry::certified(
            signorini::qp::MethodId::parse(method).unwrap(),
            &res.kkt,
            1e-6,
            true
        ),
        "{method}: {:?}",
        res.kkt
    );
    (prep, res)
}

/// Roller k (1-based): centre abscissa and radius, as in meshes/rollers.geo.
const ROLLERS: [(f64, f64); 4] = [(-6.0, 0.6), (-2.0, 0.8), (2.0, 1.0), (6.0, 1.2)];

#[test]
fn rollers_carry_their_load_with_hertz_zones() {
    let (prep, res) = solve("ssn");
    let step = signorini::post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    let t = &prep.model.topo;
    // E* of steel on the foundation (rollers.toml): 1/E* = Σ (1 − ν²)/E.
    let estar = 1.0 / ((1.0 - 0.09) / 2.0e11 + (1.0 - 0.0625) / 2.0e9);
    let pressure = 1.9e7;
    for (k, &(xc, r)) in ROLLERS.iter().enumerate() {
        // The rows of interface k (one [[contact]] per roller, in order).
        let rows: Vec<usize> = (0..t.contact.len())
            .filter(|&i| t.contact[i].interface as usize == k)
            .collect();
        assert!(!rows.is_empty(), "roller {}: no rows", k + 1);
        let f: f64 = rows.iter().map(|&i| res.lambda[i]).sum();
        let a_num = rows
            .iter()
            .filter(|&&i| step.active[i] == 1)
            .map(|&i| (t.points[t.contact[i].first][0] - xc).abs())
            .fold(0.0f64, f64::max);
        let pmax = rows
            .iter()
            .map(|&i| step.contact_pressure[i])
            .fold(0.0f64, f64::max);
        // Hertz (K.L. Johnson, Contact Mechanics, 1985, ch. 4) for the force
        // the roller carries.
        let a = (4.0 * f * r / (PI * estar)).sqrt();
        let p0 = 2.0 * f / (PI * a);
        eprintln!(
            "roller {}: F = {f:.4e}, a = {a_num:.4} (Hertz {a:.4}), p0 = {pmax:.4e} (Hertz {p0:.4e})",
            k + 1
        );
        if k % 2 == 1 {
            // Rollers 2 and 4 are held only by contact: it carries exactly
            // the pressure on their flat top (2R wide).
            let load = pressure * 2.0 * r;
            assert!(
                (f - load).abs() < 1e-8 * load,
                "roller {}: {f} vs {load}",
                k + 1
            );
        }
        // The last closed node is within one contact element (h ≈ 0.03 m) of a.
        assert!(
            (a_num - a).abs() < 0.04,
            "roller {}: a = {a_num}, Hertz {a}",
            k + 1
        );
        assert!(
            (pmax - p0).abs() < 0.06 * p0,
            "roller {}: p0 = {pmax}, Hertz {p0}",
            k + 1
        );
    }
}

/// The glued start (the rows with zero gap: one under each roller) does not
/// hold the rotation of the rollers held only by contact, so the dense
/// coarse problem of ssn's dual-space steps is singular there; ssn restarts
/// them from every row and still finds J without a sparse solve per step
/// (14 KKT solves before that restart on this mesh). The answer agrees with
/// the active set method's.
#[test]
fn ssn_dual_space_start_survives_a_singular_glued_set() {
    let (_, ssn) = solve("ssn");
    assert!(
        ssn.iterations <= 2 && ssn.inner_iterations <= 3,
        "ssn: {} KKT solves, {} sparse solves",
        ssn.iterations,
        ssn.inner_iterations
    );
    let (_, asm) = solve("asm");
    let dx = common::rel_diff(&ssn.x, &asm.x);
    let dl = common::rel_diff(&ssn.lambda, &asm.lambda);
    assert!(dx < 1e-9 && dl < 1e-8, "ssn vs asm: x {dx:.2e}, λ {dl:.2e}");
    // Same input, same bits.
    let (_, again) = solve("ssn");
    assert_eq!(
        ssn.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        again.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
}
