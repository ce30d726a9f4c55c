//! `signorini plot`: a PNG or SVG figure of an HDF5 checkpoint: the
//! deformed mesh coloured by a field, or (`--contact`) the contact pressure
//! along each interface (with friction data, the tangential traction under
//! it, stick and slip rows marked). Bad input (unreadable file, step out of range,
//! unknown field, bad extension or size, unwritable output) is one line on
//! stderr and exit 2, with no output file written.

use super::solve::EXIT_BAD_INPUT;
use crate::post::plot::{self, Field, PlotOptions};
use clap::Args;
use std::path::PathBuf;

// clap prints these doc comments as `--help`: brackets such as [px] stay
// literal there, so rustdoc must not read them as links.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone)]
pub struct PlotArgs {
    /// The HDF5 checkpoint written by `solve` (NAME.h5).
    pub checkpoint: PathBuf,
    /// Output file: .png or .svg.
    #[arg(long, short)]
    pub output: PathBuf,
    /// Step to draw (1-based; default: the last one; 3D: the number of
    /// the group /steps/NNNN, default the root's last_step).
    #[arg(long)]
    pub step: Option<usize>,
    /// von_mises | ux | uy | umag | sxx | syy | sxy | szz | s1 | s2 | material | body;
    /// axisymmetric models: srr | szz (axial) | srz | stt (hoop);
    /// 3D (with --cut): von_mises | sxx | syy | szz | sxy | syz | sxz | s1 | s2 | s3 |
    /// ux | uy | uz | umag.
    #[arg(long, default_value = "von_mises")]
    pub field: String,
    /// 3D checkpoints: draw the section of the tetrahedra by a plane, x=A,
    /// y=A, z=A or PX,PY,PZ,NX,NY,NZ (a point and a normal), in the plane's
    /// own axes. Without --cut or --contact a 3D checkpoint is cut through
    /// the centre of its bounding box across its smallest extent.
    #[arg(
        long,
        allow_hyphen_values = true,
        value_name = "PLANE",
        conflicts_with = "contact"
    )]
    pub cut: Option<String>,
    /// Displacement magnification (default: the largest displacement drawn
    /// as 5 % of the bounding-box diagonal; 3D sections: 0, undeformed).
    #[arg(long, allow_negative_numbers = true)]
    pub scale: Option<f64>,
    /// Plot the contact pressure along each interface against arc length
    /// (and, when the checkpoint has friction data, the tangential traction
    /// under it with stick and slip rows marked). 3D: the footprint, each
    /// interface's slave surface in its own plane filled by the pressure,
    /// the active set outlined.
    #[arg(long)]
    pub contact: bool,
    /// Image width [px].
    #[arg(long, default_value_t = 1200)]
    pub width: u32,
    /// Image height [px].
    #[arg(long, default_value_t = 900)]
    pub height: u32,
    /// Draw the triangle edges (default: when the triangles are large enough).
    #[arg(long, conflicts_with = "no_edges")]
    pub edges: bool,
    /// Never draw the triangle edges.
    #[arg(long)]
    pub no_edges: bool,
    /// Colour range MIN,MAX of the field (or the pressure axis with
    /// --contact; 3D: the footprint's colours); values outside get the end
    /// colours. Default: the data's range.
    #[arg(long, allow_hyphen_values = true, value_name = "MIN,MAX")]
    pub range: Option<String>,
    /// Logarithmic colour scale (values ≤ 0 get the bottom colour).
    #[arg(long)]
    pub log: bool,
    /// Draw the change since the reference step ([output] reference_step):
    /// displacement_change, stress_change, contact_pressure_change.
    #[arg(long)]
    pub change: bool,
    /// With --contact: every step of the checkpoint in one figure, one
    /// curve per step (a load-step sequence). With --change: the steps from
    /// the reference step on (the earlier ones have no change to draw).
    #[arg(long, conflicts_with = "step")]
    pub all_steps: bool,
}

/// "MIN,MAX" as two numbers.
pub(super) fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("--range {s}: expected MIN,MAX (two numbers, e.g. 0,2e8)");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let lo: f64 = a.trim().parse().map_err(|_| bad())?;
    let hi: f64 = b.trim().parse().map_err(|_| bad())?;
    Ok((lo, hi))
}

