//! The FEM side of 3D friction (issue 46, docs/methods.md §12.2, §12.6):
//! two tangential rows per contact row in the reduced unknowns (NTS, mortar,
//! conforming), their Tresca bounds, the slip offset of a load step, the
//! friction outputs and the refused inputs. Meshes: the stacked cubes of
//! tests/data/solid_contact (a quarter model: slip on x = 0 and y = 0).

mod common;

use signorini::fem::contact3d::friction::{friction_frame, tangential_displacement, Held};
use signorini::fem::element::Vector3;
use signorini::fem::solid::{build, SolidInput, SolidModel, SolidTraction};
use signorini::fem::Discrete;
use signorini::mesh::read_msh;
use signorini::problem::{
    Contact, ContactPair, Discretization, FrictionLaw, Material, NonMatchingPair, NormalKind,
};
use signorini::qp::{registry, Frame, SlipBound, SolveOptions};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/solid_contact")
        .join(name)
}

fn conforming(law: FrictionLaw) -> Contact {
    Contact {
        pair: ContactPair::Conforming {
            on: "interface".into(),
            normals: NormalKind::Averaged,
        },
        friction: law,
    }
}

fn non_matching(disc: Discretization, law: FrictionLaw) -> Contact {
    Contact {
        pair: ContactPair::NonMatching(NonMatchingPair {
            slave: "upper_bottom".into(),
            master: "lower_top".into(),
            max_gap: None,
            discretization: Some(disc),
            interference: false,
        }),
        friction: law,
    }
}

fn input(contact: Contact) -> SolidInput {
    let mut i = SolidInput::default();
    let mat = |e, nu| Material { e, nu, rho: 7800.0 };
    i.materials.insert("lower".into(), mat(2.0e11, 0.3));
    i.materials.insert("upper".into(), mat(7.0e10, 0.25));
    i.slip = vec!["x0".into(), "y0".into(), "bottom".into()];
    i.traction = vec![("top".into(), SolidTraction::Normal(-1.0e7))];
    i.contact = vec![contact];
    i
}

/// The three pairs: conforming, non-matching NTS, non-matching mortar.
fn models(law: FrictionLaw) -> Vec<(&'static str, SolidModel)> {
    let conf = read_msh(&data("stack.msh")).unwrap();
    let nm = read_msh(&data("stack_nm.msh")).unwrap();
    let p = Path::new("stack.toml");
    vec![
        (
            "conforming",
            build(&conf, p, &input(conforming(law))).unwrap(),
        ),
        (
            "nts",
            build(&nm, p, &input(non_matching(Discretization::Nts, law))).unwrap(),
        ),
        (
            "mortar",
            build(&nm, p, &input(non_matching(Discretization::Mortar, law))).unwrap(),
        ),
    ]
}

