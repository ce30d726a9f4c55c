//! Smoothed-aggregation algebraic multigrid (SA-AMG) as a preconditioner for
//! an SPD stiffness, and the preconditioned CG ([`pcg`]) that uses it.
//!
//! The method is that of P. Vaněk, J. Mandel and M. Brezina, "Algebraic
//! multigrid by smoothed aggregation for second and fourth order elliptic
//! problems", Computing 56 (1996) 179–196:
//!
//! 1. strength of connection on the block (mesh point) graph: blocks I ≠ J
//!    are strong neighbours when ‖K_IJ‖_F ≥ θ·sqrt(‖K_II‖_F ‖K_JJ‖_F);
//! 2. aggregation in Vaněk's three passes (seed aggregates of whole
//!    neighbourhoods, attach the rest to the strongest neighbouring seed,
//!    group what is left), always in index order so the hierarchy is
//!    deterministic;
//! 3. the tentative prolongator T: per aggregate, a thin QR of the rows of
//!    the near-null matrix B (rigid motions for elasticity), Q the columns
//!    of T and R the coarse near-null rows, so T reproduces B exactly;
//! 4. the smoothed prolongator P = (I − ω D⁻¹K) T, ω = (4/3)/λ_max(D⁻¹K),
//!    which turns the piecewise-rigid T into an energy-stable interpolation;
//! 5. the Galerkin coarse operator K_c = Pᵀ K P (kept SPD, nothing dropped).
//!
//! The cycle is a V-cycle with symmetric Gauss–Seidel (forward sweeps before
//! the coarse correction, backward after) and an exact dense Cholesky on the
//! coarsest level, so it is a symmetric positive definite operator, as CG
//! requires.

use crate::linalg::dense::PIVOT_REL;
use crate::linalg::sparse::{axpy, dot, norm, Csr};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{Mat, Par};
use rayon::prelude::*;
use std::sync::Mutex;

/// Unknowns grouped in blocks (the unknowns of one mesh point, contiguous:
/// block b is `block_ptr[b]..block_ptr[b+1]`) and near-null vectors (each of
/// length n; for 2D elasticity the 3 rigid motions).
pub struct NearNull<'a> {
    pub block_ptr: &'a [usize],
    pub modes: &'a [Vec<f64>],
}

/// Parameters of the hierarchy.
#[derive(Debug, Clone)]
pub struct AmgSettings {
    /// Strength threshold θ of the block graph.
    pub theta: f64,
    /// A level with at most this many unknowns is solved by dense Cholesky.
    pub coarse_max: usize,
    /// Most levels, the coarsest included.
    pub max_levels: usize,
    /// Gauss–Seidel sweeps before (forward) and after (backward) the coarse
    /// correction.
    pub smooth_sweeps: usize,
}

impl Default for AmgSettings {
    fn default() -> Self {
        AmgSettings {
            theta: 0.08,
            coarse_max: 2000,
            max_levels: 12,
            smooth_sweeps: 1,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum AmgError {
    #[error("AMG: the coarsest matrix ({n} unknowns) is singular or indefinite")]
    CoarseSingular { n: usize },
    #[error(
        "AMG: the coarsest level has {n} unknowns, more than a dense factor may take \
         ({limit}); aggregation stalled or max_levels is too small"
    )]
    CoarseTooLarge { n: usize, limit: usize },
    #[error("AMG: level {level} has diagonal entry {value} in row {row}; the matrix is not SPD")]
    NonPositiveDiagonal {
        level: usize,
        row: usize,
        value: f64,
    },
    #[error("AMG: {0}")]
    BadInput(String),
}

/// One level above the coarsest: its operator, the inverse diagonal the
/// smoother divides by, the prolongator from the next coarser level and its
/// transpose (restriction row by row, so it can run in parallel).
struct Level {
    a: Mat32,
    inv_diag: Vec<f64>,
    /// Offset of the diagonal in each row of `a` (the smoother's split).
    dpos: Vec<u32>,
    p: Mat32,
    pt: Mat32,
}

/// CSR with u32 column indices: the cycle is memory-bandwidth bound, and
/// this is 12 instead of 16 bytes an entry in every sweep and transfer.
struct Mat32 {
    nrows: usize,
    indptr: Vec<usize>,
    indices: Vec<u32>,
    data: Vec<f64>,
}

impl Mat32 {
    fn new(m: &Csr) -> Result<Mat32, AmgError> {
        if u32::try_from(m.ncols).is_err() {
            return Err(AmgError::BadInput(format!(
                "{} columns: more than u32 indices take",
                m.ncols
            )));
        }
        Ok(Mat32 {
            nrows: m.nrows,
            indptr: m.indptr.clone(),
            indices: m.indices.iter().map(|&j| j as u32).collect(),
            data: m.data.clone(),
        })
    }

    fn nnz(&self) -> usize {
        self.data.len()
    }

    #[inline]
    fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let (s, e) = (self.indptr[i], self.indptr[i + 1]);
        (&self.indices[s..e], &self.data[s..e])
    }

    /// (a_i, x), summed in column order like [`Csr::row_dot`].
    #[inline]
    fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        let (c, v) = self.row(i);
        c.iter().zip(v).map(|(&j, &a)| a * x[j as usize]).sum()
    }
}

/// Fewer rows than this run serially: rayon's overhead beats the gain.
const PAR_MIN: usize = 20_000;
/// Rows (or vector entries) per parallel task; also the fixed chunk of the
/// reductions, whose bits must not depend on the number of threads.
const CHUNK: usize = 4096;

