//! Vector kernels of the cycle and of CG, parallel on long vectors, whose
//! results do not depend on the number of threads: every entry is computed
//! alone and every reduction sums fixed chunks in a fixed order.

use crate::linalg::sparse::{axpy, Csr};
use rayon::prelude::*;

/// Fewer rows than this run serially: rayon's overhead beats the gain.
pub(super) const PAR_MIN: usize = 20_000;
/// Rows (or vector entries) per parallel task; also the fixed chunk of the
/// reductions, whose bits must not depend on the number of threads.
pub(super) const CHUNK: usize = 4096;

/// y_i = f(i, y_i) for every i, in parallel on large vectors. Each entry is
/// computed alone, so the result does not depend on the thread count.
pub(super) fn for_rows(y: &mut [f64], f: impl Fn(usize, &mut f64) + Sync) {
    let run = |c: usize, ys: &mut [f64]| {
        for (k, yi) in ys.iter_mut().enumerate() {
            f(c * CHUNK + k, yi);
        }
    };
    if y.len() >= PAR_MIN {
        y.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, ys)| run(c, ys));
    } else {
        y.chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, ys)| run(c, ys));
    }
}

/// Σ_c f(c, range of chunk c) over fixed chunks of `n`, the partial sums
/// added in chunk order: the same bits on any number of threads.
pub(super) fn chunk_sum(n: usize, f: impl Fn(usize, std::ops::Range<usize>) -> f64 + Sync) -> f64 {
    let nch = n.div_ceil(CHUNK);
    let part = |c: usize| f(c, c * CHUNK..((c + 1) * CHUNK).min(n));
    if n >= PAR_MIN {
        let parts: Vec<f64> = (0..nch).into_par_iter().map(part).collect();
        parts.iter().sum()
    } else {
        (0..nch).map(part).sum()
    }
}

/// Σ a_i b_i with four interleaved partial sums (no serial add chain).
#[inline]
pub(super) fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    for (k, (x, y)) in ra.iter().zip(rb).enumerate() {
        s[k] += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// x += α p, r −= α q in one pass, returning the chunked (r, r).
pub(super) fn cg_step(alpha: f64, p: &[f64], q: &[f64], x: &mut [f64], r: &mut [f64]) -> f64 {
    let step = |c: usize, xs: &mut [f64], rs: &mut [f64]| {
        let o = c * CHUNK;
        axpy(alpha, &p[o..o + xs.len()], xs);
        axpy(-alpha, &q[o..o + rs.len()], rs);
        dot4(rs, rs)
    };
    let parts: Vec<f64> = if r.len() >= PAR_MIN {
        x.par_chunks_mut(CHUNK)
            .zip(r.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (xs, rs))| step(c, xs, rs))
            .collect()
    } else {
        x.chunks_mut(CHUNK)
            .zip(r.chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (xs, rs))| step(c, xs, rs))
            .collect()
    };
    parts.iter().sum()
}

/// (a, b) over fixed chunks: thread-count independent.
pub(super) fn pdot(a: &[f64], b: &[f64]) -> f64 {
    chunk_sum(a.len(), |_, r| dot4(&a[r.clone()], &b[r]))
}

/// y = K x row-parallel (each row summed as in [`Csr::mul_vec`]) and the
/// chunked (x, y) of the same pass.
pub(super) fn mul_dot(k: &Csr, x: &[f64], y: &mut [f64]) -> f64 {
    let n = y.len();
    if n < PAR_MIN {
        k.mul_vec(x, y);
        return pdot(x, y);
    }
    let parts: Vec<f64> = y
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(c, ys)| {
            let r = c * CHUNK..c * CHUNK + ys.len();
            for (yi, i) in ys.iter_mut().zip(r.clone()) {
                *yi = k.row_dot(i, x);
            }
            dot4(&x[r], ys)
        })
        .collect();
    parts.iter().sum()
}
