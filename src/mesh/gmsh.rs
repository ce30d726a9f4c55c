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

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::{Dim, Mesh, MeshError, PhysicalGroup};

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
}

impl Kind {
    fn from_type(t: i64) -> Option<Kind> {
        match t {
            15 => Some(Kind::Point),
            1 => Some(Kind::Line),
            2 => Some(Kind::Triangle),
            _ => None,
        }
    }
    fn dim(self) -> Dim {
        match self {
            Kind::Point => 0,
            Kind::Line => 1,
            Kind::Triangle => 2,
        }
    }
    fn nodes(self) -> usize {
        match self {
            Kind::Point => 1,
            Kind::Line => 2,
            Kind::Triangle => 3,
        }
    }
}

fn unsupported_type_msg(t: i64, elem_tag: u64) -> String {
    let name = element_type_name(t);
    // What to change in Gmsh: the element order, or the recombination into quadrangles.
    let hint = if name.contains("quadrangle") {
        "; mesh with triangles (no Recombine / Mesh.RecombineAll = 0) and first-order \
         elements (`gmsh -2 -order 1`)"
    } else if name.contains("order") {
        "; re-mesh with first-order elements (`gmsh -2 -order 1`, Mesh.ElementOrder = 1)"
    } else {
        ""
    };
    format!(
        "element {elem_tag} has type {t} ({name}), which is not supported: only linear (P1) \
         3-node triangles (type 2), 2-node lines (type 1) and points (type 15) are supported{hint}"
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
}

impl RawElements {
    fn count(&self, kind: Kind) -> usize {
        match kind {
            Kind::Point => self.points.len(),
            Kind::Line => self.lines.len(),
            Kind::Triangle => self.tris.len(),
        }
    }
    /// Store one element; `nodes` holds at least `kind.nodes()` tags.
    fn push(&mut self, kind: Kind, tag: u64, nodes: &[u64; 3]) {
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
                self.tris.push(*nodes);
                self.tri_tags.push(tag);
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
    /// Physical tags of each entity (dim <= 2), from `$Entities`.
    entities: Option<HashMap<(Dim, i32), Vec<i32>>>,
    /// Nodes in file order.
    node_tags: Vec<u64>,
    node_xy: Vec<[f64; 2]>,
    have_nodes: bool,
    have_elements: bool,
    elems: RawElements,
    blocks: Vec<Block>,
    groups: BTreeMap<(Dim, i32), Vec<usize>>,
}

/// Bounded capacity: never reserve more items than the remaining bytes could hold.
fn cap(count: u64, remaining: usize, min_bytes_per_item: usize) -> usize {
    let by_bytes = remaining / min_bytes_per_item.max(1);
    usize::try_from(count).unwrap_or(usize::MAX).min(by_bytes)
}

fn show(tok: &[u8]) -> String {
    let mut s: String = String::from_utf8_lossy(tok).chars().take(40).collect();
    if tok.len() > 40 {
        s.push_str("...");
    }
    s
}

fn parse_u64(tok: &[u8]) -> Option<u64> {
    let digits = match tok.first() {
        Some(b'+') => tok.get(1..)?,
        _ => tok,
    };
    if digits.is_empty() {
        return None;
    }
    let mut v: u64 = 0;
    for &c in digits {
        if !c.is_ascii_digit() {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(u64::from(c - b'0'))?;
    }
    Some(v)
}

fn parse_i64(tok: &[u8]) -> Option<i64> {
    match tok.first() {
        Some(b'-') => {
            let m = parse_u64(tok.get(1..)?)?;
            if m <= i64::MAX as u64 {
                Some(-(m as i64))
            } else if m == i64::MAX as u64 + 1 {
                Some(i64::MIN)
            } else {
                None
            }
        }
        _ => i64::try_from(parse_u64(tok)?).ok(),
    }
}

fn copy8(c: &[u8]) -> [u8; 8] {
    let mut a = [0u8; 8];
    for (d, s) in a.iter_mut().zip(c) {
        *d = *s;
    }
    a
}

fn copy4(c: &[u8]) -> [u8; 4] {
    let mut a = [0u8; 4];
    for (d, s) in a.iter_mut().zip(c) {
        *d = *s;
    }
    a
}

impl<'a> Parser<'a> {
    fn new(path: &'a Path, b: &'a [u8]) -> Self {
        Parser {
            path,
            b,
            pos: 0,
            line: 1,
            tok_start: 0,
            binary: false,
            big_endian: false,
            version: Version::V41,
            section: "$MeshFormat".to_string(),
            names: HashMap::new(),
            entities: None,
            node_tags: Vec::new(),
            node_xy: Vec::new(),
            have_nodes: false,
            have_elements: false,
            elems: RawElements::default(),
            blocks: Vec::new(),
            groups: BTreeMap::new(),
        }
    }

    // ----- errors -----

    fn err_at(&self, at: usize, msg: impl Into<String>) -> MeshError {
        let msg = msg.into();
        MeshError::Parse {
            path: self.path.to_path_buf(),
            line: at,
            section: self.section.clone(),
            msg: if self.binary {
                format!("at byte offset {at}: {msg}")
            } else {
                msg
            },
        }
    }

    /// Error located at the last token read.
    fn err_tok(&self, msg: impl Into<String>) -> MeshError {
        let at = if self.binary {
            self.tok_start
        } else {
            self.line
        };
        self.err_at(at, msg)
    }

    /// Error located at the current position.
    fn err_pos(&self, msg: impl Into<String>) -> MeshError {
        let at = if self.binary { self.pos } else { self.line };
        self.err_at(at, msg)
    }

    fn err_eof(&self, what: &str) -> MeshError {
        let msg = format!("unexpected end of file while reading {what} (truncated file?)");
        if self.binary {
            self.err_at(self.b.len(), msg)
        } else {
            let last_nl = usize::from(self.b.last() == Some(&b'\n'));
            self.err_at(self.line.saturating_sub(last_nl).max(1), msg)
        }
    }

    fn invalid(&self, msg: impl Into<String>) -> MeshError {
        MeshError::Invalid {
            path: self.path.to_path_buf(),
            msg: msg.into(),
        }
    }

    fn remaining(&self) -> usize {
        self.b.len().saturating_sub(self.pos)
    }

    // ----- ASCII tokens -----

    fn skip_ws(&mut self) {
        while let Some(&c) = self.b.get(self.pos) {
            if !c.is_ascii_whitespace() {
                break;
            }
            if c == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    fn token(&mut self, what: &str) -> Result<&'a [u8], MeshError> {
        self.skip_ws();
        if self.pos >= self.b.len() {
            return Err(self.err_eof(what));
        }
        let start = self.pos;
        while let Some(&c) = self.b.get(self.pos) {
            if c.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        self.tok_start = start;
        Ok(self.b.get(start..self.pos).unwrap_or_default())
    }

    fn bad_token(&self, what: &str, kind: &str, tok: &[u8]) -> MeshError {
        if tok.first() == Some(&b'$') {
            self.err_tok(format!(
                "expected {what} ({kind}), found '{}': the section ends early \
                 (do the header counts disagree with the data?)",
                show(tok)
            ))
        } else {
            self.err_tok(format!("expected {what} ({kind}), found '{}'", show(tok)))
        }
    }

    fn a_u64(&mut self, what: &str) -> Result<u64, MeshError> {
        let tok = self.token(what)?;
        parse_u64(tok).ok_or_else(|| self.bad_token(what, "a non-negative integer", tok))
    }

    fn a_i32(&mut self, what: &str) -> Result<i32, MeshError> {
        let tok = self.token(what)?;
        parse_i64(tok)
            .and_then(|v| i32::try_from(v).ok())
            .ok_or_else(|| self.bad_token(what, "a 32-bit integer", tok))
    }

    fn a_f64(&mut self, what: &str) -> Result<f64, MeshError> {
        let tok = self.token(what)?;
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| self.bad_token(what, "a number", tok))
    }

    /// After a section header read as a token, step past the end of its line
    /// (binary data starts right after the newline).
    fn end_header_line(&mut self) -> Result<(), MeshError> {
        while let Some(&c) = self.b.get(self.pos) {
            match c {
                b' ' | b'\t' | b'\r' => self.pos += 1,
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    return Ok(());
                }
                _ => {
                    return Err(self.err_pos(format!(
                        "expected the end of the line after {}",
                        self.section
                    )))
                }
            }
        }
        Err(self.err_eof(&format!("the line after {}", self.section)))
    }

    fn expect_end(&mut self) -> Result<(), MeshError> {
        let end = format!("$End{}", self.section.get(1..).unwrap_or_default());
        let tok = self.token(&end)?;
        if tok != end.as_bytes() {
            return Err(self.err_tok(format!(
                "expected {end}, found '{}' (do the header counts disagree with the data?)",
                show(tok)
            )));
        }
        Ok(())
    }

    // ----- binary values -----

    fn take(&mut self, n: Option<usize>, what: &str) -> Result<&'a [u8], MeshError> {
        let rem = self.remaining();
        match n {
            Some(n) if n <= rem => {
                self.tok_start = self.pos;
                let s = self.b.get(self.pos..self.pos + n).unwrap_or_default();
                self.pos += n;
                Ok(s)
            }
            _ => {
                let need = n.map_or("more than the file size".to_string(), |n| n.to_string());
                Err(self.err_pos(format!(
                    "truncated: {what} needs {need} bytes but only {rem} are left"
                )))
            }
        }
    }

    fn u64_of(&self, c: &[u8]) -> u64 {
        if self.big_endian {
            u64::from_be_bytes(copy8(c))
        } else {
            u64::from_le_bytes(copy8(c))
        }
    }

    fn f64_of(&self, c: &[u8]) -> f64 {
        if self.big_endian {
            f64::from_be_bytes(copy8(c))
        } else {
            f64::from_le_bytes(copy8(c))
        }
    }

    fn i32_of(&self, c: &[u8]) -> i32 {
        if self.big_endian {
            i32::from_be_bytes(copy4(c))
        } else {
            i32::from_le_bytes(copy4(c))
        }
    }

    fn b_u64(&mut self, what: &str) -> Result<u64, MeshError> {
        let c = self.take(Some(8), what)?;
        Ok(self.u64_of(c))
    }

    fn b_i32(&mut self, what: &str) -> Result<i32, MeshError> {
        let c = self.take(Some(4), what)?;
        Ok(self.i32_of(c))
    }

    fn b_f64(&mut self, what: &str) -> Result<f64, MeshError> {
        let c = self.take(Some(8), what)?;
        Ok(self.f64_of(c))
    }

    // ----- either encoding -----

    fn size(&mut self, what: &str) -> Result<u64, MeshError> {
        if self.binary {
            self.b_u64(what)
        } else {
            self.a_u64(what)
        }
    }

    fn int(&mut self, what: &str) -> Result<i32, MeshError> {
        if self.binary {
            self.b_i32(what)
        } else {
            self.a_i32(what)
        }
    }

    fn double(&mut self, what: &str) -> Result<f64, MeshError> {
        if self.binary {
            self.b_f64(what)
        } else {
            self.a_f64(what)
        }
    }

    /// Location to report for the thing just read.
    fn here(&self) -> usize {
        if self.binary {
            self.tok_start
        } else {
            self.line
        }
    }

    // ----- top level -----

    fn run(mut self) -> Result<Mesh, MeshError> {
        if self.b.starts_with(&[0xEF, 0xBB, 0xBF]) {
            self.pos = 3;
        }
        self.skip_ws();
        if self.pos >= self.b.len() {
            return Err(self.invalid("empty file (not a Gmsh .msh file)"));
        }
        let first = self.token("$MeshFormat")?;
        if first != b"$MeshFormat" {
            return Err(self.invalid(format!(
                "missing $MeshFormat: the file starts with '{}' (not a Gmsh .msh file?)",
                show(first)
            )));
        }
        self.mesh_format()?;

        loop {
            self.section = "(between sections)".to_string();
            self.skip_ws();
            if self.pos >= self.b.len() {
                break;
            }
            let tok = self.token("a section header")?;
            let name = String::from_utf8_lossy(tok).into_owned();
            if !name.starts_with('$') || name.starts_with("$End") {
                return Err(self.err_tok(format!(
                    "expected a section header such as $Nodes, found '{}'",
                    show(tok)
                )));
            }
            self.section = name;
            match self.section.as_str() {
                "$MeshFormat" => return Err(self.err_tok("a second $MeshFormat section")),
                "$PhysicalNames" => self.physical_names()?,
                "$Entities" if self.version == Version::V41 => self.entities41()?,
                "$Nodes" => {
                    if self.have_nodes {
                        return Err(self.err_tok("a second $Nodes section"));
                    }
                    self.have_nodes = true;
                    match self.version {
                        Version::V41 => self.nodes41()?,
                        Version::V22 => self.nodes22()?,
                    }
                }
                "$Elements" => {
                    if self.have_elements {
                        return Err(self.err_tok("a second $Elements section"));
                    }
                    self.have_elements = true;
                    match self.version {
                        Version::V41 => self.elements41()?,
                        Version::V22 => self.elements22()?,
                    }
                }
                "$PartitionedEntities" => {
                    return Err(self.err_tok(
                        "partitioned meshes are not supported (save the mesh unpartitioned)",
                    ))
                }
                _ => self.skip_section()?,
            }
        }
        self.finish()
    }

    fn mesh_format(&mut self) -> Result<(), MeshError> {
        let vtok = self.token("the version number")?;
        let v = std::str::from_utf8(vtok)
            .ok()
            .and_then(|s| s.parse::<f64>().ok());
        self.version = if v == Some(4.1) {
            Version::V41
        } else if v == Some(2.2) {
            Version::V22
        } else {
            return Err(self.err_tok(format!(
                "unsupported MSH version '{}': supported versions are 4.1 (ASCII or binary) \
                     and 2.2 (ASCII); re-save the mesh with `gmsh -format msh41`",
                show(vtok)
            )));
        };
        let file_type = self.a_u64("the file-type (0 ASCII, 1 binary)")?;
        let data_size = self.a_u64("the data-size")?;
        match file_type {
            0 => {}
            1 => {
                if self.version == Version::V22 {
                    return Err(self.err_tok(
                        "binary MSH 2.2 is not supported: supported versions are 4.1 \
                         (ASCII or binary) and 2.2 (ASCII)",
                    ));
                }
                if data_size != 8 {
                    return Err(self.err_tok(format!(
                        "binary data-size is {data_size}, only 8 (64-bit size_t) is supported"
                    )));
                }
                self.binary = true;
                self.end_header_line()?;
                let at = self.pos;
                let c = self.take(Some(4), "the endianness marker")?;
                let m = copy4(c);
                if i32::from_le_bytes(m) == 1 {
                    self.big_endian = false;
                } else if i32::from_be_bytes(m) == 1 {
                    self.big_endian = true;
                } else {
                    return Err(self.err_at(
                        at,
                        format!(
                            "bad endianness marker: expected the integer 1, found bytes \
                             {:02x} {:02x} {:02x} {:02x}",
                            m[0], m[1], m[2], m[3]
                        ),
                    ));
                }
            }
            _ => {
                return Err(self.err_tok(format!(
                    "file-type must be 0 (ASCII) or 1 (binary), found {file_type}"
                )))
            }
        }
        self.expect_end()
    }

    /// Skip an unknown section by scanning to its `$End...` marker line.
    fn skip_section(&mut self) -> Result<(), MeshError> {
        let end = format!("\n$End{}", self.section.get(1..).unwrap_or_default());
        let marker = end.as_bytes();
        let rest = self.b.get(self.pos..).unwrap_or_default();
        let mut found = None;
        let mut i = 0;
        while let Some(off) = rest
            .get(i..)
            .and_then(|r| r.iter().position(|&c| c == b'\n'))
        {
            let at = i + off;
            let tail = rest.get(at..).unwrap_or_default();
            if tail.starts_with(marker) {
                let after = tail.get(marker.len()).copied();
                if after.is_none_or(|c| c.is_ascii_whitespace()) {
                    found = Some(at);
                    break;
                }
            }
            i = at + 1;
        }
        match found {
            Some(at) => {
                if !self.binary {
                    let skipped = rest.get(..at).unwrap_or_default();
                    self.line += skipped.iter().filter(|&&c| c == b'\n').count();
                }
                self.pos += at;
                self.expect_end()
            }
            None => Err(self.err_pos(format!(
                "no {} before the end of the file (truncated file?)",
                &end[1..]
            ))),
        }
    }

    fn physical_names(&mut self) -> Result<(), MeshError> {
        let n = self.a_u64("the number of physical names")?;
        for _ in 0..n {
            let dim = self.a_i32("the dimension of a physical name")?;
            let tag = self.a_i32("the tag of a physical name")?;
            if !(0..=3).contains(&dim) {
                return Err(self.err_tok(format!("physical name dimension {dim} is not 0..3")));
            }
            self.skip_ws();
            self.tok_start = self.pos;
            if self.b.get(self.pos) != Some(&b'"') {
                return match self.b.get(self.pos) {
                    None => Err(self.err_eof("a physical name")),
                    Some(_) => Err(self.err_pos("expected a quoted physical name")),
                };
            }
            let start = self.pos + 1;
            let rest = self.b.get(start..).unwrap_or_default();
            let Some(len) = rest.iter().position(|&c| c == b'"' || c == b'\n') else {
                return Err(self.err_eof("a physical name"));
            };
            if rest.get(len) != Some(&b'"') {
                return Err(self.err_pos("unterminated quoted physical name"));
            }
            let name = String::from_utf8_lossy(rest.get(..len).unwrap_or_default()).into_owned();
            self.pos = start + len + 1;
            if dim <= 2 {
                self.names.insert((dim as Dim, tag), name);
            }
        }
        self.expect_end()
    }

    fn entities41(&mut self) -> Result<(), MeshError> {
        if self.entities.is_some() {
            return Err(self.err_tok("a second $Entities section"));
        }
        if self.binary {
            self.end_header_line()?;
        }
        let mut counts = [0u64; 4];
        for (d, c) in counts.iter_mut().enumerate() {
            *c = self.size(&format!("the number of entities of dimension {d}"))?;
        }
        let total = counts.iter().fold(0u64, |a, &c| a.saturating_add(c));
        let mut map = HashMap::with_capacity(cap(total, self.remaining(), 16));
        for (d, &count) in counts.iter().enumerate() {
            let what = ["point", "curve", "surface", "volume"][d];
            for _ in 0..count {
                let tag = self.int(&format!("a {what} tag"))?;
                let ncoord = if d == 0 { 3 } else { 6 };
                for _ in 0..ncoord {
                    self.double(&format!("the bounding box of {what} {tag}"))?;
                }
                let nphys = self.size(&format!("the number of physical tags of {what} {tag}"))?;
                let mut phys = Vec::with_capacity(cap(nphys, self.remaining(), 1));
                for _ in 0..nphys {
                    let p = self.int(&format!("a physical tag of {what} {tag}"))?;
                    let p = p
                        .checked_abs()
                        .ok_or_else(|| self.err_at(self.here(), format!("bad physical tag {p}")))?;
                    if p != 0 && !phys.contains(&p) {
                        phys.push(p);
                    }
                }
                if d > 0 {
                    let nb =
                        self.size(&format!("the number of bounding entities of {what} {tag}"))?;
                    for _ in 0..nb {
                        self.int(&format!("a bounding entity of {what} {tag}"))?;
                    }
                }
                if d <= 2 {
                    map.insert((d as Dim, tag), phys);
                }
            }
        }
        self.entities = Some(map);
        self.expect_end()
    }

    fn check_finite(&self, tag: u64, x: f64, y: f64, z: f64) -> Result<(), MeshError> {
        let ok = |v: f64| v.abs() <= MAX_COORDINATE;
        if ok(x) && ok(y) && ok(z) {
            Ok(())
        } else if x.is_finite() && y.is_finite() && z.is_finite() {
            Err(self.err_at(
                self.here(),
                format!(
                    "node {tag} has a coordinate beyond ±{MAX_COORDINATE:e} ({x:e}, {y:e}, {z:e}): areas and stiffnesses would overflow; change the length unit"
                ),
            ))
        } else {
            Err(self.err_at(
                self.here(),
                format!("node {tag} has a non-finite coordinate ({x}, {y}, {z})"),
            ))
        }
    }

    /// Refuses a header count that the whole file could never hold
    /// (`min_bytes` per item). (A file merely cut short is reported where it
    /// ends; reservations are bounded by the remaining bytes in any case.)
    fn check_count(&self, count: u64, min_bytes: u64, what: &str) -> Result<(), MeshError> {
        let room = self.b.len() as u64 / min_bytes;
        if count > room {
            return Err(self.err_pos(format!(
                "the header declares {count} {what} but the whole file has only {} bytes",
                self.b.len()
            )));
        }
        Ok(())
    }

    fn nodes41(&mut self) -> Result<(), MeshError> {
        if self.binary {
            self.end_header_line()?;
        }
        let nblocks = self.size("the number of node blocks")?;
        let nnodes = self.size("the number of nodes")?;
        self.size("the minimum node tag")?;
        self.size("the maximum node tag")?;
        // A node takes at least 8 bytes (ASCII: tag and three coordinates).
        self.check_count(nnodes, 8, "nodes")?;
        let c = cap(nnodes, self.remaining(), 8);
        self.node_tags.reserve(c);
        self.node_xy.reserve(c);
        let mut total: u64 = 0;
        for _ in 0..nblocks {
            let dim = self.int("the entity dimension of a node block")?;
            let etag = self.int("the entity tag of a node block")?;
            let param = self.int("the parametric flag of a node block")?;
            let n = self.size("the number of nodes in a block")?;
            if !(0..=3).contains(&dim) {
                return Err(self.err_at(
                    self.here(),
                    format!("node block of entity {etag} has dimension {dim}, not 0..3"),
                ));
            }
            let nparam = match param {
                0 => 0usize,
                1 => dim as usize,
                _ => {
                    return Err(self.err_at(
                        self.here(),
                        format!(
                            "node block of entity {etag}: parametric flag {param} is not 0 or 1"
                        ),
                    ))
                }
            };
            total = total.saturating_add(n);
            let first = self.node_tags.len();
            let per = 3 + nparam;
            if self.binary {
                let nu = usize::try_from(n).ok();
                let tb = self.take(nu.and_then(|n| n.checked_mul(8)), "the node tags")?;
                let tags: Vec<u64> = tb.chunks_exact(8).map(|c| self.u64_of(c)).collect();
                let cb = self.take(
                    nu.and_then(|n| n.checked_mul(per * 8)),
                    "the node coordinates",
                )?;
                let start = self.pos - cb.len();
                for (k, (chunk, &tag)) in cb.chunks_exact(per * 8).zip(&tags).enumerate() {
                    let x = self.f64_of(chunk.get(0..8).unwrap_or_default());
                    let y = self.f64_of(chunk.get(8..16).unwrap_or_default());
                    let z = self.f64_of(chunk.get(16..24).unwrap_or_default());
                    let ok = |v: f64| v.abs() <= MAX_COORDINATE;
                    if !(ok(x) && ok(y) && ok(z)) {
                        self.tok_start = start + k * per * 8;
                        self.check_finite(tag, x, y, z)?;
                    }
                    self.node_xy.push([x, y]);
                }
                self.node_tags.extend_from_slice(&tags);
            } else {
                for _ in 0..n {
                    let t = self.a_u64("a node tag")?;
                    self.node_tags.push(t);
                }
                for (k, _) in (first..).zip(0..n) {
                    let tag = self.node_tags.get(k).copied().unwrap_or_default();
                    let x = self.a_f64("a node x coordinate")?;
                    let y = self.a_f64("a node y coordinate")?;
                    let z = self.a_f64("a node z coordinate")?;
                    for _ in 0..nparam {
                        self.a_f64("a node parametric coordinate")?;
                    }
                    self.check_finite(tag, x, y, z)?;
                    self.node_xy.push([x, y]);
                }
            }
        }
        if total != nnodes {
            return Err(self.err_pos(format!(
                "the header says {nnodes} nodes but the blocks contain {total}"
            )));
        }
        self.expect_end()
    }

    fn nodes22(&mut self) -> Result<(), MeshError> {
        let n = self.a_u64("the number of nodes")?;
        self.check_count(n, 8, "nodes")?;
        let c = cap(n, self.remaining(), 8);
        self.node_tags.reserve(c);
        self.node_xy.reserve(c);
        for _ in 0..n {
            let tag = self.a_u64("a node tag")?;
            let x = self.a_f64("a node x coordinate")?;
            let y = self.a_f64("a node y coordinate")?;
            let z = self.a_f64("a node z coordinate")?;
            self.check_finite(tag, x, y, z)?;
            self.node_tags.push(tag);
            self.node_xy.push([x, y]);
        }
        self.expect_end()
    }

    fn elements41(&mut self) -> Result<(), MeshError> {
        if self.binary {
            self.end_header_line()?;
        }
        let nblocks = self.size("the number of element blocks")?;
        let nelems = self.size("the number of elements")?;
        self.size("the minimum element tag")?;
        self.size("the maximum element tag")?;
        // An element takes at least 4 bytes (ASCII: a tag and a node).
        self.check_count(nelems, 4, "elements")?;
        let mut total: u64 = 0;
        for _ in 0..nblocks {
            let dim = self.int("the entity dimension of an element block")?;
            let etag = self.int("the entity tag of an element block")?;
            let etype = self.int("the element type of an element block")?;
            let n = self.size("the number of elements in a block")?;
            let block_at = self.here();
            total = total.saturating_add(n);
            if n == 0 {
                continue;
            }
            let Some(kind) = Kind::from_type(i64::from(etype)) else {
                let first = self.size("an element tag")?;
                return Err(self.err_at(self.here(), unsupported_type_msg(etype.into(), first)));
            };
            if dim != i32::from(kind.dim()) {
                return Err(self.err_at(
                    block_at,
                    format!(
                        "element block of entity {etag} has dimension {dim} but holds \
                         elements of type {etype} ({}), of dimension {}",
                        element_type_name(etype.into()),
                        kind.dim()
                    ),
                ));
            }
            let npe = kind.nodes();
            let start = self.elems.count(kind);
            let per = 1 + npe;
            self.elems.reserve(
                kind,
                cap(
                    n,
                    self.remaining(),
                    if self.binary { per * 8 } else { 2 * per },
                ),
            );
            let mut nodes = [0u64; 3];
            if self.binary {
                let nb = usize::try_from(n).ok().and_then(|n| n.checked_mul(per * 8));
                let data = self.take(nb, "the element data")?;
                for chunk in data.chunks_exact(per * 8) {
                    let mut it = chunk.chunks_exact(8).map(|c| self.u64_of(c));
                    let tag = it.next().unwrap_or_default();
                    for (slot, v) in nodes.iter_mut().zip(it) {
                        *slot = v;
                    }
                    self.elems.push(kind, tag, &nodes);
                }
            } else {
                for _ in 0..n {
                    let tag = self.a_u64("an element tag")?;
                    for slot in nodes.iter_mut().take(npe) {
                        *slot = self.a_u64("a node tag of an element")?;
                    }
                    self.elems.push(kind, tag, &nodes);
                }
            }
            let len = self.elems.count(kind) - start;
            self.blocks.push(Block {
                kind,
                entity: etag,
                start,
                len,
            });
        }
        if total != nelems {
            return Err(self.err_pos(format!(
                "the header says {nelems} elements but the blocks contain {total}"
            )));
        }
        self.expect_end()
    }

    fn elements22(&mut self) -> Result<(), MeshError> {
        let n = self.a_u64("the number of elements")?;
        self.check_count(n, 4, "elements")?;
        // The previous element: gmsh writes an element once per physical group
        // of its entity, consecutively; such copies are merged here.
        let mut prev: Option<(Kind, i32, [u64; 3], usize)> = None;
        for _ in 0..n {
            let tag = self.a_u64("an element tag")?;
            let etype = self.a_i32("an element type")?;
            let Some(kind) = Kind::from_type(i64::from(etype)) else {
                return Err(self.err_tok(unsupported_type_msg(etype.into(), tag)));
            };
            let ntags = self.a_u64("the number of tags of an element")?;
            let mut phys = 0i32;
            let mut elementary = 0i32;
            for k in 0..ntags {
                let t = self.a_i32("an element tag value")?;
                match k {
                    0 => phys = t,
                    1 => elementary = t,
                    _ => {}
                }
            }
            let mut nodes = [0u64; 3];
            for slot in nodes.iter_mut().take(kind.nodes()) {
                *slot = self.a_u64("a node tag of an element")?;
            }
            let idx = match prev {
                Some((k, e, nd, idx))
                    if k == kind && e == elementary && nd == nodes && ntags >= 2 =>
                {
                    idx
                }
                _ => {
                    let idx = self.elems.count(kind);
                    self.elems.push(kind, tag, &nodes);
                    idx
                }
            };
            prev = Some((kind, elementary, nodes, idx));
            let p = phys.checked_abs().unwrap_or(0);
            if p != 0 {
                let g = self.groups.entry((kind.dim(), p)).or_default();
                if g.last() != Some(&idx) {
                    g.push(idx);
                }
            }
        }
        self.expect_end()
    }

    // ----- assembly -----

    fn finish(mut self) -> Result<Mesh, MeshError> {
        if !self.have_nodes {
            return Err(self.invalid("no $Nodes section"));
        }
        if !self.have_elements {
            return Err(self.invalid("no $Elements section"));
        }

        // Physical groups of 4.1 element blocks, through their entities.
        if self.version == Version::V41 {
            let blocks = std::mem::take(&mut self.blocks);
            if let Some(ents) = &self.entities {
                for (&(d, _), phys) in ents {
                    for &p in phys {
                        self.groups.entry((d, p)).or_default();
                    }
                }
                for b in &blocks {
                    let d = b.kind.dim();
                    let Some(phys) = ents.get(&(d, b.entity)) else {
                        return Err(self.invalid(format!(
                            "$Elements: an element block refers to entity {} of dimension {d}, \
                             which is not in $Entities",
                            b.entity
                        )));
                    };
                    for &p in phys {
                        self.groups
                            .entry((d, p))
                            .or_default()
                            .extend(b.start..b.start + b.len);
                    }
                }
            }
            for g in self.groups.values_mut() {
                g.sort_unstable();
                g.dedup();
            }
        }
        for &k in self.names.keys() {
            self.groups.entry(k).or_default();
        }

        // Dense node numbering in increasing tag order.
        let n = self.node_tags.len();
        let sorted = self.node_tags.windows(2).all(|w| w[0] < w[1]);
        let (tags, xy) = if sorted {
            (
                std::mem::take(&mut self.node_tags),
                std::mem::take(&mut self.node_xy),
            )
        } else {
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_unstable_by_key(|&i| self.node_tags.get(i).copied().unwrap_or_default());
            let tags: Vec<u64> = order
                .iter()
                .map(|&i| self.node_tags.get(i).copied().unwrap_or_default())
                .collect();
            if let Some(w) = tags.windows(2).find(|w| w[0] == w[1]) {
                return Err(self.invalid(format!("$Nodes: duplicate node tag {}", w[0])));
            }
            let xy: Vec<[f64; 2]> = order
                .iter()
                .map(|&i| self.node_xy.get(i).copied().unwrap_or_default())
                .collect();
            (tags, xy)
        };
        let map = NodeMap::new(&tags);
        let lookup = |etag: u64, ntag: u64| -> Result<usize, MeshError> {
            map.get(ntag).ok_or_else(|| {
                self.invalid(format!(
                    "$Elements: element {etag} refers to node {ntag}, which is not in $Nodes"
                ))
            })
        };

        let e = &self.elems;
        let mut points = Vec::with_capacity(e.points.len());
        for (&t, &nd) in e.point_tags.iter().zip(&e.points) {
            points.push(lookup(t, nd)?);
        }
        let mut lines = Vec::with_capacity(e.lines.len());
        for (&t, nd) in e.line_tags.iter().zip(&e.lines) {
            lines.push([lookup(t, nd[0])?, lookup(t, nd[1])?]);
        }
        let mut triangles = Vec::with_capacity(e.tris.len());
        for (&t, nd) in e.tri_tags.iter().zip(&e.tris) {
            triangles.push([lookup(t, nd[0])?, lookup(t, nd[1])?, lookup(t, nd[2])?]);
        }
        if triangles.is_empty() {
            return Err(self.invalid(
                "$Elements: no triangles: the mesh has no 3-node triangle elements (type 2) \
                 (only elements in physical groups are saved by gmsh unless Mesh.SaveAll=1)",
            ));
        }

        let names = std::mem::take(&mut self.names);
        let groups = std::mem::take(&mut self.groups)
            .into_iter()
            .map(|((dim, tag), elements)| PhysicalGroup {
                dim,
                tag,
                name: names
                    .get(&(dim, tag))
                    .cloned()
                    .unwrap_or_else(|| tag.to_string()),
                elements,
            })
            .collect();

        Ok(Mesh {
            path: self.path.to_path_buf(),
            nodes: xy,
            node_tags: tags,
            points,
            lines,
            triangle_tags: std::mem::take(&mut self.elems.tri_tags),
            triangles,
            groups,
        })
    }
}

/// Node tag -> dense index.
enum NodeMap {
    Dense { min: u64, idx: Vec<usize> },
    Sparse(HashMap<u64, usize>),
}

impl NodeMap {
    /// `tags` sorted, without duplicates.
    fn new(tags: &[u64]) -> NodeMap {
        let (Some(&min), Some(&max)) = (tags.first(), tags.last()) else {
            return NodeMap::Sparse(HashMap::new());
        };
        let range = max - min;
        if range <= 2 * tags.len() as u64 + 1024 {
            let mut idx = vec![usize::MAX; range as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                if let Some(slot) = idx.get_mut((t - min) as usize) {
                    *slot = i;
                }
            }
            NodeMap::Dense { min, idx }
        } else {
            NodeMap::Sparse(tags.iter().enumerate().map(|(i, &t)| (t, i)).collect())
        }
    }

    fn get(&self, tag: u64) -> Option<usize> {
        match self {
            NodeMap::Dense { min, idx } => {
                let k = usize::try_from(tag.checked_sub(*min)?).ok()?;
                idx.get(k).copied().filter(|&i| i != usize::MAX)
            }
            NodeMap::Sparse(m) => m.get(&tag).copied(),
        }
    }
}
