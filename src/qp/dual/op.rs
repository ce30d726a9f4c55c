//! The dual operator (docs/methods.md §4.6, §7): λ ↦ (PHP + ρQ)λ through
//! one Cholesky factor of C, or through H formed once ([`dense_h`]) for
//! the frictional dual's many Tresca solves; shared by every dual method.

use crate::linalg::cholesky::Cholesky;
use crate::linalg::dense::{chol_factor, chol_forward};
use crate::linalg::power;
use crate::linalg::sparse::dot;
use crate::qp::{QpError, QpProblem};

use super::POWER_ITERS;

/// The dual operator λ ↦ (PHP + ρQ)λ and what defines it: the factor K of C
/// (springs at the fixing DOFs when C is singular, so K⁻¹ is a generalised
/// inverse on range C), the kernel basis R, G̃ = L⁻¹RᵀAᵀ with orthonormal
/// rows (GGᵀ = LLᵀ), Q = G̃ᵀG̃, P = I − Q. With an empty kernel it is H.
pub(crate) struct DualOp<'a> {
    pub(super) qp: &'a QpProblem,
    pub(super) fac: Cholesky,
    /// Orthonormal basis of ker C.
    pub(super) r: Vec<Vec<f64>>,
    /// Rows of G̃ (k × m, orthonormal).
    pub(super) gt: Vec<Vec<f64>>,
    /// L with GGᵀ = LLᵀ (k×k row-major).
    pub(super) l: Vec<f64>,
    /// SMALBE's penalty ρ (0 until the host sets it).
    pub(super) rho: f64,
    /// Solves with the factor so far.
    pub(super) solves: usize,
    /// H = A K⁻¹ Aᵀ formed once ([`dense_h`]), m×m (symmetric: row- or
    /// column-major alike): then
    /// [`DualOp::h`] is a dense product, not a solve with K.
    pub(super) dense: Option<std::sync::Arc<Vec<f64>>>,
}

/// Columns of K⁻¹Aᵀ formed together in [`dense_h`].
pub(super) const DENSE_CHUNK: usize = 64;

/// H = A K⁻¹ Aᵀ (row-major m×m, symmetrised) for the factor `fac` of `qp`'s
/// C: m solves with K, 64 right-hand sides a pass. A Coulomb loop applies
/// the same H thousands of times (docs/methods.md §9.2: one Tresca solve a
/// bound, each hundreds of steps), where a solve with K of the geodynamic
/// model costs as much as a product with H of its 332 stacked rows ten
/// times over.
pub(crate) fn dense_h(qp: &QpProblem, fac: &Cholesky) -> Vec<f64> {
    let (n, m) = (qp.n(), qp.m());
    let mut h = vec![0.0; m * m];
    let mut x = vec![0.0; n * DENSE_CHUNK];
    for first in (0..m).step_by(DENSE_CHUNK) {
        let k = DENSE_CHUNK.min(m - first);
        let x = &mut x[..n * k];
        x.fill(0.0);
        for c in 0..k {
            let (cols, vals) = qp.a.row(first + c);
            for (&j, &v) in cols.iter().zip(vals) {
                x[c * n + j] += v;
            }
        }
        fac.solve_many_in_place(x, k);
        for i in 0..m {
            let (cols, vals) = qp.a.row(i);
            for c in 0..k {
                let col = &x[c * n..(c + 1) * n];
                h[i * m + first + c] = cols.iter().zip(vals).map(|(&j, &v)| v * col[j]).sum();
            }
        }
    }
    for i in 0..m {
        for j in 0..i {
            let v = 0.5 * (h[i * m + j] + h[j * m + i]);
            h[i * m + j] = v;
            h[j * m + i] = v;
        }
    }
    h
}

