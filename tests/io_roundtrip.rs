//! Round trips of the output writers: VTU, contact VTU, PVD, HDF5 checkpoint.

use std::path::Path;

use signorini::fem::ElementKind;
use signorini::io::atomic::{write_atomic, IoError};
use signorini::io::hdf5::{append_step, create_checkpoint, read_checkpoint};
use signorini::io::vtu::{read_pvd, read_vtu_arrays, write_contact_vtu, write_pvd, write_vtu};
use signorini::output::{Change, ContactGeometry, OutMesh, StepInfo, StepOutput};

/// Two bodies, one triangle each, touching along y = 0 from x = 0 to x = 1.
/// The two interface nodes are duplicated (points 0,1 in body 0 and 3,4 in
/// body 1): two conforming constraint rows joined by one segment.
fn mesh(plane_strain: bool) -> OutMesh {
    OutMesh {
        points: vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, -1.0],
            [0.0, 0.0],
            [1.0, 0.0],
            [0.1, 1.0 / 3.0],
        ],
        point_tags: vec![1, 2, 3, 1, 2, 4],
        point_body: vec![0, 0, 0, 1, 1, 1],
        triangles: vec![[0, 2, 1], [3, 4, 5]],
        material: vec![0, 1],
        material_names: vec!["crust".into(), "block β".into()],
        kind: if plane_strain {
            ElementKind::PlaneStrain
        } else {
            ElementKind::PlaneStress { thickness: 1.0 }
        },
        contact: ContactGeometry {
            points: vec![[0.0, 0.0], [1.0, 0.0]],
            first: vec![0, 1],
            second: vec![[(3, 1.0), (3, 0.0)], [(4, 0.75), (3, 0.25)]],
            normal: vec![[0.0, 1.0], [0.0, 1.0]],
            gap0: vec![0.0, 1e-3],
            segments: vec![[0, 1]],
            interface: vec![0, 0],
            interface_names: vec!["fault1".into()],
            interface_discretizations: vec!["nts".into()],
            nonmatching: vec![false, true],
        },
    }
}

fn step(t: f64, scale: f64) -> StepOutput {
    let s = scale;
    StepOutput {
        time: t,
        displacement: (0..6)
            .map(|i| [0.1 * s * i as f64, -s / 3.0 * i as f64])
            .collect(),
        stress: vec![
            [1.5e8 * s, -2.0e7, 0.1 * s, 4.0e6],
            [-1.0, 2.0, -3.0 * s, 0.3],
        ],
        von_mises: vec![1.4e8 * s, 5.0 / 7.0],
        principal: vec![[1.5e8, -2.0e7 * s], [2.5, -3.5]],
        multipliers: vec![1e5 * s, 0.0],
        contact_pressure: vec![2e5 * s, 0.0],
        gap: vec![0.0, 1e-3 / 3.0],
        active: vec![1, 0],
        reaction: vec![],
        info: StepInfo {
            method: "cgc".into(),
            preconditioner: "cholesky".into(),
            converged: s > 1.5,
            iterations: 42 + t as usize,
            energy: -1.2345e6 * s,
            // every residual, so that the checkpoint is seen to keep all
            kkt: signorini::qp::Kkt {
                primal: 0.0,
                dual: 1e-14,
                complementarity: 1e-12 / 3.0,
                stationarity: 1e-10,
                contact_balance: 2e-9 * s,
                rigid_balance: 3e-11,
                friction: 4e-8 / 7.0,
                stationarity_floor: 1e-15,
                balance_floor: 5e-14,
            },
            time_assemble: 0.02,
            time_solve: 0.1 * s,
            time_total: 0.16,
        },
        change: None,
    }
}

/// Files in `dir` (names), sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn assert_no_temp_files(dir: &Path) {
    for name in listing(dir) {
        assert!(
            !name.starts_with('.') && !name.contains(".tmp"),
            "temporary file left behind: {name}"
        );
    }
}

