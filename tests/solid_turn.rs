//! `[[dirichlet]] turn = { angle, axis, origin }`: u·e_θ = θρ at each node
//! of the group, the radial and axial components free (docs/problem-format.md
//! §2, docs/methods.md §2.5). The keys as the file is read (the good form,
//! each bad form refused with its message, the steps' factor on the angle);
//! the elimination of one turned node; the rigid turn of a free tube (zero
//! stress, u = θ e × (x − o)); the reactions of a tube turned in its bore
//! and held on its outer surface (equal and opposite torques, no net
//! force). Mesh: tests/data/solid/tube.geo (bore r = 0.5, outer r = 1,
//! length 1 along z).

mod common;

use serde_json::Value;
use signorini::fem::solid::{build, SolidInput, SolidModel};
use signorini::mesh::{read_msh, Mesh};
use signorini::problem::{Material, Prescribed, Problem, Turn};
use signorini::qp::{registry, SolveOptions};
use std::path::{Path, PathBuf};

fn tube_msh() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/solid/tube.msh")
}

const HEAD: &str = "[mesh]\nfile = \"m.msh\"\n[materials.a]\nE = 1.0\nnu = 0.3\n";

/// The problem file `HEAD + body`, read and held against a `dim`D mesh.
fn parse(body: &str, dim: usize) -> Result<Problem, String> {
    let p =
        Problem::parse(Path::new("p.toml"), &format!("{HEAD}{body}")).map_err(|e| e.to_string())?;
    p.check_dimension(dim).map_err(|e| e.to_string())?;
    Ok(p)
}

#[test]
fn the_turn_form_is_read_with_a_unit_axis_and_its_angle_scaled_by_steps() {
    let p = parse(
        "[[dirichlet]]\non = \"bore\"\nturn = { angle = 1.0e-3, axis = [0.0, 0.0, 2.0], origin = [1.0, 2.0, 3.0] }\n\
         [[steps]]\ndisplacement = 0.5\n[[steps]]\nfactor = 3.0\n",
        3,
    )
    .unwrap();
    let Prescribed::Turn(t) = p.file.dirichlet[0].value else {
        panic!("{:?}", p.file.dirichlet[0].value)
    };
    assert_eq!(t.angle, 1.0e-3);
    assert_eq!(t.axis_xyz(), [0.0, 0.0, 1.0]);
    assert_eq!(t.origin_xyz(), [1.0, 2.0, 3.0]);
    // A turn fixes no Cartesian component.
    assert_eq!(p.file.dirichlet[0].value.components(), [None; 3]);
    let at = |s: usize| match p.file.at_step(s).dirichlet[0].value {
        Prescribed::Turn(t) => t,
        v => panic!("{v:?}"),
    };
    assert_eq!(at(0).angle, 0.5e-3);
    assert_eq!(at(1).angle, 3.0e-3);
    assert_eq!(at(1).axis_xyz(), [0.0, 0.0, 1.0]);
    // An oblique axis is made unit; the origin defaults to 0.
    let p = parse(
        "[[dirichlet]]\non = \"b\"\nturn = { angle = -2.0, axis = [3.0, 0.0, 4.0] }\n",
        3,
    )
    .unwrap();
    let Prescribed::Turn(t) = p.file.dirichlet[0].value else {
        panic!()
    };
    let a = t.axis_xyz();
    assert!(
        (a[0] - 0.6).abs() < 1e-15 && a[1] == 0.0 && (a[2] - 0.8).abs() < 1e-15,
        "{a:?}"
    );
    assert_eq!(t.origin_xyz(), [0.0; 3]);
    // A plane model turns about z through a 2D origin.
    let p = parse(
        "[[dirichlet]]\non = \"b\"\nturn = { angle = 0.1, origin = [1.0, -1.0] }\n",
        2,
    )
    .unwrap();
    let Prescribed::Turn(t) = p.file.dirichlet[0].value else {
        panic!()
    };
    assert_eq!(
        (t.axis_xyz(), t.origin_xyz()),
        ([0.0, 0.0, 1.0], [1.0, -1.0, 0.0])
    );
}

