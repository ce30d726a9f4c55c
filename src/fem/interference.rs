//! The bound on an intended initial overlap (`interference = true`,
//! docs/problem-format.md §5): the rows of a non-matching pair are built on
//! the reference geometry, with the gap linearized along the reference
//! normal and each slave point projected on one master segment. Pushing an
//! overlap δ out moves the slave point by about δ along the normal, so the
//! rows describe the fit only while δ is small against the segment (the
//! point stays on the segment it was projected on, where the linear
//! interpolation of the master holds) and against the bodies (a strain of
//! about δ / size stays within small-deformation elasticity). Past either
//! bound the solve would certify a model of some other contact, so the
//! input is refused, naming the pair and the point.

use super::topology::Topology;

/// An overlap may reach this fraction of the local segment length.
pub(crate) const SEGMENT_FRACTION: f64 = 0.5;
/// An overlap may reach this fraction of the smaller body's size (the
/// diagonal of its bounding box): a strain of about 2 %.
pub(crate) const BODY_FRACTION: f64 = 0.02;

impl Topology {
    /// The diagonal of each body's bounding box (by body index).
    pub(super) fn body_sizes(&self) -> Vec<f64> {
        let mut lo = vec![[f64::INFINITY; 2]; self.nbodies];
        let mut hi = vec![[f64::NEG_INFINITY; 2]; self.nbodies];
        for (p, &b) in self.points.iter().zip(&self.point_body) {
            let b = b as usize;
            if b >= self.nbodies {
                continue;
            }
            for k in 0..2 {
                lo[b][k] = lo[b][k].min(p[k]);
                hi[b][k] = hi[b][k].max(p[k]);
            }
        }
        lo.iter()
            .zip(&hi)
            .map(|(l, h)| {
                let d = (h[0] - l[0]).hypot(h[1] - l[1]);
                if d.is_finite() {
                    d
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// Refuses the overlap `overlap` (> 0) of an interference fit at `at` of the
/// pair `what` if it exceeds [`SEGMENT_FRACTION`] of `seg_len` (the segment
/// the gap is measured on) or [`BODY_FRACTION`] of the smaller of the two
/// bodies' sizes `sizes`.
pub(super) fn check_overlap(
    what: &str,
    at: &str,
    overlap: f64,
    seg_len: f64,
    sizes: [f64; 2],
) -> Result<(), String> {
    let size = sizes[0].min(sizes[1]);
    let (seg_max, body_max) = (SEGMENT_FRACTION * seg_len, BODY_FRACTION * size);
    if overlap <= seg_max && overlap <= body_max {
        return Ok(());
    }
    let why = if overlap > seg_max {
        format!(
            "more than {SEGMENT_FRACTION} × the local segment length {seg_len:.3e} (the gap and the projection are built on the reference geometry and hold within one segment)"
        )
    } else {
        format!(
            "more than {BODY_FRACTION} × the size {size:.3e} of the smaller body (a strain beyond small-deformation elasticity)"
        )
    };
    Err(format!(
        "{what}: interference overlap {overlap:.3e} at {at} is {why}; an interference fit must be a small overlap (docs/problem-format.md §5)"
    ))
}
