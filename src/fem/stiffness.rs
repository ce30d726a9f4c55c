//! The stiffness matrix C = Σ T_eᵀC_eT_e and the element part of
//! d = Σ T_eᵀ(f_e − C_e u0_e) (docs/methods.md §2.2–2.3, §2.8).
//!
//! The pattern of C is the point adjacency of the mesh expanded to the DOFs
//! of each point (sorted columns). The values are gathered row block by row
//! block: the rows of point p take the rows of p's vertex in the element
//! matrices of its triangles, in increasing triangle order, so every entry
//! is summed in triangle order whatever the number of threads (the same sums
//! as a sequential loop over the triangles), with no triplets and no sort.
//! The work runs over the points in Z-order ("ranks") and the triangles
//! grouped by their lowest rank, so that a point's triangles and their
//! vertices are mostly in cache (Gmsh numbers nodes in no spatial order).

use super::conditions::PointDofs;
use super::element::{Point, PointD, Vector};

use super::element::MaterialMatrix;
use super::topology::Topology;
use crate::problem::{Material, ModelSection};
use crate::qp::Csr;
use std::collections::BTreeMap;

/// What the element matrices need of each material in the model's
/// [`ElementKind`](super::element::ElementKind): D, the body force ρ g and the centrifugal coefficient
/// ρω² (a spin about the axis, docs/methods.md §10).
pub(super) struct Materials<const D: usize = 2> {
    pub(super) kind: super::element::ElementKind,
    pub(super) dmats: Vec<MaterialMatrix>,
    pub(super) bforce: Vec<PointD<D>>,
    pub(super) spin: Vec<f64>,
}

impl Materials {
    /// The materials of `topo.material_names`, in that order.
    pub(super) fn new(
        topo: &Topology,
        materials: &BTreeMap<String, Material>,
        model: &ModelSection,
    ) -> Materials {
        let kind = topo.kind;
        let mats: Vec<&Material> = topo.material_names.iter().map(|m| &materials[m]).collect();
        let gvec = model.gravity.map_or([0.0, 0.0], |g| g.xy());
        let w = model.omega.unwrap_or(0.0);
        // A load step scales ρω²r like every other load.
        let lf = model.centrifugal_factor.unwrap_or(1.0);
        Materials {
            kind,
            dmats: mats.iter().map(|m| kind.material(m)).collect(),
            bforce: mats
                .iter()
                .map(|m| [m.rho * gvec[0], m.rho * gvec[1]])
                .collect(),
            spin: mats.iter().map(|m| m.rho * w * w * lf).collect(),
        }
    }
}

impl Materials {
    /// The body load of vertex `a` of a triangle `pts` of material `mi`:
    /// th |T|/3 ρg, or ∫ N_a (ρg r + ρω² r² e_r) dA per radian when
    /// axisymmetric (docs/methods.md §2.2, §10). The one definition of the
    /// assembly and of a load step's d (`loads::element_d`).
    pub(super) fn body_load(&self, pts: &[Point; 3], mi: usize, a: usize) -> Vector {
        self.kind.body_load(pts, a, self.bforce[mi], self.spin[mi])
    }

    /// Rows 2a and 2a + 1 of the element stiffness of a triangle `pts` of
    /// material `mi` (per radian when axisymmetric).
    pub(super) fn stiffness_rows(&self, pts: &[Point; 3], mi: usize, a: usize) -> [[f64; 6]; 2] {
        self.kind.stiffness_rows(pts, &self.dmats[mi], a)
    }
}

impl<const D: usize> Materials<D> {
    /// [`Materials::stiffness_rows`] of a cell of N vertices, as N blocks
    /// of D×D ([`ElementKind::cell_stiffness_rows`](super::element::ElementKind::cell_stiffness_rows)).
    #[inline]
    fn cell_rows<const N: usize>(
        &self,
        pts: &[PointD<D>; N],
        mi: usize,
        a: usize,
    ) -> [[[f64; D]; D]; N] {
        self.kind.cell_stiffness_rows(pts, &self.dmats[mi], a)
    }

