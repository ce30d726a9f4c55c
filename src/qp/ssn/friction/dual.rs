//! ssn's frictional working sets in the dual space on one bordered factor
//! of C ([`Dual`], docs/methods.md §9.2).

use super::*;

/// The most rows of B = [A; T] whose dense H = B K⁻¹Bᵀ is formed (8·8192²
/// bytes, 512 MiB); more take the sparse path.
pub(super) const DUAL_ROWS_MAX: usize = 8192;

/// The largest border of B = [A; T] eliminated last, per √n: four times
/// the frictionless path's ([`super::super::BORDER_RATIO`]). Its dense
/// factor costs nb³/3 once, where the sparse path refactors K = C + ρBᵀB
/// at every Newton step and has neither the coarse start nor the direct
/// Coulomb iteration: a shrink fit with thin walls (5.8 k nodes, 641 rows,
/// a border of 2 304 = 21·√n) took 341 Newton steps and 7.3 times the
/// frictionless run there (docs/methods.md §9.2).
const BORDER_RATIO: f64 = 4.0 * super::super::BORDER_RATIO;

/// A row of B with H_jj ≤ NULL_ROW · max H holds nothing ([`Dual`]).
pub(super) const NULL_ROW: f64 = 1e-14;

/// The working-set solves in the dual space (docs/methods.md §9.2): one
/// bordered factor of C (+ springs on a floating body's fixing unknowns,
/// K) with every unknown B = [A; T] touches eliminated last, whose trailing
/// block gives all of H = B K⁻¹Bᵀ at once (§7). A working set's
/// equality-constrained problem is then a dense system on its rows, with
/// the FETI coarse problem for the rigid motions; x is one backward pass
/// (`Cholesky::finish`), formed only for an answer that is returned. The
/// factor does not change between Newton steps, Tresca solves or load
/// steps (the workspace keeps it), where K = C + ρBᵀB was refactored at
/// every Newton step and solved by augmented Lagrangian sweeps.
pub(super) struct Dual {
    /// B = [A; T], 2m × n.
    pub(super) b: Csr,
    pub(super) fac: Cholesky,
    /// The forward half of K⁻¹d.
    pub(super) fwd: Forward,
    /// H and what the working-set solves read with it.
    pub(super) dense: DenseDual,
    /// Sparse solves it took (counted as inner iterations).
    pub(super) solves: usize,
}

/// A Dual is its dense part (what every working-set solve reads) and the
/// factor that forms x.
impl std::ops::Deref for Dual {
    type Target = DenseDual;
    fn deref(&self) -> &DenseDual {
        &self.dense
    }
}

/// The dual form of a frictional problem without its sparse factor: H,
/// B K⁻¹d, B R and Rᵀd over the rows of B = [A; T] (the first half normal
/// rows, the second their tangential rows). The problem's own rows come
/// from [`Dual::new`]; a coarse level's ([`super::nested`]) are sums of them.
pub(super) struct DenseDual {
    /// H = B K⁻¹Bᵀ, 2m × 2m (shared with the workspace's [`KeptDual`]).
    pub(super) h: std::rc::Rc<Mat<f64>>,
    /// B K⁻¹d.
    pub(super) bk0: Vec<f64>,
    /// (B R)ᵢₗ by rows, 2m × k.
    pub(super) br: Vec<Vec<f64>>,
    /// e = Rᵀd.
    pub(super) e: Vec<f64>,
    /// Rows of B that hold nothing (H_jj = 0: a tangential row on a line
    /// of symmetry, whose unknown is eliminated): left out of every
    /// working set's system, their multiplier 0.
    pub(super) null: Vec<bool>,
    /// The LU of the last Coulomb system solved on this H, for the next
    /// Newton step's ([`super::update`]; systems of
    /// [`super::update::UPDATE_MIN`] unknowns or more).
    pub(super) last_lu: std::cell::RefCell<Option<super::update::Factored>>,
}

