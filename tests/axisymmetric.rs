//! Axisymmetric models (`[model] plane = "axisymmetric"`, x = r, y = z,
//! docs/methods.md §10) against analytic references: Lamé's thick cylinder
//! under internal pressure, a shrink fit of two thick cylinders (Lamé's
//! interface pressure, `interference = true`), the methods on one model,
//! and the mortar row on a symmetry line with friction.

mod common;

use signorini::qp::{QpResult, SolverSection};
use signorini::run::Prepared;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A rectangle [r0, r1] × [z0, z1] of `nr` × `nz` squares cut into two
/// triangles each, named `name` with curves `name_inner` (r = r0),
/// `name_outer`, `name_bottom`, `name_top`.
struct Block {
    name: &'static str,
    r: [f64; 2],
    z: [f64; 2],
    n: [usize; 2],
}

/// The blocks as MSH 2.2 (no node shared between blocks).
fn blocks_msh(path: &Path, blocks: &[Block]) {
    let mut nodes: Vec<[f64; 2]> = vec![];
    let mut lines: Vec<(usize, [usize; 2])> = vec![];
    let mut tris: Vec<(usize, [usize; 3])> = vec![];
    let mut names: Vec<(usize, usize, String)> = vec![];
    for (k, b) in blocks.iter().enumerate() {
        let (nr, nz) = (b.n[0], b.n[1]);
        let base = nodes.len();
        let id = |i: usize, j: usize| base + j * (nr + 1) + i + 1;
        for j in 0..=nz {
            for i in 0..=nr {
                nodes.push([
                    b.r[0] + (b.r[1] - b.r[0]) * i as f64 / nr as f64,
                    b.z[0] + (b.z[1] - b.z[0]) * j as f64 / nz as f64,
                ]);
            }
        }
        let surf = 100 + k;
        let c = 10 * k + 1;
        names.push((2, surf, b.name.to_string()));
        for (o, s) in ["inner", "outer", "bottom", "top"].iter().enumerate() {
            names.push((1, c + o, format!("{}_{s}", b.name)));
        }
        for j in 0..nz {
            for i in 0..nr {
                let (a, bb, cc, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if (i + j) % 2 == 0 {
                    tris.push((surf, [a, bb, cc]));
                    tris.push((surf, [a, cc, d]));
                } else {
                    tris.push((surf, [a, bb, d]));
                    tris.push((surf, [bb, cc, d]));
                }
            }
        }
        for j in 0..nz {
            lines.push((c, [id(0, j), id(0, j + 1)]));
            lines.push((c + 1, [id(nr, j), id(nr, j + 1)]));
        }
        for i in 0..nr {
            lines.push((c + 2, [id(i, 0), id(i + 1, 0)]));
            lines.push((c + 3, [id(i, nz), id(i + 1, nz)]));
        }
    }
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n");
    writeln!(s, "{}", names.len()).unwrap();
    for (d, t, n) in &names {
        writeln!(s, "{d} {t} \"{n}\"").unwrap();
    }
    writeln!(s, "$EndPhysicalNames\n$Nodes\n{}", nodes.len()).unwrap();
    for (i, x) in nodes.iter().enumerate() {
        writeln!(s, "{} {:?} {:?} 0", i + 1, x[0], x[1]).unwrap();
    }
    writeln!(s, "$EndNodes\n$Elements\n{}", lines.len() + tris.len()).unwrap();
    let mut k = 0;
    for (p, [a, b]) in &lines {
        k += 1;
        writeln!(s, "{k} 1 2 {p} {p} {a} {b}").unwrap();
    }
    for (p, [a, b, c]) in &tris {
        k += 1;
        writeln!(s, "{k} 2 2 {p} {p} {a} {b} {c}").unwrap();
    }
    s.push_str("$EndElements\n");
    std::fs::write(path, s).unwrap();
}

fn write_model(dir: &Path, name: &str, blocks: &[Block], body: &str) -> PathBuf {
    let msh = dir.join(format!("{name}.msh"));
    blocks_msh(&msh, blocks);
    let toml = dir.join(format!("{name}.toml"));
    std::fs::write(
        &toml,
        format!("[mesh]\nfile = \"{}\"\n{body}", msh.display()),
    )
    .unwrap();
    toml
}

fn solve_with(
    path: &Path,
    method: Option<&str>,
) -> (Prepared, QpResult, signorini::output::StepOutput) {
    let choice = match method {
        None => SolverSection::default(),
        Some(m) => {
            let text = format!("method = \"{m}\"\ntol = 1e-10\n");
            toml::from_str(&text).unwrap()
        }
    };
    let (prep, res) = common::solve_file(path, &choice);
    let step = signorini::post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    (prep, res, step)
}

const E: f64 = 2.0e11;
const NU: f64 = 0.3;

/// Lamé, plane strain (ε_zz = 0): u_r(r) of a cylinder with
/// σ_rr = A − B/r², σ_θθ = A + B/r² (Timoshenko & Goodier, Theory of
/// Elasticity, §28).
fn lame_u(a_: f64, b_: f64, r: f64) -> f64 {
    (1.0 + NU) / E * ((1.0 - 2.0 * NU) * a_ * r + b_ / r)
}

/// A cylinder a ≤ r ≤ b under internal pressure p, plane strain:
/// σ_rr, σ_θθ and u_r against Lamé at every element centroid and node.
/// Returns (max |Δσ|/p over elements, max |Δu_r|/u_r(a) over nodes).
fn lame_errors(n: usize) -> (f64, f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, h, p) = (1.0, 2.0, 0.25, 1.0e8);
    let blocks = [Block {
        name: "tube",
        r: [a, b],
        z: [0.0, h],
        n: [n, (n / 4).max(1)],
    }];
    let body = format!(
        r#"[model]
plane = "axisymmetric"
[materials.tube]
E = {E:e}
nu = {NU}
[[dirichlet]]
on = "tube_bottom"
uy = 0.0
[[dirichlet]]
on = "tube_top"
uy = 0.0
[[traction]]
on = "tube_inner"
pn = {}
"#,
        -p
    );
    let path = write_model(dir.path(), "lame", &blocks, &body);
    let (prep, _res, step) = solve_with(&path, None);
    let aa = p * a * a / (b * b - a * a);
    let bb = aa * b * b;
    let t = &prep.model.topo;
    let mut es: f64 = 0.0;
    let mut et: f64 = 0.0;
    for (tri, s) in t.triangles.iter().zip(&step.stress) {
        let rbar = (t.points[tri[0]][0] + t.points[tri[1]][0] + t.points[tri[2]][0]) / 3.0;
        es = es.max((s[0] - (aa - bb / (rbar * rbar))).abs() / p);
        et = et.max((s[3] - (aa + bb / (rbar * rbar))).abs() / p);
        assert!(s[1].is_finite());
    }
    let ua = lame_u(aa, bb, a);
    let mut eu: f64 = 0.0;
    for (x, u) in t.points.iter().zip(&step.displacement) {
        eu = eu.max((u[0] - lame_u(aa, bb, x[0])).abs() / ua);
        assert!(u[1].abs() < 1e-12 * ua);
    }
    (es, et, eu)
}

