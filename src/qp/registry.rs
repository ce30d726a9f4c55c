//! The list of methods. Adding a method = one file in `qp/` + one line here.

use crate::qp::recession::{self, Boundedness};
use crate::qp::{kkt, Kkt, QpError, QpProblem, QpResult, SolveOptions, Status};

pub type SolveFn = fn(&QpProblem, &SolveOptions) -> Result<QpResult, QpError>;

pub struct MethodInfo {
    /// CLI name (part of the contract).
    pub name: &'static str,
    pub summary: &'static str,
    /// Whether `--preconditioner` applies.
    pub preconditioned: bool,
    pub solve: SolveFn,
}

pub const METHODS: &[MethodInfo] = &[MethodInfo {
    name: "cgc",
    summary: "conjugate gradients with constraints (§4.1), preconditioned (§4.2)",
    preconditioned: true,
    solve: crate::qp::primal::cgc::solve,
},
MethodInfo {
    name: "preelim",
    summary: "pre-elimination: dense Schur complement onto the contact DOFs, then CGC (§4.3)",
    preconditioned: false,
    solve: crate::qp::primal::preelim::solve,
},
MethodInfo {
    name: "penalty",
    summary: "exterior penalty with Gauss–Seidel/SOR relaxation (§4.4)",
    preconditioned: false,
    solve: crate::qp::primal::penalty::solve,
},
MethodInfo {
    name: "uzawa",
    summary: "Uzawa's method with Cholesky inner solves (§4.5)",
    preconditioned: false,
    solve: crate::qp::dual::uzawa::solve,
},
MethodInfo {
    name: "dual",
    summary: "CGC on the dual functional, H applied through a Cholesky factor (§4.6)",
    preconditioned: false,
    solve: crate::qp::dual::solve,
},
MethodInfo {
    name: "asm",
    summary: "active set method, KKT systems by Schur-complement elimination (ASM-E, §4.7)",
    preconditioned: false,
    solve: crate::qp::active_set::solve,
},
MethodInfo {
    name: "asm-cgh",
    summary: "active set method, KKT systems by CG with hyperbolic pairs (§4.8)",
    preconditioned: false,
    solve: crate::qp::active_set::cgh::solve,
},
MethodInfo {
    name: "mprgp",
    summary: "MPRGP on the dual, H through one Cholesky factor; SMALBE for floating bodies (§7)",
    preconditioned: false,
    solve: crate::qp::dual::mprgp::solve,
},
MethodInfo {
    name: "ssn",
    summary: "semismooth Newton / primal–dual active set, Schur complement with one Cholesky factor (§7)",
    preconditioned: false,
    solve: crate::qp::ssn::solve,
}];

pub fn find(name: &str) -> Option<&'static MethodInfo> {
    METHODS.iter().find(|m| m.name == name)
}

pub fn names() -> Vec<&'static str> {
    METHODS.iter().map(|m| m.name).collect()
}

/// The method a solve falls back to when `name` claims an unbounded
/// direction that fails the certificate (docs/methods.md §8).
fn fallback_for(name: &str) -> &'static str {
    if name == "ssn" {
        "asm"
    } else {
        "ssn"
    }
}

/// Whether a result of method `name` with residuals `kkt` is certified at
/// `target`. Penalty solves its own penalised problem: unless `strict`, it is
/// certified by the stationarity of that problem (its λ = (Ax − g)⁺/ε_p), and
/// its O(ε_p) violation of Ax ≤ g is reported, not certified.
pub fn certified(name: &str, kkt: &Kkt, target: f64, strict: bool) -> bool {
    if name == "penalty" && !strict {
        let own = Kkt {
            primal: 0.0,
            dual: kkt.dual,
            complementarity: 0.0,
            ..*kkt
        };
        // NaN anywhere still fails.
        return own.within(target) && !kkt.max().is_nan() && kkt.max().is_finite();
    }
    kkt.within(target)
}