fn names(arrays: &[signorini::io::vtu::VtuArray]) -> Vec<&str> {
    arrays.iter().map(|a| a.name.as_str()).collect()
}

fn check_bulk_vtu(path: &Path, m: &OutMesh, s: &StepOutput) {
    let r = read_vtu_arrays(path).unwrap();
    assert_eq!(r.num_points, 6);
    assert_eq!(r.num_cells, 2);
    assert_eq!(r.cell_types, vec![5, 5]);
    assert_eq!(r.connectivity, vec![0, 2, 1, 3, 4, 5]);
    assert_eq!(r.offsets, vec![3, 6]);
    let pts: Vec<f64> = m.points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    assert_eq!(r.points, pts);

    assert_eq!(
        names(&r.point_data),
        vec!["displacement", "body", "contact_role"]
    );
    // Row 0 pairs points 0 and 3 (conforming); row 1 puts slave 1 on the
    // master segment (4, 3): 1 conforming, 2 slave, 3 master.
    let role = r.point_array("contact_role").unwrap();
    assert_eq!(role.values, vec![1.0, 2.0, 0.0, 3.0, 3.0, 0.0]);
    let xml = String::from_utf8_lossy(&std::fs::read(path).unwrap()).into_owned();
    assert!(xml.contains(r#"ComponentName0="ux" ComponentName1="uy" ComponentName2="uz""#));
    assert!(xml.contains(r#"ComponentName0="sxx" ComponentName1="syy" ComponentName2="sxy""#));
    assert_eq!(
        names(&r.cell_data),
        vec!["stress", "von_mises", "principal_stress", "material"]
    );

    let d = r.point_array("displacement").unwrap();
    assert_eq!(d.num_comp, 3);
    let want: Vec<f64> = s
        .displacement
        .iter()
        .flat_map(|u| [u[0], u[1], 0.0])
        .collect();
    assert_eq!(d.values, want);
    let b = r.point_array("body").unwrap();
    assert_eq!(
        (b.num_comp, b.values.clone()),
        (1, vec![0., 0., 0., 1., 1., 1.])
    );

    let nc = m.kind.stress_len();
    let st = r.cell_array("stress").unwrap();
    assert_eq!(st.num_comp, nc);
    let want: Vec<f64> = s.stress.iter().flat_map(|x| x[..nc].to_vec()).collect();
    assert_eq!(st.values, want);
    let vm = r.cell_array("von_mises").unwrap();
    assert_eq!((vm.num_comp, vm.values.clone()), (1, s.von_mises.clone()));
    let ps = r.cell_array("principal_stress").unwrap();
    assert_eq!(ps.num_comp, 2);
    assert_eq!(
        ps.values,
        s.principal.iter().flat_map(|p| *p).collect::<Vec<_>>()
    );
    let mat = r.cell_array("material").unwrap();
    assert_eq!((mat.num_comp, mat.values.clone()), (1, vec![0.0, 1.0]));
}

#[test]
fn vtu_roundtrip_plain_and_compressed() {
    let dir = tempfile::tempdir().unwrap();
    for (plane_strain, compress) in [(true, false), (false, false), (true, true), (false, true)] {
        let m = mesh(plane_strain);
        let s = step(1.0, 2.0);
        let p = dir
            .path()
            .join(format!("model_{plane_strain}_{compress}.vtu"));
        write_vtu(&p, &m, &s, compress).unwrap();
        let text = std::fs::read(&p).unwrap();
        let text = String::from_utf8_lossy(&text);
        assert!(text.contains("UnstructuredGrid"));
        assert!(text.contains("Float64"));
        assert_eq!(text.contains("vtkZLibDataCompressor"), compress);
        check_bulk_vtu(&p, &m, &s);
    }
    assert_no_temp_files(dir.path());
}

#[test]
fn vtu_overwrite_replaces_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.vtu");
    let m = mesh(true);
    write_vtu(&p, &m, &step(0.5, 1.0), false).unwrap();
    let s2 = step(1.0, 3.0);
    write_vtu(&p, &m, &s2, false).unwrap();
    check_bulk_vtu(&p, &m, &s2);
    assert_eq!(listing(dir.path()), vec!["model.vtu"]);
}

#[test]
fn contact_vtu_roundtrip() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh(true);
    let s = step(1.0, 2.0);
    for compress in [false, true] {
        let p = dir.path().join(format!("model_contact_{compress}.vtu"));
        write_contact_vtu(&p, &m, &s, compress).unwrap();
        let r = read_vtu_arrays(&p).unwrap();
        assert_eq!(r.num_points, 2);
        assert_eq!(r.num_cells, 1);
        assert_eq!(r.cell_types, vec![3]);
        assert_eq!(r.connectivity, vec![0, 1]);
        assert_eq!(r.points, vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert_eq!(
            names(&r.point_data),
            vec![
                "contact_pressure",
                "gap",
                "active",
                "normal",
                "multiplier",
                "interface",
                "tangent",
                "role"
            ]
        );
        let t = r.point_array("tangent").unwrap();
        assert_eq!(t.values, vec![-1.0, 0.0, 0.0, -1.0, 0.0, 0.0]);
        assert_eq!(r.point_array("role").unwrap().values, vec![1.0, 2.0]);
        assert!(r.cell_data.is_empty());
        let get = |n: &str| r.point_array(n).unwrap();
        assert_eq!(get("contact_pressure").values, s.contact_pressure);
        assert_eq!(get("gap").values, s.gap);
        assert_eq!(get("active").values, vec![1.0, 0.0]);
        assert_eq!(get("normal").num_comp, 3);
        assert_eq!(get("normal").values, vec![0.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
        assert_eq!(get("multiplier").values, s.multipliers);
        assert_eq!(get("interface").values, vec![0.0, 0.0]);
    }
    assert_no_temp_files(dir.path());
}

#[test]
fn contact_vtu_empty() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = mesh(false);
    m.contact = ContactGeometry::default();
    let mut s = step(1.0, 1.0);
    s.multipliers.clear();
    s.contact_pressure.clear();
    s.gap.clear();
    s.active.clear();
    for compress in [false, true] {
        let p = dir.path().join(format!("empty_{compress}.vtu"));
        write_contact_vtu(&p, &m, &s, compress).unwrap();
        let r = read_vtu_arrays(&p).unwrap();
        assert_eq!((r.num_points, r.num_cells), (0, 0));
        assert_eq!(r.point_data.len(), 8);
        assert!(r.point_data.iter().all(|a| a.values.is_empty()));
        // VTK's reader requires both counts on <Piece>, even when zero.
        let text = String::from_utf8_lossy(&std::fs::read(&p).unwrap()).into_owned();
        assert!(
            text.contains("<Piece NumberOfPoints=\"0\" NumberOfCells=\"0\">"),
            "{text}"
        );
    }

    // One contact row and no segment: points but zero cells.
    let mut m = mesh(false);
    let c = &mut m.contact;
    c.points.truncate(1);
    c.first.truncate(1);
    c.second.truncate(1);
    c.normal.truncate(1);
    c.gap0.truncate(1);
    c.interface.truncate(1);
    c.segments.clear();
    let mut s = step(1.0, 1.0);
    s.multipliers.truncate(1);
    s.contact_pressure.truncate(1);
    s.gap.truncate(1);
    s.active.truncate(1);
    let p = dir.path().join("one_row.vtu");
    write_contact_vtu(&p, &m, &s, false).unwrap();
    let text = String::from_utf8_lossy(&std::fs::read(&p).unwrap()).into_owned();
    assert!(text.contains("NumberOfPoints=\"1\""), "{text}");
    assert!(text.contains("NumberOfCells=\"0\""), "{text}");
    let r = read_vtu_arrays(&p).unwrap();
    assert_eq!((r.num_points, r.num_cells), (1, 0));
    assert_eq!(r.point_array("gap").unwrap().values, s.gap);
}

#[test]
fn vtu_rejects_inconsistent_fields_without_leaving_files() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh(true);
    let mut s = step(1.0, 1.0);
    s.displacement.pop();
    let p = dir.path().join("bad.vtu");
    let e = write_vtu(&p, &m, &s, false).unwrap_err();
    assert!(matches!(e, IoError::Format { .. }), "{e}");
    assert!(e.to_string().contains("bad.vtu"), "{e}");
    assert!(e.to_string().contains("displacement"), "{e}");

    let mut s = step(1.0, 1.0);
    s.gap.push(0.0);
    let e = write_contact_vtu(&dir.path().join("bad_contact.vtu"), &m, &s, false).unwrap_err();
    assert!(e.to_string().contains("bad_contact.vtu"), "{e}");

    let mut m2 = mesh(true);
    m2.triangles[1][2] = 99;
    let e = write_vtu(&p, &m2, &step(1.0, 1.0), false).unwrap_err();
    assert!(e.to_string().contains("99"), "{e}");

    assert!(listing(dir.path()).is_empty());
}

#[test]
fn pvd_roundtrip() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.pvd");
    let entries = vec![
        (0.1, "model_0001.vtu".to_string()),
        (0.1, "model_contact_0001.vtu".to_string()),
        (1.0 / 3.0, "a&b <\"odd\">.vtu".to_string()),
        (1.0, "model_0003.vtu".to_string()),
    ];
    write_pvd(&p, &entries).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("<VTKFile type=\"Collection\""));
    assert!(text.contains("<Collection>"));
    assert!(
        text.contains("<DataSet timestep=\"0.1\" group=\"\" part=\"0\" file=\"model_0001.vtu\"/>")
    );
    assert!(text.contains("part=\"1\" file=\"model_contact_0001.vtu\""));
    assert!(text.contains("a&amp;b &lt;&quot;odd&quot;&gt;.vtu"));
    assert_eq!(read_pvd(&p).unwrap(), entries);

    let e = write_pvd(&dir.path().join("nan.pvd"), &[(f64::NAN, "x.vtu".into())]).unwrap_err();
    assert!(e.to_string().contains("nan.pvd"), "{e}");
    assert_eq!(listing(dir.path()), vec!["model.pvd"]);
}

fn attrs() -> Vec<(&'static str, String)> {
    vec![
        ("problem", "model".to_string()),
        ("toml", "[mesh]\nfile = \"m.msh\"\n# ünïcode\n".to_string()),
        ("version", "0.1.0".to_string()),
    ]
}

#[test]
fn hdf5_roundtrip_two_steps() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.h5");
    let m = mesh(true);
    create_checkpoint(&p, &m, &attrs()).unwrap();
    let s1 = step(0.5, 1.0);
    let s2 = step(1.0, 2.0);
    append_step(&p, 1, &s1).unwrap();
    append_step(&p, 2, &s2).unwrap();
    assert_eq!(listing(dir.path()), vec!["model.h5"]);

    let c = read_checkpoint(&p).unwrap();
    let rm = &c.mesh;
    assert_eq!(rm.points, m.points);
    assert_eq!(rm.point_tags, m.point_tags);
    assert_eq!(rm.point_body, m.point_body);
    assert_eq!(rm.triangles, m.triangles);
    assert_eq!(rm.material, m.material);
    assert_eq!(rm.material_names, m.material_names);
    assert_eq!(rm.kind, m.kind);
    let (a, b) = (&rm.contact, &m.contact);
    assert_eq!(a.points, b.points);
    assert_eq!(a.first, b.first);
    assert_eq!(a.second, b.second);
    assert_eq!(a.normal, b.normal);
    assert_eq!(a.gap0, b.gap0);
    assert_eq!(a.segments, b.segments);
    assert_eq!(a.interface, b.interface);
    assert_eq!(a.interface_names, b.interface_names);

    let mut want_attrs: Vec<(String, String)> = attrs()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    want_attrs.sort();
    let mut got_attrs = c.attrs.clone();
    got_attrs.sort();
    assert_eq!(got_attrs, want_attrs);

    assert_eq!(c.steps.len(), 2);
    for (got, want) in c.steps.iter().zip([&s1, &s2]) {
        assert_eq!(got.time, want.time);
        assert_eq!(got.displacement, want.displacement);
        assert_eq!(got.stress, want.stress);
        assert_eq!(got.von_mises, want.von_mises);
        assert_eq!(got.principal, want.principal);
        assert_eq!(got.multipliers, want.multipliers);
        assert_eq!(got.contact_pressure, want.contact_pressure);
        assert_eq!(got.gap, want.gap);
        assert_eq!(got.active, want.active);
        let (gi, wi) = (&got.info, &want.info);
        assert_eq!(gi.method, wi.method);
        assert_eq!(gi.preconditioner, wi.preconditioner);
        assert_eq!(gi.converged, wi.converged);
        assert_eq!(gi.iterations, wi.iterations);
        assert_eq!(gi.energy, wi.energy);
        // all nine residuals of the certificate, bit for bit
        assert_eq!(gi.kkt, wi.kkt);
        assert_eq!(gi.time_assemble, wi.time_assemble);
        assert_eq!(gi.time_solve, wi.time_solve);
        assert_eq!(gi.time_total, wi.time_total);
    }

    // Layout details other tools rely on.
    let f = hdf5::File::open(&p).unwrap();
    assert_eq!(
        f.attr("last_step").unwrap().read_scalar::<u64>().unwrap(),
        2
    );
    assert_eq!(
        f.attr("plane_strain").unwrap().read_scalar::<u8>().unwrap(),
        1
    );
    assert_eq!(f.dataset("mesh/nodes").unwrap().shape(), vec![6, 2]);
    assert_eq!(f.dataset("mesh/triangles").unwrap().shape(), vec![2, 3]);
    assert_eq!(
        f.dataset("mesh/contact_second").unwrap().shape(),
        vec![2, 2]
    );
    assert_eq!(
        f.dataset("mesh/contact_segments").unwrap().shape(),
        vec![1, 2]
    );
    assert_eq!(f.dataset("steps/0002/stress").unwrap().shape(), vec![2, 4]);
    assert_eq!(
        f.dataset("steps/0001/displacement").unwrap().shape(),
        vec![6, 2]
    );
    assert_eq!(
        f.dataset("steps/0001/active")
            .unwrap()
            .read_raw::<u8>()
            .unwrap(),
        vec![1, 0]
    );
    assert_eq!(
        f.group("steps/0002")
            .unwrap()
            .attr("time")
            .unwrap()
            .read_scalar::<f64>()
            .unwrap(),
        1.0
    );
}

