//! `signorini plot`: a checkpoint read from its file, drawn by
//! [`crate::post::plot`] and written atomically (the drawing itself reads
//! and writes no file).

use crate::io::atomic::write_atomic_bytes;
use crate::io::hdf5::{read_checkpoint, read_solid_checkpoint, SolidSteps};
use crate::post::plot::{
    check_options, render, render_solid, Format, PlotError, PlotOptions, PlotSummary,
    SolidPlotOptions, SolidPlotSummary,
};
use std::path::Path;

/// Reads `h5`, draws the figure and writes it to `out` (format from its
/// extension) atomically.
pub fn plot_file(h5: &Path, out: &Path, opts: &PlotOptions) -> Result<PlotSummary, PlotError> {
    // One line whatever the source said, as every plot message.
    let err = |msg: String| PlotError(msg.replace('\n', " "));
    let format = Format::from_path(out)?;
    check_options(opts)?;
    let ck = read_checkpoint(h5).map_err(|e| err(e.to_string()))?;
    let name = h5
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "checkpoint".to_string());
    let (bytes, summary) =
        render(&ck, &name, opts, format).map_err(|e| err(format!("{}: {}", h5.display(), e.0)))?;
    write_atomic_bytes(out, &bytes).map_err(|e| err(e.to_string()))?;
    Ok(summary)
}

/// [`plot_file`] of a 3D checkpoint: reads the mesh and the one step
/// drawn (`--step`, by its number, or the last one).
pub fn plot_solid_file(
    h5: &Path,
    out: &Path,
    opts: &SolidPlotOptions,
) -> Result<SolidPlotSummary, PlotError> {
    let err = |msg: String| PlotError(msg.replace('\n', " "));
    let format = Format::from_path(out)?;
    check_options(&opts.base)?;
    let which = opts.base.step.map_or(SolidSteps::Last, SolidSteps::One);
    let ck = read_solid_checkpoint(h5, which).map_err(|e| err(e.to_string()))?;
    let name = h5
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "checkpoint".to_string());
    let (bytes, summary) = render_solid(&ck, &name, opts, format)
        .map_err(|e| err(format!("{}: {}", h5.display(), e.0)))?;
    write_atomic_bytes(out, &bytes).map_err(|e| err(e.to_string()))?;
    Ok(summary)
}