/// The driver: check the problem, decide boundedness from the kernel
/// ([`recession::boundedness`]), run method `name`, check any unbounded claim
/// it makes ([`recession::certify`]; a claim that fails is not trusted and
/// the solve falls back to another method, said in `notes`), and attach the
/// KKT certificate.
pub fn solve(name: &str, qp: &QpProblem, opts: &SolveOptions) -> Result<QpResult, QpError> {
    let m = find(name).ok_or_else(|| {
        QpError::BadParameter(format!(
            "unknown method \"{name}\"; known: {}",
            names().join(", ")
        ))
    })?;
    check_problem(qp)?;
    let mut notes = vec![];
    match recession::boundedness(qp) {
        Boundedness::Unbounded(c) => return Ok(unbounded_result(qp, c.direction)),
        Boundedness::Undecided(why) => {
            log::debug!("boundedness undecided ({why}); the method decides, its claim is checked")
        }
        Boundedness::Bounded => {}
    }
    let mut opts = opts.clone();
    if let Some(x0) = &opts.x0 {
        if let Err(why) = check_warm_start(qp, x0) {
            let note = format!("warm start not used: {why}");
            log::warn!("{note}");
            notes.push(note);
            opts.x0 = None;
        }
    }
    let mut r = (m.solve)(qp, &opts)?;
    if let Status::Unbounded { direction } = &r.status {
        match recession::certify(qp, direction) {
            Ok(c) => return Ok(unbounded_result(qp, c.direction)),
            Err(why) => {
                let fb = fallback_for(name);
                let note = format!(
                    "{name} reported an unbounded direction that fails the certificate ({why}); solved by {fb} instead"
                );
                log::warn!("{note}");
                notes.push(note);
                let fm = find(fb).ok_or_else(|| QpError::BadParameter(fb.into()))?;
                let t = r.timings.clone();
                r = (fm.solve)(qp, &opts)?;
                r.timings = t
                    .into_iter()
                    .map(|(k, v)| (format!("{name}-{k}"), v))
                    .chain(r.timings)
                    .collect();
                if let Status::Unbounded { direction } = &r.status {
                    let why = recession::certify(qp, direction).err().unwrap_or_default();
                    r.status = Status::Failed(format!(
                        "{fb} also reported an unbounded direction that fails the certificate ({why})"
                    ));
                }
            }
        }
    }
    r.kkt = kkt::residuals(qp, &r.x, &r.lambda);
    r.energy = qp.energy(&r.x);
    if !r.energy.is_finite() {
        r.kkt = Kkt::not_finite();
    }
    notes.append(&mut r.notes);
    r.notes = notes;
    Ok(r)
}

/// A result that carries a verified recession direction and no solution.
fn unbounded_result(qp: &QpProblem, direction: Vec<f64>) -> QpResult {
    QpResult {
        x: vec![0.0; qp.n()],
        lambda: vec![0.0; qp.m()],
        active: vec![false; qp.m()],
        status: Status::Unbounded { direction },
        iterations: 0,
        inner_iterations: 0,
        log: vec![],
        timings: vec![],
        kkt: Kkt::not_finite(),
        energy: f64::NEG_INFINITY,
        notes: vec![],
    }
}

/// The QP's data must be finite and consistently sized.
fn check_problem(qp: &QpProblem) -> Result<(), QpError> {
    let (n, m) = (qp.n(), qp.m());
    if qp.c.nrows != n || qp.c.ncols != n || qp.a.nrows != m || qp.a.ncols != n {
        return Err(QpError::BadParameter(format!(
            "inconsistent sizes: C {}×{}, d {n}, A {}×{}, g {m}",
            qp.c.nrows, qp.c.ncols, qp.a.nrows, qp.a.ncols
        )));
    }
    for (what, v) in [
        ("the stiffness matrix C", &qp.c.data),
        ("the load vector d", &qp.d),
        ("the contact matrix A", &qp.a.data),
        ("the gaps g", &qp.g),
    ] {
        if let Some(i) = v.iter().position(|e| !e.is_finite()) {
            return Err(QpError::BadParameter(format!(
                "{what} has a non-finite entry ({}) at position {i}: loads, moduli or prescribed displacements overflow",
                v[i]
            )));
        }
    }
    Ok(())
}

/// A warm start must be finite, of the right size, and of a plausible scale:
/// its energy must be finite and no larger than 10¹² times the size of the
/// load's work at the start x = 0 would allow (a checkpoint holding 1e300).
pub fn check_warm_start(qp: &QpProblem, x0: &[f64]) -> Result<(), String> {
    if x0.len() != qp.n() {
        return Err(format!("{} values for {} unknowns", x0.len(), qp.n()));
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(format!("value {i} is {}", x0[i]));
    }
    let e = qp.energy(x0);
    if !e.is_finite() {
        return Err("its energy is not finite".into());
    }
    let cx = qp.c.mul(x0);
    let r: Vec<f64> = cx.iter().zip(&qp.d).map(|(c, d)| c - d).collect();
    let dn = crate::linalg::sparse::norm(&qp.d);
    let rn = crate::linalg::sparse::norm(&r);
    if dn > 0.0 && rn > 1e12 * dn {
        return Err(format!(
            "its residual ‖Cx − d‖ is {rn:.3e}, {:.1e} times the loads",
            rn / dn
        ));
    }
    Ok(())
}
