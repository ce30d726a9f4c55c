//! Solver settings: the `[solver]` section of the problem file
//! (docs/problem-format.md §4) and the typed, validated settings of each
//! method.
//!
//! [`SolverSection`] is the TOML section (serde, unknown keys refused); the
//! command line builds one from its flags (`cli`) and
//! [`SolverSection::overlay`] lays it over the file's. Every named value is
//! a type ([`MethodChoice`], [`PrecondKind`], [`Release`], [`SsnPath`],
//! [`Ordering`], [`ByteSize`]) parsed once, by its `FromStr`, which both
//! the file (serde) and the command-line flags use: a bad name is refused where
//! it is read, with the accepted values. [`Settings::from_section`]
//! validates the numbers once: the common keys (`tol`, `max_iter`) here,
//! every method-specific key by the settings type of the method that reads
//! it ([`CgcSettings`], [`PenaltySettings`], [`DualSettings`],
//! [`UzawaSettings`], [`SsnSettings`]). All of them are checked whatever
//! the method, so a bad value in the file is reported even when another
//! method is chosen on the command line.

use super::method::{MethodChoice, MethodId};
use super::precond::PrecondKind;
use crate::linalg::ordering::Ordering;
use std::str::FromStr;

/// `[solver]` as written in the problem file, or as given on the command
/// line (docs/problem-format.md §4).
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSection {
    /// QP method: auto (default: ssn for every problem) or a method's name.
    pub method: Option<MethodChoice>,
    /// cgc's preconditioner (default cholesky).
    pub preconditioner: Option<PrecondKind>,
    /// Relative tolerance of the method's stopping test.
    pub tol: Option<f64>,
    /// Maximum number of (outer) iterations.
    pub max_iter: Option<usize>,
    /// SSOR / SOR relaxation parameter ω ∈ (0, 2) (cgc:ssor, penalty).
    pub omega: Option<f64>,
    /// Release strategy of cgc and dual.
    pub release: Option<Release>,
    /// Penalty parameter ε_p of the penalty method (default: one per
    /// contact row from the stiffness, docs/methods.md §4.4).
    pub penalty: Option<f64>,
    /// Uzawa step ρ (default: estimated from ‖H‖).
    pub rho: Option<f64>,
    /// Uzawa: Nesterov momentum; penalty: exact subspace correction
    /// between sweeps.
    pub accelerate: Option<bool>,
    /// ssn's linear algebra (docs/methods.md §7.2).
    pub ssn_path: Option<SsnPath>,
    /// Fill-reducing ordering of every sparse Cholesky factor
    /// (docs/methods.md §3).
    pub ordering: Option<Ordering>,
    /// Largest numeric Cholesky factor allowed (docs/methods.md §3).
    pub memory_limit: Option<ByteSize>,
    /// Largest KKT residual accepted as a certificate (default 1e-6,
    /// docs/methods.md §8.4).
    pub kkt_target: Option<f64>,
}

/// Deserialize each type from a TOML string through its `FromStr`, the
/// parser the command line uses too: a bad value's error is the parser's
/// (the accepted values), which the problem file's error places by line
/// and key.
macro_rules! deserialize_by_from_str {
    ($($t:ty),*) => {$(
        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let text = <String as serde::Deserialize>::deserialize(d)?;
                text.parse().map_err(serde::de::Error::custom)
            }
        }
    )*};
}

deserialize_by_from_str!(
    MethodChoice,
    PrecondKind,
    Ordering,
    Release,
    SsnPath,
    ByteSize
);

/// The release strategy of cgc and dual (docs/methods.md §4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Release {
    /// Release one constraint (the most negative multiplier) at a time.
    Single,
    /// Release every constraint with a negative multiplier at once.
    #[default]
    Multiple,
}

/// `single` | `multiple`.
impl FromStr for Release {
    type Err = String;
    fn from_str(r: &str) -> Result<Release, String> {
        match r {
            "single" => Ok(Release::Single),
            "multiple" => Ok(Release::Multiple),
            _ => Err(format!(
                "release = \"{r}\": expected \"single\" or \"multiple\""
            )),
        }
    }
}

/// A size in bytes, written as a positive number and a binary unit (B,
/// KiB, MiB, GiB, TiB; no unit = bytes): `memory_limit = "8 GiB"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct ByteSize(pub u64);

