//! Encoding a piece as the XML vtkio 0.7 writes: the streamed writer of
//! uncompressed files (each array base64-encoded straight into the file),
//! vtkio for compressed ones, and the component names and zero counts
//! vtkio leaves out (see the parent module's doc).

use std::io::{BufWriter, Write};
use std::path::Path;

use vtkio::model::{
    Attribute, ByteOrder, Cells, DataArray, DataSet, ElementType, IOBuffer, UnstructuredGridPiece,
    Version, VertexNumbers, Vtk,
};
use vtkio::xml::Compressor;

use super::super::atomic::{write_atomic, IoError};
use super::ZLIB_LEVEL;

/// Component names of the multi-component arrays, as ParaView shows them.
pub(super) type Names = &'static [(&'static str, &'static [&'static str])];

pub(super) const COMPONENT_NAMES: Names = &[
    ("displacement", &["ux", "uy", "uz"]),
    ("displacement_change", &["dux", "duy", "duz"]),
    ("reaction", &["Rx", "Ry", "Rz"]),
    ("stress", &["sxx", "syy", "sxy", "szz"]),
    ("stress_change", &["dsxx", "dsyy", "dsxy", "dszz"]),
    ("principal_stress", &["s1", "s2"]),
    ("normal", &["nx", "ny", "nz"]),
    ("tangent", &["tx", "ty", "tz"]),
];

/// The same in an axisymmetric model (x = r, y = z): (σrr, σzz, σrz, σθθ),
/// the 4th the hoop stress (docs/problem-format.md §6).
pub(super) const AXI_COMPONENT_NAMES: Names = &[
    ("displacement", &["ur", "uz", "u3"]),
    ("displacement_change", &["dur", "duz", "du3"]),
    ("reaction", &["Rr", "Rz", "R3"]),
    ("stress", &["srr", "szz", "srz", "stt"]),
    ("stress_change", &["dsrr", "dszz", "dsrz", "dstt"]),
    ("principal_stress", &["s1", "s2"]),
    ("normal", &["nx", "ny", "nz"]),
    ("tangent", &["tx", "ty", "tz"]),
];

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

/// Writes `piece` as the XML UnstructuredGrid file vtkio 0.7 writes for it
/// uncompressed (after [`add_zero_counts`] and [`add_component_names`]),
/// base64-encoding each array straight into `w`.
pub(super) fn stream_piece(
    w: &mut impl Write,
    piece: &UnstructuredGridPiece,
    names: Names,
) -> std::io::Result<()> {
    stream_head(w, piece.points.len() / 3, piece.cells.types.len())?;
    let point = data_parts(&piece.data.point);
    let cell = data_parts(&piece.data.cell);
    stream_data(w, &point, &cell, names)?;
    stream_geometry(w, &piece.points, &piece.cells, names)?;
    w.write_all(PIECE_TAIL)
}

/// The end of a one-piece file.
pub(super) const PIECE_TAIL: &[u8] = b"</Piece></UnstructuredGrid></VTKFile>";

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

/// One array of a `<PointData>` or `<CellData>`: its values, or its
/// `<DataArray>` element already encoded ([`VtuMeshParts`]).
pub(super) enum Part<'a> {
    Data(&'a DataArray),
    Encoded(&'a [u8]),
}

/// The data arrays of `attrs` (vtkio writes no field data here).
pub(super) fn data_parts(attrs: &[Attribute]) -> Vec<Part<'_>> {
    attrs
        .iter()
        .filter_map(|a| match a {
            Attribute::DataArray(d) => Some(Part::Data(d)),
            Attribute::Field { .. } => None,
        })
        .collect()
}

/// The data array `a` as a part (None: field data).
pub(super) fn part_of(a: &Attribute) -> Option<Part<'_>> {
    data_parts(std::slice::from_ref(a)).pop()
}

/// `<PointData>` and `<CellData>`, each left out when empty (as vtkio does).
pub(super) fn stream_data(
    w: &mut impl Write,
    point: &[Part],
    cell: &[Part],
    names: Names,
) -> std::io::Result<()> {
    for (tag, parts) in [("PointData", point), ("CellData", cell)] {
        if parts.is_empty() {
            continue;
        }
        write!(w, "<{tag}")?;
        let vectors = parts.iter().find_map(|p| match p {
            Part::Data(d) if d.elem == ElementType::Vectors => Some(d),
            _ => None,
        });
        if let Some(v) = vectors {
            write!(w, " Vectors=\"{}\"", v.name)?;
        }
        w.write_all(b">")?;
        for p in parts {
            match p {
                Part::Data(d) => {
                    stream_array(w, &d.name, d.elem.num_comp(), Slice::of(&d.data)?, names)?
                }
                Part::Encoded(bytes) => w.write_all(bytes)?,
            }
        }
        write!(w, "</{tag}>")?;
    }
    Ok(())
}