pub fn run(a: &PlotArgs, quiet: bool) -> i32 {
    if crate::io::hdf5::is_solid_checkpoint(&a.checkpoint) {
        return super::plot3d::run(a, quiet);
    }
    if a.cut.is_some() {
        crate::errln!(
            "error: {}: --cut draws a section of a 3D checkpoint; this one is 2D (draw it without --cut)",
            a.checkpoint.display()
        );
        return EXIT_BAD_INPUT;
    }
    let field = match Field::parse(&a.field) {
        Ok(f) => f,
        Err(e) => {
            crate::errln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let range = match a.range.as_deref().map(parse_range).transpose() {
        Ok(r) => r,
        Err(e) => {
            crate::errln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let opts = PlotOptions {
        range,
        log: a.log,
        change: a.change,
        all_steps: a.all_steps,
        step: a.step,
        field,
        scale: a.scale,
        contact: a.contact,
        width: a.width,
        height: a.height,
        edges: match (a.edges, a.no_edges) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            _ => None,
        },
        // Set from the checkpoint's problem by the renderer.
        units: Default::default(),
    };
    match crate::run::plot_file(&a.checkpoint, &a.output, &opts) {
        Ok(s) => {
            if !quiet {
                let what = if a.contact && s.stick_slip.is_some() {
                    "contact pressure and tangential traction".to_string()
                } else if a.contact {
                    "contact pressure".to_string()
                } else {
                    s.field.name().to_string()
                };
                let what = if a.change {
                    format!("{what} change since the reference step")
                } else {
                    what
                };
                // The units of the checkpoint's problem ([model] units).
                let u = &s.units;
                let unit = if a.contact {
                    format!(" {}", u.stress)
                } else {
                    s.field.unit(u).map(|x| format!(" {x}")).unwrap_or_default()
                };
                if a.all_steps {
                    crate::outln!("steps {} to {}, {what}", s.first_step, s.steps);
                    // With --change the figure starts at the reference step.
                    match s.first_step {
                        1 => {}
                        2 => crate::outln!("step 1 precedes the reference step 2: no change to draw, left out"),
                        f => crate::outln!(
                            "steps 1 to {} precede the reference step {f}: no change to draw, left out",
                            f - 1
                        ),
                    }
                } else {
                    crate::outln!("step {} of {}, {what}", s.step, s.steps);
                }
                if let Some((lo, hi)) = s.range {
                    crate::outln!(
                        "range: {} to {}{unit}{}",
                        plot::fmt_num(lo),
                        plot::fmt_num(hi),
                        match (a.range.is_some(), a.log) {
                            (true, true) => " (--range, log scale)",
                            (true, false) => " (--range)",
                            (false, true) => " (positive values, log scale)",
                            (false, false) => "",
                        }
                    );
                }
                if let Some((lo, hi)) = s.tangential_range {
                    crate::outln!(
                        "tangential traction: {} to {} {}",
                        plot::fmt_num(lo),
                        plot::fmt_num(hi),
                        u.stress
                    );
                }
                if let Some((stick, slip)) = s.stick_slip {
                    // Of the step drawn; with --all-steps, of the last one.
                    if a.all_steps {
                        crate::outln!(
                            "friction: {stick} rows stick, {slip} slip (step {}, the last drawn)",
                            s.steps
                        );
                    } else {
                        crate::outln!(
                            "friction: {stick} rows stick, {slip} slip (step {})",
                            s.step
                        );
                    }
                }
                if let Some(k) = s.scale {
                    let how = if a.scale.is_some() {
                        "--scale"
                    } else {
                        "largest displacement = 5 % of the bounding-box diagonal"
                    };
                    crate::outln!(
                        "displacement scale: {} ({how}; max |u| = {} {})",
                        plot::fmt_num(k),
                        plot::fmt_num(s.max_displacement),
                        u.length
                    );
                }
                crate::outln!("wrote {}", a.output.display());
            }
            0
        }
        Err(e) => {
            crate::errln!("error: {e}");
            EXIT_BAD_INPUT
        }
    }
}