/// The law a working set is solved under ([`DenseDual::set_solve`]).
#[derive(Clone, Copy)]
pub(super) enum Law<'a> {
    /// Coulomb's problem with its bound inside: a slipping row's force is
    /// μᵢσᵢλ_nᵢ (these μ).
    Coulomb(&'a [f64]),
    /// A Tresca problem with these bounds; glued: the slipping (open) rows
    /// carry no force.
    Tresca { s: &'a [f64], glued: bool },
}

/// The multipliers of a working set solved in the dual space.
pub(super) struct SetSolution {
    /// [λ_n; λ_t] over every row.
    pub(super) mu: Vec<f64>,
    pub(super) alpha: Vec<f64>,
    /// The rows of B in the working set's system.
    pub(super) rows: Vec<usize>,
}

/// What [`Dual::new`] derives from C, A, T and ker C alone, kept in the
/// workspace for the next solve of the same matrices (a load step): H.
pub(crate) struct KeptDual {
    /// C, A and T (clones share their arrays).
    c: Csr,
    a: Csr,
    t: Csr,
    /// [`crate::linalg::cholesky::matrix_key`] of ker C's basis.
    kernel_key: u64,
    h: std::rc::Rc<Mat<f64>>,
}

/// The workspace slot of [`KeptDual`].
const KEPT_DUAL_TAG: u64 = 0x7373_6e5f_6672_6963;

impl KeptDual {
    /// Whether `qp` has the matrices H was derived from: the same arrays
    /// (a load step's model shares them), else equal values.
    fn matches(&self, qp: &QpProblem, fr: &Friction, kernel_key: u64) -> bool {
        self.kernel_key == kernel_key
            && self.c.same_as(&qp.c)
            && self.a.same_as(&qp.a)
            && self.t.same_as(&fr.t)
    }
}

impl Dual {
    /// The dual form of `qp`, or None when the border of B is too large for
    /// a dense trailing block (the limits of the frictionless path,
    /// [`super::small_border`]) or H would be.
    pub(super) fn new(
        qp: &QpProblem,
        fr: &Friction,
        r: &[Vec<f64>],
        ws: &crate::linalg::cholesky::Workspace,
    ) -> Result<Option<Dual>, QpError> {
        let (n, m) = (qp.n(), qp.m());
        // B's rows: m normal, then T's (m on a line, 2m in a plane frame).
        let mb = m + fr.t.nrows;
        if m == 0 || mb > DUAL_ROWS_MAX {
            log::debug!(
                "ssn: friction: the sparse path: {mb} rows of B = [A; T] (the dense dual form takes 1 to {DUAL_ROWS_MAX}); no coarse start"
            );
            return Ok(None);
        }
        let mut trip = Vec::with_capacity(qp.a.nnz() + fr.t.nnz());
        for (off, mat) in [(0, &qp.a), (m, &fr.t)] {
            for i in 0..mat.nrows {
                let (cols, vals) = mat.row(i);
                trip.extend(cols.iter().zip(vals).map(|(&j, &v)| (off + i, j, v)));
            }
        }
        let b = Csr::from_triplets(mb, n, &trip);
        let rb = RowBorder::new(&qp.c, &qp.kernel, &b);
        let nb = rb.len();
        log::debug!("ssn: friction: border of B = [A; T]: {nb} unknowns");
        if nb as f64 > BORDER_RATIO * (n as f64).sqrt() || nb > super::super::BORDER_MAX {
            log::debug!(
                "ssn: friction: the sparse path: a border of {nb} unknowns exceeds {} (BORDER_RATIO·√n) or {}; no coarse start, the glued start",
                (BORDER_RATIO * (n as f64).sqrt()) as usize,
                super::super::BORDER_MAX
            );
            return Ok(None);
        }
        let t0 = std::time::Instant::now();
        let fac = ws.cholesky_rows(&qp.c, &qp.kernel, &rb)?;
        let t_fac = t0.elapsed().as_secs_f64();
        let skip = || {
            log::debug!("ssn: friction: the sparse path: the bordered factor gives no dense H; no coarse start")
        };
        // H depends on C, A, T and ker C alone: a load step of the same
        // model takes the last step's (the same bits a fresh one has).
        let kernel_key = crate::linalg::cholesky::matrix_key(&[], &qp.kernel);
        let kept = ws
            .kept::<KeptDual>(KEPT_DUAL_TAG)
            .filter(|k| k.matches(qp, fr, kernel_key));
        let h = match kept {
            Some(k) => {
                log::debug!("ssn: friction: H of the last solve of the same matrices");
                k.h.clone()
            }
            None => {
                let Some(h) = fac.border_inverse(&b) else {
                    skip();
                    return Ok(None);
                };
                let h = std::rc::Rc::new(h);
                ws.keep(
                    KEPT_DUAL_TAG,
                    std::rc::Rc::new(KeptDual {
                        c: qp.c.clone(),
                        a: qp.a.clone(),
                        t: fr.t.clone(),
                        kernel_key,
                        h: h.clone(),
                    }),
                );
                h
            }
        };
        let Some(fwd) = fac.forward(&qp.d) else {
            skip();
            return Ok(None);
        };
        let Some(bk0) = fac.border_product(&fwd, &b) else {
            skip();
            return Ok(None);
        };
        let br = (0..mb)
            .map(|i| r.iter().map(|rl| b.row_dot(i, rl)).collect())
            .collect();
        let e = r.iter().map(|rl| dot(rl, &qp.d)).collect();
        log::debug!(
            "ssn: friction: dual form: bordered factor {t_fac:.3} s, H and B K⁻¹d {:.3} s",
            t0.elapsed().as_secs_f64() - t_fac
        );
        let hmax = (0..mb).fold(0.0f64, |a, j| a.max(h[(j, j)]));
        let null = (0..mb).map(|j| !(h[(j, j)] > NULL_ROW * hmax)).collect();
        Ok(Some(Dual {
            b,
            fac,
            fwd,
            dense: DenseDual {
                h,
                bk0,
                br,
                e,
                null,
                last_lu: Default::default(),
            },
            solves: 1,
        }))
    }

    /// x = K⁻¹(d − Bᵀμ) + Rα: one backward pass.
    pub(super) fn x(&self, mu: &[f64], alpha: &[f64], r: &[Vec<f64>]) -> Option<Vec<f64>> {
        let mut x = self.fac.finish(&self.fwd, &self.b, mu)?;
        for (rl, &al) in r.iter().zip(alpha) {
            for (xi, ri) in x.iter_mut().zip(rl) {
                *xi += al * ri;
            }
        }
        Some(x)
    }
}

impl DenseDual {
    /// Rows of B (half of them normal).
    pub(super) fn m(&self) -> usize {
        self.bk0.len() / 2
    }

    /// Solve the working set (`in_n`, `tang`) under `law` with c = [g; t0]:
    /// the normal rows in N and the sticking tangential rows are held, a
    /// slipping row carries its known force (docs/methods.md §9.2). None
    /// if its system is singular.
    pub(super) fn set_solve(
        &self,
        in_n: &[bool],
        tang: &[Tangential],
        law: Law<'_>,
        c: &[f64],
    ) -> Option<SetSolution> {
        let m = self.m();
        let stick = (0..m)
            .filter(|&i| tang[i] == Tangential::Stick && !self.null[m + i])
            .map(|i| m + i);
        match law {
            Law::Coulomb(mu_c) => {
                let normal: Vec<(usize, f64)> = (0..m)
                    .filter(|&i| in_n[i] && !self.null[i])
                    .map(|i| match tang[i] {
                        Tangential::Slip(pos) => (i, if pos { mu_c[i] } else { -mu_c[i] }),
                        Tangential::Stick => (i, 0.0),
                    })
                    .collect();
                let stick: Vec<usize> = stick.collect();
                let (mu, alpha) = self.solve_coulomb(&normal, &stick, c)?;
                let rows = normal.iter().map(|&(i, _)| i).chain(stick).collect();
                Some(SetSolution { mu, alpha, rows })
            }
            Law::Tresca { s, glued } => {
                let rows: Vec<usize> = (0..m)
                    .filter(|&i| in_n[i] && !self.null[i])
                    .chain(stick)
                    .collect();
                let mut f = vec![0.0; 2 * m];
                if !glued {
                    for i in 0..m {
                        if let Tangential::Slip(pos) = tang[i] {
                            f[m + i] = if pos { s[i] } else { -s[i] };
                        }
                    }
                }
                let (w, alpha) = self.solve(&rows, &f, &self.bk0, c, &self.e)?;
                let mut mu = f;
                for (&j, wj) in rows.iter().zip(w) {
                    mu[j] = wj;
                }
                Some(SetSolution { mu, alpha, rows })
            }
        }
    }

    /// The multipliers of the working set `rows` (indices into B's rows)
    /// with the known forces `f` (2m; zero on `rows`): μ_J and α from
    /// H_JJ μ_J − (BR)_J α = (BK⁻¹b − c − H f)_J and (BR)_Jᵀμ_J = Rᵀb −
    /// (BR)ᵀf, given `bkb` = BK⁻¹b and `e` = Rᵀb (b = d and c = [g; t0]
    /// for a step; the residuals for a refinement). A rigid motion the rows
    /// leave free (a singular coarse matrix) gets no α: the step is solved
    /// as if it were held, as the sparse path regularises K along it. None
    /// if H_JJ is singular.
    pub(super) fn solve(
        &self,
        rows: &[usize],
        f: &[f64],
        bkb: &[f64],
        c: &[f64],
        e: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let nj = rows.len();
        let k = e.len();
        let h = &self.h;
        let fl: Vec<(usize, f64)> = f
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(l, &v)| (l, v))
            .collect();
        let hjj = Mat::from_fn(
            nj,
            nj,
            |a, b| {
                if b <= a {
                    h[(rows[a], rows[b])]
                } else {
                    0.0
                }
            },
        );
        let rhs = Mat::from_fn(nj, 1 + k, |t, col| {
            let j = rows[t];
            if col == 0 {
                // H is symmetric: read column j.
                bkb[j] - c[j] - fl.iter().map(|&(l, v)| h[(l, j)] * v).sum::<f64>()
            } else {
                self.br[j][col - 1]
            }
        });
        let q0: Vec<f64> = (0..k)
            .map(|l| e[l] - fl.iter().map(|&(j, v)| self.br[j][l] * v).sum::<f64>())
            .collect();
        solve_dense(hjj, rhs, |t, l| self.br[rows[t]][l], q0)
    }

    /// The multipliers of a working set whose rows are combinations of
    /// B's rows (a plane frame's slipping row holds e⊥·T_i, docs/methods.md
    /// §12.3), each with a compliance κ (its multiplier μ moves it by κμ:
    /// W_J B x − c_J = κμ_J), under the known forces `f` on B's rows: μ_J
    /// and α from (W H Wᵀ + κ)_JJ μ_J − (W B R)_J α = W_J(BK⁻¹d − H f) − c_J
    /// and (W B R)_Jᵀμ_J = Rᵀd − (BR)ᵀf. None if the system is singular.
    pub(super) fn solve_rows(&self, rows: &[DualRow], f: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        if rows.iter().any(|r| !r.force.is_empty()) {
            return self.solve_rows_coupled(rows, f);
        }
        let nj = rows.len();
        let k = self.e.len();
        let h = &self.h;
        let fl: Vec<(usize, f64)> = f
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(l, &v)| (l, v))
            .collect();
        // (H f)_j on the rows the working set reads.
        let mut hf = vec![0.0; f.len()];
        for r in rows {
            for &(j, _) in &r.terms {
                hf[j] = fl.iter().map(|&(l, v)| h[(l, j)] * v).sum::<f64>();
            }
        }
        let hjj = Mat::from_fn(nj, nj, |a, b| {
            if b > a {
                return 0.0;
            }
            let mut v: f64 = rows[a]
                .terms
                .iter()
                .map(|&(p, wp)| {
                    rows[b]
                        .terms
                        .iter()
                        .map(|&(q, wq)| wp * wq * h[(p, q)])
                        .sum::<f64>()
                })
                .sum();
            if a == b {
                v += rows[a].kappa;
            }
            v
        });
        let brj = |t: usize, l: usize| -> f64 {
            rows[t].terms.iter().map(|&(j, w)| w * self.br[j][l]).sum()
        };
        let rhs = Mat::from_fn(nj, 1 + k, |t, col| {
            if col == 0 {
                rows[t]
                    .terms
                    .iter()
                    .map(|&(j, w)| w * (self.bk0[j] - hf[j]))
                    .sum::<f64>()
                    - rows[t].c
            } else {
                brj(t, col - 1)
            }
        });
        let q0: Vec<f64> = (0..k)
            .map(|l| self.e[l] - fl.iter().map(|&(j, v)| self.br[j][l] * v).sum::<f64>())
            .collect();
        solve_dense(hjj, rhs, brj, q0)
    }

    /// The multipliers of a working set of Coulomb's problem with the slip
    /// bound inside (docs/methods.md §9.2): the normal rows `normal` (row
    /// i of A with κᵢ = μᵢσᵢ when its tangential row slips along σᵢ, else
    /// 0: λ_tᵢ = κᵢλ_nᵢ, a force the unknown λ_nᵢ sets), the stick rows
    /// `stick` (indices into B) and the rigid motions: (B x)_E = c_E on the
    /// rows E = normal ∪ stick and the equilibrium Rᵀ(d − Bᵀμ) = 0, a
    /// nonsymmetric system (the slip forces' columns) solved by LU with
    /// the coarse unknowns scaled to H's size. Returns μ over every row and
    /// α; None if the system is singular to working precision.
    pub(super) fn solve_coulomb(
        &self,
        normal: &[(usize, f64)],
        stick: &[usize],
        c: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let m = self.bk0.len() / 2;
        let k = self.e.len();
        let (nn, q) = (normal.len(), normal.len() + stick.len());
        let size = q + k;
        let h = &self.h;
        let hs = (0..2 * m)
            .fold(0.0f64, |a, j| a.max(h[(j, j)]))
            .max(f64::MIN_POSITIVE);
        let erow = |e: usize| if e < nn { normal[e].0 } else { stick[e - nn] };
        // Column p of H P (P: unknowns to multipliers), read by rows.
        let col = |re: usize, p: usize| -> f64 {
            if p < nn {
                let (i, kappa) = normal[p];
                let mut v = h[(i, re)];
                if kappa != 0.0 {
                    v += kappa * h[(m + i, re)];
                }
                v
            } else {
                h[(stick[p - nn], re)]
            }
        };
        let brp = |p: usize, l: usize| -> f64 {
            if p < nn {
                let (i, kappa) = normal[p];
                self.br[i][l] + kappa * self.br[m + i][l]
            } else {
                self.br[stick[p - nn]][l]
            }
        };
        let mut w = vec![0.0; size * size];
        let mut rhs = vec![0.0; size];
        for e in 0..q {
            let re = erow(e);
            for p in 0..q {
                w[e * size + p] = col(re, p);
            }
            for l in 0..k {
                w[e * size + q + l] = -self.br[re][l] * hs;
            }
            rhs[e] = self.bk0[re] - c[re];
        }
        for l in 0..k {
            for p in 0..q {
                w[(q + l) * size + p] = brp(p, l) * hs;
            }
            rhs[q + l] = self.e[l] * hs;
        }
        let mut last = self.last_lu.borrow_mut();
        if size >= super::update::UPDATE_MIN {
            // The unknowns' keys (rows of B; 2m + l for α_l) and slip factors.
            let keys: Vec<usize> = (0..q).map(erow).chain((0..k).map(|l| 2 * m + l)).collect();
            let kappa: Vec<f64> = (0..size)
                .map(|p| if p < nn { normal[p].1 } else { 0.0 })
                .collect();
            let changed = last
                .as_ref()
                .and_then(|f| f.solve_changed(&keys, &kappa, &w, &rhs, hs));
            if let Some((x, rank)) = changed {
                log::debug!(
                    "ssn: friction: the Coulomb system as a rank-{rank} change of the last LU"
                );
                rhs = x;
            } else {
                let lu = crate::linalg::dense::Lu::from_row_major(&w, size)?;
                lu.solve_in_place(&mut rhs);
                *last = Some(super::update::Factored::new(keys, kappa, w, lu, hs));
            }
        } else {
            let lu = crate::linalg::dense::Lu::from_row_major(&w, size)?;
            lu.solve_in_place(&mut rhs);
        }
        drop(last);
        if !rhs.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut mu = vec![0.0; 2 * m];
        for (p, &(i, kappa)) in normal.iter().enumerate() {
            mu[i] = rhs[p];
            mu[m + i] = kappa * rhs[p];
        }
        for (p, &t) in stick.iter().enumerate() {
            mu[t] = rhs[nn + p];
        }
        let alpha = rhs[q..].iter().map(|a| a * hs).collect();
        Some((mu, alpha))
    }

    /// [`DenseDual::solve_rows`] with rows whose multipliers also set
    /// forces on other rows (`DualRow::force`): the force of unknown b is
    /// F_b = W_b + its `force` terms, so μ = f + Σ w_b F_b, and the system
    /// (W H Fᵀ + diag κ) w − W(BR) α = W(b₀ − Hf) − c, (F BR)ᵀ w = q₀ is
    /// nonsymmetric: LU with the coarse unknowns scaled to H's size, as
    /// [`DenseDual::solve_coulomb`]. Returns the multipliers of the rows
    /// (their own terms; the caller adds the forces) and α; None if the
    /// system is singular to working precision (a rigid motion the rows
    /// leave free included: the step goes to the sparse path).
    fn solve_rows_coupled(&self, rows: &[DualRow], f: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let nj = rows.len();
        let k = self.e.len();
        let size = nj + k;
        let h = &self.h;
        let hs = (0..h.nrows())
            .fold(0.0f64, |a, j| a.max(h[(j, j)]))
            .max(f64::MIN_POSITIVE);
        let fl: Vec<(usize, f64)> = f
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(l, &v)| (l, v))
            .collect();
        let forces: Vec<Vec<(usize, f64)>> = rows
            .iter()
            .map(|r| r.terms.iter().chain(&r.force).copied().collect())
            .collect();
        let mut w = vec![0.0; size * size];
        let mut rhs = vec![0.0; size];
        for (a, ra) in rows.iter().enumerate() {
            for (b, fb) in forces.iter().enumerate() {
                let mut v: f64 = ra
                    .terms
                    .iter()
                    .map(|&(p, wp)| fb.iter().map(|&(q, wq)| wp * wq * h[(p, q)]).sum::<f64>())
                    .sum();
                if a == b {
                    v += ra.kappa;
                }
                w[a * size + b] = v;
            }
            for l in 0..k {
                let brl: f64 = ra.terms.iter().map(|&(j, wj)| wj * self.br[j][l]).sum();
                w[a * size + nj + l] = -brl * hs;
            }
            rhs[a] = ra
                .terms
                .iter()
                .map(|&(j, wj)| {
                    wj * (self.bk0[j] - fl.iter().map(|&(q, v)| h[(q, j)] * v).sum::<f64>())
                })
                .sum::<f64>()
                - ra.c;
        }
        for l in 0..k {
            for (b, fb) in forces.iter().enumerate() {
                let brl: f64 = fb.iter().map(|&(j, wj)| wj * self.br[j][l]).sum();
                w[(nj + l) * size + b] = brl * hs;
            }
            let q0 = self.e[l] - fl.iter().map(|&(j, v)| self.br[j][l] * v).sum::<f64>();
            rhs[nj + l] = q0 * hs;
        }
        let lu = crate::linalg::dense::Lu::from_row_major(&w, size)?;
        lu.solve_in_place(&mut rhs);
        if !rhs.iter().all(|v| v.is_finite()) {
            return None;
        }
        let alpha = rhs[nj..].iter().map(|a| a * hs).collect();
        rhs.truncate(nj);
        Some((rhs, alpha))
    }

    /// B x for the multipliers `mu` (2m) and α: B K⁻¹(d − Bᵀμ) + BRα.
    pub(super) fn bx(&self, mu: &[f64], alpha: &[f64]) -> Vec<f64> {
        let mut out = self.bk0.clone();
        for (l, &v) in mu.iter().enumerate().filter(|(_, v)| **v != 0.0) {
            for (o, hv) in out.iter_mut().zip(self.h.col(l).iter()) {
                *o -= v * hv;
            }
        }
        for (o, row) in out.iter_mut().zip(&self.br) {
            *o += row.iter().zip(alpha).map(|(a, b)| a * b).sum::<f64>();
        }
        out
    }
}

