//! Incomplete Cholesky without fill, IC(0), and the modified variant MIC(0)
//! (the report's ILLᵀD: dropped fill added to the diagonal), methods.md §4.2,
//! in the Gaussian-elimination form given there: W = L̃ D̃ L̃ᵀ on the pattern of C.
//!
//! Elasticity matrices are not M-matrices, so a pivot can turn non-positive
//! (the report names no remedy). We then restart on C + α·diag(C) with
//! α = 10⁻³, 10⁻², … (Manteuffel's shifted IC) and log the shift used.

use super::Preconditioner;
use crate::qp::{sparse::Csr, QpError};

pub struct Ic0 {
    /// Column r of L̃ below the diagonal: rows and values (CSC of the strict lower part).
    colptr: Vec<usize>,
    rows: Vec<usize>,
    vals: Vec<f64>,
    /// Pivots D̃.
    piv: Vec<f64>,
    modified: bool,
    pub shift: f64,
}

impl Ic0 {
    pub fn new(c: &Csr, modified: bool) -> Result<Ic0, QpError> {
        let n = c.nrows;
        // Strict lower part by columns = strict upper part of rows (C symmetric).
        let mut colptr = vec![0usize; n + 1];
        let mut rows = Vec::new();
        let mut base = Vec::new();
        let mut diag = vec![0.0; n];
        for j in 0..n {
            let (cols, v) = c.row(j);
            for (&i, &a) in cols.iter().zip(v) {
                if i > j {
                    rows.push(i);
                    base.push(a);
                } else if i == j {
                    diag[j] = a;
                }
            }
            colptr[j + 1] = rows.len();
        }
        if let Some(i) = diag.iter().position(|v| !(*v > 0.0)) {
            return Err(QpError::Unsupported(format!(
                "IC(0): diagonal entry {i} of C is not positive"
            )));
        }
        let mut shift = 0.0;
        loop {
            let mut vals = base.clone();
            let mut piv: Vec<f64> = diag.iter().map(|d| d * (1.0 + shift)).collect();
            if factor(n, &colptr, &rows, &mut vals, &mut piv, modified) {
                if shift > 0.0 {
                    log::info!(
                        "{}: shifted by {shift:e}·diag(C) to avoid a non-positive pivot",
                        if modified { "MIC(0)" } else { "IC(0)" }
                    );
                }
                return Ok(Ic0 {
                    colptr,
                    rows,
                    vals,
                    piv,
                    modified,
                    shift,
                });
            }
            shift = if shift == 0.0 { 1e-3 } else { shift * 10.0 };
            if shift > 10.0 {
                return Err(QpError::Factor(
                    "incomplete Cholesky broke down even with a diagonal shift".into(),
                ));
            }
        }
    }
}

/// Right-looking elimination restricted to the pattern. On return `vals`
/// holds l_ir and `piv` the pivots; false on a non-positive pivot.
fn factor(
    n: usize,
    colptr: &[usize],
    rows: &[usize],
    vals: &mut [f64],
    piv: &mut [f64],
    modified: bool,
) -> bool {
    for r in 0..n {
        let d = piv[r];
        if !(d > 0.0) || !d.is_finite() {
            return false;
        }
        let (s, e) = (colptr[r], colptr[r + 1]);
        // c_ir → l_ir (keep c_ir for the updates)
        for k in s..e {
            let c_ir = vals[k];
            let l_ir = c_ir / d;
            // update c_ij for j in column r, r < j ≤ i
            for kk in s..e {
                let j = rows[kk];
                let i = rows[k];
                if j > i {
                    continue;
                }
                let upd = l_ir * vals[kk]; // l_ir * c_jr
                if j == i {
                    piv[i] -= upd;
                } else {
                    // (i, j) with i > j lives in column j
                    let col = &rows[colptr[j]..colptr[j + 1]];
                    match col.binary_search(&i) {
                        Ok(p) => vals[colptr[j] + p] -= upd,
                        Err(_) => {
                            if modified {
                                // dropped fill on both triangles → both diagonals
                                piv[i] -= upd;
                                piv[j] -= upd;
                            }
                        }
                    }
                }
            }
        }
        for v in &mut vals[s..e] {
            *v /= d;
        }
    }
    true
}

impl Preconditioner for Ic0 {
    fn name(&self) -> &'static str {
        if self.modified {
            "mic0"
        } else {
            "ic0"
        }
    }
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let n = r.len();
        z.copy_from_slice(r);
        for c in 0..n {
            let y = z[c];
            if y != 0.0 {
                for k in self.colptr[c]..self.colptr[c + 1] {
                    z[self.rows[k]] -= self.vals[k] * y;
                }
            }
        }
        for (zi, p) in z.iter_mut().zip(&self.piv) {
            *zi /= p;
        }
        for c in (0..n).rev() {
            let mut s = z[c];
            for k in self.colptr[c]..self.colptr[c + 1] {
                s -= self.vals[k] * z[self.rows[k]];
            }
            z[c] = s;
        }
    }
}
