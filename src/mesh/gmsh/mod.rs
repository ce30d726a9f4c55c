//! Reader for Gmsh `.msh` files: MSH 4.1 (ASCII and binary) and MSH 2.2 (ASCII).
//!
//! Only what a 2D P1 mesh needs is kept: node coordinates (x, y; z is
//! ignored), 3-node triangles, 2-node lines, points and physical groups.
//! Any other element type is an error. Unknown sections are skipped.
//!
//! The parser works on a byte slice with a hand-written tokenizer, so large
//! ASCII files parse without per-token allocation; binary data is decoded
//! straight from slices. It never panics on bad input: every problem is a
//! [`MeshError`] that names the file, the section and the line (ASCII) or the
//! byte offset (binary).
//!
//! The parser's state is here; `lexer` reads tokens and values (ASCII
//! and binary) and makes the messages, `sections` parses each section,
//! and `assemble` turns what was read into a [`Mesh`].

mod assemble;
mod lexer;
mod sections;
mod solid;

pub use solid::volume6;

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::{Dim, Mesh, MeshError};

/// Read and parse a Gmsh `.msh` file.
pub fn read_msh(path: &Path) -> Result<Mesh, MeshError> {
    let bytes = read_mesh_bytes(path)?;
    parse_msh(path, &bytes)
}

/// Largest magnitude of a node coordinate: products of coordinates (areas,
/// stiffness entries) must stay far from overflow.
pub const MAX_COORDINATE: f64 = 1e100;

/// The bytes of a mesh file, which must be a regular file (a FIFO or a
/// device such as `/dev/zero` would block or never end). The buffer is
/// reserved for the file's size up front with `try_reserve`, so a file too
/// large for memory is an error, not an abort.
pub fn read_mesh_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    use std::io::Read;
    let io = |source: std::io::Error| MeshError::Io {
        path: path.to_path_buf(),
        source,
    };
    let invalid = |msg: String| MeshError::Invalid {
        path: path.to_path_buf(),
        msg,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        return Err(invalid("is a directory, not a mesh file".into()));
    }
    if !meta.is_file() {
        return Err(invalid(
            "is not a regular file (a FIFO, socket or device); give a .msh file".into(),
        ));
    }
    let len = usize::try_from(meta.len())
        .map_err(|_| invalid(format!("{} bytes is too large", meta.len())))?;
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(len).map_err(|_| {
        invalid(format!(
            "not enough memory to read it: needs about {:.1} GiB",
            len as f64 / (1u64 << 30) as f64
        ))
    })?;
    let file = std::fs::File::open(path).map_err(io)?;
    // Never more than the size seen above (the file may grow meanwhile).
    file.take(meta.len()).read_to_end(&mut bytes).map_err(io)?;
    Ok(bytes)
}

/// Parse the contents of a Gmsh `.msh` file; `path` is only used for the
/// messages and for `Mesh::path`.
pub fn parse_msh(path: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    Parser::new(path, bytes).run()
}

// ---------------------------------------------------------------------------
// Element types

/// Human name of a Gmsh element type, for messages.
fn element_type_name(t: i64) -> &'static str {
    match t {
        1 => "2-node line",
        2 => "3-node triangle",
        3 => "4-node quadrangle",
        4 => "4-node tetrahedron",
        5 => "8-node hexahedron",
        6 => "6-node prism",
        7 => "5-node pyramid",
        8 => "3-node second-order line",
        9 => "6-node second-order triangle",
        10 => "9-node second-order quadrangle",
        11 => "10-node second-order tetrahedron",
        12 => "27-node second-order hexahedron",
        13 => "18-node second-order prism",
        14 => "14-node second-order pyramid",
        15 => "1-node point",
        16 => "8-node second-order quadrangle",
        17 => "20-node second-order hexahedron",
        18 => "15-node second-order prism",
        19 => "13-node second-order pyramid",
        20 => "9-node third-order incomplete triangle",
        21 => "10-node third-order triangle",
        22 => "12-node fourth-order incomplete triangle",
        23 => "15-node fourth-order triangle",
        24 => "15-node fifth-order incomplete triangle",
        25 => "21-node fifth-order triangle",
        26 => "4-node third-order line",
        27 => "5-node fourth-order line",
        28 => "6-node fifth-order line",
        29 => "20-node third-order tetrahedron",
        30 => "35-node fourth-order tetrahedron",
        31 => "56-node fifth-order tetrahedron",
        36 => "16-node third-order quadrangle",
        92 => "64-node third-order hexahedron",
        93 => "125-node fourth-order hexahedron",
        _ => "element type unknown to this reader",
    }
}

/// The element kinds this reader keeps.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    Point,
    Line,
    Triangle,
    /// The 4-node tetrahedron of a solid model (docs/design.md §"Adding a
    /// kind: solid 3D").
    Tet,
}

