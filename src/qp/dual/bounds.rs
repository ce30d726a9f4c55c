//! The feasible set of the dual (docs/methods.md §4.11, §12.4): a product of
//! intervals ℓᵢ ≤ λ̂ᵢ ≤ uᵢ (a contact row; a tangential row in 2D) and discs
//! ‖λ̂ₖ + λ̃ₖ‖ ≤ rₖ (the two tangential rows of a contact point in 3D, λ̃ the
//! homogenising shift). MPRGP asks every factor the same questions — is the
//! point interior, the chopped gradient there, the projection, the longest
//! feasible step along a direction, the reduced free gradient — and a
//! [`Block`] answers them: an [`Interval`] with the formulas MPRGP always had
//! (Dostál & Schöberl, Comput. Optim. Appl. 30, 2005), a [`Disc`] with those
//! of MPGP for separable convex sets (Dostál & Kozubek, Math. Program. 135,
//! 2012): the projected gradient through the tangent cone, the reduced free
//! gradient through the projection, the feasible step a root of a quadratic.

use super::DualState;

/// One factor of the dual's feasible set, acting on its own entries of λ̂
/// (`x`), of the gradient and of a direction (docs/methods.md §12.4).
pub(crate) trait Block {
    /// Strictly inside the set: its entries are free (their equations hold).
    fn is_free(&self, x: &[f64]) -> bool;
    /// The chopped gradient β at a point on the boundary: the projected
    /// gradient gᴾ = −P_T(−g), T the tangent cone there.
    fn chopped(&self, x: &[f64], g: &[f64], out: &mut [f64]);
    /// x ← P(x − a·d). True when the result is not the straight step x − a·d
    /// along a curved boundary (then g − aHd is not the new gradient).
    fn step(&self, x: &mut [f64], a: f64, d: &[f64]) -> bool;
    /// The largest α ≥ 0 with x − αp in the set (∞ when no bound stops it).
    fn feasible_step(&self, x: &[f64], p: &[f64]) -> f64;
    /// φ̃ᵀφ for the free gradient φ: φ̃ = (x − P(x − ᾱφ))/ᾱ, the reduced free
    /// gradient of the proportioning test ‖β‖² ≤ Γ²φ̃ᵀφ.
    fn reduced_dot(&self, x: &[f64], phi: &[f64], abar: f64) -> f64;
}