/// y_i = f(i, y_i) for every i, in parallel on large vectors. Each entry is
/// computed alone, so the result does not depend on the thread count.
fn for_rows(y: &mut [f64], f: impl Fn(usize, &mut f64) + Sync) {
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
fn chunk_sum(n: usize, f: impl Fn(usize, std::ops::Range<usize>) -> f64 + Sync) -> f64 {
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
fn dot4(a: &[f64], b: &[f64]) -> f64 {
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
fn cg_step(alpha: f64, p: &[f64], q: &[f64], x: &mut [f64], r: &mut [f64]) -> f64 {
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
fn pdot(a: &[f64], b: &[f64]) -> f64 {
    chunk_sum(a.len(), |_, r| dot4(&a[r.clone()], &b[r]))
}

/// y = K x row-parallel (each row summed as in [`Csr::mul_vec`]) and the
/// chunked (x, y) of the same pass.
fn mul_dot(k: &Csr, x: &[f64], y: &mut [f64]) -> f64 {
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

/// Vectors of one level's cycle: the residual of this level and the right
/// side and correction of the next coarser one.
struct Work {
    res: Vec<f64>,
    next_b: Vec<f64>,
    next_x: Vec<f64>,
}

/// The SA-AMG hierarchy; [`Amg::apply`] is one V-cycle.
pub struct Amg {
    levels: Vec<Level>,
    coarse: SeqChol,
    coarse_n: usize,
    coarse_nnz: usize,
    sweeps: usize,
    /// Work vectors kept between calls (a Mutex, not a RefCell, so Amg stays
    /// Sync; a call that finds them taken allocates its own).
    work: Mutex<Option<Vec<Work>>>,
}

/// Marks an unaggregated (or empty) block.
const NONE: usize = usize::MAX;

impl Amg {
    /// Build the hierarchy for SPD K. `near = None`: blocks of one unknown
    /// and the constant vector.
    pub fn new(k: &Csr, near: Option<NearNull<'_>>, s: &AmgSettings) -> Result<Amg, AmgError> {
        let n = k.nrows;
        if k.ncols != n {
            return Err(AmgError::BadInput(format!(
                "K is {}×{}, not square",
                n, k.ncols
            )));
        }
        // The default near-null space is built only when asked for.
        let default_bp: Vec<usize>;
        let default_modes: Vec<Vec<f64>>;
        let (bp0, modes0): (&[usize], &[Vec<f64>]) = match &near {
            Some(nn) => (nn.block_ptr, nn.modes),
            None => {
                default_bp = (0..=n).collect();
                default_modes = vec![vec![1.0; n]];
                (&default_bp, &default_modes)
            }
        };
        check_near(n, bp0, modes0)?;

        let mut levels: Vec<Level> = Vec::new();
        // The fine level is read from K; coarser ones are owned.
        let mut coarser: Option<Csr> = None;
        let mut owned: Option<(Vec<usize>, Vec<Vec<f64>>)> = None;
        loop {
            let a = coarser.as_ref().unwrap_or(k);
            let n = a.nrows;
            let inv_diag = inv_diagonal(a, levels.len())?;
            if n <= s.coarse_max || levels.len() + 1 >= s.max_levels.max(1) {
                break;
            }
            let (bp, modes): (&[usize], &[Vec<f64>]) = match &owned {
                Some((b, m)) => (b, m),
                None => (bp0, modes0),
            };
            let (t, cbp, cmodes) = tentative(a, bp, modes, s.theta);
            let nc = t.ncols;
            if nc == 0 || nc as f64 > 0.8 * n as f64 {
                break;
            }
            let omega = (4.0 / 3.0) / (1.05 * lambda_max_dinv_k(a, &inv_diag));
            let p = smooth_prolongator(a, &inv_diag, &t, omega);
            drop(t);
            // Galerkin Pᵀ (A P), each factor narrowed once it is done with.
            let pt = transpose(&p);
            let ap = spgemm(a, &p);
            let p = Mat32::new(&p)?;
            let ac = spgemm(&pt, &ap);
            drop(ap);
            let pt = Mat32::new(&pt)?;
            let a = Mat32::new(a)?;
            let dpos = (0..n)
                .map(|i| a.row(i).0.partition_point(|&j| (j as usize) < i) as u32)
                .collect();
            levels.push(Level {
                a,
                inv_diag,
                dpos,
                p,
                pt,
            });
            coarser = Some(ac);
            owned = Some((cbp, cmodes));
        }

        let a = coarser.as_ref().unwrap_or(k);
        let nc = a.nrows;
        let limit = s.coarse_max.max(4000);
        if nc > limit {
            return Err(AmgError::CoarseTooLarge { n: nc, limit });
        }
        let mut dense = vec![0.0; nc * nc];
        for i in 0..nc {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                dense[i * nc + j] = x;
            }
        }
        let coarse = SeqChol::new(&dense, nc).ok_or(AmgError::CoarseSingular { n: nc })?;
        Ok(Amg {
            levels,
            coarse,
            coarse_n: nc,
            coarse_nnz: a.nnz(),
            sweeps: s.smooth_sweeps,
            work: Mutex::new(None),
        })
    }

    /// One symmetric V-cycle: z ≈ K⁻¹ r (z overwritten, start from zero).
    pub fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut work = self
            .work
            .lock()
            .ok()
            .and_then(|mut g| g.take())
            .unwrap_or_else(|| self.alloc_work());
        self.vcycle(0, r, z, &mut work);
        if let Ok(mut g) = self.work.lock() {
            *g = Some(work);
        }
    }

    /// Number of levels, the coarsest included.
    pub fn levels(&self) -> usize {
        self.levels.len() + 1
    }

    /// Σ nnz over all levels / nnz of the fine level.
    pub fn operator_complexity(&self) -> f64 {
        let total: usize = self.levels.iter().map(|l| l.a.nnz()).sum::<usize>() + self.coarse_nnz;
        let fine = self.levels.first().map_or(self.coarse_nnz, |l| l.a.nnz());
        total as f64 / fine.max(1) as f64
    }

    /// Unknowns per level, finest first.
    pub fn sizes(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.levels.iter().map(|l| l.a.nrows).collect();
        v.push(self.coarse_n);
        v
    }

    fn alloc_work(&self) -> Vec<Work> {
        let sizes = self.sizes();
        (0..self.levels.len())
            .map(|l| Work {
                res: vec![0.0; sizes[l]],
                next_b: vec![0.0; sizes[l + 1]],
                next_x: vec![0.0; sizes[l + 1]],
            })
            .collect()
    }

    /// x = V-cycle(b) on level `l` (x need not be zero on entry).
    fn vcycle(&self, l: usize, b: &[f64], x: &mut [f64], work: &mut [Work]) {
        let Some(lev) = self.levels.get(l) else {
            x.copy_from_slice(b);
            if self.coarse_n > 0 {
                self.coarse.solve_in_place(x);
            }
            return;
        };
        let Some((w, rest)) = work.split_first_mut() else {
            unreachable!("one work entry per level above the coarsest")
        };
        x.fill(0.0);
        for sweep in 0..self.sweeps {
            gs_forward(lev, b, x, sweep == 0);
        }
        // res = b − A x, restricted: next_b = Pᵀ res.
        let xs: &[f64] = x;
        for_rows(&mut w.res, |i, ri| *ri = b[i] - lev.a.row_dot(i, xs));
        let res = &w.res;
        for_rows(&mut w.next_b, |j, bj| *bj = lev.pt.row_dot(j, res));
        self.vcycle(l + 1, &w.next_b, &mut w.next_x, rest);
        let nx = &w.next_x;
        for_rows(x, |i, xi| *xi += lev.p.row_dot(i, nx));
        for _ in 0..self.sweeps {
            gs_backward(lev, b, x);
        }
    }
}

/// Block pointers must cover 0..n in order and every mode have length n.
fn check_near(n: usize, bp: &[usize], modes: &[Vec<f64>]) -> Result<(), AmgError> {
    if bp.first() != Some(&0) || bp.last() != Some(&n) || bp.windows(2).any(|w| w[0] > w[1]) {
        return Err(AmgError::BadInput(format!(
            "block_ptr must rise from 0 to n = {n}"
        )));
    }
    if modes.is_empty() || modes.iter().any(|m| m.len() != n) {
        return Err(AmgError::BadInput(format!(
            "need at least one near-null mode, each of length n = {n}"
        )));
    }
    Ok(())
}

/// 1/a_ii per row; a non-positive (or absent) diagonal means not SPD.
fn inv_diagonal(a: &Csr, level: usize) -> Result<Vec<f64>, AmgError> {
    a.diag()
        .into_iter()
        .enumerate()
        .map(|(row, d)| {
            if d > 0.0 && d.is_finite() {
                Ok(1.0 / d)
            } else {
                Err(AmgError::NonPositiveDiagonal {
                    level,
                    row,
                    value: d,
                })
            }
        })
        .collect()
}

/// One forward Gauss–Seidel sweep on A x = b. The sum over the old values
/// (j ≥ i) goes first, off the serial chain through the fresh x_{i−1}; on
/// x = 0 (`zero`) it is 0 and is skipped (half of each row not read).
fn gs_forward(lev: &Level, b: &[f64], x: &mut [f64], zero: bool) {
    let a = &lev.a;
    for i in 0..a.nrows {
        let (c, v) = a.row(i);
        let d = lev.dpos[i] as usize;
        let mut s = b[i];
        if !zero {
            let mut u = 0.0;
            for (&j, &aij) in c[d..].iter().zip(&v[d..]) {
                u += aij * x[j as usize];
            }
            s -= u;
        }
        for (&j, &aij) in c[..d].iter().zip(&v[..d]) {
            s -= aij * x[j as usize];
        }
        x[i] += s * lev.inv_diag[i];
    }
}

/// One backward Gauss–Seidel sweep (the adjoint of [`gs_forward`]): old
/// values (j ≤ i) first, then the fresh ones, x_{i+1} last.
fn gs_backward(lev: &Level, b: &[f64], x: &mut [f64]) {
    let a = &lev.a;
    for i in (0..a.nrows).rev() {
        let (c, v) = a.row(i);
        let d = lev.dpos[i] as usize + 1;
        let mut l = 0.0;
        for (&j, &aij) in c[..d].iter().zip(&v[..d]) {
            l += aij * x[j as usize];
        }
        let mut s = b[i] - l;
        for (&j, &aij) in c[d..].iter().zip(&v[d..]).rev() {
            s -= aij * x[j as usize];
        }
        x[i] += s * lev.inv_diag[i];
    }
}

/// Strong neighbours of every block as a CSR graph (blocks ascending) with
/// the normalised strength ‖K_IJ‖_F / sqrt(‖K_II‖_F ‖K_JJ‖_F) of each.
fn strength(
    a: &Csr,
    bp: &[usize],
    block_of: &[usize],
    theta: f64,
) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let nb = bp.len() - 1;
    let mut dnorm = vec![0.0f64; nb];
    for (blk, w) in bp.windows(2).enumerate() {
        let mut s = 0.0;
        for i in w[0]..w[1] {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                if block_of[j] == blk {
                    s += x * x;
                }
            }
        }
        dnorm[blk] = s.sqrt();
    }
    let mut acc = vec![0.0f64; nb];
    let mut mark = vec![NONE; nb];
    let mut touched: Vec<usize> = Vec::new();
    let mut ptr = Vec::with_capacity(nb + 1);
    let mut idx = Vec::new();
    let mut val = Vec::new();
    ptr.push(0);
    for (blk, w) in bp.windows(2).enumerate() {
        touched.clear();
        for i in w[0]..w[1] {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                let jb = block_of[j];
                if jb == blk {
                    continue;
                }
                if mark[jb] != blk {
                    mark[jb] = blk;
                    acc[jb] = 0.0;
                    touched.push(jb);
                }
                acc[jb] += x * x;
            }
        }
        touched.sort_unstable();
        for &jb in &touched {
            let den = (dnorm[blk] * dnorm[jb]).sqrt();
            if den > 0.0 {
                let st = acc[jb].sqrt() / den;
                if st >= theta {
                    idx.push(jb);
                    val.push(st);
                }
            }
        }
        ptr.push(idx.len());
    }
    (ptr, idx, val)
}

