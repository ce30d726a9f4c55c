//! `signorini plot`: PNG and SVG figures of a solved checkpoint (default
//! field, a nodal field at another size, SVG, contact pressure), and bad
//! input that must give exit 2 and no output file.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

mod common;

use common::{root, run_with_deadline, signorini};

/// One solve of two_blocks_eccentric shared by every test: (dir, NAME.h5).
fn checkpoint() -> &'static (tempfile::TempDir, PathBuf) {
    static CK: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    CK.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let problem = root().join("meshes").join("two_blocks_eccentric.toml");
        let (code, stdout, stderr) = signorini(&[
            "solve",
            problem.to_str().unwrap(),
            "--out",
            dir.path().to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(code, 0, "{stdout}\n{stderr}");
        let h5 = dir.path().join("two_blocks_eccentric.h5");
        assert!(h5.is_file());
        (dir, h5)
    })
}

fn h5() -> &'static str {
    checkpoint().1.to_str().unwrap()
}

fn out_dir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// Decodes a PNG: (width, height, number of distinct colours).
fn decode_png(path: &Path) -> (u32, u32, usize) {
    let bytes = std::fs::read(path).unwrap();
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let data = &buf[..info.buffer_size()];
    let colours: HashSet<&[u8]> = data.chunks_exact(channels).collect();
    (info.width, info.height, colours.len())
}

