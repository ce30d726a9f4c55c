//! Pre-elimination: Schur complement onto the constrained DOFs (methods.md §4.3).
//!
//! P = the DOFs occurring in A (columns with a nonzero entry), L = the others.
//! With C11 = C(L,L) (sparse Cholesky), C12 = C(L,P), C22 = C(P,P):
//!
//! ```text
//!   C̄22 = C22 − C12ᵀ C11⁻¹ C12   (dense P×P, one solve per contact DOF)
//!   d̄2  = d2 − C12ᵀ C11⁻¹ d1
//!   x2   = argmin ½x2ᵀC̄22x2 − x2ᵀd̄2  s.t. A2 x2 ≤ g      (CGC, Cholesky-preconditioned)
//!   x1   = C11⁻¹ (d1 − C12 x2)
//! ```
//!
//! The reduced KKT conditions are those of the full problem with the same λ.
//! C̄22 is stored as a sparse matrix of its nonzero entries (it is block
//! diagonal per body, since C is).
//!
//! Semicoercive C: C11 is usually nonsingular (fixing the contact DOFs removes
//! the rigid motions), C̄22 then inherits ker C restricted to P (if Cr = 0 then
//! C̄22 r2 = 0), which is handed to the reduced CGC and its preconditioner. If
//! C11 itself is singular the method refuses (`QpError::Unsupported`).
//! More than [`MAX_P`] constrained DOFs are refused (dense P² storage).

use crate::linalg::sparse::Csr;
use crate::qp::method::{Capabilities, MethodId};
use crate::qp::precond::PrecondKind;
use crate::qp::{primal::cgc, Context, Method, Output, QpError, QpProblem, Settings, Status};

/// Largest number of constrained DOFs for the dense Schur complement.
pub const MAX_P: usize = 5000;

/// Pre-elimination onto the contact DOFs, the reduced QP solved by CGC with
/// the Cholesky preconditioner (docs/methods.md §4.3).
pub struct PreelimMethod;

impl Method for PreelimMethod {
    fn id(&self) -> MethodId {
        MethodId::Preelim
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            semicoercive: false,
            ..Default::default()
        }
    }
    fn summary(&self) -> &'static str {
        "pre-elimination: dense Schur complement onto the contact DOFs, then CGC (§4.3)"
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
        solve(qp, ctx)
    }
}

