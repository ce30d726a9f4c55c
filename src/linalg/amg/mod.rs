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
//!
//! The code: the hierarchy and its V-cycle here, the setup steps 1–5 in
//! `setup`, the vector kernels whose bits do not depend on the thread
//! count in `kernels`, and the CG in `pcg`.

mod coarse;
mod kernels;
mod pcg;
mod setup;
mod update;

pub use pcg::{pcg, pcg_stall, PcgReport, PCG_STALL};

use crate::linalg::dense::PIVOT_REL;
use crate::linalg::sparse::Csr;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{Mat, Par};
use kernels::*;
use setup::*;
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
    /// Strength threshold θ of the block graph on the finest level.
    pub theta: f64,
    /// θ on level l is θ·theta_decay^l (coarse blocks have more and weaker
    /// neighbours; docs/methods.md §7.2).
    pub theta_decay: f64,
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
            theta_decay: 1.0,
            coarse_max: 2000,
            max_levels: 12,
            smooth_sweeps: 1,
        }
    }
}

impl AmgSettings {
    /// The settings for a near-null space of `modes` vectors: the default
    /// (tuned on 2D meshes, three rigid motions) below six, the 3D ones
    /// (six rigid motions; docs/methods.md §7.2) from six on.
    pub fn for_modes(modes: usize) -> AmgSettings {
        if modes < 6 {
            return AmgSettings::default();
        }
        // Measured on the Hertz model (docs/methods.md §7.2): with θ = 0.08
        // on every level coarse 6×6 blocks keep few strong neighbours, the
        // aggregates stay small and the operator complexity reaches 4.4
        // (setup 31 s at 163 k unknowns); θ = 0.02 halved per level gives
        // 1.7 and 3.7 s; two sweeps 31 CG steps instead of 41 for the
        // same time.
        AmgSettings {
            theta: 0.02,
            theta_decay: 0.5,
            coarse_max: 2000,
            max_levels: 12,
            smooth_sweeps: 2,
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
            indptr: m.indptr.to_vec(),
            indices: m.indices.iter().map(|&j| j as u32).collect(),
            data: m.data.to_vec(),
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
    /// The coarsest operator (refactored by `update`).
    coarse_a: Csr,
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
            let theta = s.theta * s.theta_decay.powi(levels.len() as i32);
            let (t, cbp, cmodes) = tentative(a, bp, modes, theta);
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
            coarse_a: a.clone(),
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
mod tests;