/// Vaněk's three aggregation passes over the strength graph; returns the
/// aggregate of every block (NONE for empty blocks) and their count.
fn aggregate(bp: &[usize], sp: &[usize], si: &[usize], sv: &[f64]) -> (Vec<usize>, usize) {
    let nb = bp.len() - 1;
    let empty = |b: usize| bp[b] == bp[b + 1];
    let nbrs = |b: usize| &si[sp[b]..sp[b + 1]];
    let mut agg = vec![NONE; nb];
    let mut nagg = 0;
    // Pass 1: a block whose whole neighbourhood is free seeds an aggregate.
    for b in 0..nb {
        if empty(b) || agg[b] != NONE {
            continue;
        }
        if nbrs(b).iter().all(|&j| agg[j] == NONE) {
            agg[b] = nagg;
            for &j in nbrs(b) {
                agg[j] = nagg;
            }
            nagg += 1;
        }
    }
    // Pass 2: join the seed aggregate of the strongest neighbour (against
    // the pass-1 state, so aggregates do not creep along chains).
    let seeded = agg.clone();
    for b in 0..nb {
        if empty(b) || seeded[b] != NONE {
            continue;
        }
        let mut best: Option<(f64, usize)> = None;
        for k in sp[b]..sp[b + 1] {
            let j = si[k];
            if seeded[j] != NONE && best.is_none_or(|(s, _)| sv[k] > s) {
                best = Some((sv[k], seeded[j]));
            }
        }
        if let Some((_, a)) = best {
            agg[b] = a;
        }
    }
    // Pass 3: what is left groups with its still-free neighbours.
    for b in 0..nb {
        if empty(b) || agg[b] != NONE {
            continue;
        }
        agg[b] = nagg;
        for &j in nbrs(b) {
            if agg[j] == NONE {
                agg[j] = nagg;
            }
        }
        nagg += 1;
    }
    (agg, nagg)
}

