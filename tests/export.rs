//! `signorini export --qp`: the files read back (our Matrix Market reader)
//! give the same QP, the exported solution satisfies its KKT conditions, the
//! kernel is the kernel; `signorini limit` solves C x = d.

use signorini::io::mtx;
use signorini::linalg::sparse::{dot, norm, norm_inf};
use signorini::qp::SolverSection;
use signorini::run::{self, ExportSpec, LimitSpec};
use std::path::{Path, PathBuf};

mod common;

use common::read_array;

/// Runs `signorini ARGS` from the crate's root (the paths below are relative).
fn signorini(args: &[&str]) -> (i32, String, String) {
    common::signorini_in(env!("CARGO_MANIFEST_DIR"), args)
}

fn check(toml: &str, floating: bool) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("qp");
    let ds = d.to_str().unwrap();
    let (code, out, err) =
        signorini(&["export", "--qp", ds, toml, "--solution", "--method", "ssn"]);
    assert_eq!(code, 0, "{out}{err}");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("meta.json")).unwrap()).unwrap();
    let c = mtx::read_sparse(&d.join("C.mtx")).unwrap();
    let a = mtx::read_sparse(&d.join("A.mtx")).unwrap();
    let dv = mtx::read_vector(&d.join("d.mtx")).unwrap();
    let g = mtx::read_vector(&d.join("g.mtx")).unwrap();
    let x = mtx::read_vector(&d.join("x.mtx")).unwrap();
    let lam = mtx::read_vector(&d.join("lambda.mtx")).unwrap();
    let (n, m) = (dv.len(), g.len());
    assert_eq!(meta["format"], "signorini-qp");
    assert_eq!(meta["n"].as_u64().unwrap() as usize, n);
    assert_eq!(meta["m"].as_u64().unwrap() as usize, m);
    assert_eq!((c.nrows, c.ncols, a.nrows, a.ncols), (n, n, m, n));
    assert!(m > 0 && x.len() == n && lam.len() == m);
    // C symmetric, as written (lower triangle expanded).
    assert_eq!(c, c.transpose());
    // The optimal value in meta.json is ½xᵀCx − dᵀx of the files.
    let j = 0.5 * dot(&x, &c.mul(&x)) - dot(&x, &dv);
    let jm = meta["energy"].as_f64().unwrap();
    assert!((j - jm).abs() <= 1e-10 * jm.abs(), "{j} vs {jm}");
    // KKT of the exported problem: Cx − d + Aᵀλ = 0, Ax ≤ g, λ ≥ 0, λ(Ax − g) = 0.
    let mut r = c.mul(&x);
    let at = a.mul_t(&lam);
    for i in 0..n {
        r[i] += at[i] - dv[i];
    }
    let scale = norm(&dv).max(norm(&c.mul(&x)));
    assert!(
        norm(&r) <= 1e-6 * scale,
        "stationarity {}",
        norm(&r) / scale
    );
    let ax = a.mul(&x);
    let xs = norm_inf(&x);
    for i in 0..m {
        assert!(ax[i] - g[i] <= 1e-8 * xs, "row {i} violated");
        assert!(lam[i] >= 0.0);
        assert!((lam[i] * (ax[i] - g[i])).abs() <= 1e-8 * norm_inf(&lam) * xs);
    }
    // Kernel: one column per rigid mode, C R = 0.
    let (rn, k, rv) = read_array(&d.join("R.mtx"));
    assert_eq!(rn, n);
    assert_eq!(k, meta["kernel_dim"].as_u64().unwrap() as usize);
    assert_eq!(k > 0, floating);
    let cmax = norm_inf(&c.diag());
    for col in rv.chunks(n) {
        assert!(norm(&c.mul(col)) <= 1e-8 * cmax * norm(col));
    }
}

#[test]
fn export_three_bodies_floating_wedge() {
    check("meshes/three_bodies.toml", true);
}

#[test]
fn export_hertz_nonmatching() {
    check("meshes/hertz.toml", true);
}

#[test]
fn export_cantilevers_coercive() {
    check("meshes/cantilevers.toml", false);
}