/// Lamé's thick cylinder: the errors in σ_rr, σ_θθ (at the centroids) and
/// u_r (at the nodes) are small and fall with the mesh size.
#[test]
fn lame_cylinder_under_internal_pressure() {
    let coarse = lame_errors(8);
    let fine = lame_errors(32);
    eprintln!("lame n=8: {coarse:?}; n=32: {fine:?}");
    // u_r: O(h²) at the nodes.
    assert!(fine.2 < 2e-3, "{fine:?}");
    assert!(fine.2 < coarse.2 / 4.0, "{coarse:?} -> {fine:?}");
    // Stresses at the centroids: O(h).
    assert!(fine.0 < 0.05 && fine.1 < 0.05, "{fine:?}");
    assert!(fine.0 < coarse.0 / 2.0 && fine.1 < coarse.1 / 2.0);
}

/// Lamé's shrink-fit pressure of a tube a ≤ r ≤ c inside a tube c ≤ r ≤ b
/// with radial interference δ (plane strain, one material): δ equals the
/// outer tube's expansion at c under internal pressure p less the inner
/// one's (negative) under external p, both linear in p.
fn shrink_fit_pressure(a: f64, c: f64, b: f64, delta: f64) -> f64 {
    let outer = {
        let aa = c * c / (b * b - c * c);
        lame_u(aa, aa * b * b, c)
    };
    let inner = {
        let aa = -c * c / (c * c - a * a);
        lame_u(aa, aa * a * a, c)
    };
    delta / (outer - inner)
}

