//! `signorini pack`: a checkpoint as one self-contained file. A run with
//! load steps writes its checkpoint split (`NAME.h5`, an index of external
//! links to `NAME_mesh.h5` and one `NAME_NNNN.h5` per step), which moves
//! only as a whole; the packed file holds the same tree in one file
//! (docs/problem-format.md §6) and is read by `solve --restart` and `plot`
//! like any checkpoint. Bad input (an unreadable checkpoint, a missing step
//! file, named; an output that is one of the checkpoint's own files) is one
//! line on stderr and exit 2, with no output file written.

use super::solve::{bad_input, EXIT_BAD_INPUT};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct PackArgs {
    /// The checkpoint (NAME.h5, either layout).
    pub checkpoint: PathBuf,
    /// The single file to write (replaced atomically if it exists).
    #[arg(long, short)]
    pub output: PathBuf,
}

pub fn run(a: &PackArgs, quiet: bool) -> i32 {
    match crate::io::hdf5::pack(&a.checkpoint, &a.output) {
        Ok(p) => {
            if !quiet {
                crate::outln!(
                    "packed {} step(s) from {} file(s) of {} into {}",
                    p.steps.len(),
                    p.sources.len(),
                    a.checkpoint.display(),
                    a.output.display()
                );
            }
            0
        }
        Err(e) => {
            bad_input(&e);
            EXIT_BAD_INPUT
        }
    }
}
