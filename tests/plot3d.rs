//! `signorini plot` of 3D checkpoints: the section by a plane (`--cut`)
//! and the contact footprint (`--contact`), their numbers held against
//! the checkpoint itself, the step choice on a file with two steps, and
//! bad input (exit 2, one line, no file).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

mod common;

use common::{root, signorini};
use signorini::io::hdf5::{read_solid_checkpoint, SolidSteps};
use signorini::output::SolidCheckpoint;
use signorini::post::plot::{
    render_solid, Format, Plane, PlotOptions, SolidField, SolidPlotOptions,
};

/// Solves `toml` once into its own directory: NAME.h5.
fn solved(cell: &'static OnceLock<(tempfile::TempDir, PathBuf)>, toml: &Path) -> &'static Path {
    &cell
        .get_or_init(|| {
            let dir = tempfile::tempdir().unwrap();
            let (code, stdout, stderr) = signorini(&[
                "solve",
                toml.to_str().unwrap(),
                "--out",
                dir.path().to_str().unwrap(),
                "--quiet",
            ]);
            assert_eq!(code, 0, "{stdout}\n{stderr}");
            let stem = toml.file_stem().unwrap().to_str().unwrap();
            let h5 = dir.path().join(format!("{stem}.h5"));
            assert!(h5.is_file());
            (dir, h5)
        })
        .1
}

fn punch() -> &'static Path {
    static CK: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    solved(&CK, &root().join("meshes/3d/flat_punch_3d.toml"))
}

fn cantilever() -> &'static Path {
    static CK: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    solved(&CK, &root().join("meshes/3d/cantilever_3d.toml"))
}

/// Hertz's sphere on a block (tests/data/solid_contact/hertz.geo), node-to-surface rows.
fn hertz() -> &'static Path {
    static TOML: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    static CK: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let toml = &TOML
        .get_or_init(|| {
            let dir = tempfile::tempdir().unwrap();
            let msh = root().join("tests/data/solid_contact/hertz.msh");
            let text = common::hertz_toml(&msh, -4.664e7, "nts", "max_gap = 0.05\n");
            let p = dir.path().join("hertz.toml");
            std::fs::write(&p, text).unwrap();
            (dir, p)
        })
        .1;
    solved(&CK, toml)
}