/// The tentative prolongator T (n × n_c), the coarse block pointers (one
/// block per aggregate) and the coarse near-null modes R.
fn tentative(
    a: &Csr,
    bp: &[usize],
    modes: &[Vec<f64>],
    theta: f64,
) -> (Csr, Vec<usize>, Vec<Vec<f64>>) {
    let n = a.nrows;
    let nm = modes.len();
    let mut block_of = vec![NONE; n];
    for (blk, w) in bp.windows(2).enumerate() {
        block_of[w[0]..w[1]].fill(blk);
    }
    let (sp, si, sv) = strength(a, bp, &block_of, theta);
    let (agg, nagg) = aggregate(bp, &sp, &si, &sv);
    drop((sp, si, sv));

    // Blocks of each aggregate, ascending.
    let mut mptr = vec![0usize; nagg + 1];
    for &g in agg.iter().filter(|&&g| g != NONE) {
        mptr[g + 1] += 1;
    }
    for g in 0..nagg {
        mptr[g + 1] += mptr[g];
    }
    let mut fill = mptr.clone();
    let mut members = vec![0usize; mptr[nagg]];
    for (blk, &g) in agg.iter().enumerate() {
        if g != NONE {
            members[fill[g]] = blk;
            fill[g] += 1;
        }
    }

    // QR per aggregate. T's row i holds the kept columns of its aggregate,
    // so T's pattern is known once every aggregate's rank is.
    let mut rows: Vec<usize> = Vec::new();
    let mut q: Vec<f64> = Vec::new();
    let mut r = vec![0.0f64; nm * nm];
    let mut kept_cols: Vec<usize> = Vec::new();
    let mut cptr = vec![0usize; nagg + 1];
    // T's row pointers need every aggregate's rank before any value goes
    // in, so Q (kept columns only, nnz(T) numbers) and R wait here.
    let mut q_store: Vec<f64> = Vec::new();
    let mut q_ptr = vec![0usize; nagg + 1];
    let mut r_store: Vec<f64> = Vec::new();
    for g in 0..nagg {
        rows.clear();
        for &blk in &members[mptr[g]..mptr[g + 1]] {
            rows.extend(bp[blk]..bp[blk + 1]);
        }
        let m = rows.len();
        q.clear();
        q.resize(m * nm, 0.0);
        for (c, mode) in modes.iter().enumerate() {
            for (l, &i) in rows.iter().enumerate() {
                q[c * m + l] = mode[i];
            }
        }
        let kept = mgs(&mut q, m, nm, &mut r, &mut kept_cols);
        cptr[g + 1] = cptr[g] + kept;
        for &c in &kept_cols {
            q_store.extend_from_slice(&q[c * m..(c + 1) * m]);
        }
        q_ptr[g + 1] = q_store.len();
        r_store.extend_from_slice(&r[..kept * nm]);
    }
    let nc = cptr[nagg];

    // T row by row.
    let mut indptr = vec![0usize; n + 1];
    for i in 0..n {
        let g = agg[block_of[i]];
        indptr[i + 1] = indptr[i] + if g == NONE { 0 } else { cptr[g + 1] - cptr[g] };
    }
    let nnz = indptr[n];
    let mut indices = vec![0usize; nnz];
    let mut data = vec![0.0f64; nnz];
    for g in 0..nagg {
        let kept = cptr[g + 1] - cptr[g];
        let qg = &q_store[q_ptr[g]..q_ptr[g + 1]];
        let m = qg.len().checked_div(kept).unwrap_or(0);
        let mut l = 0;
        for &blk in &members[mptr[g]..mptr[g + 1]] {
            for i in bp[blk]..bp[blk + 1] {
                for c in 0..kept {
                    indices[indptr[i] + c] = cptr[g] + c;
                    data[indptr[i] + c] = qg[c * m + l];
                }
                l += 1;
            }
        }
    }
    let t = Csr {
        nrows: n,
        ncols: nc,
        indptr,
        indices,
        data,
    };

    let mut cmodes = vec![vec![0.0f64; nc]; nm];
    for g in 0..nagg {
        let kept = cptr[g + 1] - cptr[g];
        let rg = &r_store[cptr[g] * nm..(cptr[g] + kept) * nm];
        for k in 0..kept {
            for (c, cm) in cmodes.iter_mut().enumerate() {
                cm[cptr[g] + k] = rg[k * nm + c];
            }
        }
    }
    (t, cptr, cmodes)
}