impl<'a> DualOp<'a> {
    /// The operator of `qp` (whose C is not used) with the factor `fac` of
    /// its C and the orthonormal kernel basis `r`; refuses a kernel that no
    /// contact row sees (G rank deficient).
    pub(crate) fn new(
        qp: &'a QpProblem,
        fac: Cholesky,
        r: Vec<Vec<f64>>,
        name: &str,
    ) -> Result<DualOp<'a>, QpError> {
        let m = qp.m();
        let k = r.len();
        // G = RᵀAᵀ (k×m), GGᵀ = LLᵀ, G̃ = L⁻¹G.
        let g0: Vec<Vec<f64>> = r.iter().map(|rl| qp.a.mul(rl)).collect();
        let mut l = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..k {
                l[a * k + b] = dot(&g0[a], &g0[b]);
            }
        }
        if !chol_factor(&mut l, k) {
            return Err(QpError::Unsupported(format!(
                "{name}: a rigid motion of a floating body is not restrained by any contact row \
                 (A·R rank deficient), the dual equality constraint is degenerate; use cgc or ssn"
            )));
        }
        let mut gt = vec![vec![0.0; m]; k];
        let mut col = vec![0.0; k];
        for i in 0..m {
            for (c, row) in col.iter_mut().zip(&g0) {
                *c = row[i];
            }
            chol_forward(&l, k, &mut col);
            for (row, c) in gt.iter_mut().zip(&col) {
                row[i] = *c;
            }
        }
        Ok(DualOp {
            qp,
            fac,
            r,
            gt,
            l,
            rho: 0.0,
            solves: 0,
            dense: None,
        })
    }
    /// Dimension k of the kernel.
    pub(crate) fn k(&self) -> usize {
        self.gt.len()
    }
    /// b ← K⁻¹ b
    pub(crate) fn solve_k(&mut self, b: &mut [f64]) {
        self.fac.solve_in_place(b);
        self.solves += 1;
    }
    /// x(λ) = K⁻¹(d − Aᵀλ) (rows with λᵢ = 0 skipped).
    pub(crate) fn x_of(&mut self, lam: &[f64]) -> Vec<f64> {
        let qp = self.qp;
        let mut b = qp.d.clone();
        for (i, &li) in lam.iter().enumerate() {
            if li != 0.0 {
                let (c, v) = qp.a.row(i);
                for (&j, &a) in c.iter().zip(v) {
                    b[j] -= a * li;
                }
            }
        }
        self.solve_k(&mut b);
        b
    }
    /// h = A K⁻¹ d − g
    pub(crate) fn h_vec(&mut self) -> Vec<f64> {
        let mut t = self.qp.d.clone();
        self.solve_k(&mut t);
        let qp = self.qp;
        qp.a.mul(&t).iter().zip(&qp.g).map(|(a, g)| a - g).collect()
    }
    /// Apply H through the dense `h` ([`dense_h`]) from now on.
    pub(crate) fn with_dense(&mut self, h: std::sync::Arc<Vec<f64>>) {
        debug_assert_eq!(h.len(), self.qp.m() * self.qp.m());
        self.dense = Some(h);
    }
    /// H v = A K⁻¹ Aᵀ v
    pub(crate) fn h(&mut self, v: &[f64]) -> Vec<f64> {
        if let Some(h) = &self.dense {
            // faer's product (SIMD lanes, several sums at once): a row by
            // row `dot` is one chain of dependent additions (60 % of the
            // geodynamic μ = 0.15 run, docs/methods.md §9.2).
            let m = v.len();
            let mut out = vec![0.0; m];
            faer::linalg::matmul::matmul(
                faer::MatMut::from_column_major_slice_mut(&mut out, m, 1),
                faer::Accum::Replace,
                faer::MatRef::from_column_major_slice(h, m, m),
                faer::MatRef::from_column_major_slice(v, m, 1),
                1.0,
                faer::Par::Seq,
            );
            return out;
        }
        let mut t = self.qp.a.mul_t(v);
        self.solve_k(&mut t);
        self.qp.a.mul(&t)
    }
    /// G̃ v
    pub(super) fn gmul(&self, v: &[f64]) -> Vec<f64> {
        self.gt.iter().map(|row| dot(row, v)).collect()
    }
    /// out += G̃ᵀ c
    pub(super) fn gt_add(&self, c: &[f64], out: &mut [f64]) {
        for (row, &cl) in self.gt.iter().zip(c) {
            for (o, r) in out.iter_mut().zip(row) {
                *o += cl * r;
            }
        }
    }
    /// v ← P v
    pub(super) fn project(&self, v: &mut [f64]) {
        if self.k() == 0 {
            return;
        }
        let c: Vec<f64> = self.gmul(v).iter().map(|a| -a).collect();
        self.gt_add(&c, v);
    }
    /// (PHP + ρQ) v
    pub(crate) fn apply(&mut self, v: &[f64]) -> Vec<f64> {
        if self.k() == 0 {
            return self.h(v);
        }
        let mut pv = v.to_vec();
        self.project(&mut pv);
        let mut out = self.h(&pv);
        self.project(&mut out);
        if self.rho != 0.0 {
            let q: Vec<f64> = self.gmul(v).iter().map(|a| self.rho * a).collect();
            self.gt_add(&q, &mut out);
        }
        out
    }
    /// ‖(PHP + ρQ)‖ estimated by [`power::norm_estimate`] from the projected
    /// fixed start vector.
    pub(crate) fn norm_estimate(&mut self) -> f64 {
        let mut v = power::start_vector(self.qp.m());
        self.project(&mut v);
        power::norm_estimate(v, POWER_ITERS, |v| self.apply(v))
    }
}
