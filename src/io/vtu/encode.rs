//! Encoding a piece as the XML vtkio 0.7 writes: the streamed writer of
//! uncompressed files (each array base64-encoded straight into the file),
//! vtkio for compressed ones, and the component names and zero counts
//! vtkio leaves out (see the parent module's doc).

use std::io::{BufWriter, Write};
use std::path::Path;

use vtkio::model::{
    Attribute, ByteOrder, DataSet, ElementType, IOBuffer, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};
use vtkio::xml::Compressor;

use super::super::atomic::{write_atomic, IoError};
use super::ZLIB_LEVEL;

/// Component names of the multi-component arrays, as ParaView shows them
/// (those of a model's fields are its kind's,
/// [`ElementKind::component_names`](crate::fem::ElementKind::component_names)).
pub(super) type Names = crate::fem::element::ComponentNames;

/// The names of the arrays whose names do not depend on the kind (the
/// mesh, the contact points' normals and tangents): a plane model's.
pub(super) const COMPONENT_NAMES: Names = crate::fem::element::PLANE_COMPONENT_NAMES;

/// vtkio 0.7's `DataArray` has no component names, so they are added to
/// the XML it writes: `ComponentName0="sxx"`, … on each `<DataArray>` whose
/// `Name` is listed in [`COMPONENT_NAMES`] (as many as it has components).
pub(super) fn add_component_names(buf: Vec<u8>, names_of: Names) -> Vec<u8> {
    let Ok(text) = String::from_utf8(buf) else {
        unreachable!("vtkio writes UTF-8 XML")
    };
    let mut out = String::with_capacity(text.len() + 512);
    let mut rest = text.as_str();
    while let Some(at) = rest.find("<DataArray") {
        let (head, tail) = rest.split_at(at);
        out.push_str(head);
        let end = tail.find('>').unwrap_or(tail.len());
        let tag = &tail[..end];
        let attr = |key: &str| -> Option<&str> {
            let k = format!(" {key}=\"");
            let s = tag.find(&k)? + k.len();
            let e = tag[s..].find('"')?;
            Some(&tag[s..s + e])
        };
        let mut extra = String::new();
        if let Some(name) = attr("Name") {
            let ncomp: usize = attr("NumberOfComponents")
                .and_then(|v| v.parse().ok())
                .unwrap_or(1);
            if let Some((_, names)) = names_of.iter().find(|(n, _)| *n == name) {
                if ncomp > 1 {
                    for (k, c) in names.iter().take(ncomp).enumerate() {
                        extra.push_str(&format!(" ComponentName{k}=\"{c}\""));
                    }
                }
            }
        }
        let self_closing = tag.ends_with('/');
        let (t, close) = if self_closing {
            (&tag[..tag.len() - 1], "/")
        } else {
            (tag, "")
        };
        out.push_str(t);
        out.push_str(&extra);
        out.push_str(close);
        rest = &tail[end..];
    }
    out.push_str(rest);
    out.into_bytes()
}

/// Encodes `piece` as an XML UnstructuredGrid and writes it atomically:
/// streamed when uncompressed, through vtkio when compressed.
pub(super) fn write_piece(
    path: &Path,
    piece: UnstructuredGridPiece,
    compress: bool,
    names: Names,
) -> Result<(), IoError> {
    if !compress {
        return write_atomic(path, |tmp| {
            let file = super::super::atomic::create_new(tmp)
                .map_err(|e| IoError::io(path, "cannot create", e))?;
            let mut w = BufWriter::with_capacity(1 << 20, file);
            stream_piece(&mut w, &piece, names)
                .and_then(|()| w.flush())
                .map_err(|e| IoError::io(path, "cannot write", e))
        });
    }
    let buf = vtkio_bytes(piece, true, names).map_err(|message| IoError::Vtk {
        path: path.to_path_buf(),
        message,
    })?;
    write_atomic(path, |tmp| {
        let file = super::super::atomic::create_new(tmp)
            .map_err(|e| IoError::io(path, "cannot create", e))?;
        let mut w = BufWriter::new(file);
        w.write_all(&buf)
            .and_then(|()| w.flush())
            .map_err(|e| IoError::io(path, "cannot write", e))?;
        Ok(())
    })
}