/// Thin QR of the m × nm column-major `q` by modified Gram–Schmidt, two
/// passes (one pass loses orthogonality on nearly dependent modes). A column
/// whose norm falls below 1e-10 of its original norm is dropped. On return
/// `kept` lists the surviving column slots of `q` (orthonormal) and `r`
/// holds the R rows (kept × nm, row-major) in the same order. Returns the
/// rank.
fn mgs(q: &mut [f64], m: usize, nm: usize, r: &mut [f64], kept: &mut Vec<usize>) -> usize {
    kept.clear();
    r.fill(0.0);
    for c in 0..nm {
        let (before, this) = q.split_at_mut(c * m);
        let v = &mut this[..m];
        let n0 = norm(v);
        for _pass in 0..2 {
            for (k, &qc) in kept.iter().enumerate() {
                let qk = &before[qc * m..(qc + 1) * m];
                let h = dot(qk, v);
                axpy(-h, qk, v);
                r[k * nm + c] += h;
            }
        }
        let n1 = norm(v);
        if n0 == 0.0 || n1 == 0.0 || n1 < 1e-10 * n0 {
            continue;
        }
        for x in v.iter_mut() {
            *x /= n1;
        }
        r[kept.len() * nm + c] = n1;
        kept.push(c);
    }
    kept.len()
}

/// λ_max(D⁻¹A) by 15 power steps from the fixed start (1 + i mod 7); the
/// estimate is the Rayleigh quotient in the D inner product (D⁻¹A is
/// self-adjoint there), which lies below λ_max.
fn lambda_max_dinv_k(a: &Csr, inv_d: &[f64]) -> f64 {
    let n = a.nrows;
    let mut v: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
    let mut w = vec![0.0; n];
    let mut lam = 0.0;
    for _ in 0..15 {
        a.mul_vec(&v, &mut w);
        // Rayleigh quotient (v, Av) / (v, Dv).
        let vav = dot(&v, &w);
        let vdv: f64 = v.iter().zip(inv_d).map(|(x, id)| x * x / id).sum();
        if vdv > 0.0 {
            lam = vav / vdv;
        }
        for (wi, id) in w.iter_mut().zip(inv_d) {
            *wi *= id;
        }
        let nw = norm(&w);
        if !(nw > 0.0) || !nw.is_finite() {
            break;
        }
        for (vi, wi) in v.iter_mut().zip(&w) {
            *vi = wi / nw;
        }
    }
    if lam > 0.0 && lam.is_finite() {
        lam
    } else {
        // No usable estimate (a degenerate start vector): λ_max(D⁻¹A) ≤ 2
        // holds for diagonally dominant A, a safe guess otherwise.
        2.0
    }
}

/// Dense accumulator for Gustavson products: one row at a time, the columns
/// touched kept in a list and sorted when the row is emitted.
struct RowAcc {
    val: Vec<f64>,
    mark: Vec<usize>,
    cols: Vec<usize>,
}

impl RowAcc {
    fn new(ncols: usize) -> RowAcc {
        RowAcc {
            val: vec![0.0; ncols],
            mark: vec![NONE; ncols],
            cols: Vec::new(),
        }
    }

    /// acc += w · (row of B given as columns and values); `row` tags the
    /// current output row.
    #[inline]
    fn add(&mut self, row: usize, w: f64, c: &[usize], v: &[f64]) {
        for (&j, &x) in c.iter().zip(v) {
            if self.mark[j] != row {
                self.mark[j] = row;
                self.val[j] = 0.0;
                self.cols.push(j);
            }
            self.val[j] += w * x;
        }
    }

    /// Append the row (sorted) to `out` and clear the accumulator.
    fn emit(&mut self, out: &mut Csr) {
        self.cols.sort_unstable();
        for &j in &self.cols {
            out.indices.push(j);
            out.data.push(self.val[j]);
        }
        out.indptr.push(out.indices.len());
        self.cols.clear();
    }
}

/// P = (I − ω D⁻¹A) T in one Gustavson pass.
fn smooth_prolongator(a: &Csr, inv_d: &[f64], t: &Csr, omega: f64) -> Csr {
    let mut out = Csr::zeros(a.nrows, t.ncols);
    out.indptr.truncate(1);
    let mut acc = RowAcc::new(t.ncols);
    for i in 0..a.nrows {
        let (tc, tv) = t.row(i);
        acc.add(i, 1.0, tc, tv);
        let w = -omega * inv_d[i];
        let (c, v) = a.row(i);
        for (&j, &aij) in c.iter().zip(v) {
            let (tc, tv) = t.row(j);
            acc.add(i, w * aij, tc, tv);
        }
        acc.emit(&mut out);
    }
    out
}

/// C = A B (Gustavson, columns sorted, nothing dropped).
fn spgemm(a: &Csr, b: &Csr) -> Csr {
    let mut out = Csr::zeros(a.nrows, b.ncols);
    out.indptr.truncate(1);
    let mut acc = RowAcc::new(b.ncols);
    for i in 0..a.nrows {
        let (c, v) = a.row(i);
        for (&j, &aij) in c.iter().zip(v) {
            let (bc, bv) = b.row(j);
            acc.add(i, aij, bc, bv);
        }
        acc.emit(&mut out);
    }
    out
}

/// Mᵀ by a counting sort: O(nnz) without the triplet list of
/// [`Csr::transpose`] (which would be 24 bytes per entry of P); rows are
/// visited in order, so the columns come out sorted.
fn transpose(m: &Csr) -> Csr {
    let mut indptr = vec![0usize; m.ncols + 1];
    for &j in &m.indices {
        indptr[j + 1] += 1;
    }
    for j in 0..m.ncols {
        indptr[j + 1] += indptr[j];
    }
    let mut next = indptr.clone();
    let mut indices = vec![0usize; m.nnz()];
    let mut data = vec![0.0f64; m.nnz()];
    for i in 0..m.nrows {
        let (c, v) = m.row(i);
        for (&j, &x) in c.iter().zip(v) {
            indices[next[j]] = i;
            data[next[j]] = x;
            next[j] += 1;
        }
    }
    Csr {
        nrows: m.ncols,
        ncols: m.nrows,
        indptr,
        indices,
        data,
    }
}

/// Result of [`pcg`].
#[derive(Debug, Clone, Copy)]
pub struct PcgReport {
    pub iterations: usize,
    /// ‖b − Kx‖₂ / ‖b‖₂ of the returned x (recomputed, not the recursion's).
    pub rel_residual: f64,
    pub converged: bool,
    /// Stopped because the stall window of [`pcg_stall`] passed without
    /// halving the residual: the rounding floor of b − Kx is above rtol.
    pub stalled: bool,
}