/// The shrink-fit model: the inner tube's outer radius is c + δ, so the
/// tubes overlap by δ in the reference configuration (`interference`).
fn shrink_fit_model(dir: &Path, disc: &str, interference: bool) -> PathBuf {
    let (a, c, b, h, delta) = (0.5, 1.0, 1.5, 0.25, 1.0e-3);
    let blocks = [
        Block {
            name: "inner",
            r: [a, c + delta],
            z: [0.0, h],
            n: [12, 6],
        },
        Block {
            name: "outer",
            r: [c, b],
            z: [0.0, h],
            n: [12, 6],
        },
    ];
    let mut body = format!(
        r#"[model]
plane = "axisymmetric"
[materials.inner]
E = {E:e}
nu = {NU}
[materials.outer]
E = {E:e}
nu = {NU}
"#
    );
    for g in ["inner_bottom", "inner_top", "outer_bottom", "outer_top"] {
        writeln!(body, "[[dirichlet]]\non = \"{g}\"\nuy = 0.0").unwrap();
    }
    writeln!(
        body,
        "[[contact]]\nslave = \"inner_outer\"\nmaster = \"outer_inner\"\ndiscretization = \"{disc}\""
    )
    .unwrap();
    if interference {
        body.push_str("interference = true\n");
    }
    write_model(
        dir,
        &format!("shrink_{disc}_{interference}"),
        &blocks,
        &body,
    )
}

