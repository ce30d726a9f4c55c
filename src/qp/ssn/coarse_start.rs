//! The coarse start of the iterative path (docs/methods.md §7.2, "The
//! coarse start"; solid models): the working set the Newton loop starts
//! from, found on a coarse level of the multigrid instead of grown from
//! the rows that touch.
//!
//! Grown from the one row that touches, J doubles per step under the growth
//! limit, so the loop took log₂(|J|/32) steps more on every refinement
//! (Hertz 45 k / 163 k / 306 k / 946 k unknowns: 6 / 8 / 8 / 11 Newton
//! steps). Here the contact problem is first solved in the coarse space of
//! the hierarchy built for the first K_J (P the composite prolongator,
//! K_c = PᵀK_JP, on the coarsest level with at least a thousandth of the
//! fine unknowns, [`LEVEL_RATIO`]):
//! every row restricted, v_j = Pᵀa_jᵀ, and each row that penetrates held
//! by its own penalty spring ρ_j (the rows of the first J are already
//! springs in K_J). The
//! restricted rows outnumber the coarse unknowns, so they cannot all be
//! equalities (the gaps of a set of them need not be reachable); a penalty
//! asks no such thing. Its active-set Newton steps (a row is active iff it
//! penetrates) each factor one matrix of the coarse size (dense up to
//! [`DENSE_MAX`] unknowns, sparse above). The fine
//! loop then starts from the rows that penetrate there, with x = Py and
//! λ_j = ρ_j·(v_jᵀy − g_j) on them, and decides and certifies as before: no
//! coarse answer enters the result.

use super::limit_changes;
use crate::linalg::amg::Amg;
use crate::linalg::cholesky::Workspace;
use crate::linalg::dense::SpdFactor;
use crate::linalg::sparse::Csr;
use crate::qp::QpProblem;
use std::collections::HashSet;

/// Active-set steps on the coarse level, at most (a repeated set ends them
/// earlier).
const COARSE_STEPS: usize = 40;
/// The coarse level is the coarsest with at least 1/LEVEL_RATIO of the
/// fine unknowns (Hertz 45 k / 163 k / 306 k / 946 k / 2.76 M: 246 / 714 /
/// 1 272 / 3 390 / 9 174 unknowns, 1/183 to 1/301 of the fine ones; the
/// coarsest level of 2.76 M, 288 unknowns, gave 10 Newton steps where 946 k
/// takes 6, and a level 1/10 of the fine one a stiffer start still).
const LEVEL_RATIO: usize = 1000;
/// Up to this many unknowns the coarse level is factored dense, above it
/// sparse (a level of a few thousand aggregates is a sparse 3D operator).
const DENSE_MAX: usize = 4000;
/// The coarse level has at most this many unknowns (a coarser one is taken).
const SPARSE_MAX: usize = 50_000;
/// Growth of J per step, on the coarse level and in the fine loop after a
/// coarse start: at most max(32, GROW·|J|) rows enter (`limit_changes`). The coarse J
/// falls short of the answer (a coarse space is stiffer: Hertz 45 k / 163 k
/// / 306 k, 38 / 95 / 120 rows of 161 / 388 / 594), and from there tripling
/// reaches it in two steps; the fine rows' first prediction overshoots by
/// half, and an overshoot shrinks by a ring of rows per step (Hertz 163 k
/// with no limit: 8 Newton steps and 93 CG steps; doubling 5 and 48;
/// tripling 5 and 42; where the coarse set is over a third of the answer
/// tripling overshoots, docs/methods.md §7.2).
pub(super) const GROW: usize = 2;

/// The coarse level's operator PᵀK_JP: dense (row-major) up to DENSE_MAX
/// unknowns, else sparse. Its pattern holds every restricted row's
/// v_jv_jᵀ (K_J's pattern holds every a_jᵀa_j, and the coarse patterns are
/// Galerkin products, docs/methods.md §7.2), so the springs of a step add
/// in place, and one symbolic analysis (kept in a [`Workspace`]) serves
/// every step (Hertz 2.76 M, 9 174 unknowns: 0.27 s of 1.7 s a step).
enum Level {
    Dense(Vec<f64>),
    Sparse(Csr, Workspace),
}

/// The start found on the coarse level.
pub(super) struct CoarseStart {
    pub in_j: Vec<bool>,
    pub x: Vec<f64>,
    pub lam: Vec<f64>,
    /// Coarse active-set steps taken.
    pub steps: usize,
    /// Unknowns of the level it was found on.
    pub unknowns: usize,
}