/// A stall window for [`pcg_stall`] with a multigrid preconditioner.
pub const PCG_STALL: usize = 50;

/// Preconditioned CG for K x = b from the given x (warm start), stop when
/// ‖b − Kx‖₂ ≤ rtol·‖b‖₂ (or b = 0, then x = 0) or after max_iter.
/// Deterministic. The stop is confirmed on the true residual: if the
/// recursive one has drifted, CG restarts from the true one.
pub fn pcg(
    k: &Csr,
    b: &[f64],
    x: &mut [f64],
    m: &dyn Fn(&[f64], &mut [f64]),
    rtol: f64,
    max_iter: usize,
) -> PcgReport {
    pcg_stall(k, b, x, m, rtol, max_iter, usize::MAX)
}

/// [`pcg`] that also stops when `stall` steps have not halved the best
/// residual once it is below √rtol·‖b‖₂ (counts only; a CG residual may
/// grow for a while before): the rounding floor of b − Kx (a soft body
/// beside a stiff one) lies above rtol. [`PCG_STALL`] suits a multigrid
/// preconditioner, not a weak one, whose CG may crawl that long.
pub fn pcg_stall(
    k: &Csr,
    b: &[f64],
    x: &mut [f64],
    m: &dyn Fn(&[f64], &mut [f64]),
    rtol: f64,
    max_iter: usize,
    stall: usize,
) -> PcgReport {
    let n = b.len();
    let bn = pdot(b, b).sqrt();
    if bn == 0.0 {
        x.fill(0.0);
        return PcgReport {
            iterations: 0,
            rel_residual: 0.0,
            converged: true,
            stalled: false,
        };
    }
    let tol = rtol * bn;
    let true_residual = |x: &[f64], r: &mut [f64]| {
        for_rows(r, |i, ri| *ri = b[i] - k.row_dot(i, x));
    };
    let pnorm = |v: &[f64]| pdot(v, v).sqrt();
    let mut r = vec![0.0; n];
    true_residual(x, &mut r);
    let mut z = vec![0.0; n];
    let mut q = vec![0.0; n];
    let mut it = 0;
    let r0 = pnorm(&r);
    let (mut best, mut best_at, mut stalled) = (r0, 0usize, false);
    if r0 > tol && max_iter > 0 {
        m(&r, &mut z);
        let mut rz = pdot(&r, &z);
        let mut p = z.clone();
        while it < max_iter {
            let pq = mul_dot(k, &p, &mut q);
            if !(pq > 0.0) || !(rz > 0.0) {
                break; // K or M not SPD (or exact convergence)
            }
            let alpha = rz / pq;
            let rn = cg_step(alpha, &p, &q, x, &mut r).sqrt();
            it += 1;
            if rn <= 0.5 * best {
                (best, best_at) = (rn, it);
            } else if it - best_at >= stall && best <= rtol.sqrt() * bn {
                stalled = true;
                break;
            }
            let mut restart = false;
            if rn <= tol {
                true_residual(x, &mut r);
                if pnorm(&r) <= tol {
                    break;
                }
                restart = true;
            }
            m(&r, &mut z);
            let rz_new = pdot(&r, &z);
            let beta = if restart { 0.0 } else { rz_new / rz };
            rz = rz_new;
            for_rows(&mut p, |i, pi| *pi = z[i] + beta * *pi);
        }
    }
    true_residual(x, &mut r);
    let rel = pnorm(&r) / bn;
    PcgReport {
        iterations: it,
        rel_residual: rel,
        converged: rel <= rtol,
        stalled: stalled && rel > rtol,
    }
}

/// The coarsest level's dense Cholesky factor, computed and applied on the
/// calling thread (`Par::Seq`): faer's global parallelism splits blocked
/// kernels by the thread count, and the bits of the answer must not depend
/// on it (`qp::ssn` tests it on 1 and 2 threads).
struct SeqChol {
    l: Mat<f64>,
}

