//! Trust on hard models (docs/methods.md §8): a stiff body held only by
//! contact on a soft one is solved, never refused as unbounded; certified
//! means the contact forces are right; the same input gives the same bits;
//! NaN, overflowing data and absurd warm starts are never certified.
//!
//! The model is tests/data/punch (a steel punch floating on a soft
//! foundation, stiffness contrast 4200 and 1000, non-matching contact).

use signorini::fem::Model;
use signorini::problem::Problem;
use signorini::qp::{registry, SolveOptions, Status};
use std::path::PathBuf;

mod common;

use common::{rel_diff as rel, root};

fn dir() -> PathBuf {
    root().join("tests/data/punch")
}

/// The punch model with the punch's Young's modulus replaced.
fn punch(e_punch: f64) -> Model {
    let path = dir().join("punch.toml");
    let text = std::fs::read_to_string(&path)
        .expect("punch.toml")
        .replace("E = 2.1e11", &format!("E = {e_punch:e}"));
    let problem = Problem::parse(&path, &text).expect("problem");
    let mesh = signorini::mesh::read_msh(&problem.mesh_path()).expect("mesh");
    signorini::fem::build(&mesh, &problem).expect("model")
}

/// Every exact method solves the floating punch, certifies its KKT residuals
/// and agrees with the others on x and on the contact forces λ to 1e-6; the
/// vertical contact resultant equals the load 1 MPa × 2 m.
#[test]
fn a_stiff_punch_floating_on_a_soft_foundation_is_solved_not_refused() {
    for e in [2.1e11, 5.0e10] {
        let model = punch(e);
        assert!(!model.qp.kernel.is_empty(), "the punch must float");
        let reference = registry::solve("asm", &model.qp, &SolveOptions::default()).expect("asm");
        assert!(
            reference.status.converged() && reference.kkt.within(1e-8),
            "{:?}",
            reference.kkt
        );
        for method in ["cgc", "preelim", "ssn", "mprgp", "dual"] {
            let r = registry::solve(method, &model.qp, &SolveOptions::default())
                .unwrap_or_else(|err| panic!("E = {e:e}, {method}: {err}"));
            assert!(
                matches!(r.status, Status::Converged),
                "E = {e:e}, {method}: {}",
                r.status.describe()
            );
            assert!(r.kkt.within(1e-6), "E = {e:e}, {method}: {:?}", r.kkt);
            let (dx, dl) = (rel(&r.x, &reference.x), rel(&r.lambda, &reference.lambda));
            assert!(
                dx < 1e-6 && dl < 1e-6,
                "E = {e:e}, {method}: x {dx:.2e}, λ {dl:.2e}"
            );
            // Σλ·n_y: the rows of a horizontal master carry unit normals, so
            // the resultant is the sum of the multipliers.
            let total: f64 = r.lambda.iter().sum();
            assert!(
                (total - 2.0e6).abs() < 1e-6 * 2.0e6,
                "E = {e:e}, {method}: {total}"
            );
        }
    }
}

/// Same input, same bits: iterations, active set, x and λ.
#[test]
fn the_same_input_gives_the_same_bits() {
    let model = punch(2.1e11);
    for method in ["cgc", "ssn", "mprgp", "penalty"] {
        let a = registry::solve(method, &model.qp, &SolveOptions::default()).expect(method);
        let b = registry::solve(method, &model.qp, &SolveOptions::default()).expect(method);
        assert_eq!(a.iterations, b.iterations, "{method}");
        assert_eq!(a.active, b.active, "{method}");
        assert!(
            a.x.iter()
                .zip(&b.x)
                .all(|(p, q)| p.to_bits() == q.to_bits()),
            "{method}: x differs between two runs"
        );
        assert!(
            a.lambda
                .iter()
                .zip(&b.lambda)
                .all(|(p, q)| p.to_bits() == q.to_bits()),
            "{method}: λ differs between two runs"
        );
    }
}

/// Same bits on any number of cores: `signorini solve` on a three-body
/// mesh of 89 k nodes (meshed here by Gmsh, as the benchmark does) writes
/// the same VTU bytes with SIGNORINI_THREADS=1 (sequential assembly, one
/// worker) and 2. Before faer's split was fixed (`linalg::PAR_SPLITS`,
/// docs/methods.md §8.5) the stresses of this very model differed by 1e-13
/// relative between the two.
#[test]
fn the_bits_do_not_depend_on_the_number_of_threads() {
    let d = tempfile::tempdir().unwrap();
    let geo = common::meshes().join("three_bodies.geo");
    let msh = d.path().join("three_bodies.msh");
    let st = std::process::Command::new("gmsh")
        .args([
            "-2", "-format", "msh41", "-bin", "-algo", "del2d", "-clscale", "0.102",
        ])
        .arg(&geo)
        .arg("-o")
        .arg(&msh)
        .output()
        .expect("gmsh (scripts/setup.sh installs it)");
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    // The shipped problem file, beside the finer mesh of the same name.
    let model = d.path().join("three_bodies.toml");
    std::fs::copy(common::meshes().join("three_bodies.toml"), &model).unwrap();
    let vtu = |threads: &str| {
        let out = d.path().join(format!("out{threads}"));
        let o = common::command()
            .env("SIGNORINI_THREADS", threads)
            .args(["solve", "--method", "ssn", "-q", "-o"])
            .arg(&out)
            .arg(&model)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v = std::fs::read(out.join("three_bodies.vtu")).unwrap();
        let c = std::fs::read(out.join("three_bodies_contact.vtu")).unwrap();
        (v, c)
    };
    let (one, two) = (vtu("1"), vtu("2"));
    assert!(one.0.len() > 1_000_000, "a mesh of ~89 k nodes");
    assert!(one.0 == two.0, "the VTU differs between 1 and 2 threads");
    assert!(
        one.1 == two.1,
        "the contact VTU differs between 1 and 2 threads"
    );
}