pub fn solve(qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError> {
    let n = qp.n();
    let mut is_p = vec![false; n];
    for (&c, &v) in qp.a.indices.iter().zip(&qp.a.data) {
        if v != 0.0 {
            is_p[c] = true;
        }
    }
    let pdofs: Vec<usize> = (0..n).filter(|&i| is_p[i]).collect();
    let ldofs: Vec<usize> = (0..n).filter(|&i| !is_p[i]).collect();
    let np = pdofs.len();
    if np > MAX_P {
        return Err(QpError::Unsupported(format!(
            "preelim: {np} constrained DOFs > {MAX_P}; the dense Schur complement C̄22 would need P² = {} \
             numbers ({:.1} GB) of memory (use cgc with the Cholesky preconditioner)",
            np * np,
            (np * np) as f64 * 8.0 / 1e9
        )));
    }
    // Position of each DOF within L or P.
    let mut pos = vec![0usize; n];
    for (k, &i) in pdofs.iter().enumerate() {
        pos[i] = k;
    }
    for (k, &i) in ldofs.iter().enumerate() {
        pos[i] = k;
    }

    // C11 and the factor.
    let f11 = ctx.phase("factor", |ctx| factor_c11(qp, &ldofs, &is_p, &pos, ctx))?;

    // C̄22 column by column, d̄2.
    let (red, np) = ctx.phase("schur", |_| {
        schur(qp, &pdofs, &ldofs, &is_p, &pos, f11.as_ref())
    });

    // Reduced QP by CGC, injected with its own settings.
    let rsettings = Settings {
        cgc: crate::qp::settings::CgcSettings {
            preconditioner: PrecondKind::Cholesky,
            ..ctx.settings.cgc
        },
        ..ctx.settings.clone()
    };
    let r = ctx.phase("reduced-cgc", |ctx| {
        cgc::solve(&red, &mut ctx.sub(&rsettings))
    })?;

    // Back substitution x1 = C11⁻¹(d1 − C12 x2).
    let (x, status) = ctx.phase("backsubstitute", |_| {
        back_substitute(qp, &pdofs, &ldofs, &is_p, f11.as_ref(), &r)
    });
    Ok(Output {
        x,
        lambda: r.lambda,
        lambda_t: vec![],
        active: r.active,
        status,
        iterations: r.iterations,
        inner_iterations: r.inner_iterations + np,
        log: r.log,
        timings: vec![],
    })
}

/// The sparse Cholesky factor of C11 = C[L,L] (None when L is empty).
fn factor_c11(
    qp: &QpProblem,
    ldofs: &[usize],
    is_p: &[bool],
    pos: &[usize],
    ctx: &Context,
) -> Result<Option<crate::linalg::cholesky::Cholesky>, QpError> {
    let nl = ldofs.len();
    let mut trip = Vec::new();
    for (kl, &i) in ldofs.iter().enumerate() {
        let (c, v) = qp.c.row(i);
        for (&j, &a) in c.iter().zip(v) {
            if !is_p[j] {
                trip.push((kl, pos[j], a));
            }
        }
    }
    let c11 = Csr::from_triplets(nl, nl, &trip);
    drop(trip);
    if nl == 0 {
        return Ok(None);
    }
    ctx.ws.cholesky(&c11, &[]).map(Some).map_err(|e| {
        if e.is_memory() {
            return e.into();
        }
        QpError::Unsupported(format!(
            "preelim: the stiffness block C11 of the non-contact DOFs is singular ({e}); a body can move \
             even with its contact DOFs fixed (use cgc)"
        ))
    })
}

/// The reduced problem on P: C̄22, d̄2, A2, g and the kernel restricted to P.
fn schur(
    qp: &QpProblem,
    pdofs: &[usize],
    ldofs: &[usize],
    is_p: &[bool],
    pos: &[usize],
    f11: Option<&crate::linalg::cholesky::Cholesky>,
) -> (QpProblem, usize) {
    let (np, nl) = (pdofs.len(), ldofs.len());
    // C12ᵀ w for w on L: entry q = Σ_{l} C[P[q], L[l]] w_l (rows of C at P DOFs).
    let c12t_mul = |w: &[f64], out: &mut [f64]| {
        for (q, &pi) in pdofs.iter().enumerate() {
            let (c, v) = qp.c.row(pi);
            out[q] = c
                .iter()
                .zip(v)
                .filter(|(&j, _)| !is_p[j])
                .map(|(&j, &a)| a * w[pos[j]])
                .sum();
        }
    };
    let mut dense = vec![0.0; np * np];
    let mut w = vec![0.0; nl];
    let mut col = vec![0.0; np];
    for (k, &pk) in pdofs.iter().enumerate() {
        // column k of C22
        let (c, v) = qp.c.row(pk);
        for (&j, &a) in c.iter().zip(v) {
            if is_p[j] {
                dense[pos[j] * np + k] += a;
            }
        }
        if let Some(f) = &f11 {
            w.iter_mut().for_each(|e| *e = 0.0);
            for (&j, &a) in c.iter().zip(v) {
                if !is_p[j] {
                    w[pos[j]] = a;
                }
            }
            f.solve_in_place(&mut w);
            c12t_mul(&w, &mut col);
            for q in 0..np {
                dense[q * np + k] -= col[q];
            }
        }
    }
    let mut d2: Vec<f64> = pdofs.iter().map(|&i| qp.d[i]).collect();
    let mut d1: Vec<f64> = ldofs.iter().map(|&i| qp.d[i]).collect();
    if let Some(f) = &f11 {
        f.solve_in_place(&mut d1); // d1 ← C11⁻¹ d1
        c12t_mul(&d1, &mut col);
        for (a, b) in d2.iter_mut().zip(&col) {
            *a -= b;
        }
    }
    let mut trip = Vec::new();
    for i in 0..np {
        for j in 0..np {
            let v = 0.5 * (dense[i * np + j] + dense[j * np + i]);
            if v != 0.0 || i == j {
                trip.push((i, j, v));
            }
        }
    }
    drop(dense);
    let c22 = Csr::from_triplets(np, np, &trip);
    drop(trip);
    let mut atrip = Vec::with_capacity(qp.a.nnz());
    for r in 0..qp.m() {
        let (c, v) = qp.a.row(r);
        for (&j, &a) in c.iter().zip(v) {
            if is_p[j] {
                atrip.push((r, pos[j], a));
            }
        }
    }
    let a2 = Csr::from_triplets(qp.m(), np, &atrip);
    let kernel: Vec<Vec<f64>> = qp
        .kernel
        .iter()
        .map(|z| pdofs.iter().map(|&i| z[i]).collect::<Vec<f64>>())
        .filter(|z| z.iter().any(|v| *v != 0.0))
        .collect();
    let red = QpProblem {
        c: c22,
        d: d2,
        a: a2,
        g: qp.g.clone(),
        kernel,
        friction: None,
        near: None,
    };
    (red, np)
}

/// x from the reduced solution: x2 = r.x on P, x1 = C11⁻¹(d1 − C12 x2) on L;
/// an unbounded direction of the reduced problem extends the same way.
fn back_substitute(
    qp: &QpProblem,
    pdofs: &[usize],
    ldofs: &[usize],
    is_p: &[bool],
    f11: Option<&crate::linalg::cholesky::Cholesky>,
    r: &Output,
) -> (Vec<f64>, Status) {
    let (n, np) = (qp.n(), pdofs.len());
    let mut x = vec![0.0; n];
    for (k, &i) in pdofs.iter().enumerate() {
        x[i] = r.x[k];
    }
    if let Some(f) = f11 {
        let mut rhs: Vec<f64> = ldofs.iter().map(|&i| qp.d[i]).collect();
        for (kl, &i) in ldofs.iter().enumerate() {
            let (c, v) = qp.c.row(i);
            rhs[kl] -= c
                .iter()
                .zip(v)
                .filter(|(&j, _)| is_p[j])
                .map(|(&j, &a)| a * x[j])
                .sum::<f64>();
        }
        f.solve_in_place(&mut rhs);
        for (kl, &i) in ldofs.iter().enumerate() {
            x[i] = rhs[kl];
        }
    }
    // An unbounded direction of the reduced problem extends by x1 = −C11⁻¹C12 x2.
    let status = match &r.status {
        Status::Unbounded { direction } if direction.len() == np => {
            let mut full = vec![0.0; n];
            for (k, &i) in pdofs.iter().enumerate() {
                full[i] = direction[k];
            }
            if let Some(f) = f11 {
                let mut rhs: Vec<f64> = ldofs
                    .iter()
                    .map(|&i| {
                        let (c, v) = qp.c.row(i);
                        -c.iter()
                            .zip(v)
                            .filter(|(&j, _)| is_p[j])
                            .map(|(&j, &a)| a * full[j])
                            .sum::<f64>()
                    })
                    .collect();
                f.solve_in_place(&mut rhs);
                for (kl, &i) in ldofs.iter().enumerate() {
                    full[i] = rhs[kl];
                }
            }
            Status::Unbounded { direction: full }
        }
        s => s.clone(),
    };
    (x, status)
}
