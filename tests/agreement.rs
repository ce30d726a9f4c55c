//! Property tests: on random loads (traction magnitude and direction,
//! gravity direction), prescribed displacements and initial gaps on the
//! small shipped meshes, every exact method of the registry (all but
//! `penalty`) agrees with CGC + Cholesky to 10⁻⁸ relative in x and meets the
//! KKT target.
//!
//! The problems are built through the library (TOML written to a temporary
//! directory, `run::prepare`); random initial gaps are added to the QP's
//! g (g ≥ 0 stays a valid contact QP: the bodies start apart by that much).
//! The random loads stay in the cone that keeps each floating body pressed
//! onto its support (bounded problems; an unbounded one is bad input and is
//! tested in tests/bad_inputs).

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use signorini::qp::precond::PrecondKind;
use signorini::qp::settings::SsnPath;
use signorini::qp::{registry, QpError, QpProblem, QpResult, SolveOptions};
use signorini::run;

mod common;

use common::{meshes, norm, XorShift};

/// Agreement with the reference, relative: ‖x − x_ref‖ / ‖x_ref‖.
const AGREE: f64 = 1e-8;
/// The KKT target of `signorini solve` (`--kkt-target` default).
const KKT_TARGET: f64 = 1e-6;
/// Cases per property (each case solves one problem with every method);
/// three_bodies (3286 DOFs) gets fewer to keep the file under a minute.
const CASES: u32 = 16;
const CASES_THREE_BODIES: u32 = 8;

/// The seed of every run: CI tests the same cases each time (same input,
/// same result). `PROPTEST_RNG_SEED` and `PROPTEST_CASES` in the
/// environment explore others (how the case of
/// [`two_blocks_eccentric_ci_case`] was found, on a random seed).
const SEED: u64 = 0x5167_6e6f_7269_6e69;

fn config(cases: u32) -> Config {
    let env = Config::default();
    let set = |v: &str| std::env::var_os(v).is_some();
    Config {
        cases: if set("PROPTEST_CASES") {
            env.cases
        } else {
            cases
        },
        rng_seed: if set("PROPTEST_RNG_SEED") {
            env.rng_seed
        } else {
            RngSeed::Fixed(SEED)
        },
        max_shrink_iters: 16,
        failure_persistence: None,
        ..env
    }
}

fn mesh(name: &str) -> String {
    meshes().join(format!("{name}.msh")).display().to_string()
}

/// The QP of a TOML problem text.
fn build(toml: &str) -> QpProblem {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("case.toml");
    std::fs::write(&p, toml).unwrap();
    let prep = run::prepare(&p, false).unwrap_or_else(|e| panic!("{e}\n{toml}"));
    prep.model.qp
}

/// A direction at `deg` degrees from straight down, scaled by `m`.
fn down(m: f64, deg: f64) -> [f64; 2] {
    let a = deg.to_radians();
    [m * a.sin(), -m * a.cos()]
}

fn opts(pc: PrecondKind) -> SolveOptions {
    {
        let mut o = SolveOptions::default();
        o.settings.cgc.preconditioner = pc;
        o
    }
}

fn reference(qp: &QpProblem) -> Result<QpResult, TestCaseError> {
    let r = registry::solve("cgc", qp, &opts(PrecondKind::Cholesky))
        .map_err(|e| TestCaseError::fail(format!("cgc+cholesky refused: {e}")))?;
    prop_assert!(r.status.converged(), "cgc+cholesky: {:?}", r.status);
    prop_assert!(
        r.kkt.within(KKT_TARGET),
        "cgc+cholesky KKT {:?} above {KKT_TARGET}",
        r.kkt
    );
    Ok(r)
}

/// Adds gaps g_i += frac·u_i·s (u_i ∈ [0, 1) from `seed`, s the largest
/// displacement of the solution without gaps): a mix of rows that close and
/// rows that stay open.
fn with_gaps(mut qp: QpProblem, frac: f64, seed: u64) -> Result<QpProblem, TestCaseError> {
    if frac > 0.0 && qp.m() > 0 {
        let r = reference(&qp)?;
        let s = r.x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut rng = XorShift(seed | 1);
        for g in qp.g.iter_mut() {
            let x = rng.next();
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            *g += frac * u * s;
        }
    }
    Ok(qp)
}

