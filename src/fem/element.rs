//! The P1 element of docs/methods.md §1.4 and §2.2: material matrix D, strain
//! matrix B, element stiffness C_e = t_h|T| BᵀDB, stresses τ̄ = D B x_e.

use crate::problem::{Material, Plane};

/// D for ē = (e11, e22, 2e12) (methods.md §1.4).
pub fn d_matrix(m: &Material, plane: Plane) -> [[f64; 3]; 3] {
    let (e, nu) = (m.e, m.nu);
    match plane {
        Plane::Strain => {
            let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            [
                [f * (1.0 - nu), f * nu, 0.0],
                [f * nu, f * (1.0 - nu), 0.0],
                [0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
            ]
        }
        Plane::Stress => {
            let f = e / (1.0 - nu * nu);
            [
                [f, f * nu, 0.0],
                [f * nu, f, 0.0],
                [0.0, 0.0, f * (1.0 - nu) / 2.0],
            ]
        }
    }
}

/// Twice the signed area: positive for counter-clockwise vertices.
pub fn area2(p: &[[f64; 2]; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
}

/// B (3×6) of §2.2 for counter-clockwise vertices, and |T|.
pub fn b_matrix(p: &[[f64; 2]; 3]) -> ([[f64; 6]; 3], f64) {
    let a2 = area2(p);
    let b = [p[1][1] - p[2][1], p[2][1] - p[0][1], p[0][1] - p[1][1]];
    let c = [p[2][0] - p[1][0], p[0][0] - p[2][0], p[1][0] - p[0][0]];
    let mut bm = [[0.0; 6]; 3];
    for a in 0..3 {
        bm[0][2 * a] = b[a] / a2;
        bm[1][2 * a + 1] = c[a] / a2;
        bm[2][2 * a] = c[a] / a2;
        bm[2][2 * a + 1] = b[a] / a2;
    }
    (bm, a2 / 2.0)
}

/// D B (3×6).
#[inline]
fn d_times_b(d: &[[f64; 3]; 3], b: &[[f64; 6]; 3]) -> [[f64; 6]; 3] {
    let mut db = [[0.0; 6]; 3];
    for i in 0..3 {
        for j in 0..6 {
            db[i][j] = (0..3).map(|k| d[i][k] * b[k][j]).sum();
        }
    }
    db
}

/// Entry (i, j) of C_e from B, |T| and D B: the one expression that both
/// [`stiffness`] and [`stiffness_rows`] use, so that they agree bit for bit.
#[inline]
fn ke_entry(b: &[[f64; 6]; 3], db: &[[f64; 6]; 3], th: f64, area: f64, i: usize, j: usize) -> f64 {
    th * area * (0..3).map(|l| b[l][i] * db[l][j]).sum::<f64>()
}

/// C_e = t_h |T| BᵀDB (6×6).
pub fn stiffness(p: &[[f64; 2]; 3], d: &[[f64; 3]; 3], th: f64) -> [[f64; 6]; 6] {
    let (b, area) = b_matrix(p);
    let db = d_times_b(d, &b);
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ke_entry(&b, &db, th, area, i, j);
        }
    }
    k
}

/// Rows 2a and 2a+1 of C_e (the two rows of vertex `a`), bit for bit equal
/// to those of [`stiffness`].
#[inline]
pub fn stiffness_rows(p: &[[f64; 2]; 3], d: &[[f64; 3]; 3], th: f64, a: usize) -> [[f64; 6]; 2] {
    let (b, area) = b_matrix(p);
    let db = d_times_b(d, &b);
    let mut k = [[0.0; 6]; 2];
    for (r, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ke_entry(&b, &db, th, area, 2 * a + r, j);
        }
    }
    k
}

/// Stresses (σxx, σyy, σxy, σzz) from the element displacements.
pub fn stress(
    p: &[[f64; 2]; 3],
    d: &[[f64; 3]; 3],
    m: &Material,
    plane: Plane,
    u: &[f64; 6],
) -> [f64; 4] {
    let (b, _) = b_matrix(p);
    let mut e = [0.0; 3];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..6).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 3];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..3).map(|k| d[i][k] * e[k]).sum();
    }
    let szz = match plane {
        Plane::Strain => m.nu * (s[0] + s[1]),
        Plane::Stress => 0.0,
    };
    [s[0], s[1], s[2], szz]
}

/// The report's equivalent stress τe = sqrt(σxx² + σyy² − σxxσyy + 3σxy²) (§1.4).
pub fn von_mises(s: &[f64; 4]) -> f64 {
    (s[0] * s[0] + s[1] * s[1] - s[0] * s[1] + 3.0 * s[2] * s[2])
        .max(0.0)
        .sqrt()
}

/// In-plane principal stresses, σ1 ≥ σ2.
pub fn principal(s: &[f64; 4]) -> [f64; 2] {
    let c = 0.5 * (s[0] + s[1]);
    let r = (0.25 * (s[0] - s[1]).powi(2) + s[2] * s[2]).sqrt();
    [c + r, c - r]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_motions_have_zero_energy_and_stiffness_is_symmetric() {
        let p = [[0.0, 0.0], [2.0, 0.3], [0.4, 1.5]];
        let m = Material {
            e: 1e9,
            nu: 0.3,
            rho: 0.0,
        };
        let d = d_matrix(&m, Plane::Strain);
        let k = stiffness(&p, &d, 1.0);
        for i in 0..6 {
            for j in 0..6 {
                assert!((k[i][j] - k[j][i]).abs() < 1e-6 * k[0][0].abs());
            }
        }
        // translations and the infinitesimal rotation (−y, x)
        let modes = [
            [1.0, 0.0, 1.0, 0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
            [-p[0][1], p[0][0], -p[1][1], p[1][0], -p[2][1], p[2][0]],
        ];
        for z in modes {
            for row in k.iter() {
                let f: f64 = row.iter().zip(&z).map(|(a, b)| a * b).sum();
                assert!(f.abs() < 1e-6 * k[0][0].abs(), "{f}");
            }
        }
    }

    #[test]
    fn stiffness_rows_equal_stiffness_bit_for_bit() {
        let p = [[0.1, -0.2], [2.3, 0.35], [0.45, 1.7]];
        let m = Material {
            e: 3.1e10,
            nu: 0.27,
            rho: 0.0,
        };
        for plane in [Plane::Strain, Plane::Stress] {
            let d = d_matrix(&m, plane);
            let k = stiffness(&p, &d, 0.7);
            for a in 0..3 {
                let r = stiffness_rows(&p, &d, 0.7, a);
                assert_eq!(r[0], k[2 * a]);
                assert_eq!(r[1], k[2 * a + 1]);
            }
        }
    }

    #[test]
    fn uniaxial_stress_state() {
        // u = (εx, 0): plane stress σxx = E/(1−ν²) ε, σyy = ν σxx
        let p = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let m = Material {
            e: 200.0,
            nu: 0.25,
            rho: 0.0,
        };
        let d = d_matrix(&m, Plane::Stress);
        let eps = 1e-3;
        let u = [0.0, 0.0, eps, 0.0, 0.0, 0.0];
        let s = stress(&p, &d, &m, Plane::Stress, &u);
        let sxx = 200.0 / (1.0 - 0.0625) * eps;
        assert!((s[0] - sxx).abs() < 1e-12);
        assert!((s[1] - 0.25 * sxx).abs() < 1e-12);
        assert_eq!(s[3], 0.0);
        let pr = principal(&s);
        assert!((pr[0] - sxx).abs() < 1e-12 && (pr[1] - 0.25 * sxx).abs() < 1e-12);
    }
}