/// Files left in `dir` (a failed plot must leave none, not even a temporary).
fn files_in(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn default_png_is_von_mises_at_1200x900_with_many_colours() {
    let dir = out_dir();
    let fig = dir.path().join("fig.png");
    let (code, stdout, stderr) = signorini(&["plot", h5(), "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("von_mises"), "{stdout}");
    assert!(stdout.contains("displacement scale"), "{stdout}");
    let (w, h, colours) = decode_png(&fig);
    assert_eq!((w, h), (1200, 900));
    assert!(colours > 20, "only {colours} colours");
    assert_eq!(files_in(dir.path()), vec!["fig.png".to_string()]);
}

#[test]
fn nodal_field_png_has_the_requested_size() {
    let dir = out_dir();
    let fig = dir.path().join("uy.png");
    let (code, stdout, stderr) = signorini(&[
        "plot",
        h5(),
        "--field",
        "uy",
        "--width",
        "800",
        "--height",
        "600",
        "-o",
        fig.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let (w, h, colours) = decode_png(&fig);
    assert_eq!((w, h), (800, 600));
    assert!(colours > 20, "only {colours} colours");
}

#[test]
fn categorical_field_and_explicit_scale() {
    let dir = out_dir();
    let fig = dir.path().join("material.png");
    let (code, stdout, stderr) = signorini(&[
        "plot",
        h5(),
        "--field",
        "material",
        "--scale",
        "50",
        "--step",
        "1",
        "-o",
        fig.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("displacement scale: 50"), "{stdout}");
    let (w, h, colours) = decode_png(&fig);
    assert_eq!((w, h), (1200, 900));
    assert!(colours >= 4, "only {colours} colours");
}

#[test]
fn svg_is_well_formed_enough() {
    let dir = out_dir();
    let fig = dir.path().join("fig.svg");
    let (code, stdout, stderr) = signorini(&["plot", h5(), "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let text = std::fs::read_to_string(&fig).unwrap();
    let head = text.trim_start();
    assert!(
        head.starts_with("<svg") || head.starts_with("<?xml"),
        "{}",
        &head[..head.len().min(200)]
    );
    assert!(text.trim_end().ends_with("</svg>"));
    assert!(text.contains("<polygon"), "no triangles drawn");
    assert!(text.contains("two_blocks_eccentric — step 1 — von_mises"));
    assert!(text.contains("von_mises [Pa]"));
}

#[test]
fn contact_pressure_png() {
    let dir = out_dir();
    let fig = dir.path().join("contact.png");
    let (code, stdout, stderr) =
        signorini(&["plot", h5(), "--contact", "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("contact pressure"), "{stdout}");
    let (w, h, colours) = decode_png(&fig);
    assert_eq!((w, h), (1200, 900));
    assert!(colours > 5, "only {colours} colours");
}

#[test]
fn contact_svg_names_the_interface() {
    let dir = out_dir();
    let fig = dir.path().join("contact.svg");
    let (code, stdout, stderr) =
        signorini(&["plot", h5(), "--contact", "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let text = std::fs::read_to_string(&fig).unwrap();
    assert!(text.contains("interface"));
    assert!(text.contains("contact pressure [Pa]"));
    assert!(text.contains("arc length s [m]"));
    // Each interface says where its arc length starts.
    assert!(text.contains("arc length from ("), "no arc-length origin");
}

#[test]
fn range_and_log_set_the_colour_bar() {
    let dir = out_dir();
    let fig = dir.path().join("range.svg");
    let (code, stdout, stderr) = signorini(&[
        "plot",
        h5(),
        "--range",
        "-2e6,3e6",
        "--field",
        "syy",
        "-o",
        fig.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("range: -2e6 to 3e6 Pa (--range)"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(&fig).unwrap();
    // The ends of the colour bar are the given range, with the unit in its title.
    let labels: Vec<&str> = text.lines().map(str::trim).collect();
    assert!(labels.contains(&"-2e6") && labels.contains(&"3e6"), "ticks");
    assert!(text.contains("syy [Pa]"));
    let fig = dir.path().join("log.svg");
    let (code, stdout, stderr) = signorini(&["plot", h5(), "--log", "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("log scale"), "{stdout}");
    let text = std::fs::read_to_string(&fig).unwrap();
    assert!(text.contains("von_mises [Pa] (log)"));
}

#[test]
fn bad_range_is_exit_2() {
    let e = fails(&["--range", "5,1"], "fig.png");
    assert!(e.contains("--range") && e.contains("MIN < MAX"), "{e}");
    let e = fails(&["--range", "abc"], "fig.png");
    assert!(e.contains("--range") && e.contains("MIN,MAX"), "{e}");
    let e = fails(&["--log", "--range", "0,1e6"], "fig.png");
    assert!(e.contains("positive"), "{e}");
    let e = fails(&["--log", "--field", "sxy", "--range", "-1,1"], "fig.png");
    assert!(e.contains("positive"), "{e}");
}

/// Runs a failing plot: exit 2, one line on stderr, no file left behind.
fn fails(extra: &[&str], file: &str) -> String {
    let dir = out_dir();
    let fig = dir.path().join(file);
    let mut args = vec!["plot", h5()];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", fig.to_str().unwrap()]);
    let (code, stdout, stderr) = signorini(&args);
    assert_eq!(code, 2, "{stdout}\n{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
    stderr
}

#[test]
fn step_out_of_range_is_exit_2() {
    let e = fails(&["--step", "5"], "fig.png");
    assert!(e.contains("step"), "{e}");
    let e = fails(&["--step", "0"], "fig.png");
    assert!(e.contains("step"), "{e}");
}

#[test]
fn unknown_field_is_exit_2() {
    let e = fails(&["--field", "nope"], "fig.png");
    assert!(e.contains("nope"), "{e}");
}

#[test]
fn bad_extension_and_size_are_exit_2() {
    let e = fails(&[], "fig.jpg");
    assert!(e.contains(".png"), "{e}");
    let e = fails(&["--width", "10"], "fig.png");
    assert!(e.contains("width"), "{e}");
}

#[test]
fn unreadable_checkpoint_and_unwritable_output_are_exit_2() {
    let dir = out_dir();
    let fig = dir.path().join("fig.png");
    let (code, _, stderr) = signorini(&[
        "plot",
        dir.path().join("missing.h5").to_str().unwrap(),
        "-o",
        fig.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("missing.h5"), "{stderr}");
    // Not an HDF5 file.
    let junk = dir.path().join("junk.h5");
    std::fs::write(&junk, b"not hdf5").unwrap();
    let (code, _, stderr) =
        signorini(&["plot", junk.to_str().unwrap(), "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 2, "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    // Output in a directory that does not exist.
    let bad = dir.path().join("no").join("such").join("fig.png");
    let (code, _, stderr) = signorini(&["plot", h5(), "-o", bad.to_str().unwrap()]);
    assert_eq!(code, 2, "{stderr}");
    assert!(!fig.exists());
}

// ------------------------------------------------------------ issue 34

/// How long a plot may run before the test calls it a hang (a plot of
/// this model takes well under a second).
const HANG: Duration = Duration::from_secs(60);

/// A copy of the shared checkpoint in `dir`, with the f64 dataset `path`
/// passed through `edit` (written with the `hdf5` crate, same shape).
fn edited_checkpoint(dir: &Path, path: &str, edit: impl FnOnce(&mut [f64])) -> PathBuf {
    let copy = dir.join("edited.h5");
    std::fs::copy(h5(), &copy).unwrap();
    {
        let f = hdf5::File::open_rw(&copy).unwrap();
        let ds = f.dataset(path).unwrap();
        let mut v: Vec<f64> = ds.read_raw().unwrap();
        edit(&mut v);
        ds.write_raw(&v).unwrap();
    }
    copy
}

/// Runs `signorini plot CHECKPOINT ARGS -o DIR/FILE` with the hang
/// deadline: (exit code, output, whether the file was written).
fn plot_bounded(dir: &Path, checkpoint: &Path, extra: &[&str], file: &str) -> (i32, String, bool) {
    let fig = dir.join(file);
    let mut args = vec!["plot", checkpoint.to_str().unwrap()];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", fig.to_str().unwrap()]);
    let (code, log) = run_with_deadline(&args, HANG);
    (code, log, fig.exists())
}

/// A range whose span is beyond a double made the pressure axis infinite,
/// and the tick search never ended; now exit 2 naming the option.
#[test]
fn a_range_whose_span_overflows_is_exit_2_not_a_hang() {
    let dir = out_dir();
    let ck = checkpoint().1.clone();
    for extra in [
        &["--contact", "--range=-1e308,1e308"][..],
        &["--range=-1e308,1e308"][..],
    ] {
        let (code, log, written) = plot_bounded(dir.path(), &ck, extra, "fig.png");
        assert_eq!(code, 2, "{extra:?}: {log}");
        assert!(
            log.contains("--range -1e308,1e308") && log.contains("too large"),
            "{log}"
        );
        assert!(!written);
    }
}

/// A contact pressure of 1.7e308: the padded axis overflowed to infinity
/// (a hang); now exit 2 naming the file, the field and the step. The mesh
/// figure of the same file, which does not draw the pressure, still works.
#[test]
fn a_contact_pressure_near_the_largest_double_is_exit_2_not_a_hang() {
    let dir = out_dir();
    let ck = edited_checkpoint(dir.path(), "steps/0001/contact_pressure", |p| {
        p[p.len() / 2] = 1.7e308
    });
    let (code, log, written) = plot_bounded(dir.path(), &ck, &["--contact"], "fig.png");
    assert_eq!(code, 2, "{log}");
    assert!(
        log.contains("edited.h5")
            && log.contains("contact_pressure of step 1")
            && log.contains("--range"),
        "{log}"
    );
    assert!(!written);
    // Within what the axis can hold, the plot is drawn.
    let (code, log, written) = plot_bounded(
        dir.path(),
        &ck,
        &["--contact", "--range", "0,1e6"],
        "fig.svg",
    );
    assert_eq!(code, 0, "{log}");
    assert!(written);
    let (code, log, written) = plot_bounded(dir.path(), &ck, &[], "mesh.png");
    assert_eq!(code, 0, "{log}");
    assert!(written);
}

/// Node coordinates at ±1e308: the bounding box's span overflowed and the
/// axes became infinite (a hang); now exit 2 naming the file and the
/// dataset. The contact figure, which does not use the nodes, still works.
#[test]
fn node_coordinates_at_the_ends_of_the_doubles_are_exit_2_not_a_hang() {
    let dir = out_dir();
    let ck = edited_checkpoint(dir.path(), "mesh/nodes", |xy| {
        let n = xy.len();
        xy[0] = -1e308;
        xy[n - 2] = 1e308;
    });
    for (extra, file) in [(&[][..], "fig.png"), (&["--field", "uy"][..], "fig.svg")] {
        let (code, log, written) = plot_bounded(dir.path(), &ck, extra, file);
        assert_eq!(code, 2, "{extra:?}: {log}");
        assert!(
            log.contains("edited.h5")
                && log.contains("/mesh/nodes")
                && log.contains("x coordinates"),
            "{log}"
        );
        assert!(!written);
    }
    let (code, log, written) = plot_bounded(dir.path(), &ck, &["--contact"], "contact.png");
    assert_eq!(code, 0, "{log}");
    assert!(written);
}

/// `--contact --all-steps --change` with `[output] reference_step = 2`:
/// step 1 has no change fields, and the figure failed; now it draws steps
/// 2 to 4 (one curve each, step 2's being zero) and says that step 1 is
/// left out.
#[test]
fn all_steps_change_starts_at_a_later_reference_step() {
    let dir = out_dir();
    let text = std::fs::read_to_string(root().join("meshes/three_bodies_steps.toml")).unwrap();
    let mesh = root().join("meshes/three_bodies.msh");
    assert!(text.contains("file = \"three_bodies.msh\"") && text.contains("\n[output]\n"));
    let text = text
        .replace(
            "file = \"three_bodies.msh\"",
            &format!("file = {:?}", mesh.to_str().unwrap()),
        )
        .replace("\n[output]\n", "\n[output]\nreference_step = 2\n");
    let toml = dir.path().join("steps.toml");
    std::fs::write(&toml, text).unwrap();
    let out = dir.path().join("out");
    let (code, stdout, stderr) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let ck = out.join("steps.h5");
    let (code, log, written) = plot_bounded(
        dir.path(),
        &ck,
        &["--contact", "--all-steps", "--change"],
        "change.svg",
    );
    assert_eq!(code, 0, "{log}");
    assert!(written);
    assert!(
        log.contains("steps 2 to 4, contact pressure change since the reference step")
            && log.contains("step 1 precedes the reference step 2"),
        "{log}"
    );
    let svg = std::fs::read_to_string(dir.path().join("change.svg")).unwrap();
    assert!(svg.contains("steps 2–4, change since step 2"), "title");
    for k in 2..=4 {
        assert!(
            svg.contains(&format!("step {k} (t = {k})")),
            "legend of step {k}"
        );
    }
    assert!(
        !svg.contains("step 1 (t = 1)"),
        "step 1 has no change to draw"
    );
    // Without --change every step is drawn, as before.
    let (code, log, _) = plot_bounded(dir.path(), &ck, &["--contact", "--all-steps"], "all.png");
    assert_eq!(code, 0, "{log}");
    assert!(
        log.contains("steps 1 to 4, contact pressure") && !log.contains("precede"),
        "{log}"
    );
}

/// A stress component spanning ±1.7e308 has no finite colour scale:
/// exit 2 naming the field (other fields of the file still draw).
#[test]
fn a_field_whose_span_overflows_is_exit_2() {
    let dir = out_dir();
    let ck = edited_checkpoint(dir.path(), "steps/0001/stress", |s| {
        s[0] = -1.7e308;
        s[4] = 1.7e308;
    });
    let (code, log, written) = plot_bounded(dir.path(), &ck, &["--field", "sxx"], "fig.png");
    assert_eq!(code, 2, "{log}");
    assert!(
        log.contains("edited.h5") && log.contains("field sxx") && log.contains("--range"),
        "{log}"
    );
    assert!(!written);
    let (code, log, _) = plot_bounded(
        dir.path(),
        &ck,
        &["--field", "sxx", "--range", "-1e6,1e6"],
        "fig.png",
    );
    assert_eq!(code, 0, "{log}");
    let (code, log, _) = plot_bounded(dir.path(), &ck, &["--field", "uy"], "uy.png");
    assert_eq!(code, 0, "{log}");
}

/// The RGB pixels of a PNG.
fn png_pixels(path: &Path) -> Vec<[u8; 3]> {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    buf[..info.buffer_size()]
        .chunks_exact(ch)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// Issue 35: `plot --contact` of a frictional checkpoint (tests/data/bumps:
/// a pad on two bumps, Coulomb μ = 0.4, stick and slip) draws the
/// tangential traction in its own panel, labelled with its unit, marks
/// stick and slip and shades the slip stretches; the counts it prints are
/// the checkpoint's; a frictionless checkpoint gets none of it.
#[test]
fn contact_plot_with_friction_draws_tangential_traction_stick_and_slip() {
    let dir = out_dir();
    for f in ["bumps.toml", "bumps.msh"] {
        std::fs::copy(root().join("tests/data/bumps").join(f), dir.path().join(f)).unwrap();
    }
    let out = dir.path().join("out");
    let toml = dir.path().join("bumps.toml");
    let (code, so, se) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{so}\n{se}");
    let ck_path = out.join("bumps.h5");
    let ck = signorini::io::hdf5::read_checkpoint(&ck_path).unwrap();
    let state = &ck.friction[0].as_ref().expect("friction arrays").state;
    let n = |v: u8| state.iter().filter(|&&s| s == v).count();
    assert!(n(1) > 0 && n(2) > 0, "stick {} slip {}", n(1), n(2));
    let png = dir.path().join("fig.png");
    let (code, so, se) = signorini(&[
        "plot",
        ck_path.to_str().unwrap(),
        "--contact",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{so}\n{se}");
    assert!(
        so.contains("contact pressure and tangential traction"),
        "{so}"
    );
    assert!(so.contains("tangential traction: "), "{so}");
    let counts = format!("friction: {} rows stick, {} slip", n(1), n(2));
    assert!(so.contains(&counts), "{so} (want {counts})");
    // The slip shading: white under (214, 39, 40) at 12 %.
    let px = png_pixels(&png);
    let band = px
        .iter()
        .filter(|p| p[0] >= 249 && (228..=230).contains(&p[1]) && (228..=230).contains(&p[2]))
        .count();
    assert!(band > 500, "{band} shaded pixels");
    let svg = dir.path().join("fig.svg");
    let (code, so, se) = signorini(&[
        "plot",
        ck_path.to_str().unwrap(),
        "--contact",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{so}\n{se}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.contains("tangential traction [Pa]"),
        "no tangential axis"
    );
    assert!(text.contains("contact pressure [Pa]"));
    assert!(text.contains(&format!("{} rows stick (dots), {} slip", n(1), n(2))));
    // Frictionless: the pressure alone, no friction line.
    let plain = dir.path().join("plain.svg");
    let (code, so, se) = signorini(&["plot", h5(), "--contact", "-o", plain.to_str().unwrap()]);
    assert_eq!(code, 0, "{so}\n{se}");
    assert!(
        !so.contains("tangential") && !so.contains("friction"),
        "{so}"
    );
    let text = std::fs::read_to_string(&plain).unwrap();
    assert!(!text.contains("tangential") && text.contains("contact pressure [Pa]"));
}

/// Issue 35: an axisymmetric checkpoint's stress is (σrr, σzz, σrz, σθθ)
/// (docs/problem-format.md §11): `--field stt` draws and labels the hoop
/// stress (the fourth component, which `szz` used to draw and label as
/// σzz), `szz` the axial stress (the second, the same values as `syy`),
/// `srr`/`srz` the first and third; the axisymmetric names on a plane
/// checkpoint are exit 2, naming the plane field.
#[test]
fn axisymmetric_fields_are_named_srr_szz_srz_stt() {
    let dir = out_dir();
    let text = std::fs::read_to_string(root().join("meshes/two_blocks_eccentric.toml")).unwrap();
    let msh = root().join("meshes/two_blocks_eccentric.msh");
    let text = text
        .replace("plane = \"strain\"", "plane = \"axisymmetric\"")
        .replace(
            "file = \"two_blocks_eccentric.msh\"",
            &format!("file = \"{}\"", msh.display()),
        );
    assert!(text.contains("axisymmetric") && text.contains(msh.to_str().unwrap()));
    let toml = dir.path().join("axi_blocks.toml");
    std::fs::write(&toml, text).unwrap();
    let (code, so, se) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{so}\n{se}");
    let ck = dir.path().join("axi_blocks.h5");
    // (stdout, svg text) of one field.
    let plot = |field: &str| {
        let svg = dir.path().join(format!("{field}.svg"));
        let (code, so, se) = signorini(&[
            "plot",
            ck.to_str().unwrap(),
            "--field",
            field,
            "-o",
            svg.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{field}: {so}\n{se}");
        (so, std::fs::read_to_string(&svg).unwrap())
    };
    let range = |so: &str| {
        so.lines()
            .find(|l| l.starts_with("range: "))
            .unwrap_or_else(|| panic!("no range in {so}"))
            .to_string()
    };
    let (stt_out, stt_svg) = plot("stt");
    assert!(stt_svg.contains("stt [Pa]"), "hoop stress not labelled stt");
    assert!(stt_svg.contains("axi_blocks — step 1 — stt"));
    assert!(stt_out.contains("stt"), "{stt_out}");
    let (szz_out, szz_svg) = plot("szz");
    assert!(szz_svg.contains("szz [Pa]"));
    // szz is the axial stress: syy's values, not the hoop stress's.
    let (syy_out, syy_svg) = plot("syy");
    assert_eq!(range(&szz_out), range(&syy_out));
    assert_ne!(range(&szz_out), range(&stt_out));
    assert!(syy_svg.contains("szz [Pa]"), "syy not labelled szz");
    let (srr_out, srr_svg) = plot("srr");
    let (sxx_out, _) = plot("sxx");
    assert!(srr_svg.contains("srr [Pa]"));
    assert_eq!(range(&srr_out), range(&sxx_out));
    let (srz_out, srz_svg) = plot("srz");
    let (sxy_out, _) = plot("sxy");
    assert!(srz_svg.contains("srz [Pa]"));
    assert_eq!(range(&srz_out), range(&sxy_out));
    // The axisymmetric names on the plane checkpoint.
    for (axi, plane) in [("stt", "szz"), ("srr", "sxx"), ("srz", "sxy")] {
        let e = fails(&["--field", axi], "fig.png");
        assert!(
            e.contains(axi) && e.contains(&format!("\"{plane}\"")),
            "{e}"
        );
    }
}

/// A model in mm and MPa (`[model] units`) is labelled so: the colour bar,
/// the axes, the contact plot and the printed range name its units, not m
/// and Pa. The key is a label only: a checkpoint solved without it is
/// continued (`--restart`) by the same problem with it, and the bits of the
/// solution do not change.
#[test]
fn model_units_label_the_figures() {
    let dir = out_dir();
    let d = dir.path();
    let plain = common::model_variant(
        &common::meshes(),
        "two_blocks_eccentric.toml",
        &[],
        &d.join("m.toml"),
    );
    let out0 = d.join("o0");
    let (code, _, stderr) = signorini(&[
        "solve",
        plain.to_str().unwrap(),
        "--out",
        out0.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let mut text = std::fs::read_to_string(&plain).unwrap();
    assert!(text.contains("[model]\n"), "{text}");
    text = text.replace(
        "[model]\n",
        "[model]\nunits = { length = \"mm\", stress = \"MPa\" }\n",
    );
    std::fs::write(&plain, &text).unwrap();
    let out1 = d.join("o1");
    let (code, _, stderr) = signorini(&[
        "solve",
        plain.to_str().unwrap(),
        "--out",
        out1.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let a = signorini::io::hdf5::read_checkpoint(&out0.join("m.h5")).unwrap();
    let b = signorini::io::hdf5::read_checkpoint(&out1.join("m.h5")).unwrap();
    assert_eq!(a.steps[0].displacement, b.steps[0].displacement);
    let h5 = out1.join("m.h5");
    let fig = d.join("f.svg");
    let (code, stdout, stderr) =
        signorini(&["plot", h5.to_str().unwrap(), "-o", fig.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(&fig).unwrap();
    assert!(
        svg.contains("von_mises [MPa]") && svg.contains("x [mm]"),
        "labels"
    );
    assert!(
        !svg.contains("[Pa]") && !svg.contains("[m]"),
        "SI labels left"
    );
    let range = stdout.lines().find(|l| l.starts_with("range:")).unwrap();
    assert!(range.ends_with(" MPa"), "{range}");
    let scale = stdout
        .lines()
        .find(|l| l.starts_with("displacement"))
        .unwrap();
    assert!(scale.ends_with(" mm)"), "{scale}");
    let cfig = d.join("c.svg");
    let (code, stdout, stderr) = signorini(&[
        "plot",
        h5.to_str().unwrap(),
        "--contact",
        "-o",
        cfig.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(&cfig).unwrap();
    assert!(svg.contains("contact pressure [MPa]") && svg.contains("arc length s [mm]"));
    assert!(stdout.contains(" MPa"), "{stdout}");
    // The SI checkpoint keeps its labels.
    let sfig = d.join("s.svg");
    let (code, _, _) = signorini(&[
        "plot",
        out0.join("m.h5").to_str().unwrap(),
        "-o",
        sfig.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    assert!(std::fs::read_to_string(&sfig)
        .unwrap()
        .contains("von_mises [Pa]"));
    // A restart across the added key is the same problem.
    let out2 = d.join("o2");
    let (code, _, stderr) = signorini(&[
        "solve",
        plain.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
        "--restart",
        out0.join("m.h5").to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 0, "restart refused: {stderr}");
}

/// The friction count of `plot --contact --step 1` is step 1's, and the
/// line says so; it said "(last step drawn)" whatever the step. Two blocks
/// with Coulomb friction, pressed in step 1 and sheared in steps 2 and 3.
#[test]
fn the_friction_count_names_the_step_drawn() {
    let dir = out_dir();
    let d = dir.path();
    let toml = common::model_variant(
        &common::meshes(),
        "two_blocks.toml",
        &[
            ("on = \"left_upper\"", "on = \"left_lower\""),
            ("on = \"right_upper\"", "on = \"right_lower\""),
            ("[[traction]]\non = \"top\"\npn = -1.0e6\n", "[[dirichlet]]\non = \"top\"\nu = [0.0, 0.0]\n"),
            ("normals = \"averaged\"\n", "normals = \"averaged\"\nfriction = 0.3\n[[steps]]\ndirichlet = { top = [0.0, -2.0e-4] }\n[[steps]]\ndirichlet = { top = [2.0e-5, -2.0e-4] }\n[[steps]]\ndirichlet = { top = [4.0e-5, -2.0e-4] }\n"),
        ],
        &d.join("sheared.toml"),
    );
    let out = d.join("out");
    let (code, so, se) = signorini(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(code, 0, "{so}\n{se}");
    let ck_path = out.join("sheared.h5");
    let ck = signorini::io::hdf5::read_checkpoint(&ck_path).unwrap();
    assert_eq!(ck.steps.len(), 3);
    let counts = |k: usize| {
        let s = &ck.friction[k].as_ref().expect("friction arrays").state;
        let n = |v: u8| s.iter().filter(|&&x| x == v).count();
        (n(1), n(2))
    };
    for (step, args) in [
        ("1", vec!["--step", "1"]),
        ("3", vec![]),
        ("3", vec!["--all-steps"]),
    ] {
        let fig = d.join(format!("f{step}{}.svg", args.len()));
        let mut a = vec![
            "plot",
            ck_path.to_str().unwrap(),
            "--contact",
            "-o",
            fig.to_str().unwrap(),
        ];
        a.extend(args.iter().copied());
        let (code, so, se) = signorini(&a);
        assert_eq!(code, 0, "{so}\n{se}");
        let (stick, slip) = counts(step.parse::<usize>().unwrap() - 1);
        let line = so.lines().find(|l| l.starts_with("friction:")).unwrap();
        assert!(
            line.starts_with(&format!(
                "friction: {stick} rows stick, {slip} slip (step {step}"
            )),
            "{args:?}: {line}"
        );
        assert!(!line.contains("last step drawn)"), "{line}");
    }
}