impl FromStr for ByteSize {
    type Err = String;
    fn from_str(text: &str) -> Result<ByteSize, String> {
        const UNITS: [(&str, f64); 5] = [
            ("TiB", 1099511627776.0),
            ("GiB", 1073741824.0),
            ("MiB", 1048576.0),
            ("KiB", 1024.0),
            ("B", 1.0),
        ];
        // The unit is a suffix, so the number may have an exponent ("1e3 KiB").
        let t = text.trim();
        let (num, scale) = UNITS
            .iter()
            .find_map(|(u, k)| t.strip_suffix(u).map(|n| (n.trim(), *k)))
            .unwrap_or((t, 1.0));
        let v: f64 = num.parse().unwrap_or(f64::NAN) * scale;
        if v.is_finite() && v >= 1.0 && v < 2f64.powi(63) {
            Ok(ByteSize(v as u64))
        } else {
            Err(format!(
                "memory_limit = \"{text}\": expected a positive size such as \"8 GiB\" (units B, KiB, MiB, GiB, TiB)"
            ))
        }
    }
}

impl SolverSection {
    /// The method-specific keys set here that `method` does not read (a
    /// user who set `rho` for uzawa and then chose ssn is told so).
    pub fn unused_by(&self, method: MethodId) -> Vec<&'static str> {
        use MethodId::*;
        let keys: [(&str, bool, &[MethodId]); 7] = [
            ("preconditioner", self.preconditioner.is_some(), &[Cgc]),
            ("omega", self.omega.is_some(), &[Cgc, Penalty]),
            ("release", self.release.is_some(), &[Cgc, Preelim, Dual]),
            ("penalty", self.penalty.is_some(), &[Penalty]),
            ("rho", self.rho.is_some(), &[Uzawa]),
            ("accelerate", self.accelerate.is_some(), &[Uzawa, Penalty]),
            ("ssn_path", self.ssn_path.is_some(), &[Ssn]),
        ];
        keys.iter()
            .filter(|(_, set, users)| *set && !users.contains(&method))
            .map(|(k, _, _)| *k)
            .collect()
    }

    /// `self` with every entry that `over` sets replaced (the command line
    /// over the file).
    pub fn overlay(&self, over: &SolverSection) -> SolverSection {
        fn pick<T: Clone>(a: &Option<T>, b: &Option<T>) -> Option<T> {
            b.clone().or_else(|| a.clone())
        }
        SolverSection {
            method: pick(&self.method, &over.method),
            preconditioner: pick(&self.preconditioner, &over.preconditioner),
            tol: pick(&self.tol, &over.tol),
            max_iter: pick(&self.max_iter, &over.max_iter),
            omega: pick(&self.omega, &over.omega),
            release: pick(&self.release, &over.release),
            penalty: pick(&self.penalty, &over.penalty),
            rho: pick(&self.rho, &over.rho),
            accelerate: pick(&self.accelerate, &over.accelerate),
            ssn_path: pick(&self.ssn_path, &over.ssn_path),
            ordering: pick(&self.ordering, &over.ordering),
            memory_limit: pick(&self.memory_limit, &over.memory_limit),
            kkt_target: pick(&self.kkt_target, &over.kkt_target),
        }
    }
}

/// The certificate's target when none is set: the largest relative KKT
/// residual an answer may have (docs/methods.md §8.4).
pub const DEFAULT_KKT_TARGET: f64 = 1e-6;

/// The validated settings of every method (what [`Settings::from_section`]
/// makes of a [`SolverSection`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Relative tolerance of the method's own stopping test, in (0, 1).
    pub tol: f64,
    /// Maximum number of outer iterations, ≥ 1.
    pub max_iter: usize,
    /// Fill-reducing ordering of the sparse Cholesky factors (the caller's
    /// [`Workspace`](crate::linalg::cholesky::Workspace) is made with it).
    pub ordering: Ordering,
    /// `memory_limit` in bytes: the caller's workspace refuses a larger
    /// numeric factor ([`Settings::workspace`]).
    pub memory_limit: Option<u64>,
    /// The certificate's target: every rule that judges an answer (the
    /// driver's, the methods' own checks, the run's verdict) reads it.
    pub kkt_target: f64,
    pub cgc: CgcSettings,
    pub penalty: PenaltySettings,
    pub dual: DualSettings,
    pub uzawa: UzawaSettings,
    pub ssn: SsnSettings,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            tol: 1e-10,
            max_iter: 100_000,
            ordering: Ordering::Amd,
            memory_limit: None,
            kkt_target: DEFAULT_KKT_TARGET,
            cgc: CgcSettings::default(),
            penalty: PenaltySettings::default(),
            dual: DualSettings::default(),
            uzawa: UzawaSettings::default(),
            ssn: SsnSettings::default(),
        }
    }
}

