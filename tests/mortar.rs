//! Mortar contact on non-matching pairs (`[[contact]] discretization =
//! "mortar"`, docs/methods.md §7.1): the contact patch test (El-Abbasi &
//! Bathe 2001) to round-off on non-matching meshes where node-to-segment
//! rows fail it, Hertz against the analytic solution, and mortar vs NTS on
//! three meshes.

mod common;

use signorini::fem::topology::RowKind;
use signorini::qp::{QpResult, SolverSection};
use signorini::run::{self, Prepared};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn solve(path: &Path) -> (Prepared, QpResult, signorini::output::StepOutput) {
    let (prep, res) = common::solve_file(path, &SolverSection::default());
    let step = signorini::post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    (prep, res, step)
}

/// Two unit blocks as MSH 2.2: "lower" [0,1]×[−1,0] with `nl`×`nl` squares,
/// "upper" [0,1]×[0,1] with `nu`×`nu`, each square cut into two triangles
/// along alternating diagonals; the blocks share no node (the interface
/// y = 0 is meshed twice, non-matching when nl ≠ nu).
fn two_blocks_msh(path: &Path, nu: usize, nl: usize) {
    let mut nodes: Vec<[f64; 2]> = vec![];
    let mut lines: Vec<(usize, [usize; 2])> = vec![]; // (physical, nodes)
    let mut tris: Vec<(usize, [usize; 3])> = vec![];
    // Physical tags: curves 1..8, surfaces 11, 12.
    for (n, y0, surf, [bottom, top, left, right]) in
        [(nl, -1.0, 11, [1, 2, 3, 4]), (nu, 0.0, 12, [5, 6, 7, 8])]
    {
        let base = nodes.len();
        let id = |i: usize, j: usize| base + j * (n + 1) + i + 1; // 1-based
        for j in 0..=n {
            for i in 0..=n {
                nodes.push([i as f64 / n as f64, y0 + j as f64 / n as f64]);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if (i + j) % 2 == 0 {
                    tris.push((surf, [a, b, c]));
                    tris.push((surf, [a, c, d]));
                } else {
                    tris.push((surf, [a, b, d]));
                    tris.push((surf, [b, c, d]));
                }
            }
        }
        for i in 0..n {
            lines.push((bottom, [id(i, 0), id(i + 1, 0)]));
            lines.push((top, [id(i, n), id(i + 1, n)]));
            lines.push((left, [id(0, i), id(0, i + 1)]));
            lines.push((right, [id(n, i), id(n, i + 1)]));
        }
    }
    let names = [
        (1, 1, "lower_bottom"),
        (1, 2, "lower_top"),
        (1, 3, "lower_left"),
        (1, 4, "lower_right"),
        (1, 5, "upper_bottom"),
        (1, 6, "upper_top"),
        (1, 7, "upper_left"),
        (1, 8, "upper_right"),
        (1, 9, "spare"),
        (2, 11, "lower"),
        (2, 12, "upper"),
    ];
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n");
    writeln!(s, "{}", names.len()).unwrap();
    for (d, t, n) in names {
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

/// The contact patch test's problem file: ν = 0, E = 2e6, bottom u_y = 0,
/// top u_y = −0.1, all sides on slip lines (El-Abbasi & Bathe 2001).
fn patch_toml(dir: &Path, msh: &Path, slave: &str, master: &str, disc: &str) -> PathBuf {
    let text = format!(
        r#"[mesh]
file = "{}"
[model]
plane = "strain"
[materials.lower]
E = 2.0e6
nu = 0.0
[materials.upper]
E = 2.0e6
nu = 0.0
[[dirichlet]]
on = "lower_bottom"
uy = 0.0
[[dirichlet]]
on = "upper_top"
uy = -0.1
[[slip]]
on = "lower_left"
[[slip]]
on = "lower_right"
[[slip]]
on = "upper_left"
[[slip]]
on = "upper_right"
[[contact]]
slave = "{slave}"
master = "{master}"
discretization = "{disc}"
[solver]
method = "ssn"
tol = 1e-12
"#,
        msh.display()
    );
    let p = dir.join(format!("patch_{disc}_{slave}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// (largest relative deviation of the pressure from 1e5, largest error of
/// the displacement field relative to 0.1) of one patch test.
fn patch_errors(nu: usize, nl: usize, slave_upper: bool, disc: &str) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("blocks.msh");
    two_blocks_msh(&msh, nu, nl);
    let (s, m) = if slave_upper {
        ("upper_bottom", "lower_top")
    } else {
        ("lower_top", "upper_bottom")
    };
    let (prep, res, step) = solve(&patch_toml(dir.path(), &msh, s, m, disc));
    assert!(
        res.active.iter().all(|a| *a),
        "{disc} {nu}/{nl}: the interface must stay closed"
    );
    let p_dev = step
        .contact_pressure
        .iter()
        .map(|p| (p / 1e5 - 1.0).abs())
        .fold(0.0, f64::max);
    // Exact field: u_y = −0.05 (y + 1) below, −0.05 − 0.05 y above; u_x = 0.
    let t = &prep.model.topo;
    let mut u_err = 0.0f64;
    for (i, x) in t.points.iter().enumerate() {
        let exact = if is_upper(&prep, i) {
            -0.05 - 0.05 * x[1]
        } else {
            -0.05 * (x[1] + 1.0)
        };
        let u = step.displacement[i];
        u_err = u_err.max((u[1] - exact).abs() / 0.1).max(u[0].abs() / 0.1);
    }
    (p_dev, u_err)
}

/// Whether point `i` belongs to the upper block (by its triangles' material).
fn is_upper(prep: &Prepared, i: usize) -> bool {
    let t = &prep.model.topo;
    t.triangles
        .iter()
        .zip(&t.tri_material)
        .find(|(tri, _)| tri.contains(&i))
        .map(|(_, &m)| t.material_names[m as usize] == "upper")
        .unwrap_or(false)
}

#[test]
fn contact_patch_test_is_passed_to_round_off_by_mortar_and_failed_by_nts() {
    for (nu, nl) in [(7, 10), (10, 7), (3, 11), (11, 3), (5, 13)] {
        for slave_upper in [true, false] {
            let (p_dev, u_err) = patch_errors(nu, nl, slave_upper, "mortar");
            eprintln!(
                "patch {nu}/{nl} slave {}: mortar pressure dev {p_dev:.2e}, displacement err {u_err:.2e}",
                if slave_upper { "upper" } else { "lower" }
            );
            assert!(
                p_dev < 1e-10,
                "mortar {nu}/{nl}: pressure deviates by {p_dev:e}"
            );
            assert!(
                u_err < 1e-10,
                "mortar {nu}/{nl}: displacement error {u_err:e}"
            );
        }
    }
    // The test can fail: node-to-segment rows on the same meshes miss it by
    // percents (the issue's ±15 % at 7/10).
    let (p_dev, u_err) = patch_errors(7, 10, true, "nts");
    eprintln!("patch 7/10 nts: pressure dev {p_dev:.2e}, displacement err {u_err:.2e}");
    assert!(p_dev > 0.05 && u_err > 1e-3, "NTS: {p_dev:e} {u_err:e}");
}

/// On matching meshes the mortar rows are node-to-node with weight 1.
#[test]
fn matching_meshes_give_node_to_node_mortar_rows() {
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("blocks.msh");
    two_blocks_msh(&msh, 6, 6);
    let (prep, _, step) = solve(&patch_toml(
        dir.path(),
        &msh,
        "upper_bottom",
        "lower_top",
        "mortar",
    ));
    let t = &prep.model.topo;
    assert_eq!(t.contact.len(), 7);
    for row in &t.contact {
        let heavy: Vec<_> = row.masters.iter().filter(|m| m.1.abs() > 1e-13).collect();
        assert_eq!(heavy.len(), 1, "{:?}", row.masters);
        let m = heavy[0];
        assert!((m.1 - 1.0).abs() < 1e-13);
        let (xs, xm) = (t.points[row.first], t.points[m.0]);
        assert!((xs[0] - xm[0]).abs() < 1e-15 && xs[1] == xm[1]);
        // D_jj: half the adjacent slave segments (1/12 at the ends).
        let want = if xs[0] == 0.0 || xs[0] == 1.0 {
            1.0 / 12.0
        } else {
            1.0 / 6.0
        };
        assert!((row.trib - want).abs() < 1e-15, "{} vs {want}", row.trib);
    }
    assert!(step
        .contact_pressure
        .iter()
        .all(|p| (p / 1e5 - 1.0).abs() < 1e-10));
}

/// A slave curve longer than the master: the overhanging part of a slave
/// segment gets no weight, the rest keeps exact rows, so a uniform pressure
/// is still transmitted exactly where the master is.
#[test]
fn slave_segments_partly_outside_the_master_are_integrated_over_the_overlap() {
    // Upper block [0,1] on a lower block cut to [0, 0.55]: ... the master
    // curve is the lower top, which ends inside an upper segment.
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("blocks.msh");
    two_blocks_msh(&msh, 4, 10);
    // Keep only the first 6 lower-top segments as master: [0, 0.6], which
    // ends inside the slave segment [0.5, 0.75].
    let text = std::fs::read_to_string(&msh).unwrap();
    let mut out = String::new();
    let mut cut = 0;
    for line in text.lines() {
        let f: Vec<&str> = line.split(' ').collect();
        if f.len() == 7 && f[1] == "1" && f[3] == "2" {
            cut += 1;
            if cut > 6 {
                // Re-tag as a curve that is not in the pair.
                writeln!(out, "{} 1 2 9 9 {} {}", f[0], f[5], f[6]).unwrap();
                continue;
            }
        }
        writeln!(out, "{line}").unwrap();
    }
    std::fs::write(&msh, out).unwrap();
    let p = patch_toml(dir.path(), &msh, "upper_bottom", "lower_top", "mortar");
    let prep = run::prepare(&p, false).unwrap_or_else(|e| panic!("{e}"));
    let t = &prep.model.topo;
    // Slave nodes x = 0, 0.25, 0.5, 0.75 have weight; x = 1 has none.
    let xs: Vec<f64> = t.contact.iter().map(|r| t.points[r.first][0]).collect();
    assert_eq!(xs, vec![0.0, 0.25, 0.5, 0.75]);
    for r in &t.contact {
        let x = t.points[r.first][0];
        // D_jj = ∫ over the overlap of N_j: the segment [0.5, 0.75] counts
        // on [0.5, 0.6] only.
        let want = match x {
            0.0 => 0.125,
            0.25 => 0.25,
            0.5 => 0.125 + 0.1 - 0.1 * 0.1 / (2.0 * 0.25),
            _ => 0.1 * 0.1 / (2.0 * 0.25),
        };
        assert!(
            (r.trib - want).abs() < 1e-14,
            "x = {x}: D = {} vs {want}",
            r.trib
        );
        // Σ_m M_jm = D_jj (rigid translations pass the row), gap 0.
        let s: f64 = r.masters.iter().map(|m| m.1).sum();
        assert!(
            (s - 1.0).abs() < 1e-13 && r.gap0.abs() < 1e-15,
            "x = {x}: Σw = {s}"
        );
        // The masters lie within the overlap's reach.
        for &(pm, w) in &r.masters {
            assert!(w == 0.0 || t.points[pm][0] <= 0.6 + 1e-12);
        }
    }
}

/// A Hertz model (meshes/hertz.geo at contact size `hmin`) with the given
/// discretization; returns (Σλ, fitted a, fitted p0, pressure (x, p) sorted).
struct Hertz {
    sum_lambda: f64,
    /// The vertical resultant Σ λ_j |n_jy| (= the load by equilibrium).
    vertical: f64,
    a: f64,
    p0: f64,
    profile: Vec<(f64, f64)>,
}

fn hertz(dir: &Path, msh: &Path, disc: &str) -> Hertz {
    let text = std::fs::read_to_string(common::root().join("meshes/hertz.toml"))
        .unwrap()
        .replace(
            "file = \"hertz.msh\"",
            &format!("file = \"{}\"", msh.display()),
        )
        .replace(
            "master = \"block_top\"",
            &format!("master = \"block_top\"\ndiscretization = \"{disc}\""),
        )
        .replace("method = \"cgc\"", "method = \"ssn\"");
    let p = dir.join(format!("hertz_{disc}.toml"));
    std::fs::write(&p, text).unwrap();
    let (prep, res, step) = solve(&p);
    let t = &prep.model.topo;
    let mut profile: Vec<(f64, f64)> = t
        .contact
        .iter()
        .zip(&step.contact_pressure)
        .map(|(r, &p)| (t.points[r.first][0], p))
        .collect();
    profile.sort_by(|x, y| x.0.total_cmp(&y.0));
    // Hertz: p² = p0² − (p0/a)² x², fitted by least squares on the nodes
    // with p > 0.3 max p (away from the edge, where one node straddles it).
    let pmax = profile.iter().fold(0.0f64, |m, q| m.max(q.1));
    let pts: Vec<(f64, f64)> = profile
        .iter()
        .filter(|q| q.1 > 0.3 * pmax)
        .map(|&(x, p)| (x * x, p * p))
        .collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |s, q| (s.0 + q.0, s.1 + q.1));
    let (mx, my) = (sx / n, sy / n);
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |s, q| {
        (s.0 + (q.0 - mx) * (q.1 - my), s.1 + (q.0 - mx) * (q.0 - mx))
    });
    let beta = -sxy / sxx;
    let alpha = my + beta * mx;
    Hertz {
        sum_lambda: res.lambda.iter().sum(),
        vertical: prep
            .model
            .qp_rows
            .iter()
            .zip(&res.lambda)
            .map(|(&r, l)| l * t.contact[r].normal[1].abs())
            .sum(),
        a: (alpha / beta).sqrt(),
        p0: alpha.sqrt(),
        profile,
    }
}

/// The analytic Hertz values of meshes/hertz.toml: (a, p0).
fn hertz_analytic() -> (f64, f64) {
    let (e, nu, r) = (2.0e11, 0.3, 1.0);
    let estar = 1.0 / (2.0 * (1.0 - nu * nu) / e);
    let f = 2.0 * 4.3154e8; // full model: twice the half model's load
    let a = (4.0 * f * r / (std::f64::consts::PI * estar)).sqrt();
    (a, 2.0 * f / (std::f64::consts::PI * a))
}

/// The node-to-node ripple: the largest second difference
/// |r_i − (r_{i−1} + r_{i+1})/2| / p0 of the residual r = p − p0·sqrt(1 − x²/a²)
/// from the fitted Hertz profile (so that the profile's own curvature does
/// not count), over nodes with x < 0.8 a.
fn ripple(h: &Hertz) -> f64 {
    let r: Vec<(f64, f64)> = h
        .profile
        .iter()
        .map(|&(x, p)| (x, p - h.p0 * (1.0 - (x / h.a).powi(2)).max(0.0).sqrt()))
        .collect();
    r.windows(3)
        .filter(|w| w[2].0 < 0.8 * h.a)
        .map(|w| (w[1].1 - 0.5 * (w[0].1 + w[2].1)).abs() / h.p0)
        .fold(0.0, f64::max)
}

#[test]
fn hertz_with_mortar_matches_a_and_p0_without_ripple() {
    let dir = tempfile::tempdir().unwrap();
    let h = hertz(
        dir.path(),
        &common::root().join("meshes/hertz.msh"),
        "mortar",
    );
    let (a, p0) = hertz_analytic();
    let rip = ripple(&h);
    eprintln!(
        "hertz mortar: a = {:.5} (analytic {a:.5}), p0 = {:.5e} (analytic {p0:.5e}), ripple {rip:.2e}",
        h.a, h.p0
    );
    assert!((h.a - a).abs() < 0.01 * a, "a = {}, analytic {a}", h.a);
    assert!(
        (h.p0 - p0).abs() < 0.01 * p0,
        "p0 = {}, analytic {p0}",
        h.p0
    );
    assert!(rip < 0.01, "ripple {rip}");
    // The closed nodes are contiguous from the axis (no alternate opening).
    let last_closed = h.profile.iter().rposition(|q| q.1 > 0.0).unwrap();
    assert!(h.profile[..=last_closed].iter().all(|q| q.1 > 0.0));
    // Every pressure within 2 % of p0 of p0·sqrt(1 − x²/a²) inside 0.8 a.
    for &(x, p) in h.profile.iter().filter(|q| q.0 < 0.8 * a) {
        let ph = p0 * (1.0 - x * x / (a * a)).sqrt();
        assert!(
            (p - ph).abs() < 0.02 * p0,
            "x = {x}: p = {p:.4e}, Hertz {ph:.4e}"
        );
    }
}

/// meshes/hertz.geo with the contact element size a/`k` (and the far size
/// scaled alike), meshed by gmsh.
fn hertz_mesh(dir: &Path, k: usize) -> PathBuf {
    let geo = std::fs::read_to_string(common::root().join("meshes/hertz.geo")).unwrap();
    assert!(geo.contains("hmin = a / 15;"));
    let geo = geo
        .replace("hmin = a / 15;", &format!("hmin = a / {k};"))
        .replace("hmax = 0.3;", &format!("hmax = {};", 0.3 * 15.0 / k as f64));
    let g = dir.join(format!("hertz_{k}.geo"));
    std::fs::write(&g, geo).unwrap();
    let m = dir.join(format!("hertz_{k}.msh"));
    let (code, out, err) =
        common::signorini(&["mesh", g.to_str().unwrap(), "-o", m.to_str().unwrap()]);
    assert_eq!(code, 0, "signorini mesh: {out}{err}");
    m
}

#[test]
fn mortar_and_nts_agree_as_the_mesh_is_refined() {
    let dir = tempfile::tempdir().unwrap();
    let (a, p0) = hertz_analytic();
    let load = 4.3154e8;
    let mut table = String::from(
        "  h_c  | Σλ/F mortar Σλ/F nts | ΣλFy/F−1 mortar nts | p0 mortar  p0 nts     |Δp0|/p0 | a mortar a nts   | ripple mortar nts\n",
    );
    let mut dp = vec![];
    let mut df = vec![];
    for k in [8, 15, 30] {
        let msh = hertz_mesh(dir.path(), k);
        let m = hertz(dir.path(), &msh, "mortar");
        let n = hertz(dir.path(), &msh, "nts");
        let d = (m.p0 - n.p0).abs() / p0;
        writeln!(
            table,
            "  a/{k:<2} | {:.6}    {:.6}  | {:+.1e}  {:+.1e}       | {:.5e} {:.5e} {:.2e} | {:.5}  {:.5} | {:.2e}  {:.2e}",
            m.sum_lambda / load,
            n.sum_lambda / load,
            m.vertical / load - 1.0,
            n.vertical / load - 1.0,
            m.p0,
            n.p0,
            d,
            m.a,
            n.a,
            ripple(&m),
            ripple(&n),
        )
        .unwrap();
        dp.push(d);
        // The vertical resultant is the load for both (equilibrium of the
        // cylinder, held by contact alone).
        for h in [&m, &n] {
            assert!(
                (h.vertical / load - 1.0).abs() < 1e-8,
                "{}",
                h.vertical / load
            );
        }
        df.push((m.sum_lambda - n.sum_lambda).abs() / load);
        // Both near Hertz on every mesh.
        assert!((m.p0 - p0).abs() < 0.03 * p0 && (n.p0 - p0).abs() < 0.03 * p0);
        assert!((m.a - a).abs() < 0.03 * a && (n.a - a).abs() < 0.03 * a);
    }
    eprintln!("mortar vs NTS on Hertz (F = {load:e} N/m, a = {a:.5}, p0 = {p0:.5e}):\n{table}");
    // The differences shrink with h.
    assert!(df[2] < df[0], "Σλ differences {df:?}");
    assert!(dp[2] < dp[0], "p0 differences {dp:?}");
}

/// `discretization` on a conforming pair, or an unknown value: an error
/// naming the file and the pair.
#[test]
fn bad_discretization_is_refused_naming_the_file_and_the_pair() {
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("blocks.msh");
    two_blocks_msh(&msh, 3, 4);
    let p = patch_toml(dir.path(), &msh, "upper_bottom", "lower_top", "segment");
    let e = run::prepare(&p, false)
        .err()
        .expect("unknown value accepted")
        .to_string();
    assert!(
        e.contains(&p.display().to_string())
            && e.contains("[[contact]] #1 (slave = \"upper_bottom\", master = \"lower_top\")")
            && e.contains("discretization = \"segment\" is unknown"),
        "{e}"
    );
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replace(
            "slave = \"upper_bottom\"\nmaster = \"lower_top\"",
            "on = \"upper_bottom\"",
        )
        .replace("\"segment\"", "\"mortar\"");
    std::fs::write(&p, text).unwrap();
    let e = run::prepare(&p, false)
        .err()
        .expect("conforming mortar accepted")
        .to_string();
    assert!(
        e.contains(&p.display().to_string())
            && e.contains("[[contact]] #1 (on = \"upper_bottom\"): discretization applies to non-matching pairs"),
        "{e}"
    );
}

/// The hard punch (tests/hard/punch.toml) with the soft foundation as the
/// mortar slave: its top is longer than the punch (slave segments partly
/// outside the master) and the punch corners are rounded (a curved master).
/// The closed nodes are contiguous, the pressure is symmetric, and the
/// vertical resultant is the load, 1e6 Pa × 2 m.
#[test]
fn punch_with_the_foundation_as_mortar_slave_is_smooth_and_balanced() {
    let dir = tempfile::tempdir().unwrap();
    let hard = common::root().join("tests/hard");
    let text = std::fs::read_to_string(hard.join("punch.toml"))
        .unwrap()
        .replace(
            "file = \"punch.msh\"",
            &format!("file = \"{}\"", hard.join("punch.msh").display()),
        )
        .replace("slave = \"punch_bottom\"", "slave = \"found_top\"")
        .replace(
            "master = \"found_top\"",
            "master = \"punch_bottom\"\ndiscretization = \"mortar\"",
        )
        .replace("method = \"cgc\"", "method = \"ssn\"");
    assert!(text.contains("discretization = \"mortar\""));
    let p = dir.path().join("punch_mortar.toml");
    std::fs::write(&p, text).unwrap();
    let (prep, res, step) = solve(&p);
    let t = &prep.model.topo;
    let vertical: f64 = prep
        .model
        .qp_rows
        .iter()
        .zip(&res.lambda)
        .map(|(&r, l)| l * t.contact[r].normal[1].abs())
        .sum();
    assert!(
        (vertical / 2e6 - 1.0).abs() < 1e-8,
        "vertical resultant {vertical}"
    );
    let mut prof: Vec<(f64, f64)> = t
        .contact
        .iter()
        .zip(&step.contact_pressure)
        .map(|(r, &p)| (t.points[r.first][0], p))
        .collect();
    prof.sort_by(|x, y| x.0.total_cmp(&y.0));
    let closed: Vec<usize> = (0..prof.len()).filter(|&i| prof[i].1 > 0.0).collect();
    let (lo, hi) = (closed[0], *closed.last().unwrap());
    assert_eq!(
        closed.len(),
        hi - lo + 1,
        "open nodes inside the contact: {prof:?}"
    );
    let pmax = prof.iter().fold(0.0f64, |m, q| m.max(q.1));
    for (i, q) in prof.iter().enumerate() {
        let mirror = prof[prof.len() - 1 - i];
        assert!((q.0 + mirror.0).abs() < 1e-9 && (q.1 - mirror.1).abs() < 1e-2 * pmax);
    }
}

/// Two blocks of `two_blocks_msh` pressed by a uniform pressure of 100 MPa
/// on the top of the upper one (the slave), the left sides and the bottom
/// sliding, frictionless; `disc` is the `discretization` line (empty: no
/// key, the default). Upper E = `e_upper`, lower E = 2.1e11, ν = 0.3.
fn pressed_toml(dir: &Path, msh: &Path, name: &str, e_upper: f64, disc: &str) -> PathBuf {
    let text = format!(
        r#"[mesh]
file = "{}"
[model]
plane = "strain"
[materials.lower]
E = 2.1e11
nu = 0.3
[materials.upper]
E = {e_upper:e}
nu = 0.3
[[traction]]
on = "upper_top"
pn = -1.0e8
[[slip]]
on = "lower_bottom"
[[slip]]
on = "lower_left"
[[slip]]
on = "upper_left"
[[contact]]
slave = "upper_bottom"
master = "lower_top"
{disc}
[solver]
tol = 1e-12
"#,
        msh.display()
    );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// Issue 42 §5. A flat interface meshed 5:4 (5k slave segments on 4k master
/// segments, unit blocks, one material) under a uniform pressure p: the
/// exact pressure is p on every row (the contact patch test, Taylor &
/// Papadopoulos 1991). A pair without `discretization` gets mortar rows,
/// which give p to round-off on three meshes; node-to-segment rows, on
/// request, are low where a slave node lands on a master node (every fifth
/// slave node), by the same 7 % on every mesh: their error does not shrink
/// with h. Before mortar became the default, the pair without the key
/// was the NTS one and the first assertion failed at 7e-2.
#[test]
fn a_5_to_4_interface_gets_mortar_by_default_and_nts_stays_low_under_refinement() {
    let dir = tempfile::tempdir().unwrap();
    let p = 1.0e8;
    let mut nts_low = vec![];
    for k in [2usize, 4, 8] {
        let msh = dir.path().join(format!("blocks54_{k}.msh"));
        two_blocks_msh(&msh, 5 * k, 4 * k);
        for (name, disc) in [("default", ""), ("nts", "discretization = \"nts\"")] {
            let path = pressed_toml(dir.path(), &msh, &format!("{name}_{k}"), 2.1e11, disc);
            let (prep, res, step) = solve(&path);
            let t = &prep.model.topo;
            assert!(res.active.iter().all(|a| *a), "{name} {k}: a row opened");
            let dev: Vec<(f64, f64)> = t
                .contact
                .iter()
                .zip(&step.contact_pressure)
                .map(|(r, &q)| (t.points[r.first][0], q / p - 1.0))
                .collect();
            let worst = dev.iter().fold(0.0f64, |m, d| m.max(d.1.abs()));
            if disc.is_empty() {
                assert_eq!(t.interface_kinds, vec![RowKind::Mortar]);
                assert!(worst < 1e-10, "k = {k}: mortar deviates by {worst:e}");
            } else {
                assert_eq!(t.interface_kinds, vec![RowKind::NonMatching]);
                // Interior slave nodes on a master node: x = j / k.
                let on: Vec<f64> = dev
                    .iter()
                    .filter(|d| d.0 > 1e-9 && d.0 < 1.0 - 1e-9)
                    .filter(|d| (d.0 * k as f64 - (d.0 * k as f64).round()).abs() < 1e-9)
                    .map(|d| d.1)
                    .collect();
                assert_eq!(on.len(), k - 1);
                let mean = on.iter().sum::<f64>() / on.len() as f64;
                eprintln!("5:4, k = {k}: nts rows on master nodes {mean:+.4}, worst {worst:.4}");
                nts_low.push(mean);
            }
        }
    }
    // Low by 6–8 % on every mesh, the same to 0.5 % of p: no convergence.
    assert!(
        nts_low.iter().all(|m| (-0.08..-0.06).contains(m)),
        "{nts_low:?}"
    );
    let spread = nts_low
        .iter()
        .fold(0.0f64, |m, a| m.max((a - nts_low[0]).abs()));
    assert!(spread < 0.005, "{nts_low:?}");
}

/// A pair without `discretization` whose slave is more than 10 times
/// stiffer than its master keeps node-to-segment rows (mortar multipliers
/// on a much stiffer slave alternate between open and closed rows,
/// docs/methods.md §7.1); at 5 times it gets mortar rows, and a key
/// written by hand is obeyed either way. The checkpoint and the JSON
/// record what each pair ran.
#[test]
fn the_default_keeps_nts_for_a_much_stiffer_slave_and_the_outputs_record_it() {
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("blocks.msh");
    two_blocks_msh(&msh, 5, 4);
    for (e_upper, disc, want, name) in [
        (2.1e12, "", "mortar", "e10"),
        (2.1e13, "", "nts", "e100"),
        (
            2.1e13,
            "discretization = \"mortar\"",
            "mortar",
            "e100_mortar",
        ),
        (2.1e11, "discretization = \"nts\"", "nts", "e1_nts"),
    ] {
        let path = pressed_toml(dir.path(), &msh, name, e_upper, disc);
        let out = dir.path().join(format!("out_{name}"));
        let (code, o, e) = common::signorini(&[
            "solve",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{name}: {o}{e}");
        let warned = e.contains("times stiffer than master");
        assert_eq!(warned, name == "e100", "{name}: {e}");
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("{name}.json"))).unwrap(),
        )
        .unwrap();
        let it = &json["contact"]["interfaces"]["upper_bottom->lower_top"];
        assert_eq!(it["discretization"], want, "{name}");
        let ck = signorini::io::hdf5::read_checkpoint(&out.join(format!("{name}.h5"))).unwrap();
        assert_eq!(
            ck.mesh.contact.interface_discretizations,
            vec![want.to_string()]
        );
    }
}

/// A restart compares the rows a pair was built with, not the text. A
/// checkpoint written before mortar became the default, of a pair without
/// `discretization` (node-to-segment rows then; made here by writing a
/// checkpoint with the key and giving it the fingerprint of that time,
/// `run::fingerprint_before_mortar`), is refused for the pair without the
/// key, which now has mortar rows, with the hint to write
/// `discretization = "nts"`, and continued once it is written. A
/// checkpoint of the default continues with `discretization = "mortar"`
/// written out (the same rows).
#[test]
fn restart_refuses_a_checkpoint_of_other_rows_and_names_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let msh = dir.path().join("blocks.msh");
    two_blocks_msh(&msh, 5, 4);
    let with = |disc: &str| {
        let p = pressed_toml(dir.path(), &msh, "steps", 2.1e11, disc);
        let text = std::fs::read_to_string(&p).unwrap()
            + "[[steps]]\nfactor = 0.5\n[[steps]]\nfactor = 1.0\n";
        std::fs::write(&p, text).unwrap();
        p
    };
    let solve_steps = |p: &Path, out: &Path, restart: Option<&Path>| {
        let mut args = vec![
            "solve".to_string(),
            p.display().to_string(),
            "--out".into(),
            out.display().to_string(),
            "--quiet".into(),
        ];
        match restart {
            Some(h5) => args.extend(["--restart".into(), h5.display().to_string()]),
            None => args.extend(["--max-steps".into(), "1".into()]),
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        common::signorini(&args)
    };
    let nts = "discretization = \"nts\"";
    for (first, old, then, ok) in [
        (nts, true, "", false),
        (nts, true, nts, true),
        (nts, false, nts, true),
        ("", false, "discretization = \"mortar\"", true),
    ] {
        let part = tempfile::tempdir().unwrap();
        let toml = with(first);
        let (code, o, e) = solve_steps(&toml, part.path(), None);
        assert_eq!(code, 0, "{o}{e}");
        let h5 = part.path().join("steps.h5");
        if old {
            let prep = run::prepare(&toml, false).unwrap();
            let fp = run::fingerprint_before_mortar(&prep, false).unwrap();
            assert_ne!(fp, run::fingerprint(&prep, false));
            let f = hdf5::File::open_rw(&h5).unwrap();
            f.delete_attr("fingerprint").unwrap();
            let v: hdf5::types::VarLenUnicode = fp.parse().unwrap();
            f.new_attr::<hdf5::types::VarLenUnicode>()
                .create("fingerprint")
                .unwrap()
                .write_scalar(&v)
                .unwrap();
        }
        let out = tempfile::tempdir().unwrap();
        let (code, o, e) = solve_steps(&with(then), out.path(), Some(&h5));
        let case = format!("{first:?} (old: {old}) -> {then:?}");
        if ok {
            assert_eq!(code, 0, "{case}: {o}{e}");
        } else {
            assert_eq!(code, 2, "{case}: {o}{e}");
            assert!(
                e.contains("different contact") && e.contains("add discretization = \"nts\""),
                "{case}: {e}"
            );
        }
    }
}

/// verification/shrinkfit (axisymmetric, Coulomb μ = 0.2, mortar rows by
/// default): the inner tube's ends are held at u_z = 0 during the fit and
/// pushed by 1e−4 m in the last step. The end rows' slave points are held
/// along the tangent in the fit but not in the push, so they are no
/// symmetry line and keep their friction: the push force at full slip is
/// μ·p·c·L per radian with Lamé's fit pressure p (Timoshenko & Goodier
/// 1970, §28). Before, the end rows lost their friction in every step and
/// the force came out 12.8 % low on this mesh.
#[test]
fn mortar_friction_at_an_end_moved_in_a_later_step_is_kept() {
    let dir = tempfile::tempdir().unwrap();
    let src = common::root().join("verification/shrinkfit");
    let geo = dir.path().join("shrinkfit.geo");
    std::fs::copy(src.join("shrinkfit.geo"), &geo).unwrap();
    std::fs::copy(
        src.join("shrinkfit.toml"),
        dir.path().join("shrinkfit.toml"),
    )
    .unwrap();
    let (code, o, e) = common::signorini(&["mesh", geo.to_str().unwrap()]);
    assert_eq!(code, 0, "{o}{e}");
    let out = dir.path().join("out");
    let toml = dir.path().join("shrinkfit.toml");
    let (code, o, e) = common::signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{o}{e}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("shrinkfit.json")).unwrap())
            .unwrap();
    let it = &json["contact"]["interfaces"]["inner_contact->outer_contact"];
    assert_eq!(it["discretization"], "mortar");
    let fz = |g: &str| json["reactions"][g]["force"][1].as_f64().unwrap();
    let push = (fz("inner_bottom") + fz("inner_top")).abs();
    // Lamé: u_r(r) = (1+ν)/E ((1−2ν) A r + B/r) for σ_rr = A − B/r².
    let (a, c, b, delta, e_mod, nu, mu, l) = (0.5, 1.0, 1.5, 1.0e-3, 2.0e11, 0.3, 0.2, 0.5);
    let u = |aa: f64, bb: f64, r: f64| (1.0 + nu) / e_mod * ((1.0 - 2.0 * nu) * aa * r + bb / r);
    let ao = c * c / (b * b - c * c);
    let ai = -c * c / (c * c - a * a);
    let p = delta / (u(ao, ao * b * b, c) - u(ai, ai * a * a, c));
    let limit = mu * p * c * l;
    assert!(
        (push / limit - 1.0).abs() < 0.005,
        "push {push:e} against μpcL {limit:e}: {:+.2} %",
        100.0 * (push / limit - 1.0)
    );
}