/// A warm start holding 1e300 or NaN (a corrupt checkpoint) is not used, the
/// result says so and is still certified; data that overflow are refused.
#[test]
fn absurd_warm_starts_and_overflowing_data_are_never_certified() {
    let model = punch(2.1e11);
    for bad in [1e300, f64::NAN] {
        let opts = SolveOptions {
            x0: Some(vec![bad; model.qp.n()]),
            ..Default::default()
        };
        for method in ["cgc", "ssn"] {
            let r = registry::solve(method, &model.qp, &opts).expect(method);
            assert!(
                r.notes
                    .iter()
                    .any(|n| n.to_string().contains("warm start not used")),
                "{:?}",
                r.notes
            );
            assert!(
                r.status.converged() && r.kkt.within(1e-6),
                "{method}: {:?}",
                r.kkt
            );
        }
    }
    let mut qp = model.qp.clone();
    qp.d[0] = f64::INFINITY;
    let err = registry::solve("cgc", &qp, &SolveOptions::default()).expect_err("Inf load");
    assert!(err.to_string().contains("non-finite"), "{err}");
}

/// Pulling the punch up instead of pressing it down is unbounded: refused
/// with a verified recession direction (an upward translation, dᵀr > 0),
/// before any method runs, for every method.
#[test]
fn a_punch_pulled_away_is_unbounded_with_a_certificate() {
    let mut model = punch(2.1e11);
    for v in model.qp.d.iter_mut() {
        *v = -*v;
    }
    for method in ["cgc", "ssn", "asm", "uzawa"] {
        let r = registry::solve(method, &model.qp, &SolveOptions::default()).expect(method);
        let Status::Unbounded { direction } = &r.status else {
            panic!("{method}: {}", r.status.describe());
        };
        let c = signorini::qp::recession::certify(&model.qp, direction).expect("certificate");
        assert!(c.work > 0.0);
        let u = model.motions(direction);
        assert!(
            model
                .describe_rigid_motion(&u)
                .contains("translation along (0, 1)"),
            "{}",
            model.describe_rigid_motion(&u)
        );
    }
}

/// A soft keystone between steel abutments (tests/data/keystone: conforming
/// joints, the keystone held only by them, loaded on part of its top) at
/// contrasts 1e4 and 1e7: ssn settles on its first working set and agrees
/// with asm. Before the working-set rule measured λ and the gaps each in
/// their own units, the joint ends' small multipliers fell below a
/// threshold scaled by the steel's stiffness: they left J, penetrated, came
/// back, and after 10 000 steps the run stopped, not certified.
#[test]
fn a_soft_keystone_between_steel_abutments_settles() {
    let path = root().join("tests/data/keystone/keystone.toml");
    let base = std::fs::read_to_string(&path).expect("keystone.toml");
    assert!(
        base.contains("E = 2.0e4"),
        "the keystone modulus to replace"
    );
    for e_key in [2.0e7, 2.0e4] {
        let text = base.replace("E = 2.0e4", &format!("E = {e_key:e}"));
        let problem = Problem::parse(&path, &text).expect("problem");
        let mesh = signorini::mesh::read_msh(&problem.mesh_path()).expect("mesh");
        let model = signorini::fem::build(&mesh, &problem).expect("model");
        assert!(!model.qp.kernel.is_empty(), "the keystone must float");
        let reference = registry::solve("asm", &model.qp, &SolveOptions::default()).expect("asm");
        assert!(reference.status.converged() && reference.kkt.within(1e-8));
        let r = registry::solve("ssn", &model.qp, &SolveOptions::default()).expect("ssn");
        assert!(
            matches!(r.status, Status::Converged) && r.iterations <= 2,
            "E = {e_key:e}: {} after {} KKT solves",
            r.status.describe(),
            r.iterations
        );
        assert!(r.kkt.within(1e-6), "E = {e_key:e}: {:?}", r.kkt);
        let (dx, dl) = (rel(&r.x, &reference.x), rel(&r.lambda, &reference.lambda));
        assert!(
            dx < 1e-8 && dl < 1e-8,
            "E = {e_key:e}: x {dx:.2e}, λ {dl:.2e}"
        );
    }
}

/// The keystone of [`a_soft_keystone_between_steel_abutments_settles`] with
/// friction on both joints (the joints are ~15° from vertical, so with
/// μ = 0.3 > tan 15° the keystone wedges in). At contrasts 1e2, 1e4 and 1e7
/// ssn and mprgp both end certified and agree. Before: ssn judged every
/// row with one constant (the mean of diag C) and weighted the augmented
/// Lagrangian with one ρ (from max diag C), so a soft body's rows were
/// predicted and measured at the steel's scale: Tresca cycled for 10 000
/// steps; and the Coulomb loop s = μλ_n alternated between two bounds 55 %
/// and 84 % apart until both methods gave up (docs/methods.md §9.1).
#[test]
fn a_wedged_keystone_with_friction_is_certified_at_any_contrast() {
    let path = root().join("tests/data/keystone/keystone.toml");
    let base = std::fs::read_to_string(&path).expect("keystone.toml");
    for (e_abut, law) in [
        (2.0e6, "tresca = 1.0e4"),
        (2.0e6, "friction = 0.3"),
        (2.0e8, "friction = 0.3"),
        (2.0e11, "friction = 0.3"),
    ] {
        let text = base
            .replace("E = 2.0e11", &format!("E = {e_abut:e}"))
            .replace("on = \"joint1\"", &format!("on = \"joint1\"\n{law}"))
            .replace("on = \"joint2\"", &format!("on = \"joint2\"\n{law}"));
        assert!(text.contains(law) && !text.contains("2.0e11"));
        let problem = Problem::parse(&path, &text).expect("problem");
        let mesh = signorini::mesh::read_msh(&problem.mesh_path()).expect("mesh");
        let model = signorini::fem::build(&mesh, &problem).expect("model");
        assert!(model.qp.friction.is_some() && !model.qp.kernel.is_empty());
        let what = format!("abutments E = {e_abut:e}, {law}");
        let mut xs = vec![];
        for method in ["ssn", "mprgp"] {
            let r = registry::solve(method, &model.qp, &SolveOptions::default()).expect(method);
            assert!(
                matches!(r.status, Status::Converged),
                "{what}, {method}: {} after {} iterations",
                r.status.describe(),
                r.iterations
            );
            assert!(r.kkt.within(1e-6), "{what}, {method}: {:?}", r.kkt);
            assert!(
                r.lambda_t.iter().any(|l| l.abs() > 0.0),
                "{what}, {method}: no tangential force"
            );
            xs.push(r.solution.x);
        }
        let dx = rel(&xs[0], &xs[1]);
        assert!(dx < 1e-6, "{what}: ssn and mprgp differ by {dx:.2e}");
    }
}