/// two_blocks.toml's model with traction `t` on the top, gravity `g`,
/// density `rho` and the bottom moved by (0, `uy`): the upper block floats
/// (vertical translation, held by contact).
fn two_blocks_toml(t: [f64; 2], g: [f64; 2], rho: f64, uy: f64) -> String {
    format!(
        r#"
[mesh]
file = "{}"
[model]
gravity = [{}, {}]
[materials.lower]
E = 2.0e9
nu = 0.25
rho = {rho}
[materials.upper]
E = 2.0e9
nu = 0.25
rho = {rho}
[[dirichlet]]
on = "bottom"
u = [0.0, {uy}]
[[slip]]
on = "left_lower"
[[slip]]
on = "right_lower"
[[slip]]
on = "left_upper"
[[slip]]
on = "right_upper"
[[traction]]
on = "top"
p = [{}, {}]
[[contact]]
on = "interface"
"#,
        mesh("two_blocks"),
        g[0],
        g[1],
        t[0],
        t[1]
    )
}

/// two_blocks_eccentric.toml's model with traction `t` on the right half
/// of the top, gravity `g`, density `rho` and the bottom moved by
/// (`ux`, `uy`): the upper block may tilt (held at one point in x).
fn eccentric_toml(t: [f64; 2], g: [f64; 2], rho: f64, ux: f64, uy: f64) -> String {
    format!(
        r#"
[mesh]
file = "{}"
[model]
gravity = [{}, {}]
[materials.lower]
E = 2.0e9
nu = 0.25
rho = {rho}
[materials.upper]
E = 2.0e9
nu = 0.25
rho = {rho}
[[dirichlet]]
on = "bottom"
u = [{ux}, {uy}]
[[dirichlet]]
on = "top_mid"
ux = 0.0
[[traction]]
on = "top_right"
p = [{}, {}]
[[contact]]
on = "interface"
"#,
        mesh("two_blocks_eccentric"),
        g[0],
        g[1],
        t[0],
        t[1]
    )
}

