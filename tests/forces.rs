//! Reactions and contact resultants (post/forces.rs) on every shipped model:
//! the reactions balance the applied loads (force and moment), each body is
//! in equilibrium under its loads, reactions and contact forces, every
//! interface's two sides carry equal and opposite resultants, and the
//! reactions of two models match the load they carry by hand.

use signorini::post::{self, forces};
use signorini::qp::SolverSection;
use signorini::run;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// (prepared problem, forces) of a shipped model solved by the default method.
fn solved(name: &str) -> (run::Prepared, forces::Forces) {
    let path = root().join("meshes").join(format!("{name}.toml"));
    let prep = run::prepare(&path, false).unwrap_or_else(|e| panic!("{e}"));
    let (method, opts) = run::options(&prep.problem, &SolverSection::default()).unwrap();
    let res = run::solve(&prep, method, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(res.status.converged(), "{name}: {:?}", res.status);
    let step = post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    let f = forces::compute(
        &prep.model,
        &prep.problem.file.materials,
        &step.displacement,
        &step.multipliers,
        &step.contact_pressure,
    );
    assert_eq!(step.reaction, f.point_reaction);
    (prep, f)
}

const SHIPPED: &[&str] = &[
    "column",
    "two_blocks",
    "two_blocks_glued",
    "two_blocks_eccentric",
    "hertz",
    "floating_block",
    "three_bodies",
    "cantilevers",
    "hip",
    "geodynamic",
    "geodynamic_steps",
    "rollers",
];

/// |a + b| ≤ tol · scale, for force and moment.
fn balanced(what: &str, a: forces::Resultant, b: forces::Resultant, scale: [f64; 2], tol: f64) {
    let df = (a.force[0] + b.force[0]).hypot(a.force[1] + b.force[1]);
    let dm = (a.moment + b.moment).abs();
    assert!(
        df <= tol * scale[0] && dm <= tol * scale[1],
        "{what}: force {:?} + {:?} (|sum| {df:.3e}, scale {:.3e}), moment {:.6e} + {:.6e} (|sum| {dm:.3e}, scale {:.3e})",
        a.force,
        b.force,
        scale[0],
        a.moment,
        b.moment,
        scale[1]
    );
}

/// Σ|f_p| and Σ|x_p × f_p| over the given point forces: the scales that a
/// sum of them is compared with.
fn scales<'a>(pts: &[[f64; 2]], fs: impl Iterator<Item = &'a [[f64; 2]]>) -> [f64; 2] {
    let mut s = [0.0f64, 0.0];
    for f in fs {
        for (x, v) in pts.iter().zip(f) {
            s[0] += v[0].hypot(v[1]);
            s[1] += (x[0] * v[1] - x[1] * v[0]).abs() + x[0].hypot(x[1]) * v[0].hypot(v[1]);
        }
    }
    s
}

#[test]
fn reactions_balance_the_loads_on_every_shipped_model() {
    for name in SHIPPED {
        let (prep, f) = solved(name);
        let m = &prep.model;
        let pts = &m.topo.points;
        let scale = scales(pts, [&m.loads[..], &f.point_reaction[..]].into_iter());
        assert!(scale[0] > 0.0, "{name}: neither loads nor reactions");
        // Loads + reactions + the contact couple = 0 in moment: mortar rows
        // (hertz) spread a slave node's force over master points off its
        // line of action, so their couple is not 0 without friction either.
        let with_couple = forces::Resultant {
            moment: f.reactions.moment + f.couple,
            ..f.reactions
        };
        balanced(name, f.loads, with_couple, scale, 1e-8);
        // The groups add up to the total.
        let mut sum = forces::Resultant::default();
        for g in &f.groups {
            sum.force[0] += g.resultant.force[0];
            sum.force[1] += g.resultant.force[1];
            sum.moment += g.resultant.moment;
        }
        let neg = forces::Resultant {
            force: [-f.reactions.force[0], -f.reactions.force[1]],
            moment: -f.reactions.moment,
        };
        balanced(&format!("{name}: groups"), sum, neg, scale, 1e-12);
        // Every [[dirichlet]]/[[slip]] group appears, with its points.
        let f_toml = &prep.problem.file;
        for on in f_toml
            .dirichlet
            .iter()
            .map(|d| &d.on)
            .chain(f_toml.slip.iter().map(|s| &s.on))
        {
            let g = f.groups.iter().find(|g| &g.on == on);
            assert!(g.is_some_and(|g| g.points > 0), "{name}: group {on}");
        }
    }
}