fn files_in(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

/// `plot H5 ARGS -o DIR/FILE`: (stdout, the figure's bytes).
fn plots(h5: &Path, args: &[&str], file: &str) -> (String, Vec<u8>) {
    let dir = tempfile::tempdir().unwrap();
    let fig = dir.path().join(file);
    let mut a = vec!["plot", h5.to_str().unwrap()];
    a.extend_from_slice(args);
    a.extend_from_slice(&["-o", fig.to_str().unwrap()]);
    let (code, stdout, stderr) = signorini(&a);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    (stdout, std::fs::read(&fig).unwrap())
}

/// `plot H5 ARGS`: exit 2, one line on stderr, no file; the line.
fn fails(h5: &Path, args: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let fig = dir.path().join("f.png");
    let mut a = vec!["plot", h5.to_str().unwrap()];
    a.extend_from_slice(args);
    a.extend_from_slice(&["-o", fig.to_str().unwrap()]);
    let (code, stdout, stderr) = signorini(&a);
    assert_eq!(code, 2, "{stdout}\n{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
    stderr
}

fn read(h5: &Path) -> SolidCheckpoint {
    read_solid_checkpoint(h5, SolidSteps::Last).unwrap()
}

fn opts(cut: Option<&str>, field: &str, contact: bool) -> SolidPlotOptions {
    SolidPlotOptions {
        base: PlotOptions {
            contact,
            ..PlotOptions::default()
        },
        field: SolidField::parse(field).unwrap(),
        cut: cut.map(|c| Plane::parse(c).unwrap()),
    }
}

fn is_png(b: &[u8]) -> bool {
    b.starts_with(b"\x89PNG")
}

#[test]
fn the_footprint_of_the_flat_punch_covers_its_face_at_the_checkpoints_pressures() {
    let (stdout, png) = plots(punch(), &["--contact"], "f.png");
    assert!(is_png(&png));
    assert!(stdout.contains("118 of 118 rows active"), "{stdout}");
    assert!(stdout.contains("axes x and y"), "{stdout}");
    let ck = read(punch());
    let (_, s) = render_solid(&ck, "p", &opts(None, "von_mises", true), Format::Png).unwrap();
    assert_eq!(s.interfaces.len(), 1);
    let i = &s.interfaces[0];
    assert_eq!(i.name, "punch_bottom/block_top");
    let st = &ck.steps[0];
    let pmax = st.contact_pressure.iter().copied().fold(f64::MIN, f64::max);
    let pmin = st.contact_pressure.iter().copied().fold(f64::MAX, f64::min);
    assert_eq!(i.max_pressure, pmax);
    assert_eq!(s.data_range, (pmin, pmax));
    assert_eq!(i.active, st.active.iter().filter(|&&a| a != 0).count());
    // A flat face: the area drawn is the slave surface's, all of it active,
    // and a quarter disc of radius 0.3 within the faceting.
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(i.area, i.surface_area) < 1e-12, "{i:?}");
    assert!(rel(i.active_area, i.area) < 1e-12, "{i:?}");
    let disc = std::f64::consts::PI * 0.09 / 4.0;
    assert!(i.area < disc && rel(i.area, disc) < 0.01, "{}", i.area);
    assert_eq!(i.normal, [0.0, 0.0, 1.0]);
}

#[test]
fn the_hertz_footprint_is_partly_active_and_its_svg_is_drawn() {
    let (stdout, svg) = plots(hertz(), &["--contact"], "f.svg");
    let svg = String::from_utf8(svg).unwrap();
    assert!(
        svg.contains("<svg") && svg.contains("ball/block_top"),
        "{stdout}"
    );
    assert!(svg.contains("contact_pressure [Pa]"));
    let ck = read(hertz());
    let (_, s) = render_solid(&ck, "h", &opts(None, "von_mises", true), Format::Svg).unwrap();
    let i = &s.interfaces[0];
    let st = &ck.steps[0];
    assert_eq!(
        i.max_pressure,
        st.contact_pressure.iter().copied().fold(f64::MIN, f64::max)
    );
    assert!(i.active > 0 && i.active < i.rows, "{i:?}");
    // The contact zone of radius a ≈ 0.1: a quarter disc of about π a²/4.
    let zone = std::f64::consts::PI * 0.01 / 4.0;
    assert!(
        (i.active_area / zone - 1.0).abs() < 0.25,
        "{}",
        i.active_area
    );
    // A curved surface covers less of its plane than its area.
    assert!(i.area < i.surface_area);
}

/// Mortar rows carry the slave surface's normals: on the quarter sphere
/// their plain mean leans 12° from the block's normal, and the footprint
/// is drawn in the plane of the contact zone (normals weighted by the
/// pressure), the block's top z = 0 within the quarter cap's curvature
/// (a/R = 0.1: 2.6° here, under 3.6° asked).
#[test]
fn a_curved_slave_surface_is_drawn_in_the_plane_of_its_contact_zone() {
    let dir = tempfile::tempdir().unwrap();
    let msh = root().join("tests/data/solid_contact/hertz.msh");
    let toml = dir.path().join("hm.toml");
    std::fs::write(&toml, common::hertz_toml(&msh, -4.664e7, "mortar", "")).unwrap();
    static CK: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let ck = read(solved(&CK, &toml));
    let (_, s) = render_solid(&ck, "hm", &opts(None, "von_mises", true), Format::Png).unwrap();
    let n = s.interfaces[0].normal;
    let mut plain = [0.0f64; 3];
    for v in &ck.contact.normal {
        for k in 0..3 {
            plain[k] += v[k];
        }
    }
    let len = plain.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(plain[2].abs() / len < 0.98, "the plain mean {plain:?}");
    assert!(n[2].abs() > 0.998, "{n:?}");
}

/// The tetrahedra strictly on both sides of z = c and the range of their von Mises stress.
fn crossing(ck: &SolidCheckpoint, c: f64) -> (usize, (f64, f64)) {
    let mut n = 0;
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for (k, t) in ck.tets.iter().enumerate() {
        let z = t.map(|i| ck.points[i][2]);
        if z.iter().any(|&v| v < c) && z.iter().any(|&v| v > c) {
            n += 1;
            lo = lo.min(ck.steps[0].von_mises[k]);
            hi = hi.max(ck.steps[0].von_mises[k]);
        }
    }
    (n, (lo, hi))
}

#[test]
fn a_cut_shows_the_values_of_the_tetrahedra_it_crosses() {
    let (stdout, png) = plots(punch(), &["--cut", "z=0.2345"], "c.png");
    assert!(is_png(&png));
    assert!(
        stdout.contains("cut z = 0.2345") && stdout.contains("axes x and y"),
        "{stdout}"
    );
    let ck = read(punch());
    let (n, range) = crossing(&ck, 0.2345);
    let (_, s) = render_solid(
        &ck,
        "p",
        &opts(Some("z=0.2345"), "von_mises", false),
        Format::Png,
    )
    .unwrap();
    let cut = s.cut.as_ref().unwrap();
    assert_eq!(cut.tets, n);
    assert_eq!(s.data_range, range);
    assert_eq!(s.range, range);
    // The block is 1 × 1 (a quarter of 2 × 2) at that height.
    assert!((cut.area - 1.0).abs() < 1e-9, "{}", cut.area);
    // The same plane given by a point and a normal.
    let (_, g) = render_solid(
        &ck,
        "p",
        &opts(Some("0.3,0.1,0.2345,0,0,-2"), "von_mises", false),
        Format::Png,
    )
    .unwrap();
    assert_eq!(g.cut.as_ref().unwrap().tets, n);
    assert_eq!(g.data_range, range);
    // The mesh's top and bottom faces: the punch's top, the block's base.
    for (z, area) in [(0.8, std::f64::consts::PI * 0.09 / 4.0), (0.0, 1.0)] {
        let (_, s) = render_solid(
            &ck,
            "p",
            &opts(Some(&format!("z={z}")), "von_mises", false),
            Format::Png,
        )
        .unwrap();
        assert!((s.cut.unwrap().area / area - 1.0).abs() < 0.01, "z = {z}");
    }
    // Through the punch (0 < x < 0.3 above z = 0.5): its area is a quarter disc.
    let (_, p) = render_solid(&ck, "p", &opts(Some("z=0.65"), "szz", false), Format::Png).unwrap();
    let a = p.cut.unwrap().area;
    assert!(
        (a / (std::f64::consts::PI * 0.09 / 4.0) - 1.0).abs() < 0.01,
        "{a}"
    );
    assert!(
        p.data_range.1 < 0.0,
        "the punch is in compression: {:?}",
        p.data_range
    );
}

#[test]
fn nodal_fields_on_a_deformed_cut_and_every_3d_name() {
    let (stdout, svg) = plots(
        punch(),
        &["--cut", "y=0.1", "--field", "uz", "--scale", "500"],
        "u.svg",
    );
    assert!(String::from_utf8(svg).unwrap().contains("uz [m]"));
    assert!(
        stdout.contains("displacement scale: 500 (--scale"),
        "{stdout}"
    );
    let ck = read(punch());
    let (_, s) = render_solid(&ck, "p", &opts(Some("y=0.1"), "uz", false), Format::Png).unwrap();
    // The punch's top is pushed down 0.1 mm; nothing rises by more than that.
    assert!((s.data_range.0 + 1e-4).abs() < 1e-12, "{:?}", s.data_range);
    for f in SolidField::names() {
        let (_, s) = render_solid(&ck, "p", &opts(Some("x=0.15"), f, false), Format::Png).unwrap();
        assert!(s.data_range.0 <= s.data_range.1, "{f}");
    }
}

#[test]
fn a_3d_checkpoint_without_cut_or_contact_is_cut_across_its_smallest_extent() {
    let (stdout, png) = plots(
        cantilever(),
        &["--width", "800", "--height", "400"],
        "d.png",
    );
    assert!(is_png(&png));
    assert!(
        stdout.contains("cut y = 0.1 (no --cut or --contact"),
        "{stdout}"
    );
    assert!(stdout.contains("axes x and z"), "{stdout}");
}

#[test]
fn bad_3d_input_is_exit_2_with_no_file() {
    let e = fails(punch(), &["--cut", "z=5"]);
    assert!(
        e.contains("misses the mesh") && e.contains("z runs from 0 to 0.8"),
        "{e}"
    );
    let e = fails(punch(), &["--cut", "1,1,9,0,1,1"]);
    assert!(e.contains("misses the mesh"), "{e}");
    let e = fails(punch(), &["--cut", "w=1"]);
    assert!(e.contains("expected x=A"), "{e}");
    let e = fails(punch(), &["--cut", "z=0.3", "--field", "srr"]);
    assert!(
        e.contains("not a field of a 3D checkpoint") && e.contains("syz"),
        "{e}"
    );
    let e = fails(punch(), &["--field", "material"]);
    assert!(e.contains("not a field of a 3D checkpoint"), "{e}");
    let e = fails(cantilever(), &["--contact"]);
    assert!(e.contains("no contact rows"), "{e}");
    let e = fails(punch(), &["--step", "2"]);
    assert!(
        e.contains("step 2 out of range") && e.contains("1 step (1)"),
        "{e}"
    );
    let e = fails(punch(), &["--change"]);
    assert!(e.contains("2D checkpoints only"), "{e}");
    let e = fails(punch(), &["--contact", "--scale", "2"]);
    assert!(e.contains("--scale"), "{e}");
    let e = fails(punch(), &["--cut", "z=0.3", "--range", "2,1"]);
    assert!(e.contains("--range"), "{e}");
}

#[test]
fn cut_on_a_2d_checkpoint_is_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = signorini(&[
        "solve",
        root().join("meshes/two_blocks.toml").to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let e = fails(&dir.path().join("two_blocks.h5"), &["--cut", "z=0"]);
    assert!(e.contains("this one is 2D"), "{e}");
}

/// A copy of the punch's checkpoint with a second step, its displacement
/// twice the first's, and `last_step` = 2 (the layout of load steps).
fn two_steps(dir: &Path) -> PathBuf {
    let h5 = dir.join("two.h5");
    std::fs::copy(punch(), &h5).unwrap();
    let f = hdf5::File::open_rw(&h5).unwrap();
    let s1 = f.group("steps/0001").unwrap();
    let s2 = f.group("steps").unwrap().create_group("0002").unwrap();
    for name in s1.member_names().unwrap() {
        let ds = s1.dataset(&name).unwrap();
        let shape = ds.shape();
        if name == "active" {
            let v: Vec<u8> = ds.read_raw().unwrap();
            let d = s2
                .new_dataset::<u8>()
                .shape(shape)
                .create(name.as_str())
                .unwrap();
            d.write_raw(&v).unwrap();
        } else {
            let mut v: Vec<f64> = ds.read_raw().unwrap();
            if name == "displacement" {
                v.iter_mut().for_each(|x| *x *= 2.0);
            }
            let d = s2
                .new_dataset::<f64>()
                .shape(shape)
                .create(name.as_str())
                .unwrap();
            d.write_raw(&v).unwrap();
        }
    }
    for a in s1.attr_names().unwrap() {
        let at = s1.attr(&a).unwrap();
        let td = at.dtype().unwrap().to_descriptor().unwrap();
        use hdf5::types::TypeDescriptor as T;
        match td {
            T::Float(_) => {
                let v: f64 = at.read_scalar().unwrap();
                s2.new_attr::<f64>()
                    .create(a.as_str())
                    .unwrap()
                    .write_scalar(&v)
                    .unwrap();
            }
            T::Unsigned(hdf5::types::IntSize::U1) => {
                let v: u8 = at.read_scalar().unwrap();
                s2.new_attr::<u8>()
                    .create(a.as_str())
                    .unwrap()
                    .write_scalar(&v)
                    .unwrap();
            }
            T::Unsigned(_) => {
                let v: u64 = at.read_scalar().unwrap();
                s2.new_attr::<u64>()
                    .create(a.as_str())
                    .unwrap()
                    .write_scalar(&v)
                    .unwrap();
            }
            _ => {
                let v: hdf5::types::VarLenUnicode = at.read_scalar().unwrap();
                s2.new_attr::<hdf5::types::VarLenUnicode>()
                    .create(a.as_str())
                    .unwrap()
                    .write_scalar(&v)
                    .unwrap();
            }
        }
    }
    f.attr("last_step").unwrap().write_scalar(&2u64).unwrap();
    h5
}

#[test]
fn the_last_step_is_drawn_unless_step_says_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = two_steps(dir.path());
    let all = read_solid_checkpoint(&h5, SolidSteps::All).unwrap();
    assert_eq!(all.step_indices, [1, 2]);
    assert_eq!(all.steps.len(), 2);
    let last = read(&h5);
    assert_eq!((last.steps.len(), last.steps[0].index), (1, 2));
    let one = read_solid_checkpoint(&h5, SolidSteps::One(1)).unwrap();
    assert_eq!(one.steps[0].index, 1);
    assert_eq!(
        last.steps[0].displacement[5][2],
        2.0 * one.steps[0].displacement[5][2]
    );
    let (stdout, _) = plots(&h5, &["--cut", "y=0.1", "--field", "uz"], "s.png");
    assert!(stdout.contains("step 2 (2 steps in the file)"), "{stdout}");
    assert!(stdout.contains("uz on the section: -2e-4"), "{stdout}");
    let (stdout, _) = plots(
        &h5,
        &["--cut", "y=0.1", "--field", "uz", "--step", "1"],
        "s.png",
    );
    assert!(stdout.contains("step 1 (2 steps in the file)"), "{stdout}");
    assert!(stdout.contains("uz on the section: -1e-4"), "{stdout}");
    let e = fails(&h5, &["--step", "3"]);
    assert!(e.contains("2 steps (1 to 2)"), "{e}");
}

#[test]
fn a_conforming_interface_under_uniform_pressure_is_one_colour() {
    let dir = tempfile::tempdir().unwrap();
    let msh = root().join("tests/data/solid_contact/stack.msh");
    let toml = format!(
        "[mesh]\nfile = \"{}\"\n[materials.lower]\nE = 2.0e11\nnu = 0.3\n[materials.upper]\nE = 7.0e10\nnu = 0.25\n\
         [[slip]]\non = \"x0\"\n[[slip]]\non = \"y0\"\n[[slip]]\non = \"bottom\"\n\
         [[traction]]\non = \"top\"\npn = -1.0e6\n[[contact]]\non = \"interface\"\n",
        msh.display()
    );
    let p = dir.path().join("stack.toml");
    std::fs::write(&p, toml).unwrap();
    let (code, stdout, stderr) = signorini(&[
        "solve",
        p.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let h5 = dir.path().join("stack.h5");
    let (stdout, _) = plots(&h5, &["--contact"], "f.png");
    assert!(
        stdout.contains("interface 0 (interface): 45 of 45 rows active"),
        "{stdout}"
    );
    let ck = read(&h5);
    let (_, s) = render_solid(&ck, "s", &opts(None, "von_mises", true), Format::Png).unwrap();
    let i = &s.interfaces[0];
    assert!((i.area - 1.0).abs() < 1e-12 && (i.surface_area - 1.0).abs() < 1e-12);
    // 1 MPa within rounding: one colour, the scale collapsed to its middle.
    let (lo, hi) = s.data_range;
    assert!(
        (lo / 1e6 - 1.0).abs() < 1e-9 && (hi / 1e6 - 1.0).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert_eq!(s.range.0, s.range.1);
}

#[test]
fn a_split_checkpoint_is_read_through_its_links() {
    let dir = tempfile::tempdir().unwrap();
    let data = two_steps(dir.path());
    let idx = dir.path().join("idx.h5");
    {
        let f = hdf5::File::create(&idx).unwrap();
        let src = hdf5::File::open(&data).unwrap();
        for a in ["model", "toml"] {
            let v: hdf5::types::VarLenUnicode = src.attr(a).unwrap().read_scalar().unwrap();
            f.new_attr::<hdf5::types::VarLenUnicode>()
                .create(a)
                .unwrap()
                .write_scalar(&v)
                .unwrap();
        }
        for (a, v) in [("dim", 3u64), ("last_step", 1u64)] {
            f.new_attr::<u64>()
                .create(a)
                .unwrap()
                .write_scalar(&v)
                .unwrap();
        }
        f.link_external("two.h5", "/mesh", "mesh").unwrap();
        let s = f.create_group("steps").unwrap();
        for n in ["0001", "0002"] {
            s.link_external("two.h5", &format!("/steps/{n}"), n)
                .unwrap();
        }
    }
    // last_step = 1 names the step drawn by default, though 0002 exists.
    let (stdout, _) = plots(&idx, &["--cut", "y=0.1", "--field", "uz"], "s.png");
    assert!(stdout.contains("step 1 (2 steps in the file)"), "{stdout}");
    assert!(stdout.contains("uz on the section: -1e-4"), "{stdout}");
    let (stdout, _) = plots(&idx, &["--contact", "--step", "2"], "s.png");
    assert!(stdout.contains("step 2 (2 steps in the file)"), "{stdout}");
    std::fs::remove_file(&data).unwrap();
    let e = fails(&idx, &["--contact"]);
    assert!(e.contains("two.h5") && e.contains("does not exist"), "{e}");
}

#[test]
fn a_3d_run_with_load_steps_draws_each_step() {
    let dir = tempfile::tempdir().unwrap();
    let msh = root().join("meshes/3d/flat_punch_3d.msh");
    let text = std::fs::read_to_string(root().join("meshes/3d/flat_punch_3d.toml"))
        .unwrap()
        .replace(
            "file = \"flat_punch_3d.msh\"",
            &format!("file = \"{}\"", msh.display()),
        );
    let toml = dir.path().join("fp.toml");
    std::fs::write(
        &toml,
        format!("{text}\n[[steps]]\nfactor = 0.5\n[[steps]]\nfactor = 1.0\n"),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (code, stdout, stderr) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let h5 = out.join("fp.h5");
    assert!(out.join("fp_0002.h5").is_file(), "the split layout");
    let all = read_solid_checkpoint(&h5, SolidSteps::All).unwrap();
    assert_eq!(all.step_indices, [1, 2]);
    for (k, st) in all.steps.iter().enumerate() {
        let one = read_solid_checkpoint(&h5, SolidSteps::One(k + 1)).unwrap();
        let (_, s) = render_solid(&one, "fp", &opts(None, "von_mises", true), Format::Png).unwrap();
        let pmax = st.contact_pressure.iter().copied().fold(f64::MIN, f64::max);
        assert_eq!((s.step, s.steps), (k + 1, 2));
        assert_eq!(s.interfaces[0].max_pressure, pmax);
    }
    let (stdout, _) = plots(&h5, &["--contact"], "f.png");
    assert!(stdout.contains("step 2 (2 steps in the file)"), "{stdout}");
    let (stdout, _) = plots(&h5, &["--cut", "z=0.3", "--step", "1"], "f.svg");
    assert!(stdout.contains("step 1 (2 steps in the file)"), "{stdout}");
}