impl Settings {
    /// Read and validate `s`: the common keys here, the others by the
    /// method types. The error is one sentence naming the key and its
    /// allowed values.
    pub fn from_section(s: &SolverSection) -> Result<Settings, String> {
        let d = Settings::default();
        let settings = Settings {
            tol: s.tol.unwrap_or(d.tol),
            max_iter: s.max_iter.unwrap_or(d.max_iter),
            ordering: s.ordering.unwrap_or(d.ordering),
            memory_limit: s.memory_limit.map(|b| b.0),
            kkt_target: s.kkt_target.unwrap_or(d.kkt_target),
            cgc: CgcSettings::from_section(s)?,
            penalty: PenaltySettings::from_section(s)?,
            dual: DualSettings::from_section(s)?,
            uzawa: UzawaSettings::from_section(s)?,
            ssn: SsnSettings::from_section(s)?,
        };
        settings.validate()?;
        Ok(settings)
    }

    /// The ranges of every value (the driver checks again: settings built
    /// in code did not come through [`Settings::from_section`]).
    pub fn validate(&self) -> Result<(), String> {
        let t = self.tol;
        if !(t > 0.0 && t < 1.0) {
            return Err(format!("tol = {t} must lie in (0, 1)"));
        }
        if self.max_iter == 0 {
            return Err("max_iter must be positive".into());
        }
        let k = self.kkt_target;
        if !(k > 0.0 && k.is_finite()) {
            return Err(format!(
                "kkt_target = {k}: the KKT target must be a positive number"
            ));
        }
        self.cgc.validate()?;
        self.penalty.validate()?;
        self.uzawa.validate()
    }
}

impl Settings {
    /// Why `method` factors no matrix at these settings, for the report's
    /// ordering line (None: its factors use [`Settings::ordering`]).
    pub fn factor_free(&self, method: MethodId) -> Option<&'static str> {
        match method.capabilities().factor {
            crate::qp::method::Factor::Never => Some("the method factors nothing"),
            crate::qp::method::Factor::BySettings
                if method == MethodId::Ssn && self.ssn.path == SsnPath::Iterative =>
            {
                Some("ssn_path = iterative")
            }
            _ => None,
        }
    }

    /// The workspace of a solve: the factors' ordering and memory limit.
    pub fn workspace(&self) -> crate::linalg::cholesky::Workspace {
        let ws = crate::linalg::cholesky::Workspace::with_ordering(self.ordering);
        match self.memory_limit {
            Some(b) => ws.with_memory_limit(b),
            None => ws,
        }
    }
}

fn check_omega(w: f64) -> Result<(), String> {
    if w > 0.0 && w < 2.0 {
        Ok(())
    } else {
        Err(format!("omega = {w} must lie in (0, 2)"))
    }
}

fn check_positive(key: &str, v: Option<f64>) -> Result<(), String> {
    match v {
        Some(p) if !(p > 0.0 && p.is_finite()) => {
            Err(format!("{key} = {p} must be a positive finite number"))
        }
        _ => Ok(()),
    }
}

/// CGC (docs/methods.md §4.1–§4.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgcSettings {
    pub preconditioner: PrecondKind,
    /// SSOR ω.
    pub omega: f64,
    /// Release every constraint with a negative multiplier at once.
    pub multiple_release: bool,
}

impl Default for CgcSettings {
    fn default() -> Self {
        CgcSettings {
            preconditioner: PrecondKind::Cholesky,
            omega: 1.0,
            multiple_release: true,
        }
    }
}

impl CgcSettings {
    pub fn from_section(s: &SolverSection) -> Result<Self, String> {
        Ok(CgcSettings {
            preconditioner: s.preconditioner.unwrap_or(PrecondKind::Cholesky),
            omega: s.omega.unwrap_or(1.0),
            multiple_release: s.release.unwrap_or_default() == Release::Multiple,
        })
    }

    pub fn validate(&self) -> Result<(), String> {
        check_omega(self.omega)
    }
}

/// Penalty with relaxation (docs/methods.md §4.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenaltySettings {
    /// ε_p; None: one per contact row from the stiffness.
    pub eps: Option<f64>,
    /// SOR ω of the relaxation sweeps.
    pub omega: f64,
    /// Exact solve on the penalty active set between sweeps.
    pub accelerate: bool,
}

impl Default for PenaltySettings {
    fn default() -> Self {
        PenaltySettings {
            eps: None,
            omega: 1.0,
            accelerate: true,
        }
    }
}