/// tests/data/gasket: a rubber gasket in a steel groove (three non-matching
/// pairs, corner nodes on two of them) under a steel plate held only by the
/// gasket and two slip lines, the gasket floating too, so C has a partial
/// kernel (the plate's vertical slide) and the gasket's three rigid modes.
/// At contrasts 1e4 and 1e8 (loads scaled with the rubber, so the strains
/// are the same) every exact method named (the primal cgc:cholesky and
/// preelim included) is certified and agrees with ssn
/// on x and λ; the slip lines carry no vertical force, so the groove floor
/// carries the whole load through the gasket, and the two walls push on it
/// with equal and opposite forces.
#[test]
fn a_gasket_under_a_sliding_plate_balances_at_any_contrast() {
    use signorini::post;
    use signorini::qp::SolverSection;
    use signorini::run;
    let dir = root().join("tests/data/gasket");
    let tmp = tempfile::tempdir().expect("tempdir");
    for e_rubber in [2.0e7, 2.0e3] {
        let s = e_rubber / 2.0e5;
        let (e, pl, pr) = (
            format!("E = {e_rubber:e}"),
            format!("pn = {:e}", -2.0e4 * s),
            format!("pn = {:e}", -5.0e3 * s),
        );
        let path = common::model_variant(
            &dir,
            "gasket.toml",
            &[
                ("E = 2.0e5", &e),
                ("pn = -2.0e4", &pl),
                ("pn = -5.0e3", &pr),
            ],
            &tmp.path().join(format!("gasket_{e_rubber:e}.toml")),
        );
        let prep = run::prepare(&path, false).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            prep.model.qp.kernel.len() >= 4,
            "the plate and the gasket float"
        );
        let load = 3.75e4 * s; // (20 + 5) kPa × 1.5 m
        let mut reference: Option<(Vec<f64>, Vec<f64>)> = None;
        // cgc:cholesky and preelim stopped uncertified at 1e8 (stationarity
        // 5.5e-4 and 3.7e-6) while their rounding-floor bound (10³ above the
        // noise they reach) licensed the stop without a stall.
        for (method, pc) in [
            ("ssn", None),
            ("asm", None),
            ("mprgp", None),
            ("dual", None),
            ("cgc", Some("cholesky")),
            ("preelim", None),
        ] {
            let choice = SolverSection {
                preconditioner: pc.map(|p| p.parse().unwrap()),
                ..SolverSection::default()
            };
            let (_, opts) = run::options(&prep.problem, &choice).expect("options");
            let what = format!("rubber E = {e_rubber:e}, {method}");
            let r = solve_certified(&prep, method, &opts, &what);
            match &reference {
                None => reference = Some((r.x.clone(), r.lambda.clone())),
                Some((x, l)) => {
                    let (dx, dl) = (rel(&r.x, x), rel(&r.lambda, l));
                    assert!(dx < 1e-6 && dl < 1e-6, "{what}: x {dx:.2e}, λ {dl:.2e}");
                }
            }
            let (_, f) =
                post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &r, 1.0);
            let on = |name: &str| interface_resultant(&f, name, &what);
            let floor = on("gasket_bottom->groove_floor");
            let top = on("gasket_top->plate_bottom");
            let (left, right) = (
                on("gasket_left->groove_left"),
                on("gasket_right->groove_right"),
            );
            assert!(
                (floor.force[1] - load).abs() < 1e-6 * load,
                "{what}: floor {floor:?}"
            );
            assert!(
                (top.force[1] + load).abs() < 1e-6 * load,
                "{what}: top {top:?}"
            );
            assert!(
                left.force[0] > 0.1 * load,
                "{what}: the walls hold the gasket: {left:?}"
            );
            assert!(
                (left.force[0] + right.force[0]).abs() < 1e-6 * load,
                "{what}: walls {left:?} {right:?}"
            );
        }
    }
}

