//! [`Discrete`]: what every assembled model is, plane or solid, as the load
//! steps ask it (docs/design.md §"Element kinds"): points whose
//! displacements are u_p = u0_p + T_p ξ_p (`conditions::eliminate`), the
//! QP over ξ, and with friction the tangential rows whose slip is measured
//! from the last step (docs/methods.md §9.5, §12.2). The plane
//! [`super::Model`] and the solid [`super::solid::SolidModel`] give the
//! parts that are their own (their DOFs, their QP, the tangential
//! displacement of their rows); the rest is written here once for D = 2
//! and D = 3.

use super::conditions::PointDofs;
use super::element::PointD;
use crate::qp::QpProblem;

/// a·b summed from the first component on: the order that fixes the bits
/// (a0 b0 + a1 b1 in the plane, + a2 b2 in 3D).
#[inline]
fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    let mut s = a[0] * b[0];
    for k in 1..D {
        s += a[k] * b[k];
    }
    s
}

/// Point displacements u_p = u0_p + T_p ξ_p of the unknowns `x`.
pub fn point_displacements<const D: usize>(dofs: &[PointDofs<D>], x: &[f64]) -> Vec<PointD<D>> {
    dofs.iter()
        .map(|p| {
            let mut u = p.u0;
            for k in 0..p.ndof {
                let xi = x[p.start + k];
                for (c, uc) in u.iter_mut().enumerate() {
                    *uc += p.t[k][c] * xi;
                }
            }
            u
        })
        .collect()
}

/// An assembled model of dimension D, plane (D = 2) or solid (D = 3).
pub trait Discrete<const D: usize> {
    /// u_p = u0_p + T_p ξ_p of every point.
    fn dofs(&self) -> &[PointDofs<D>];
    fn qp(&self) -> &QpProblem;
    fn qp_mut(&mut self) -> &mut QpProblem;
    /// The tangential relative displacement of every row of the friction's
    /// T for the point displacements `u` (one per QP row in the plane, two
    /// in 3D).
    fn tangential_displacement(&self, u: &[PointD<D>]) -> Vec<f64>;

    /// ξ_p = T_pᵀ(u_p − u0_p): the unknowns of point displacements `u`
    /// (T_p's columns are orthonormal): the warm start of the next step.
    fn reduce(&self, u: &[PointD<D>]) -> Vec<f64> {
        let mut x = vec![0.0; self.qp().n()];
        for (p, pd) in self.dofs().iter().enumerate() {
            let mut du = [0.0; D];
            for (c, v) in du.iter_mut().enumerate() {
                *v = u[p][c] - pd.u0[c];
            }
            for k in 0..pd.ndof {
                x[pd.start + k] = dot(&pd.t[k], &du);
            }
        }
        x
    }

    /// The offset t0 that makes the slip T x − t0 the increment from the
    /// point displacements `u_prev` (the previous load step's; None: the
    /// reference configuration): their tangential displacement less the
    /// part the prescribed displacements u0 of this model contribute
    /// (docs/methods.md §9.5, §12.2).
    fn slip_offset(&self, u_prev: Option<&[PointD<D>]>) -> Vec<f64> {
        let u0: Vec<PointD<D>> = self.dofs().iter().map(|p| p.u0).collect();
        let from_u0 = self.tangential_displacement(&u0);
        match u_prev {
            None => from_u0.iter().map(|v| -v).collect(),
            Some(u) => self
                .tangential_displacement(u)
                .iter()
                .zip(&from_u0)
                .map(|(a, b)| a - b)
                .collect(),
        }
    }

    /// Set the slip offset of the model's friction from the previous
    /// step's point displacements (None: the reference configuration;
    /// nothing without friction).
    fn start_step(&mut self, u_prev: Option<&[PointD<D>]>) {
        if self.qp().friction.is_some() {
            let t0 = self.slip_offset(u_prev);
            if let Some(f) = self.qp_mut().friction.as_mut() {
                f.t0 = t0;
            }
        }
    }
}
