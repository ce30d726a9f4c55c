//! ASM-CGH (docs/methods.md §4.8): the active set loop of ASM-E (`super`,
//! §4.7) with the face systems B_J y = f solved matrix-free by CG with
//! hyperbolic pairs (Luenberger): no factor, no fill-in. CGH works on the
//! Jacobi-scaled system B̃ = [[ΣCΣ, ΣA_JᵀT], [TA_JΣ, 0]], Σ = diag(C)^(-1/2),
//! Tᵢ = 1/‖Σaᵢ‖ (unit diagonal and rows), so a stiffness contrast does not
//! bury the soft body's residual under the stiff body's rounding. A direction
//! p is singular when |(p, Bp)| ≤ ε_s‖p‖‖Bp‖ (ε_s = 10⁻⁴; the local ‖Bp‖/‖p‖
//! replaces ‖B‖, which would flag every smooth direction of C). Rigid motions
//! J leaves free come from the loop; one with no force along it is appended
//! to B_J as an extra row (zero multiplier), so CGH only sees nonsingular
//! systems. If CGH fails on a working set (breakdown, no progress in
//! 2n + 200 steps, or 10·max_iter steps) the run switches for good to the
//! exact ASM-E solve, with a warning and a `factor (ASM-E fallback)` timing.

use crate::linalg::cholesky::Workspace;
use crate::linalg::sparse::{axpy, dot, norm};
use crate::qp::active_set::{ActiveSet, FaceKernel, FaceSolver, SchurSolver};
use crate::qp::method::{Capabilities, MethodId};
use crate::qp::{Context, Method, Output, QpError, QpProblem};
use std::time::Instant;

/// ASM-CGH: the active set method, KKT systems by CG with hyperbolic pairs
/// (docs/methods.md §4.8).
pub struct AsmCghMethod;

impl Method for AsmCghMethod {
    fn id(&self) -> MethodId {
        MethodId::AsmCgh
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "active set method, KKT systems by CG with hyperbolic pairs (§4.8)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

/// Solve `qp` by the active set method with CGH inner solves.
pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let opts = ctx.settings;
    let t1 = Instant::now();
    let solver = Hybrid {
        qp,
        cgh: CghSolver::new(qp, opts.tol, opts.max_iter),
        schur: None,
        cgh_steps: 0,
        switch_time: 0.0,
        ws: ctx.ws,
    };
    let mut state = ActiveSet::new(qp, solver, opts)?;
    let mut exec = ctx.executor("asm-cgh");
    let (status, iters) = exec.run(&mut state);
    let t_it = t1.elapsed().as_secs_f64();
    let mut timings = vec![("iterate".into(), t_it)];
    let switched = state.solver().schur.is_some();
    if switched {
        // Visible in the result: the factor's time under its own name.
        timings.push(("factor (ASM-E fallback)".into(), state.solver().switch_time));
    }
    Ok(state.into_result(status, iters, exec.log, timings))
}

/// CGH until it fails on a working set (breakdown, stall, step cap), then
/// the exact ASM-E Schur solve (one Cholesky factor of C) for the rest of the
/// run, with a warning. The switch is decided by step counts only, never by
/// time, so the same input always takes the same path.
struct Hybrid<'a> {
    qp: &'a QpProblem,
    cgh: CghSolver<'a>,
    schur: Option<SchurSolver<'a>>,
    cgh_steps: usize,
    switch_time: f64,
    ws: &'a Workspace,
}

