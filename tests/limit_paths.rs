//! `signorini limit` on plane and solid models, on both yardsticks
//! (docs/methods.md §3 and §7.2): the Cholesky one and one AMG-PCG solve of
//! the iterative path's operator.

use signorini::fem::BuildOptions;
use signorini::run::{self, LimitPath, LimitSpec};
use std::path::Path;

fn measure(toml: &str, path: LimitPath) -> run::LimitReport {
    let loaded = run::load(Path::new(toml), false, &BuildOptions::default()).unwrap();
    let spec = LimitSpec {
        path,
        ..Default::default()
    };
    run::limit(loaded.assembled(), &spec).unwrap()
}

#[test]
fn limit_runs_solid_models_on_both_paths() {
    // Hertz in 3D: the ball floats along z, so the iterative yardstick adds
    // every contact row as a spring and the Cholesky one is regularised.
    let toml = "tests/data/solid/xcheck/hertz_nts.toml";
    let chol = measure(toml, LimitPath::Cholesky);
    assert_eq!(chol.kernel_dim, 1, "{chol:?}");
    assert!(chol.iterations.is_none() && chol.levels.is_none());
    let it = measure(toml, LimitPath::Iterative);
    assert_eq!((it.n, it.nnz_c), (chol.n, chol.nnz_c));
    assert!(it.springs.is_some_and(|s| s > 0), "{it:?}");
    assert!(it.relative_residual.is_some_and(|r| r <= 1e-10), "{it:?}");
    assert!(
        it.iterations.is_some_and(|k| (1..=100).contains(&k)),
        "{it:?}"
    );
    assert_eq!(it.ordering, "block-rcm");
    let v: serde_json::Value = serde_json::from_str(&it.to_json_line()).unwrap();
    assert!(v["levels"].as_array().is_some_and(|l| !l.is_empty()));
}

#[test]
fn limit_iterative_on_a_plane_model() {
    let it = measure("meshes/column.toml", LimitPath::Iterative);
    assert_eq!(it.springs, Some(0));
    assert!(it.relative_residual.is_some_and(|r| r <= 1e-10), "{it:?}");
    // The Cholesky report keeps its keys (no iterative ones).
    let chol = measure("meshes/column.toml", LimitPath::Cholesky);
    let v: serde_json::Value = serde_json::from_str(&chol.to_json_line()).unwrap();
    assert!(v.get("iterations").is_none() && v.get("levels").is_none());
    assert!("direct".parse::<LimitPath>().is_err());
}