impl SeqChol {
    /// Factor the row-major n×n SPD `a`; None if a pivot fails the
    /// [`PIVOT_REL`] test of [`crate::linalg::dense::SpdFactor`] or anything
    /// is not finite.
    fn new(a: &[f64], n: usize) -> Option<SeqChol> {
        use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
        let mut l = Mat::from_fn(n, n, |i, j| if j <= i { a[i * n + j] } else { 0.0 });
        let mut mem = MemBuffer::try_new(cholesky_in_place_scratch::<f64>(
            n,
            Par::Seq,
            Default::default(),
        ))
        .ok()?;
        cholesky_in_place(
            l.as_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .ok()?;
        for j in 0..n {
            let d = l[(j, j)] * l[(j, j)];
            if !(d.is_finite() && d > PIVOT_REL * a[j * n + j].abs()) {
                return None;
            }
            for i in 0..j {
                l[(i, j)] = 0.0; // the strict upper part is not L
            }
        }
        l.is_all_finite().then_some(SeqChol { l })
    }

    /// b ← (LLᵀ)⁻¹ b.
    fn solve_in_place(&self, b: &mut [f64]) {
        use faer::linalg::triangular_solve::{
            solve_lower_triangular_in_place, solve_upper_triangular_in_place,
        };
        let mut col = faer::MatMut::from_column_major_slice_mut(b, self.l.nrows(), 1);
        solve_lower_triangular_in_place(self.l.as_ref(), col.as_mut(), Par::Seq);
        solve_upper_triangular_in_place(self.l.transpose(), col.as_mut(), Par::Seq);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity(r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }

    /// 5-point Laplacian on an m × m interior grid (Dirichlet boundary).
    fn laplacian(m: usize) -> Csr {
        let id = |i: usize, j: usize| j * m + i;
        let mut t = Vec::new();
        for j in 0..m {
            for i in 0..m {
                let r = id(i, j);
                t.push((r, r, 4.0));
                if i > 0 {
                    t.push((r, id(i - 1, j), -1.0));
                }
                if i + 1 < m {
                    t.push((r, id(i + 1, j), -1.0));
                }
                if j > 0 {
                    t.push((r, id(i, j - 1), -1.0));
                }
                if j + 1 < m {
                    t.push((r, id(i, j + 1), -1.0));
                }
            }
        }
        Csr::from_triplets(m * m, m * m, &t)
    }

    /// Plane-strain P1 elasticity on the unit square (nx × ny squares, two
    /// triangles each), left edge clamped, ν = 0.3, Young's modulus
    /// `young(x, y)` at the element centroid. Returns K, the per-node block
    /// pointers and the 3 rigid motions on the free DOFs.
    fn elasticity(
        nx: usize,
        ny: usize,
        young: impl Fn(f64, f64) -> f64,
    ) -> (Csr, Vec<usize>, Vec<Vec<f64>>) {
        let nu = 0.3;
        let node = |i: usize, j: usize| j * (nx + 1) + i;
        let xy = |v: usize| {
            let (i, j) = (v % (nx + 1), v / (nx + 1));
            (i as f64 / nx as f64, j as f64 / ny as f64)
        };
        // Free nodes (i > 0) numbered in node order, 2 DOFs each.
        let nn = (nx + 1) * (ny + 1);
        let mut dof = vec![NONE; nn];
        let mut nfree = 0;
        for v in 0..nn {
            if v % (nx + 1) > 0 {
                dof[v] = 2 * nfree;
                nfree += 1;
            }
        }
        let mut trip = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (
                    node(i, j),
                    node(i + 1, j),
                    node(i + 1, j + 1),
                    node(i, j + 1),
                );
                for tri in [[a, b, c], [a, c, d]] {
                    let p: Vec<(f64, f64)> = tri.iter().map(|&v| xy(v)).collect();
                    let area2 = (p[1].0 - p[0].0) * (p[2].1 - p[0].1)
                        - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
                    let area = 0.5 * area2;
                    let bb = [p[1].1 - p[2].1, p[2].1 - p[0].1, p[0].1 - p[1].1];
                    let cc = [p[2].0 - p[1].0, p[0].0 - p[2].0, p[1].0 - p[0].0];
                    let (cx, cy) = (
                        (p[0].0 + p[1].0 + p[2].0) / 3.0,
                        (p[0].1 + p[1].1 + p[2].1) / 3.0,
                    );
                    let e = young(cx, cy);
                    let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
                    let mu = e / (2.0 * (1.0 + nu));
                    let dm = [
                        [lam + 2.0 * mu, lam, 0.0],
                        [lam, lam + 2.0 * mu, 0.0],
                        [0.0, 0.0, mu],
                    ];
                    let mut bm = [[0.0; 6]; 3];
                    for k in 0..3 {
                        bm[0][2 * k] = bb[k] / area2;
                        bm[1][2 * k + 1] = cc[k] / area2;
                        bm[2][2 * k] = cc[k] / area2;
                        bm[2][2 * k + 1] = bb[k] / area2;
                    }
                    for r in 0..6 {
                        for s in 0..6 {
                            let mut v = 0.0;
                            for u in 0..3 {
                                for w in 0..3 {
                                    v += bm[u][r] * dm[u][w] * bm[w][s];
                                }
                            }
                            let (gr, gs) = (dof[tri[r / 2]], dof[tri[s / 2]]);
                            if gr != NONE && gs != NONE {
                                trip.push((gr + r % 2, gs + s % 2, area * v));
                            }
                        }
                    }
                }
            }
        }
        let n = 2 * nfree;
        let k = Csr::from_triplets(n, n, &trip);
        let bp: Vec<usize> = (0..=nfree).map(|v| 2 * v).collect();
        let mut modes = vec![vec![0.0; n]; 3];
        for v in 0..nn {
            if dof[v] != NONE {
                let (x, y) = xy(v);
                let d = dof[v];
                modes[0][d] = 1.0;
                modes[1][d + 1] = 1.0;
                modes[2][d] = -y;
                modes[2][d + 1] = x;
            }
        }
        (k, bp, modes)
    }