#[test]
fn bad_turns_are_refused_naming_the_entry_and_the_key() {
    let turn = |keys: &str| format!("[[dirichlet]]\non = \"bore\"\nturn = {{ {keys} }}\n");
    let ax = "axis = [0.0, 0.0, 1.0]";
    for (body, dim, want) in [
        (
            format!("[[dirichlet]]\non = \"bore\"\nux = 0.0\nturn = {{ angle = 1.0, {ax} }}\n"),
            3,
            "[[dirichlet]] #1 (on = \"bore\"): turn excludes ux",
        ),
        (
            format!("[[dirichlet]]\non = \"bore\"\nu = [0.0, 0.0, 0.0]\nuz = 1.0\nturn = {{ angle = 1.0, {ax} }}\n"),
            3,
            "turn excludes u, uz",
        ),
        (turn("angle = 1.0, axis = [0.0, 0.0, 0.0]"), 3, "turn.axis = [0, 0, 0]: the axis must be a finite, non-zero vector"),
        (turn("angle = 1.0, axis = [nan, 0.0, 1.0]"), 3, "the axis must be a finite, non-zero vector"),
        (turn("angle = 1.0, axis = [inf, 0.0, 1.0]"), 3, "the axis must be a finite, non-zero vector"),
        (turn(&format!("angle = inf, {ax}")), 3, "turn.angle = inf must be finite and within ±1e100"),
        (turn(&format!("angle = 1e101, {ax}")), 3, "turn.angle = 1e101 must be finite"),
        (turn(&format!("angle = 1.0, {ax}, origin = [nan, 0.0, 0.0]")), 3, "turn.origin = [NaN, 0, 0]"),
        (turn(&format!("angle = 1.0, {ax}, centre = [0.0, 0.0, 0.0]")), 3, "unknown field `centre`"),
        (turn(ax), 3, "missing field `angle`"),
        (turn("angle = 1.0"), 3, "turn needs axis = [x, y, z] in a 3D model"),
        (turn("angle = 1.0, axis = [0.0, 1.0]"), 3, "turn.axis = [0, 1]: expected 3 components"),
        (turn(&format!("angle = 1.0, {ax}, origin = [0.0, 1.0]")), 3, "turn.origin = [0, 1]: expected 3 components"),
        (turn(&format!("angle = 1.0, {ax}")), 2, "turn.axis is a key of 3D models only"),
        (turn("angle = 1.0, origin = [0.0, 1.0, 2.0]"), 2, "turn.origin = [0, 1, 2]: expected 2 components"),
        (
            format!("[model]\nplane = \"axisymmetric\"\n{}", turn("angle = 1.0")),
            2,
            "turn is refused in an axisymmetric model",
        ),
        (
            format!("{}[[steps]]\ndirichlet = {{ bore = [0.0, 0.0, 1.0] }}\n", turn(&format!("angle = 1.0, {ax}"))),
            3,
            "[[steps]] #1: dirichlet.bore: [[dirichlet]] on = \"bore\" is a turn, which takes no explicit step values",
        ),
    ] {
        let e = parse(&body, dim).unwrap_err();
        assert!(e.starts_with("p.toml: ") && e.contains(want), "{body}\n→ {e}\nwant {want}");
        if want.contains("axis") || want.contains("turn") {
            assert!(e.contains("bore") || e.contains("line"), "{e}");
        }
    }
}

fn steel() -> Material {
    Material {
        e: 2.0e11,
        nu: 0.3,
        rho: 0.0,
    }
}

fn tube_input(dirichlet: Vec<(&str, Prescribed)>) -> SolidInput {
    let mut i = SolidInput::default();
    i.materials.insert("tube".into(), steel());
    i.dirichlet = dirichlet.into_iter().map(|(n, p)| (n.into(), p)).collect();
    i
}

fn turn(angle: f64, origin: [f64; 3]) -> Prescribed {
    Prescribed::Turn(Turn {
        angle,
        axis: Some([0.0, 0.0, 1.0].into()),
        origin: Some(origin.into()),
    })
}