/// ℓ ≤ λ̂ ≤ u (u = +∞ on a contact row): MPRGP's box, its formulas as they
/// were (the same bits).
pub(crate) struct Interval {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl Block for Interval {
    fn is_free(&self, x: &[f64]) -> bool {
        x[0] > self.lo && x[0] < self.hi
    }
    /// min(g, 0) at ℓ, max(g, 0) at u, 0 when ℓ = u (a slip bound 0).
    fn chopped(&self, x: &[f64], g: &[f64], out: &mut [f64]) {
        out[0] = if x[0] <= self.lo {
            if x[0] >= self.hi {
                0.0
            } else {
                g[0].min(0.0)
            }
        } else {
            g[0].max(0.0)
        };
    }
    /// A clip is never reported: MPRGP on a box updates g by −aHd as it
    /// always did (a proportioning step longer than the box, from one bound
    /// past the other, is clipped with g not recomputed; left as it was).
    fn step(&self, x: &mut [f64], a: f64, d: &[f64]) -> bool {
        x[0] = (x[0] - a * d[0]).max(self.lo).min(self.hi);
        false
    }
    fn feasible_step(&self, x: &[f64], p: &[f64]) -> f64 {
        if p[0] > 0.0 {
            ((x[0] - self.lo) / p[0]).max(0.0)
        } else if p[0] < 0.0 && self.hi < f64::INFINITY {
            ((x[0] - self.hi) / p[0]).max(0.0)
        } else {
            f64::INFINITY
        }
    }
    /// min((λ̂ − ℓ)/ᾱ, φ)·φ, or max((λ̂ − u)/ᾱ, φ)·φ where φ < 0 below a
    /// finite u: (λ̂ − P(λ̂ − ᾱφ))/ᾱ·φ on an interval.
    fn reduced_dot(&self, x: &[f64], phi: &[f64], abar: f64) -> f64 {
        if phi[0] < 0.0 && self.hi < f64::INFINITY {
            ((x[0] - self.hi) / abar).max(phi[0]) * phi[0]
        } else {
            ((x[0] - self.lo) / abar).min(phi[0]) * phi[0]
        }
    }
}

/// Boundary slack of a disc, relative to r + ‖λ̃‖: λ̂ = z − λ̃ rounds z, so a
/// point the projection put on the circle is read back within a few ulps of
/// r + ‖λ̃‖ of it and must count as on it.
const DISC_SLACK: f64 = 8.0 * f64::EPSILON;

/// ‖λ̂ + λ̃‖ ≤ r on two rows (docs/methods.md §12.4): z = λ̂ + λ̃ is the
/// tangential multiplier itself, the disc centred at −λ̃. r = 0 is a point,
/// r = ∞ (glued) no bound.
pub(crate) struct Disc {
    /// λ̃ of the two rows.
    pub(crate) shift: [f64; 2],
    /// r, the scaled slip bound.
    pub(crate) radius: f64,
}

impl Disc {
    fn z(&self, x: &[f64]) -> [f64; 2] {
        [x[0] + self.shift[0], x[1] + self.shift[1]]
    }
    /// P(z) = z·min(1, r/‖z‖) on the disc about 0; r = 0 gives 0.
    pub(crate) fn project(z: [f64; 2], r: f64) -> [f64; 2] {
        let n = z[0].hypot(z[1]);
        if n <= r {
            z
        } else {
            let c = r / n;
            [z[0] * c, z[1] * c]
        }
    }
}

impl Block for Disc {
    fn is_free(&self, x: &[f64]) -> bool {
        if self.radius == f64::INFINITY {
            return true;
        }
        let z = self.z(x);
        let slack = DISC_SLACK * (self.radius + self.shift[0].hypot(self.shift[1]));
        self.radius - z[0].hypot(z[1]) > slack
    }
    /// With the outward normal ν = z/‖z‖: g where −g points inwards (νᵀg ≥
    /// 0), else its tangential part g − (νᵀg)ν; 0 on a disc of radius 0
    /// (its tangent cone is {0}).
    fn chopped(&self, x: &[f64], g: &[f64], out: &mut [f64]) {
        let z = self.z(x);
        let n = z[0].hypot(z[1]);
        if self.radius == 0.0 || n == 0.0 {
            out[0] = 0.0;
            out[1] = 0.0;
            return;
        }
        let nu = [z[0] / n, z[1] / n];
        let gn = nu[0] * g[0] + nu[1] * g[1];
        if gn >= 0.0 {
            out[0] = g[0];
            out[1] = g[1];
        } else {
            out[0] = g[0] - gn * nu[0];
            out[1] = g[1] - gn * nu[1];
        }
    }
    fn step(&self, x: &mut [f64], a: f64, d: &[f64]) -> bool {
        let y = [x[0] - a * d[0], x[1] - a * d[1]];
        let z = self.z(&y);
        if z[0].hypot(z[1]) <= self.radius {
            x[0] = y[0];
            x[1] = y[1];
            false
        } else {
            let p = Disc::project(z, self.radius);
            x[0] = p[0] - self.shift[0];
            x[1] = p[1] - self.shift[1];
            true
        }
    }
    /// The positive root of ‖z − αp‖² = r²: with q = zᵀp and
    /// e = r² − ‖z‖² ≥ 0, α = (q + √(q² + ‖p‖²e))/‖p‖², written
    /// e/(√(q² + ‖p‖²e) − q) for q < 0 (no cancellation).
    fn feasible_step(&self, x: &[f64], p: &[f64]) -> f64 {
        let pp = p[0] * p[0] + p[1] * p[1];
        if self.radius == f64::INFINITY || pp == 0.0 {
            return f64::INFINITY;
        }
        let z = self.z(x);
        let n = z[0].hypot(z[1]);
        let q = z[0] * p[0] + z[1] * p[1];
        let e = ((self.radius - n) * (self.radius + n)).max(0.0);
        let root = (q * q + pp * e).sqrt();
        let a = if q >= 0.0 {
            (q + root) / pp
        } else {
            e / (root - q)
        };
        a.max(0.0)
    }
    fn reduced_dot(&self, x: &[f64], phi: &[f64], abar: f64) -> f64 {
        let z = self.z(x);
        let w = Disc::project([z[0] - abar * phi[0], z[1] - abar * phi[1]], self.radius);
        ((z[0] - w[0]) * phi[0] + (z[1] - w[1]) * phi[1]) / abar
    }
}

impl DualState<'_> {
    /// Row i's interval (rows before `disc_start`).
    fn interval(&self, i: usize) -> Interval {
        Interval {
            lo: self.lb[i],
            hi: self.ub[i],
        }
    }
    /// The disc holding row i ≥ `disc_start` and its first row.
    fn disc_of(&self, i: usize) -> (&Disc, usize) {
        let k = (i - self.disc_start) / 2;
        (&self.discs[k], self.disc_start + 2 * k)
    }
    /// λ̂ᵢ strictly inside its factor of the set.
    pub(crate) fn is_free(&self, i: usize) -> bool {
        if i < self.disc_start {
            self.lam[i] > self.lb[i] && self.lam[i] < self.ub[i]
        } else {
            let (d, j) = self.disc_of(i);
            d.is_free(&self.lam[j..j + 2])
        }
    }
    /// Free gradient φ: g on the free entries, 0 elsewhere.
    pub(crate) fn phi(&self) -> Vec<f64> {
        (0..self.lam.len())
            .map(|i| if self.is_free(i) { self.g[i] } else { 0.0 })
            .collect()
    }
    /// Chopped gradient β: the projected gradient on the entries at their
    /// bounds (min(g, 0) at ℓ, max(g, 0) at u; on a disc's circle g or its
    /// tangential part), 0 on the free ones.
    pub(crate) fn beta(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.lam.len()];
        for (i, o) in out.iter_mut().enumerate().take(self.disc_start) {
            if !self.is_free(i) {
                let mut v = [0.0];
                self.interval(i)
                    .chopped(&self.lam[i..=i], &self.g[i..=i], &mut v);
                *o = v[0];
            }
        }
        for (k, d) in self.discs.iter().enumerate() {
            let j = self.disc_start + 2 * k;
            if !d.is_free(&self.lam[j..j + 2]) {
                d.chopped(&self.lam[j..j + 2], &self.g[j..j + 2], &mut out[j..j + 2]);
            }
        }
        out
    }
    /// ‖gᴾ‖ = ‖φ + β‖.
    pub(crate) fn gp_norm(&self) -> f64 {
        let rows: f64 = (0..self.disc_start)
            .map(|i| {
                let v = if self.is_free(i) {
                    self.g[i]
                } else {
                    let mut v = [0.0];
                    self.interval(i)
                        .chopped(&self.lam[i..=i], &self.g[i..=i], &mut v);
                    v[0]
                };
                v * v
            })
            .sum::<f64>();
        if self.discs.is_empty() {
            return rows.sqrt();
        }
        let b = self.beta();
        let discs: f64 = (self.disc_start..self.lam.len())
            .map(|i| {
                let v = if self.is_free(i) { self.g[i] } else { b[i] };
                v * v
            })
            .sum();
        (rows + discs).sqrt()
    }
    /// φ̃ᵀφ over the free factors ([`Block::reduced_dot`]).
    pub(crate) fn reduced_dot(&self, phi: &[f64], abar: f64) -> f64 {
        let rows: f64 = (0..self.disc_start)
            .filter(|&i| self.is_free(i))
            .map(|i| {
                self.interval(i)
                    .reduced_dot(&self.lam[i..=i], &phi[i..=i], abar)
            })
            .sum();
        if self.discs.is_empty() {
            return rows;
        }
        let discs: f64 = self
            .discs
            .iter()
            .enumerate()
            .map(|(k, d)| {
                let j = self.disc_start + 2 * k;
                let x = &self.lam[j..j + 2];
                if d.is_free(x) {
                    d.reduced_dot(x, &phi[j..j + 2], abar)
                } else {
                    0.0
                }
            })
            .sum();
        rows + discs
    }
    /// The largest α ≥ 0 with λ̂ − αp feasible ([`Block::feasible_step`]).
    pub(crate) fn feasible_step(&self, p: &[f64]) -> f64 {
        let mut af = f64::INFINITY;
        for i in 0..self.disc_start {
            let a = self.interval(i).feasible_step(&self.lam[i..=i], &p[i..=i]);
            if a < f64::INFINITY {
                af = af.min(a);
            }
        }
        for (k, d) in self.discs.iter().enumerate() {
            let j = self.disc_start + 2 * k;
            af = af.min(d.feasible_step(&self.lam[j..j + 2], &p[j..j + 2]));
        }
        af
    }
    /// Whether a disc on its circle has −g leaving it with a tangential
    /// part (the chopped gradient `beta` nonzero there and νᵀg < 0): a step
    /// along β would leave the disc at once.
    pub(crate) fn slides(&self, beta: &[f64]) -> bool {
        self.discs.iter().enumerate().any(|(k, d)| {
            let j = self.disc_start + 2 * k;
            let x = &self.lam[j..j + 2];
            let z = d.z(x);
            let g = &self.g[j..j + 2];
            (beta[j] != 0.0 || beta[j + 1] != 0.0)
                && !d.is_free(x)
                && z[0] * g[0] + z[1] * g[1] < 0.0
        })
    }
    /// λ̂ ← P(λ̂ − a·d); true when a disc's projection bent the step (then
    /// g − aHd is not the new gradient, [`Block::step`]).
    pub(crate) fn step_projected(&mut self, a: f64, d: &[f64]) -> bool {
        for i in 0..self.disc_start {
            let iv = Interval {
                lo: self.lb[i],
                hi: self.ub[i],
            };
            iv.step(&mut self.lam[i..=i], a, &d[i..=i]);
        }
        let mut bent = false;
        for (k, disc) in self.discs.iter().enumerate() {
            let j = self.disc_start + 2 * k;
            bent |= disc.step(&mut self.lam[j..j + 2], a, &d[j..j + 2]);
        }
        bent
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(r: f64) -> Disc {
        Disc {
            shift: [0.25, -0.5],
            radius: r,
        }
    }

    /// The projection onto a disc is λ·min(1, s/‖λ‖), 0 for s = 0.
    #[test]
    fn projection_onto_a_disc() {
        assert_eq!(Disc::project([3.0, 4.0], 10.0), [3.0, 4.0]);
        let p = Disc::project([3.0, 4.0], 2.5);
        assert!((p[0] - 1.5).abs() < 1e-15 && (p[1] - 2.0).abs() < 1e-15);
        assert_eq!(Disc::project([3.0, 4.0], 0.0), [0.0, 0.0]);
        assert_eq!(Disc::project([0.0, 0.0], 0.0), [0.0, 0.0]);
    }

    /// The feasible step reaches the circle exactly, from inside, from the
    /// centre and along a chord from the circle; 0 when it leaves at once.
    #[test]
    fn the_feasible_step_ends_on_the_circle() {
        let d = disc(2.0);
        for (z, p) in [
            ([0.3, -0.4], [1.0, 0.7]),
            ([0.3, -0.4], [-1.0, 0.2]),
            ([0.0, 0.0], [0.0, -3.0]),
            ([1.2, 1.6], [1.0, 0.0]),
        ] {
            let x = [z[0] - d.shift[0], z[1] - d.shift[1]];
            let a = d.feasible_step(&x, &p);
            let end = [z[0] - a * p[0], z[1] - a * p[1]];
            assert!(
                (end[0].hypot(end[1]) - 2.0).abs() < 1e-14,
                "{z:?} {p:?}: {a}"
            );
            assert!(a > 0.0);
        }
        // On the circle, moving outwards: no step.
        let x = [1.2 - d.shift[0], 1.6 - d.shift[1]];
        assert_eq!(d.feasible_step(&x, &[-1.0, -1.0]), 0.0);
        assert_eq!(
            disc(f64::INFINITY).feasible_step(&x, &[-1.0, -1.0]),
            f64::INFINITY
        );
        // Glued (r = ∞): always free, the slack notwithstanding.
        assert!(disc(f64::INFINITY).is_free(&[1e300, -1e300]));
        assert!(d.is_free(&[-d.shift[0], -d.shift[1]]));
    }

    /// On the circle the chopped gradient is g when −g points inwards, its
    /// tangential part (orthogonal to z) when −g points outwards.
    #[test]
    fn the_chopped_gradient_is_the_projected_gradient() {
        let d = disc(2.0);
        let x = [1.2 - d.shift[0], 1.6 - d.shift[1]];
        assert!(!d.is_free(&x));
        let mut b = [0.0; 2];
        d.chopped(&x, &[0.6, 0.8], &mut b);
        assert_eq!(b, [0.6, 0.8]);
        d.chopped(&x, &[-1.0, 0.5], &mut b);
        // −g = (1, −0.5) leaves through ν = (0.6, 0.8): its normal part goes.
        assert!((b[0] * 0.6 + b[1] * 0.8).abs() < 1e-15, "{b:?}");
        assert!((b[0] - (-1.0 + 0.2 * 0.6)).abs() < 1e-15, "{b:?}");
        disc(0.0).chopped(&[-0.25, 0.5], &[1.0, 2.0], &mut b);
        assert_eq!(b, [0.0, 0.0]);
    }

    /// Interval answers are the box formulas of MPRGP.
    #[test]
    fn interval_answers_are_the_box_formulas() {
        let iv = Interval { lo: -1.0, hi: 2.0 };
        assert_eq!(iv.feasible_step(&[0.0], &[0.5]), 2.0);
        assert_eq!(iv.feasible_step(&[0.0], &[-0.5]), 4.0);
        let mut x = [0.0];
        assert!(!iv.step(&mut x, 10.0, &[-1.0]));
        assert_eq!(x, [2.0]);
        let mut b = [9.0];
        iv.chopped(&[-1.0], &[3.0], &mut b);
        assert_eq!(b, [0.0]);
        iv.chopped(&[-1.0], &[-3.0], &mut b);
        assert_eq!(b, [-3.0]);
        assert_eq!(iv.reduced_dot(&[0.0], &[4.0], 0.5), 2.0 * 4.0);
    }
}
