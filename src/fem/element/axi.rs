//! The axisymmetric P1 triangle (docs/methods.md §10): D4, B4 with the
//! hoop row at the centroid, C_e = r̄|T| B4ᵀD4B4, the exact body-load
//! integrals, stresses and von Mises with σθθ.

use super::*;

/// D4 of an axisymmetric body for ε = (ε_rr, ε_zz, 2ε_rz, ε_θθ)
/// (docs/methods.md §10; Zienkiewicz & Taylor, The Finite Element Method,
/// vol. 1, ch. "Axisymmetric stress analysis").
pub fn d_axi(m: &Material) -> [[f64; 4]; 4] {
    let (e, nu) = (m.e, m.nu);
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let (a, b, g) = (f * (1.0 - nu), f * nu, f * (1.0 - 2.0 * nu) / 2.0);
    [
        [a, b, 0.0, b],
        [b, a, 0.0, b],
        [0.0, 0.0, g, 0.0],
        [b, b, 0.0, a],
    ]
}

/// The centroid radius r̄ = (r₁ + r₂ + r₃)/3 of a triangle (x = r).
pub fn centroid_r(p: &[Point; 3]) -> f64 {
    (p[0][0] + p[1][0] + p[2][0]) / 3.0
}

/// B4 (4×6) of the axisymmetric P1 triangle with the hoop row evaluated
/// at the centroid, N_a(r̄)/r̄ = 1/(3r̄): the one-point rule for the hoop
/// terms, finite whenever the triangle has area (r̄ > 0 even with two
/// vertices on the axis), with |T|, r̄. Zienkiewicz & Taylor (vol. 1,
/// "Axisymmetric stress analysis") give this centroid approximation; the
/// in-plane rows are constant, so r̄|T| BᵀD4B is the one-point rule of
/// ∫ BᵀD4B r dA (docs/methods.md §10).
pub fn axi_b(p: &[Point; 3]) -> ([[f64; 6]; 4], f64, f64) {
    let (b3, area) = b_matrix(p);
    let rbar = centroid_r(p);
    let mut b = [[0.0; 6]; 4];
    b[..3].copy_from_slice(&b3);
    for a in 0..3 {
        b[3][2 * a] = 1.0 / (3.0 * rbar);
    }
    (b, area, rbar)
}

/// C_e = r̄ |T| B4ᵀ D4 B4 (6×6, per radian) of the axisymmetric triangle.
pub fn axi_stiffness(p: &[Point; 3], d4: &[[f64; 4]; 4]) -> [[f64; 6]; 6] {
    let (b, area, rbar) = axi_b(p);
    let mut db = [[0.0; 6]; 4];
    for i in 0..4 {
        for j in 0..6 {
            db[i][j] = (0..4).map(|k| d4[i][k] * b[k][j]).sum();
        }
    }
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = rbar * area * (0..4).map(|l| b[l][i] * db[l][j]).sum::<f64>();
        }
    }
    k
}

/// ∫ N_a (f_b r + c r² e_r) dA over an axisymmetric triangle, exactly
/// (∫ λ₁^i λ₂^j λ₃^k dA = 2|T| i! j! k! / (i + j + k + 2)!): the nodal force
/// per radian of vertex `a` from a body force f_b (gravity, along z) and a
/// centrifugal load c r along r (c = ρω²).
pub fn axi_body_load(p: &[Point; 3], a: usize, fb: Vector, c: f64) -> Vector {
    let area = area2(p) / 2.0;
    let r = [p[0][0], p[1][0], p[2][0]];
    let w1 = area / 12.0 * (r[a] + r[0] + r[1] + r[2]);
    let fact = [1.0, 1.0, 2.0, 6.0];
    let mut w2 = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let mut k = [0usize; 3];
            k[a] += 1;
            k[i] += 1;
            k[j] += 1;
            w2 += r[i] * r[j] * 2.0 * area * fact[k[0]] * fact[k[1]] * fact[k[2]] / 120.0;
        }
    }
    [w1 * fb[0] + c * w2, w1 * fb[1]]
}

/// (σ_rr, σ_zz, σ_rz, σ_θθ) at the centroid of an axisymmetric triangle.
pub(super) fn axi_stress(p: &[Point; 3], d4: &[[f64; 4]; 4], u: &[f64; 6]) -> [f64; 4] {
    let (b, _, _) = axi_b(p);
    let mut e = [0.0; 4];
    for (i, ei) in e.iter_mut().enumerate() {
        *ei = (0..6).map(|j| b[i][j] * u[j]).sum();
    }
    let mut s = [0.0; 4];
    for (i, si) in s.iter_mut().enumerate() {
        *si = (0..4).map(|k| d4[i][k] * e[k]).sum();
    }
    s
}

/// von Mises from the four components (σ_rr, σ_zz, σ_rz, σ_θθ) of an
/// axisymmetric stress: sqrt(½[(σ1−σ2)² + (σ2−σ3)² + (σ3−σ1)²] + 3τ²).
pub fn von_mises_axi(s: &[f64; 4]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[3], s[3] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * s[2] * s[2])
        .max(0.0)
        .sqrt()
}
