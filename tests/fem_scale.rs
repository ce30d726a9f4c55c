//! The FEM side at scale: mesh → topology → assembly of the QP.
//!
//! * `assembly_is_well_formed_on_shipped_models` (runs by default): every
//!   shipped problem assembles to a QP whose C is symmetric (pattern and
//!   values), has sorted unique columns and a positive diagonal, and
//!   annihilates the rigid modes; a second build (sequential) gives the same
//!   QP bit for bit.
//! * `phase_breakdown` (ignored): times read / topology / whole build on a
//!   large model and prints the peak RSS. Run with
//!
//!   ```text
//!   SIGNORINI_SCALE_TOML=/tmp/h8/tb1m.toml \
//!     cargo test --release --test fem_scale -- --ignored --nocapture
//!   ```
//!
//!   `SIGNORINI_SCALE_DUMP=FILE` writes the assembled QP (C, d, A, g,
//!   kernel) to FILE; `SIGNORINI_SCALE_REF=FILE` compares with such a dump
//!   (C and d to 1e-12 relative, A and g exactly).

use signorini::mesh::read_msh;
use signorini::problem::Problem;
use signorini::qp::{Csr, QpProblem};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod common;

use common::root;

/// Peak resident set size of this process [MB] (Linux), if known.
fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn check_csr(c: &Csr, what: &str) {
    assert_eq!(c.indptr.len(), c.nrows + 1, "{what}");
    assert_eq!(c.indptr[c.nrows], c.indices.len(), "{what}");
    assert_eq!(c.indices.len(), c.data.len(), "{what}");
    for i in 0..c.nrows {
        let (cols, _) = c.row(i);
        assert!(
            cols.windows(2).all(|w| w[0] < w[1]),
            "{what}: row {i} not sorted/unique"
        );
        assert!(cols.iter().all(|&j| j < c.ncols), "{what}: row {i}");
    }
}

/// C symmetric (to round-off), C z ≈ 0 for the kernel, pattern well formed.
fn check_qp(qp: &QpProblem, name: &str) {
    check_csr(&qp.c, name);
    check_csr(&qp.a, name);
    let n = qp.n();
    assert_eq!(qp.c.nrows, n);
    assert_eq!(qp.a.nrows, qp.m());
    let cmax = qp.c.data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let ct = qp.c.transpose();
    assert_eq!(ct.indptr, qp.c.indptr, "{name}: pattern of C not symmetric");
    assert_eq!(ct.indices, qp.c.indices, "{name}");
    for (a, b) in ct.data.iter().zip(&qp.c.data) {
        assert!((a - b).abs() <= 1e-12 * cmax, "{name}: C not symmetric");
    }
    for z in &qp.kernel {
        let cz = qp.c.mul(z);
        let r = cz.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(r <= 1e-9 * cmax, "{name}: |C z| = {r:e} (|C| = {cmax:e})");
    }
    // Every diagonal entry present and positive.
    for (i, v) in qp.c.diag().iter().enumerate() {
        assert!(*v > 0.0, "{name}: C[{i},{i}] = {v}");
    }
}

#[test]
fn assembly_is_well_formed_on_shipped_models() {
    let dir = root().join("meshes");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().map(|x| x == "toml").unwrap_or(false))
        .collect();
    names.sort();
    assert!(!names.is_empty());
    for path in names {
        let problem = Problem::load(&path).unwrap();
        let mesh = read_msh(&problem.mesh_path()).unwrap();
        let model = signorini::fem::build(&mesh, &problem)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        check_qp(&model.qp, &path.display().to_string());
        // Building twice, the second time on one thread, gives the same QP
        // bit for bit (no hash-order or thread-count effects).
        let sequential = signorini::fem::BuildOptions { parallel: false };
        let again = signorini::fem::build_with(&mesh, &problem, &sequential).unwrap();
        assert_eq!(again.qp.c, model.qp.c, "{}", path.display());
        assert_eq!(again.qp.d, model.qp.d);
        assert_eq!(again.qp.a, model.qp.a);
        assert_eq!(again.qp.g, model.qp.g);
        assert_eq!(again.qp.kernel, model.qp.kernel);
        assert_eq!(again.qp_rows, model.qp_rows);
        assert_eq!(again.topo.contact_segments, model.topo.contact_segments);
    }
}

// --- dump / compare (for the ignored scale run)