#[test]
fn export_bad_input_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("qp");
    let (code, _, err) = signorini(&[
        "export",
        "--qp",
        d.to_str().unwrap(),
        "meshes/nonexistent.toml",
    ]);
    assert_eq!(code, 2);
    assert!(err.starts_with("error:"), "{err}");
    assert!(!d.exists());
    // --qp naming a file: refused before the solve, the file left as it was.
    std::fs::write(&d, "mine").unwrap();
    let (code, _, err) = signorini(&[
        "export",
        "--qp",
        d.to_str().unwrap(),
        "meshes/column.toml",
        "--solution",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is not a directory"), "{err}");
    assert_eq!(std::fs::read_to_string(&d).unwrap(), "mine");
}

#[test]
fn limit_solves_c() {
    let (code, out, err) = signorini(&["limit", "meshes/column.toml", "--repeat", "2"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert!(v["relative_residual"].as_f64().unwrap() < 1e-9);
    assert!(v["t_factor"].as_f64().unwrap() > 0.0);
    assert_eq!(v["repeat"], 2);
}

/// meshes/two_blocks with the upper block held by the contact only, a shear
/// traction on top and the friction `law` on the interface.
fn sheared_blocks(dir: &Path, law: &str) -> PathBuf {
    std::fs::copy("meshes/two_blocks.msh", dir.join("two_blocks.msh")).unwrap();
    let p = dir.join("sheared.toml");
    std::fs::write(
        &p,
        format!(
            r#"[mesh]
file = "two_blocks.msh"
[model]
plane = "strain"
[materials.lower]
E = 2.0e9
nu = 0.25
[materials.upper]
E = 2.0e9
nu = 0.25
[[dirichlet]]
on = "bottom"
u = [0.0, 0.0]
[[slip]]
on = "left_lower"
[[slip]]
on = "right_lower"
[[traction]]
on = "top"
p = [1.0e5, -1.0e6]
[[contact]]
on = "interface"
{law}
"#
        ),
    )
    .unwrap();
    p
}

/// Issue 33 item 4: with friction the export holds the tangential rows, the
/// offsets, the bounds and λ_t; the files read back satisfy
/// Cx − d + Aᵀλ + Tᵀλ_t = 0 and the friction law, and meta.json's residuals
/// are those of the files.
#[test]
fn frictional_export_holds_the_tangential_rows() {
    for (law, bound) in [("friction = 0.3", "mu.mtx"), ("tresca = 3.0e5", "s.mtx")] {
        let dir = tempfile::tempdir().unwrap();
        let toml = sheared_blocks(dir.path(), law);
        let prep = run::prepare(&toml, false).unwrap();
        let d = dir.path().join("qp");
        let spec = ExportSpec {
            dir: d.clone(),
            solution: true,
            solver: SolverSection {
                method: Some("ssn".parse().unwrap()),
                ..Default::default()
            },
        };
        let rep = run::export(&prep, &spec).unwrap_or_else(|e| panic!("{law}: {e}"));
        assert_eq!(rep.files.last().map(String::as_str), Some("meta.json"));
        for f in ["T.mtx", "t0.mtx", bound, "lambda_t.mtx"] {
            assert!(
                rep.files.iter().any(|n| n == f),
                "{law}: {f} in {:?}",
                rep.files
            );
        }
        let meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("meta.json")).unwrap()).unwrap();
        assert_eq!(meta["files"]["T"], "T.mtx");
        assert_eq!(meta["files"][bound.trim_end_matches(".mtx")], bound);
        assert_eq!(meta["friction"], rep.friction.unwrap());
        let c = mtx::read_sparse(&d.join("C.mtx")).unwrap();
        let a = mtx::read_sparse(&d.join("A.mtx")).unwrap();
        let t = mtx::read_sparse(&d.join("T.mtx")).unwrap();
        let dv = mtx::read_vector(&d.join("d.mtx")).unwrap();
        let t0 = mtx::read_vector(&d.join("t0.mtx")).unwrap();
        let bnd = mtx::read_vector(&d.join(bound)).unwrap();
        let x = mtx::read_vector(&d.join("x.mtx")).unwrap();
        let lam = mtx::read_vector(&d.join("lambda.mtx")).unwrap();
        let lt = mtx::read_vector(&d.join("lambda_t.mtx")).unwrap();
        let (n, m) = (dv.len(), lam.len());
        assert_eq!((t.nrows, t.ncols), (m, n));
        assert_eq!((t0.len(), bnd.len(), lt.len()), (m, m, m));
        assert!(
            lt.iter().any(|v| v.abs() > 0.0),
            "{law}: no tangential force"
        );
        // Stationarity of what was written.
        let cx = c.mul(&x);
        let mut r = cx.clone();
        let (at, tt) = (a.mul_t(&lam), t.mul_t(&lt));
        for i in 0..n {
            r[i] += at[i] + tt[i] - dv[i];
        }
        let scale = norm(&dv).max(norm(&cx));
        let st = norm(&r) / scale;
        assert!(st <= 1e-8, "{law}: stationarity {st:e}");
        // meta.json's stationarity is that of the files (the same formula).
        let ms = meta["kkt"]["stationarity"].as_f64().unwrap();
        assert!(
            (ms - st).abs() <= 1e-3 * st.max(1e-300) + 1e-15,
            "{law}: meta {ms:e}, files {st:e}"
        );
        assert!(meta["kkt"]["friction"].as_f64().unwrap() <= 1e-8);
        // Without the tangential forces the balance fails: they carry the shear.
        let mut r0 = cx;
        for i in 0..n {
            r0[i] += at[i] - dv[i];
        }
        assert!(norm(&r0) / scale > 1e-3, "{law}: λ_t carries nothing");
        // The friction law: |λ_t| ≤ s, s = μλ for Coulomb; slip only at the bound.
        let s: Vec<f64> = if bound == "mu.mtx" {
            bnd.iter()
                .zip(&lam)
                .map(|(mu, l)| mu * l.max(0.0))
                .collect()
        } else {
            bnd.clone()
        };
        let smax = norm_inf(&s);
        let v: Vec<f64> = t.mul(&x).iter().zip(&t0).map(|(a, b)| a - b).collect();
        let vmax = norm_inf(&v).max(f64::MIN_POSITIVE);
        for i in 0..m {
            assert!(lt[i].abs() <= s[i] + 1e-8 * smax, "{law}: row {i}");
            if v[i].abs() > 1e-6 * vmax {
                assert!(
                    (lt[i] - s[i] * v[i].signum()).abs() <= 1e-6 * smax,
                    "{law}: row {i} slips below its bound"
                );
            }
        }
        // The objective of meta.json: ½xᵀCx − dᵀx + Σ sᵢ|vᵢ|.
        let j = 0.5 * dot(&x, &c.mul(&x)) - dot(&x, &dv)
            + s.iter().zip(&v).map(|(s, v)| s * v.abs()).sum::<f64>();
        let jm = meta["energy"].as_f64().unwrap();
        assert!((j - jm).abs() <= 1e-10 * jm.abs(), "{law}: {j} vs {jm}");
    }
}

/// A frictionless export has no friction keys or files (as before).
#[test]
fn frictionless_export_writes_no_tangential_files() {
    let dir = tempfile::tempdir().unwrap();
    let prep = run::prepare(Path::new("meshes/two_blocks.toml"), false).unwrap();
    let d = dir.path().join("qp");
    let spec = ExportSpec {
        dir: d.clone(),
        solution: false,
        solver: SolverSection::default(),
    };
    let rep = run::export(&prep, &spec).unwrap();
    assert_eq!(
        rep.files,
        ["C.mtx", "A.mtx", "d.mtx", "g.mtx", "R.mtx", "meta.json"]
    );
    assert!(rep.friction.is_none() && rep.solution.is_none());
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("meta.json")).unwrap()).unwrap();
    assert!(meta.get("friction").is_none() && meta["files"].get("T").is_none());
    assert!(meta["kkt"].is_null() && meta["files"]["x"].is_null());
    assert!(!d.join("T.mtx").exists());
}

#[test]
fn limit_through_the_library() {
    let prep = run::prepare(Path::new("meshes/column.toml"), false).unwrap();
    let spec = LimitSpec {
        repeat: 3,
        ..Default::default()
    };
    let r = run::limit(&prep, &spec).unwrap();
    assert_eq!(r.repeat, 3);
    assert_eq!(r.n, prep.model.qp.n());
    assert!(r.relative_residual.is_some_and(|v| v < 1e-9), "{r:?}");
    let v: serde_json::Value = serde_json::from_str(&r.to_json_line()).unwrap();
    assert_eq!(v["nnz_C"].as_u64().unwrap() as usize, r.nnz_c);
    // A bad ordering cannot reach the library: its parser refuses it
    // (`--ordering random` is clap's error, exit 2).
    let e = "random"
        .parse::<signorini::linalg::ordering::Ordering>()
        .unwrap_err();
    assert!(e.contains("\"nested-dissection\""), "{e}");
}