/// The file vtkio writes for `piece` (zlib level [`ZLIB_LEVEL`] with
/// `compress`), with the zero counts and component names it leaves out.
pub(super) fn vtkio_bytes(
    piece: UnstructuredGridPiece,
    compress: bool,
    names: Names,
) -> Result<Vec<u8>, String> {
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        byte_order: ByteOrder::LittleEndian,
        title: String::new(),
        file_path: None,
        data: DataSet::inline(piece),
    };
    let (compressor, level) = if compress {
        (Compressor::ZLib, ZLIB_LEVEL)
    } else {
        (Compressor::None, 0)
    };
    let xml = vtk
        .try_into_xml_format(compressor, level)
        .map_err(|e| e.to_string())?;
    let mut buf = Vec::new();
    xml.write(&mut buf).map_err(|e| e.to_string())?;
    Ok(add_component_names(add_zero_counts(buf), names))
}

/// Writes `piece` as an XML UnstructuredGrid with its arrays appended raw
/// ([`stream_appended`]): the arrays, counts and component names of the
/// file vtkio 0.7 writes for it (after [`add_zero_counts`] and
/// [`add_component_names`]), without base64.
pub(super) fn stream_piece(
    w: &mut impl Write,
    piece: &UnstructuredGridPiece,
    names: Names,
) -> std::io::Result<()> {
    let point = data_arrs(&piece.data.point, names)?;
    let cell = data_arrs(&piece.data.cell, names)?;
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = &piece.cells.cell_verts
    else {
        return Err(std::io::Error::other("cells must be in XML form"));
    };
    let types: Vec<u8> = piece.cells.types.iter().map(|&t| t as u8).collect();
    let geometry = [
        Arr::new("Points", 3, Slice::of(&piece.points)?, names, false),
        Arr::new("connectivity", 1, Slice::U64(connectivity), names, false),
        Arr::new("offsets", 1, Slice::U64(offsets), names, false),
        Arr::new("types", 1, Slice::U8(&types), names, false),
    ];
    fn refs<'b>(v: &'b [Arr<'_>]) -> Vec<ArrRef<'b>> {
        v.iter().map(Arr::by_ref).collect()
    }
    stream_appended(
        w,
        piece.points.len() / 3,
        piece.cells.types.len(),
        &refs(&point),
        &refs(&cell),
        &refs(&geometry),
    )
}

/// The data arrays of `attrs` (vtkio writes no field data here) as [`Arr`]s.
pub(super) fn data_arrs<'a>(attrs: &'a [Attribute], names: Names) -> std::io::Result<Vec<Arr<'a>>> {
    let mut out = vec![];
    for a in attrs {
        if let Attribute::DataArray(d) = a {
            out.push(Arr::new(
                &d.name,
                d.elem.num_comp(),
                Slice::of(&d.data)?,
                names,
                d.elem == ElementType::Vectors,
            ));
        }
    }
    Ok(out)
}

/// One array of a file with appended raw data: the start of its
/// `<DataArray>` tag (every attribute but `offset`), and its block in the
/// appended data (the UInt64 byte count, then the little-endian values),
/// encoded as it is written ([`OwnedArr`]: encoded before).
pub(super) struct Arr<'a> {
    head: Vec<u8>,
    vectors: Option<String>,
    data: Slice<'a>,
}

/// An [`Arr`] encoded once (the mesh arrays of a series of load steps).
pub(super) struct OwnedArr {
    head: Vec<u8>,
    block: Vec<u8>,
}

/// A borrowed [`Arr`] or [`OwnedArr`].
pub(super) struct ArrRef<'a> {
    head: &'a [u8],
    vectors: Option<&'a str>,
    data: BlockRef<'a>,
}

#[derive(Clone, Copy)]
enum BlockRef<'a> {
    Values(&'a Slice<'a>),
    Bytes(&'a [u8]),
}

