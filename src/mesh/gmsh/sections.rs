//! The sections of a `.msh` file, MSH 4.1 and 2.2: format, names,
//! entities, nodes and elements; unknown sections are skipped.

use super::lexer::*;
use super::{
    element_type_name, unsupported_in_group, unsupported_type_msg, Block, Kind, Parser, Version,
    MAX_COORDINATE,
};
use crate::mesh::{Dim, Mesh, MeshError};
use std::collections::HashMap;

impl<'a> Parser<'a> {
    // ----- top level -----

    pub(super) fn run(mut self) -> Result<Mesh, MeshError> {
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

    pub(super) fn mesh_format(&mut self) -> Result<(), MeshError> {
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
    pub(super) fn skip_section(&mut self) -> Result<(), MeshError> {
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

    pub(super) fn physical_names(&mut self) -> Result<(), MeshError> {
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
            self.names.insert((dim as Dim, tag), name);
        }
        self.expect_end()
    }

    pub(super) fn entities41(&mut self) -> Result<(), MeshError> {
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
                map.insert((d as Dim, tag), phys);
            }
        }
        self.entities = Some(map);
        self.expect_end()
    }

    pub(super) fn check_finite(&self, tag: u64, x: f64, y: f64, z: f64) -> Result<(), MeshError> {
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
    pub(super) fn check_count(
        &self,
        count: u64,
        min_bytes: u64,
        what: &str,
    ) -> Result<(), MeshError> {
        let room = self.b.len() as u64 / min_bytes;
        if count > room {
            return Err(self.err_pos(format!(
                "the header declares {count} {what} but the whole file has only {} bytes",
                self.b.len()
            )));
        }
        Ok(())
    }

    pub(super) fn nodes41(&mut self) -> Result<(), MeshError> {
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
        self.node_z.reserve(c);
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
                    self.node_z.push(z);
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
                    self.node_z.push(z);
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

    pub(super) fn nodes22(&mut self) -> Result<(), MeshError> {
        let n = self.a_u64("the number of nodes")?;
        self.check_count(n, 8, "nodes")?;
        let c = cap(n, self.remaining(), 8);
        self.node_tags.reserve(c);
        self.node_xy.reserve(c);
        self.node_z.reserve(c);
        for _ in 0..n {
            let tag = self.a_u64("a node tag")?;
            let x = self.a_f64("a node x coordinate")?;
            let y = self.a_f64("a node y coordinate")?;
            let z = self.a_f64("a node z coordinate")?;
            self.check_finite(tag, x, y, z)?;
            self.node_tags.push(tag);
            self.node_xy.push([x, y]);
            self.node_z.push(z);
        }
        self.expect_end()
    }

    pub(super) fn elements41(&mut self) -> Result<(), MeshError> {
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
                let group = self.entity_groups(dim, etag);
                return Err(self.err_at(
                    self.here(),
                    unsupported_in_group(etype.into(), first, group.as_deref()),
                ));
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
            let mut nodes = [0u64; 4];
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

    pub(super) fn elements22(&mut self) -> Result<(), MeshError> {
        let n = self.a_u64("the number of elements")?;
        self.check_count(n, 4, "elements")?;
        // The previous element: gmsh writes an element once per physical group
        // of its entity, consecutively; such copies are merged here.
        let mut prev: Option<(Kind, i32, [u64; 4], usize)> = None;
        for _ in 0..n {
            let tag = self.a_u64("an element tag")?;
            let etype = self.a_i32("an element type")?;
            let Some(kind) = Kind::from_type(i64::from(etype)) else {
                if etype != 11 {
                    return Err(self.err_tok(unsupported_type_msg(etype.into(), tag)));
                }
                // A 10-node tetrahedron: name its Physical Volume (the tag
                // that follows).
                let ntags = self.a_u64("the number of tags of an element")?;
                let phys = if ntags > 0 {
                    self.a_i32("an element tag value")?
                } else {
                    0
                };
                let group = self.group_label(3, phys);
                return Err(self.err_tok(unsupported_in_group(11, tag, Some(&group))));
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
            let mut nodes = [0u64; 4];
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

    /// 'NAME' of the physical group (dim, tag), or its tag.
    fn group_label(&self, dim: i32, tag: i32) -> String {
        let d = crate::mesh::Dim::try_from(dim).unwrap_or(0);
        match self.names.get(&(d, tag.abs())) {
            Some(n) => format!("'{n}'"),
            None => format!("{}", tag.abs()),
        }
    }

    /// The physical groups of entity (dim, tag) of a 4.1 file, as
    /// [`Parser::group_label`]s, when it has any.
    fn entity_groups(&self, dim: i32, tag: i32) -> Option<String> {
        let d = crate::mesh::Dim::try_from(dim).ok()?;
        let phys = self.entities.as_ref()?.get(&(d, tag))?;
        (!phys.is_empty()).then(|| {
            phys.iter()
                .map(|&p| self.group_label(dim, p))
                .collect::<Vec<_>>()
                .join(", ")
        })
    }
}