/// The dense core of a working set's dual solve: `hjj` (its lower
/// triangle), `rhs` = [r₀ | (BR)_J] and q₀ = Rᵀb − (BR)ᵀf give μ_J and α
/// (docs/methods.md §9.2): H_JJ μ_J − (BR)_J α = r₀, (BR)_Jᵀ μ_J = q₀. A
/// rigid motion the rows leave free (a singular coarse matrix F) gets no
/// α: the step is solved as if it were held, as the sparse path
/// regularises K along it. None if H_JJ is singular.
fn solve_dense(
    hjj: Mat<f64>,
    mut rhs: Mat<f64>,
    brj: impl Fn(usize, usize) -> f64,
    q0: Vec<f64>,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let nj = hjj.nrows();
    let k = q0.len();
    let fac = SpdFactor::new(hjj.as_ref())?;
    fac.solve_mat_in_place(rhs.as_mut());
    let mut w: Vec<f64> = rhs.col(0).iter().copied().collect();
    let mut alpha = vec![0.0; k];
    if k > 0 {
        // F = (BR)_Jᵀ Y, Y = H_JJ⁻¹(BR)_J; F α = q₀ − (BR)_Jᵀw.
        let mut fm = vec![vec![0.0; k]; k];
        for (a, row) in fm.iter_mut().enumerate() {
            for (b, v) in row.iter_mut().enumerate() {
                *v = (0..nj).map(|t| brj(t, a) * rhs[(t, 1 + b)]).sum();
            }
        }
        for a in 0..k {
            for b in 0..a {
                let v = 0.5 * (fm[a][b] + fm[b][a]);
                fm[a][b] = v;
                fm[b][a] = v;
            }
        }
        let mut q: Vec<f64> = (0..k)
            .map(|l| {
                let bw: f64 = (0..nj).map(|t| brj(t, l) * w[t]).sum();
                q0[l] - bw
            })
            .collect();
        // α = F⁺q: the motions null F leaves free get none.
        let (vals, vecs) = sym_eigen(&fm);
        let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut out = vec![0.0; k];
        for (lam, v) in vals.iter().zip(&vecs) {
            if !(lam.abs() > 1e-12 * top) {
                continue;
            }
            let p = dot(v, &q) / lam;
            for (o, vi) in out.iter_mut().zip(v) {
                *o += p * vi;
            }
        }
        q = out;
        for (t, wt) in w.iter_mut().enumerate() {
            *wt += (0..k).map(|l| rhs[(t, 1 + l)] * q[l]).sum::<f64>();
        }
        alpha = q;
    }
    if !w.iter().chain(&alpha).all(|v| v.is_finite()) {
        return None;
    }
    Some((w, alpha))
}

/// A row of a working set in the dual space ([`DenseDual::solve_rows`]):
/// Σ w·(row j of B) with its right-hand side c and compliance κ.
pub(super) struct DualRow {
    /// (j, w): at most two rows of B.
    pub(super) terms: Vec<(usize, f64)>,
    pub(super) c: f64,
    pub(super) kappa: f64,
    /// (j, w): forces the row's multiplier sets on other rows of B besides
    /// its own (a slipping row's μλ_n ê on its tangential pair when the
    /// slip bound is inside the step, docs/methods.md §12.3); empty
    /// otherwise.
    pub(super) force: Vec<(usize, f64)>,
}

/// A bordered factor that cannot finish a solve (it always can: B is its border).
pub(super) fn unfinished() -> QpError {
    QpError::BadParameter("ssn: the bordered factor of B = [A; T] cannot finish a solve".into())
}
