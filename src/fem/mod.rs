//! Finite elements: topology (bodies, node copies, contact rows), the P1
//! element, and assembly of the [`crate::qp::QpProblem`].

pub mod assembly;
pub mod element;
pub mod topology;

pub use assembly::{build, Model};

use std::path::{Path, PathBuf};

/// A problem that does not fit its mesh: the message names the TOML file
/// and the group, key, node or element.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {msg}")]
pub struct FemError {
    pub path: PathBuf,
    pub msg: String,
}

impl FemError {
    pub fn new(path: &Path, msg: String) -> FemError {
        FemError {
            path: path.to_path_buf(),
            msg,
        }
    }
}
