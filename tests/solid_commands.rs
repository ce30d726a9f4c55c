//! `export`, `pack` and a frictional `compare` on 3D models, through the
//! binary: the stacked cubes of tests/data/solid_contact meshed apart
//! (mortar rows), a soft cube (E = 2·10⁷ Pa, ν = 0.45) on a steel one,
//! Coulomb μ = 0.3 on the interface, the planes x = 0 and y = 0 slip
//! planes, a pressure and a shear on top in three load steps.
//!
//! Required:
//! * `export --solution` of a 3D model writes the QP and signorini's answer,
//!   and what the files hold proves itself: Cx − d + Aᵀλ + Tᵀλ_t = 0 with
//!   two rows of T per contact row, the disc law ‖λ_t,i‖ ≤ μλᵢ, slip only at
//!   the bound and along the force, the objective of meta.json, C R = 0;
//! * `pack` of a 3D split checkpoint gives one file that `--restart`
//!   continues, into another directory, to the uninterrupted run's answer
//!   bit for bit;
//! * `compare` follows the frictional load path for every variant, and the
//!   dual method agrees with ssn, λ_t included: a tangent held by a plane
//!   of symmetry carries λ_t = 0 whatever the method left there;
//! * `compare` without one certified row exits 3.

mod common;

use serde_json::Value;
use signorini::io::mtx;
use signorini::linalg::sparse::{dot, norm, norm_inf};
use std::path::{Path, PathBuf};

/// The soft cube on the steel one, both slipping on the planes x = 0 and
/// y = 0 (so the rows there hold a tangent); `steps` follows the model.
fn stack(dir: &Path, steps: &str) -> PathBuf {
    let tail = format!("\n[output]\nprobes = {{ corner = [1.0, 1.0, 2.0] }}\n{steps}");
    let text = common::soft_cube_toml(["x0", "y0"], [2.0e5, 1.0e5], &tail);
    let path = dir.join("stack.toml");
    std::fs::write(&path, text).unwrap();
    path
}

const STEPS: &str = "
[[steps]]
factor = 0.3
[[steps]]
factor = 0.6
[[steps]]
factor = 1.0
";

fn signorini(args: &[&str]) -> (i32, String) {
    common::run(args)
}

/// `signorini solve TOML -q FLAGS… --out OUT`, which must exit 0.
fn solve_ok(toml: &str, out: &Path, flags: &[&str]) {
    let mut args = vec!["solve", toml, "-q"];
    args.extend_from_slice(flags);
    args.extend(["--out", out.to_str().unwrap()]);
    let (code, text) = signorini(&args);
    assert_eq!(code, 0, "{text}");
}

/// `signorini export --qp QP TOML --solution`, which must exit 0.
fn export_ok(toml: &Path, qp: &Path) {
    let (code, text) = signorini(&[
        "export",
        "--qp",
        qp.to_str().unwrap(),
        toml.to_str().unwrap(),
        "--solution",
    ]);
    assert_eq!(code, 0, "{text}");
}

