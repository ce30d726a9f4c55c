//! `signorini plot` of a 3D checkpoint: the section by a plane (`--cut`,
//! by default through the bounding box's centre across its smallest
//! extent) coloured by a field, or the contact footprint (`--contact`).
//! Bad input is one line on stderr and exit 2, no file written, as in 2D.

use super::plot::{parse_range, PlotArgs};
use super::solve::EXIT_BAD_INPUT;
use crate::post::plot::{self, Plane, PlotOptions, SolidField, SolidPlotOptions};

pub fn run(a: &PlotArgs, quiet: bool) -> i32 {
    let fail = |e: String| {
        crate::errln!("error: {e}");
        EXIT_BAD_INPUT
    };
    let field = match SolidField::parse(&a.field) {
        Ok(f) => f,
        Err(e) => return fail(format!("{}: {e}", a.checkpoint.display())),
    };
    let range = match a.range.as_deref().map(parse_range).transpose() {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let cut = match a.cut.as_deref().map(Plane::parse).transpose() {
        Ok(c) => c,
        Err(e) => return fail(e.0),
    };
    let opts = SolidPlotOptions {
        base: PlotOptions {
            range,
            log: a.log,
            change: a.change,
            all_steps: a.all_steps,
            step: a.step,
            scale: a.scale,
            contact: a.contact,
            width: a.width,
            height: a.height,
            edges: match (a.edges, a.no_edges) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
            ..PlotOptions::default()
        },
        field,
        cut,
    };
    let s = match crate::run::plot_solid_file(&a.checkpoint, &a.output, &opts) {
        Ok(s) => s,
        Err(e) => return fail(e.0),
    };
    if quiet {
        return 0;
    }
    let u = &s.units;
    let n = plot::fmt_num;
    crate::outln!(
        "step {} ({} step{} in the file)",
        s.step,
        s.steps,
        if s.steps == 1 { "" } else { "s" }
    );
    if let Some(c) = &s.cut {
        let f = s.field.map_or("", |f| f.name());
        if c.default {
            crate::outln!(
                "cut {} (no --cut or --contact: through the bounding box's centre, across its smallest extent)",
                c.plane.text
            );
        } else {
            crate::outln!("cut {}", c.plane.text);
        }
        crate::outln!(
            "section: {} tetrahedra cut, area {} {}², axes {} and {}",
            c.tets,
            n(c.area),
            u.length,
            c.axes[0],
            c.axes[1]
        );
        let unit = s.field.map_or("", |f| f.unit(u));
        crate::outln!(
            "{f} on the section: {} to {} {unit}",
            n(s.data_range.0),
            n(s.data_range.1)
        );
        if a.range.is_some() || a.log {
            crate::outln!(
                "colour range: {} to {} {unit}{}",
                n(s.range.0),
                n(s.range.1),
                if a.log { " (log scale)" } else { "" }
            );
        }
        if let Some(k) = s.scale {
            crate::outln!(
                "displacement scale: {} ({}; max |u| = {} {})",
                n(k),
                if a.scale.is_some() {
                    "--scale"
                } else {
                    "undeformed; --scale K draws the deformed section"
                },
                n(s.max_displacement),
                u.length
            );
        }
    }
    for i in &s.interfaces {
        crate::outln!(
            "interface {} ({}): {} of {} rows active, max pressure {} {}, area {} {}² ({} {}² active; surface {} {}²), normal ({}, {}, {}), axes {} and {}",
            i.interface,
            i.name,
            i.active,
            i.rows,
            n(i.max_pressure),
            u.stress,
            n(i.area),
            u.length,
            n(i.active_area),
            u.length,
            n(i.surface_area),
            u.length,
            n(i.normal[0]),
            n(i.normal[1]),
            n(i.normal[2]),
            i.axes[0],
            i.axes[1]
        );
        if let (Some(stick), Some(slip)) = (i.stick, i.slip) {
            crate::outln!(
                "friction {}: {stick} rows stick, {slip} slip (the slip zone outlined in white); {} traction arrows, the longest {} {}",
                i.name,
                i.arrows,
                n(i.max_tangential),
                u.stress
            );
        }
    }
    if !s.interfaces.is_empty() {
        crate::outln!(
            "contact pressure drawn: {} to {} {}{}",
            n(s.data_range.0),
            n(s.data_range.1),
            u.stress,
            if a.range.is_some() {
                format!(" (colour range {} to {})", n(s.range.0), n(s.range.1))
            } else {
                String::new()
            }
        );
    }
    crate::outln!("wrote {}", a.output.display());
    0
}