    /// [`Materials::body_load`] of a cell of N vertices.
    #[inline]
    fn cell_load<const N: usize>(&self, pts: &[PointD<D>; N], mi: usize, a: usize) -> PointD<D> {
        self.kind
            .cell_body_load(pts, a, self.bforce[mi], self.spin[mi])
    }
}

/// The cells of a model as the assembly reads them: the points, the
/// cells (N = D + 1 point indices: triangles, tetrahedra) and each cell's
/// material (an index into [`Materials`]).
#[derive(Clone, Copy)]
pub(super) struct Cells<'a, const D: usize, const N: usize> {
    pub(super) points: &'a [PointD<D>],
    pub(super) cells: &'a [[usize; N]],
    pub(super) material: &'a [u32],
}

impl<'a> Cells<'a, 2, 3> {
    /// The triangles of a plane or axisymmetric model.
    pub(super) fn plane(topo: &'a Topology) -> Self {
        Cells {
            points: &topo.points,
            cells: &topo.triangles,
            material: &topo.tri_material,
        }
    }
}

/// Points per parallel work item of the assembly.
const CHUNK_POINTS: usize = 2048;

/// `f` of every item, in order, on rayon's threads if `parallel`. The
/// results never depend on it: every item works on its own data.
fn map_items<T: Send, R: Send>(
    parallel: bool,
    items: Vec<T>,
    f: impl Fn(T) -> R + Sync + Send,
) -> Vec<R> {
    use rayon::prelude::*;
    if !parallel || items.len() <= 1 {
        items.into_iter().map(f).collect()
    } else {
        items.into_par_iter().map(f).collect()
    }
}

/// Run `f` on every item, on rayon's threads if `parallel`.
fn for_each_mut<T: Send>(parallel: bool, items: &mut [T], f: impl Fn(&mut T) + Sync + Send) {
    use rayon::prelude::*;
    if !parallel || items.len() <= 1 {
        items.iter_mut().for_each(f);
    } else {
        items.par_iter_mut().for_each(f);
    }
}

/// The row blocks of a chunk of points (in rank order): columns and values
/// (point i of the chunk at `at[i]..at[i + 1]`), D d entries per point;
/// `coff` is scratch.
#[derive(Default)]
struct Block {
    cols: Vec<usize>,
    vals: Vec<f64>,
    at: Vec<usize>,
    d: Vec<f64>,
    coff: Vec<usize>,
}

/// Where a thread copies the blocks of its DOF rows: the rows, and C's
/// indices and values from entry `off` on, and d, of those rows.
struct Target<'a> {
    rows: std::ops::Range<usize>,
    off: usize,
    ind: &'a mut [usize],
    dat: &'a mut [f64],
    d: &'a mut [f64],
}

/// A point without conditions: ndof D, T = I, u0 = 0 (the assembly skips
/// the transformation, which changes nothing but the sign of zeros).
fn is_free<const D: usize>(pd: &PointDofs<D>) -> bool {
    pd.ndof == D
        && (0..D).all(|k| (0..D).all(|c| pd.t[k][c] == if k == c { 1.0 } else { 0.0 }))
        && pd.u0.iter().all(|&u| u == 0.0)
}

/// Z-order (Morton) keys of D-dimensional positions: 32/D bits per axis
/// (16 in the plane, 10 in 3D) over the box of all of them. Sorting by key
/// puts nearby positions near each other.
struct Morton<const D: usize> {
    lo: PointD<D>,
    scale: PointD<D>,
}

impl<const D: usize> Morton<D> {
    /// Bits per axis.
    const BITS: u32 = 32 / D as u32;
    /// The largest coordinate on an axis.
    const MAX: f64 = ((1u64 << Self::BITS) - 1) as f64;

