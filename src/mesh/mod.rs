//! The mesh as read from Gmsh: nodes, P1 triangles, 2-node lines, points,
//! 4-node tetrahedra (a 3D mesh), and physical groups by name. No mechanics
//! here; `fem::topology` cuts it into bodies.

pub mod gmsh;

use std::path::PathBuf;

pub use gmsh::read_msh;

/// Dimension of a physical group's entities: 0 points, 1 curves, 2 surfaces,
/// 3 volumes.
pub type Dim = u8;

/// A Gmsh physical group: its elements are indices into `Mesh::points`
/// (dim 0), `Mesh::lines` (dim 1), `Mesh::triangles` (dim 2) or
/// `Mesh::tets` (dim 3).
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
    /// z of each node, kept only for a 3D mesh (one with tetrahedra);
    /// empty for a 2D one, whose z the reader ignores.
    pub z: Vec<f64>,
    /// 4-node tetrahedra (Gmsh type 4), positively oriented (the reader
    /// reorders a volume given the other way round, src/mesh/gmsh/solid.rs).
    /// In a 3D mesh the triangles are the boundary facets.
    pub tets: Vec<[usize; 4]>,
    /// Gmsh element tag of each tetrahedron.
    pub tet_tags: Vec<u64>,
}

impl Mesh {
    /// The group named `name` of dimension `dim`, if any.
    pub fn group(&self, name: &str, dim: Dim) -> Option<&PhysicalGroup> {
        self.groups.iter().find(|g| g.dim == dim && g.name == name)
    }

    /// The dimension of the model the mesh holds: 3 with tetrahedra, else 2.
    pub fn dim(&self) -> usize {
        if self.tets.is_empty() {
            2
        } else {
            3
        }
    }

    /// Node `i` as a point of the model's `D`-dimensional space: (x, y)
    /// or (x, y, z) (docs/design.md §"Element kinds").
    pub fn node<const D: usize>(&self, i: usize) -> [f64; D] {
        let (xy, z) = (self.nodes[i], self.z.get(i).copied().unwrap_or(0.0));
        std::array::from_fn(|k| [xy[0], xy[1], z][k])
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
