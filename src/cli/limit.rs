//! `signorini limit model.toml`: the flags of [`crate::run::limit()`] (the
//! benchmark's yardstick: one sparse Cholesky factorization of C and one
//! solve C x = d, or with `--path iterative` one AMG-PCG solve as on ssn's
//! iterative path; plane and solid models) and its report as one JSON line.

use super::solve::bad_input;
use crate::linalg::ordering::Ordering;
use crate::qp::ByteSize;
use crate::run::{self, LimitPath, LimitSpec};
use clap::Args;
use std::path::PathBuf;

// clap prints these doc comments as `--help`: brackets such as [px] stay
// literal there, so rustdoc must not read them as links.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone)]
pub struct LimitArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Ignore every [[contact]] (contact curves become interior lines).
    #[arg(long)]
    pub no_contact: bool,
    /// Factor and solve this many times; the JSON holds the median.
    #[arg(long, default_value_t = 1, value_parser = at_least_one)]
    pub repeat: usize,
    /// amd | nested-dissection; overrides [solver] ordering (docs/methods.md §3).
    #[arg(long)]
    pub ordering: Option<Ordering>,
    /// Largest factor allowed, e.g. "8 GiB"; overrides [solver] memory_limit.
    #[arg(long)]
    pub memory_limit: Option<ByteSize>,
    /// cholesky | iterative: one sparse Cholesky factorization and solve of
    /// C, or one AMG-PCG solve of C (C + ρAᵀA when a body floats) with the
    /// near-null space, multigrid and tol of ssn_path = "iterative"
    /// (docs/methods.md §7.2); the JSON adds iterations and levels.
    #[arg(long, default_value = "cholesky")]
    pub path: LimitPath,
}

/// A count of at least 1 (`--repeat 0` would time nothing).
fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err("expected a whole number of times, at least 1".into()),
    }
}

pub fn run(a: &LimitArgs, _quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let prep = match run::load(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let spec = LimitSpec {
        repeat: a.repeat,
        ordering: a.ordering,
        memory_limit: a.memory_limit,
        path: a.path,
    };
    match run::limit(prep.assembled(), &spec) {
        Ok(r) => {
            crate::outln!("{}", r.to_json_line());
            0
        }
        Err(e) => bad_input(&e),
    }
}