#[test]
fn a_3d_frictional_export_proves_itself() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack(tmp.path(), "");
    let d = tmp.path().join("qp");
    export_ok(&toml, &d);
    let meta: Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("meta.json")).unwrap()).unwrap();
    assert_eq!(meta["dim"], 3);
    assert_eq!(meta["friction"], "coulomb");
    assert_eq!(meta["tangential_rows"], 2);
    assert!(meta["tetrahedra"].as_u64().unwrap() > 0, "{meta}");
    assert!(meta.get("triangles").is_none(), "{meta}");
    assert_eq!(meta["certified"], true);
    let c = mtx::read_sparse(&d.join("C.mtx")).unwrap();
    let a = mtx::read_sparse(&d.join("A.mtx")).unwrap();
    let t = mtx::read_sparse(&d.join("T.mtx")).unwrap();
    let dv = mtx::read_vector(&d.join("d.mtx")).unwrap();
    let g = mtx::read_vector(&d.join("g.mtx")).unwrap();
    let t0 = mtx::read_vector(&d.join("t0.mtx")).unwrap();
    let mu = mtx::read_vector(&d.join("mu.mtx")).unwrap();
    let x = mtx::read_vector(&d.join("x.mtx")).unwrap();
    let lam = mtx::read_vector(&d.join("lambda.mtx")).unwrap();
    let lt = mtx::read_vector(&d.join("lambda_t.mtx")).unwrap();
    let (n, m) = (dv.len(), lam.len());
    assert_eq!(meta["n"].as_u64().unwrap() as usize, n);
    assert_eq!(meta["m"].as_u64().unwrap() as usize, m);
    assert!(m > 0);
    assert_eq!((t.nrows, t.ncols), (2 * m, n));
    assert_eq!(
        (t0.len(), lt.len(), mu.len(), g.len()),
        (2 * m, 2 * m, m, m)
    );
    // Stationarity of what was written; without λ_t the shear is unbalanced.
    let cx = c.mul(&x);
    let (at, tt) = (a.mul_t(&lam), t.mul_t(&lt));
    let scale = norm(&dv).max(norm(&cx));
    let r: Vec<f64> = (0..n).map(|i| cx[i] + at[i] + tt[i] - dv[i]).collect();
    assert!(
        norm(&r) <= 1e-8 * scale,
        "stationarity {:e}",
        norm(&r) / scale
    );
    let r0: Vec<f64> = (0..n).map(|i| cx[i] + at[i] - dv[i]).collect();
    assert!(norm(&r0) > 1e-3 * scale, "λ_t carries nothing");
    // Contact: Ax ≤ g, λ ≥ 0, complementarity.
    let ax = a.mul(&x);
    let (xs, ls) = (norm_inf(&x), norm_inf(&lam));
    for i in 0..m {
        assert!(ax[i] - g[i] <= 1e-8 * xs, "row {i} penetrates");
        assert!(lam[i] >= 0.0);
        assert!((lam[i] * (ax[i] - g[i])).abs() <= 1e-8 * ls * xs);
    }
    // The disc law per contact row: ‖(λ_t,2i, λ_t,2i+1)‖ ≤ μᵢλᵢ, and where
    // the row slips the force is at the bound along the slip v (the QP's
    // sign: λ_t = s v/‖v‖).
    let v: Vec<f64> = t.mul(&x).iter().zip(&t0).map(|(a, b)| a - b).collect();
    let s: Vec<f64> = mu.iter().zip(&lam).map(|(m, l)| m * l.max(0.0)).collect();
    let smax = norm_inf(&s);
    let mut slipping = 0;
    for i in 0..m {
        let (f, w) = ([lt[2 * i], lt[2 * i + 1]], [v[2 * i], v[2 * i + 1]]);
        let (fn_, wn) = (f[0].hypot(f[1]), w[0].hypot(w[1]));
        assert!(
            fn_ <= s[i] + 1e-8 * smax,
            "row {i}: |λ_t| {fn_:e} > s {:e}",
            s[i]
        );
        if wn > 1e-9 * xs {
            slipping += 1;
            for k in 0..2 {
                assert!(
                    (f[k] - s[i] * w[k] / wn).abs() <= 1e-6 * smax,
                    "row {i} slips below its bound or across its force: {f:?} against {:?}",
                    [s[i] * w[0] / wn, s[i] * w[1] / wn]
                );
            }
        }
    }
    assert!(slipping > 0, "no row slips: the test shows nothing");
    // The objective of meta.json: ½xᵀCx − dᵀx + Σ sᵢ‖vᵢ‖.
    let j = 0.5 * dot(&x, &cx) - dot(&x, &dv)
        + (0..m)
            .map(|i| s[i] * v[2 * i].hypot(v[2 * i + 1]))
            .sum::<f64>();
    let jm = meta["energy"].as_f64().unwrap();
    assert!((j - jm).abs() <= 1e-10 * jm.abs(), "{j} vs {jm}");
    // The kernel: the upper cube's motion along z, held by the contact alone.
    let (rn, k, rv) = common::read_array(&d.join("R.mtx"));
    assert_eq!((rn, k), (n, 1));
    assert!(norm(&c.mul(&rv)) <= 1e-8 * norm_inf(&c.diag()) * norm(&rv));
}

