//! The figures of a 3D checkpoint: a section of the tetrahedra by a plane
//! coloured by a field (`--cut`), or the contact footprint of each
//! interface (`--contact`), both drawn flat in the plane's own axes by
//! [`super::panel`].

use super::colorbar::{finite_range, scale_of};
use super::cut::{misses, polygon_area, section, Frame, Plane, V3};
use super::footprint::{footprints, interface_names, FootprintSummary};
use super::panel::{draw_panels, Fill, Panel, P2};
use super::style::{de, encode_png, font_size, register_fonts};
use super::{check_options, err, Format, PlotError, PlotOptions, Units};
use crate::fem::ElementKind;
use crate::output::{SolidCheckpoint, SolidStep};
use plotters::prelude::*;

/// What colours a section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolidField {
    VonMises,
    /// Stress component k of (sxx, syy, szz, sxy, syz, sxz).
    Stress(usize),
    /// Principal stress s1, s2, s3 (k = 0, 1, 2).
    Principal(usize),
    /// Displacement component ux, uy, uz.
    U(usize),
    Umag,
}

impl SolidField {
    /// Every name `--field` takes on a 3D checkpoint.
    pub fn names() -> Vec<&'static str> {
        let mut v = vec!["von_mises"];
        v.extend_from_slice(ElementKind::Solid.stress_names());
        v.extend_from_slice(&["s1", "s2", "s3", "ux", "uy", "uz", "umag"]);
        v
    }

    pub fn parse(s: &str) -> Result<SolidField, PlotError> {
        let stress = ElementKind::Solid.stress_names();
        let f = match s {
            "von_mises" => SolidField::VonMises,
            "s1" => SolidField::Principal(0),
            "s2" => SolidField::Principal(1),
            "s3" => SolidField::Principal(2),
            "ux" => SolidField::U(0),
            "uy" => SolidField::U(1),
            "uz" => SolidField::U(2),
            "umag" => SolidField::Umag,
            _ => match stress.iter().position(|n| *n == s) {
                Some(k) => SolidField::Stress(k),
                None => {
                    return Err(err(format!(
                        "field \"{s}\" is not a field of a 3D checkpoint; known: {}",
                        SolidField::names().join(", ")
                    )))
                }
            },
        };
        Ok(f)
    }

    pub fn name(self) -> &'static str {
        match self {
            SolidField::VonMises => "von_mises",
            SolidField::Stress(k) => ElementKind::Solid.stress_names()[k],
            SolidField::Principal(k) => ["s1", "s2", "s3"][k],
            SolidField::U(k) => ["ux", "uy", "uz"][k],
            SolidField::Umag => "umag",
        }
    }

    pub fn nodal(self) -> bool {
        matches!(self, SolidField::U(_) | SolidField::Umag)
    }

    pub fn unit(self, units: &Units) -> &str {
        if self.nodal() {
            &units.length
        } else {
            &units.stress
        }
    }
}

/// What to draw of a 3D checkpoint: the 2D options that apply (step,
/// contact, scale, size, edges, range, log), the field and the plane.
#[derive(Debug, Clone)]
pub struct SolidPlotOptions {
    pub base: PlotOptions,
    pub field: SolidField,
    /// The cutting plane; None (and no `base.contact`): the default cut.
    pub cut: Option<Plane>,
}

/// What a section showed.
#[derive(Debug, Clone)]
pub struct CutSummary {
    pub plane: Plane,
    /// Chosen by `plot` (no `--cut`): through the bounding box's centre,
    /// across its smallest extent.
    pub default: bool,
    /// Tetrahedra cut (polygons of nonzero area) and the section's area
    /// (undeformed) \[m²\].
    pub tets: usize,
    pub area: f64,
    pub axes: [String; 2],
}

/// What was drawn of a 3D checkpoint.
#[derive(Debug, Clone)]
pub struct SolidPlotSummary {
    /// The step drawn (its group number) and the step groups in the file.
    pub step: usize,
    pub steps: usize,
    /// The field (None for the footprint).
    pub field: Option<SolidField>,
    /// The colour scale, and the range of the values drawn.
    pub range: (f64, f64),
    pub data_range: (f64, f64),
    /// The displacement scale of the section (0: undeformed).
    pub scale: Option<f64>,
    pub max_displacement: f64,
    pub cut: Option<CutSummary>,
    pub interfaces: Vec<FootprintSummary>,
    pub units: Units,
}