impl FaceSolver for Hybrid<'_> {
    fn push(&mut self, j: usize, jl: &[usize]) -> bool {
        match &mut self.schur {
            Some(s) => s.push(j, jl),
            None => self.cgh.push(j, jl),
        }
    }

    fn remove(&mut self, pos: usize) {
        match &mut self.schur {
            Some(s) => s.remove(pos),
            None => self.cgh.remove(pos),
        }
    }

    fn solve(
        &mut self,
        r: &[f64],
        e: &[f64],
        jl: &[usize],
        fk: &FaceKernel,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        if self.schur.is_none() {
            match self.cgh.solve(r, e, jl, fk) {
                Ok(v) => return Ok(v),
                Err(msg) => {
                    log::warn!(
                        "{msg}; switching to the ASM-E Schur-complement solve (one Cholesky factor of C) \
                         for this and the remaining working sets"
                    );
                    let t0 = Instant::now();
                    let chol = self
                        .ws
                        .cholesky(&self.qp.c, &self.qp.kernel)
                        .map_err(|e| format!("{msg}; the ASM-E fallback failed: {e}"))?;
                    let mut s = SchurSolver::new(self.qp, chol);
                    for (p, &j) in jl.iter().enumerate() {
                        if !s.push(j, &jl[..p]) {
                            return Err(format!(
                                "{msg}; ASM-E fallback: row {j} depends on the working set"
                            ));
                        }
                    }
                    self.switch_time = t0.elapsed().as_secs_f64();
                    self.cgh_steps = self.cgh.inner();
                    self.schur = Some(s);
                }
            }
        }
        match &mut self.schur {
            Some(s) => s.solve(r, e, jl, fk),
            None => Err("asm-cgh: no face solver".into()),
        }
    }

    /// CGH steps, then plus the solves with the factor after a switch.
    fn inner(&self) -> usize {
        match &self.schur {
            Some(s) => self.cgh_steps + s.inner(),
            None => self.cgh.inner(),
        }
    }
}

/// Parameters of [`cgh`].
#[derive(Debug, Clone, Copy)]
pub struct CghOptions {
    /// Stop when ‖f − By‖ ≤ tol ‖f‖.
    pub tol: f64,
    /// Singularity threshold ε_s: p is singular if |(p,Bp)| ≤ ε_s ‖p‖‖Bp‖.
    pub eps_s: f64,
    pub max_iter: usize,
}