/// A packed 3D checkpoint, moved alone, is continued by `--restart` in a
/// new directory to the uninterrupted run's answer bit for bit, and the
/// packed steps' VTU pairs are written again from it.
#[test]
fn a_packed_3d_checkpoint_is_continued_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack(tmp.path(), STEPS);
    let toml = toml.to_str().unwrap();
    let dir = |n: &str| tmp.path().join(n);
    let full = dir("full");
    solve_ok(toml, &full, &[]);
    let part = dir("part");
    solve_ok(toml, &part, &["--max-steps", "2"]);
    let alone = dir("alone");
    std::fs::create_dir(&alone).unwrap();
    let packed = alone.join("packed.h5");
    let (code, text) = signorini(&[
        "pack",
        part.join("stack.h5").to_str().unwrap(),
        "-o",
        packed.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("packed 2 step(s)"), "{text}");
    std::fs::remove_dir_all(&part).unwrap();
    // One file: every step readable without the split files.
    let ck =
        signorini::io::hdf5::read_solid_checkpoint(&packed, signorini::io::hdf5::SolidSteps::All)
            .unwrap();
    assert_eq!(ck.step_indices, vec![1, 2]);
    let again = dir("again");
    solve_ok(toml, &again, &["--restart", packed.to_str().unwrap()]);
    for f in [
        "stack_mesh.h5",
        "stack_0001.h5",
        "stack_0002.h5",
        "stack_0003.h5",
    ] {
        assert!(again.join(f).is_file(), "no {f}");
    }
    let read = |d: &Path| {
        signorini::io::hdf5::read_solid_checkpoint(
            &d.join("stack.h5"),
            signorini::io::hdf5::SolidSteps::All,
        )
        .unwrap()
    };
    let (want, got) = (read(&full), read(&again));
    assert_eq!(got.step_indices, vec![1, 2, 3]);
    for (a, b) in want.steps.iter().zip(&got.steps) {
        let bits = |u: &[[f64; 3]]| u.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.displacement), bits(&b.displacement));
    }
    // The packed steps' VTU pairs are written again from the checkpoint:
    // the displacements and contact pressures of the uninterrupted run's.
    for k in 1..=2 {
        for (f, field) in [
            (format!("stack_{k:04}.vtu"), "displacement"),
            (format!("stack_{k:04}_contact.vtu"), "contact_pressure"),
        ] {
            let a = signorini::io::vtu::read_vtu_arrays(&full.join(&f)).unwrap();
            let b = signorini::io::vtu::read_vtu_arrays(&again.join(&f)).unwrap();
            let (ua, ub) = (a.point_array(field), b.point_array(field));
            assert!(ua.is_some() && ua == ub, "{f}: {field} differs");
        }
    }
    let pvd = std::fs::read_to_string(again.join("stack.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 6, "{pvd}");
}

/// `compare` on the frictional steps: each variant follows the path, and
/// mprgp agrees with ssn on x, λ and λ_t (before, every variant failed
/// with "not in yet"; and mprgp's λ_t on the held tangents of the rows on
/// the planes x = 0, y = 0 was arbitrary: rel_diff_lambda_t 4.8 %).
#[test]
fn a_3d_frictional_compare_follows_the_path_and_agrees() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack(tmp.path(), STEPS);
    let json = tmp.path().join("c.json");
    let (code, text) = signorini(&[
        "compare",
        toml.to_str().unwrap(),
        "--methods",
        "ssn,mprgp",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{text}");
    let t: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(t["steps"]["path"], true, "{t}");
    assert_eq!(t["steps"]["compared"], 3);
    let rows = t["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        assert!(r.get("error").is_none(), "{r}");
        assert_eq!(r["certified"], true, "{r}");
        assert_eq!(r["agrees"], true, "{r}");
        let d = r["rel_diff_lambda_t"].as_f64().unwrap();
        assert!(d <= 1e-6, "{}: λ_t {d:e} off", r["method"]);
    }
}

/// No certified row: nothing to compare against, exit 3.
#[test]
fn a_compare_without_a_certified_row_exits_3() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack(tmp.path(), "");
    let (code, text) = signorini(&[
        "compare",
        toml.to_str().unwrap(),
        "--methods",
        "mprgp",
        "--max-iter",
        "3",
    ]);
    assert_eq!(code, 3, "{text}");
    assert!(
        text.contains("no variant gave a certified answer"),
        "{text}"
    );
}

/// A 3D problem with `[[steps]]` is exported as written, its loads at
/// factor 1 and no step applied, as in 2D (docs/guide.md §10): the same
/// d and x as the problem without its steps (step 1, at factor 0.3, was
/// exported before).
#[test]
fn a_3d_export_with_steps_is_the_problem_as_written() {
    let tmp = tempfile::tempdir().unwrap();
    let export = |name: &str, steps: &str| {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        let toml = stack(&dir, steps);
        let qp = dir.join("qp");
        export_ok(&toml, &qp);
        let read = |f: &str| mtx::read_vector(&qp.join(f)).unwrap();
        (read("d.mtx"), read("x.mtx"))
    };
    let (d_steps, x_steps) = export("steps", STEPS);
    let (d_one, x_one) = export("one", "");
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&d_steps), bits(&d_one));
    assert_eq!(bits(&x_steps), bits(&x_one));
}