#[test]
fn hdf5_append_replaces_later_steps() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.h5");
    create_checkpoint(&p, &mesh(false), &attrs()).unwrap();
    append_step(&p, 1, &step(0.5, 1.0)).unwrap();
    append_step(&p, 2, &step(1.0, 2.0)).unwrap();
    // A restart from step 1 rewrites step 2 and drops anything after it.
    append_step(&p, 2, &step(0.75, 3.0)).unwrap();
    let c = read_checkpoint(&p).unwrap();
    assert_eq!(c.steps.len(), 2);
    assert_eq!(c.steps[1].time, 0.75);
    assert_eq!(c.mesh.kind.stress_len(), 3);
    append_step(&p, 1, &step(0.25, 1.0)).unwrap();
    let c = read_checkpoint(&p).unwrap();
    assert_eq!(c.steps.len(), 1);
    assert_eq!(c.steps[0].time, 0.25);
    assert_eq!(listing(dir.path()), vec!["model.h5"]);
}

#[test]
fn hdf5_mesh_only_has_zero_steps() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.h5");
    create_checkpoint(&p, &mesh(true), &[]).unwrap();
    let c = read_checkpoint(&p).unwrap();
    assert!(c.steps.is_empty());
    assert!(c.attrs.is_empty());
    assert_eq!(c.mesh.triangles.len(), 2);
}

