//! The plane P1 triangle (docs/methods.md §1.4, §2.2): D of plane strain
//! and plane stress, B, C_e = t_h|T| BᵀDB, stresses, the report's
//! equivalent stress and the principal stresses.

use super::*;

/// D of plane strain for ē = (e11, e22, 2e12) (methods.md §1.4); also the
/// in-plane block of the axisymmetric D4.
pub(super) fn d_plane_strain(m: &Material) -> [[f64; 3]; 3] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    [
        [f * (1.0 - nu), f * nu, 0.0],
        [f * nu, f * (1.0 - nu), 0.0],
        [0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
    ]
}

/// D of plane stress for ē = (e11, e22, 2e12) (methods.md §1.4).
pub(super) fn d_plane_stress(m: &Material) -> [[f64; 3]; 3] {
    let (e, nu) = (m.e, m.nu);
    let f = e / (1.0 - nu * nu);
    [
        [f, f * nu, 0.0],
        [f * nu, f, 0.0],
        [0.0, 0.0, f * (1.0 - nu) / 2.0],
    ]
}

/// Twice the signed area: positive for counter-clockwise vertices.
pub fn area2(p: &[Point; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
}

/// B (3×6) of §2.2 for counter-clockwise vertices, and |T|.
pub fn b_matrix(p: &[Point; 3]) -> ([[f64; 6]; 3], f64) {
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
pub fn stiffness(p: &[Point; 3], d: &[[f64; 3]; 3], th: f64) -> [[f64; 6]; 6] {
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
pub fn stiffness_rows(p: &[Point; 3], d: &[[f64; 3]; 3], th: f64, a: usize) -> [[f64; 6]; 2] {
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

/// Stresses (σxx, σyy, σxy, σzz) of a plane element from its
/// displacements: σzz = ν(σxx + σyy) when `out_of_plane` (plane strain),
/// else 0.
pub(super) fn plane_stress_of(
    p: &[Point; 3],
    d: &[[f64; 3]; 3],
    nu: f64,
    out_of_plane: bool,
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
    let szz = if out_of_plane {
        nu * (s[0] + s[1])
    } else {
        0.0
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
