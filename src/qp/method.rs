//! What a method is to the rest of the program: its identity
//! ([`MethodId`]), what it solves and how its answer is judged
//! ([`Capabilities`]), what the driver falls back to when it cannot be
//! trusted ([`Method::fallback`]), and the user's choice ([`MethodChoice`],
//! with `auto`). Every rule that used to test a method's name reads these
//! types instead (docs/methods.md §8).

use super::driver::{Context, Output};
use super::{QpError, QpProblem};

/// The methods, by identity. The CLI name ([`MethodId::name`]) is part of
/// the problem-file contract (docs/problem-format.md §4); no rule compares
/// it as a string.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MethodId {
    Cgc,
    Preelim,
    Penalty,
    Uzawa,
    Dual,
    Asm,
    AsmCgh,
    Mprgp,
    Ssn,
}

impl MethodId {
    /// Every method, in the order of `signorini methods` and `compare`.
    pub const ALL: [MethodId; 9] = [
        MethodId::Cgc,
        MethodId::Preelim,
        MethodId::Penalty,
        MethodId::Uzawa,
        MethodId::Dual,
        MethodId::Asm,
        MethodId::AsmCgh,
        MethodId::Mprgp,
        MethodId::Ssn,
    ];

    /// The name in the problem file, on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            MethodId::Cgc => "cgc",
            MethodId::Preelim => "preelim",
            MethodId::Penalty => "penalty",
            MethodId::Uzawa => "uzawa",
            MethodId::Dual => "dual",
            MethodId::Asm => "asm",
            MethodId::AsmCgh => "asm-cgh",
            MethodId::Mprgp => "mprgp",
            MethodId::Ssn => "ssn",
        }
    }

    /// The method named `name`, if any.
    pub fn parse(name: &str) -> Option<MethodId> {
        MethodId::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The method's implementation.
    pub fn method(self) -> &'static dyn Method {
        match self {
            MethodId::Cgc => &super::primal::cgc::CgcMethod,
            MethodId::Preelim => &super::primal::preelim::PreelimMethod,
            MethodId::Penalty => &super::primal::penalty::PenaltyMethod,
            MethodId::Uzawa => &super::dual::uzawa::UzawaMethod,
            MethodId::Dual => &super::dual::polyak::DualMethod,
            MethodId::Asm => &super::active_set::AsmMethod,
            MethodId::AsmCgh => &super::active_set::cgh::AsmCghMethod,
            MethodId::Mprgp => &super::dual::mprgp::MprgpMethod,
            MethodId::Ssn => &super::ssn::SsnMethod,
        }
    }

    /// What the method solves ([`Method::capabilities`]).
    pub fn capabilities(self) -> Capabilities {
        self.method().capabilities()
    }

    /// "cgc, preelim, …": the known names, for messages.
    pub fn known() -> String {
        MethodId::ALL.map(MethodId::name).join(", ")
    }
}

impl std::fmt::Display for MethodId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for MethodId {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// The method the user asks for: one by name, or `auto` (the default),
/// which the program resolves for the problem at hand
/// ([`MethodChoice::resolve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MethodChoice {
    /// ssn for every problem: the fastest method here on every shipped and
    /// benchmark model, frictional ones included, and the one whose answer
    /// every other method is compared with (README, "Which method").
    #[default]
    Auto,
    Named(MethodId),
}

/// `"auto"` or a method's name: the one parser of the problem file's
/// `method` and of `--method`; the error lists what is accepted.
impl std::str::FromStr for MethodChoice {
    type Err = String;
    fn from_str(name: &str) -> Result<MethodChoice, String> {
        if name == "auto" {
            return Ok(MethodChoice::Auto);
        }
        MethodId::parse(name)
            .map(MethodChoice::Named)
            .ok_or_else(|| {
                format!(
                    "unknown method \"{name}\"; known: auto, {}",
                    MethodId::known()
                )
            })
    }
}

impl MethodChoice {
    /// The method that solves the problem.
    pub fn resolve(self) -> MethodId {
        match self {
            MethodChoice::Auto => MethodId::Ssn,
            MethodChoice::Named(m) => m,
        }
    }
}

/// How a method's answer is judged against the KKT certificate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Certificate {
    /// By the KKT conditions of the QP itself.
    Kkt,
    /// By the stationarity of its own penalised problem (penalty, whose
    /// λ = (Ax − g)⁺/ε_p): the O(ε_p) violation of Ax ≤ g is reported,
    /// not certified, unless the user asks for `--strict`
    /// (docs/methods.md §4.4).
    Penalised,
}

/// Whether a method needs a sparse Cholesky factor of C (or of C plus
/// contact terms), the memory a user plans for (docs/methods.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factor {
    /// Always.
    Always,
    /// Never.
    Never,
    /// As its settings say (cgc's preconditioner, ssn's path).
    BySettings,
}

