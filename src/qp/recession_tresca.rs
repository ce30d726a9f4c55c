//! Is a Tresca problem bounded below? (docs/methods.md §9.3, "Unbounded
//! with friction"). With the bounds sᵢ given, a rigid motion r = Rα can
//! run away iff the loads' work on it exceeds what the contact rows can
//! resist: dᵀr > Σᵢ sᵢ‖(Tr)ᵢ‖ with Ar ≤ 0. Equivalently the loads on the
//! rigid motions, w = Rᵀd, are not in the set K = {(BR)ᵀλ : λ_n ≥ 0,
//! ‖λ_tᵢ‖ ≤ sᵢ} of forces the rows can balance; then ρ = w − P_K(w) gives
//! the direction r = Rρ, for which dᵀr − Σᵢ sᵢ‖(Tr)ᵢ‖ ≥ ‖ρ‖² and Ar ≤ 0
//! (the optimality of the projection). The projection is found by
//! accelerated projected gradient (FISTA, Beck & Teboulle, SIAM J.
//! Imaging Sci. 2, 2009) in λ; the direction is accepted only by an
//! independent check ([`certify`]) in each quantity's own scale, so an
//! inexact projection can miss a borderline case (the method's failure
//! then stands) but never invent one. Used by the driver when a method
//! did not converge on a frictional problem: mprgp's SMALBE stagnates on
//! such a problem (its equality has no solution in the discs) where ssn
//! decides the slide itself. Coulomb's bound μλ_n is not fixed by the
//! rigid motions alone (λ_n comes from the bodies' elastic balance), so
//! this decision is Tresca's only.

use crate::linalg::sparse::{dot, norm};
use crate::qp::recession::{self, Recession};
use crate::qp::{tangential_norm, QpProblem, SlipBound};

/// Most FISTA steps.
const MAX_STEPS: usize = 20_000;
/// The loads on the rigid motions are balanced when ‖ρ‖ ≤ BALANCED·‖w‖.
const BALANCED: f64 = 1e-9;
/// Relative tolerance of the work against the friction's dissipation.
const SIGN_TOL: f64 = 1e-9;

/// A verified direction along which the Tresca problem `qp` is unbounded
/// below, or None (bounded, not Tresca, no rigid motion, or not found).
pub fn tresca_recession(qp: &QpProblem) -> Option<Recession> {
    let fr = qp.friction.as_ref()?;
    let SlipBound::Tresca(s) = &fr.bound else {
        return None;
    };
    let r = recession::normalized(&qp.kernel);
    let k = r.len();
    if k == 0 {
        return None;
    }
    let (m, per) = (qp.m(), fr.frame.rows());
    // The columns of M = (BR)ᵀ: the normal rows', then the tangential rows'.
    let cols: Vec<Vec<f64>> = (0..m)
        .map(|i| r.iter().map(|z| qp.a.row_dot(i, z)).collect())
        .chain((0..fr.t.nrows).map(|j| r.iter().map(|z| fr.t.row_dot(j, z)).collect()))
        .collect();
    let w: Vec<f64> = r.iter().map(|z| dot(z, &qp.d)).collect();
    let wn = norm(&w);
    if !(wn > 0.0) {
        return None;
    }
    // Step 1/L, L the largest eigenvalue of MMᵀ (k × k).
    let mut mmt = vec![vec![0.0; k]; k];
    for c in &cols {
        for a in 0..k {
            for b in 0..k {
                mmt[a][b] += c[a] * c[b];
            }
        }
    }
    let (ev, _) = crate::linalg::dense::sym_eigen(&mmt);
    let l = ev.iter().fold(0.0f64, |a, &v| a.max(v));
    if !(l > 0.0 && l.is_finite()) {
        return None;
    }
    let project = |lam: &mut [f64]| {
        for (i, si) in s.iter().enumerate().take(m) {
            lam[i] = lam[i].max(0.0);
            let t = &mut lam[m + per * i..m + per * (i + 1)];
            let nt = tangential_norm(t);
            if nt > *si {
                let f = if nt > 0.0 { si / nt } else { 0.0 };
                t.iter_mut().for_each(|v| *v *= f);
            }
        }
    };
    let residual = |lam: &[f64]| -> Vec<f64> {
        let mut rho = w.clone();
        for (c, &v) in cols.iter().zip(lam) {
            if v != 0.0 {
                for (ra, ca) in rho.iter_mut().zip(c) {
                    *ra -= v * ca;
                }
            }
        }
        rho
    };
    let nl = cols.len();
    let (mut lam, mut prev, mut y) = (vec![0.0; nl], vec![0.0; nl], vec![0.0; nl]);
    let mut tk = 1.0f64;
    let mut rho_last = w.clone();
    for step in 0..MAX_STEPS {
        let rho = residual(&y);
        for (j, c) in cols.iter().enumerate() {
            lam[j] = y[j] + dot(c, &rho) / l;
        }
        project(&mut lam);
        let t1 = 0.5 * (1.0 + (1.0 + 4.0 * tk * tk).sqrt());
        for j in 0..nl {
            y[j] = lam[j] + (tk - 1.0) / t1 * (lam[j] - prev[j]);
        }
        tk = t1;
        prev.clone_from(&lam);
        if step % 100 == 99 {
            let rho = residual(&lam);
            let change = norm(
                &rho.iter()
                    .zip(&rho_last)
                    .map(|(a, b)| a - b)
                    .collect::<Vec<_>>(),
            );
            let rn = norm(&rho);
            if rn <= BALANCED * wn {
                return None;
            }
            if change <= 1e-12 * wn {
                break;
            }
            rho_last = rho;
        }
    }
    let rho = residual(&lam);
    if norm(&rho) <= BALANCED * wn {
        return None;
    }
    let mut dir = vec![0.0; qp.n()];
    for (z, &a) in r.iter().zip(&rho) {
        for (d, zi) in dir.iter_mut().zip(z) {
            *d += a * zi;
        }
    }
    certify(qp, &dir).ok()
}