/// Draws the figure of the one step `ck` holds (read with
/// [`crate::io::hdf5::SolidSteps`]); `name` titles it.
pub fn render_solid(
    ck: &SolidCheckpoint,
    name: &str,
    opts: &SolidPlotOptions,
    format: Format,
) -> Result<(Vec<u8>, SolidPlotSummary), PlotError> {
    let o = &opts.base;
    check_options(o)?;
    if o.change || o.all_steps {
        return Err(err(
            "--change and --all-steps draw load steps of 2D checkpoints only (not yet 3D)",
        ));
    }
    if o.contact && opts.cut.is_some() {
        return Err(err("--contact and --cut exclude each other"));
    }
    if o.contact && o.scale.is_some() {
        return Err(err(
            "--scale deforms the section (--cut); the footprint is drawn undeformed",
        ));
    }
    let Some(step) = ck.steps.last() else {
        return Err(err("the checkpoint holds no step"));
    };
    check_consistent(ck, step)?;
    let problem = ck
        .attrs
        .iter()
        .find(|(k, _)| k == "toml" || k == "problem_toml")
        .map(|(_, t)| t.as_str())
        .unwrap_or("");
    let units = Units::of_problem_text(problem);
    let max_u = step
        .displacement
        .iter()
        .map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let mut summary = SolidPlotSummary {
        step: step.index,
        steps: ck.step_indices.len(),
        field: None,
        range: (0.0, 0.0),
        data_range: (0.0, 0.0),
        scale: None,
        max_displacement: max_u,
        cut: None,
        interfaces: vec![],
        units: units.clone(),
    };
    let (title, panels, label, values) = if o.contact {
        if ck.contact.slave.is_empty() {
            return Err(err(
                "--contact: the checkpoint has no contact rows (its problem has no [[contact]])",
            ));
        }
        let names = interface_names(problem);
        let (panels, sums) = footprints(ck, step, &names, &units.length);
        if panels.is_empty() {
            return Err(err(
                "--contact: the contact rows have no slave triangles to draw",
            ));
        }
        summary.interfaces = sums;
        let values: Vec<f64> = panels
            .iter()
            .flat_map(|p| match &p.fill {
                Fill::Nodal(v) | Fill::Cell(v) => v.clone(),
            })
            .collect();
        let title = format!(
            "{name} — step {} — contact pressure footprint, active set outlined red",
            step.index
        );
        let label = format!("contact_pressure [{}]", units.stress);
        (title, panels, label, values)
    } else {
        let (plane, default) = match &opts.cut {
            Some(p) => (p.clone(), false),
            None => (default_plane(&ck.points), true),
        };
        let scale = o.scale.unwrap_or(0.0);
        let (panel, values, cut) = cut_panel(ck, step, &plane, opts.field, scale, &units)?;
        summary.field = Some(opts.field);
        summary.scale = Some(scale);
        summary.cut = Some(CutSummary { default, ..cut });
        let title = format!(
            "{name} — step {} — {} on the cut {}",
            step.index,
            opts.field.name(),
            plane.text
        );
        let label = format!("{} [{}]", opts.field.name(), opts.field.unit(&units));
        (title, vec![panel], label, values)
    };
    let what = summary.field.map_or("contact_pressure", |f| f.name());
    let mut cs = scale_of(&values, o.range, o.log, what, false)?;
    // A field uniform but for rounding (a stacked block's pressure) is one
    // colour with one tick, not its noise stretched over the map.
    if o.range.is_none() && !o.log && cs.hi - cs.lo <= 1e-9 * cs.lo.abs().max(cs.hi.abs()) {
        let mid = 0.5 * (cs.lo + cs.hi);
        (cs.lo, cs.hi) = (mid, mid);
    }
    summary.range = (cs.lo, cs.hi);
    summary.data_range = finite_range(&values);
    register_fonts();
    let (w, h) = (o.width, o.height);
    let fs = font_size(w, h);
    let bytes = match format {
        Format::Png => {
            let mut buf = vec![255u8; (w as usize) * (h as usize) * 3];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw_panels(&root, true, &title, &panels, cs, &label, fs, o.edges)?;
                root.present().map_err(de)?;
            }
            encode_png(&buf, w, h)?
        }
        Format::Svg => {
            let mut s = String::new();
            {
                let root = SVGBackend::with_string(&mut s, (w, h)).into_drawing_area();
                draw_panels(&root, false, &title, &panels, cs, &label, fs, o.edges)?;
                root.present().map_err(de)?;
            }
            s.into_bytes()
        }
    };
    Ok((bytes, summary))
}