    /// A load that is neither smooth nor aligned with the grid.
    fn rhs(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.3)
            .collect()
    }

    fn solve_amg(
        k: &Csr,
        near: Option<NearNull<'_>>,
        max_iter: usize,
    ) -> (PcgReport, Vec<f64>, Amg) {
        let amg = Amg::new(k, near, &AmgSettings::default()).expect("hierarchy");
        let b = rhs(k.nrows);
        let mut x = vec![0.0; k.nrows];
        let rep = pcg(k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, max_iter);
        (rep, x, amg)
    }

    #[test]
    fn amg_laplacian_beats_cg() {
        let k = laplacian(100);
        let (rep, _, amg) = solve_amg(&k, None, 500);
        let b = rhs(k.nrows);
        let mut x = vec![0.0; k.nrows];
        let plain = pcg(&k, &b, &mut x, &identity, 1e-10, 10_000);
        eprintln!(
            "laplacian 100²: amg {} its (levels {:?}, oc {:.2}), cg {} its",
            rep.iterations,
            amg.sizes(),
            amg.operator_complexity(),
            plain.iterations
        );
        assert!(rep.converged && rep.iterations <= 30, "{rep:?}");
        assert!(plain.converged, "{plain:?}");
        assert!(plain.iterations >= 3 * rep.iterations, "{plain:?} {rep:?}");
    }

    #[test]
    fn amg_elasticity_mesh_independent() {
        let mut its = Vec::new();
        for m in [64, 128] {
            let (k, bp, modes) = elasticity(m, m, |_, _| 1.0);
            let amg = Amg::new(
                &k,
                Some(NearNull {
                    block_ptr: &bp,
                    modes: &modes,
                }),
                &AmgSettings::default(),
            )
            .expect("hierarchy");
            let b = rhs(k.nrows);
            let mut x = vec![0.0; k.nrows];
            let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 500);
            let mut x0 = vec![0.0; k.nrows];
            let plain = pcg(&k, &b, &mut x0, &identity, 1e-10, 100_000);
            let (scalar, _, samg) = solve_amg(&k, None, 2000);
            eprintln!(
                "elasticity {m}²: n {} amg {} its (levels {:?}, oc {:.2}), \
                 scalar amg {} its (levels {:?}), cg {} its",
                k.nrows,
                rep.iterations,
                amg.sizes(),
                amg.operator_complexity(),
                scalar.iterations,
                samg.sizes(),
                plain.iterations
            );
            assert!(rep.converged, "{rep:?}");
            assert!(scalar.converged, "{scalar:?}");
            assert!(plain.converged, "{plain:?}");
            assert!(plain.iterations >= 5 * rep.iterations, "{plain:?} {rep:?}");
            its.push(rep.iterations);
        }
        assert!(
            its[1] as f64 <= 1.5 * its[0] as f64 + 5.0,
            "iterations grow: {its:?}"
        );
    }

    /// 1 : 1e6 halves. The load is b = K x★ for a rough x★: with a nodal load
    /// of O(1) the displacement of the soft half is so large that
    /// ε‖K‖‖x‖/‖b‖ ≈ 1e-6, and no solver can get ‖b − Kx‖/‖b‖ below that in
    /// double precision; b = K x★ keeps the attainable residual at rounding.
    #[test]
    fn amg_stiffness_contrast() {
        let (k, bp, modes) = elasticity(64, 64, |x, _| if x < 0.5 { 1.0 } else { 1e6 });
        let near = NearNull {
            block_ptr: &bp,
            modes: &modes,
        };
        let amg = Amg::new(&k, Some(near), &AmgSettings::default()).expect("hierarchy");
        let xs = rhs(k.nrows);
        let b = k.mul(&xs);
        let mut x = vec![0.0; k.nrows];
        let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-10, 500);
        let err: Vec<f64> = x.iter().zip(&xs).map(|(a, b)| a - b).collect();
        let rel_err = norm(&err) / norm(&xs);
        eprintln!(
            "contrast 1:1e6 64²: {} its, relative error {rel_err:.1e}",
            rep.iterations
        );
        assert!(rep.converged && rep.iterations <= 60, "{rep:?}");
        assert!(rel_err < 1e-4, "{rel_err}");
    }

    #[test]
    fn amg_deterministic() {
        let (k, bp, modes) = elasticity(40, 30, |_, _| 1.0);
        let run = || {
            let near = NearNull {
                block_ptr: &bp,
                modes: &modes,
            };
            solve_amg(&k, Some(near), 500).1
        };
        let (x1, x2) = (run(), run());
        assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn amg_vcycle_symmetric() {
        let (k, bp, modes) = elasticity(48, 48, |_, _| 1.0);
        let s = AmgSettings {
            coarse_max: 200,
            smooth_sweeps: 2,
            ..AmgSettings::default()
        };
        let near = NearNull {
            block_ptr: &bp,
            modes: &modes,
        };
        let amg = Amg::new(&k, Some(near), &s).expect("hierarchy");
        assert!(amg.levels() >= 3, "{:?}", amg.sizes());
        let n = k.nrows;
        let u: Vec<f64> = (0..n).map(|i| ((i * 31 + 7) % 101) as f64 - 50.0).collect();
        let v: Vec<f64> = (0..n).map(|i| ((i * 17 + 3) % 89) as f64 - 44.0).collect();
        let (mut mu, mut mv) = (vec![0.0; n], vec![0.0; n]);
        amg.apply(&u, &mut mu);
        amg.apply(&v, &mut mv);
        let (umv, vmu) = (dot(&u, &mv), dot(&v, &mu));
        assert!((umv - vmu).abs() <= 1e-10 * umv.abs(), "{umv} {vmu}");
        // Positive definite on these vectors, too.
        assert!(dot(&u, &mu) > 0.0 && dot(&v, &mv) > 0.0);
    }

    #[test]
    fn amg_small_matrix_is_exact_and_bad_input_refused() {
        let k = laplacian(10);
        let amg = Amg::new(&k, None, &AmgSettings::default()).expect("dense");
        assert_eq!(amg.levels(), 1);
        let b = rhs(k.nrows);
        let mut x = vec![0.0; k.nrows];
        let rep = pcg(&k, &b, &mut x, &|r, z| amg.apply(r, z), 1e-12, 5);
        assert!(rep.converged && rep.iterations <= 2, "{rep:?}");
        let bad = NearNull {
            block_ptr: &[0, 3],
            modes: &[],
        };
        assert!(matches!(
            Amg::new(&k, Some(bad), &AmgSettings::default()),
            Err(AmgError::BadInput(_))
        ));
        // A singular matrix (zero Neumann Laplacian row sums) is refused at
        // the coarse factor.
        let sing = Csr::from_triplets(
            2,
            2,
            &[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)],
        );
        assert!(matches!(
            Amg::new(&sing, None, &AmgSettings::default()),
            Err(AmgError::CoarseSingular { n: 2 })
        ));
    }

    /// Empty blocks (mesh points without free unknowns) are skipped, and
    /// the hierarchy may be shared between threads.
    #[test]
    fn amg_empty_blocks_and_sync() {
        fn send_sync<T: Send + Sync>() {}
        send_sync::<Amg>();
        let k = laplacian(60);
        let n = k.nrows;
        // Blocks of one unknown with an empty block after every 7th.
        let mut bp = vec![0];
        for i in 1..=n {
            bp.push(i);
            if i % 7 == 0 {
                bp.push(i);
            }
        }
        let ones = vec![vec![1.0; n]];
        let near = NearNull {
            block_ptr: &bp,
            modes: &ones,
        };
        let (rep, _, amg) = solve_amg(&k, Some(near), 100);
        assert!(
            amg.levels() >= 2 && rep.converged && rep.iterations <= 30,
            "{rep:?}"
        );
    }

    /// The parallel residual, transfers, K·p and reductions give the same
    /// bits on any number of threads (n above the parallel threshold).
    #[test]
    fn amg_pcg_thread_count_independent() {
        let (k, bp, modes) = elasticity(200, 200, |_, _| 1.0);
        assert!(k.nrows > 2 * PAR_MIN);
        let solve = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let near = NearNull {
                    block_ptr: &bp,
                    modes: &modes,
                };
                solve_amg(&k, Some(near), 500)
            })
        };
        let (r1, x1, _) = solve(1);
        let (r2, x2, _) = solve(2);
        assert!(
            r1.converged && r1.iterations == r2.iterations,
            "{r1:?} {r2:?}"
        );
        assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