#[test]
fn hdf5_empty_contact_roundtrip() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nocontact.h5");
    let mut m = mesh(true);
    m.contact = ContactGeometry::default();
    let mut s = step(1.0, 1.0);
    s.multipliers.clear();
    s.contact_pressure.clear();
    s.gap.clear();
    s.active.clear();
    create_checkpoint(&p, &m, &attrs()).unwrap();
    append_step(&p, 1, &s).unwrap();
    let c = read_checkpoint(&p).unwrap();
    assert_eq!(c.mesh.contact.points.len(), 0);
    assert!(c.mesh.contact.interface_names.is_empty());
    assert_eq!(c.steps.len(), 1);
    assert!(c.steps[0].multipliers.is_empty());
}

#[test]
fn hdf5_bad_step_leaves_previous_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.h5");
    create_checkpoint(&p, &mesh(true), &attrs()).unwrap();
    append_step(&p, 1, &step(0.5, 1.0)).unwrap();
    let before = std::fs::read(&p).unwrap();
    let mut s = step(1.0, 2.0);
    s.stress.pop();
    let e = append_step(&p, 2, &s).unwrap_err();
    assert!(e.to_string().contains("model.h5"), "{e}");
    assert!(e.to_string().contains("stress"), "{e}");
    assert_eq!(std::fs::read(&p).unwrap(), before);
    assert_eq!(listing(dir.path()), vec!["model.h5"]);
    assert_eq!(read_checkpoint(&p).unwrap().steps.len(), 1);
    let e = append_step(&p, 0, &step(1.0, 1.0)).unwrap_err();
    assert!(e.to_string().contains("model.h5"), "{e}");
}