    fn new(pts: &[PointD<D>]) -> Morton<D> {
        let mut lo = [f64::INFINITY; D];
        let mut hi = [f64::NEG_INFINITY; D];
        for x in pts {
            for k in 0..D {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        let scale = std::array::from_fn(|k| {
            let e = hi[k] - lo[k];
            if e > 0.0 && e.is_finite() {
                Self::MAX / e
            } else {
                0.0
            }
        });
        Morton { lo, scale }
    }

    fn key(&self, x: PointD<D>) -> u64 {
        let mut key = 0u64;
        for k in 0..D {
            let q = ((x[k] - self.lo[k]) * self.scale[k]).clamp(0.0, Self::MAX) as u64;
            for bit in 0..Self::BITS as usize {
                key |= ((q >> bit) & 1) << (bit * D + k);
            }
        }
        key
    }
}

/// Indices 0..keys.len() sorted by (key, index).
fn sorted_by_key(parallel: bool, keys: impl Iterator<Item = u64>) -> Vec<u32> {
    use rayon::prelude::*;
    let mut k: Vec<u64> = keys
        .enumerate()
        .map(|(i, key)| (key << 32) | i as u64)
        .collect();
    if parallel {
        k.par_sort_unstable();
    } else {
        k.sort_unstable();
    }
    k.into_iter().map(|x| x as u32).collect()
}

/// A point as the assembly reads it, stored in Z-order.
#[derive(Clone, Copy)]
struct RankPoint<const D: usize> {
    x: PointD<D>,
    start: usize,
    /// The point's index.
    p: u32,
    ndof: u8,
    free: bool,
}

/// A cell as the assembly reads it: its vertices (Z-order ranks), mesh
/// index and material.
#[derive(Clone, Copy)]
struct TriRec<const N: usize> {
    v: [u32; N],
    t: u32,
    mat: u32,
}

impl<const N: usize> Default for TriRec<N> {
    fn default() -> Self {
        TriRec {
            v: [0; N],
            t: 0,
            mat: 0,
        }
    }
}

/// The points in Z-order and the triangles by lowest rank, with each rank's
/// triangles (indices into `trec`, in increasing mesh order).
struct Order<const D: usize, const N: usize> {
    /// Rank r holds point `rp[r].p`.
    rp: Vec<RankPoint<D>>,
    trec: Vec<TriRec<N>>,
    inc_ptr: Vec<usize>,
    inc: Vec<u32>,
}

impl<const D: usize, const N: usize> Order<D, N> {
    fn new(
        topo: Cells<D, N>,
        dofs: &[PointDofs<D>],
        parallel: bool,
        lap: &mut super::Lap,
    ) -> Order<D, N> {
        let np = topo.points.len();
        let (rp, rank) = point_order(topo.points, dofs, parallel);
        lap.lap("point order");
        // Triangles bucketed by their lowest vertex rank (mesh order within
        // a bucket), vertices as ranks.
        let trec: Vec<TriRec<N>> = {
            let recs = || {
                topo.cells.iter().enumerate().map(|(t, tri)| TriRec {
                    v: tri.map(|v| rank[v]),
                    t: t as u32,
                    mat: topo.material[t],
                })
            };
            let low = |rec: &TriRec<N>| rec.v.iter().copied().min().unwrap_or(0) as usize;
            super::sort::bucket_sort(recs, low, np).0
        };
        drop(rank);
        lap.lap("triangle order");
        let (inc_ptr, inc) = incidence(&trec, np, parallel);
        lap.lap("incidence");
        Order {
            rp,
            trec,
            inc_ptr,
            inc,
        }
    }

    /// The triangles of rank r (indices into `trec`).
    fn tris_of(&self, r: usize) -> &[u32] {
        &self.inc[self.inc_ptr[r]..self.inc_ptr[r + 1]]
    }
}

/// The points in Z-order (as `RankPoint`s) and each point's rank.
fn point_order<const D: usize>(
    points: &[PointD<D>],
    dofs: &[PointDofs<D>],
    parallel: bool,
) -> (Vec<RankPoint<D>>, Vec<u32>) {
    let mut rank = vec![0u32; points.len()];
    let z = Morton::new(points);
    let order = sorted_by_key(parallel, points.iter().map(|&x| z.key(x)));
    let rp = order
        .iter()
        .enumerate()
        .map(|(r, &p)| {
            let p = p as usize;
            rank[p] = r as u32;
            let pd = &dofs[p];
            RankPoint {
                x: points[p],
                start: pd.start,
                p: p as u32,
                ndof: pd.ndof as u8,
                free: is_free(pd),
            }
        })
        .collect();
    (rp, rank)
}

/// Rank → its triangles (indices into `trec`), in increasing mesh order:
/// (pointers, lists).
fn incidence<const N: usize>(
    trec: &[TriRec<N>],
    np: usize,
    parallel: bool,
) -> (Vec<usize>, Vec<u32>) {
    let mut inc_ptr = vec![0usize; np + 1];
    for rec in trec {
        for &v in &rec.v {
            inc_ptr[v as usize + 1] += 1;
        }
    }
    for r in 0..np {
        inc_ptr[r + 1] += inc_ptr[r];
    }
    let mut inc = vec![0u32; inc_ptr[np]];
    {
        let mut fill = inc_ptr[..np].to_vec();
        for (i, rec) in trec.iter().enumerate() {
            for &v in &rec.v {
                inc[fill[v as usize]] = i as u32;
                fill[v as usize] += 1;
            }
        }
    }
    // Each list in mesh order, chunk by chunk.
    let mut items = Vec::with_capacity(np.div_ceil(CHUNK_POINTS));
    let mut rest = &mut inc[..];
    for s in (0..np).step_by(CHUNK_POINTS) {
        let e = (s + CHUNK_POINTS).min(np);
        let (part, r) = std::mem::take(&mut rest).split_at_mut(inc_ptr[e] - inc_ptr[s]);
        rest = r;
        items.push((s, e, part));
    }
    let inc_ptr_ref = &inc_ptr;
    map_items(parallel, items, |(s, e, part)| {
        for r in s..e {
            part[inc_ptr_ref[r] - inc_ptr_ref[s]..inc_ptr_ref[r + 1] - inc_ptr_ref[s]]
                .sort_unstable_by_key(|&i| trec[i as usize].t);
        }
    });
    (inc_ptr, inc)
}

/// The neighbours of the ranks of one chunk: for each point with DOFs, the
/// vertices with DOFs of its triangles (itself included) as ranks, in
/// increasing point order (`adj[ptr[k]..ptr[k + 1]]` for rank s + k), and
/// the length `len` of the point's rows.
struct Nbrs {
    adj: Vec<u32>,
    ptr: Vec<u32>,
    len: Vec<u32>,
}

/// Pass 1 for the ranks s..e.
fn neighbours<const D: usize, const N: usize>(ord: &Order<D, N>, (s, e): (usize, usize)) -> Nbrs {
    let rp = &ord.rp;
    let mut adj: Vec<u32> = Vec::with_capacity((e - s) * 8);
    let mut ptr: Vec<u32> = Vec::with_capacity(e - s + 1);
    let mut len: Vec<u32> = Vec::with_capacity(e - s);
    let mut buf: Vec<u64> = Vec::with_capacity(64);
    ptr.push(0);
    for r in s..e {
        if rp[r].ndof == 0 {
            ptr.push(adj.len() as u32);
            len.push(0);
            continue;
        }
        buf.clear();
        for &i in ord.tris_of(r) {
            for &q in &ord.trec[i as usize].v {
                let x = &rp[q as usize];
                let key = ((x.p as u64) << 32) | q as u64;
                if x.ndof > 0 && !buf.contains(&key) {
                    buf.push(key);
                }
            }
        }
        buf.sort_unstable();
        let mut l = 0u32;
        for &k in &buf {
            let q = k as u32;
            adj.push(q);
            l += rp[q as usize].ndof as u32;
        }
        ptr.push(adj.len() as u32);
        len.push(l);
    }
    Nbrs { adj, ptr, len }
}

/// CSR row pointers of C in DOF order, from the row lengths of pass 1.
fn row_pointers<const D: usize, const N: usize>(
    ord: &Order<D, N>,
    parts: &[Nbrs],
    dofs: &[PointDofs<D>],
    n: usize,
) -> Vec<usize> {
    let mut len_of = vec![0u32; dofs.len()];
    for (r, x) in ord.rp.iter().enumerate() {
        len_of[x.p as usize] = parts[r / CHUNK_POINTS].len[r % CHUNK_POINTS];
    }
    let mut indptr = Vec::with_capacity(n + 1);
    indptr.push(0usize);
    for (pd, &len) in dofs.iter().zip(&len_of) {
        for _ in 0..pd.ndof {
            indptr.push(indptr[indptr.len() - 1] + len as usize);
        }
    }
    indptr
}

/// Everything pass 2 reads: the order, the neighbours, the DOFs and the
/// materials.
struct Gather<'a, const D: usize, const N: usize> {
    ord: &'a Order<D, N>,
    parts: &'a [Nbrs],
    dofs: &'a [PointDofs<D>],
    mats: &'a Materials<D>,
}

impl<const D: usize, const N: usize> Gather<'_, D, N> {
    /// The neighbours of rank r (pass 1).
    fn nbrs(&self, r: usize) -> &[u32] {
        let (c, k) = (&self.parts[r / CHUNK_POINTS], r % CHUNK_POINTS);
        &c.adj[c.ptr[k] as usize..c.ptr[k + 1] as usize]
    }