/// The nodes of a physical group.
fn nodes(mesh: &Mesh, on: &str) -> Vec<usize> {
    let g = mesh.group_any(on).unwrap();
    let mut v: Vec<usize> = g.elements.iter().flat_map(|&e| mesh.triangles[e]).collect();
    v.sort_unstable();
    v.dedup();
    v
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// e_θ and ρ about z through o at x.
fn e_theta(x: [f64; 3], o: [f64; 3]) -> ([f64; 3], f64) {
    let (dx, dy) = (x[0] - o[0], x[1] - o[1]);
    let rho = dx.hypot(dy);
    ([-dy / rho, dx / rho, 0.0], rho)
}

/// A node of the bore turned by θ about z keeps two unknowns, radial and
/// axial: u0·e_θ = θρ exactly, T orthonormal and orthogonal to e_θ.
#[test]
fn a_turned_node_is_held_along_e_theta_only() {
    let mesh = read_msh(&tube_msh()).unwrap();
    let th = 1.0e-3;
    let inp = tube_input(vec![
        ("bore", turn(th, [0.0; 3])),
        ("outer", turn(0.0, [0.0; 3])),
        ("end0", [None, None, Some(0.0)].into()),
    ]);
    let m = build(&mesh, Path::new("tube.toml"), &inp).unwrap();
    let end0 = nodes(&mesh, "end0");
    let mut seen = 0;
    for v in nodes(&mesh, "bore") {
        let pd = &m.dofs[v];
        let (e, rho) = e_theta(m.points[v], [0.0; 3]);
        assert!((rho - 0.5).abs() < 1e-9, "{rho}");
        let want = if end0.contains(&v) { 1 } else { 2 };
        assert_eq!(pd.ndof, want, "node {v}");
        assert!(
            (dot(pd.u0, e) - th * rho).abs() <= 1e-15 * th * rho,
            "{:?}",
            pd.u0
        );
        // u0 is along the conditions only: no radial part.
        let er = [e[1], -e[0], 0.0];
        assert!(dot(pd.u0, er).abs() < 1e-18, "{:?}", pd.u0);
        for a in 0..pd.ndof {
            assert!(dot(pd.t[a], e).abs() < 1e-14);
            for b in 0..pd.ndof {
                let d = dot(pd.t[a], pd.t[b]) - f64::from(u8::from(a == b));
                assert!(d.abs() < 1e-14);
            }
        }
        seen += usize::from(want == 2);
    }
    assert!(seen > 10, "{seen}");
    // A turn and a fixed u on the same nodes disagree along e_θ, which is
    // along no axis at most of them: the conflict is refused …
    let inp = tube_input(vec![
        ("bore", turn(th, [0.0; 3])),
        ("bore", [Some(0.0); 3].into()),
    ]);
    let e = build(&mesh, Path::new("tube.toml"), &inp)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("tube.toml") && e.contains("conflicting conditions at node"),
        "{e}"
    );
    // … and agree when the turn is zero.
    let inp = tube_input(vec![
        ("bore", turn(0.0, [0.0; 3])),
        ("bore", [Some(0.0); 3].into()),
        ("outer", [Some(0.0); 3].into()),
    ]);
    build(&mesh, Path::new("tube.toml"), &inp).unwrap();
}

fn solve(m: &SolidModel) -> Vec<[f64; 3]> {
    let opts = SolveOptions::default();
    let r = registry::solve("ssn", &m.qp, &opts).expect("solves");
    assert!(r.status.converged(), "{:?}", r.status);
    m.displacements(&r.x)
}

/// Every boundary surface turned by θ about an axis off the tube's own
/// (z through o), the axial translation held on one end: the rigid turn
/// u = θ e_z × (x − o) at every node, and zero stress to round-off.
#[test]
fn a_free_tube_turned_on_all_its_surface_turns_rigidly() {
    let mesh = read_msh(&tube_msh()).unwrap();
    let (th, o) = (2.0e-3, [0.1, -0.05, 0.0]);
    let mut d: Vec<(&str, Prescribed)> = ["bore", "outer", "end0", "end1"]
        .iter()
        .map(|&g| (g, turn(th, o)))
        .collect();
    d.push(("end0", [None, None, Some(0.0)].into()));
    let inp = tube_input(d);
    let m = build(&mesh, Path::new("tube.toml"), &inp).unwrap();
    let u = solve(&m);
    let mut err = 0.0f64;
    for (x, ui) in m.points.iter().zip(&u) {
        let want = [-th * (x[1] - o[1]), th * (x[0] - o[0]), 0.0];
        for k in 0..3 {
            err = err.max((ui[k] - want[k]).abs());
        }
    }
    assert!(err < 1e-12 * th, "displacement error {err:e}");
    let smax = m
        .stresses(&inp.materials, &u)
        .iter()
        .flatten()
        .fold(0.0f64, |a, s| a.max(s.abs()));
    assert!(smax < 1e-9 * steel().e * th, "stress {smax:e}");
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().expect("a 3-vector");
    [0, 1, 2].map(|k| a[k].as_f64().unwrap())
}