/// tests/data/slope: a steel block resting on a 25° rubber slope against a
/// rubber stop, under gravity alone (rotated geometry, non-matching pairs on
/// inclined masters, the block's corner a slave of both pairs, the block
/// floating). Frictionless, so the slope carries W cos θ along its normal
/// and the stop W sin θ along its own, whatever the contrast. At a contrast
/// of 2.1e8 (rubber E = 1e3, density scaled with it so the strains are the
/// same) the block's rigid motion is 10⁸ times its deformation: f64 holds
/// the deformation only to ε·|x|, and every method's stationarity stood at
/// 7e-6, uncertified (exit 3). The certificate now allows the residual's
/// rounding floor (docs/methods.md §8.4); the answer is still held to the
/// analytic resultants and to the other methods.
#[test]
fn a_block_on_a_rubber_slope_is_certified_and_balanced_at_any_contrast() {
    use signorini::post;
    use signorini::run;
    let dir = root().join("tests/data/slope");
    let tmp = tempfile::tempdir().expect("tempdir");
    let theta = 25f64.to_radians();
    for (e_pad, rho) in [(1.0e6, 7850.0), (1.0e3, 7.85)] {
        let (e, r) = (format!("E = {e_pad:e}"), format!("rho = {rho:e}"));
        let path = common::model_variant(
            &dir,
            "slope.toml",
            &[("E = 1.0e6", &e), ("rho = 7850.0", &r)],
            &tmp.path().join(format!("slope_{e_pad:e}.toml")),
        );
        let (prep, opts) = prepared(&path);
        assert_eq!(prep.model.qp.kernel.len(), 3, "the block floats");
        let w = rho * 9.81 * 1.2 * 0.6; // the block's weight per unit thickness
        let slope_force = [
            -w * theta.cos() * theta.sin(),
            w * theta.cos() * theta.cos(),
        ];
        let stop_force = [w * theta.sin() * theta.cos(), w * theta.sin() * theta.sin()];
        let mut reference: Option<(Vec<f64>, Vec<f64>)> = None;
        for method in ["ssn", "asm", "mprgp", "dual"] {
            let what = format!("pad E = {e_pad:e}, {method}");
            let r = run::solve(&prep, method, &opts).unwrap_or_else(|e| panic!("{what}: {e}"));
            // At 2.1e8 the dual family stops with gaps right to its relative
            // tolerance only, and its contact forces on the stop were 20 %
            // off per row: it must not be certified at the floor then. asm's
            // forces leave the block out of balance by 6.3e-6 there (rigid
            // balance, docs/methods.md §8.4; ssn: 5e-16): not certified.
            let must = e_pad > 1e3 || method == "ssn";
            let certified = matches!(r.status, Status::Converged) && r.kkt.within(1e-6);
            assert!(
                certified || !must,
                "{what}: {} {:?}",
                r.status.describe(),
                r.kkt
            );
            if !certified {
                continue;
            }
            assert!(r.kkt.stationarity_floor < 1e-4, "{what}: {:?}", r.kkt);
            // Rounding in the block's balance acts as a load of relative
            // size up to the floor, which the soft pad answers in kind: at
            // 2.1e8, x and λ of two methods differ by 7e-6 and 8e-6 with a
            // floor of 2.9e-5 (at 2.1e5: below 1e-8).
            let agree = r.kkt.stationarity_floor.max(1e-6);
            match &reference {
                None => reference = Some((r.x.clone(), r.lambda.clone())),
                Some((x, l)) => {
                    let (dx, dl) = (rel(&r.x, x), rel(&r.lambda, l));
                    assert!(
                        dx < agree && dl < agree,
                        "{what}: x {dx:.2e}, λ {dl:.2e}, tolerance {agree:.1e}"
                    );
                }
            }
            let (_, f) =
                post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &r, 1.0);
            let on = |name: &str| interface_resultant(&f, name, &what);
            let (slope, stop) = (on("block_bottom->slope"), on("block_left->stop"));
            for (got, want, name) in [(slope, slope_force, "slope"), (stop, stop_force, "stop")] {
                let err =
                    ((got.force[0] - want[0]).powi(2) + (got.force[1] - want[1]).powi(2)).sqrt();
                assert!(
                    err < 1e-5 * w,
                    "{what}: {name} carries {:?}, analytic {want:?} (error {:.1e} W)",
                    got.force,
                    err / w
                );
            }
        }
    }
}

/// The same block held on the slope by Coulomb friction alone (μ = 0.6 >
/// tan 25°; the stop removed) at a contrast of 2.1e7: not refused as
/// sliding, and the slope carries the whole weight, (0, W), normal and
/// tangential together. Frictional ssn leaves 0.51‖e‖ of rounding in its
/// stationarity (1.34e-6 > 1e-6; its solves are with C + ρBᵀB) and is
/// certified at the floor; mprgp is certified outright; they agree.
#[test]
fn a_block_held_on_a_rubber_slope_by_friction_alone_is_certified() {
    use signorini::post;
    let dir = root().join("tests/data/slope");
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::model_variant(
        &dir,
        "slope.toml",
        &[
            ("E = 1.0e6", "E = 1.0e4"),
            ("rho = 7850.0", "rho = 78.5"),
            (
                "[[contact]]\nslave = \"block_left\"\nmaster = \"stop\"\n",
                "",
            ),
            ("master = \"slope\"", "master = \"slope\"\nfriction = 0.6"),
        ],
        &tmp.path().join("slope_friction.toml"),
    );
    let (prep, opts) = prepared(&path);
    let w = 78.5 * 9.81 * 1.2 * 0.6;
    let mut xs = vec![];
    for method in ["ssn", "mprgp"] {
        let r = solve_certified(&prep, method, &opts, method);
        let (_, f) =
            post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &r, 1.0);
        let on = interface_resultant(&f, "block_bottom->slope", method);
        assert!(
            on.force[0].abs() < 1e-6 * w && (on.force[1] - w).abs() < 1e-6 * w,
            "{method}: the slope carries {:?}, the weight is {w}",
            on.force
        );
        xs.push(r.solution.x);
    }
    assert!(
        rel(&xs[0], &xs[1]) < 1e-6,
        "ssn and mprgp: {:.2e}",
        rel(&xs[0], &xs[1])
    );
}

