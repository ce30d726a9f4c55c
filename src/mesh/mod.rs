//! The mesh as read from Gmsh: nodes, P1 triangles, 2-node lines, points, and
//! physical groups by name. No mechanics here; `fem::topology` cuts it into bodies.

pub mod gmsh;

use std::path::PathBuf;

pub use gmsh::read_msh;

/// Dimension of a physical group's entities: 0 points, 1 curves, 2 surfaces.
pub type Dim = u8;

/// A Gmsh physical group: its elements are indices into `Mesh::points`
/// (dim 0), `Mesh::lines` (dim 1) or `Mesh::triangles` (dim 2).
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalGroup {
    pub dim: Dim,
    pub tag: i32,
    /// From `$PhysicalNames`; the tag as text when the group has no name.
    pub name: String,
    pub elements: Vec<usize>,
}

/// A triangulated 2D mesh. Node indices are dense (0..n) in the order of the
/// Gmsh node tags; `node_tags` keeps the original tags for messages.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub path: PathBuf,
    pub nodes: Vec<[f64; 2]>,
    pub node_tags: Vec<u64>,
    /// Point elements (Gmsh type 15): node index.
    pub points: Vec<usize>,
    /// 2-node line elements (Gmsh type 1).
    pub lines: Vec<[usize; 2]>,
    /// 3-node triangles (Gmsh type 2), node order as in the file.
    pub triangles: Vec<[usize; 3]>,
    /// Gmsh element tag of each triangle (for error messages).
    pub triangle_tags: Vec<u64>,
    pub groups: Vec<PhysicalGroup>,
}

impl Mesh {
    /// The group named `name` of dimension `dim`, if any.
    pub fn group(&self, name: &str, dim: Dim) -> Option<&PhysicalGroup> {
        self.groups.iter().find(|g| g.dim == dim && g.name == name)
    }

    /// Any group named `name`, whatever its dimension.
    pub fn group_any(&self, name: &str) -> Option<&PhysicalGroup> {
        self.groups.iter().find(|g| g.name == name)
    }
}

/// Errors of the mesh reader. Every message names the file and, where it
/// applies, the section and the line (ASCII) or byte offset (binary).
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}", parse_message(path, *line, section, msg))]
    Parse {
        path: PathBuf,
        /// 1-based line number (ASCII) or byte offset (binary, prefixed in `msg`).
        line: usize,
        section: String,
        msg: String,
    },
    #[error("{path}: {msg}")]
    Invalid { path: PathBuf, msg: String },
}

/// `file:LINE: section: msg` for ASCII files; `file: section: at byte offset
/// N: msg` for binary ones (the offset is already in `msg`, and `file:N:`
/// would read as a line number).
fn parse_message(path: &std::path::Path, line: usize, section: &str, msg: &str) -> String {
    if msg.starts_with("at byte offset ") {
        format!("{}: {section}: {msg}", path.display())
    } else {
        format!("{}:{line}: {section}: {msg}", path.display())
    }
}