/// A shrink fit: the contact pressure on the interface is Lamé's
/// to 2.5 % (12 elements through each wall), with NTS and mortar rows, ssn, cgc and mprgp agree, and without
/// `interference = true` the overlap is refused with a message naming it.
#[test]
fn shrink_fit_pressure_matches_lame_and_methods_agree() {
    let dir = tempfile::tempdir().unwrap();
    let want = shrink_fit_pressure(0.5, 1.0, 1.5, 1.0e-3);
    for disc in ["nts", "mortar"] {
        let path = shrink_fit_model(dir.path(), disc, true);
        let mut us: Vec<Vec<f64>> = vec![];
        for method in ["ssn", "cgc", "mprgp"] {
            let (prep, _res, step) = solve_with(&path, Some(method));
            // Tubes: no node on the axis, so no axis condition is reported.
            assert!(
                prep.model.cond_groups.iter().all(|(k, _)| *k != "axis"),
                "{:?}",
                prep.model.cond_groups
            );
            let rows = &prep.model.topo.contact;
            let ps: Vec<f64> = rows
                .iter()
                .zip(&step.contact_pressure)
                .map(|(_, &p)| p)
                .collect();
            assert!(!ps.is_empty());
            eprintln!(
                "{disc} {method}: pressures / Lamé = {:?}",
                ps.iter().map(|p| p / want).collect::<Vec<_>>()
            );
            for &p in &ps {
                assert!(
                    (p - want).abs() < 0.025 * want,
                    "{disc} {method}: pressure {p:e} vs Lamé {want:e}"
                );
            }
            // The rows alternate ±1.2 % with the diagonals; their mean is
            // Lamé's to 0.06 % (measured).
            let mean = ps.iter().sum::<f64>() / ps.len() as f64;
            assert!(
                (mean - want).abs() < 0.005 * want,
                "{disc} {method}: mean {mean:e}"
            );
            us.push(step.displacement.iter().flat_map(|u| *u).collect());
        }
        for k in 1..us.len() {
            let d = common::rel_diff(&us[k], &us[0]);
            assert!(d < 1e-6, "{disc}: method {k} differs from ssn by {d:e}");
        }
    }
    let path = shrink_fit_model(dir.path(), "nts", false);
    let err = match signorini::run::prepare(&path, false) {
        Ok(_) => panic!("an overlap without interference = true was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("penetrates") && err.contains("interference = true"),
        "{err}"
    );
}

/// A block pressed on a softer base with Coulomb friction (μ = 0.3), the
/// left side x = 0 a line of symmetry (`[[slip]]` in plane strain, the
/// axis in an axisymmetric model); non-matching meshes, the block slave.
fn symmetric_friction_model(dir: &Path, plane: &str, disc: &str) -> PathBuf {
    let blocks = [
        Block {
            name: "base",
            r: [0.0, 1.0],
            z: [-1.0, 0.0],
            n: [7, 7],
        },
        Block {
            name: "block",
            r: [0.0, 1.0],
            z: [0.0, 1.0],
            n: [5, 5],
        },
    ];
    let mut body = format!(
        r#"[model]
plane = "{plane}"
[materials.base]
E = 1.0e8
nu = 0.45
[materials.block]
E = 1.0e9
nu = 0.2
[[dirichlet]]
on = "base_bottom"
uy = 0.0
[[dirichlet]]
on = "block_top"
uy = -0.01
[[contact]]
slave = "block_bottom"
master = "base_top"
discretization = "{disc}"
friction = 0.3
"#
    );
    if plane != "axisymmetric" {
        body.push_str("[[slip]]\non = \"base_inner\"\n[[slip]]\non = \"block_inner\"\n");
    }
    write_model(dir, &format!("sym_{plane}_{disc}"), &blocks, &body)
}

/// The mortar row on the line of symmetry carries no tangential traction
/// (symmetry; NTS rows there have none either), with ssn and mprgp, in
/// plane strain and axisymmetric; and the total friction force of mortar
/// rows is NTS's to 3 %.
#[test]
fn mortar_friction_row_on_the_symmetry_line_is_zero() {
    let dir = tempfile::tempdir().unwrap();
    for plane in ["strain", "axisymmetric"] {
        let mut total = vec![];
        for disc in ["nts", "mortar"] {
            let path = symmetric_friction_model(dir.path(), plane, disc);
            for method in ["ssn", "mprgp"] {
                let (prep, res, step) = solve_with(&path, Some(method));
                let fo = signorini::post::friction::friction_output(&prep.model, &res).unwrap();
                let t = &prep.model.topo;
                let mut on_axis = 0;
                let mut sum = 0.0;
                for (r, row) in t.contact.iter().enumerate() {
                    sum += fo.lambda_t[r];
                    if t.points[row.first][0] == 0.0 {
                        on_axis += 1;
                        assert!(step.contact_pressure[r] > 0.0);
                        assert_eq!(
                            fo.tangential_traction[r], 0.0,
                            "{plane} {disc} {method}: row on x = 0 has traction {:e} (state {})",
                            fo.tangential_traction[r], fo.state[r]
                        );
                        // Held by the line: in contact, it sticks (it
                        // was reported as slipping at the bound 0).
                        if disc == "mortar" {
                            assert_eq!(fo.state[r], 1, "{plane} {method}: row on x = 0");
                        }
                    }
                }
                assert!(on_axis <= 1);
                // Elsewhere the friction is working (the materials' Poisson
                // expansions differ).
                let most = fo
                    .tangential_traction
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(most > 0.0, "{plane} {disc} {method}: no friction at all");
                eprintln!("{plane} {disc} {method}: Σλ_t = {sum:e}");
                total.push(sum);
            }
        }
        let (nts, mortar) = (total[0], total[2]);
        assert!(
            (mortar - nts).abs() < 0.03 * nts.abs(),
            "{plane}: friction resultant mortar {mortar:e} vs nts {nts:e}"
        );
    }
}

/// A solid cylinder 0 ≤ r ≤ b spinning at ω (`omega`), plane strain
/// (ε_zz = 0): σ_rr = (3−2ν)/(8(1−ν)) ρω²(b² − r²) and
/// σ_θθ = ρω²/(8(1−ν))((3−2ν)b² − (1+2ν)r²) (Timoshenko & Goodier, Theory
/// of Elasticity, ch. 4, the long rotating cylinder). The mesh has nodes on
/// the axis (u_r = 0 there without any condition) and no radial support.
#[test]
fn spinning_solid_cylinder_matches_the_analytic_stresses() {
    let dir = tempfile::tempdir().unwrap();
    let (b, rho, w) = (0.5, 7800.0, 600.0);
    let blocks = [Block {
        name: "rotor",
        r: [0.0, b],
        z: [0.0, 0.1],
        n: [40, 8],
    }];
    let body = format!(
        r#"[model]
plane = "axisymmetric"
omega = {w}
[materials.rotor]
E = {E:e}
nu = {NU}
rho = {rho}
[[dirichlet]]
on = "rotor_bottom"
uy = 0.0
[[dirichlet]]
on = "rotor_top"
uy = 0.0
"#
    );
    let path = write_model(dir.path(), "spin", &blocks, &body);
    let (prep, _res, step) = solve_with(&path, None);
    let t = &prep.model.topo;
    let q = rho * w * w;
    let scale = (3.0 - 2.0 * NU) / (8.0 * (1.0 - NU)) * q * b * b;
    let (mut er, mut et): (f64, f64) = (0.0, 0.0);
    for (tri, s) in t.triangles.iter().zip(&step.stress) {
        let r = (t.points[tri[0]][0] + t.points[tri[1]][0] + t.points[tri[2]][0]) / 3.0;
        let srr = (3.0 - 2.0 * NU) / (8.0 * (1.0 - NU)) * q * (b * b - r * r);
        let stt = q / (8.0 * (1.0 - NU)) * ((3.0 - 2.0 * NU) * b * b - (1.0 + 2.0 * NU) * r * r);
        er = er.max((s[0] - srr).abs() / scale);
        et = et.max((s[3] - stt).abs() / scale);
    }
    eprintln!("spinning cylinder: max |Δσrr|, |Δσθθ| / σ(0) = {er:e}, {et:e}");
    assert!(er < 0.005 && et < 0.005, "{er:e} {et:e}");
    // Nodes on the axis do not move radially.
    for (x, u) in t.points.iter().zip(&step.displacement) {
        if x[0] == 0.0 {
            assert_eq!(u[0], 0.0);
        }
    }
    assert!(prep.model.qp.kernel.is_empty());
    // The VTU names the 4th stress component the hoop stress.
    let om = signorini::post::out_mesh(&prep.model, &prep.mesh);
    let vtu = dir.path().join("spin.vtu");
    signorini::io::vtu::write_vtu(&vtu, &om, &step, false).unwrap();
    // The arrays are appended raw: the XML around them is text.
    let xml = String::from_utf8_lossy(&std::fs::read(&vtu).unwrap()).into_owned();
    assert!(
        xml.contains(
            r#"ComponentName0="srr" ComponentName1="szz" ComponentName2="srz" ComponentName3="stt""#
        ),
        "hoop component not named"
    );
    assert!(xml.contains(r#"ComponentName0="s1" ComponentName1="s2""#));
}

/// Bad axisymmetric input is refused with a message naming the key or the
/// node: a node at r < 0, a radial gravity, `omega` in a plane model,
/// `interference` on a conforming pair.
#[test]
fn bad_axisymmetric_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let block = |r0: f64| Block {
        name: "part",
        r: [r0, 1.0],
        z: [0.0, 1.0],
        n: [2, 2],
    };
    let base = "[materials.part]\nE = 1e9\nnu = 0.3\nrho = 1000.0\n[[dirichlet]]\non = \"part_bottom\"\nuy = 0.0\n";
    let cases: [(&str, f64, String, &str); 4] = [
        ("neg", -0.5, format!("[model]\nplane = \"axisymmetric\"\n{base}"), "x = r >= 0"),
        (
            "grav",
            0.0,
            format!("[model]\nplane = \"axisymmetric\"\ngravity = [1.0, -9.81]\n{base}"),
            "gravity along z only",
        ),
        (
            "omega",
            0.0,
            format!("[model]\nplane = \"strain\"\nomega = 10.0\n{base}"),
            "omega",
        ),
        (
            "conf",
            0.0,
            format!("[model]\nplane = \"axisymmetric\"\n{base}[[contact]]\non = \"part_top\"\ninterference = true\n"),
            "interference applies to non-matching pairs",
        ),
    ];
    for (name, r0, body, want) in cases {
        let path = write_model(dir.path(), name, &[block(r0)], &body);
        let err = match signorini::run::prepare(&path, false) {
            Ok(_) => panic!("{name}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(want), "{name}: {err}");
    }
}

/// An axisymmetric load step reuses the prepared C and A (issue 36): its
/// d — body loads weighted by r, spin ρω²r, tractions, prescribed radial
/// displacements through C_e — is computed by the assembly's own element
/// load (`fem::step_model_reusing`), and equals a full build of the step
/// bit for bit, as do g, u0, the nodal loads and the ssn answer.
#[test]
fn axisymmetric_step_model_reuses_c_and_equals_the_full_build() {
    use signorini::linalg::cholesky::Workspace;
    use signorini::qp::{registry, SolveOptions};
    use signorini::run;
    let dir = tempfile::tempdir().unwrap();
    let (a, c, b, h, delta) = (0.5, 1.0, 1.5, 0.25, 1.0e-4);
    let blocks = [
        Block {
            name: "inner",
            r: [a, c + delta],
            z: [0.0, h],
            n: [8, 4],
        },
        Block {
            name: "outer",
            r: [c, b],
            z: [0.0, h],
            n: [8, 4],
        },
    ];
    let mut body = format!(
        r#"[model]
plane = "axisymmetric"
gravity = [0.0, -9.81]
omega = 200.0
[materials.inner]
E = {E:e}
nu = {NU}
rho = 7800.0
[materials.outer]
E = {E:e}
nu = {NU}
rho = 2700.0
[[dirichlet]]
on = "inner_inner"
ux = 2.0e-4
[[traction]]
on = "outer_outer"
pn = -1.0e7
[[traction]]
on = "inner_top"
p = [0.0, -1.0e6]
"#
    );
    for g in ["inner_bottom", "outer_bottom"] {
        writeln!(body, "[[dirichlet]]\non = \"{g}\"\nuy = 0.0").unwrap();
    }
    body.push_str(
        "[[contact]]\nslave = \"inner_outer\"\nmaster = \"outer_inner\"\ndiscretization = \"mortar\"\ninterference = true\n",
    );
    for (t, step) in [
        (1.0, "factor = 0.25"),
        (2.0, "factor = 0.5"),
        (3.0, "load = 1.0\ndisplacement = 0.75"),
    ] {
        writeln!(body, "[[steps]]\nt = {t}\n{step}").unwrap();
    }
    let path = write_model(dir.path(), "axi_steps", &blocks, &body);
    let prep = run::prepare(&path, false).unwrap_or_else(|e| panic!("{e}"));
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let (ws_reused, ws_fresh) = (Workspace::new(), Workspace::new());
    let mut prev = None;
    for s in 0..prep.problem.file.nsteps() {
        let reused = run::step_model_reusing(&prep, s, prev.take()).unwrap();
        let mut p = prep.problem.clone();
        p.file = prep.problem.file.at_step(s);
        let fresh = signorini::fem::build_with(&prep.mesh, &p, &prep.build).unwrap();
        let at = format!("step {}", s + 1);
        // Reused, not rebuilt: the prepared model's arrays, no copy.
        assert!(reused.qp.c.data.ptr_eq(&prep.model.qp.c.data), "C, {at}");
        assert_eq!(reused.qp.c, fresh.qp.c, "C, {at}");
        assert_eq!(reused.qp.a, fresh.qp.a, "A, {at}");
        assert!(reused.qp.d.iter().any(|v| *v != 0.0), "{at}");
        assert_eq!(bits(&reused.qp.d), bits(&fresh.qp.d), "d, {at}");
        assert_eq!(bits(&reused.qp.g), bits(&fresh.qp.g), "g, {at}");
        let u0 = |m: &signorini::fem::Model| {
            m.dofs
                .iter()
                .flat_map(|p| [p.u0[0].to_bits(), p.u0[1].to_bits(), p.start as u64])
                .collect::<Vec<_>>()
        };
        assert_eq!(u0(&reused), u0(&fresh), "u0, {at}");
        let flat =
            |m: &signorini::fem::Model| m.loads.iter().flatten().copied().collect::<Vec<_>>();
        assert_eq!(bits(&flat(&reused)), bits(&flat(&fresh)), "loads, {at}");
        let mut xs = vec![];
        for (model, ws) in [(&reused, &ws_reused), (&fresh, &ws_fresh)] {
            let r = registry::solve_in("ssn", &model.qp, &SolveOptions::default(), ws).unwrap();
            assert!(r.status.converged(), "{at}");
            xs.push(r.solution.x);
        }
        assert_eq!(bits(&xs[0]), bits(&xs[1]), "x, {at}");
        prev = Some(reused);
    }
}

/// A block one element wide pressed on a base, both between two lines of
/// symmetry (`[[slip]]` left and right), mortar with Coulomb friction:
/// both slave rows sit on a symmetry line, so the friction residual is
/// exactly 0. The JSON still writes `kkt.friction` (a frictional problem
/// always does; it was left out, as for a frictionless one).
#[test]
fn kkt_friction_is_written_when_every_frictional_row_is_on_a_symmetry_line() {
    let dir = tempfile::tempdir().unwrap();
    let blocks = [
        Block {
            name: "base",
            r: [0.0, 1.0],
            z: [-1.0, 0.0],
            n: [2, 2],
        },
        Block {
            name: "block",
            r: [0.0, 1.0],
            z: [0.0, 1.0],
            n: [1, 2],
        },
    ];
    let body = r#"[model]
plane = "strain"
[materials.base]
E = 1.0e8
nu = 0.45
[materials.block]
E = 1.0e9
nu = 0.2
[[dirichlet]]
on = "base_bottom"
uy = 0.0
[[dirichlet]]
on = "block_top"
uy = -0.01
[[slip]]
on = "base_inner"
[[slip]]
on = "base_outer"
[[slip]]
on = "block_inner"
[[slip]]
on = "block_outer"
[[contact]]
slave = "block_bottom"
master = "base_top"
discretization = "mortar"
friction = 0.3
"#;
    let path = write_model(dir.path(), "all_on_symmetry", &blocks, body);
    let out = dir.path().join("out");
    let (code, _, stderr) = common::signorini(&[
        "solve",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("all_on_symmetry.json")).unwrap())
            .unwrap();
    assert_eq!(j["kkt"]["friction"], 0.0, "{}", j["kkt"]);
    assert!(j["contact"]["stick"].is_u64(), "{}", j["contact"]);
}

/// The checkpoint's root attribute `model` names the kind of model: an
/// axisymmetric checkpoint said only `plane_strain = 1`.
#[test]
fn the_checkpoint_names_the_model_kind() {
    let dir = tempfile::tempdir().unwrap();
    let blocks = [Block {
        name: "ring",
        r: [1.0, 2.0],
        z: [0.0, 1.0],
        n: [2, 2],
    }];
    for (plane, kind) in [
        ("axisymmetric", "axisymmetric"),
        ("strain", "plane_strain"),
        ("stress", "plane_stress"),
    ] {
        let body = format!(
            "[model]\nplane = \"{plane}\"\n[materials.ring]\nE = 1.0e9\nnu = 0.3\n[[dirichlet]]\non = \"ring_bottom\"\nu = [0.0, 0.0]\n[[traction]]\non = \"ring_top\"\npn = -1.0e6\n"
        );
        let name = format!("kind_{plane}");
        let path = write_model(dir.path(), &name, &blocks, &body);
        let out = dir.path().join(&name);
        let (code, _, stderr) = common::signorini(&[
            "solve",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert_eq!(code, 0, "{plane}: {stderr}");
        let f = hdf5::File::open(out.join(format!("{name}.h5"))).unwrap();
        let v: hdf5::types::VarLenUnicode = f.attr("model").unwrap().read_scalar().unwrap();
        assert_eq!(v.as_str(), kind, "{plane}");
        // The old attribute keeps its meaning: a fourth stress component.
        let ps: u8 = f.attr("plane_strain").unwrap().read_scalar().unwrap();
        assert_eq!(ps, u8::from(plane != "stress"), "{plane}");
        // Not a user attribute of the checkpoint as read back.
        let ck = signorini::io::hdf5::read_checkpoint(&out.join(format!("{name}.h5"))).unwrap();
        assert!(!ck.attrs.iter().any(|(k, _)| k == "model"), "{plane}");
    }
}

/// Issue 43, hostile axisymmetric input: a traction on the axis r = 0
/// carries no area and adds no load, which the run says, naming the group
/// (a traction on a curve off the axis says nothing); an interference
/// overlap as thick as a tube's wall is refused naming the pair; a spin
/// whose ρω²r passes the load bound is refused naming `omega`.
#[test]
fn hostile_axisymmetric_loads_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let block = Block {
        name: "part",
        r: [0.0, 1.0],
        z: [0.0, 1.0],
        n: [4, 4],
    };
    let base = "[model]\nplane = \"axisymmetric\"\n[materials.part]\nE = 1e9\nnu = 0.3\nrho = 1000.0\n[[dirichlet]]\non = \"part_bottom\"\nuy = 0.0\n";
    for (name, on, warned) in [("axis", "part_inner", true), ("rim", "part_outer", false)] {
        let body = format!("{base}[[traction]]\non = \"{on}\"\np = [1.0e6, 0.0]\n");
        let path = write_model(dir.path(), name, &[block_of(&block)], &body);
        let out = dir.path().join(format!("out_{name}"));
        let (code, log) = common::run(&[
            "solve",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{name}: {log}");
        let said = log
            .lines()
            .any(|l| l.contains(on) && l.contains("axis r = 0") && l.contains("no load"));
        assert_eq!(said, warned, "{name}: {log}");
    }
    // A spin of 1e60 rad/s: ρω²r ≈ 1e123, past the bound of 1e100.
    let body = base.replace(
        "plane = \"axisymmetric\"\n",
        "plane = \"axisymmetric\"\nomega = 1.0e60\n",
    );
    let path = write_model(dir.path(), "spin", &[block_of(&block)], &body);
    let err = match signorini::run::prepare(&path, false) {
        Ok(_) => panic!("a spin of 1e60 was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("omega = 1e60") && err.contains("centrifugal"),
        "{err}"
    );
    // A tube whose outer radius is 0.3 past the bore of the other (its
    // wall is 0.5 thick, its segments about 0.04): no small overlap.
    let blocks = [
        Block {
            name: "inner",
            r: [0.5, 1.3],
            z: [0.0, 0.25],
            n: [12, 6],
        },
        Block {
            name: "outer",
            r: [1.0, 1.5],
            z: [0.0, 0.25],
            n: [12, 7],
        },
    ];
    let body = "[model]\nplane = \"axisymmetric\"\n[materials.inner]\nE = 2e11\nnu = 0.3\n[materials.outer]\nE = 2e11\nnu = 0.3\n[[dirichlet]]\non = \"inner_bottom\"\nuy = 0.0\n[[dirichlet]]\non = \"outer_bottom\"\nuy = 0.0\n[[contact]]\nslave = \"inner_outer\"\nmaster = \"outer_inner\"\ninterference = true\n";
    let path = write_model(dir.path(), "deep_fit", &blocks, body);
    let err = match signorini::run::prepare(&path, false) {
        Ok(_) => panic!("an overlap of 0.3 was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("interference overlap")
            && err.contains("inner_outer")
            && err.contains("outer_inner")
            && err.contains("segment length"),
        "{err}"
    );
}

fn block_of(b: &Block) -> Block {
    Block {
        name: b.name,
        r: b.r,
        z: b.z,
        n: b.n,
    }
}

/// Issue 43, probes: a probe on the boundary of a coarse mesh, between
/// two nodes and half an element from either (it was refused as "outside
/// the mesh", the rule being 10 % of the mesh diagonal to a node), is in
/// its triangle and reports the nearest output point's displacement bit
/// for bit; one at 10 % of an element past the boundary is refused, the
/// message saying the rule.
#[test]
fn a_probe_on_the_boundary_is_in_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let block = Block {
        name: "part",
        r: [0.0, 1.0],
        z: [0.0, 1.0],
        n: [1, 1],
    };
    let base = "[model]\nplane = \"strain\"\n[materials.part]\nE = 1e9\nnu = 0.3\n[[dirichlet]]\non = \"part_bottom\"\nu = [0.0, 0.0]\n[[traction]]\non = \"part_top\"\np = [1.0e6, -1.0e6]\n";
    let body = format!("{base}[output]\nprobes = {{ edge = [0.5, 1.0], corner = [1.0, 1.0] }}\n");
    let path = write_model(dir.path(), "edge", &[block_of(&block)], &body);
    let out = dir.path().join("out");
    let (code, log) = common::run(&[
        "solve",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("edge.json")).unwrap()).unwrap();
    let ck = signorini::io::hdf5::read_checkpoint(&out.join("edge.h5")).unwrap();
    let u = &ck.steps[0].displacement;
    for (name, x) in [("edge", [0.5, 1.0]), ("corner", [1.0, 1.0])] {
        let p = &j["probes"][name];
        let node = p["node"].as_u64().unwrap() as usize;
        // The nearest output point (the first of equals), as before.
        let d2 = |q: &[f64; 2]| (q[0] - x[0]).powi(2) + (q[1] - x[1]).powi(2);
        let nearest = (0..ck.mesh.points.len()).fold(0, |b, i| {
            if d2(&ck.mesh.points[i]) < d2(&ck.mesh.points[b]) {
                i
            } else {
                b
            }
        });
        assert_eq!(node, nearest, "{name}");
        // Its displacement (the JSON's decimal text: to 1 ulp).
        for k in 0..2 {
            let got = p["u"][k].as_f64().unwrap();
            assert!(
                (got - u[node][k]).abs() <= 1e-15 * u[node][k].abs(),
                "{name}: {got} vs {:?}",
                u[node]
            );
        }
    }
    assert_eq!(j["probes"]["corner"]["x"].as_f64(), Some(1.0));
    // 0.1 past the top edge of a 1 × 1 element: 10 % of its size > 5 %.
    let body = format!("{base}[output]\nprobes = {{ above = [0.5, 1.1] }}\n");
    let path = write_model(dir.path(), "above", &[block_of(&block)], &body);
    let err = match signorini::run::prepare(&path, false) {
        Ok(_) => panic!("a probe 0.1 past the mesh was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("probe above")
            && err.contains("outside the mesh")
            && err.contains("0.05 × its size"),
        "{err}"
    );
    // 0.02 past it (2 % of the element) is in.
    let body = format!("{base}[output]\nprobes = {{ near = [0.5, 1.02] }}\n");
    let path = write_model(dir.path(), "near", &[block_of(&block)], &body);
    assert!(signorini::run::prepare(&path, false).is_ok());
}
