//! Fonts, colours and number formats of the figures, and the PNG encoder.

use super::{err, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(super) fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let bytes = dejavu::sans::regular();
        for family in ["sans-serif", "serif", "monospace"] {
            let _ = plotters::style::register_font(family, FontStyle::Normal, bytes);
        }
    });
}

pub(super) fn font_size(w: u32, h: u32) -> f64 {
    (w.min(h) as f64 / 45.0).clamp(11.0, 30.0)
}

pub(super) fn de<E: std::fmt::Display>(e: E) -> PlotError {
    err(format!("drawing failed: {e}"))
}

/// Viridis (matplotlib) at t = 0, 0.1, …, 1.
const VIRIDIS: [(u8, u8, u8); 11] = [
    (0x44, 0x01, 0x54),
    (0x48, 0x24, 0x75),
    (0x41, 0x44, 0x87),
    (0x35, 0x5f, 0x8d),
    (0x2a, 0x78, 0x8e),
    (0x21, 0x91, 0x8c),
    (0x22, 0xa8, 0x84),
    (0x44, 0xbf, 0x70),
    (0x7a, 0xd1, 0x51),
    (0xbd, 0xdf, 0x26),
    (0xfd, 0xe7, 0x25),
];

/// Colour of t ∈ [0, 1] (clamped) on the viridis map; NaN is grey.
pub fn viridis(t: f64) -> RGBColor {
    if !t.is_finite() {
        return RGBColor(160, 160, 160);
    }
    let x = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Qualitative palette (matplotlib tab10) for categories and line series.
const TAB10: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

pub(super) fn category_color(i: usize) -> RGBColor {
    let (r, g, b) = TAB10[i % TAB10.len()];
    RGBColor(r, g, b)
}

/// Short number: 4 significant digits, exponent outside [1e-3, 1e5),
/// trailing zeros removed.
pub fn fmt_num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_nan() {
            "NaN".into()
        } else if v == 0.0 {
            "0".into()
        } else {
            format!("{v}")
        };
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let d = (3 - a.log10().floor() as i32).max(0) as usize;
        trim_zeros(&format!("{v:.d$}"))
    } else {
        let s = format!("{v:.3e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim_zeros(m)),
            None => s,
        }
    }
}

/// An axis tick: [`fmt_num`], with a value within rounding of zero against
/// the axis span written as 0 (ticks are sums of steps: a centred axis put
/// "-2.22e-16" where 0 belonged).
pub(super) fn tick(v: f64, span: f64) -> String {
    if v.abs() <= 1e-9 * span.abs() {
        "0".into()
    } else {
        fmt_num(v)
    }
}

fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        let t = s.trim_end_matches('0').trim_end_matches('.');
        if t == "-0" {
            "0".into()
        } else {
            t.to_string()
        }
    } else {
        s.to_string()
    }
}

pub(super) fn encode_png(buf: &[u8], w: u32, h: u32) -> Result<Vec<u8>, PlotError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc
            .write_header()
            .map_err(|e| err(format!("PNG encoding failed: {e}")))?;
        wr.write_image_data(buf)
            .map_err(|e| err(format!("PNG encoding failed: {e}")))?;
        wr.finish()
            .map_err(|e| err(format!("PNG encoding failed: {e}")))?;
    }
    Ok(out)
}

/// The area below the title, with a small margin all round.
pub(super) fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    fs: f64,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
    let m = (fs * 0.5) as u32;
    root.margin(m, m / 2, m / 2, m + m / 2)
        .titled(title, ("sans-serif", fs * 1.35).into_font().color(&BLACK))
        .map_err(de)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tick_within_rounding_of_zero_is_zero() {
        assert_eq!(tick(-2.220446049250313e-16, 2.2), "0");
        assert_eq!(tick(1e-3, 2.2), "0.001");
        assert_eq!(tick(-0.4, 2.2), "-0.4");
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(1.5), "1.5");
        assert_eq!(fmt_num(-0.25), "-0.25");
        assert_eq!(fmt_num(1234.5678), "1235");
        assert_eq!(fmt_num(1.0e6), "1e6");
        assert_eq!(fmt_num(-2.5e-5), "-2.5e-5");
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(viridis(1.0), RGBColor(0xfd, 0xe7, 0x25));
        assert_eq!(viridis(2.0), viridis(1.0));
    }
}