/// `method` on a prepared model, which must converge with a certificate
/// (≤ 1e-6, rounding floor included); `what` names the case on failure.
fn solve_certified(
    prep: &signorini::run::Prepared,
    method: &str,
    opts: &SolveOptions,
    what: &str,
) -> signorini::qp::QpResult {
    let r = signorini::run::solve(prep, method, opts).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        matches!(r.status, Status::Converged) && r.kkt.within(1e-6),
        "{what}: {} {:?}",
        r.status.describe(),
        r.kkt
    );
    r
}

/// The resultant of the contact forces of interface `name` (post's own
/// forces, tangential ones included).
fn interface_resultant(
    f: &signorini::post::forces::Forces,
    name: &str,
    what: &str,
) -> signorini::post::forces::Resultant {
    f.interfaces
        .iter()
        .find(|i| i.name == name)
        .unwrap_or_else(|| panic!("{what}: no interface {name}"))
        .resultant
}

/// A segmental arch of five voussoirs held only by contact on radial joints
/// (tests/data/arch: 15 rigid modes, conforming inner joints, non-matching
/// springings, a soft crown block at contrast 2e5 to the steel abutments).
///
/// Frictionless, the voussoirs can slide along all six joints at once
/// without opening any (translations along the joints' radial directions
/// that close the chain: a 4-parameter family on which gravity does work),
/// so the problem is unbounded: refused before any method runs, naming
/// every voussoir's motion. With Coulomb friction 0.8 ssn and mprgp are
/// certified and agree, and each voussoir is in equilibrium under the forces
/// the post-processing reports: on v1, v3, v4 and v5 (gravity only; the
/// haunch load is on v2) the two joints carry the weight ρ g A,
/// A = (28/360) π (2.6² − 2²), and no net horizontal force: the arch's
/// thrust passes from joint to joint unchanged.
#[test]
fn an_arch_of_voussoirs_slides_without_friction_and_stands_with_it() {
    use signorini::post;
    use signorini::run;
    let dir = root().join("tests/data/arch");
    let tmp = tempfile::tempdir().expect("tempdir");
    let frictionless = common::model_variant(
        &dir,
        "arch.toml",
        &[("friction = 0.8\n", "")],
        &tmp.path().join("arch_frictionless.toml"),
    );
    let said = match run::prepare(&frictionless, false) {
        Ok(_) => panic!("the frictionless arch was accepted"),
        Err(e) => format!("{e:#}"),
    };
    assert!(said.contains("unbounded"), "{said}");
    for v in ["v1", "v2", "v3", "v4", "v5"] {
        assert!(said.contains(&format!("body '{v}' (translation")), "{said}");
    }

    let (prep, opts) = prepared(&dir.join("arch.toml"));
    let area = 28.0 / 360.0 * std::f64::consts::PI * (2.6f64.powi(2) - 2.0f64.powi(2));
    let (w_stone, w_crown) = (2400.0 * 9.81 * area, 1200.0 * 9.81 * area);
    let mut xs = vec![];
    for method in ["ssn", "mprgp"] {
        let r = solve_certified(&prep, method, &opts, method);
        let (_, f) =
            post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &r, 1.0);
        // The force on body `on` across interface `name`.
        let on = |name: &str, body: &str| {
            let i = f
                .interfaces
                .iter()
                .find(|i| i.name == name)
                .unwrap_or_else(|| panic!("{method}: no interface {name}"));
            if i.on_body == body {
                i.resultant.force
            } else {
                i.other.force
            }
        };
        let sum = |a: [f64; 2], b: [f64; 2]| [a[0] + b[0], a[1] + b[1]];
        let blocks = [
            (
                "v1",
                sum(on("joint1", "v1"), on("spring_r_v->spring_r_a", "v1")),
                w_stone,
            ),
            ("v3", sum(on("joint2", "v3"), on("joint3", "v3")), w_crown),
            ("v4", sum(on("joint3", "v4"), on("joint4", "v4")), w_stone),
            (
                "v5",
                sum(on("joint4", "v5"), on("spring_l_v->spring_l_a", "v5")),
                w_stone,
            ),
        ];
        for (v, force, w) in blocks {
            assert!(
                force[0].abs() < 1e-3 * w && (force[1] - w).abs() < 1e-3 * w,
                "{method}: the joints of {v} carry {force:?}, its weight is {w}"
            );
        }
        xs.push(r.solution.x);
    }
    assert!(
        rel(&xs[0], &xs[1]) < 1e-6,
        "ssn and mprgp: {:.2e}",
        rel(&xs[0], &xs[1])
    );
}

/// A rubber ring pressed between two steel plates (tests/data/ring,
/// contrast 2e4): nothing fixes where along the plates the ring sits (it
/// slides along every contact row without opening one, and no load works
/// on that motion), so the solution is unique only up to that translation.
/// Every exact method returns the one without it, certified, says so, and
/// agrees with the others; each plate carries the lid's load, 1 kPa × 2 m.
/// Before, ssn, mprgp, dual and preelim refused the problem (a singular KKT
/// system, a degenerate dual equality, a singular C₁₁) and the methods that
/// solved it returned the ring shifted by different amounts.
#[test]
fn a_ring_free_to_slide_between_two_plates_gets_one_answer() {
    use signorini::post;
    let (prep, opts) = prepared(&root().join("tests/data/ring/ring.toml"));
    let load = 1e3 * 2.0;
    let methods = ["asm", "ssn", "mprgp", "dual", "preelim"];
    let runs = one_answer(&prep, &opts, &methods, "unique only up to 1 rigid motion");
    for (method, r) in methods.iter().zip(&runs) {
        let (_, f) =
            post::step_output_with_forces(&prep.model, &prep.problem.file.materials, r, 1.0);
        for pair in ["ring_out->bottom_face", "ring_out->top_face"] {
            let on = interface_resultant(&f, pair, method);
            assert!(
                on.force[0].abs() < 1e-6 * load && (on.force[1].abs() - load).abs() < 1e-6 * load,
                "{method}: {pair} carries {:?}",
                on.force
            );
        }
    }
}