    /// Pass 2 for the ranks s..e: their row blocks (columns, values, d)
    /// into `buf`'s own storage.
    fn block(&self, (s, e): (usize, usize), mut buf: Block) -> Block {
        let rp = &self.ord.rp;
        let Block {
            cols,
            vals,
            at,
            d: dv,
            coff,
        } = &mut buf;
        cols.clear();
        vals.clear();
        at.clear();
        at.push(0);
        dv.clear();
        dv.resize(D * (e - s), 0.0);
        for r in s..e {
            let pr = rp[r];
            if pr.ndof == 0 {
                at.push(cols.len());
                continue;
            }
            let nb = self.nbrs(r);
            coff.clear();
            let c0 = cols.len();
            for &q in nb {
                let x = &rp[q as usize];
                coff.push(cols.len() - c0);
                cols.extend(x.start..x.start + x.ndof as usize);
            }
            let len = cols.len() - c0;
            for _ in 1..pr.ndof {
                cols.extend_from_within(c0..c0 + len);
            }
            let v0 = vals.len();
            vals.resize(v0 + pr.ndof as usize * len, 0.0);
            let row = RowBlock {
                r,
                len,
                nb,
                coff,
                blk: &mut vals[v0..],
                dr: &mut dv[D * (r - s)..D * (r - s) + D],
            };
            self.add_triangles(row);
            at.push(cols.len());
        }
        buf
    }

