//! `signorini export --qp`: the files read back (our Matrix Market reader)
//! give the same QP, the exported solution satisfies its KKT conditions, the
//! kernel is the kernel; `signorini limit` solves C x = d.

use signorini::io::mtx;
use signorini::linalg::sparse::{dot, norm, norm_inf};

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