/// The direction's check: [`recession::certify`] (Cr = 0 body by body,
/// Ar ≤ 0 row by row, dᵀr > 0) and the loads' work beyond the friction's
/// dissipation, dᵀr − Σᵢ sᵢ‖(Tr)ᵢ‖ > 10⁻⁹·(Σⱼ|dⱼrⱼ| + Σᵢ sᵢΣⱼ|Tᵢⱼ|)
/// (r scaled to max|r| = 1, as certify scales it).
pub fn certify(qp: &QpProblem, dir: &[f64]) -> Result<Recession, String> {
    let c = recession::certify(qp, dir)?;
    let Some(fr) = &qp.friction else {
        return Ok(c);
    };
    let SlipBound::Tresca(s) = &fr.bound else {
        return Err("a Coulomb problem's bound is not fixed by its rigid motions".into());
    };
    let per = fr.frame.rows();
    let tr = fr.t.mul(&c.direction);
    let (mut diss, mut scale) = (0.0, 0.0);
    for (i, si) in s.iter().enumerate() {
        diss += si * tangential_norm(&tr[per * i..per * (i + 1)]);
        for j in per * i..per * (i + 1) {
            scale += si * fr.t.row(j).1.iter().map(|v| v.abs()).sum::<f64>();
        }
    }
    let abs: f64 =
        qp.d.iter()
            .zip(&c.direction)
            .map(|(d, r)| (d * r).abs())
            .sum();
    if c.work - diss > SIGN_TOL * (abs + scale) {
        Ok(c)
    } else {
        Err(format!(
            "friction resists it: dᵀr = {:.3e}, Σ s‖Tr‖ = {diss:.3e}",
            c.work
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::testing::friction_point3;

    /// A point floating in the plane of its floor, pressed by 2 and pushed
    /// by 0.5 at 53°: bounded while the push is inside the disc (s = 0.6),
    /// unbounded along the push beyond it (s = 0.4), at two scales of the
    /// loads and bounds 10⁶ apart; a direction across the push is refused.
    #[test]
    fn a_point_beyond_its_disc_runs_away_along_the_push() {
        for scale in [1.0, 1e6] {
            let f = [0.3 * scale, 0.4 * scale, -2.0 * scale];
            let held = friction_point3(0.0, f, SlipBound::Tresca(vec![0.6 * scale]));
            assert!(tresca_recession(&held).is_none());
            let pushed = friction_point3(0.0, f, SlipBound::Tresca(vec![0.4 * scale]));
            let c = tresca_recession(&pushed).expect("unbounded");
            let (a, b) = (c.direction[0], c.direction[1]);
            assert!(
                a > 0.0 && (a * 0.4 - b * 0.3).abs() < 1e-9 * a,
                "{:?}",
                c.direction
            );
            let mut across = vec![0.0; pushed.n()];
            across[0] = 0.4;
            across[1] = -0.3;
            assert!(certify(&pushed, &across).is_err());
            // Along the push but against a larger bound: friction resists.
            let mut along = vec![0.0; held.n()];
            along[0] = 0.3;
            along[1] = 0.4;
            assert!(certify(&held, &along).is_err());
            assert!(certify(&pushed, &along).is_ok());
        }
    }
}