impl PenaltySettings {
    pub fn from_section(s: &SolverSection) -> Result<Self, String> {
        Ok(PenaltySettings {
            eps: s.penalty,
            omega: s.omega.unwrap_or(1.0),
            accelerate: s.accelerate.unwrap_or(true),
        })
    }

    pub fn validate(&self) -> Result<(), String> {
        check_positive("penalty", self.eps)?;
        check_omega(self.omega)
    }
}

/// CGC on the dual functional (docs/methods.md §4.6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualSettings {
    pub multiple_release: bool,
}

impl Default for DualSettings {
    fn default() -> Self {
        DualSettings {
            multiple_release: true,
        }
    }
}

impl DualSettings {
    pub fn from_section(s: &SolverSection) -> Result<Self, String> {
        Ok(DualSettings {
            multiple_release: s.release.unwrap_or_default() == Release::Multiple,
        })
    }
}

/// Uzawa (docs/methods.md §4.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UzawaSettings {
    /// Step ρ; None: 1.9/‖H‖ estimated by power iteration.
    pub rho: Option<f64>,
    /// Nesterov momentum with gradient restart.
    pub accelerate: bool,
}

impl Default for UzawaSettings {
    fn default() -> Self {
        UzawaSettings {
            rho: None,
            accelerate: true,
        }
    }
}

impl UzawaSettings {
    pub fn from_section(s: &SolverSection) -> Result<Self, String> {
        Ok(UzawaSettings {
            rho: s.rho,
            accelerate: s.accelerate.unwrap_or(true),
        })
    }

    pub fn validate(&self) -> Result<(), String> {
        check_positive("rho", self.rho)
    }
}

/// The linear algebra of ssn (docs/methods.md §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SsnPath {
    /// Chosen from counts (nnz of the factor, flops), never timings.
    #[default]
    Auto,
    Augmented,
    Refactor,
    Schur,
    /// No factor of C's size: multigrid-preconditioned CG (docs/methods.md §7.2).
    Iterative,
}

impl SsnPath {
    pub const ALL: [SsnPath; 5] = [
        SsnPath::Auto,
        SsnPath::Augmented,
        SsnPath::Refactor,
        SsnPath::Schur,
        SsnPath::Iterative,
    ];

    /// The name in the problem file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SsnPath::Auto => "auto",
            SsnPath::Augmented => "augmented",
            SsnPath::Refactor => "refactor",
            SsnPath::Schur => "schur",
            SsnPath::Iterative => "iterative",
        }
    }
}

/// `auto` | `augmented` | `refactor` | `schur` | `iterative`.
impl FromStr for SsnPath {
    type Err = String;
    fn from_str(p: &str) -> Result<SsnPath, String> {
        SsnPath::ALL
            .into_iter()
            .find(|k| k.name() == p)
            .ok_or_else(|| {
                format!(
                "ssn_path = \"{p}\": expected \"auto\", \"augmented\", \"refactor\", \"schur\" or \"iterative\""
            )
            })
    }
}

/// Semismooth Newton / primal–dual active set (docs/methods.md §7).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SsnSettings {
    pub path: SsnPath,
}