    /// Add the rows of rank `row.r`'s vertex in the element matrices (and
    /// vectors) of its triangles, in increasing triangle order.
    fn add_triangles(&self, row: RowBlock) {
        let (rp, dofs, mats) = (&self.ord.rp, self.dofs, self.mats);
        let RowBlock {
            r,
            len,
            nb,
            coff,
            blk,
            dr,
        } = row;
        let pr = rp[r];
        let pp = if pr.free {
            None
        } else {
            Some(&dofs[pr.p as usize])
        };
        for &i in self.ord.tris_of(r) {
            let rec = self.ord.trec[i as usize];
            let vx = rec.v.map(|v| &rp[v as usize]);
            let a = rec.v.iter().position(|&v| v as usize == r).unwrap_or(0);
            let mi = rec.mat as usize;
            let pts = vx.map(|x| x.x);
            // ke[b][i][j]: row D a + i, column D b + j of the element matrix.
            let ke = mats.cell_rows(&pts, mi, a);
            let mut fe = mats.cell_load(&pts, mi, a);
            // fe − Ke u0
            for (k, fk) in fe.iter_mut().enumerate() {
                for b in 0..N {
                    if vx[b].free {
                        continue;
                    }
                    let u0 = dofs[vx[b].p as usize].u0;
                    *fk -= dot(&ke[b][k], &u0);
                }
            }
            match pp {
                None => {
                    for (dk, fk) in dr.iter_mut().zip(fe) {
                        *dk += fk;
                    }
                }
                Some(pp) => {
                    for (dk, ta) in dr.iter_mut().zip(&pp.t[..pp.ndof]) {
                        *dk += dot(ta, &fe);
                    }
                }
            }
            for b in 0..N {
                if vx[b].ndof == 0 {
                    continue;
                }
                let col = nb
                    .iter()
                    .position(|&q| q == rec.v[b])
                    .map(|k| coff[k])
                    .unwrap_or(0);
                match pp {
                    None if vx[b].free => {
                        for (i, kbi) in ke[b].iter().enumerate() {
                            for (j, v) in kbi.iter().enumerate() {
                                blk[i * len + col + j] += v;
                            }
                        }
                    }
                    _ => {
                        let pa = &dofs[pr.p as usize];
                        let pb = &dofs[vx[b].p as usize];
                        for ka in 0..pa.ndof {
                            let ta = pa.t[ka];
                            let row = ka * len + col;
                            for kb in 0..pb.ndof {
                                let tb = pb.t[kb];
                                // Σ_i ta_i (Σ_j ke_ij tb_j)
                                let ktb: [f64; D] = std::array::from_fn(|i| dot(&ke[b][i], &tb));
                                blk[row + kb] += dot(&ta, &ktb);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// a·b summed from the first component on (a0 b0 + a1 b1 in the plane:
/// the order that fixes the 2D bits).
#[inline]
fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    let mut s = a[0] * b[0];
    for k in 1..D {
        s += a[k] * b[k];
    }
    s
}

/// The row block of one rank being filled: its `len` columns per row, the
/// neighbours `nb` and the offset of each one's columns (`coff`), the
/// values (ndof rows of `len`) and d.
struct RowBlock<'a> {
    r: usize,
    len: usize,
    nb: &'a [u32],
    coff: &'a [usize],
    blk: &'a mut [f64],
    dr: &'a mut [f64],
}

/// Split C's indices and values and d into `threads` disjoint ranges of
/// rows of whole points, each with about 1/threads of the entries.
fn targets<'a, const D: usize>(
    dofs: &[PointDofs<D>],
    indptr: &[usize],
    threads: usize,
    indices: &'a mut [usize],
    data: &'a mut [f64],
    d: &'a mut [f64],
) -> Vec<Target<'a>> {
    let (n, nnz) = (d.len(), indptr[d.len()]);
    let mut targets = Vec::with_capacity(threads);
    let (mut ind_rest, mut dat_rest, mut d_rest) = (indices, data, d);
    let (mut lo, mut off) = (0usize, 0usize);
    for k in 1..=threads {
        // The rows [lo, hi) of whole points, with about k/threads of the
        // entries.
        let hi = if k == threads {
            n
        } else {
            let q = dofs.partition_point(|pd| indptr[pd.start] < nnz / threads * k);
            dofs.get(q).map(|pd| pd.start).unwrap_or(n).max(lo)
        };
        let end = indptr[hi];
        let (ind, ir) = std::mem::take(&mut ind_rest).split_at_mut(end - off);
        let (dat, dr) = std::mem::take(&mut dat_rest).split_at_mut(end - off);
        let (dd, ddr) = std::mem::take(&mut d_rest).split_at_mut(hi - lo);
        ind_rest = ir;
        dat_rest = dr;
        d_rest = ddr;
        targets.push(Target {
            rows: lo..hi,
            off,
            ind,
            dat,
            d: dd,
        });
        lo = hi;
        off = end;
    }
    targets
}

/// Copy the blocks `out` of the chunks `round` that fall in `t`'s rows.
fn copy_blocks<const D: usize>(
    rp: &[RankPoint<D>],
    indptr: &[usize],
    round: &[(usize, usize)],
    out: &[Block],
    t: &mut Target,
) {
    for (&(s, e), b) in round.iter().zip(out) {
        for (i, &x) in rp[s..e].iter().enumerate() {
            let k = x.ndof as usize;
            if k == 0 || !t.rows.contains(&x.start) {
                continue;
            }
            let (b0, b1) = (b.at[i], b.at[i + 1]);
            let i0 = indptr[x.start] - t.off;
            let i1 = i0 + (b1 - b0);
            t.ind[i0..i1].copy_from_slice(&b.cols[b0..b1]);
            t.dat[i0..i1].copy_from_slice(&b.vals[b0..b1]);
            let (d0, dk) = (x.start - t.rows.start, D * i);
            t.d[d0..d0 + k].copy_from_slice(&b.d[dk..dk + k]);
        }
    }
}

/// C and the element part of d for the `n` unknowns of `dofs`, on rayon's
/// threads if `parallel` (the result is the same bit for bit).
pub(super) fn assemble<const D: usize, const N: usize>(
    topo: Cells<D, N>,
    dofs: &[PointDofs<D>],
    n: usize,
    mats: &Materials<D>,
    parallel: bool,
) -> (Csr, Vec<f64>) {
    let np = topo.points.len();
    let mut lap = super::Lap::new("fem::stiffness");
    let ord = Order::new(topo, dofs, parallel, &mut lap);
    let chunks: Vec<(usize, usize)> = (0..np)
        .step_by(CHUNK_POINTS)
        .map(|s| (s, (s + CHUNK_POINTS).min(np)))
        .collect();
    let parts: Vec<Nbrs> = map_items(parallel, chunks.clone(), |c| neighbours(&ord, c));
    lap.lap("neighbours");
    let indptr = row_pointers(&ord, &parts, dofs, n);
    let nnz = indptr[n];
    lap.lap("row pointers");
    // Pass 2: each chunk's row blocks into its own buffers, a few chunks
    // per thread at a time, then copied to their place.
    let gather = Gather {
        ord: &ord,
        parts: &parts,
        dofs,
        mats,
    };
    let mut indices = vec![0usize; nnz];
    let mut data = vec![0.0f64; nnz];
    let mut d = vec![0.0f64; n];
    let threads = if parallel {
        rayon::current_num_threads().max(1)
    } else {
        1
    };
    // The copy goes to `threads` disjoint ranges of DOFs, each scanning
    // the round's blocks for its own points.
    let mut tgts = targets(dofs, &indptr, threads, &mut indices, &mut data, &mut d);
    let per_round = 2 * threads;
    let mut pool: Vec<Block> = (0..per_round).map(|_| Block::default()).collect();
    for round in chunks.chunks(per_round) {
        let items: Vec<_> = round.iter().copied().zip(pool.drain(..)).collect();
        let out = map_items(parallel, items, |(c, buf)| gather.block(c, buf));
        for_each_mut(parallel, &mut tgts, |t| {
            copy_blocks(&ord.rp, &indptr, round, &out, t)
        });
        pool = out;
    }
    drop(tgts);
    lap.lap("values");
    let c = Csr {
        nrows: n,
        ncols: n,
        indptr: indptr.into(),
        indices: indices.into(),
        data: data.into(),
    };
    (c, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The former assembly: 36 triplets per triangle, then
    /// `Csr::from_triplets` (the reference for the gathered assembly).
    fn reference_stiffness(
        topo: &Topology,
        dofs: &[PointDofs],
        n: usize,
        mats: &Materials,
    ) -> (Csr, Vec<f64>) {
        let (bforce, th) = (&mats.bforce, mats.kind.thickness());
        let mut trip: Vec<(usize, usize, f64)> = Vec::with_capacity(topo.triangles.len() * 36);
        let mut d = vec![0.0; n];
        for (t, tri) in topo.triangles.iter().enumerate() {
            let mi = topo.tri_material[t] as usize;
            let pts = [
                topo.points[tri[0]],
                topo.points[tri[1]],
                topo.points[tri[2]],
            ];
            let ke = mats.kind.stiffness(&pts, &mats.dmats[mi]);
            let area = super::super::element::area2(&pts) / 2.0;
            let fb = bforce[mi];
            let mut fe = [0.0; 6];
            for a in 0..3 {
                fe[2 * a] = th * area / 3.0 * fb[0];
                fe[2 * a + 1] = th * area / 3.0 * fb[1];
            }
            for i in 0..6 {
                for b in 0..3 {
                    let u0 = dofs[tri[b]].u0;
                    fe[i] -= ke[i][2 * b] * u0[0] + ke[i][2 * b + 1] * u0[1];
                }
            }
            for a in 0..3 {
                let pa = dofs[tri[a]];
                for ka in 0..pa.ndof {
                    let ta = pa.t[ka];
                    let ia = pa.start + ka;
                    d[ia] += ta[0] * fe[2 * a] + ta[1] * fe[2 * a + 1];
                    for b in 0..3 {
                        let pb = dofs[tri[b]];
                        for kb in 0..pb.ndof {
                            let tb = pb.t[kb];
                            let v = ta[0]
                                * (ke[2 * a][2 * b] * tb[0] + ke[2 * a][2 * b + 1] * tb[1])
                                + ta[1]
                                    * (ke[2 * a + 1][2 * b] * tb[0]
                                        + ke[2 * a + 1][2 * b + 1] * tb[1]);
                            trip.push((ia, pb.start + kb, v));
                        }
                    }
                }
            }
        }
        (Csr::from_triplets(n, n, &trip), d)
    }

    #[test]
    fn gathered_assembly_matches_triplets_on_shipped_models() {
        for (path, problem, mesh) in crate::shipped_examples() {
            let m = super::super::build(&mesh, &problem).unwrap();
            let mats = Materials::new(&m.topo, &problem.file.materials, &problem.file.model);
            let n = m.qp.n();
            let (cr, dr) = reference_stiffness(&m.topo, &m.dofs, n, &mats);
            let (cs, ds) = assemble(Cells::plane(&m.topo), &m.dofs, n, &mats, false);
            let (cp, dp) = assemble(Cells::plane(&m.topo), &m.dofs, n, &mats, true);
            // Threads change nothing, bit for bit.
            assert_eq!(cs, cp, "{}", path.display());
            assert_eq!(ds, dp);
            // Same pattern; values equal up to the order of summation.
            assert_eq!(cs.indptr, cr.indptr, "{}", path.display());
            assert_eq!(cs.indices, cr.indices, "{}", path.display());
            let cmax = cr.data.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (x, y) in cs.data.iter().zip(&cr.data) {
                assert!(
                    (x - y).abs() <= 1e-14 * cmax,
                    "{}: {x} vs {y}",
                    path.display()
                );
            }
            // d is summed in triangle order in both: bit for bit.
            assert_eq!(ds, dr, "{}", path.display());
        }
    }
}
