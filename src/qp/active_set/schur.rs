//! ASM-E's face solver (docs/methods.md §4.7): exact elimination through the
//! Schur complement on the constraints. With Z = C⁻¹ (one sparse Cholesky
//! factor of C, reused; for semicoercive C the generalised inverse
//! (C + springs at fixing DOFs)⁻¹, `linalg::cholesky`),
//! `S_J λ_J = A_J Z r − e_J`, S_J = A_J Z A_Jᵀ (dense |J|×|J|, SPD), then
//! δ = Z(r − A_Jᵀλ_J) + Rα, where α solves the small SPD system of the rigid
//! motions J fixes (FETI: the solvability condition Rᵀ(r − A_Jᵀλ) = 0). The
//! dense factor of S_J is updated as J changes ([`PackedChol`]: a new row
//! costs one solve with C, a deleted one Givens rotations).

use super::{FaceKernel, FaceSolver};
use crate::linalg::cholesky::Cholesky;
use crate::linalg::dense::{spd_solve, PackedChol};
use crate::linalg::sparse::{axpy, dot};
use crate::qp::QpProblem;

/// ASM-E's face solver (module doc).
pub(crate) struct SchurSolver<'a> {
    qp: &'a QpProblem,
    chol: Cholesky,
    s: PackedChol,
    solves: usize,
}

impl<'a> SchurSolver<'a> {
    pub(crate) fn new(qp: &'a QpProblem, chol: Cholesky) -> Self {
        SchurSolver {
            qp,
            chol,
            s: PackedChol::default(),
            solves: 0,
        }
    }

    /// Z v
    fn zsolve(&mut self, v: &mut [f64]) {
        self.solves += 1;
        self.chol.solve_in_place(v);
    }
}

impl FaceSolver for SchurSolver<'_> {
    fn push(&mut self, j: usize, jl: &[usize]) -> bool {
        let qp = self.qp;
        let mut z = vec![0.0; qp.n()];
        let (c, v) = qp.a.row(j);
        for (&k, &a) in c.iter().zip(v) {
            z[k] = a;
        }
        self.zsolve(&mut z);
        let col: Vec<f64> = jl.iter().map(|&i| qp.a.row_dot(i, &z)).collect();
        let diag = qp.a.row_dot(j, &z);
        self.s.push(&col, diag)
    }

    fn remove(&mut self, pos: usize) {
        self.s.remove(pos);
    }

    fn solve(
        &mut self,
        r: &[f64],
        e: &[f64],
        jl: &[usize],
        fk: &FaceKernel,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let qp = self.qp;
        let mut z = r.to_vec();
        self.zsolve(&mut z);
        // λ0 = S⁻¹ (A_J Z r − e)
        let mut lam: Vec<f64> = jl
            .iter()
            .zip(e)
            .map(|(&j, &ej)| qp.a.row_dot(j, &z) - ej)
            .collect();
        self.s.solve_in_place(&mut lam);
        // Rigid motions fixed by J: α on range(Gᵀ), Gr = A_J R Q_r.
        let q = fk.range.len();
        let mut alpha = vec![0.0; q];
        if q > 0 {
            let gr: Vec<Vec<f64>> = fk
                .range_vecs
                .iter()
                .map(|v| jl.iter().map(|&j| qp.a.row_dot(j, v)).collect())
                .collect();
            let w: Vec<Vec<f64>> = gr
                .iter()
                .map(|g| {
                    let mut t = g.clone();
                    self.s.solve_in_place(&mut t);
                    t
                })
                .collect();
            let mut kmat = vec![0.0; q * q];
            for a in 0..q {
                for b in 0..q {
                    kmat[a * q + b] = dot(&gr[a], &w[b]);
                }
            }
            let rhs: Vec<f64> = (0..q)
                .map(|a| dot(&fk.range_vecs[a], r) - dot(&gr[a], &lam))
                .collect();
            alpha =
                spd_solve(&kmat, q, &rhs).ok_or("the rigid-motion system Gᵀ S⁻¹ G is singular")?;
            for (wa, &aa) in w.iter().zip(&alpha) {
                axpy(aa, wa, &mut lam);
            }
        }
        // δ = Z (r − A_Jᵀλ) + R Q_r α
        let mut delta = r.to_vec();
        for (&j, &l) in jl.iter().zip(&lam) {
            let (c, v) = qp.a.row(j);
            for (&k, &a) in c.iter().zip(v) {
                delta[k] -= a * l;
            }
        }
        self.zsolve(&mut delta);
        for (v, &aa) in fk.range_vecs.iter().zip(&alpha) {
            axpy(aa, v, &mut delta);
        }
        // Free force-free rigid motions: remove their component (any is optimal).
        for v in &fk.free {
            let t = dot(&delta, v);
            axpy(-t, v, &mut delta);
        }
        Ok((delta, lam))
    }

    fn inner(&self) -> usize {
        self.solves
    }
}