/// Solve B y = f (B symmetric, nonsingular, possibly indefinite) by CG with
/// hyperbolic pairs, starting from the given y. `apply(v, out)` sets out = Bv.
/// Returns the number of steps (a hyperbolic pair counts two), or an error
/// message on breakdown / non-convergence.
///
/// Case I (regular p) and Case II (nearly singular p: |(p,Bp)| ≤ ε_s‖p‖‖Bp‖)
/// follow methods.md §4.8, (2.27)–(2.38). In Case II the two step lengths and
/// the new direction are obtained from the 2×2 Galerkin system on span{p_k,
/// p_{k+1}} with matrix [[(p,Bp), (p,Bq)], [(q,Bp), (q,Bq)]]; with
/// (p_k,Bp_k) = 0 (and hence (q,Bq) = 0) this is exactly the report's
/// α_k = (r,p_{k+1})/den, α_{k+1} = (r,p_k)/den, p_{k+2} = r − (r,Bp_{k+1})/den·p_k,
/// and it stays exact when the test admits a small nonzero (p_k,Bp_k). Should
/// that 2×2 matrix be numerically singular while (p_k,Bp_k) ≠ 0 (p_k close to
/// an eigenvector), the regular step is taken instead.
pub fn cgh(
    apply: &mut dyn FnMut(&[f64], &mut [f64]),
    f: &[f64],
    y: &mut [f64],
    o: &CghOptions,
) -> Result<usize, String> {
    let n = f.len();
    let fnorm = norm(f);
    if fnorm == 0.0 {
        y.iter_mut().for_each(|v| *v = 0.0);
        return Ok(0);
    }
    let target = o.tol * fnorm;
    let mut by = vec![0.0; n];
    apply(y, &mut by);
    let mut r: Vec<f64> = f.iter().zip(&by).map(|(a, b)| a - b).collect();
    let mut p = r.clone();
    let mut bp = vec![0.0; n];
    apply(&p, &mut bp);
    let mut b2p = vec![0.0; n];
    let mut q = vec![0.0; n];
    let mut bq = vec![0.0; n];
    let mut k = 0usize;
    let mut restarts = 0;
    // Stall: no new best residual (by 1 %) in `stall` steps. CG on a
    // well-conditioned system of this size would have finished long before.
    let stall = 2 * n + 200;
    let (mut best, mut best_at) = (f64::INFINITY, 0usize);
    loop {
        let rn = norm(&r);
        if !rn.is_finite() {
            return Err(format!("CGH: NaN/Inf after {k} steps"));
        }
        if rn < 0.99 * best {
            (best, best_at) = (rn, k);
        } else if k - best_at >= stall {
            return Err(format!(
                "CGH stalls: no progress in {stall} steps (relative residual {:.2e}, best {:.2e}, {k} steps)",
                rn / fnorm,
                best / fnorm
            ));
        }
        if rn <= target {
            // Confirm with the true residual (rounding drift); restart if needed.
            apply(y, &mut by);
            for i in 0..n {
                r[i] = f[i] - by[i];
            }
            if norm(&r) <= target {
                return Ok(k);
            }
            restarts += 1;
            if restarts > 10 {
                return Err(format!(
                    "CGH stagnates at relative residual {:.2e} > {:.2e}",
                    norm(&r) / fnorm,
                    o.tol
                ));
            }
            p.copy_from_slice(&r);
            apply(&p, &mut bp);
        }
        if k >= o.max_iter {
            return Err(format!(
                "CGH did not converge in {k} steps (relative residual {:.2e}); B_J may be singular",
                rn / fnorm
            ));
        }
        let pbp = dot(&p, &bp);
        let pp = dot(&p, &p);
        if pp == 0.0 {
            return Err("CGH breakdown: zero search direction".into());
        }
        let bpn = norm(&bp);
        let mut regular = pbp.abs() > o.eps_s * pp.sqrt() * bpn;
        if !regular {
            // Case II: hyperbolic pair (p, q).
            let bpbp = bpn * bpn;
            if bpbp <= 0.0 || bpbp.is_nan() {
                return Err("CGH breakdown: B p = 0 for a direction p ≠ 0 (B_J singular)".into());
            }
            apply(&bp, &mut b2p);
            let shift = dot(&bp, &b2p) / (2.0 * bpbp);
            for i in 0..n {
                q[i] = bp[i] - shift * p[i];
                bq[i] = b2p[i] - shift * bp[i];
            }
            let m11 = pbp;
            let m12 = dot(&p, &bq);
            let m22 = dot(&q, &bq);
            let det = m11 * m22 - m12 * m12;
            if det.abs() > 1e-12 * ((m11 * m22).abs() + m12 * m12) {
                let solve2 =
                    |b1: f64, b2: f64| ((m22 * b1 - m12 * b2) / det, (m11 * b2 - m12 * b1) / det);
                let (a0, a1) = solve2(dot(&r, &p), dot(&r, &q));
                axpy(a0, &p, y);
                axpy(a1, &q, y);
                axpy(-a0, &bp, &mut r);
                axpy(-a1, &bq, &mut r);
                let (b0, b1) = solve2(dot(&r, &bp), dot(&r, &bq));
                for i in 0..n {
                    p[i] = r[i] - b0 * p[i] - b1 * q[i];
                }
                apply(&p, &mut bp);
                k += 2;
            } else if pbp != 0.0 {
                regular = true;
            } else {
                return Err("CGH breakdown: singular hyperbolic pair (B_J singular?)".into());
            }
        }
        if regular {
            // Case I: regular step.
            let alpha = dot(&r, &p) / pbp;
            axpy(alpha, &p, y);
            axpy(-alpha, &bp, &mut r);
            let beta = dot(&r, &bp) / pbp;
            for i in 0..n {
                p[i] = r[i] - beta * p[i];
            }
            apply(&p, &mut bp);
            k += 1;
        }
    }
}

struct CghSolver<'a> {
    qp: &'a QpProblem,
    tol: f64,
    /// Jacobi scaling of the displacement block: x = σ ⊙ x̃, σⱼ = 1/√Cⱼⱼ.
    sigma: Vec<f64>,
    /// Row scaling of the multipliers: λᵢ = τᵢ μᵢ, τᵢ = 1/‖aᵢ ⊙ σ‖.
    tau: Vec<f64>,
    /// Cap on the CGH steps of one face solve.
    max_steps: usize,
    steps: usize,
    /// Multipliers of the previous solve by constraint (warm start).
    warm: Vec<f64>,
}