/// Every exact method against CGC + Cholesky (the reference itself is not
/// repeated); `ic0` adds CGC with the incomplete factor (its diagonal-shift
/// restarts), slow on the larger mesh.
fn agree(qp: &QpProblem, ic0: bool) -> Result<(), TestCaseError> {
    let r0 = reference(qp)?;
    let scale = norm(&r0.x).max(f64::MIN_POSITIVE);
    let mut variants: Vec<(String, &str, SolveOptions)> = signorini::qp::MethodId::ALL
        .iter()
        .filter(|m| m.name() != "penalty" && m.name() != "cgc")
        .map(|m| {
            let pc = PrecondKind::Cholesky;
            (format!("{} ({})", m.name(), pc.name()), m.name(), opts(pc))
        })
        .collect();
    // ssn with no factor of C's size (multigrid CG inside the active-set loop).
    let mut it = opts(PrecondKind::Cholesky);
    it.settings.ssn.path = SsnPath::Iterative;
    variants.push(("ssn (iterative)".into(), "ssn", it));
    if ic0 {
        variants.push(("cgc (ic0)".into(), "cgc", opts(PrecondKind::Ic0)));
    }
    for (label, name, o) in variants {
        let r = match registry::solve(name, qp, &o) {
            Ok(r) => r,
            // Being extended elsewhere: may refuse a singular C.
            Err(QpError::Unsupported(_)) if matches!(name, "uzawa" | "dual") => continue,
            Err(e) => return Err(TestCaseError::fail(format!("{label}: refused: {e}"))),
        };
        prop_assert!(r.status.converged(), "{}: {:?}", label, r.status);
        prop_assert!(
            r.kkt.within(KKT_TARGET),
            "{}: KKT {:?} above {}",
            label,
            r.kkt,
            KKT_TARGET
        );
        let diff: Vec<f64> = r.x.iter().zip(&r0.x).map(|(a, b)| a - b).collect();
        let rel = norm(&diff) / scale;
        prop_assert!(
            rel <= AGREE,
            "{}: ‖x − x_ref‖/‖x_ref‖ = {:e} > {:e}",
            label,
            rel,
            AGREE
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(CASES))]

    /// two_blocks: the upper block floats (vertical translation, held by contact).
    #[test]
    fn two_blocks(
        p in 1e4f64..1e7, p_deg in -80f64..80.0,
        rho in 0f64..3000.0, g_deg in -80f64..80.0,
        uy in -1e-3f64..1e-3,
        gap in prop_oneof![Just(0.0), 0f64..1.0], seed in any::<u64>(),
    ) {
        let t = down(p, p_deg);
        let g = down(9.81, g_deg);
        let toml = two_blocks_toml(t, g, rho, uy);
        agree(&with_gaps(build(&toml), gap, seed)?, true)?;
    }

    /// two_blocks_eccentric: the upper block may tilt (held at one point in x).
    #[test]
    fn two_blocks_eccentric(
        p in 1e4f64..1e7, p_deg in -80f64..80.0,
        rho in 0f64..3000.0, g_deg in -50f64..50.0,
        ux in -1e-4f64..1e-4, uy in -1e-4f64..1e-4,
        gap in prop_oneof![Just(0.0), 0f64..1.0], seed in any::<u64>(),
    ) {
        let t = down(p, p_deg);
        let g = down(9.81, g_deg);
        let toml = eccentric_toml(t, g, rho, ux, uy);
        agree(&with_gaps(build(&toml), gap, seed)?, true)?;
    }

    /// floating_block: a block on a foundation, vertical translation free.
    #[test]
    fn floating_block(
        p in 1e3f64..1e6, p_deg in -80f64..80.0,
        g_deg in -80f64..80.0, g in 0f64..20.0,
        uy in -1e-4f64..1e-4,
        gap in prop_oneof![Just(0.0), 0f64..1.0], seed in any::<u64>(),
    ) {
        let t = down(p, p_deg);
        let gv = down(g, g_deg);
        let toml = format!(r#"
[mesh]
file = "{}"
[model]
gravity = [{}, {}]
[materials.foundation]
E = 3.0e10
nu = 0.2
rho = 2400.0
[materials.block]
E = 1.0e10
nu = 0.25
rho = 2500.0
[[dirichlet]]
on = "found_bottom"
u = [0.0, {uy}]
[[slip]]
on = "found_left"
[[slip]]
on = "found_right"
[[slip]]
on = "block_left"
[[traction]]
on = "block_top"
p = [{}, {}]
[[contact]]
on = "interface"
"#, mesh("floating_block"), gv[0], gv[1], t[0], t[1]);
        agree(&with_gaps(build(&toml), gap, seed)?, true)?;
    }

}

proptest! {
    #![proptest_config(config(CASES_THREE_BODIES))]

    /// three_bodies: a floating wedge (three rigid motions) between two faults.
    #[test]
    fn three_bodies(
        top in 0.1f64..2.0, top_deg in -30f64..30.0,
        bottom in 0f64..2.0, bottom_deg in -30f64..30.0,
        g_deg in -30f64..30.0,
        left in (-0.2f64..0.4, -0.1f64..0.1), right in (-0.2f64..0.4, -0.1f64..0.1),
        gap in prop_oneof![Just(0.0), 0f64..1.0], seed in any::<u64>(),
    ) {
        let pt = down(0.8e8 * top, top_deg);
        let pb = down(0.8e8 * bottom, bottom_deg);
        let g = down(9.81, g_deg);
        let toml = format!(r#"
[mesh]
file = "{}"
[model]
gravity = [{}, {}]
[materials.rock_left]
E = 1.0e11
nu = 0.3
rho = 2700.0
[materials.rock_wedge]
E = 1.0e11
nu = 0.3
rho = 2700.0
[materials.rock_right]
E = 1.0e11
nu = 0.3
rho = 2700.0
[[dirichlet]]
on = "left"
u = [{}, {}]
[[dirichlet]]
on = "right"
u = [{}, {}]
[[traction]]
on = "top"
p = [{}, {}]
[[traction]]
on = "bottom"
p = [{}, {}]
[[contact]]
on = "fault1"
[[contact]]
on = "fault2"
"#, mesh("three_bodies"), g[0], g[1], left.0, left.1, -right.0, right.1,
            pt[0], pt[1], pb[0], pb[1]);
        agree(&with_gaps(build(&toml), gap, seed)?, false)?;
    }
}

/// The case proptest found on CI (stop 31): a nearly horizontal load on the
/// tilting upper block with wide gaps; ssn stagnated.
#[test]
fn two_blocks_eccentric_ci_case() {
    let (p, p_deg, gap, seed) = (
        6873737.026284413,
        -79.89435665014842,
        0.9094680663796626,
        15495622681602840434u64,
    );
    let t = down(p, p_deg);
    let toml = eccentric_toml(t, [0.0, -9.81], 0.0, 0.0, 0.0);
    let qp = with_gaps(build(&toml), gap, seed).unwrap();
    agree(&qp, true).unwrap();
}

/// A case `PROPTEST_RNG_SEED=303` found (2026-11-26): two_blocks with
/// initial gaps of up to 0.7 × the deformation. uzawa's answer was
/// certified (primal 6e-11) but failed the dual host's own guard on the
/// recovered x (2.7e-9 against 2.4e-9) once the stopping scale left the
/// open gaps out; the guard keeps its former scale.
#[test]
fn two_blocks_wide_gaps_seed_case() {
    let (p, p_deg, gap, seed) = (
        2835785.1053915876,
        0.8695716853054597,
        0.7125384595093924,
        4906879679384458270u64,
    );
    let t = down(p, p_deg);
    let toml = two_blocks_toml(t, [0.0, -9.81], 0.0, 0.0);
    let qp = with_gaps(build(&toml), gap, seed).unwrap();
    agree(&qp, true).unwrap();
}
