//! Tokens and values of a `.msh` file: the ASCII tokenizer, binary
//! decoding, and the messages that locate a problem by line or byte offset.

use super::{Parser, RawElements, Version};
use crate::mesh::MeshError;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Bounded capacity: never reserve more items than the remaining bytes could hold.
pub(super) fn cap(count: u64, remaining: usize, min_bytes_per_item: usize) -> usize {
    let by_bytes = remaining / min_bytes_per_item.max(1);
    usize::try_from(count).unwrap_or(usize::MAX).min(by_bytes)
}

pub(super) fn show(tok: &[u8]) -> String {
    let mut s: String = String::from_utf8_lossy(tok).chars().take(40).collect();
    if tok.len() > 40 {
        s.push_str("...");
    }
    s
}

pub(super) fn parse_u64(tok: &[u8]) -> Option<u64> {
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

pub(super) fn parse_i64(tok: &[u8]) -> Option<i64> {
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

pub(super) fn copy8(c: &[u8]) -> [u8; 8] {
    let mut a = [0u8; 8];
    for (d, s) in a.iter_mut().zip(c) {
        *d = *s;
    }
    a
}

pub(super) fn copy4(c: &[u8]) -> [u8; 4] {
    let mut a = [0u8; 4];
    for (d, s) in a.iter_mut().zip(c) {
        *d = *s;
    }
    a
}

impl<'a> Parser<'a> {
    pub(super) fn new(path: &'a Path, b: &'a [u8]) -> Self {
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
            node_z: Vec::new(),
            have_nodes: false,
            have_elements: false,
            elems: RawElements::default(),
            blocks: Vec::new(),
            groups: BTreeMap::new(),
        }
    }

    // ----- errors -----

    pub(super) fn err_at(&self, at: usize, msg: impl Into<String>) -> MeshError {
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
    pub(super) fn err_tok(&self, msg: impl Into<String>) -> MeshError {
        let at = if self.binary {
            self.tok_start
        } else {
            self.line
        };
        self.err_at(at, msg)
    }

    /// Error located at the current position.
    pub(super) fn err_pos(&self, msg: impl Into<String>) -> MeshError {
        let at = if self.binary { self.pos } else { self.line };
        self.err_at(at, msg)
    }

    pub(super) fn err_eof(&self, what: &str) -> MeshError {
        let msg = format!("unexpected end of file while reading {what} (truncated file?)");
        if self.binary {
            self.err_at(self.b.len(), msg)
        } else {
            let last_nl = usize::from(self.b.last() == Some(&b'\n'));
            self.err_at(self.line.saturating_sub(last_nl).max(1), msg)
        }
    }

    pub(super) fn invalid(&self, msg: impl Into<String>) -> MeshError {
        MeshError::Invalid {
            path: self.path.to_path_buf(),
            msg: msg.into(),
        }
    }

    pub(super) fn remaining(&self) -> usize {
        self.b.len().saturating_sub(self.pos)
    }

    // ----- ASCII tokens -----

    pub(super) fn skip_ws(&mut self) {
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

    pub(super) fn token(&mut self, what: &str) -> Result<&'a [u8], MeshError> {
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

    pub(super) fn bad_token(&self, what: &str, kind: &str, tok: &[u8]) -> MeshError {
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

    pub(super) fn a_u64(&mut self, what: &str) -> Result<u64, MeshError> {
        let tok = self.token(what)?;
        parse_u64(tok).ok_or_else(|| self.bad_token(what, "a non-negative integer", tok))
    }

    pub(super) fn a_i32(&mut self, what: &str) -> Result<i32, MeshError> {
        let tok = self.token(what)?;
        parse_i64(tok)
            .and_then(|v| i32::try_from(v).ok())
            .ok_or_else(|| self.bad_token(what, "a 32-bit integer", tok))
    }

    pub(super) fn a_f64(&mut self, what: &str) -> Result<f64, MeshError> {
        let tok = self.token(what)?;
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| self.bad_token(what, "a number", tok))
    }

    /// After a section header read as a token, step past the end of its line
    /// (binary data starts right after the newline).
    pub(super) fn end_header_line(&mut self) -> Result<(), MeshError> {
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

    pub(super) fn expect_end(&mut self) -> Result<(), MeshError> {
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

    pub(super) fn take(&mut self, n: Option<usize>, what: &str) -> Result<&'a [u8], MeshError> {
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

    pub(super) fn u64_of(&self, c: &[u8]) -> u64 {
        if self.big_endian {
            u64::from_be_bytes(copy8(c))
        } else {
            u64::from_le_bytes(copy8(c))
        }
    }

    pub(super) fn f64_of(&self, c: &[u8]) -> f64 {
        if self.big_endian {
            f64::from_be_bytes(copy8(c))
        } else {
            f64::from_le_bytes(copy8(c))
        }
    }

    pub(super) fn i32_of(&self, c: &[u8]) -> i32 {
        if self.big_endian {
            i32::from_be_bytes(copy4(c))
        } else {
            i32::from_le_bytes(copy4(c))
        }
    }

    pub(super) fn b_u64(&mut self, what: &str) -> Result<u64, MeshError> {
        let c = self.take(Some(8), what)?;
        Ok(self.u64_of(c))
    }

    pub(super) fn b_i32(&mut self, what: &str) -> Result<i32, MeshError> {
        let c = self.take(Some(4), what)?;
        Ok(self.i32_of(c))
    }

    pub(super) fn b_f64(&mut self, what: &str) -> Result<f64, MeshError> {
        let c = self.take(Some(8), what)?;
        Ok(self.f64_of(c))
    }

    // ----- either encoding -----

    pub(super) fn size(&mut self, what: &str) -> Result<u64, MeshError> {
        if self.binary {
            self.b_u64(what)
        } else {
            self.a_u64(what)
        }
    }

    pub(super) fn int(&mut self, what: &str) -> Result<i32, MeshError> {
        if self.binary {
            self.b_i32(what)
        } else {
            self.a_i32(what)
        }
    }

    pub(super) fn double(&mut self, what: &str) -> Result<f64, MeshError> {
        if self.binary {
            self.b_f64(what)
        } else {
            self.a_f64(what)
        }
    }

    /// Location to report for the thing just read.
    pub(super) fn here(&self) -> usize {
        if self.binary {
            self.tok_start
        } else {
            self.line
        }
    }
}
