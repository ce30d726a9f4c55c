//! Output files: VTU (ParaView), PVD (time series), HDF5 checkpoint, JSON summary.
//! Every file is written to a temporary name in the target directory and
//! renamed into place, so a crash never leaves a half-written output.
//!
//! The writers see only the plain arrays of [`crate::output`]; they know
//! nothing of the solver or of the mesh reader.

pub mod atomic;
pub mod console;
pub mod hdf5;
pub mod mtx;
pub mod vtu;

pub use atomic::{write_atomic, IoError};
