//! Matrix Market files (NIST format, <https://math.nist.gov/MatrixMarket/formats.html>)
//! for `signorini export --qp`: the QP min ½xᵀCx − xᵀd, Ax ≤ g as plain files
//! that scipy.io.mmread, Julia and MATLAB read.
//!
//! C is written `coordinate real symmetric` (lower triangle only), A as
//! `coordinate real general`, vectors as `array real general` (n × 1).
//! Values use Rust's shortest round-trip formatting, so reading back is exact.

use super::atomic::{write_atomic_with, IoError};
use crate::qp::Csr;
use std::path::Path;

/// Writes sparse `m`; with `symmetric` only entries with col ≤ row are kept.
pub fn write_sparse(path: &Path, m: &Csr, symmetric: bool, comment: &str) -> Result<(), IoError> {
    write_atomic_with(path, |w| {
        let kind = if symmetric { "symmetric" } else { "general" };
        writeln!(w, "%%MatrixMarket matrix coordinate real {kind}")?;
        for line in comment.lines() {
            writeln!(w, "% {line}")?;
        }
        let keep = |i: usize, j: usize| !symmetric || j <= i;
        let mut nnz = 0usize;
        for i in 0..m.nrows {
            let (cols, _) = m.row(i);
            nnz += cols.iter().filter(|&&j| keep(i, j)).count();
        }
        writeln!(w, "{} {} {}", m.nrows, m.ncols, nnz)?;
        for i in 0..m.nrows {
            let (cols, vals) = m.row(i);
            for (&j, &v) in cols.iter().zip(vals) {
                if keep(i, j) {
                    writeln!(w, "{} {} {:e}", i + 1, j + 1, v)?;
                }
            }
        }
        Ok(())
    })
}

/// Writes `v` as an n × 1 dense array.
pub fn write_vector(path: &Path, v: &[f64], comment: &str) -> Result<(), IoError> {
    write_atomic_with(path, |w| {
        writeln!(w, "%%MatrixMarket matrix array real general")?;
        for line in comment.lines() {
            writeln!(w, "% {line}")?;
        }
        writeln!(w, "{} 1", v.len())?;
        for x in v {
            writeln!(w, "{x:e}")?;
        }
        Ok(())
    })
}

/// Reads a file written by [`write_sparse`] back as CSR (symmetric files are
/// expanded to both triangles). For tests and round trips, not a general reader.
pub fn read_sparse(path: &Path) -> Result<Csr, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, "cannot read", e))?;
    let mut lines = text.lines().enumerate();
    let bad = |line: usize, msg: &str| IoError::format(path, format!("line {}: {msg}", line + 1));
    let (_, header) = lines.next().ok_or_else(|| bad(0, "empty file"))?;
    let symmetric = header.contains("symmetric");
    if !header.starts_with("%%MatrixMarket matrix coordinate real") {
        return Err(bad(0, "expected %%MatrixMarket matrix coordinate real"));
    }
    let mut size: Option<(usize, usize)> = None;
    let mut trip = vec![];
    for (ln, line) in lines {
        if line.starts_with('%') || line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        match size {
            None => {
                let p = |s: &str| s.parse::<usize>().map_err(|_| bad(ln, "bad size line"));
                if f.len() != 3 {
                    return Err(bad(ln, "bad size line"));
                }
                size = Some((p(f[0])?, p(f[1])?));
            }
            Some((nr, nc)) => {
                if f.len() != 3 {
                    return Err(bad(ln, "expected: row col value"));
                }
                let i: usize = f[0].parse().map_err(|_| bad(ln, "bad row"))?;
                let j: usize = f[1].parse().map_err(|_| bad(ln, "bad column"))?;
                let v: f64 = f[2].parse().map_err(|_| bad(ln, "bad value"))?;
                if i == 0 || j == 0 || i > nr || j > nc {
                    return Err(bad(ln, "index out of range"));
                }
                trip.push((i - 1, j - 1, v));
                if symmetric && i != j {
                    trip.push((j - 1, i - 1, v));
                }
            }
        }
    }
    let (nr, nc) = size.ok_or_else(|| bad(0, "no size line"))?;
    Ok(Csr::from_triplets(nr, nc, &trip))
}

/// Reads an n × 1 array written by [`write_vector`].
pub fn read_vector(path: &Path) -> Result<Vec<f64>, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, "cannot read", e))?;
    let bad = |line: usize, msg: &str| IoError::format(path, format!("line {}: {msg}", line + 1));
    let mut it = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('%') && !l.trim().is_empty());
    let (ln, size) = it.next().ok_or_else(|| bad(0, "no size line"))?;
    let n: usize = size
        .split_whitespace()
        .next()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| bad(ln, "bad size line"))?;
    let v: Vec<f64> = it
        .map(|(ln, l)| l.trim().parse::<f64>().map_err(|_| bad(ln, "bad value")))
        .collect::<Result<_, _>>()?;
    if v.len() != n {
        return Err(bad(ln, &format!("{} values for size {n}", v.len())));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact() -> Result<(), Box<dyn std::error::Error>> {
        let c = Csr::from_triplets(
            3,
            3,
            &[
                (0, 0, 4.0),
                (0, 1, -1.0 / 3.0),
                (1, 0, -1.0 / 3.0),
                (1, 1, 2.5e11),
                (2, 2, 1e-300),
            ],
        );
        let a = Csr::from_triplets(2, 3, &[(0, 2, 0.1), (1, 0, -7.0)]);
        let d = vec![1.0 / 7.0, -0.0, 3e200];
        let dir = tempfile::tempdir()?;
        let p = |n: &str| dir.path().join(n);
        write_sparse(&p("C.mtx"), &c, true, "C")?;
        write_sparse(&p("A.mtx"), &a, false, "A")?;
        write_vector(&p("d.mtx"), &d, "d")?;
        let c2 = read_sparse(&p("C.mtx"))?;
        let a2 = read_sparse(&p("A.mtx"))?;
        assert_eq!(c2, c);
        assert_eq!(a2, a);
        assert_eq!(read_vector(&p("d.mtx"))?, d);
        // The symmetric file holds the lower triangle only: 4 entries, not 5.
        let text = std::fs::read_to_string(p("C.mtx"))?;
        assert!(text.lines().any(|l| l == "3 3 4"), "{text}");
        Ok(())
    }
}