/// The same ring under 1 kPa, 1 Pa and 1 mPa: the contact gaps (up to
/// 5 cm) do not scale with the load, and the dual family must not care.
/// Before, mprgp took 535 iterations at 1 kPa, 21 157 at 1 Pa and failed on
/// stagnation at 1 mPa (its tolerance was relative to ‖h‖, dominated by the
/// open gaps); with that scale fixed it came out rotated by 1.4e-3 at
/// 1 mPa (the rigid part of x from the SMALBE multiplier, a difference of
/// gap-sized terms). Every method is certified at every load, agrees with
/// ssn, and the dual family's iteration count does not grow as the load falls.
#[test]
fn the_dual_family_does_not_depend_on_the_load_scale() {
    let dir = root().join("tests/data/ring");
    let tmp = tempfile::tempdir().expect("tempdir");
    let mut iters = vec![];
    for (i, pn) in ["-1.0e3", "-1.0", "-1.0e-3"].iter().enumerate() {
        let path = common::model_variant(
            &dir,
            "ring.toml",
            &[("pn = -1.0e3", &format!("pn = {pn}"))],
            &tmp.path().join(format!("ring_{i}.toml")),
        );
        let (prep, opts) = prepared(&path);
        let runs = one_answer(
            &prep,
            &opts,
            &["ssn", "mprgp", "dual", "uzawa"],
            "unique only up to 1 rigid motion",
        );
        iters.push(runs[1].iterations);
    }
    assert!(
        iters[1] <= iters[0] && iters[2] <= 2 * iters[1],
        "mprgp iterations at 1 kPa, 1 Pa, 1 mPa: {iters:?}"
    );
}

/// The ring of [`a_ring_free_to_slide_between_two_plates_gets_one_answer`]
/// under a hundredth of the load: each plate touches it at one node, and
/// the ring may also roll (and the top plate rock) until a neighbouring node
/// touches: a segment of solutions with the same λ. Each method's answer is
/// moved to the point of least rolling the gaps allow, so all agree. Before,
/// ssn stalled on a singular coarse problem, the dual family stalled above
/// its own tolerance (now judged by the certificate), and the answers were
/// rolled by different amounts (x 20× apart in relative terms). The same
/// with Coulomb friction, where rolling about a contact node does not slip.
#[test]
fn a_lightly_loaded_ring_free_to_roll_gets_one_answer() {
    let dir = root().join("tests/data/ring");
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::model_variant(
        &dir,
        "ring.toml",
        &[("pn = -1.0e3", "pn = -10.0")],
        &tmp.path().join("ring_light.toml"),
    );
    let (prep, opts) = prepared(&path);
    one_answer(
        &prep,
        &opts,
        &["asm", "ssn", "mprgp", "dual", "uzawa"],
        "that the rows carrying a force leave free",
    );
    // With Coulomb friction 0.3 the ring can still roll about its contact
    // nodes (no slip there): ssn returns the least roll (8.6 apart from
    // mprgp in relative x before). mprgp stops on stagnation with the
    // ring's forces 1.1e-6 out of balance (rigid balance, docs/methods.md
    // §8.4): if it is certified it must agree, if not that is the reason.
    let path = common::model_variant(
        &dir,
        "ring.toml",
        &[
            ("pn = -1.0e3", "pn = -10.0"),
            ("max_gap = 0.05", "max_gap = 0.05\nfriction = 0.3"),
        ],
        &tmp.path().join("ring_light_friction.toml"),
    );
    let (prep, opts) = prepared(&path);
    let runs = one_answer(
        &prep,
        &opts,
        &["ssn"],
        "that the rows carrying a force leave free",
    );
    let m = signorini::run::solve(&prep, "mprgp", &opts).expect("mprgp runs");
    if m.kkt.within(1e-6) {
        let d = rel(&m.x, &runs[0].x);
        assert!(d < 1e-6, "mprgp: x {d:.2e} from ssn");
    } else {
        let without = signorini::qp::Kkt {
            rigid_balance: 0.0,
            ..m.kkt
        };
        assert!(
            without.within(1e-6) && m.kkt.rigid_balance > 1e-6,
            "mprgp: {:?}",
            m.kkt
        );
    }
}

