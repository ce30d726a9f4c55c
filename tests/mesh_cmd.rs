//! `signorini mesh`: runs Gmsh and checks its output with our reader.

mod common;

use common::{msh_fixture, run};

#[test]
fn meshes_a_geo_file_with_gmsh() {
    // scripts/setup.sh installs gmsh; the test needs it.
    let d = tempfile::tempdir().unwrap();
    let geo = msh_fixture("square.geo").display().to_string();
    let out = d.path().join("square.msh");
    let (code, log) = run(&["mesh", &geo, "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    let m = signorini::mesh::read_msh(&out).unwrap();
    assert!(m.triangles.len() > 10);
    assert!(m.group("interface", 1).is_some(), "{log}");
    assert!(log.contains("interface"), "{log}");
}

#[test]
fn missing_gmsh_is_a_clear_error() {
    let d = tempfile::tempdir().unwrap();
    let geo = msh_fixture("square.geo").display().to_string();
    let out = d.path().join("x.msh");
    let (code, log) = run(&[
        "mesh",
        &geo,
        "-o",
        out.to_str().unwrap(),
        "--gmsh",
        "/nonexistent/gmsh",
    ]);
    assert_eq!(code, 2, "{log}");
    assert!(log.contains("not installed"), "{log}");
    assert!(!out.exists());
}