/// The default cut: through the centre of the bounding box, across its
/// smallest extent (on a tie y before x before z, so that a model with z
/// up is cut vertically).
pub fn default_plane(points: &[[f64; 3]]) -> Plane {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let ext = |k: usize| hi[k] - lo[k];
    let mut best = 1;
    for k in [0, 2] {
        if ext(k) < ext(best) * (1.0 - 1e-9) {
            best = k;
        }
    }
    Plane::axis(best, 0.5 * (lo[best] + hi[best]))
}

/// The section of `ck` by `plane` as a panel, its values and summary.
fn cut_panel(
    ck: &SolidCheckpoint,
    step: &SolidStep,
    plane: &Plane,
    field: SolidField,
    scale: f64,
    units: &Units,
) -> Result<(Panel, Vec<f64>, CutSummary), PlotError> {
    let polys = section(&ck.points, &ck.tets, plane);
    if polys.is_empty() {
        return Err(misses(&ck.points, plane));
    }
    let frame = Frame::of_normal(plane.normal);
    let lerp = |a: V3, b: V3, t: f64| -> V3 { [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k])) };
    let nodal = |u: V3| match field {
        SolidField::U(k) => u[k],
        _ => (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt(),
    };
    let cell = |t: usize| match field {
        SolidField::VonMises => step.von_mises[t],
        SolidField::Stress(k) => step.stress[t][k],
        SolidField::Principal(k) => step.principal[t][k],
        _ => f64::NAN,
    };
    let mut pts: Vec<P2> = Vec::new();
    let mut tris = Vec::new();
    let mut edges = Vec::new();
    let mut point_values = Vec::new();
    let mut tri_values = Vec::new();
    let mut area = 0.0;
    for poly in &polys {
        let base = pts.len();
        let mut p3 = Vec::with_capacity(4);
        for &(i, j, t) in &poly.verts {
            let x = lerp(ck.points[i], ck.points[j], t);
            let u = lerp(step.displacement[i], step.displacement[j], t);
            p3.push(x);
            pts.push(frame.project([0, 1, 2].map(|k| x[k] + scale * u[k])));
            point_values.push(nodal(u));
        }
        area += polygon_area(&p3);
        let m = poly.verts.len();
        for q in 1..m - 1 {
            tris.push([base, base + q, base + q + 1]);
            tri_values.push(cell(poly.tet));
        }
        for q in 0..m {
            edges.push([pts[base + q], pts[base + (q + 1) % m]]);
        }
    }
    let (fill, values) = if field.nodal() {
        (Fill::Nodal(point_values.clone()), point_values)
    } else {
        let v: Vec<f64> = polys.iter().map(|p| cell(p.tet)).collect();
        (Fill::Cell(tri_values), v)
    };
    let panel = Panel {
        title: String::new(),
        labels: frame
            .labels
            .clone()
            .map(|s| format!("{s} [{}]", units.length)),
        pts,
        tris,
        fill,
        edges,
        outline: vec![],
        zones: vec![],
        arrows: vec![],
    };
    let summary = CutSummary {
        plane: plane.clone(),
        default: false,
        tets: polys.len(),
        area,
        axes: frame.labels,
    };
    Ok((panel, values, summary))
}