#[test]
fn writes_into_missing_directory_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no_such_dir");
    let m = mesh(true);
    let s = step(1.0, 1.0);
    let results: Vec<(&str, Result<(), IoError>)> = vec![
        (
            "model.vtu",
            write_vtu(&missing.join("model.vtu"), &m, &s, false),
        ),
        (
            "model_contact.vtu",
            write_contact_vtu(&missing.join("model_contact.vtu"), &m, &s, true),
        ),
        (
            "model.pvd",
            write_pvd(&missing.join("model.pvd"), &[(1.0, "a.vtu".into())]),
        ),
        (
            "model.h5",
            create_checkpoint(&missing.join("model.h5"), &m, &attrs()),
        ),
        ("other.h5", append_step(&missing.join("other.h5"), 1, &s)),
    ];
    for (name, r) in results {
        let e = r.unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(name) && msg.contains("no_such_dir"), "{msg}");
        assert!(
            !msg.contains(".tmp-"),
            "error names the temporary file: {msg}"
        );
        assert_eq!(e.path(), missing.join(name));
    }
    assert!(!missing.exists());
    assert!(listing(dir.path()).is_empty());

    // append_step on a checkpoint that does not exist.
    let e = append_step(&dir.path().join("absent.h5"), 1, &s).unwrap_err();
    assert!(e.to_string().contains("absent.h5"), "{e}");
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn write_atomic_removes_temp_on_error() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.json");
    std::fs::write(&target, b"old").unwrap();
    let r = write_atomic(&target, |tmp| {
        std::fs::write(tmp, b"partial").unwrap();
        Err(IoError::Format {
            path: tmp.to_path_buf(),
            message: "boom".into(),
        })
    });
    let e = r.unwrap_err();
    // The error is retargeted to the user's file.
    assert_eq!(e.path(), target);
    assert!(e.to_string().contains("boom"));
    assert_eq!(std::fs::read(&target).unwrap(), b"old");
    assert_eq!(listing(dir.path()), vec!["out.json"]);

    signorini::io::atomic::write_atomic_bytes(&target, b"new").unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"new");
    assert_eq!(listing(dir.path()), vec!["out.json"]);
}

