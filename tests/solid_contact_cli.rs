//! `signorini solve` on 3D models with `[[contact]]` (issue 45), through the
//! binary, its outputs read back: the stacked cubes of
//! tests/data/solid_contact under a uniform pressure p on top, the upper
//! cube held along z by the contact alone — conforming (node-to-node rows
//! on the cut interface) and non-matching with mortar rows (the 3D contact
//! patch test). Required: exit 0 with the certificate; the contact
//! pressure p at every row in the contact VTU and the HDF5 checkpoint; the
//! contact VTU's triangles cover the interface (area 1 m²); the JSON
//! interface resultant is the load p·1 m² on the slave side, every row
//! active; the supports' reactions net of the contact forces, loads +
//! reactions = 0.

mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};

const P: f64 = 1.0e6;

fn data(name: &str) -> PathBuf {
    common::root().join("tests/data/solid_contact").join(name)
}

/// The stack problem on `msh` with the contact entry `contact`.
fn stack_toml(msh: &Path, contact: &str) -> String {
    common::solid_stack_toml(msh, contact, -P, "")
}

/// Solve `toml` in `dir`; the JSON summary.
fn solve(dir: &Path, toml: &str) -> Value {
    let path = dir.join("stack.toml");
    std::fs::write(&path, toml).unwrap();
    let o = common::command()
        .args(["solve", path.to_str().unwrap(), "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(text.contains("certified"), "{text}");
    assert!(text.contains("interface"), "{text}");
    let json = std::fs::read_to_string(dir.join("out/stack.json")).unwrap();
    serde_json::from_str(&json).unwrap()
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [0, 1, 2].map(|k| a[k].as_f64().unwrap())
}

/// The checks of the module doc on one solved stack.
fn check(dir: &Path, json: &Value, interface: &str) {
    let it = &json["contact"][interface];
    let (rows, active) = (it["rows"].as_u64().unwrap(), it["active"].as_u64().unwrap());
    assert!(rows > 0 && rows == active, "{rows} rows, {active} active");
    let f = vec3(&it["force"]);
    assert!((f[2] - P).abs() <= 1e-9 * P, "interface force {f:?}");
    assert!(f[0].abs() <= 1e-9 * P && f[1].abs() <= 1e-9 * P, "{f:?}");
    let pmax = it["max_pressure"].as_f64().unwrap();
    assert!((pmax - P).abs() <= 1e-9 * P, "max pressure {pmax:e}");
    // Loads + reactions = 0 (the contact forces are internal).
    let loads = vec3(&json["loads"]["force"]);
    let mut total = loads;
    for (_, g) in json["reactions"].as_object().unwrap() {
        let r = vec3(&g["force"]);
        for k in 0..3 {
            total[k] += r[k];
        }
    }
    assert!(
        total.iter().all(|t| t.abs() <= 1e-8 * P),
        "loads + reactions = {total:?}"
    );
    let bottom = vec3(&json["reactions"]["bottom"]["force"]);
    assert!((bottom[2] - P).abs() <= 1e-9 * P, "bottom {bottom:?}");

    // The contact VTU: p at every row, its triangles cover 1 m².
    let vtu = signorini::io::vtu::read_vtu_arrays(&dir.join("out/stack_contact.vtu")).unwrap();
    assert_eq!(vtu.num_points as u64, rows);
    assert!(vtu.cell_types.iter().all(|&t| t == 5), "triangles");
    let pressure = vtu
        .point_data
        .iter()
        .find(|a| a.name == "contact_pressure")
        .expect("contact_pressure");
    let perr = pressure
        .values
        .iter()
        .map(|p| (p - P).abs() / P)
        .fold(0.0, f64::max);
    assert!(perr <= 1e-9, "contact VTU pressure error {perr:e}");
    for name in ["gap", "active", "normal", "multiplier", "interface"] {
        assert!(vtu.point_data.iter().any(|a| a.name == name), "no {name}");
    }

    // The checkpoint: the same pressures; the triangles' area is 1 m².
    let h5 = dir.join("out/stack.h5");
    let f = hdf5::File::open(&h5).unwrap();
    let pr: Vec<f64> = f
        .dataset("steps/0001/contact_pressure")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(pr.len() as u64, rows);
    assert!(pr.iter().all(|p| (p - P).abs() <= 1e-9 * P));
    let lam: Vec<f64> = f
        .dataset("steps/0001/multipliers")
        .unwrap()
        .read_raw()
        .unwrap();
    let sum: f64 = lam.iter().sum();
    assert!((sum - P).abs() <= 1e-9 * P, "Σλ = {sum:e}");
    let tris: Vec<u64> = f
        .dataset("mesh/contact_triangles")
        .unwrap()
        .read_raw()
        .unwrap();
    let slave: Vec<u64> = f.dataset("mesh/contact_slave").unwrap().read_raw().unwrap();
    let nodes: Vec<f64> = f.dataset("mesh/nodes").unwrap().read_raw().unwrap();
    let at = |row: u64| {
        let p = slave[row as usize] as usize;
        [nodes[3 * p], nodes[3 * p + 1], nodes[3 * p + 2]]
    };
    let area: f64 = tris
        .chunks(3)
        .map(|t| {
            let (a, b, c) = (at(t[0]), at(t[1]), at(t[2]));
            let (u, v) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            let x = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
        })
        .sum();
    assert!(
        (area - 1.0).abs() <= 1e-12,
        "contact triangles cover {area}"
    );
}

#[test]
fn stacked_cubes_with_a_conforming_interface_through_the_cli() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack_toml(&data("stack.msh"), "on = \"interface\"");
    let json = solve(tmp.path(), &toml);
    check(tmp.path(), &json, "interface");
}

#[test]
fn stacked_cubes_non_matching_with_mortar_rows_through_the_cli() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = stack_toml(
        &data("stack_nm.msh"),
        "slave = \"upper_bottom\"\nmaster = \"lower_top\"\ndiscretization = \"mortar\"",
    );
    let json = solve(tmp.path(), &toml);
    check(tmp.path(), &json, "upper_bottom/lower_top");
}