impl<'a> Arr<'a> {
    /// The array `name` of `ncomp` components: its tag's attributes as
    /// vtkio writes them (range over all components, Display of f64) and
    /// the component names of `names_of`; `vectors` marks the array a
    /// `<PointData Vectors=…>` names.
    pub(super) fn new(
        name: &str,
        ncomp: u32,
        buf: Slice<'a>,
        names_of: Names,
        vectors: bool,
    ) -> Arr<'a> {
        Arr {
            head: array_head(name, ncomp, &buf, names_of),
            vectors: vectors.then(|| name.to_string()),
            data: buf,
        }
    }

    pub(super) fn by_ref(&self) -> ArrRef<'_> {
        ArrRef {
            head: &self.head,
            vectors: self.vectors.as_deref(),
            data: BlockRef::Values(&self.data),
        }
    }

    /// Encoded once, for files written again and again.
    pub(super) fn to_owned_arr(&self) -> OwnedArr {
        let mut block = vec![];
        // Writing into memory cannot fail.
        let _ = write_block(&mut block, self.by_ref().data);
        OwnedArr {
            head: self.head.clone(),
            block,
        }
    }
}

impl OwnedArr {
    pub(super) fn by_ref(&self) -> ArrRef<'_> {
        ArrRef {
            head: &self.head,
            vectors: None,
            data: BlockRef::Bytes(&self.block),
        }
    }
}

impl BlockRef<'_> {
    /// The bytes of the block (count included).
    fn len(&self) -> u64 {
        match self {
            BlockRef::Values(v) => 8 + v.nbytes() as u64,
            BlockRef::Bytes(b) => b.len() as u64,
        }
    }
}

/// The attributes of a `<DataArray>` tag but `offset` (see [`Arr::new`]).
fn array_head(name: &str, ncomp: u32, buf: &Slice<'_>, names_of: Names) -> Vec<u8> {
    fn range<T: Copy + PartialOrd + Into<f64>>(v: &[T]) -> Option<(f64, f64)> {
        let mut it = v.iter().map(|&x| x.into());
        let first = it.next()?;
        Some(it.fold((first, first), |(a, b), x: f64| (a.min(x), b.max(x))))
    }
    let (ty, range) = match buf {
        Slice::F64(v) => ("Float64", range(v)),
        Slice::Xy0(v) => {
            // The same fold, in the same order, as over the padded copy.
            let mut it = v.iter().flat_map(|p| [p[0], p[1], 0.0]);
            let r = it
                .next()
                .map(|first| it.fold((first, first), |(a, b), x| (a.min(x), b.max(x))));
            ("Float64", r)
        }
        Slice::I32(v) => ("Int32", range(v)),
        Slice::U64(v) => (
            "UInt64",
            v.iter()
                .min()
                .zip(v.iter().max())
                .map(|(&a, &b)| (a as f64, b as f64)),
        ),
        Slice::U8(v) => ("UInt8", range(v)),
    };
    let mut h = format!("<DataArray type=\"{ty}\" Name=\"{name}\"");
    if ncomp != 1 {
        h.push_str(&format!(" NumberOfComponents=\"{ncomp}\""));
    }
    h.push_str(" format=\"appended\"");
    if let Some((lo, hi)) = range {
        h.push_str(&format!(" RangeMin=\"{lo}\" RangeMax=\"{hi}\""));
    }
    if let Some((_, names)) = names_of.iter().find(|(n, _)| *n == name) {
        if ncomp > 1 {
            for (k, c) in names.iter().take(ncomp as usize).enumerate() {
                h.push_str(&format!(" ComponentName{k}=\"{c}\""));
            }
        }
    }
    h.into_bytes()
}

/// The block of an array in the appended data: its UInt64 byte count, then
/// its values little-endian.
fn write_block(w: &mut impl Write, data: BlockRef<'_>) -> std::io::Result<()> {
    let v = match data {
        BlockRef::Bytes(b) => return w.write_all(b),
        BlockRef::Values(v) => v,
    };
    w.write_all(&(v.nbytes() as u64).to_le_bytes())?;
    #[cfg(target_endian = "little")]
    if let Slice::F64(v) = v {
        // SAFETY: an f64 slice is v.len() * 8 initialised bytes, aligned
        // for u8; on a little-endian machine they are the bytes to write.
        let bytes = unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), v.len() * 8) };
        return w.write_all(bytes);
    }
    let mut chunk: Vec<u8> = Vec::with_capacity(1 << 16);
    macro_rules! put {
        ($v:expr) => {
            for part in $v.chunks(1 << 13) {
                chunk.clear();
                for x in part {
                    chunk.extend_from_slice(&x.to_le_bytes());
                }
                w.write_all(&chunk)?;
            }
        };
    }
    match v {
        Slice::F64(v) => put!(v),
        Slice::Xy0(v) => {
            for part in v.chunks(1 << 12) {
                chunk.clear();
                for p in part {
                    for x in [p[0], p[1], 0.0] {
                        chunk.extend_from_slice(&x.to_le_bytes());
                    }
                }
                w.write_all(&chunk)?;
            }
        }
        Slice::I32(v) => put!(v),
        Slice::U64(v) => put!(v),
        Slice::U8(v) => w.write_all(v)?,
    }
    Ok(())
}