#[test]
fn corrupt_checkpoints_give_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.h5");
    create_checkpoint(&good, &mesh(true), &attrs()).unwrap();
    append_step(&good, 1, &step(0.5, 1.0)).unwrap();
    let bytes = std::fs::read(&good).unwrap();

    // Truncated at several lengths.
    for frac in [0.0, 0.1, 0.5, 0.9] {
        let p = dir.path().join(format!("trunc_{frac}.h5"));
        std::fs::write(&p, &bytes[..(bytes.len() as f64 * frac) as usize]).unwrap();
        let e = read_checkpoint(&p).unwrap_err();
        assert!(e.to_string().contains(&format!("trunc_{frac}.h5")), "{e}");
        let e = append_step(&p, 2, &step(1.0, 1.0)).unwrap_err();
        assert!(e.to_string().contains(&format!("trunc_{frac}.h5")), "{e}");
    }
    // Not HDF5 at all.
    let junk = dir.path().join("junk.h5");
    std::fs::write(&junk, b"this is not an HDF5 file\n").unwrap();
    let e = read_checkpoint(&junk).unwrap_err();
    assert!(e.to_string().contains("junk.h5"), "{e}");
    // Missing file.
    let e = read_checkpoint(&dir.path().join("none.h5")).unwrap_err();
    assert!(e.to_string().contains("none.h5"), "{e}");
}