/// The frictional problems a method solves (docs/methods.md §9, §12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum FrictionSupport {
    /// Frictionless contact only.
    None,
    /// One tangential row per contact row ([`crate::qp::Frame::Line`]: plane
    /// and axisymmetric models).
    Lines,
    /// Lines and the discs and cones of two tangential rows per contact row
    /// ([`crate::qp::Frame::Plane`]: solid models).
    Planes,
}

impl FrictionSupport {
    /// Whether a method of this support solves `qp` (frictionless problems
    /// always).
    pub fn solves(self, qp: &crate::qp::QpProblem) -> bool {
        match &qp.friction {
            None => true,
            Some(f) => match f.frame {
                crate::qp::Frame::Line => self >= FrictionSupport::Lines,
                crate::qp::Frame::Plane => self >= FrictionSupport::Planes,
            },
        }
    }
    /// Solves some friction.
    pub fn any(self) -> bool {
        self > FrictionSupport::None
    }
}

/// What a method declares about itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capabilities {
    /// Which friction laws it solves (`QpProblem::friction`,
    /// docs/methods.md §9, §12); the driver refuses it the others.
    pub friction: FrictionSupport,
    /// Solves semicoercive problems (ker C ≠ 0: a body held only by contact)
    /// whatever the kernel, without refusing (docs/methods.md §1.7).
    pub semicoercive: bool,
    /// Takes `--preconditioner`.
    pub preconditioned: bool,
    pub factor: Factor,
    pub certificate: Certificate,
    /// Starts from the caller's warm start (`SolveOptions::x0`, `active0`:
    /// load steps, restart); the others start from their own first iterate.
    pub warm_start: bool,
    /// What a user should know before a frictional solve of more than
    /// [`SLOW_FRICTION_DOFS`] unknowns (the driver warns up front): a
    /// method that solves friction but far slower than ssn says why.
    pub friction_caveat: Option<&'static str>,
}

/// Unknowns above which a method's [`Capabilities::friction_caveat`] is
/// said before a frictional solve (NAFEMS 1 with μ = 0.1, BENCHMARKS.md
/// "Friction": mprgp 4 times ssn's time at 58 k and 160 k unknowns with
/// the dual Hessian formed, docs/methods.md §9.2; 30 and 160 times
/// without).
pub const SLOW_FRICTION_DOFS: usize = 10_000;

impl Default for Capabilities {
    fn default() -> Self {
        Capabilities {
            friction: FrictionSupport::None,
            semicoercive: true,
            preconditioned: false,
            factor: Factor::Always,
            certificate: Certificate::Kkt,
            warm_start: false,
            friction_caveat: None,
        }
    }
}

/// Why the driver does not keep a method's answer (docs/methods.md §8.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallbackCause {
    /// The method claimed an unbounded direction that fails the certificate.
    RefusedClaim,
    /// The method's working sets cycle (frictional ssn on a Tresca problem
    /// with friction on many open rows of a floating body, §9.2).
    Cycling,
}

/// A QP method (one type per method; a family is one folder).
pub trait Method: Sync {
    fn id(&self) -> MethodId;
    /// One line for `signorini methods`.
    fn summary(&self) -> &'static str;
    fn capabilities(&self) -> Capabilities;
    /// The method that solves the problem instead when this one's answer
    /// cannot be trusted for `cause`; None: the failure stands.
    fn fallback(&self, cause: FallbackCause) -> Option<MethodId> {
        match cause {
            FallbackCause::RefusedClaim => Some(MethodId::Ssn),
            FallbackCause::Cycling => None,
        }
    }
    fn solve(&self, qp: &QpProblem, ctx: &mut Context) -> Result<Output, QpError>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_auto_is_ssn() {
        for m in MethodId::ALL {
            assert_eq!(MethodId::parse(m.name()), Some(m));
            assert_eq!(m.method().id(), m, "{m}");
        }
        assert_eq!(MethodId::parse("auto"), None);
        assert_eq!("auto".parse(), Ok(MethodChoice::Auto));
        assert_eq!("asm".parse(), Ok(MethodChoice::Named(MethodId::Asm)));
        let e = "cgd".parse::<MethodChoice>().unwrap_err();
        assert!(e.contains("auto, cgc") && e.contains("ssn"), "{e}");
        assert_eq!(MethodChoice::Auto.resolve(), MethodId::Ssn);
    }

    #[test]
    fn a_fallback_is_never_the_method_itself() {
        for m in MethodId::ALL {
            for c in [FallbackCause::RefusedClaim, FallbackCause::Cycling] {
                if let Some(f) = m.method().fallback(c) {
                    assert_ne!(f, m, "{m} falls back to itself on {c:?}");
                    if c == FallbackCause::Cycling {
                        // the problem that cycled has friction
                        assert!(f.capabilities().friction.any(), "{m} → {f}");
                    }
                }
            }
        }
    }
}