impl<'a> CghSolver<'a> {
    fn new(qp: &'a QpProblem, tol: f64, max_iter: usize) -> Self {
        let diag = qp.c.diag();
        let sigma: Vec<f64> = diag
            .iter()
            .map(|&c| {
                if c > 0.0 && c.is_finite() {
                    1.0 / c.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let tau = (0..qp.m())
            .map(|i| {
                let (cols, vals) = qp.a.row(i);
                let t: f64 = cols
                    .iter()
                    .zip(vals)
                    .map(|(&j, &a)| (a * sigma[j]).powi(2))
                    .sum();
                if t > 0.0 && t.is_finite() {
                    1.0 / t.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        CghSolver {
            qp,
            tol,
            sigma,
            tau,
            max_steps: cgh_cap(qp.n() + qp.m(), max_iter),
            steps: 0,
            warm: vec![0.0; qp.m()],
        }
    }
}

/// CGH steps allowed for one face solve: 20 × the system size (CG needs at
/// most the size in exact arithmetic), but never more than 10·`max_iter`
/// (so that `--max-iter` bounds the inner loops too) and at least 50.
fn cgh_cap(dim: usize, max_iter: usize) -> usize {
    (20 * dim + 200).min(max_iter.saturating_mul(10).max(50))
}

impl FaceSolver for CghSolver<'_> {
    fn push(&mut self, _j: usize, _jl: &[usize]) -> bool {
        true // rows assumed independent (methods.md §2.7)
    }

    fn remove(&mut self, _pos: usize) {}

    /// CGH on the symmetrically scaled system
    /// `[[ΣCΣ, ΣA_JᵀT], [TA_JΣ, 0]] (x̃, μ) = (Σr, Te)`, x = Σx̃, λ = Tμ: every
    /// diagonal entry of ΣCΣ is 1 and every scaled row has norm 1, whatever
    /// the stiffness of the body a DOF belongs to. Without it the soft body's
    /// part of the residual sat below the stiff body's rounding (the steel
    /// punch on a soft foundation stalled at 1.6e-9 after 175 680 steps).
    fn solve(
        &mut self,
        r: &[f64],
        e: &[f64],
        jl: &[usize],
        fk: &FaceKernel,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let qp = self.qp;
        let n = qp.n();
        let nj = jl.len();
        let sig = &self.sigma;
        let tau = &self.tau;
        // Extra rows: the free rigid motions v, scaled to Σv/‖Σv‖.
        let extra: Vec<Vec<f64>> = fk
            .free
            .iter()
            .map(|w| {
                let v: Vec<f64> = w.iter().zip(sig).map(|(a, s)| a * s).collect();
                let nv = norm(&v);
                v.iter().map(|a| a / nv.max(f64::MIN_POSITIVE)).collect()
            })
            .collect();
        let dim = n + nj + extra.len();
        let mut f = vec![0.0; dim];
        for ((fi, ri), si) in f[..n].iter_mut().zip(r).zip(sig) {
            *fi = ri * si;
        }
        for ((fi, ei), &j) in f[n..n + nj].iter_mut().zip(e).zip(jl) {
            *fi = tau[j] * ei;
        }
        let mut y = vec![0.0; dim];
        for (yi, &j) in y[n..n + nj].iter_mut().zip(jl) {
            *yi = self.warm[j] / tau[j];
        }
        let mut tmp = vec![0.0; n];
        let mut apply = |v: &[f64], out: &mut [f64]| {
            let (vx, vm) = v.split_at(n);
            let (ox, om) = out.split_at_mut(n);
            for ((t, a), s) in tmp.iter_mut().zip(vx).zip(sig) {
                *t = a * s;
            }
            qp.c.mul_vec(&tmp, ox);
            for (t, &j) in jl.iter().enumerate() {
                let mu = vm[t] * tau[j];
                let (c, a) = qp.a.row(j);
                let mut acc = 0.0;
                for (&k, &aa) in c.iter().zip(a) {
                    if mu != 0.0 {
                        ox[k] += aa * mu;
                    }
                    acc += aa * tmp[k];
                }
                om[t] = tau[j] * acc;
            }
            for (o, s) in ox.iter_mut().zip(sig) {
                *o *= s;
            }
            for (t, w) in extra.iter().enumerate() {
                let mu = vm[nj + t];
                if mu != 0.0 {
                    axpy(mu, w, ox);
                }
                om[nj + t] = dot(w, vx);
            }
        };
        let o = CghOptions {
            tol: self.tol,
            eps_s: 1e-4,
            max_iter: self.max_steps.min(20 * dim + 200),
        };
        let res = cgh(&mut apply, &f, &mut y, &o);
        match res {
            Ok(k) => self.steps += k,
            Err(msg) => return Err(format!("asm-cgh, working set of {nj} rows: {msg}")),
        }
        let lam: Vec<f64> = y[n..n + nj]
            .iter()
            .zip(jl)
            .map(|(m, &j)| tau[j] * m)
            .collect();
        for (&j, &l) in jl.iter().zip(&lam) {
            self.warm[j] = l;
        }
        y.truncate(n);
        for (yi, s) in y.iter_mut().zip(sig) {
            *yi *= s;
        }
        Ok((y, lam))
    }

    fn inner(&self) -> usize {
        self.steps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense solve by Gaussian elimination with partial pivoting.
    fn dense_solve(a: &[f64], n: usize, b: &[f64]) -> Vec<f64> {
        let mut m = a.to_vec();
        let mut x = b.to_vec();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&i, &j| m[i * n + c].abs().total_cmp(&m[j * n + c].abs()))
                .unwrap();
            for k in 0..n {
                m.swap(c * n + k, p * n + k);
            }
            x.swap(c, p);
            for i in c + 1..n {
                let l = m[i * n + c] / m[c * n + c];
                for k in c..n {
                    m[i * n + k] -= l * m[c * n + k];
                }
                x[i] -= l * x[c];
            }
        }
        for c in (0..n).rev() {
            let s: f64 = (c + 1..n).map(|k| m[c * n + k] * x[k]).sum();
            x[c] = (x[c] - s) / m[c * n + c];
        }
        x
    }

    fn run(b: &[f64], n: usize, f: &[f64]) -> (Vec<f64>, usize) {
        let mut apply = |v: &[f64], out: &mut [f64]| {
            for i in 0..n {
                out[i] = (0..n).map(|j| b[i * n + j] * v[j]).sum();
            }
        };
        let mut y = vec![0.0; n];
        let o = CghOptions {
            tol: 1e-13,
            eps_s: 1e-4,
            max_iter: 20 * n,
        };
        let k = cgh(&mut apply, f, &mut y, &o).expect("cgh");
        (y, k)
    }

    #[test]
    fn cgh_small_kkt_against_direct() {
        // B = [[C, Aᵀ], [A, 0]], C SPD 6×6 (tridiagonal + shift), A 2×6.
        let (nc, na) = (6, 2);
        let n = nc + na;
        let mut b = vec![0.0; n * n];
        for i in 0..nc {
            b[i * n + i] = 3.0 + i as f64 * 0.5;
            if i + 1 < nc {
                b[i * n + i + 1] = -1.0;
                b[(i + 1) * n + i] = -1.0;
            }
        }
        let arows = [
            [1.0, 0.0, -1.0, 0.0, 0.5, 0.0],
            [0.0, 1.0, 0.0, 0.0, -1.0, 2.0],
        ];
        for (r, row) in arows.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                b[(nc + r) * n + c] = v;
                b[c * n + nc + r] = v;
            }
        }
        let f: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).sin()).collect();
        let exact = dense_solve(&b, n, &f);
        let (y, _) = run(&b, n, &f);
        for (a, e) in y.iter().zip(&exact) {
            assert!((a - e).abs() < 1e-9, "{a} vs {e}");
        }
    }

    #[test]
    fn cgh_semidefinite_block_and_hyperbolic_pair() {
        // C singular (ker C = span(e0 − e1)), fixed by the constraint row: B nonsingular.
        let n = 4;
        let b = vec![
            1.0, -1.0, 0.0, 1.0, //
            -1.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 2.0, 1.0, //
            1.0, 0.0, 1.0, 0.0,
        ];
        let f = vec![1.0, 0.0, 0.5, -1.0];
        let exact = dense_solve(&b, n, &f);
        let (y, _) = run(&b, n, &f);
        for (a, e) in y.iter().zip(&exact) {
            assert!((a - e).abs() < 1e-9, "{a} vs {e}");
        }
        // Pure hyperbolic start: B = [[0,1],[1,0]], p0 = f has (p,Bp) = 0.
        let b2 = vec![0.0, 1.0, 1.0, 0.0];
        let (y, k) = run(&b2, 2, &[1.0, 0.0]);
        assert!((y[0]).abs() < 1e-12 && (y[1] - 1.0).abs() < 1e-12, "{y:?}");
        assert_eq!(k, 2);
    }
}