impl SsnSettings {
    pub fn from_section(s: &SolverSection) -> Result<Self, String> {
        let path = s.ssn_path.unwrap_or_default();
        Ok(SsnSettings { path })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_override_the_file_key_by_key() {
        let file = SolverSection {
            method: Some(MethodChoice::Named(MethodId::Asm)),
            tol: Some(1e-8),
            rho: Some(2.0),
            ..Default::default()
        };
        let flags = SolverSection {
            tol: Some(1e-9),
            ..Default::default()
        };
        let s = file.overlay(&flags);
        assert_eq!(s.method, Some(MethodChoice::Named(MethodId::Asm)));
        assert_eq!(s.tol, Some(1e-9));
        assert_eq!(s.rho, Some(2.0));
    }

    #[test]
    fn every_key_is_validated_whatever_the_method() {
        let bad = [
            SolverSection {
                tol: Some(1.0),
                ..Default::default()
            },
            SolverSection {
                tol: Some(f64::NAN),
                ..Default::default()
            },
            SolverSection {
                max_iter: Some(0),
                ..Default::default()
            },
            SolverSection {
                omega: Some(2.0),
                ..Default::default()
            },
            SolverSection {
                penalty: Some(-1.0),
                ..Default::default()
            },
            SolverSection {
                rho: Some(f64::NAN),
                ..Default::default()
            },
            SolverSection {
                penalty: Some(f64::INFINITY),
                ..Default::default()
            },
            SolverSection {
                rho: Some(f64::INFINITY),
                ..Default::default()
            },
            SolverSection {
                kkt_target: Some(0.0),
                ..Default::default()
            },
            SolverSection {
                kkt_target: Some(f64::NAN),
                ..Default::default()
            },
        ];
        for s in bad {
            assert!(Settings::from_section(&s).is_err(), "{s:?}");
        }
        let s = Settings::from_section(&SolverSection::default()).unwrap();
        assert_eq!(s, Settings::default());
    }

    /// A bad name is refused by its parser, the one the file and the flags
    /// share, with the accepted values.
    #[test]
    fn names_are_parsed_once_with_the_accepted_values() {
        let e = "all".parse::<Release>().unwrap_err();
        assert!(
            e.contains("release = \"all\"") && e.contains("\"multiple\""),
            "{e}"
        );
        let e = "fast".parse::<SsnPath>().unwrap_err();
        assert!(
            e.contains("ssn_path = \"fast\"") && e.contains("\"iterative\""),
            "{e}"
        );
        let e = "ilu".parse::<PrecondKind>().unwrap_err();
        assert!(e.contains("\"ilu\"") && e.contains("none, jacobi"), "{e}");
        let e = "metis".parse::<Ordering>().unwrap_err();
        assert!(e.contains("\"amd\" or \"nested-dissection\""), "{e}");
        for p in SsnPath::ALL {
            assert_eq!(p.name().parse(), Ok(p));
        }
        assert_eq!("single".parse(), Ok(Release::Single));
        let e = toml::from_str::<SolverSection>("method = \"magic\"").unwrap_err();
        assert!(e.to_string().contains("unknown method \"magic\""), "{e}");
        let e = toml::from_str::<SolverSection>("release = \"all\"").unwrap_err();
        assert!(e.to_string().contains("release = \"all\""), "{e}");
    }

    #[test]
    fn keys_of_another_method_are_named() {
        let s = SolverSection {
            rho: Some(1.0),
            ssn_path: Some(SsnPath::Schur),
            preconditioner: Some(PrecondKind::Ic0),
            ..Default::default()
        };
        assert_eq!(s.unused_by(MethodId::Ssn), vec!["preconditioner", "rho"]);
        assert_eq!(
            s.unused_by(MethodId::Uzawa),
            vec!["preconditioner", "ssn_path"]
        );
        assert_eq!(s.unused_by(MethodId::Cgc), vec!["rho", "ssn_path"]);
        assert!(SolverSection::default()
            .unused_by(MethodId::Penalty)
            .is_empty());
    }

    #[test]
    fn the_section_refuses_unknown_keys() {
        let e = toml::from_str::<SolverSection>("tol = 1e-8\ntolerance = 1e-8\n").unwrap_err();
        assert!(e.to_string().contains("tolerance"), "{e}");
        let s: SolverSection = toml::from_str("accelerate = false\nssn_path = \"schur\"").unwrap();
        let t = Settings::from_section(&s).unwrap();
        assert!(!t.uzawa.accelerate && !t.penalty.accelerate);
        assert_eq!(t.ssn.path, SsnPath::Schur);
        assert_eq!(t.ordering, Ordering::Amd);
        assert_eq!(t.memory_limit, None);
        for (text, bytes) in [
            ("8 GiB", 8u64 << 30),
            ("512MiB", 512 << 20),
            ("1.5 KiB", 1536),
            ("1000", 1000),
            ("2 TiB", 2 << 40),
            ("1e3 KiB", 1_024_000),
            ("2E1MiB", 20 << 20),
        ] {
            let s: SolverSection = toml::from_str(&format!("memory_limit = \"{text}\"")).unwrap();
            let t = Settings::from_section(&s).unwrap();
            assert_eq!(t.memory_limit, Some(bytes), "{text}");
        }
        for text in [
            "8 GB", "-1 GiB", "0", "0.5", "GiB", "lots", "nan GiB", "1e30 TiB",
        ] {
            let e = toml::from_str::<SolverSection>(&format!("memory_limit = \"{text}\""))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("memory_limit") && e.contains("GiB"),
                "{text}: {e}"
            );
        }
        let s: SolverSection = toml::from_str("ordering = \"nested-dissection\"").unwrap();
        let t = Settings::from_section(&s).unwrap();
        assert_eq!(t.ordering, Ordering::NestedDissection);
        let e = toml::from_str::<SolverSection>("ordering = \"nd\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"amd\" or \"nested-dissection\""), "{e}");
    }
}