fn dot(a: Vector3, b: Vector3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// T applied to a rigid translation a of the upper (slave) body gives
/// −(t1·a, t2·a) on every row whose points are free, and on every row
/// T x = the tangential displacement of the motion the conditions allow.
#[test]
fn t_of_a_translation_is_its_tangential_components() {
    for (name, m) in models(FrictionLaw::Coulomb(0.3)) {
        let f = m.qp.friction.as_ref().expect("friction");
        assert_eq!(f.frame, Frame::Plane);
        assert_eq!(f.t.nrows, 2 * m.qp.m(), "{name}");
        assert_eq!(f.t0.len(), 2 * m.qp.m(), "{name}");
        let a = [0.3, -0.7, 0.2];
        let upper = m.point_body[m.contact[m.qp_rows[0]].slave];
        let u: Vec<Vector3> = (0..m.points.len())
            .map(|p| {
                if m.point_body[p] == upper {
                    a
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let x = m.reduce(&u);
        let tx = f.t.mul(&x);
        let allowed = m.displacements(&x);
        let td = tangential_displacement(&m, &allowed);
        let mut free_rows = 0;
        for (qi, &r) in m.qp_rows.iter().enumerate() {
            let row = &m.contact[r];
            for k in 0..2 {
                assert!(
                    (tx[2 * qi + k] - td[2 * qi + k]).abs() < 1e-13,
                    "{name} row {r}"
                );
            }
            let free = std::iter::once(row.slave)
                .chain(row.masters.iter().filter(|w| w.1 != 0.0).map(|w| w.0))
                .all(|p| m.dofs[p].ndof == 3);
            if free {
                free_rows += 1;
                let (t, held) = friction_frame(row, &m.dofs[row.slave]);
                assert_eq!(held, Held::None);
                assert_eq!(t, row.tangents);
                for k in 0..2 {
                    let want = -dot(t[k], a);
                    assert!(
                        (tx[2 * qi + k] - want).abs() < 1e-13,
                        "{name} row {r}: {} vs {want}",
                        tx[2 * qi + k]
                    );
                }
            }
        }
        assert!(free_rows > 0, "{name}: no interior row");
    }
}

/// The tangential relative displacement of a rigid motion of both bodies
/// together (a translation and a rotation about an oblique axis) is 0.
#[test]
fn t_of_a_common_rigid_motion_is_zero() {
    for (name, m) in models(FrictionLaw::Tresca(1.0e6)) {
        let (a, w) = ([0.1, 0.2, -0.3], [0.05, -0.02, 0.04]);
        let u: Vec<Vector3> = m
            .points
            .iter()
            .map(|x| {
                [
                    a[0] + w[1] * x[2] - w[2] * x[1],
                    a[1] + w[2] * x[0] - w[0] * x[2],
                    a[2] + w[0] * x[1] - w[1] * x[0],
                ]
            })
            .collect();
        let td = tangential_displacement(&m, &u);
        let worst = td.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        assert!(worst < 1e-12, "{name}: {worst:e}");
    }
}

/// Tresca bounds are s × the row's tributary area and sum to s × the
/// contact area (1 m², a quarter of the interface); Coulomb's are μ.
#[test]
fn tresca_bounds_are_s_times_area() {
    let s = 2.5e6;
    for (name, m) in models(FrictionLaw::Tresca(s)) {
        let f = m.qp.friction.as_ref().unwrap();
        let SlipBound::Tresca(b) = &f.bound else {
            panic!("{name}: not Tresca");
        };
        assert_eq!(b.len(), m.qp.m());
        for (bi, &r) in b.iter().zip(&m.qp_rows) {
            assert_eq!(*bi, s * m.contact[r].area, "{name}");
        }
        let total: f64 = b.iter().sum();
        assert!((total - s).abs() < 1e-9 * s, "{name}: Σ s_i = {total}");
    }
    for (name, m) in models(FrictionLaw::Coulomb(0.4)) {
        let f = m.qp.friction.as_ref().unwrap();
        assert_eq!(f.bound, SlipBound::Coulomb(vec![0.4; m.qp.m()]), "{name}");
    }
}

/// t0 of a step is the previous step's tangential displacement (less the
/// prescribed part): T x − t0 is the increment from the previous step.
#[test]
fn the_offset_makes_the_slip_an_increment() {
    for (name, m) in models(FrictionLaw::Coulomb(0.3)) {
        let f = m.qp.friction.as_ref().unwrap();
        // The reference configuration: no prescribed displacement, t0 = 0.
        assert!(f.t0.iter().all(|&v| v == 0.0), "{name}");
        let field = |c: f64| -> Vec<Vector3> {
            // Discontinuous across the interface: each body its own.
            m.points
                .iter()
                .zip(&m.point_body)
                .map(|(x, &b)| {
                    let c = c * (1.0 + f64::from(b));
                    [c * x[1] * x[2], -c * x[0], c * (x[0] + x[1])]
                })
                .collect()
        };
        // The previous step's answer satisfies the conditions.
        let u_prev = m.displacements(&m.reduce(&field(1e-3)));
        let t0 = m.slip_offset(Some(&u_prev));
        let prev = tangential_displacement(&m, &u_prev);
        assert_eq!(t0, prev, "{name}");
        assert!(
            prev.iter().any(|v| v.abs() > 1e-6),
            "{name}: a motion along the rows"
        );
        let x = m.reduce(&field(-2e-3));
        let mut tx = f.t.mul(&x);
        for (v, o) in tx.iter_mut().zip(&t0) {
            *v -= o;
        }
        let now = tangential_displacement(&m, &m.displacements(&x));
        for i in 0..tx.len() {
            assert!((tx[i] - (now[i] - prev[i])).abs() < 1e-15, "{name} {i}");
        }
    }
}

/// The friction outputs on a solved Coulomb model, then on a synthetic
/// λ_t: shapes, global vectors λ_t1 t1 + λ_t2 t2 over the area, the state.
#[test]
fn friction_outputs_on_a_synthetic_result() {
    let (_, m) = models(FrictionLaw::Coulomb(0.3)).remove(0);
    let mut res = registry::solve("ssn", &m.qp, &SolveOptions::default()).unwrap();
    assert!(res.status.converged());
    let mut c = signorini::output::SolidContactOutput::default();
    let counts = signorini::post::solid_friction::solid_friction_output(&m, &res, &mut c);
    let r = m.contact.len();
    assert_eq!(c.tangential_traction.len(), r);
    assert_eq!(c.slip.len(), r);
    assert_eq!(c.friction_state.len(), r);
    assert_eq!(counts.len(), 1);
    assert_eq!(counts[0].0 + counts[0].1, m.qp.m(), "every row in contact");
    // Synthetic: row i gets λ_t ∥ (1, −2), the first row with two
    // tangential rows at the bound, the others well inside.
    let qm = m.qp.m();
    let bound: Vec<f64> = res.lambda.iter().map(|l| 0.3 * l).collect();
    let f = m.qp.friction.as_ref().unwrap();
    let idle = |j: usize| f.t.indptr[j] == f.t.indptr[j + 1];
    let first = (0..qm).find(|&i| !idle(2 * i) && !idle(2 * i + 1)).unwrap();
    for (i, b) in bound.iter().enumerate() {
        let k = if i == first { 1.0 } else { 1e-3 } * b / 5f64.sqrt();
        res.lambda_t[2 * i] = k;
        res.lambda_t[2 * i + 1] = -2.0 * k;
    }
    let mut c = signorini::output::SolidContactOutput::default();
    let counts = signorini::post::solid_friction::solid_friction_output(&m, &res, &mut c);
    let mut slipping = 0;
    for (i, &rw) in m.qp_rows.iter().enumerate() {
        let row = &m.contact[rw];
        let (t, held) = friction_frame(row, &m.dofs[row.slave]);
        // A tangential row without unknowns carries no force (t0 = 0 here).
        let idle = |k: usize| f.t.indptr[2 * i + k] == f.t.indptr[2 * i + k + 1];
        assert!(held == Held::None || idle(1), "a held second row is empty");
        assert!(held != Held::Both || idle(0), "both held rows are empty");
        let l1 = if idle(0) { 0.0 } else { res.lambda_t[2 * i] };
        let l2 = if idle(1) {
            0.0
        } else {
            res.lambda_t[2 * i + 1]
        };
        for (k, got) in c.tangential_traction[rw].iter().enumerate() {
            let want = (l1 * t[0][k] + l2 * t[1][k]) / row.area;
            assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0));
        }
        // Tangential to the row.
        assert!(dot(c.tangential_traction[rw], row.normal).abs() < 1e-9 * bound[i] / row.area);
        let at_bound = i == first;
        assert_eq!(
            c.friction_state[rw],
            if at_bound { 2 } else { 1 },
            "row {i}"
        );
        slipping += usize::from(at_bound);
    }
    assert_eq!((counts[0].1, slipping), (1, 1));
}

/// A frictional pair none of whose rows has an unknown is refused naming
/// the file and the entry.
#[test]
fn friction_on_a_pair_without_rows_is_refused() {
    let conf = read_msh(&data("stack.msh")).unwrap();
    let mut inp = input(conforming(FrictionLaw::Tresca(1e6)));
    inp.slip.clear();
    inp.dirichlet = vec![
        ("lower".into(), [Some(0.0); 3].into()),
        ("upper".into(), [Some(0.0); 3].into()),
    ];
    let e = match build(&conf, Path::new("fixed.toml"), &inp) {
        Err(e) => e,
        Ok(_) => panic!("accepted"),
    };
    assert_eq!(e.path, Path::new("fixed.toml"));
    assert!(
        e.msg.contains("[[contact]] #1 (on = \"interface\")"),
        "{}",
        e.msg
    );
    assert!(e.msg.contains("no contact rows"), "{}", e.msg);
}

/// μ and s out of range in a 3D problem file: refused naming the file and
/// the entry (the 2D validation applies).
#[test]
fn friction_out_of_range_is_refused_in_3d() {
    let dir = tempfile::tempdir().unwrap();
    for (law, words) in [
        ("friction = -0.2", "friction"),
        ("tresca = -1.0", "tresca"),
        ("friction = 1e300", "friction"),
    ] {
        let contact = format!("on = \"interface\"\n{law}");
        let text = common::solid_stack_toml(&data("stack.msh"), &contact, -1e7, "");
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, &text).unwrap();
        let out = common::command()
            .args(["solve", path.to_str().unwrap(), "--out"])
            .arg(dir.path().join("out"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{law}: {err}");
        assert!(err.contains("bad.toml"), "{law}: {err}");
        assert!(
            err.contains("[[contact]]") && err.contains(words),
            "{law}: {err}"
        );
    }
}

/// Two hemispheres on the symmetry planes x = 0 and y = 0 (the quarter
/// model of verification/ssnv104, `gmsh -3 -setnumber hc 4
/// ssnv104_3d.geo`, the .msh committed): a rubber cap (E = 2, ν = 0.45)
/// crushed on a stiff one (E = 2·10⁴), mortar rows, Coulomb μ = 0.3.
/// A row whose slave point lies on a plane has its normal in the plane
/// (docs/methods.md §11.7), its tangent across the plane held, and on the
/// symmetry edge (the pole) both; ssn and mprgp then certify the same
/// answer, λ_t included. Before the mirrored normals the one-sided
/// averages tilted out of the planes, the held rows were kept with
/// 1 % of a normal row's norm, mprgp ran 100 000 iterations without
/// converging on the third load step and its λ_t differed from ssn's by
/// 40 % of the largest.
#[test]
fn rows_on_symmetry_planes_are_mirrored_and_both_methods_agree() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let msh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/solid/hemispheres_hc4.msh");
    let toml = dir.join("hemi.toml");
    std::fs::write(
        &toml,
        format!(
            r#"[mesh]
file = "{}"
[materials.lower]
E = 2.0e4
nu = 0.3
[materials.upper]
E = 2.0
nu = 0.45
[[dirichlet]]
on = "lower_base"
uz = 0.0
[[dirichlet]]
on = "upper_top"
uz = -0.5
[[slip]]
on = "sym_x"
[[slip]]
on = "sym_y"
[[contact]]
slave = "upper_cap"
master = "lower_cap"
max_gap = 5.0
friction = 0.3
"#,
            msh.display()
        ),
    )
    .unwrap();
    let loaded = signorini::run::load(&toml, false, &Default::default()).expect("loads");
    let signorini::run::Loaded::Solid(p) = loaded else {
        panic!("a 3D model")
    };
    let m = &p.model;
    let f = m.qp.friction.as_ref().expect("friction");
    let empty = |i: usize| f.t.indptr[i] == f.t.indptr[i + 1];
    let (mut one, mut edge) = (0, 0);
    for (qi, &r) in m.qp_rows.iter().enumerate() {
        let row = &m.contact[r];
        let x = m.points[row.slave];
        let on = [x[0].abs() < 1e-9, x[1].abs() < 1e-9];
        let (_, held) = friction_frame(row, &m.dofs[row.slave]);
        for (k, _) in on.iter().enumerate().filter(|(_, &o)| o) {
            assert!(
                row.normal[k].abs() < 1e-12,
                "row {r} at {x:?}: {:?}",
                row.normal
            );
        }
        match on {
            [true, true] => {
                edge += 1;
                assert_eq!(held, Held::Both, "row {r} at {x:?}");
                assert!(empty(2 * qi) && empty(2 * qi + 1), "row {r}");
            }
            [true, false] | [false, true] => {
                one += 1;
                assert_eq!(held, Held::Second, "row {r} at {x:?}");
                assert!(!empty(2 * qi) && empty(2 * qi + 1), "row {r}");
            }
            _ => assert_eq!(held, Held::None, "row {r} at {x:?}"),
        }
    }
    assert_eq!(edge, 1, "the pole");
    assert!(one >= 4, "{one} rows on one plane");
    let opts = SolveOptions::default();
    let solve = |method: &str| {
        let r = registry::solve(method, &m.qp, &opts).expect("solves");
        assert!(r.status.converged(), "{method}: {:?}", r.status);
        assert!(
            r.kkt.within(opts.settings.kkt_target),
            "{method}: {:?}",
            r.kkt
        );
        r
    };
    let (a, b) = (solve("ssn"), solve("mprgp"));
    let rel = |u: &[f64], v: &[f64]| {
        let big = u.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        u.iter()
            .zip(v)
            .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()))
            / big
    };
    assert!(a.active.iter().any(|&x| x), "some row in contact");
    assert!(a.lambda_t.iter().any(|&x| x != 0.0), "friction acts");
    assert!(rel(&a.x, &b.x) < 1e-8, "x: {:e}", rel(&a.x, &b.x));
    assert!(
        rel(&a.lambda, &b.lambda) < 1e-8,
        "λ_n: {:e}",
        rel(&a.lambda, &b.lambda)
    );
    let lt = rel(&a.lambda_t, &b.lambda_t);
    assert!(lt < 1e-6, "λ_t: {lt:e}");
}
