//! The `signorini` command line. Exit codes: 0 converged, 2 bad input
//! (including an unbounded problem and an unwritable output directory),
//! 3 not converged (outputs written and flagged) or, with `--strict`, a
//! KKT residual above target, 4 standard output not writable (a closed
//! pipe, a full disk; the report is lost, the files are written).

pub mod compare;
pub mod export;
pub mod limit;
pub mod mesh;
pub mod pack;
pub mod plot;
mod plot3d;
pub mod progress;
pub mod section;
pub mod solve;

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "signorini",
    version,
    about = "Multibody contact in 2D elasticity (Signorini, optional Tresca/Coulomb friction) by P1 FEM, with a choice of QP methods"
)]
pub struct Cli {
    /// Diagnostics level on stderr (`error` hides the warnings).
    #[arg(
        long,
        global = true,
        default_value = "warn",
        value_parser = ["error", "warn", "info", "debug", "trace"]
    )]
    pub log_level: String,
    /// `-q`: no report nor progress on stdout (warnings and errors still go
    /// to stderr); `-qq`: the warnings hidden too (`--log-level error`).
    #[arg(long, short, global = true, action = clap::ArgAction::Count)]
    pub quiet: u8,
    #[command(subcommand)]
    pub command: Command,
    /// How models are built: set by `main` from SIGNORINI_THREADS, no flag.
    #[arg(skip)]
    pub build: crate::fem::BuildOptions,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Solve a problem file and write VTU, HDF5 and JSON outputs.
    Solve(SolveArgs),
    /// Run every method (or `--methods a,b`) on one problem and print the comparison table.
    Compare(compare::CompareArgs),
    /// Draw a checkpoint (NAME.h5) as PNG or SVG: the deformed mesh coloured by a field, or the contact pressure; 3D: a section by a plane (--cut) or the contact footprint (--contact).
    Plot(plot::PlotArgs),
    /// Mesh a Gmsh .geo file (2D, MSH 4.1) and check it.
    Mesh(mesh::MeshArgs),
    /// Write a checkpoint (a split NAME.h5 with its step files) as one self-contained HDF5 file.
    Pack(pack::PackArgs),
    /// Write the assembled QP (C, d, A, g, ker C) as Matrix Market files + meta.json.
    Export(export::ExportArgs),
    /// The benchmark's yardstick: one sparse Cholesky factorization + solve of C (no contact).
    Limit(limit::LimitArgs),
    /// List the available methods and preconditioners.
    Methods,
}

/// The `[solver]` entries as flags (they override the file, key by key)
/// and the certificate's target.
#[derive(Args, Debug, Clone, Default)]
pub struct SolverFlags {
    #[command(flatten)]
    pub flags: section::SectionFlags,
    /// Exit 3 when the KKT certificate fails its target (or any warning).
    #[arg(long)]
    pub strict: bool,
}

impl SolverFlags {
    /// The `[solver]` entries given on the command line.
    pub fn section(&self) -> crate::qp::SolverSection {
        (&self.flags).into()
    }
}

// clap prints these doc comments as `--help`: `[output]` stays as written.
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Args, Debug, Clone)]
pub struct SolveArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// Output directory (default: [output] dir, else `out`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Ignore every [[contact]] (contact curves become interior lines).
    #[arg(long)]
    pub no_contact: bool,
    /// zlib-compress the VTU arrays.
    #[arg(long)]
    pub compress: bool,
    /// Continue after the last complete step of this checkpoint (warm start).
    #[arg(long)]
    pub restart: Option<PathBuf>,
    /// Start each load step from the answer of the same model on a coarser
    /// mesh: that solve's checkpoint (NAME.h5), interpolated onto this mesh
    /// (3D models; nested iteration, docs/methods.md §7.2).
    #[arg(long, value_name = "COARSE.h5", conflicts_with = "restart")]
    pub start_from: Option<PathBuf>,
    /// Stop after this load step (1-based); `--restart` continues later.
    #[arg(long)]
    pub max_steps: Option<usize>,
    #[command(flatten)]
    pub solver: SolverFlags,
}

/// The exit code of a command line clap refused or answered itself
/// (`--help`, `--version`): its text printed, where a failure to write the
/// help to stdout is exit [`crate::run::EXIT_STDOUT`] with one line on
/// stderr, as for every command.
pub fn clap_exit(e: &clap::Error) -> i32 {
    use std::io::Write;
    let printed = e.print().and_then(|()| std::io::stdout().flush());
    match printed {
        Err(io) if !e.use_stderr() => {
            crate::io::console::record_stdout_failure(&io);
            stdout_verdict(0)
        }
        _ => e.exit_code(),
    }
}

/// The exit code `code` of a command whose stdout failed (a closed pipe,
/// a full disk): one line on stderr, and [`crate::run::EXIT_STDOUT`]
/// instead of 0 (a failure's own code is kept).
fn stdout_verdict(code: i32) -> i32 {
    match crate::io::console::stdout_failure() {
        None => code,
        Some(e) => {
            crate::errln!(
                "error: cannot write to standard output: {e} (the report is lost; files already written are complete)"
            );
            if code == 0 {
                crate::run::EXIT_STDOUT
            } else {
                code
            }
        }
    }
}

/// Run the CLI; returns the process exit code.
pub fn run(cli: Cli) -> i32 {
    let code = run_command(cli);
    stdout_verdict(code)
}

fn run_command(cli: Cli) -> i32 {
    let level = if cli.quiet >= 2 {
        "error"
    } else {
        cli.log_level.as_str()
    };
    let quiet = cli.quiet > 0;
    // Debug and trace lines carry a millisecond timestamp (phase timing).
    let verbose = level.contains("debug") || level.contains("trace");
    let _ = env_logger::Builder::new()
        .parse_filters(level)
        .format_timestamp(verbose.then_some(env_logger::TimestampPrecision::Millis))
        .try_init();
    match cli.command {
        Command::Solve(a) => solve::run(&a, quiet, &cli.build),
        Command::Compare(a) => compare::run(&a, quiet, &cli.build),
        Command::Mesh(a) => mesh::run(&a, quiet),
        Command::Plot(a) => plot::run(&a, quiet),
        Command::Pack(a) => pack::run(&a, quiet),
        Command::Export(a) => export::run(&a, quiet, &cli.build),
        Command::Limit(a) => limit::run(&a, quiet, &cli.build),
        Command::Methods => {
            // One line per method, its name first (scripts parse it), then
            // what it declares; `auto`, the default, is ssn.
            for id in crate::qp::MethodId::ALL {
                let m = id.method();
                let c = m.capabilities();
                let factor = match c.factor {
                    crate::qp::method::Factor::Always => "always",
                    crate::qp::method::Factor::Never => "never",
                    crate::qp::method::Factor::BySettings => "by settings",
                };
                crate::outln!(
                    "{:<10} {} [friction {}, floating bodies {}, factor {factor}{}]",
                    id.name(),
                    m.summary(),
                    match c.friction {
                        crate::qp::method::FrictionSupport::None => "no",
                        crate::qp::method::FrictionSupport::Lines => "2D",
                        crate::qp::method::FrictionSupport::Planes => "2D and 3D",
                    },
                    if c.semicoercive { "yes" } else { "no" },
                    if id == crate::qp::MethodChoice::Auto.resolve() {
                        "; the default, method = \"auto\""
                    } else {
                        ""
                    }
                );
            }
            let pcs: Vec<&str> = crate::qp::precond::PrecondKind::ALL
                .iter()
                .map(|k| k.name())
                .collect();
            crate::outln!("preconditioners (cgc): {}", pcs.join(", "));
            0
        }
    }
}
