//! End-to-end checks of the pipeline against analytic solutions and against
//! itself (issue: Gmsh + TOML → P1 contact QP → CGC → outputs).

use signorini::qp::QpResult;
use signorini::qp::SolverSection;
use signorini::run::{self, Prepared};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

use common::solve_file;

fn solve_example(name: &str) -> (Prepared, QpResult) {
    solve_file(
        &root().join("meshes").join(format!("{name}.toml")),
        &SolverSection::default(),
    )
}

/// Write a TOML next to nothing (mesh path absolute) in a temp dir.
fn temp_toml(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

mod common;

fn square_mesh(kind: &str) -> String {
    common::msh_fixture(&format!("square_{kind}.msh"))
        .display()
        .to_string()
}

/// Uniaxial stress patch: left slip (ux = 0), bottom slip (uy = 0), traction
/// σ on the right. The exact solution u = (σx/E, −νσy/E) (plane stress) is
/// linear, so P1 must reproduce it to round-off, with or without a
/// conforming contact interface across the load (compression keeps it closed).
fn patch(with_contact: bool) {
    let dir = tempfile::tempdir().unwrap();
    let (e, nu, s) = (7.0e10, 0.28, -3.0e7);
    let contact = if with_contact {
        "[[contact]]\non = \"interface\"\n"
    } else {
        ""
    };
    let text = format!(
        r#"
[mesh]
file = "{}"
[model]
plane = "stress"
thickness = 0.1
[materials.body_left]
E = {e}
nu = {nu}
[materials.body_right]
E = {e}
nu = {nu}
[[slip]]
on = "left"
[[slip]]
on = "bottom"
[[traction]]
on = "right"
pn = {s}
{contact}
[solver]
tol = 1e-12
"#,
        square_mesh("ascii41")
    );
    let p = temp_toml(dir.path(), "patch", &text);
    let (prep, res) = solve_file(&p, &SolverSection::default());
    let u = prep.model.displacements(&res.x);
    for (i, x) in prep.model.topo.points.iter().enumerate() {
        let exact = [s * x[0] / e, -nu * s * x[1] / e];
        for k in 0..2 {
            assert!(
                (u[i][k] - exact[k]).abs() < 1e-12 * (s / e).abs(),
                "point {i}: {:?} vs {:?}",
                u[i],
                exact
            );
        }
    }
    let step = signorini::post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    for st in &step.stress {
        assert!(
            (st[0] - s).abs() < 1e-9 * s.abs()
                && st[1].abs() < 1e-9 * s.abs()
                && st[2].abs() < 1e-9 * s.abs(),
            "{st:?}"
        );
    }
    if with_contact {
        assert_eq!(prep.model.topo.nbodies, 2);
        assert!(
            res.active.iter().all(|a| *a),
            "the compressed interface must stay closed"
        );
        // Contact pressure = −σ on the vertical interface (σxx = s < 0).
        for p in &step.contact_pressure {
            assert!((p + s).abs() < 1e-8 * s.abs(), "pressure {p} vs {}", -s);
        }
    }
}

#[test]
fn patch_test_one_body() {
    patch(false);
}

#[test]
fn patch_test_across_contact_interface() {
    patch(true);
}

#[test]
fn gravity_column_matches_oedometric_solution() {
    let (prep, res) = solve_example("column");
    let f = &prep.problem.file;
    let m = &f.materials["soil"];
    let (e, nu, rho, g) = (m.e, m.nu, m.rho, 9.81);
    let big_m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let h = 10.0;
    let u = prep.model.displacements(&res.x);
    let umax = rho * g / big_m * h * h / 2.0;
    let mut worst: f64 = 0.0;
    for (i, x) in prep.model.topo.points.iter().enumerate() {
        let exact = -(rho * g / big_m) * (h * x[1] - x[1] * x[1] / 2.0);
        worst = worst.max((u[i][1] - exact).abs() / umax);
        assert!(u[i][0].abs() < 1e-4 * umax, "u_x must vanish: {}", u[i][0]);
    }
    // P1 on this mesh: nodal error O(h²); measured worst relative error is printed.
    eprintln!("column: worst |u_y − exact| / u_max = {worst:.3e}");
    assert!(worst < 2e-3, "worst relative error {worst}");
}

#[test]
fn two_blocks_in_full_contact_equal_one_glued_body() {
    let (pa, ra) = solve_example("two_blocks");
    let (pb, rb) = solve_example("two_blocks_glued");
    assert_eq!(pa.model.topo.nbodies, 2);
    assert_eq!(pb.model.topo.nbodies, 1);
    assert!(ra.active.iter().all(|a| *a));
    let ua = pa.model.displacements(&ra.x);
    let ub = pb.model.displacements(&rb.x);
    let scale = ub
        .iter()
        .fold(0.0f64, |m, v| m.max(v[0].abs()).max(v[1].abs()));
    for (i, &node) in pa.model.topo.point_node.iter().enumerate() {
        let j = pb.model.topo.point(node, 0).unwrap();
        for k in 0..2 {
            assert!(
                (ua[i][k] - ub[j][k]).abs() <= 1e-9 * scale,
                "node {node}: {:?} vs {:?}",
                ua[i],
                ub[j]
            );
        }
    }
}

#[test]
fn eccentric_load_opens_part_of_the_interface_with_tight_kkt() {
    let (prep, res) = solve_example("two_blocks_eccentric");
    let k = res.kkt;
    assert!(k.within(1e-8), "{k:?}");
    let na = res.active.iter().filter(|a| **a).count();
    assert!(
        na > 0 && na < res.active.len(),
        "partly open: {na} of {}",
        res.active.len()
    );
    let step = signorini::post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    let gmax = step.gap.iter().fold(0.0f64, |m, g| m.max(*g));
    for (i, (&l, &g)) in res.lambda.iter().zip(&step.gap).enumerate() {
        assert!(l >= 0.0, "row {i}: λ = {l}");
        assert!(g >= -1e-10 * gmax, "row {i}: gap {g}");
    }
    // Opening on the left (unloaded) side: the open rows lie left of the closed ones.
    let rows = &prep.model.topo.contact;
    let open_x: Vec<f64> = rows
        .iter()
        .zip(&step.active)
        .filter(|(_, a)| **a == 0)
        .map(|(r, _)| prep.model.topo.points[r.first][0])
        .collect();
    let closed_x: Vec<f64> = rows
        .iter()
        .zip(&step.active)
        .filter(|(_, a)| **a == 1)
        .map(|(r, _)| prep.model.topo.points[r.first][0])
        .collect();
    let max_open = open_x.iter().fold(f64::MIN, |m, v| m.max(*v));
    let min_closed = closed_x.iter().fold(f64::MAX, |m, v| m.min(*v));
    assert!(
        max_open < min_closed + 1e-12,
        "open up to x = {max_open}, closed from x = {min_closed}"
    );
}

#[test]
fn floating_block_is_in_equilibrium_through_contact() {
    let (prep, res) = solve_example("floating_block");
    assert!(
        !prep.model.qp.kernel.is_empty(),
        "the block must be semicoercive"
    );
    assert!(res.kkt.within(1e-8), "{:?}", res.kkt);
    // The body held only by contact: vertical contact force = its weight + top load.
    let t = &prep.model.topo;
    let fy: f64 = t
        .contact
        .iter()
        .zip(&res.lambda)
        .map(|(r, l)| l * r.normal[1].abs())
        .sum();
    let f = &prep.problem.file;
    let mut weight = 0.0;
    for (e, tri) in t.triangles.iter().enumerate() {
        if t.tri_body[e] == 1 {
            let m = &f.materials[&t.material_names[t.tri_material[e] as usize]];
            let p = [t.points[tri[0]], t.points[tri[1]], t.points[tri[2]]];
            weight += m.rho * 9.81 * signorini::fem::element::area2(&p) / 2.0;
        }
    }
    let d_sum: f64 = {
        // Applied vertical load on body 1 = −(sum of vertical load components)
        let qp = &prep.model.qp;
        let mut z = vec![0.0; qp.n()];
        for (p, pd) in prep.model.dofs.iter().enumerate() {
            if t.point_body[p] == 1 {
                for k in 0..pd.ndof {
                    z[pd.start + k] = pd.t[k][1];
                }
            }
        }
        -z.iter().zip(&qp.d).map(|(a, b)| a * b).sum::<f64>()
    };
    assert!(weight > 0.0);
    assert!(
        (fy - d_sum).abs() < 1e-8 * d_sum,
        "contact force {fy} vs load {d_sum}"
    );
}

#[test]
fn hertz_contact_width_and_peak_pressure() {
    let (prep, res) = solve_example("hertz");
    let step = signorini::post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    let (e, nu) = (2.0e11, 0.3);
    let estar = 1.0 / (2.0 * (1.0 - nu * nu) / e);
    // Full-model force per unit thickness = 2 × the half model's contact force.
    let f_half: f64 = res.lambda.iter().sum();
    let f = 2.0 * f_half;
    let r = 1.0;
    let a = (4.0 * f * r / (std::f64::consts::PI * estar)).sqrt();
    let p0 = 2.0 * f / (std::f64::consts::PI * a);
    let t = &prep.model.topo;
    let xs: Vec<f64> = t
        .contact
        .iter()
        .zip(&step.active)
        .filter(|(_, a)| **a == 1)
        .map(|(r, _)| t.points[r.first][0])
        .collect();
    let a_num = xs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let pmax = step.contact_pressure.iter().fold(0.0f64, |m, p| m.max(*p));
    eprintln!("hertz: a = {a_num:.4} (analytic {a:.4}), p0 = {pmax:.4e} (analytic {p0:.4e})");
    // The last closed slave node lies within one contact element (a/15) of a.
    assert!((a_num - a).abs() < 0.1 * a, "a = {a_num}, analytic {a}");
    assert!((pmax - p0).abs() < 0.03 * p0, "p0 = {pmax}, analytic {p0}");
    // The pressure profile follows p0·sqrt(1 − x²/a²) inside the contact.
    for (row, p) in t.contact.iter().zip(&step.contact_pressure) {
        let x = t.points[row.first][0].abs();
        if x < 0.7 * a {
            let ph = p0 * (1.0 - x * x / (a * a)).sqrt();
            assert!(
                (p - ph).abs() < 0.05 * p0,
                "x = {x}: p = {p:.4e}, Hertz {ph:.4e}"
            );
        }
    }
}

#[test]
fn ascii_and_binary_meshes_give_identical_results() {
    let dir = tempfile::tempdir().unwrap();
    let mut out = vec![];
    for kind in ["ascii41", "bin41"] {
        let text = format!(
            "[mesh]\nfile = \"{}\"\n[model]\ngravity = [0.0, -9.81]\n[materials.body_left]\nE = 1e9\nnu = 0.3\nrho = 2000.0\n[materials.body_right]\nE = 2e9\nnu = 0.25\nrho = 1000.0\n[[dirichlet]]\non = \"bottom\"\nu = [0.0, 0.0]\n[[traction]]\non = \"top\"\np = [1e5, -1e6]\n[[contact]]\non = \"interface\"\n",
            square_mesh(kind)
        );
        let p = temp_toml(dir.path(), kind, &text);
        let (prep, res) = solve_file(&p, &SolverSection::default());
        out.push((prep.model.displacements(&res.x), res.lambda.clone()));
    }
    assert_eq!(out[0].0, out[1].0, "bit-identical displacements");
    assert_eq!(out[0].1, out[1].1, "bit-identical multipliers");
}

#[test]
fn every_shipped_example_solves_with_the_default_method() {
    let mut names: Vec<String> = std::fs::read_dir(root().join("meshes"))
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().map(|x| x == "toml").unwrap_or(false))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 6, "{names:?}");
    for n in names {
        let (_, res) = solve_example(&n);
        assert!(res.kkt.within(1e-8), "{n}: {:?}", res.kkt);
    }
}