/// `<Points>` and `<Cells>`.
pub(super) fn stream_geometry(
    w: &mut impl Write,
    points: &IOBuffer,
    cells: &Cells,
    names: Names,
) -> std::io::Result<()> {
    w.write_all(b"<Points>")?;
    stream_array(w, "Points", 3, Slice::of(points)?, names)?;
    w.write_all(b"</Points><Cells>")?;
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = &cells.cell_verts
    else {
        return Err(std::io::Error::other("cells must be in XML form"));
    };
    stream_array(w, "connectivity", 1, Slice::U64(connectivity), names)?;
    stream_array(w, "offsets", 1, Slice::U64(offsets), names)?;
    let types: Vec<u8> = cells.types.iter().map(|&t| t as u8).collect();
    stream_array(w, "types", 1, Slice::U8(&types), names)?;
    w.write_all(b"</Cells>")
}

/// The values of an array, borrowed.
pub(super) enum Slice<'a> {
    F64(&'a [f64]),
    I32(&'a [i32]),
    U64(&'a [u64]),
    U8(&'a [u8]),
}

impl Slice<'_> {
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

/// One `<DataArray format="binary">`: attributes as vtkio writes them
/// (range over all components, Display of f64), then the UInt64 byte count
/// and the little-endian values, base64-encoded as one stream.
pub(super) fn stream_array(
    w: &mut impl Write,
    name: &str,
    ncomp: u32,
    buf: Slice<'_>,
    names_of: Names,
) -> std::io::Result<()> {
    use base64::engine::general_purpose::STANDARD;
    use base64::write::EncoderWriter;
    fn range<T: Copy + PartialOrd + Into<f64>>(v: &[T]) -> Option<(f64, f64)> {
        let mut it = v.iter().map(|&x| x.into());
        let first = it.next()?;
        Some(it.fold((first, first), |(a, b), x: f64| (a.min(x), b.max(x))))
    }
    let (ty, range, nbytes) = match buf {
        Slice::F64(v) => ("Float64", range(v), v.len() * 8),
        Slice::I32(v) => ("Int32", range(v), v.len() * 4),
        Slice::U64(v) => (
            "UInt64",
            v.iter()
                .min()
                .zip(v.iter().max())
                .map(|(&a, &b)| (a as f64, b as f64)),
            v.len() * 8,
        ),
        Slice::U8(v) => ("UInt8", range(v), v.len()),
    };
    write!(w, "<DataArray type=\"{ty}\" Name=\"{name}\"")?;
    if ncomp != 1 {
        write!(w, " NumberOfComponents=\"{ncomp}\"")?;
    }
    w.write_all(b" format=\"binary\"")?;
    if let Some((lo, hi)) = range {
        write!(w, " RangeMin=\"{lo}\" RangeMax=\"{hi}\"")?;
    }
    if let Some((_, names)) = names_of.iter().find(|(n, _)| *n == name) {
        if ncomp > 1 {
            for (k, c) in names.iter().take(ncomp as usize).enumerate() {
                write!(w, " ComponentName{k}=\"{c}\"")?;
            }
        }
    }
    w.write_all(b">")?;
    {
        let mut enc = EncoderWriter::new(&mut *w, &STANDARD);
        enc.write_all(&(nbytes as u64).to_le_bytes())?;
        let mut chunk: Vec<u8> = Vec::with_capacity(1 << 16);
        macro_rules! put {
            ($v:expr) => {
                for part in $v.chunks(1 << 13) {
                    chunk.clear();
                    for x in part {
                        chunk.extend_from_slice(&x.to_le_bytes());
                    }
                    enc.write_all(&chunk)?;
                }
            };
        }
        match buf {
            Slice::F64(v) => put!(v),
            Slice::I32(v) => put!(v),
            Slice::U64(v) => put!(v),
            Slice::U8(v) => enc.write_all(v)?,
        }
        enc.finish()?;
    }
    w.write_all(b"</DataArray>")
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