#[test]
fn missing_groups_and_datasets_are_named() {
    let dir = tempfile::tempdir().unwrap();
    // A valid HDF5 file without /mesh.
    let p = dir.path().join("nomesh.h5");
    {
        let f = hdf5::File::create(&p).unwrap();
        f.new_attr::<u8>()
            .create("plane_strain")
            .unwrap()
            .write_scalar(&0u8)
            .unwrap();
    }
    let e = read_checkpoint(&p).unwrap_err();
    assert!(matches!(e, IoError::Missing { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("nomesh.h5") && msg.contains("/mesh"), "{msg}");
    let e = append_step(&p, 1, &step(1.0, 1.0)).unwrap_err();
    assert!(e.to_string().contains("/mesh"), "{e}");

    // A checkpoint with one mesh dataset removed.
    let q = dir.path().join("partial.h5");
    create_checkpoint(&q, &mesh(true), &attrs()).unwrap();
    {
        let f = hdf5::File::open_rw(&q).unwrap();
        f.group("mesh").unwrap().unlink("contact_normal").unwrap();
    }
    let e = read_checkpoint(&q).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("partial.h5") && msg.contains("/mesh/contact_normal"),
        "{msg}"
    );

    // A step group missing a dataset.
    let r = dir.path().join("badstep.h5");
    create_checkpoint(&r, &mesh(true), &attrs()).unwrap();
    append_step(&r, 1, &step(1.0, 1.0)).unwrap();
    {
        let f = hdf5::File::open_rw(&r).unwrap();
        f.group("steps/0001").unwrap().unlink("gap").unwrap();
    }
    let e = read_checkpoint(&r).unwrap_err();
    assert!(e.to_string().contains("/steps/0001/gap"), "{e}");
}

#[test]
fn non_finite_values_survive() {
    // A diverged solve still writes its outputs.
    let dir = tempfile::tempdir().unwrap();
    let m = mesh(true);
    let mut s = step(1.0, 1.0);
    s.von_mises = vec![f64::NAN, f64::NAN];
    s.stress[0][0] = f64::INFINITY;
    s.displacement[2][1] = f64::NEG_INFINITY;
    s.info.energy = f64::NAN;
    for compress in [false, true] {
        let p = dir.path().join(format!("nan_{compress}.vtu"));
        write_vtu(&p, &m, &s, compress).unwrap();
        let r = read_vtu_arrays(&p).unwrap();
        assert!(r
            .cell_array("von_mises")
            .unwrap()
            .values
            .iter()
            .all(|v| v.is_nan()));
        assert_eq!(r.cell_array("stress").unwrap().values[0], f64::INFINITY);
        assert_eq!(
            r.point_array("displacement").unwrap().values[7],
            f64::NEG_INFINITY
        );
    }
    let p = dir.path().join("nan.h5");
    create_checkpoint(&p, &m, &attrs()).unwrap();
    append_step(&p, 1, &s).unwrap();
    let c = read_checkpoint(&p).unwrap();
    assert!(c.steps[0].von_mises.iter().all(|v| v.is_nan()));
    assert!(c.steps[0].info.energy.is_nan());
    assert_eq!(c.steps[0].stress[0][0], f64::INFINITY);
}

#[test]
fn io_error_is_send_sync_for_anyhow() {
    fn check<T: std::error::Error + Send + Sync + 'static>() {}
    check::<IoError>();
}

/// The change fields of `[output] reference_step` go through the checkpoint
/// unchanged, and into the VTU pair with component names; a change of the
/// wrong length is refused before anything is written.
#[test]
fn change_fields_roundtrip_through_hdf5_and_vtu() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.h5");
    let m = mesh(true);
    create_checkpoint(&p, &m, &attrs()).unwrap();
    let s1 = step(0.5, 1.0);
    let mut s2 = step(1.0, 2.0);
    s2.change = Some(Change::between(&s2, &s1, 1));
    let c = s2.change.as_ref().unwrap();
    let d = |s: &StepOutput| s.displacement[2];
    assert_eq!(
        c.displacement[2],
        [d(&s2)[0] - d(&s1)[0], d(&s2)[1] - d(&s1)[1]]
    );
    assert!((c.displacement[2][0] - 0.2).abs() < 1e-15);
    assert_eq!(c.stress[0][0], 1.5e8);
    append_step(&p, 1, &s1).unwrap();
    append_step(&p, 2, &s2).unwrap();
    let ck = read_checkpoint(&p).unwrap();
    assert_eq!(ck.steps[0].change, None);
    assert_eq!(ck.steps[1].change, s2.change);

    let v = dir.path().join("model.vtu");
    write_vtu(&v, &m, &s2, false).unwrap();
    let r = read_vtu_arrays(&v).unwrap();
    let du = r.point_array("displacement_change").unwrap();
    assert_eq!(du.num_comp, 3);
    let c2 = c.displacement[2];
    assert_eq!(du.values[6..9], [c2[0], c2[1], 0.0]);
    let ds = r.cell_array("stress_change").unwrap();
    assert_eq!((ds.num_comp, ds.values[0]), (4, 1.5e8));
    let xml = String::from_utf8_lossy(&std::fs::read(&v).unwrap()).into_owned();
    assert!(xml.contains(r#"ComponentName0="dux""#), "component names");
    let vc = dir.path().join("model_contact.vtu");
    write_contact_vtu(&vc, &m, &s2, false).unwrap();
    let rc = read_vtu_arrays(&vc).unwrap();
    assert_eq!(
        rc.point_array("contact_pressure_change").unwrap().values,
        vec![2e5, 0.0]
    );

    let mut bad = s2.clone();
    bad.change.as_mut().unwrap().stress.pop();
    let q = dir.path().join("bad.vtu");
    assert!(write_vtu(&q, &m, &bad, false).is_err());
    assert!(!q.exists());
    assert!(append_step(&p, 3, &bad).is_err());
    assert_eq!(read_checkpoint(&p).unwrap().steps.len(), 2);
}