#[test]
fn every_body_is_in_equilibrium_and_interfaces_are_action_reaction() {
    for name in SHIPPED {
        let (prep, f) = solved(name);
        let m = &prep.model;
        let t = &m.topo;
        let scale = scales(
            &t.points,
            [&m.loads[..], &f.point_reaction[..], &f.point_contact[..]].into_iter(),
        );
        for b in 0..t.nbodies {
            let mut body = forces::Resultant::default();
            for p in (0..t.points.len()).filter(|&p| t.point_body[p] as usize == b) {
                for v in [m.loads[p], f.point_reaction[p], f.point_contact[p]] {
                    body.add(t.points[p], v);
                }
            }
            balanced(
                &format!("{name}: {}", m.body_label(b)),
                body,
                forces::Resultant::default(),
                scale,
                1e-8,
            );
        }
        for it in &f.interfaces {
            let s = it.resultant.force[0].hypot(it.resultant.force[1]);
            let xmax = t.points.iter().fold(0.0f64, |a, x| a.max(x[0].hypot(x[1])));
            // The other side's moment is the opposite one plus the couple
            // (docs/problem-format.md §7).
            let other = forces::Resultant {
                moment: it.other.moment - it.couple,
                ..it.other
            };
            balanced(
                &format!("{name}: interface {}", it.name),
                it.resultant,
                other,
                [s.max(f64::MIN_POSITIVE), s * xmax.max(1.0)],
                1e-12,
            );
            assert!(it.active <= it.rows && it.rows > 0);
            assert!(!it.on_body.is_empty());
        }
    }
}

#[test]
fn reactions_carry_the_load_by_hand() {
    // Column under its own weight: the bottom carries ρ g H W, the slip
    // sides carry no vertical force.
    let (_, f) = solved("column");
    let g = |on: &str| f.groups.iter().find(|g| g.on == on).unwrap().resultant;
    let w = 2000.0 * 9.81 * 10.0 * 1.0;
    assert!(
        (g("bottom").force[1] - w).abs() <= 1e-9 * w,
        "{:?}",
        g("bottom")
    );
    assert!(g("left").force[1].abs() <= 1e-9 * w);
    assert!((g("left").force[0] + g("right").force[0]).abs() <= 1e-8 * w);
    // Hertz: the traction on the cylinder top goes through the contact
    // into the block's bottom; the interface resultant on the cylinder is
    // the whole load, pointing up.
    let (prep, f) = solved("hertz");
    let total = -f.loads.force[1];
    assert!(total > 0.0);
    let bottom = f.groups.iter().find(|g| g.on == "block_bottom").unwrap();
    assert!((bottom.resultant.force[1] - total).abs() <= 1e-8 * total);
    let it = &f.interfaces[0];
    assert_eq!(it.on_body, "cylinder");
    assert!((it.resultant.force[1] - total).abs() <= 1e-8 * total);
    // Mortar rows (the default) act along the cylinder's normals, tilted by
    // up to a/R = 0.1 from the vertical: a horizontal force of the order
    // (a/R)·F on the half cylinder, which its axis (a slip line) takes.
    let axis = f.groups.iter().find(|g| g.on == "cyl_axis").unwrap();
    assert!((it.resultant.force[0] + axis.resultant.force[0]).abs() <= 1e-8 * total);
    assert!(it.resultant.force[0].abs() <= 0.1 * total);
    assert!(it.max_pressure > 0.0);
    assert!(prep.model.body_names.contains(&"block".to_string()));
}