/// A steel deck on two rubber bearings (tests/data/deck, a geometry unlike
/// the shipped ones), at a contrast of 2.1e4 and of 1e8: every exact
/// method with a direct factor is certified, agrees with ssn in x and λ,
/// and the bearings carry the deck's weight and load. At 1e8, before the
/// dual host judged its own answer by the certificate, uzawa, dual and
/// mprgp stopped with gaps exact to 2–5e-13 only and were refused.
#[test]
fn a_steel_deck_on_rubber_bearings_is_certified_at_any_contrast() {
    use signorini::post;
    let dir = root().join("tests/data/deck");
    let tmp = tempfile::tempdir().expect("tempdir");
    let soft = common::model_variant(
        &dir,
        "deck.toml",
        &[
            ("E = 1.0e7", "E = 2.1e3"),
            ("pn = -1.0e5", "pn = -0.1"),
            ("gravity = [0.0, -9.81]", "gravity = [0.0, 0.0]"),
        ],
        &tmp.path().join("deck_1e8.toml"),
    );
    // (model, vertical load on the deck per metre of thickness)
    let cases = [
        (dir.join("deck.toml"), 1e5 * 2.0 + 7850.0 * 9.81 * 5.0),
        (soft, 0.1 * 2.0),
    ];
    for (path, load) in cases {
        let (prep, opts) = prepared(&path);
        let what = path.display().to_string();
        let ssn = solve_certified(&prep, "ssn", &opts, &what);
        for m in ["asm", "mprgp", "dual", "uzawa", "ssn"] {
            let r = solve_certified(&prep, m, &opts, &format!("{what}: {m}"));
            let (dx, dl) = (rel(&r.x, &ssn.x), rel(&r.lambda, &ssn.lambda));
            assert!(
                dx < 1e-6 && dl < 1e-6,
                "{what}: {m}: x {dx:.2e}, λ {dl:.2e}"
            );
            let (_, f) =
                post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &r, 1.0);
            let total: f64 = ["bear_l_top->deck_bottom", "bear_r_top->deck_bottom"]
                .iter()
                .map(|p| interface_resultant(&f, p, m).force[1])
                .sum();
            assert!(
                (total.abs() - load).abs() < 1e-6 * load,
                "{what}: {m}: bearings carry {total:e}, load {load:e}"
            );
        }
        // cgc's zero-curvature test: at 1e8 its CG went on below its
        // rounding floor until pᵀCp came out −2e-38 off ker C, and it
        // claimed the deck unbounded (the driver refused the claim and
        // solved by ssn). Now it never claims that; whether its answer is
        // certified is the certificate's call.
        let mut o = opts.clone();
        o.settings.cgc.preconditioner = signorini::qp::precond::PrecondKind::Cholesky;
        let r = signorini::run::solve(&prep, "cgc", &o).expect("cgc runs");
        assert!(
            !matches!(r.status, Status::Unbounded { .. })
                && !r.notes.iter().any(|n| n.to_string().contains("unbounded")),
            "{what}: cgc: {} {:?}",
            r.status.describe(),
            r.notes
        );
    }
}

/// Each of `methods` on `prep`: certified, with a note containing `note`,
/// and x within 1e-6 of the first one's. Returns the results in order.
fn one_answer(
    prep: &signorini::run::Prepared,
    opts: &SolveOptions,
    methods: &[&str],
    note: &str,
) -> Vec<signorini::qp::QpResult> {
    let runs: Vec<_> = methods
        .iter()
        .map(|m| solve_certified(prep, m, opts, m))
        .collect();
    for (m, r) in methods.iter().zip(&runs) {
        assert!(
            r.notes.iter().any(|n| n.to_string().contains(note)),
            "{m}: {:?}",
            r.notes
        );
        let d = rel(&r.x, &runs[0].x);
        assert!(d < 1e-6, "{m}: x {d:.2e} from {}", methods[0]);
    }
    runs
}

/// The model at `path` prepared, with the solver options of its file and
/// no command-line flags.
fn prepared(path: &std::path::Path) -> (signorini::run::Prepared, SolveOptions) {
    let prep = signorini::run::prepare(path, false).unwrap_or_else(|e| panic!("{e}"));
    let (_, opts) =
        signorini::run::options(&prep.problem, &signorini::qp::SolverSection::default())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (prep, opts)
}

/// The ring of [`a_ring_free_to_slide_between_two_plates_gets_one_answer`]
/// under Tresca friction (bound 50 Pa, so 6 contact rows slip and many open
/// rows carry their bound): the primal–dual active sets of ssn cycle
/// (before: 10 130 Newton steps, 35 s, uncertified; with a bound of 5 kPa
/// 14 133 steps, 181 s). ssn now stops after a counted budget of steps
/// without a better residual and the driver solves by mprgp, said in the
/// notes: the answer is mprgp's to the bit, certified, balanced, and the
/// same on a second run.
#[test]
fn a_ring_under_tresca_friction_whose_ssn_sets_cycle_is_solved_by_the_dual() {
    use signorini::post;
    let dir = root().join("tests/data/ring");
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::model_variant(
        &dir,
        "ring.toml",
        &[("max_gap = 0.05", "max_gap = 0.05\ntresca = 50.0")],
        &tmp.path().join("ring_tresca.toml"),
    );
    let (prep, opts) = prepared(&path);
    let ssn = solve_certified(&prep, "ssn", &opts, "ssn");
    assert!(
        ssn.notes.iter().any(|n| matches!(
            n,
            signorini::qp::Note::Fallback {
                to: signorini::qp::MethodId::Mprgp,
                cause: signorini::qp::FallbackCause::Cycling,
                ..
            }
        ) && n.to_string().contains("ssn: cycling")),
        "{:?}",
        ssn.notes
    );
    let mprgp = solve_certified(&prep, "mprgp", &opts, "mprgp");
    assert_eq!(ssn.x, mprgp.x, "the fallback is mprgp's answer");
    let again = solve_certified(&prep, "ssn", &opts, "ssn again");
    assert_eq!(ssn.x, again.x, "same input, same bits");
    let load = 1e3 * 2.0;
    let (_, f) =
        post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &ssn, 1.0);
    for pair in ["ring_out->bottom_face", "ring_out->top_face"] {
        let on = interface_resultant(&f, pair, "ssn");
        assert!(
            on.force[0].abs() < 1e-3 * load && (on.force[1].abs() - load).abs() < 1e-6 * load,
            "{pair} carries {:?}",
            on.force
        );
    }
}