/// The coarse start (module doc) from the hierarchy `amg` of
/// K_J = C + Σ_{j∈J0} ρ_j a_ja_jᵀ, J0 = `j0`; `qp` supplies d, A and g
/// (its C is not read). None when the hierarchy has no coarse level of at
/// most SPARSE_MAX unknowns or a coarse matrix is not positive definite.
pub(super) fn coarse_start(
    amg: &Amg,
    qp: &QpProblem,
    j0: &[bool],
    rho: &[f64],
) -> Option<CoarseStart> {
    coarse_start_at(amg, qp, j0, rho, DENSE_MAX)
}

/// [`coarse_start`] with a dense factor of the coarse level up to
/// `dense_max` unknowns (a test compares the two factors).
fn coarse_start_at(
    amg: &Amg,
    qp: &QpProblem,
    j0: &[bool],
    rho: &[f64],
    dense_max: usize,
) -> Option<CoarseStart> {
    let sizes = amg.sizes();
    // The coarsest level with at least 1/LEVEL_RATIO of the fine unknowns
    // (the coarsest may hold a few aggregates only: Hertz at 946 k unknowns
    // has levels of 92 892, 3 390 and 132), else the finest coarse one; a
    // coarser one while it is above SPARSE_MAX.
    let mut l = (1..sizes.len())
        .rev()
        .find(|&l| sizes[l] * LEVEL_RATIO >= sizes[0])
        .unwrap_or(1);
    while l < sizes.len() && sizes[l] > SPARSE_MAX {
        l += 1;
    }
    let nc = *sizes.get(l)?;
    let m = qp.m();
    let kc = if nc <= dense_max {
        Level::Dense(amg.level_dense(l))
    } else {
        Level::Sparse(
            Csr::from_triplets(nc, nc, &amg.level_triplets(l)),
            Workspace::new(),
        )
    };
    // The right side of K_J x = d + Σ_{J0} ρ_j g_j a_jᵀ, restricted.
    let mut w = vec![0.0; m];
    for j in (0..m).filter(|&j| j0[j]) {
        w[j] = rho[j] * qp.g[j];
    }
    let mut f = qp.d.clone();
    qp.a.mul_t_add(&w, &mut f);
    let fc = amg.restrict_to_level(l, &f);
    let v: Vec<Vec<(usize, f64)>> = (0..m)
        .map(|j| {
            let (c, a) = qp.a.row(j);
            amg.restrict_row_to_level(l, c, a)
        })
        .collect();
    let mut in_j = j0.to_vec();
    let mut seen: HashSet<Vec<bool>> = HashSet::new();
    let mut steps = 0;
    let (mut y, mut gaps);
    loop {
        let springs = (0..m).filter(|&j| in_j[j] && !j0[j]);
        let mut rhs = fc.clone();
        for j in springs.clone() {
            for &(a, va) in &v[j] {
                rhs[a] += rho[j] * qp.g[j] * va;
            }
        }
        y = rhs;
        match &kc {
            Level::Dense(kd) => {
                let mut mat = kd.clone();
                for j in springs {
                    for &(a, va) in &v[j] {
                        for &(b, vb) in &v[j] {
                            mat[a * nc + b] += rho[j] * va * vb;
                        }
                    }
                }
                SpdFactor::from_row_major(&mat, nc)?.solve_in_place(&mut y);
            }
            Level::Sparse(k, ws) => {
                let mut data = k.data.to_vec();
                for j in springs {
                    for &(a, va) in &v[j] {
                        let (s0, cols) = (k.indptr[a], k.row(a).0);
                        for &(b, vb) in &v[j] {
                            // Not in the pattern: no coarse start (the
                            // fine loop starts from J0).
                            let at = cols.binary_search(&b).ok()?;
                            data[s0 + at] += rho[j] * va * vb;
                        }
                    }
                }
                let kj = Csr {
                    data: data.into(),
                    ..k.clone()
                };
                ws.cholesky(&kj, &[]).ok()?.solve_in_place(&mut y);
            }
        }
        steps += 1;
        seen.insert(in_j.clone());
        gaps = (0..m)
            .map(|j| v[j].iter().map(|&(k, vk)| vk * y[k]).sum::<f64>() - qp.g[j])
            .collect::<Vec<f64>>();
        // Rows that penetrate are active; at most max(GROW_MIN, GROW·|J|)
        // enter, the deepest first (the fine loop's growth limit,
        // `limit_changes`, with no anti-cycling: a repeated set ends the
        // steps): from the first J's point springs every row near the
        // contact penetrates, and the set would then shrink by a ring of
        // rows per step.
        let predicted: Vec<bool> = (0..m).map(|j| j0[j] || gaps[j] > 0.0).collect();
        let next = limit_changes(&in_j, predicted, &gaps, &HashSet::new(), &mut false, GROW);
        if next == in_j || seen.contains(&next) || steps >= COARSE_STEPS {
            break;
        }
        in_j = next;
    }
    if y.iter().any(|t| !t.is_finite()) {
        return None;
    }
    let lam = (0..m)
        .map(|j| {
            if in_j[j] {
                rho[j] * gaps[j].max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    Some(CoarseStart {
        in_j,
        x: amg.prolong_from_level(l, &y),
        unknowns: nc,
        lam,
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::solid::{build, SolidInput, SolidTraction};
    use crate::linalg::amg::{AmgSettings, NearNull};
    use crate::linalg::augmented::AugPattern;
    use crate::linalg::sparse::norm_inf;
    use crate::problem::{
        Contact, ContactPair, Discretization, FrictionLaw, Material, NonMatchingPair,
    };
    use std::path::Path;

    /// The coarse start with a sparse factor of the coarse level (levels
    /// above DENSE_MAX: the springs added in place in the level's pattern)
    /// finds the dense factor's set, steps and x. `coarse_max`: the
    /// hierarchy's coarsest size (below the path's on a test mesh, so that
    /// there is a coarse level).
    fn agree(qp: &QpProblem, coarse_max: usize) {
        let diag = qp.c.diag();
        let rho = super::super::iterative::rho_rows(qp, &diag, norm_inf(&diag), 10.0);
        let j0: Vec<bool> = qp.g.iter().map(|&g| g <= 0.0).collect();
        let mut aug = AugPattern::new(&qp.c, &qp.a);
        aug.assemble((0..qp.m()).filter(|&j| j0[j]), &rho);
        let nk = qp.near.as_ref().unwrap();
        let near = NearNull {
            block_ptr: &nk.block_ptr,
            modes: &nk.modes,
        };
        let settings = AmgSettings {
            coarse_max,
            ..AmgSettings::for_modes(6)
        };
        let amg = Amg::new(aug.matrix(), Some(near), &settings).unwrap();
        assert!(amg.sizes().len() > 1, "one level: {:?}", amg.sizes());
        let dense = coarse_start_at(&amg, qp, &j0, &rho, usize::MAX).unwrap();
        let sparse = coarse_start_at(&amg, qp, &j0, &rho, 0).unwrap();
        let rows = dense.in_j.iter().filter(|b| **b).count();
        assert!(rows > 1, "the coarse start found {rows} rows");
        assert_eq!(dense.in_j, sparse.in_j);
        assert_eq!(dense.steps, sparse.steps);
        let dx = dense
            .x
            .iter()
            .zip(&sparse.x)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        assert!(dx <= 1e-10 * norm_inf(&dense.x), "{dx:e}");
    }

    fn material(e: f64, nu: f64) -> Material {
        Material { e, nu, rho: 7800.0 }
    }

    /// Hertz, the test mesh: ball on block between slip planes, NTS rows.
    #[test]
    fn sparse_and_dense_coarse_levels_agree() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/solid_contact");
        let mesh = crate::mesh::read_msh(&dir.join("hertz.msh")).unwrap();
        let mut inp = SolidInput::default();
        for body in ["ball", "block"] {
            inp.materials.insert(body.into(), material(2e11, 0.3));
        }
        inp.slip = vec!["x0".into(), "y0".into(), "block_bottom".into()];
        inp.traction = vec![("ball_top".into(), SolidTraction::Normal(-4.66e7))];
        inp.contact = vec![Contact {
            pair: ContactPair::NonMatching(NonMatchingPair {
                slave: "ball".into(),
                master: "block_top".into(),
                max_gap: Some(0.05),
                discretization: Some(Discretization::Nts),
                interference: false,
            }),
            friction: FrictionLaw::Frictionless,
        }];
        agree(
            &build(&mesh, Path::new("t.toml"), &inp).unwrap().qp,
            AmgSettings::for_modes(6).coarse_max,
        );
    }

    /// The stacked cubes meshed apart: aluminium held along z by the
    /// contact alone on steel, mortar rows (each touches the unknowns of
    /// several master triangles).
    #[test]
    fn sparse_and_dense_coarse_levels_agree_on_mortar_rows_of_a_floating_body() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/solid_contact");
        let mesh = crate::mesh::read_msh(&dir.join("stack_nm.msh")).unwrap();
        let mut inp = SolidInput::default();
        inp.materials.insert("lower".into(), material(2e11, 0.3));
        inp.materials.insert("upper".into(), material(7e10, 0.33));
        inp.slip = vec!["x0".into(), "y0".into(), "bottom".into()];
        inp.traction = vec![("top".into(), SolidTraction::Normal(-1e8))];
        inp.contact = vec![Contact {
            pair: ContactPair::NonMatching(NonMatchingPair {
                slave: "upper_bottom".into(),
                master: "lower_top".into(),
                max_gap: None,
                discretization: Some(Discretization::Mortar),
                interference: false,
            }),
            friction: FrictionLaw::Frictionless,
        }];
        agree(&build(&mesh, Path::new("t.toml"), &inp).unwrap().qp, 200);
    }
}