/// A frictional body pulled off its support is refused as unbounded and
/// named as pulled away, not as sliding: friction holds nothing on an open
/// row (before, every frictional refusal said "slides … its friction
/// cannot hold the loads").
#[test]
fn a_frictional_cube_pulled_off_is_named_as_pulled_away() {
    let tmp = tempfile::tempdir().unwrap();
    let text =
        common::soft_cube_toml(["x0", "y0"], [2.0e5, 1.0e5], "").replace("-1.0e6]", "1.0e6]");
    assert!(
        text.contains(", 1.0e6]") && !text.contains("-1.0e6"),
        "{text}"
    );
    let toml = tmp.path().join("pull.toml");
    std::fs::write(&toml, text).unwrap();
    let out = tmp.path().join("out");
    let (code, said) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{said}");
    assert!(
        said.contains("unbounded") && said.contains("\"upper\""),
        "{said}"
    );
    assert!(said.contains("pulled away"), "{said}");
    assert!(!said.contains("slides"), "{said}");
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none());
}

/// A 3D restart from a split checkpoint in another directory brings the
/// VTU pairs that run left beside it, as 2D does, and its `.pvd` lists
/// every step's pair (before, it listed only the steps it solved).
#[test]
fn a_3d_restart_into_another_directory_brings_the_pairs() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack(tmp.path(), STEPS);
    let toml = toml.to_str().unwrap();
    let (first, second) = (tmp.path().join("first"), tmp.path().join("second"));
    solve_ok(toml, &first, &["--max-steps", "2"]);
    let h5 = first.join("stack.h5");
    solve_ok(toml, &second, &["--restart", h5.to_str().unwrap()]);
    for k in 1..=2 {
        for f in [
            format!("stack_{k:04}.vtu"),
            format!("stack_{k:04}_contact.vtu"),
        ] {
            let a = std::fs::read(first.join(&f)).unwrap();
            let b = std::fs::read(second.join(&f)).unwrap_or_default();
            assert!(a == b, "{f}: not copied as it was");
        }
    }
    let pvd = std::fs::read_to_string(second.join("stack.pvd")).unwrap();
    for k in 1..=3 {
        assert!(pvd.contains(&format!("file=\"stack_{k:04}.vtu\"")), "{pvd}");
        assert!(
            pvd.contains(&format!("file=\"stack_{k:04}_contact.vtu\"")),
            "{pvd}"
        );
    }
}

/// `pack` of a 3D split checkpoint missing a step file: exit 2 naming the
/// file, nothing written (every step is read and checked before the copy).
#[test]
fn a_3d_pack_with_a_missing_step_file_names_it() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack(tmp.path(), STEPS);
    let part = tmp.path().join("part");
    solve_ok(toml.to_str().unwrap(), &part, &["--max-steps", "2"]);
    std::fs::remove_file(part.join("stack_0002.h5")).unwrap();
    let packed = tmp.path().join("packed.h5");
    let (code, text) = signorini(&[
        "pack",
        part.join("stack.h5").to_str().unwrap(),
        "-o",
        packed.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("stack_0002.h5"), "{text}");
    assert!(!packed.exists());
}
