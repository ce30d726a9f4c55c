//! A dump of everything `fem::build` produces (C, d, A, g, the kernel and
//! every map back to the mesh, or the error message) for every problem file
//! shipped with the repository, one text file per problem and load step.
//! f64 values are written with `{:?}` (shortest round-trip form), so two
//! dumps are equal as text exactly when the models are equal bit for bit.
//!
//! Run by hand before and after a change of the assembly, then `diff -r`:
//! `FEM_DUMP_DIR=/tmp/before cargo test --release --test fem_dump -- --ignored`.

use signorini::fem::{self, BuildOptions};
use signorini::problem::Problem;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The problem files: meshes/*.toml and tests/{data/*,hard,bad_inputs/*}/*.toml.
fn problem_files(root: &Path) -> Vec<PathBuf> {
    let mut dirs = vec![root.join("meshes"), root.join("tests/hard")];
    for parent in ["tests/data", "tests/bad_inputs"] {
        if let Ok(rd) = std::fs::read_dir(root.join(parent)) {
            dirs.extend(rd.filter_map(|e| e.ok().map(|e| e.path())));
        }
    }
    let mut files = vec![];
    for d in dirs {
        // /dev/zero and friends as meshes: the reader's business, not fem's.
        if d.to_string_lossy().contains("mesh_dev_") {
            continue;
        }
        if let Ok(rd) = std::fs::read_dir(&d) {
            files.extend(
                rd.filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|x| x == "toml")),
            );
        }
    }
    files.sort();
    files
}

/// Every field of the model, in a fixed order.
fn dump_model(m: &fem::Model) -> String {
    let mut s = String::new();
    let qp = &m.qp;
    let _ = writeln!(s, "C {:?}", qp.c);
    let _ = writeln!(s, "d {:?}", qp.d);
    let _ = writeln!(s, "A {:?}", qp.a);
    let _ = writeln!(s, "g {:?}", qp.g);
    let _ = writeln!(s, "kernel {:?}", qp.kernel);
    let _ = writeln!(s, "kernel_body {:?}", m.kernel_body);
    let _ = writeln!(s, "qp_rows {:?}", m.qp_rows);
    let _ = writeln!(s, "dofs {:?}", m.dofs);
    let _ = writeln!(s, "kind {:?}", m.kind);
    let _ = writeln!(s, "conditions {:?}", m.conditions);
    let _ = writeln!(s, "cond_groups {:?}", m.cond_groups);
    let _ = writeln!(s, "loads {:?}", m.loads);
    let _ = writeln!(s, "body_names {:?}", m.body_names);
    let t = &m.topo;
    let _ = writeln!(s, "points {:?}", t.points);
    let _ = writeln!(s, "point_node {:?}", t.point_node);
    let _ = writeln!(s, "point_body {:?}", t.point_body);
    let _ = writeln!(s, "triangles {:?}", t.triangles);
    let _ = writeln!(s, "tri_body {:?}", t.tri_body);
    let _ = writeln!(s, "tri_material {:?}", t.tri_material);
    let _ = writeln!(s, "material_names {:?}", t.material_names);
    let _ = writeln!(s, "nbodies {}", t.nbodies);
    let _ = writeln!(s, "contact {:?}", t.contact);
    let _ = writeln!(s, "contact_segments {:?}", t.contact_segments);
    let _ = writeln!(s, "interface_names {:?}", t.interface_names);
    let copies: Vec<_> = (0..t.point_node.iter().max().map_or(0, |v| v + 1))
        .map(|v| t.copies(v).to_vec())
        .collect();
    let _ = writeln!(s, "copies {copies:?}");
    s
}

/// One dump per problem file and load step; an error is dumped as its message.
fn dump_all(out: &Path, opts: &BuildOptions) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(out).unwrap();
    let mut n = 0;
    for path in problem_files(root) {
        let rel = path
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('/', "+");
        let mut text = String::new();
        match Problem::load(&path) {
            Err(e) => text = format!("problem error: {e}\n"),
            Ok(problem) => match signorini::mesh::read_msh(&problem.mesh_path()) {
                Err(e) => text = format!("mesh error: {e}\n"),
                Ok(mesh) => {
                    for s in 0..problem.file.nsteps() {
                        let mut p = problem.clone();
                        p.file = problem.file.at_step(s);
                        let _ = writeln!(text, "== step {s}");
                        match fem::build_with(&mesh, &p, opts) {
                            Ok(m) => text.push_str(&dump_model(&m)),
                            Err(e) => {
                                let _ = writeln!(text, "fem error: {e}");
                            }
                        }
                    }
                }
            },
        }
        std::fs::write(out.join(format!("{rel}.txt")), text).unwrap();
        n += 1;
    }
    n
}

#[test]
#[ignore = "writes a dump for a before/after comparison; run by hand"]
fn dump_models() {
    let out = std::env::var_os("FEM_DUMP_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_TARGET_TMPDIR")).join("fem_dump"));
    for (sub, parallel) in [("parallel", true), ("sequential", false)] {
        let n = dump_all(&out.join(sub), &BuildOptions { parallel });
        assert!(n > 100, "{n} problem files");
    }
}