fn check_consistent(ck: &SolidCheckpoint, s: &SolidStep) -> Result<(), PlotError> {
    let (n, m, r) = (ck.points.len(), ck.tets.len(), ck.contact.slave.len());
    let bad = s.displacement.len() != n
        || s.stress.len() != m
        || s.von_mises.len() != m
        || s.principal.len() != m
        || s.contact_pressure.len() != r
        || s.active.len() != r
        || ck.contact.normal.len() != r
        || ck.contact.interface.len() != r;
    if bad {
        return Err(err("inconsistent array lengths in the checkpoint"));
    }
    if m == 0 {
        return Err(err("the mesh has no tetrahedron"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_parse_by_their_3d_names() {
        assert_eq!(SolidField::parse("syz").unwrap(), SolidField::Stress(4));
        assert_eq!(SolidField::parse("sxz").unwrap().name(), "sxz");
        assert_eq!(SolidField::parse("s3").unwrap(), SolidField::Principal(2));
        assert!(SolidField::parse("uz").unwrap().nodal());
        let e = SolidField::parse("srr").unwrap_err().0;
        assert!(
            e.contains("not a field of a 3D checkpoint") && e.contains("syz"),
            "{e}"
        );
        for n in SolidField::names() {
            assert_eq!(SolidField::parse(n).unwrap().name(), n);
        }
    }

    /// Two unit squares as slave surfaces, one in z = 0 (normal z) and one
    /// in x = 2 (normal x), rows active but one, pressure = row number.
    fn two_interfaces() -> SolidCheckpoint {
        let points = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [2.0, 1.0, 1.0],
            [2.0, 0.0, 1.0],
        ];
        let contact = crate::output::SolidContactMesh {
            slave: (0..8).collect(),
            normal: [[0.0, 0.0, 1.0]; 4]
                .into_iter()
                .chain([[1.0, 0.0, 0.0]; 4])
                .collect(),
            gap0: vec![0.0; 8],
            interface: vec![0, 0, 0, 0, 1, 1, 1, 1],
            triangles: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
        };
        let step = SolidStep {
            index: 1,
            displacement: vec![[0.0; 3]; 8],
            stress: vec![[0.0; 6]],
            von_mises: vec![0.0],
            principal: vec![[0.0; 3]],
            contact_pressure: (0..8).map(f64::from).collect(),
            active: vec![1, 1, 1, 1, 1, 1, 1, 0],
            ..Default::default()
        };
        SolidCheckpoint {
            tets: vec![[0, 1, 3, 7]],
            points,
            contact,
            step_indices: vec![1],
            steps: vec![step],
            attrs: vec![(
                "toml".into(),
                "[[contact]]\non = \"a\"\n[[contact]]\nslave = \"b\"\nmaster = \"c\"\n".into(),
            )],
            ..Default::default()
        }
    }

    #[test]
    fn each_interface_has_its_panel_in_its_own_plane() {
        let ck = two_interfaces();
        let opts = SolidPlotOptions {
            base: PlotOptions {
                contact: true,
                ..PlotOptions::default()
            },
            field: SolidField::VonMises,
            cut: None,
        };
        let (svg, s) = render_solid(&ck, "two", &opts, Format::Svg).unwrap();
        let svg = String::from_utf8(svg).unwrap();
        assert_eq!(s.interfaces.len(), 2);
        let (a, b) = (&s.interfaces[0], &s.interfaces[1]);
        assert_eq!((a.name.as_str(), b.name.as_str()), ("a", "b/c"));
        assert_eq!((a.rows, a.active, b.rows, b.active), (4, 4, 4, 3));
        assert_eq!((a.area, b.area, b.surface_area), (1.0, 1.0, 1.0));
        assert_eq!(b.axes, ["y".to_string(), "z".to_string()]);
        // One corner inactive: the region where the flag is ≥ ½ loses the
        // corner triangle cut at the edges' midpoints (area ⅛).
        assert!((b.active_area - 0.875).abs() < 1e-15, "{}", b.active_area);
        assert_eq!((a.max_pressure, b.max_pressure), (3.0, 7.0));
        assert_eq!(s.data_range, (0.0, 7.0));
        assert!(svg.contains("b/c: 3 of 4 rows active"));
        assert!(svg.contains("y [m]") && svg.contains("z [m]"));
    }

    #[test]
    fn the_default_cut_is_across_the_smallest_extent() {
        let box_ = |a: f64, b: f64, c: f64| vec![[0.0, 0.0, 0.0], [a, b, c]];
        assert_eq!(default_plane(&box_(2.0, 0.2, 0.2)).text, "y = 0.1");
        assert_eq!(default_plane(&box_(1.0, 1.0, 0.5)).text, "z = 0.25");
        assert_eq!(default_plane(&box_(0.1, 1.0, 1.0)).text, "x = 0.05");
    }
}