impl Kind {
    fn from_type(t: i64) -> Option<Kind> {
        match t {
            15 => Some(Kind::Point),
            1 => Some(Kind::Line),
            2 => Some(Kind::Triangle),
            4 => Some(Kind::Tet),
            _ => None,
        }
    }
    fn dim(self) -> Dim {
        match self {
            Kind::Point => 0,
            Kind::Line => 1,
            Kind::Triangle => 2,
            Kind::Tet => 3,
        }
    }
    fn nodes(self) -> usize {
        match self {
            Kind::Point => 1,
            Kind::Line => 2,
            Kind::Triangle => 3,
            Kind::Tet => 4,
        }
    }
}

fn unsupported_type_msg(t: i64, elem_tag: u64) -> String {
    unsupported_in_group(t, elem_tag, None)
}

/// [`unsupported_type_msg`] naming the physical group(s) of the element
/// when known (a 10-node tetrahedron in a Physical Volume).
fn unsupported_in_group(t: i64, elem_tag: u64, group: Option<&str>) -> String {
    let name = element_type_name(t);
    let dim = if name.contains("tetra") || name.contains("hexa") || name.contains("pri") {
        3
    } else {
        2
    };
    // What to change in Gmsh: the element order, or the recombination into quadrangles.
    let hint = if name.contains("quadrangle") {
        "; mesh with triangles (no Recombine / Mesh.RecombineAll = 0) and first-order \
         elements (`gmsh -2 -order 1`)"
            .to_string()
    } else if name.contains("order") {
        format!(
            "; re-mesh with first-order elements (`gmsh -{dim} -order 1`, Mesh.ElementOrder = 1)"
        )
    } else {
        String::new()
    };
    let group = group.map_or(String::new(), |g| format!(" in physical group {g}"));
    format!(
        "element {elem_tag}{group} has type {t} ({name}), which is not supported: only linear (P1) \
         3-node triangles (type 2), 2-node lines (type 1) and points (type 15) are supported, \
         and 4-node tetrahedra (type 4) in 3D{hint}"
    )
}

// ---------------------------------------------------------------------------
// Parser state

#[derive(Clone, Copy, PartialEq, Eq)]
enum Version {
    V41,
    V22,
}

/// An element block of a 4.1 file, resolved against `$Entities` at the end.
struct Block {
    kind: Kind,
    entity: i32,
    start: usize,
    len: usize,
}

/// Elements as read, with node tags not yet mapped to indices.
#[derive(Default)]
struct RawElements {
    points: Vec<u64>,
    point_tags: Vec<u64>,
    lines: Vec<[u64; 2]>,
    line_tags: Vec<u64>,
    tris: Vec<[u64; 3]>,
    tri_tags: Vec<u64>,
    tets: Vec<[u64; 4]>,
    tet_tags: Vec<u64>,
}

impl RawElements {
    fn count(&self, kind: Kind) -> usize {
        match kind {
            Kind::Point => self.points.len(),
            Kind::Line => self.lines.len(),
            Kind::Triangle => self.tris.len(),
            Kind::Tet => self.tets.len(),
        }
    }
    /// Store one element; `nodes` holds at least `kind.nodes()` tags.
    fn push(&mut self, kind: Kind, tag: u64, nodes: &[u64; 4]) {
        match kind {
            Kind::Point => {
                self.points.push(nodes[0]);
                self.point_tags.push(tag);
            }
            Kind::Line => {
                self.lines.push([nodes[0], nodes[1]]);
                self.line_tags.push(tag);
            }
            Kind::Triangle => {
                self.tris.push([nodes[0], nodes[1], nodes[2]]);
                self.tri_tags.push(tag);
            }
            Kind::Tet => {
                self.tets.push(*nodes);
                self.tet_tags.push(tag);
            }
        }
    }
    fn reserve(&mut self, kind: Kind, n: usize) {
        match kind {
            Kind::Point => {
                self.points.reserve(n);
                self.point_tags.reserve(n);
            }
            Kind::Line => {
                self.lines.reserve(n);
                self.line_tags.reserve(n);
            }
            Kind::Triangle => {
                self.tris.reserve(n);
                self.tri_tags.reserve(n);
            }
            Kind::Tet => {
                self.tets.reserve(n);
                self.tet_tags.reserve(n);
            }
        }
    }
}

struct Parser<'a> {
    path: &'a Path,
    b: &'a [u8],
    pos: usize,
    /// 1-based line of `pos` (ASCII files only).
    line: usize,
    /// Start of the last token read (for binary messages).
    tok_start: usize,
    binary: bool,
    big_endian: bool,
    version: Version,
    section: String,

    names: HashMap<(Dim, i32), String>,
    /// Physical tags of each entity (dim 0 to 3), from `$Entities`.
    entities: Option<HashMap<(Dim, i32), Vec<i32>>>,
    /// Nodes in file order.
    node_tags: Vec<u64>,
    node_xy: Vec<[f64; 2]>,
    /// z of each node (kept apart so that a 2D mesh reads as before; the
    /// mesh keeps it only when it holds tetrahedra).
    node_z: Vec<f64>,
    have_nodes: bool,
    have_elements: bool,
    elems: RawElements,
    blocks: Vec<Block>,
    groups: BTreeMap<(Dim, i32), Vec<usize>>,
}