#[test]
fn vtu_names_components_and_writes_reactions() {
    // The shipped column model through the pipeline's writer: ParaView's
    // ComponentName attributes in the XML, and the file still reads back.
    let (prep, _) = solved("column");
    let path = root().join("meshes/column.toml");
    let (method, opts) = run::options(&prep.problem, &SolverSection::default()).unwrap();
    let res = run::solve(&prep, method, &opts).unwrap();
    let step = post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let dir = tempfile::tempdir().unwrap();
    let out = run::output_paths(dir.path(), "column", None);
    signorini::io::vtu::write_vtu(&out.vtu, &om, &step, false).unwrap();
    // The arrays are appended raw: the XML around them is text.
    let xml = String::from_utf8_lossy(&std::fs::read(&out.vtu).unwrap()).into_owned();
    for want in [
        r#"Name="stress" NumberOfComponents="4""#,
        r#"ComponentName0="sxx" ComponentName1="syy" ComponentName2="sxy" ComponentName3="szz""#,
        r#"ComponentName0="ux" ComponentName1="uy" ComponentName2="uz""#,
        r#"ComponentName0="s1" ComponentName1="s2""#,
        r#"ComponentName0="Rx""#,
    ] {
        assert!(xml.contains(want), "{want} missing in {}", path.display());
    }
    let back = signorini::io::vtu::read_vtu_arrays(&out.vtu).unwrap();
    let r = back.point_array("reaction").expect("reaction array");
    assert_eq!(r.num_comp, 3);
    // The reaction of the bottom (u_y = 0) carries the column's weight.
    let sum_y: f64 = r.values.chunks(3).map(|c| c[1]).sum();
    let w = 2000.0 * 9.81 * 10.0;
    assert!((sum_y - w).abs() <= 1e-8 * w, "{sum_y} vs {w}");
    assert!(back.point_array("contact_role").is_some());
}

