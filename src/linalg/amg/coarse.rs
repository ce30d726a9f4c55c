//! A coarse level as a space of its own (docs/methods.md §7.2, "The
//! coarse start"): the composite prolongator P = P_0⋯P_{l−1} from level l's
//! unknowns to the fine ones, its transpose applied to vectors and to
//! sparse rows, and level l's Galerkin operator PᵀKP (level 0 is the fine
//! one, level `levels() − 1` the coarsest). A caller may
//! solve a small problem there (the contact problem restricted to the
//! coarse space) and carry its answer to the fine level; the hierarchy
//! itself is not changed.

use super::{kernels::for_rows, Amg};

impl Amg {
    /// Level l's operator PᵀKP, dense and row-major (`sizes()[l]`² values).
    pub fn level_dense(&self, l: usize) -> Vec<f64> {
        let nc = self.sizes()[l];
        let mut dense = vec![0.0; nc * nc];
        for i in 0..nc {
            for (j, x) in self.level_row(l, i) {
                dense[i * nc + j] = x;
            }
        }
        dense
    }

    /// Level l's operator PᵀKP as (row, column, value) triplets, row by
    /// row (for a sparse factor of a level too large for a dense one).
    pub fn level_triplets(&self, l: usize) -> Vec<(usize, usize, f64)> {
        let nc = self.sizes()[l];
        (0..nc)
            .flat_map(|i| {
                self.level_row(l, i)
                    .into_iter()
                    .map(move |(j, x)| (i, j, x))
            })
            .collect()
    }

    /// Row i of level l's operator: (column, value), columns sorted.
    fn level_row(&self, l: usize, i: usize) -> Vec<(usize, f64)> {
        match self.levels.get(l) {
            Some(lev) => {
                let (c, v) = lev.a.row(i);
                c.iter()
                    .map(|&j| j as usize)
                    .zip(v.iter().copied())
                    .collect()
            }
            None => {
                let (c, v) = self.coarse_a.row(i);
                c.iter().copied().zip(v.iter().copied()).collect()
            }
        }
    }

    /// Pᵀr: a fine vector restricted to level l.
    pub fn restrict_to_level(&self, l: usize, r: &[f64]) -> Vec<f64> {
        let mut cur = r.to_vec();
        for lev in &self.levels[..l] {
            let mut next = vec![0.0; lev.pt.nrows];
            let src = &cur;
            for_rows(&mut next, |j, nj| *nj = lev.pt.row_dot(j, src));
            cur = next;
        }
        cur
    }

    /// Py: a vector of level l carried to the fine level.
    pub fn prolong_from_level(&self, l: usize, y: &[f64]) -> Vec<f64> {
        let mut cur = y.to_vec();
        for lev in self.levels[..l].iter().rev() {
            let mut next = vec![0.0; lev.p.nrows];
            let src = &cur;
            for_rows(&mut next, |i, xi| *xi = lev.p.row_dot(i, src));
            cur = next;
        }
        cur
    }

    /// Pᵀu for a sparse fine row u (columns, values): the row on level l,
    /// columns sorted.
    pub fn restrict_row_to_level(
        &self,
        l: usize,
        cols: &[usize],
        vals: &[f64],
    ) -> Vec<(usize, f64)> {
        let mut u: Vec<(usize, f64)> = cols.iter().copied().zip(vals.iter().copied()).collect();
        let mut scratch = Scratch::default();
        for k in 0..l {
            u = self.restrict_row_one(k, &u, &mut scratch);
        }
        u
    }

    /// P_lᵀu for a sparse row u on level l: Σ_k u_k · (row k of P_l),
    /// columns sorted (also the update's restriction, `update.rs`).
    pub(super) fn restrict_row_one(
        &self,
        l: usize,
        u: &[(usize, f64)],
        s: &mut Scratch,
    ) -> Vec<(usize, f64)> {
        let p = &self.levels[l].p;
        let nc = self.levels.get(l + 1).map_or(self.coarse_n, |n| n.a.nrows);
        if s.acc.len() < nc {
            s.acc.resize(nc, 0.0);
            s.mark.resize(nc, false);
        }
        let mut touched: Vec<usize> = Vec::new();
        for &(kk, uk) in u {
            let (c, v) = p.row(kk);
            for (&j, &pj) in c.iter().zip(v) {
                let j = j as usize;
                if !s.mark[j] {
                    s.mark[j] = true;
                    s.acc[j] = 0.0;
                    touched.push(j);
                }
                s.acc[j] += uk * pj;
            }
        }
        touched.sort_unstable();
        let v: Vec<(usize, f64)> = touched.iter().map(|&j| (j, s.acc[j])).collect();
        for &j in &touched {
            s.mark[j] = false;
        }
        v
    }
}

/// Work arrays of [`Amg::restrict_row_one`], kept across rows.
#[derive(Default)]
pub(super) struct Scratch {
    acc: Vec<f64>,
    mark: Vec<bool>,
}