#[test]
fn point_force_is_per_unit_thickness_in_plane_stress() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "[mesh]\nfile = \"{}\"\n[model]\nplane = \"stress\"\nthickness = 0.1\n[materials.body_left]\nE = 1e9\nnu = 0.3\n[materials.body_right]\nE = 1e9\nnu = 0.3\n[[dirichlet]]\non = \"top\"\nu = [0.0, 0.0]\n[[force]]\non = \"corner\"\nf = [1e3, 2e3]\n",
        square_mesh("ascii41")
    );
    let p = temp_toml(dir.path(), "force", &text);
    let prep = run::prepare(&p, false).unwrap();
    let m = &prep.model;
    let corner = m
        .topo
        .points
        .iter()
        .position(|x| x[0] == 0.0 && x[1] == 0.0)
        .unwrap();
    let pd = m.dofs[corner];
    assert_eq!(pd.ndof, 2);
    // The load vector holds t_h·f at the corner and nothing else.
    assert!(
        (m.qp.d[pd.start] - 100.0).abs() < 1e-9 && (m.qp.d[pd.start + 1] - 200.0).abs() < 1e-9,
        "{:?}",
        &m.qp.d[pd.start..pd.start + 2]
    );
    let total: f64 = m.qp.d.iter().map(|v| v.abs()).sum();
    assert!((total - 300.0).abs() < 1e-9, "{total}");
}
