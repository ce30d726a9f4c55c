//! The rigid motions a frictional working set leaves free (docs/methods.md
//! §9.3): which ones, whether the loads drive a body along one further than
//! friction can hold (an unbounded problem), and the start that holds a body
//! pressed towards its support across a gap.

use super::*;

impl State<'_> {
    /// Start from every row in normal contact when the rows closed at the
    /// start leave free a rigid motion the loads work on (a body pressed
    /// towards its support across a gap): as the frictionless start does
    /// (docs/methods.md §4.10, §9.2).
    /// From the closed rows alone the dual path solves such a step as if
    /// the motion were held, so the body never moved into contact: a disc
    /// pressed onto a block across a gap of 5·10⁻⁴ kept N empty, and its
    /// sideways push was taken for sliding.
    pub(super) fn hold_free_bodies(&mut self) {
        self.in_n0 = self.in_n.clone();
        if self.r.is_empty() || self.in_n.iter().all(|a| *a) {
            return;
        }
        let m = self.qp.m();
        let brows: Vec<(bool, usize)> = (0..m)
            .filter(|&i| self.in_n[i])
            .flat_map(|i| [(false, i), (true, i)])
            .collect();
        // Only a motion the loads work on: one they do not (a plate free to
        // rock about the node it rests on, under a uniform pressure) is
        // solved with the pseudo-inverse, at the least motion (§1.7).
        let loaded = self.free_motions(&brows).iter().any(|z| {
            let (work, scale) = self.work_of_loads(z);
            work.abs() > 1e-8 * scale
        });
        if loaded {
            log::debug!(
                "ssn: friction: the closed rows leave a rigid motion free: every row starts in N"
            );
            self.in_n = vec![true; m];
            self.in_n0 = vec![true; m];
        }
    }

    /// Whether the working set `(n_set, tang)` leaves a rigid motion free
    /// along which the problem is bounded.
    pub(super) fn frees_a_bounded_motion(&self, n_set: &[bool], tang: &[Tangential]) -> bool {
        let m = self.qp.m();
        let brows: Vec<(bool, usize)> = (0..m)
            .filter(|&i| n_set[i])
            .map(|i| (false, i))
            .chain(
                (0..m)
                    .filter(|&i| tang[i] == Tangential::Stick)
                    .map(|i| (true, i)),
            )
            .collect();
        let free = self.free_motions(&brows);
        !free.is_empty() && self.unbounded_along(&free).is_none()
    }

    /// An orthonormal basis (as vectors of ℝⁿ) of the rigid motions z with
    /// B z = 0.
    pub(super) fn free_motions(&self, brows: &[(bool, usize)]) -> Vec<Vec<f64>> {
        let k = self.r.len();
        if k == 0 {
            return vec![];
        }
        let mut g = vec![vec![0.0; k]; k];
        let mut bnorm = 0.0;
        for &(t, i) in brows {
            let (cols, vals) = if t {
                self.fr.t.row(i)
            } else {
                self.qp.a.row(i)
            };
            bnorm += vals.iter().map(|v| v * v).sum::<f64>();
            let br: Vec<f64> = self
                .r
                .iter()
                .map(|rl| cols.iter().zip(vals).map(|(&j, &a)| a * rl[j]).sum())
                .collect();
            for a in 0..k {
                for c in 0..k {
                    g[a][c] += br[a] * br[c];
                }
            }
        }
        null_motions(&g, &self.r, self.qp.n(), bnorm)
    }

    /// A free rigid motion ±z (z in span `free`) along which the loads do
    /// more work than friction dissipates and no contact row closes.
    ///
    /// Under a given bound (a Tresca problem) any such z is a recession
    /// direction, so the loads projected on the free motions and each basis
    /// motion are tried. Under Coulomb's law or the glued start the bound
    /// of a row is set by its normal force, which an iterate that has not
    /// yet closed a row knows as zero: a disc above a block, pressed down
    /// and pushed sideways by less than μ times the pressing force, was
    /// refused as sliding along the push (docs/methods.md §9.3). There only
    /// the loads' own direction is tried: the body slides only if the loads
    /// move it without closing a row.
    pub(super) fn unbounded_along(&self, free: &[Vec<f64>]) -> Option<Vec<f64>> {
        let qp = self.qp;
        // Steepest: the loads projected on the free motions, then each basis vector.
        let mut cands: Vec<Vec<f64>> = vec![];
        let mut p = vec![0.0; qp.n()];
        for z in free {
            let w = dot(&qp.d, z);
            for (pj, zj) in p.iter_mut().zip(z) {
                *pj += w * zj;
            }
        }
        cands.push(p);
        let given_bound = !self.glued && self.coulomb.is_none();
        for z in free.iter().filter(|_| given_bound) {
            cands.push(z.clone());
            cands.push(z.iter().map(|v| -v).collect());
        }
        for z in cands {
            let zmax = norm_inf(&z);
            if !(zmax > 0.0) {
                continue;
            }
            // Az ≤ 0 row by row, C z = 0 and positive work, judged as the
            // driver judges a recession direction (a test of its own,
            // 10⁻¹⁰·Σ|a|·max|z| per row, let a direction that closed a row
            // of a masonry arch by 10⁻¹¹ of that through, and the driver
            // then refused the claim: exit 3 at μ = 0.2 and 0.3).
            if crate::qp::recession::certify(qp, &z).is_err() {
                continue;
            }
            let tz = self.fr.t.mul(&z);
            let (work, dscale) = self.work_of_loads(&z);
            let dissipation: f64 = tz.iter().zip(&self.s).map(|(t, s)| s * t.abs()).sum();
            if work - dissipation > 1e-10 * dscale {
                return Some(z);
            }
        }
        None
    }

    /// dᵀz, the loads' work along z, and Σ|dⱼzⱼ|, the scale it is judged
    /// against (scale-invariant tests: a 10⁸ stiffness contrast moves both).
    fn work_of_loads(&self, z: &[f64]) -> (f64, f64) {
        let d = &self.qp.d;
        (dot(d, z), d.iter().zip(z).map(|(a, b)| (a * b).abs()).sum())
    }
}

/// The rigid motions z = R v (R's columns `r`, n unknowns) of the null
/// space of the rows' Gram matrix `g` = Σ w (B R)ᵀ(B R): those the rows
/// leave free, to a tolerance relative to the rows' size `bnorm`. Shared
/// by 2D's rows and the discs' (plane_free.rs).
pub(super) fn null_motions(g: &[Vec<f64>], r: &[Vec<f64>], n: usize, bnorm: f64) -> Vec<Vec<f64>> {
    let (vals, vecs) = sym_eigen(g);
    let tol = 1e-9 * bnorm.max(1.0) / n.max(1) as f64;
    vals.iter()
        .zip(&vecs)
        .filter(|(e, _)| !(**e > tol))
        .map(|(_, v)| {
            let mut z = vec![0.0; n];
            for (c, rl) in v.iter().zip(r) {
                for (zj, rj) in z.iter_mut().zip(rl) {
                    *zj += c * rj;
                }
            }
            z
        })
        .collect()
}