fn put_usizes(w: &mut impl Write, v: &[usize]) {
    w.write_all(&(v.len() as u64).to_le_bytes()).unwrap();
    for &x in v {
        w.write_all(&(x as u64).to_le_bytes()).unwrap();
    }
}
fn put_f64s(w: &mut impl Write, v: &[f64]) {
    w.write_all(&(v.len() as u64).to_le_bytes()).unwrap();
    for &x in v {
        w.write_all(&x.to_le_bytes()).unwrap();
    }
}
fn get_u64(r: &mut impl Read) -> u64 {
    let mut b = [0u8; 8];
    r.read_exact(&mut b).unwrap();
    u64::from_le_bytes(b)
}
fn get_usizes(r: &mut impl Read) -> Vec<usize> {
    let n = get_u64(r) as usize;
    (0..n).map(|_| get_u64(r) as usize).collect()
}
fn get_f64s(r: &mut impl Read) -> Vec<f64> {
    let n = get_u64(r) as usize;
    (0..n).map(|_| f64::from_bits(get_u64(r))).collect()
}

fn dump(qp: &QpProblem, path: &Path) {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for m in [&qp.c, &qp.a] {
        put_usizes(&mut w, &[m.nrows, m.ncols]);
        put_usizes(&mut w, &m.indptr);
        put_usizes(&mut w, &m.indices);
        put_f64s(&mut w, &m.data);
    }
    put_f64s(&mut w, &qp.d);
    put_f64s(&mut w, &qp.g);
    put_usizes(&mut w, &[qp.kernel.len()]);
    for z in &qp.kernel {
        put_f64s(&mut w, z);
    }
}

fn compare(qp: &QpProblem, path: &Path) {
    let mut r = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let rel = |a: &[f64], b: &[f64], what: &str, tol: f64| {
        assert_eq!(a.len(), b.len(), "{what}: length");
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        let mut worst = 0.0f64;
        for (x, y) in a.iter().zip(b) {
            worst = worst.max((x - y).abs() / scale);
        }
        println!("{what}: max |new − ref| / max|ref| = {worst:.3e}");
        assert!(worst <= tol, "{what}: {worst:e} > {tol:e}");
    };
    for (m, what, tol) in [(&qp.c, "C", 1e-12), (&qp.a, "A", 0.0)] {
        let dims = get_usizes(&mut r);
        assert_eq!(dims, vec![m.nrows, m.ncols], "{what}: dimensions");
        assert_eq!(get_usizes(&mut r), m.indptr, "{what}: indptr");
        assert_eq!(get_usizes(&mut r), m.indices, "{what}: indices");
        rel(&m.data, &get_f64s(&mut r), what, tol);
    }
    rel(&qp.d, &get_f64s(&mut r), "d", 1e-12);
    rel(&qp.g, &get_f64s(&mut r), "g", 0.0);
    let k = get_usizes(&mut r)[0];
    assert_eq!(k, qp.kernel.len(), "kernel size");
    for (i, z) in qp.kernel.iter().enumerate() {
        rel(z, &get_f64s(&mut r), &format!("kernel {i}"), 1e-12);
    }
}

#[test]
#[ignore]
fn phase_breakdown() {
    // RUST_LOG=signorini::fem=debug prints the phases inside fem::build.
    let _ = env_logger::builder().is_test(true).try_init();
    let toml = std::env::var("SIGNORINI_SCALE_TOML").unwrap_or("/tmp/h8/tb1m.toml".into());
    let t0 = Instant::now();
    let problem = Problem::load(Path::new(&toml)).unwrap();
    let mesh = read_msh(&problem.mesh_path()).unwrap();
    let t_read = t0.elapsed().as_secs_f64();
    let rss_read = peak_rss_mb().unwrap_or(f64::NAN);
    let nt = mesh.triangles.len();
    let t1 = Instant::now();
    let topo = signorini::fem::topology::Topology::build(
        &mesh,
        &problem.path,
        signorini::fem::ElementKind::of(&problem.file.model),
        &problem.file.materials,
        &problem.file.contact,
    )
    .unwrap();
    let t_topo = t1.elapsed().as_secs_f64();
    let np = topo.points.len();
    drop(topo);
    let t2 = Instant::now();
    let model = signorini::fem::build(&mesh, &problem).unwrap();
    let t_build = t2.elapsed().as_secs_f64();
    println!(
        "{toml}: {} nodes, {np} points, {nt} triangles, {} DOFs, nnz(C) {}, {} contact rows",
        mesh.nodes.len(),
        model.qp.n(),
        model.qp.c.nnz(),
        model.qp.m()
    );
    println!(
        "read {t_read:.3} s | Topology::build {t_topo:.3} s | fem::build (all) {t_build:.3} s = {:.0} triangles/s",
        nt as f64 / t_build
    );
    println!(
        "peak RSS: after read {rss_read:.0} MB, after build {:.0} MB",
        peak_rss_mb().unwrap_or(f64::NAN)
    );
    if let Ok(p) = std::env::var("SIGNORINI_SCALE_DUMP") {
        dump(&model.qp, Path::new(&p));
        println!("dumped to {p}");
    }
    if let Ok(p) = std::env::var("SIGNORINI_SCALE_REF") {
        compare(&model.qp, Path::new(&p));
        println!("matches {p}");
    }
}