/// A tube turned in its bore and held by a zero turn on its outer surface
/// (uz = 0 on both ends), solved by the binary: the reactions of the two
/// groups are torques about z, equal and opposite, and the reactions sum
/// to no force.
#[test]
fn a_tube_turned_in_its_bore_has_balanced_torques() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let toml = format!(
        "[mesh]\nfile = \"{}\"\n[materials.tube]\nE = 2.0e11\nnu = 0.3\n\
         [[dirichlet]]\non = \"bore\"\nturn = {{ angle = 1.0e-3, axis = [0.0, 0.0, 1.0] }}\n\
         [[dirichlet]]\non = \"outer\"\nturn = {{ angle = 0.0, axis = [0.0, 0.0, 1.0] }}\n\
         [[dirichlet]]\non = \"end0\"\nuz = 0.0\n[[dirichlet]]\non = \"end1\"\nuz = 0.0\n",
        tube_msh().display()
    );
    std::fs::write(dir.join("tube.toml"), toml).unwrap();
    let o = common::command()
        .current_dir(dir)
        .args(["solve", "tube.toml", "--out", "out"])
        .output()
        .unwrap();
    let (code, out, err) = common::split(&o);
    assert_eq!(code, 0, "{out}{err}");
    let j: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/tube.json")).unwrap()).unwrap();
    let r = &j["reactions"];
    assert_eq!(r["bore"]["kind"], "dirichlet");
    let (mb, mo) = (vec3(&r["bore"]["moment"]), vec3(&r["outer"]["moment"]));
    // A positive turn of the bore needs a positive torque there.
    let t = mb[2];
    assert!(t > 0.0, "{mb:?}");
    assert!((mb[2] + mo[2]).abs() < 1e-9 * t, "{mb:?} {mo:?}");
    let mut f = [0.0; 3];
    for g in r.as_object().unwrap().values() {
        let fg = vec3(&g["force"]);
        for k in 0..3 {
            f[k] += fg[k];
        }
    }
    // Force scale: the torque over the bore's radius.
    for fk in f {
        assert!(fk.abs() < 1e-9 * t / 0.5, "{f:?}");
    }
    // The bore's own force is one of a torque: small on this mesh.
    let fb = vec3(&r["bore"]["force"]);
    assert!(fb.iter().all(|c| c.abs() < 0.05 * t / 0.5), "{fb:?}");
}

/// The plane form: a ring (tests/data/ring, no contact pairs, the plates
/// clamped) turned by θ about z through a point off its centre on its
/// outer circle turns rigidly, u = θ e_z × (x − o) at every ring node, and
/// the reactions there carry no force or torque; a ring turned against a
/// fixed component at the same nodes is refused as a conflict.
#[test]
fn a_plane_ring_turned_on_its_rim_turns_rigidly() {
    let tmp = tempfile::tempdir().unwrap();
    let msh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ring/ring.msh");
    let (th, o) = (1.0e-3, [0.05, -0.02]);
    let head = format!(
        "[mesh]\nfile = \"{}\"\n[materials.bottom]\nE = 2.0e11\nnu = 0.3\n[materials.top]\nE = 2.0e11\nnu = 0.3\n\
         [materials.ring]\nE = 1.0e7\nnu = 0.45\n[[dirichlet]]\non = \"base\"\nu = [0.0, 0.0]\n\
         [[dirichlet]]\non = \"lid\"\nu = [0.0, 0.0]\n\
         [[dirichlet]]\non = \"ring_out\"\nturn = {{ angle = {th:e}, origin = [{}, {}] }}\n",
        msh.display(),
        o[0],
        o[1]
    );
    let path = tmp.path().join("ring.toml");
    std::fs::write(&path, &head).unwrap();
    let (prep, res) = common::solve_file(&path, &Default::default());
    let m = &prep.model;
    let ring = m.body_names.iter().position(|n| n == "ring").unwrap() as u32;
    let mut n = 0;
    for (p, pd) in m.dofs.iter().enumerate() {
        if m.topo.point_body[p] != ring {
            continue;
        }
        let x = m.topo.points[p];
        let mut u = pd.u0;
        for (k, tk) in pd.t.iter().enumerate().take(pd.ndof) {
            for (uc, tc) in u.iter_mut().zip(tk) {
                *uc += tc * res.x[pd.start + k];
            }
        }
        let want = [-th * (x[1] - o[1]), th * (x[0] - o[0])];
        for c in 0..2 {
            assert!((u[c] - want[c]).abs() < 1e-10 * th, "{x:?}: {u:?} {want:?}");
        }
        n += 1;
    }
    assert!(n > 100, "{n}");
    // The turn is part of the checkpoint's fingerprint: another angle is
    // another problem, named by its part.
    let other = tmp.path().join("ring2.toml");
    std::fs::write(&other, head.replace(&format!("{th:e}"), "2e-3")).unwrap();
    let prep2 = signorini::run::prepare(&other, false).unwrap();
    let (f1, f2) = (
        signorini::run::fingerprint(&prep, false),
        signorini::run::fingerprint(&prep2, false),
    );
    assert_eq!(signorini::run::fingerprint_diff(&f1, &f2), ["dirichlet"]);
    // A turn about the ring's centre against ux = 0 on the rim: e_θ and
    // e_x are independent at most rim nodes, but at the rim's top and
    // bottom, (0, ±R), e_θ = ∓e_x and they disagree.
    let head = head.replace(
        &format!("origin = [{}, {}]", o[0], o[1]),
        "origin = [0.0, 0.0]",
    );
    std::fs::write(
        &path,
        format!("{head}[[dirichlet]]\non = \"ring_out\"\nux = 0.0\n"),
    )
    .unwrap();
    let e = match signorini::run::prepare(&path, false) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted"),
    };
    assert!(
        e.contains("conflicting conditions") && e.contains("ring_out"),
        "{e}"
    );
}