/// One slave curve over two blocks (tests/data/two_on_one): the resultant
/// is on both, named "a+b", and carries the whole load (1e6 Pa on the two
/// 1 m tops). Before, `on_body` named the first row's body only ("a"),
/// beside a force that was both blocks'.
#[test]
fn a_slave_curve_over_two_bodies_names_both() {
    let path = root().join("tests/data/two_on_one/two_on_one.toml");
    let prep = run::prepare(&path, false).unwrap_or_else(|e| panic!("{e}"));
    let (method, opts) = run::options(&prep.problem, &SolverSection::default()).unwrap();
    let res = run::solve(&prep, method, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(res.status.converged() && res.kkt.within(1e-6));
    let step = post::step_output(&prep.model, &prep.problem.file.materials, &res, 1.0);
    let f = forces::compute(
        &prep.model,
        &prep.problem.file.materials,
        &step.displacement,
        &step.multipliers,
        &step.contact_pressure,
    );
    assert_eq!(f.interfaces.len(), 1);
    let it = &f.interfaces[0];
    assert_eq!(it.on_body, "a+b", "{}", it.name);
    let fy = it.resultant.force[1];
    assert!((fy - 2.0e6).abs() <= 1e-8 * 2.0e6, "F_y = {fy:e}");
}

/// Every load step of the model `toml` (next to a copy of `msh`) through
/// the library: the last step's model and its forces, friction included.
fn solved_with_friction(
    dir: &std::path::Path,
    msh: &std::path::Path,
    toml: &str,
) -> (
    run::Prepared,
    Option<signorini::fem::Model>,
    forces::Forces,
    Vec<f64>,
    Vec<f64>,
) {
    let mname = msh.file_name().unwrap().to_str().unwrap();
    std::fs::copy(msh, dir.join(mname)).unwrap();
    let path = dir.join("model.toml");
    std::fs::write(&path, toml.replace("MESH", mname)).unwrap();
    let prep = run::prepare(&path, false).unwrap_or_else(|e| panic!("{e}"));
    let (m, opts) = run::options(&prep.problem, &SolverSection::default()).unwrap();
    let out = run::Run::new(&prep, m, &opts)
        .solve(&mut [], None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(out.certified);
    let last = out.last.unwrap();
    let model = last.model.as_ref().unwrap_or(&prep.model);
    let (step, mut f) =
        post::step_output_with_forces(model, &prep.problem.file.materials, &last.result, 1.0);
    f.point_reaction = step.reaction;
    let lt = post::friction::friction_output(model, &last.result)
        .expect("friction")
        .lambda_t;
    (prep, last.model, f, lt, step.multipliers)
}

/// meshes/hertz.msh with Coulomb friction, both bodies held by their far
/// sides and the cylinder's top moved down and sideways: rows of the
/// curved slave close initial gaps and carry λ_t.
const HERTZ_FRICTION: &str = r#"[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.cylinder]
E = 2.0e11
nu = 0.3
[materials.block]
E = 1.0e11
nu = 0.25
[[dirichlet]]
on = "cyl_top"
u = [0.002, -0.015]
[[slip]]
on = "block_axis"
[[dirichlet]]
on = "block_bottom"
u = [0.0, 0.0]
[[contact]]
slave = "cyl_contact"
master = "block_top"
discretization = "nts"
friction = 0.3
[solver]
method = "ssn"
"#;

/// Issue 35: with friction across initial gaps the moment of loads +
/// reactions was −Σλ_t·g0, not 0. The contact forces of a row sum to zero
/// but act an initial gap apart; the reported couple closes the balance to
/// 1e-8, and without it the balance misses by far more.
#[test]
fn friction_across_initial_gaps_makes_a_couple_that_closes_the_moment_balance() {
    let bumps = root().join("tests/data/bumps/bumps.toml");
    let bumps = std::fs::read_to_string(bumps)
        .unwrap()
        .replace("bumps.msh", "MESH")
        .replace(
            "master = \"found_top\"",
            "master = \"found_top\"\ndiscretization = \"nts\"",
        );
    for (name, msh, toml) in [
        (
            "hertz",
            root().join("meshes/hertz.msh"),
            HERTZ_FRICTION.to_string(),
        ),
        ("bumps", root().join("tests/data/bumps/bumps.msh"), bumps),
    ] {
        let d = tempfile::tempdir().unwrap();
        let (prep, model, f, lt, _) = solved_with_friction(d.path(), &msh, &toml);
        let model = model.as_ref().unwrap_or(&prep.model);
        let t = &model.topo;
        let scale = scales(
            &t.points,
            [&model.loads[..], &f.point_reaction[..]].into_iter(),
        );
        let open = f.loads.moment + f.reactions.moment;
        let closed = open + f.couple;
        eprintln!(
            "{name}: loads + reactions M = {open:.4e}, couple {:.4e}, with it {closed:.3e} (scale {:.3e})",
            f.couple, scale[1]
        );
        assert!(closed.abs() <= 1e-8 * scale[1], "{name}: {closed:e}");
        assert!(open.abs() > 1e-6 * scale[1], "{name}: no couple to test");
        // Node-to-segment rows (asked for by name in both models): the
        // slave point is its master point plus g0·n, so the couple is
        // Σ λ_t·g0 (the normal forces are collinear).
        let want: f64 = t.contact.iter().zip(&lt).map(|(r, l)| l * r.gap0).sum();
        assert!(
            (f.couple - want).abs() <= 1e-9 * want.abs(),
            "{name}: couple {} vs Σλ_t·g0 {want}",
            f.couple
        );
        let by_iface: f64 = f.interfaces.iter().map(|i| i.couple).sum();
        assert_eq!(by_iface, f.couple);
    }
}

/// The extent of each interface against a direct reading of x-monotone
/// interfaces: rows sorted by x, the first and last active, the arc length
/// between them over the sorted points, runs of active rows as zones, and
/// the mean pressure Σλ/Σ tributary length.
#[test]
fn the_extent_and_mean_pressure_of_each_interface() {
    let d = tempfile::tempdir().unwrap();
    let bumps = std::fs::read_to_string(root().join("tests/data/bumps/bumps.toml"))
        .unwrap()
        .replace("bumps.msh", "MESH");
    let (prep, model, f, _, lambda) =
        solved_with_friction(d.path(), &root().join("tests/data/bumps/bumps.msh"), &bumps);
    let mut cases = vec![("bumps".to_string(), prep, model, f, lambda, Some(2))];
    for name in ["hertz", "two_blocks_eccentric", "cantilevers"] {
        let path = root().join("meshes").join(format!("{name}.toml"));
        let prep = run::prepare(&path, false).unwrap_or_else(|e| panic!("{e}"));
        let (method, opts) = run::options(&prep.problem, &SolverSection::default()).unwrap();
        let res = run::solve(&prep, method, &opts).unwrap_or_else(|e| panic!("{e}"));
        let (step, f) =
            post::step_output_with_forces(&prep.model, &prep.problem.file.materials, &res, 1.0);
        // cantilevers: its zone count is the sorted reading only.
        let z = (name != "cantilevers").then_some(1);
        cases.push((name.to_string(), prep, None, f, step.multipliers, z));
    }
    for (name, prep, model, f, lambda, zones) in &cases {
        let model = model.as_ref().unwrap_or(&prep.model);
        let t = &model.topo;
        for (i, it) in f.interfaces.iter().enumerate() {
            let mut rows: Vec<(f64, usize)> = t
                .contact
                .iter()
                .enumerate()
                .filter(|(_, r)| r.interface == i as u32)
                .map(|(k, r)| (t.points[r.first][0], k))
                .collect();
            rows.sort_by(|a, b| a.0.total_cmp(&b.0));
            let ext = it.extent.expect("an active row");
            let on: Vec<bool> = rows.iter().map(|&(_, k)| lambda[k] > 0.0).collect();
            let first = on.iter().position(|&a| a).unwrap();
            let last = on.iter().rposition(|&a| a).unwrap();
            let x = |j: usize| t.points[t.contact[rows[j].1].first];
            let (mut len, mut act, mut runs) = (0.0, 0.0, 1);
            for j in first..last {
                let dd = (x(j + 1)[0] - x(j)[0]).hypot(x(j + 1)[1] - x(j)[1]);
                len += dd;
                if on[j] && on[j + 1] {
                    act += dd;
                }
                if !on[j] && on[j + 1] {
                    runs += 1;
                }
            }
            let ends = [x(first), x(last)];
            let same = (ends[0] == ext.start && ends[1] == ext.end)
                || (ends[1] == ext.start && ends[0] == ext.end);
            assert!(same, "{name}: {ext:?} vs {ends:?}");
            assert!(
                (ext.length - len).abs() <= 1e-12 * len.max(1.0),
                "{name}: {ext:?} {len}"
            );
            assert!(
                (ext.active_length - act).abs() <= 1e-12 * len.max(1.0),
                "{name}: {ext:?} {act}"
            );
            assert_eq!(ext.zones, runs, "{name}");
            if let Some(z) = zones {
                assert_eq!(ext.zones, *z, "{name}: {ext:?}");
            }
            let (mut sl, mut st) = (0.0, 0.0);
            for &(_, k) in &rows {
                if lambda[k] > 0.0 {
                    sl += lambda[k];
                    st += t.contact[k].trib;
                }
            }
            let want = sl / (model.t_eff() * st);
            assert!(
                (it.mean_pressure - want).abs() <= 1e-6 * want,
                "{name}: mean {} vs {want}",
                it.mean_pressure
            );
            assert!(it.mean_pressure < it.max_pressure, "{name}");
        }
    }
}

/// The JSON keys of docs/problem-format.md §7 on tests/data/bumps: per
/// interface `extent` (two zones, the union's ends on the two bumps'
/// outer slopes), `mean_pressure` and `couple`; in `contact` the total
/// couple, which closes the moment balance of loads + reactions.
#[test]
fn the_json_reports_extent_mean_pressure_and_couple() {
    let d = tempfile::tempdir().unwrap();
    for f in ["bumps.toml", "bumps.msh"] {
        std::fs::copy(root().join("tests/data/bumps").join(f), d.path().join(f)).unwrap();
    }
    let out = d.path().join("out");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args(["solve", "--quiet", "--out"])
        .arg(&out)
        .arg(d.path().join("bumps.toml"))
        .status()
        .unwrap();
    assert!(st.success());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bumps.json")).unwrap()).unwrap();
    let c = &s["contact"];
    let it = &c["interfaces"]["pad_bottom->found_top"];
    let e = &it["extent"];
    assert_eq!(e["zones"].as_u64(), Some(2), "{e}");
    let (x0, x1) = (
        e["start"][0].as_f64().unwrap(),
        e["end"][0].as_f64().unwrap(),
    );
    // Both flats (|x| in [0.6, 0.9], y = 0) are in contact, the middle is not.
    assert!(x0.min(x1) < -0.9 && x0.max(x1) > 0.9, "{e}");
    let (len, act) = (
        e["length"].as_f64().unwrap(),
        e["active_length"].as_f64().unwrap(),
    );
    assert!(len > 1.8 && act >= 0.6 && act < len - 1.0, "{e}");
    let (mean, max) = (
        it["mean_pressure"].as_f64().unwrap(),
        it["max_pressure"].as_f64().unwrap(),
    );
    assert!(mean > 0.0 && mean < max, "{mean} {max}");
    assert_eq!(c["mean_pressure"].as_f64(), Some(mean));
    assert_eq!(c["couple"].as_f64(), it["couple"].as_f64());
    let m = s["loads"]["moment"].as_f64().unwrap()
        + s["reactions"]
            .as_object()
            .unwrap()
            .values()
            .map(|r| r["moment"].as_f64().unwrap())
            .sum::<f64>();
    let couple = c["couple"].as_f64().unwrap();
    assert!(couple.abs() > 1e2, "{couple}");
    assert!((m + couple).abs() <= 1e-6 * couple.abs(), "{m} + {couple}");
}
