//! Rigid motions a working set of the discs leaves free (docs/methods.md
//! §12.3, §9.3): which motions B holds with no stiffness, whether the loads
//! outwork the discs' dissipation along one (unbounded), and the start
//! that holds a body the loads push across a gap.

use super::{BRow, Disc, State};
use crate::linalg::sparse::{dot, norm_inf};
use crate::qp::tangential_norm;

impl State<'_> {
    /// Every row starts in N when the rows closed at the start leave free
    /// a rigid motion the loads work on (a body pressed towards its support
    /// across a gap), as 2D does (§9.2).
    pub(super) fn hold_free_bodies(&mut self) {
        if self.r.is_empty() || self.in_n.iter().all(|a| *a) {
            return;
        }
        let tang = vec![Disc::Stick; self.qp.m()];
        let rows = self.brows(&self.in_n, &tang);
        let loaded = self.free_motions(&rows).iter().any(|z| {
            let (work, scale) = work_of_loads(&self.qp.d, z);
            work.abs() > 1e-8 * scale
        });
        if loaded {
            log::debug!(
                "ssn: discs: the closed rows leave a rigid motion free: every row starts in N"
            );
            self.in_n = vec![true; self.qp.m()];
        }
    }

    /// An orthonormal basis (in ℝⁿ) of the rigid motions z that B holds
    /// with no stiffness: Σ w_b (b z)² ≈ 0, each row weighted by what it
    /// adds to K (ρ, or a slipping row's spring 1/κ). A motion held only by
    /// springs far softer than the rows' ρ (a body sliding away, ‖ξ‖ → ∞)
    /// counts as free: K is singular along it to round-off, so it is
    /// tested for unboundedness and regularised, not factored (§12.3).
    pub(super) fn free_motions<'r>(
        &self,
        rows: impl IntoIterator<Item = &'r BRow>,
    ) -> Vec<Vec<f64>> {
        let k = self.r.len();
        if k == 0 {
            return vec![];
        }
        let mut g = vec![vec![0.0; k]; k];
        let mut bnorm = 0.0;
        for b in rows {
            let w = b.spring.map_or(1.0, |k_s| k_s / b.rho);
            bnorm += b.vals.iter().map(|v| v * v).sum::<f64>();
            let br: Vec<f64> = self
                .r
                .iter()
                .map(|rl| b.cols.iter().zip(&b.vals).map(|(&j, &a)| a * rl[j]).sum())
                .collect();
            for a in 0..k {
                for c in 0..k {
                    g[a][c] += w * br[a] * br[c];
                }
            }
        }
        super::super::motions::null_motions(&g, &self.r, self.qp.n(), bnorm)
    }

    /// A free rigid motion along which the loads do more work than the
    /// discs dissipate, Σ sᵢ‖(T z)ᵢ‖, and no contact row closes (§9.3 with
    /// the disc's dissipation); under the glued start only the loads' own
    /// direction is tried, as in 2D.
    pub(super) fn unbounded_along(&self, free: &[Vec<f64>]) -> Option<Vec<f64>> {
        let qp = self.qp;
        let mut p = vec![0.0; qp.n()];
        for z in free {
            let w = dot(&qp.d, z);
            for (pj, zj) in p.iter_mut().zip(z) {
                *pj += w * zj;
            }
        }
        let mut cands = vec![p];
        if !self.glued {
            for z in free {
                cands.push(z.clone());
                cands.push(z.iter().map(|v| -v).collect());
            }
            cands.push(self.steepest_slide(free));
        }
        cands.into_iter().find(|z| {
            if !(norm_inf(z) > 0.0) || crate::qp::recession::certify(qp, z).is_err() {
                return false;
            }
            let tz = self.fr.t.mul(z);
            let (work, scale) = work_of_loads(&qp.d, z);
            let dissipation: f64 = tz
                .chunks(2)
                .zip(&self.s)
                .map(|(t, s)| s * tangential_norm(t))
                .sum();
            work - dissipation > 1e-10 * scale
        })
    }

    /// The unit motion z in span(`free`) that maximises the loads' work
    /// less the discs' dissipation, f(z) = d·z − Σ sᵢ‖T_i z‖ (concave), by
    /// projected subgradient ascent on the unit sphere from the loads' own
    /// direction: the test of §12.3 needs a z with f(z) > 0 when one exists,
    /// and the loads' direction misses it when a turn of the body costs
    /// less than it gains. Deterministic: a fixed number of steps.
    pub(super) fn steepest_slide(&self, free: &[Vec<f64>]) -> Vec<f64> {
        let q = free.len();
        let a: Vec<f64> = free.iter().map(|z| dot(&self.qp.d, z)).collect();
        let tz: Vec<Vec<f64>> = free.iter().map(|z| self.fr.t.mul(z)).collect();
        let m = self.s.len();
        let f_and_grad = |c: &[f64]| -> (f64, Vec<f64>) {
            let mut f: f64 = a.iter().zip(c).map(|(x, y)| x * y).sum();
            let mut g = a.clone();
            for i in 0..m {
                let v = [0, 1].map(|k| (0..q).map(|j| c[j] * tz[j][2 * i + k]).sum::<f64>());
                let nv = tangential_norm(&v);
                f -= self.s[i] * nv;
                if nv > 0.0 {
                    for (j, gj) in g.iter_mut().enumerate() {
                        *gj -= self.s[i] * (v[0] * tz[j][2 * i] + v[1] * tz[j][2 * i + 1]) / nv;
                    }
                }
            }
            (f, g)
        };
        let unit = |c: &mut Vec<f64>| {
            let n = c.iter().map(|v| v * v).sum::<f64>().sqrt();
            if n > 0.0 {
                c.iter_mut().for_each(|v| *v /= n);
            }
        };
        let mut c = a.clone();
        unit(&mut c);
        let (mut best_f, mut best) = (f64::NEG_INFINITY, c.clone());
        for it in 0..=200 {
            let (f, g) = f_and_grad(&c);
            if f > best_f {
                (best_f, best) = (f, c.clone());
            }
            if it == 200 {
                break;
            }
            let gc: f64 = g.iter().zip(&c).map(|(x, y)| x * y).sum();
            let mut gt: Vec<f64> = g.iter().zip(&c).map(|(x, y)| x - gc * y).collect();
            unit(&mut gt);
            let step = 0.5 / (1.0 + it as f64).sqrt();
            for (cj, gj) in c.iter_mut().zip(&gt) {
                *cj += step * gj;
            }
            unit(&mut c);
        }
        let mut z = vec![0.0; self.qp.n()];
        for (cj, fz) in best.iter().zip(free) {
            for (zk, fk) in z.iter_mut().zip(fz) {
                *zk += cj * fk;
            }
        }
        z
    }
}

/// dᵀz and Σ|dⱼzⱼ|, the scale it is judged against.
fn work_of_loads(d: &[f64], z: &[f64]) -> (f64, f64) {
    (dot(d, z), d.iter().zip(z).map(|(a, b)| (a * b).abs()).sum())
}