/// A one-piece UnstructuredGrid whose arrays (`point` data, `cell` data,
/// then `geometry`: the points, connectivity, offsets and types) are
/// appended raw (`<AppendedData encoding="raw">`, UInt64 headers), in the
/// order they are listed: no base64 (a third fewer bytes, no encoding
/// pass). VTK, ParaView, pyvista and meshio read it; so does
/// [`read_vtu_arrays`](super::read_vtu_arrays).
pub(super) fn stream_appended(
    w: &mut impl Write,
    np: usize,
    nc: usize,
    point: &[ArrRef<'_>],
    cell: &[ArrRef<'_>],
    geometry: &[ArrRef<'_>],
) -> std::io::Result<()> {
    stream_head(w, np, nc)?;
    let mut offset = 0u64;
    let mut tag = |w: &mut dyn Write, a: &ArrRef<'_>| -> std::io::Result<()> {
        w.write_all(a.head)?;
        write!(w, " offset=\"{offset}\"/>")?;
        offset += a.data.len();
        Ok(())
    };
    for (name, arrs) in [("PointData", point), ("CellData", cell)] {
        if arrs.is_empty() {
            continue;
        }
        write!(w, "<{name}")?;
        if let Some(v) = arrs.iter().find_map(|a| a.vectors) {
            write!(w, " Vectors=\"{v}\"")?;
        }
        w.write_all(b">")?;
        for a in arrs {
            tag(w, a)?;
        }
        write!(w, "</{name}>")?;
    }
    let [points, rest @ ..] = geometry else {
        return Err(std::io::Error::other("no points array"));
    };
    w.write_all(b"<Points>")?;
    tag(w, points)?;
    w.write_all(b"</Points><Cells>")?;
    for a in rest {
        tag(w, a)?;
    }
    w.write_all(b"</Cells></Piece></UnstructuredGrid><AppendedData encoding=\"raw\">_")?;
    for a in point.iter().chain(cell).chain(geometry) {
        write_block(w, a.data)?;
    }
    w.write_all(APPENDED_TAIL)
}

/// The end of a file with appended data. The newline ends the raw data as
/// VTK writes it (meshio's reader cuts the data at its last newline).
pub(super) const APPENDED_TAIL: &[u8] = b"\n</AppendedData></VTKFile>";

/// A file of [`stream_appended`] turned back into the inline base64 form
/// vtkio reads (`format="binary"`, each array's count and values as one
/// base64 stream); other files unchanged.
pub(super) fn appended_to_inline(bytes: Vec<u8>) -> Result<Vec<u8>, String> {
    use base64::Engine;
    const OPEN: &[u8] = b"<AppendedData encoding=\"raw\">";
    let Some(at) = bytes.windows(OPEN.len()).position(|w| w == OPEN) else {
        return Ok(bytes);
    };
    let data_start = bytes[at + OPEN.len()..]
        .iter()
        .position(|&b| b == b'_')
        .map(|p| at + OPEN.len() + p + 1)
        .ok_or("AppendedData without its '_' mark")?;
    let data = &bytes[data_start..];
    let head = std::str::from_utf8(&bytes[..at])
        .map_err(|_| "the XML before AppendedData is not UTF-8")?;
    let mut out = String::with_capacity(head.len() + 4 * data.len() / 3 + 64);
    let mut rest = head;
    while let Some(p) = rest.find("<DataArray") {
        out.push_str(&rest[..p]);
        let tail = &rest[p..];
        let end = tail.find("/>").ok_or("unterminated <DataArray>")?;
        let tag = &tail[..end];
        let off_at = tag.find(" offset=\"").ok_or("<DataArray> without offset")?;
        let off_str = &tag[off_at + 9..];
        let off_end = off_str.find('"').ok_or("bad offset")?;
        let off: usize = off_str[..off_end].parse().map_err(|_| "bad offset")?;
        let count = data
            .get(off..off + 8)
            .ok_or("offset beyond the appended data")?;
        let n = u64::from_le_bytes(count.try_into().map_err(|_| "bad count")?) as usize;
        let block = data
            .get(off..off + 8 + n)
            .ok_or("array beyond the appended data")?;
        let attrs = tag[..off_at].replace(" format=\"appended\"", " format=\"binary\"");
        out.push_str(&attrs);
        out.push_str(&tag[off_at + 9 + off_end + 1..]);
        out.push('>');
        out.push_str(&base64::engine::general_purpose::STANDARD.encode(block));
        out.push_str("</DataArray>");
        rest = &tail[end + 2..];
    }
    out.push_str(rest);
    out.push_str("</VTKFile>");
    Ok(out.into_bytes())
}

/// The file's start up to the `<Piece>` tag with its counts.
pub(super) fn stream_head(w: &mut impl Write, np: usize, nc: usize) -> std::io::Result<()> {
    w.write_all(
        b"<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"><UnstructuredGrid><Piece",
    )?;
    // vtkio leaves out zero counts; add_zero_counts puts them first.
    for (key, v) in [("NumberOfPoints", np), ("NumberOfCells", nc)] {
        if v == 0 {
            write!(w, " {key}=\"0\"")?;
        }
    }
    for (key, v) in [("NumberOfPoints", np), ("NumberOfCells", nc)] {
        if v != 0 {
            write!(w, " {key}=\"{v}\"")?;
        }
    }
    w.write_all(b">")
}

/// The values of an array, borrowed.
pub(super) enum Slice<'a> {
    F64(&'a [f64]),
    /// Plane vectors written as 3-component Float64 with z = 0, straight
    /// from the step's arrays (no padded copy while a step is written).
    Xy0(&'a [[f64; 2]]),
    I32(&'a [i32]),
    U64(&'a [u64]),
    U8(&'a [u8]),
}

impl Slice<'_> {
    /// The size of the values in bytes.
    pub(super) fn nbytes(&self) -> usize {
        match self {
            Slice::F64(v) => v.len() * 8,
            Slice::Xy0(v) => v.len() * 24,
            Slice::I32(v) => v.len() * 4,
            Slice::U64(v) => v.len() * 8,
            Slice::U8(v) => v.len(),
        }
    }

    pub(super) fn of(buf: &IOBuffer) -> std::io::Result<Slice<'_>> {
        Ok(match buf {
            IOBuffer::F64(v) => Slice::F64(v),
            IOBuffer::I32(v) => Slice::I32(v),
            IOBuffer::U64(v) => Slice::U64(v),
            IOBuffer::U8(v) => Slice::U8(v),
            _ => return Err(std::io::Error::other("unsupported VTU array type")),
        })
    }
}

/// vtkio omits `NumberOfPoints` / `NumberOfCells` from `<Piece>` when they
/// are zero, but VTK's reader requires both ("Piece 0 is missing its
/// NumberOfPoints attribute"). Insert the missing ones as `"0"`.
pub(super) fn add_zero_counts(mut buf: Vec<u8>) -> Vec<u8> {
    fn find(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
        hay.get(from..)?
            .windows(needle.len())
            .position(|w| w == needle)
            .map(|p| p + from)
    }
    let Some(start) = find(&buf, b"<Piece", 0) else {
        return buf;
    };
    let Some(end) = find(&buf, b">", start) else {
        return buf;
    };
    let tag = &buf[start..end];
    let mut extra = Vec::new();
    for key in ["NumberOfPoints", "NumberOfCells"] {
        if find(tag, format!(" {key}=").as_bytes(), 0).is_none() {
            extra.extend_from_slice(format!(" {key}=\"0\"").as_bytes());
        }
    }
    let at = start + b"<Piece".len();
    buf.splice(at..at, extra);
    buf
}