/// The ring with its lid held (ux = 0, uy = −1 nm) under a light load: each
/// plate touches it at one node and it may roll until a neighbour touches,
/// a segment of solutions. ssn and asm return the point of least rolling
/// and agree. The dual family stopped on stagnation with the ring rolled by
/// 1.7 mm against a deformation of 1 nm and the forces of its two contacts
/// 2.3·10⁻⁴ apart: the ring was not in equilibrium. Before the rigid
/// balance (docs/methods.md §8.4) that answer was certified (stationarity
/// 2·10⁻¹¹, measured against the steel lid's forces); then it was refused;
/// since the dual's scale no longer comes from the gaps (2026-11-26) the
/// dual family solves it and agrees with ssn.
#[test]
fn a_lightly_held_ring_gets_the_least_roll_from_every_method() {
    let dir = root().join("tests/data/ring");
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::model_variant(
        &dir,
        "ring.toml",
        &[
            ("pn = -1.0e3", "pn = -1.0e-3"),
            (
                "on = \"lid\"\nux = 0.0",
                "on = \"lid\"\nux = 0.0\nuy = -1.0e-9",
            ),
        ],
        &tmp.path().join("ring_held_light.toml"),
    );
    let (prep, opts) = prepared(&path);
    let least = "has the least component along it";
    let one_of = "is one of those solutions, not the one with the least component";
    let ssn = solve_certified(&prep, "ssn", &opts, "ssn");
    let asm = solve_certified(&prep, "asm", &opts, "asm");
    for (m, r) in [("ssn", &ssn), ("asm", &asm)] {
        assert!(
            r.notes.iter().any(|n| n.to_string().contains(least)),
            "{m}: {:?}",
            r.notes
        );
    }
    let d = rel(&asm.x, &ssn.x);
    assert!(d < 1e-6, "asm x {d:.2e} from ssn");
    for (m, r) in [("ssn", &ssn), ("asm", &asm)] {
        assert!(r.kkt.rigid_balance < 1e-12, "{m}: {:?}", r.kkt);
        assert!(
            !r.notes.iter().any(|n| n.to_string().contains(one_of)),
            "{m}"
        );
    }
    // The dual family now solves it too (its scale and its rigid part of x
    // no longer come from the 5 cm gaps, see
    // `the_dual_family_does_not_depend_on_the_load_scale`).
    for m in ["dual", "mprgp", "uzawa"] {
        let r = solve_certified(&prep, m, &opts, m);
        assert!(r.kkt.rigid_balance < 1e-8, "{m}: {:?}", r.kkt);
        let d = rel(&r.x, &ssn.x);
        assert!(d < 1e-6, "{m}: x {d:.2e} from ssn");
    }
}

/// The ring between two steel plates at a contrast of 2·10⁸ (rubber
/// E = 1 kPa, 0.1 Pa on the lid): ssn and asm were both certified at the
/// rounding floor yet 1.4·10⁻³ apart in x. The rigid balance (docs/methods.md
/// §8.4) tells them apart: ssn's forces hold the ring and the lid in
/// equilibrium to 5·10⁻¹⁵, asm's only to 3·10⁻⁵, and asm is refused. ssn
/// agrees with the dual method to 10⁻⁵ in x (which stops above its own
/// tolerance there and is not certified either).
#[test]
fn at_a_contrast_of_2e8_the_rigid_balance_refuses_the_answer_that_disagrees() {
    let dir = root().join("tests/data/ring");
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::model_variant(
        &dir,
        "ring.toml",
        &[("E = 1.0e7", "E = 1.0e3"), ("pn = -1.0e3", "pn = -0.1")],
        &tmp.path().join("ring_2e8.toml"),
    );
    let (prep, opts) = prepared(&path);
    let ssn = solve_certified(&prep, "ssn", &opts, "ssn");
    assert!(ssn.kkt.rigid_balance < 1e-12, "{:?}", ssn.kkt);
    let asm = signorini::run::solve(&prep, "asm", &opts).expect("asm runs");
    assert!(
        asm.kkt.rigid_balance > 1e-5 && !asm.kkt.within(1e-6),
        "asm: {:?}",
        asm.kkt
    );
    assert!(rel(&asm.x, &ssn.x) > 1e-4, "they did differ");
    let dual = signorini::run::solve(&prep, "dual", &opts).expect("dual runs");
    let d = rel(&dual.x, &ssn.x);
    assert!(d < 1e-5, "dual x {d:.2e} from ssn");
}

/// The arch of tests/data/arch with Coulomb μ = 0.3 on its joints: ssn
/// found a sliding motion of the voussoirs on which the loads outwork
/// friction, but judged "no row closes" by a test of its own (10⁻¹⁰ of
/// Σ|a|·max|z| per row) that let row 53 close by 10⁻¹¹ of that, the
/// driver refused the claim, and the run exited 3 "not certified" at
/// μ = 0.2, 0.25 and 0.3. Now ssn claims only a direction the driver's
/// own test accepts: exit 2, the sliding voussoirs named; μ = 0.35 stands
/// (certified).
#[test]
fn an_arch_with_too_little_friction_is_refused_as_sliding() {
    let dir = root().join("tests/data/arch");
    let tmp = tempfile::tempdir().expect("tempdir");
    for (mu, code) in [("0.3", 2), ("0.35", 0)] {
        let model = common::model_variant(
            &dir,
            "arch.toml",
            &[("friction = 0.8\n", &format!("friction = {mu}\n"))],
            &tmp.path().join(format!("arch_{mu}.toml")),
        );
        let out = tmp.path().join(format!("out_{mu}"));
        let (got, text) = common::run(&[
            "solve",
            &model.display().to_string(),
            "--out",
            &out.display().to_string(),
        ]);
        assert_eq!(got, code, "μ = {mu}:\n{text}");
        if code == 2 {
            assert!(text.contains("the problem is unbounded"), "{text}");
            assert!(text.contains("body 'v3' (translation"), "{text}");
        } else {
            assert!(text.contains("→ certified"), "{text}");
        }
    }
}
