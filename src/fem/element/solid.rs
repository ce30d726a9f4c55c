//! The P1 tetrahedron of the solid kind (docs/design.md §"Adding a kind:
//! solid 3D"): D6, B (6×12), C_e = |T| BᵀD6B, stresses, the 3D von Mises
//! and principal stresses.

use super::*;

pub(super) fn sub(a: Point3, b: Point3) -> Vector3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn cross(a: Vector3, b: Vector3) -> Vector3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn dot(a: Vector3, b: Vector3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// D6 of an isotropic solid for ε = (εxx, εyy, εzz, 2εxy, 2εyz, 2εxz):
/// λ + 2μ on the normal diagonal, λ off it, μ on the shears.
pub fn d_solid(m: &Material) -> [[f64; 6]; 6] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let (a, b, g) = (f * (1.0 - nu), f * nu, f * (1.0 - 2.0 * nu) / 2.0);
    let mut d = [[0.0; 6]; 6];
    for i in 0..3 {
        for j in 0..3 {
            d[i][j] = if i == j { a } else { b };
        }
        d[3 + i][3 + i] = g;
    }
    d
}

/// B (6×12) of a tetrahedron, for ε in the order of [`d_solid`], and its
/// volume |T|: the gradients of the barycentric coordinates are the rows
/// of J⁻¹, J = [p1 − p0, p2 − p0, p3 − p0] (cofactors over det J = 6|T|).
pub fn tet_b(p: &[Point3; 4]) -> ([[f64; 12]; 6], f64) {
    let (e1, e2, e3) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let det = dot(e1, cross(e2, e3));
    let g1 = cross(e2, e3).map(|c| c / det);
    let g2 = cross(e3, e1).map(|c| c / det);
    let g3 = cross(e1, e2).map(|c| c / det);
    let g0 = [0, 1, 2].map(|k| -(g1[k] + g2[k] + g3[k]));
    let mut b = [[0.0; 12]; 6];
    for (a, g) in [g0, g1, g2, g3].iter().enumerate() {
        let c = 3 * a;
        b[0][c] = g[0];
        b[1][c + 1] = g[1];
        b[2][c + 2] = g[2];
        b[3][c] = g[1];
        b[3][c + 1] = g[0];
        b[4][c + 1] = g[2];
        b[4][c + 2] = g[1];
        b[5][c] = g[2];
        b[5][c + 2] = g[0];
    }
    (b, det.abs() / 6.0)
}

/// C_e = |T| BᵀD6B (12×12) of a tetrahedron.
pub fn tet_stiffness(p: &[Point3; 4], d6: &[[f64; 6]; 6]) -> [[f64; 12]; 12] {
    let (b, vol) = tet_b(p);
    let mut db = [[0.0; 12]; 6];
    for i in 0..6 {
        for j in 0..12 {
            db[i][j] = (0..6).map(|k| d6[i][k] * b[k][j]).sum();
        }
    }
    let mut k = [[0.0; 12]; 12];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = vol * (0..6).map(|l| b[l][i] * db[l][j]).sum::<f64>();
        }
    }
    k
}

/// σ = D6 B u of a tetrahedron, (σxx, σyy, σzz, σxy, σyz, σxz).
pub fn tet_stress(p: &[Point3; 4], d6: &[[f64; 6]; 6], u: &[f64; 12]) -> [f64; 6] {
    let (b, _) = tet_b(p);
    let mut e = [0.0; 6];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..12).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 6];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..6).map(|k| d6[i][k] * e[k]).sum();
    }
    s
}

/// The 3D von Mises stress of (σxx, σyy, σzz, σxy, σyz, σxz):
/// sqrt(½[(σxx−σyy)² + (σyy−σzz)² + (σzz−σxx)²] + 3(σxy² + σyz² + σxz²)).
pub fn von_mises_solid(s: &[f64; 6]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]))
        .max(0.0)
        .sqrt()
}

/// The principal stresses σ1 ≥ σ2 ≥ σ3 of (σxx, σyy, σzz, σxy, σyz, σxz):
/// the eigenvalues of the symmetric 3×3 tensor by the trigonometric
/// formula of the deviator's invariants (Smith, CACM 4 (1961) 168).
pub fn principal_solid(s: &[f64; 6]) -> [f64; 3] {
    let (xx, yy, zz, xy, yz, xz) = (s[0], s[1], s[2], s[3], s[4], s[5]);
    let off = xy * xy + yz * yz + xz * xz;
    let q = (xx + yy + zz) / 3.0;
    let (a, b, c) = (xx - q, yy - q, zz - q);
    let p2 = a * a + b * b + c * c + 2.0 * off;
    if p2 <= 0.0 || !p2.is_finite() {
        return [q, q, q];
    }
    let p = (p2 / 6.0).sqrt();
    // det((σ − qI)/p) / 2
    let det = a * (b * c - yz * yz) - xy * (xy * c - yz * xz) + xz * (xy * yz - b * xz);
    let r = (det / (p * p * p) / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let s1 = q + 2.0 * p * phi.cos();
    let s3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    [s1, 3.0 * q - s1 - s3, s3]
}
