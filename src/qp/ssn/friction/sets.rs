//! The working sets of ssn's frictional Newton steps (docs/methods.md
//! §9.2): how a row is held, the sets a solve starts from (its own start
//! or a load step's warm start), and the rule that predicts the next sets.

use crate::qp::Friction;

/// How each row is held in a working set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Tangential {
    Stick,
    /// Slips with λ_t = s·sign (the sign as a bool: true = positive).
    Slip(bool),
}

/// The tangential sets a solve starts from: the rows in N stick, and
/// (unless glued) every row with a positive bound; the others slip
/// (docs/methods.md §9.2). For every level of rows ([`nested`] too).
pub(super) fn start_tang(in_n: &[bool], s: &[f64], glued: bool) -> Vec<Tangential> {
    in_n.iter()
        .zip(s)
        .map(|(&a, &si)| {
            if a || (!glued && si > 0.0) {
                Tangential::Stick
            } else {
                Tangential::Slip(true)
            }
        })
        .collect()
}

/// What the working-set rule reads of the rows of one level: the
/// problem's own, or a coarse level's ([`nested`]).
pub(super) struct Rule<'a> {
    pub(super) g: &'a [f64],
    pub(super) t0: &'a [f64],
    /// cᵢ of the normal prediction.
    pub(super) cn: &'a [f64],
    /// c_tᵢ of the slip prediction.
    pub(super) ct: &'a [f64],
    /// Tangential rows that cannot respond (the dual path's null rows).
    pub(super) forced: Option<&'a [bool]>,
}

impl Rule<'_> {
    /// The sets predicted at B x = `bx` ([A x; T x]), the multipliers
    /// and the bound s (the rule of the module's head).
    pub(super) fn predict(
        &self,
        bx: &[f64],
        ln: &[f64],
        lt: &[f64],
        s: &[f64],
        glued: bool,
    ) -> (Vec<bool>, Vec<Tangential>) {
        let m = self.g.len();
        let (ax, tx) = bx.split_at(m);
        let n_set: Vec<bool> = (0..m)
            .map(|i| ln[i] + self.cn[i] * (ax[i] - self.g[i]) > 0.0)
            .collect();
        // A tangential row the dual path leaves out (no free unknown: both
        // sides' tangential motion prescribed, or a line of symmetry) cannot
        // respond: its slip v = −t0 is given, so it sticks only where that
        // is zero and otherwise slips with it (at the end of a tube pushed
        // through a fit, its forced slip was taken for a stick).
        let forced = |i: usize| self.forced.is_some_and(|f| f[i]);
        let tang = (0..m)
            .map(|i| {
                let v = tx[i] - self.t0[i];
                let z = lt[i] + self.ct[i] * v;
                if glued {
                    if n_set[i] {
                        Tangential::Stick
                    } else {
                        Tangential::Slip(true)
                    }
                } else if forced(i) {
                    if self.t0[i] == 0.0 {
                        Tangential::Stick
                    } else {
                        Tangential::Slip(v > 0.0)
                    }
                } else if s[i] > 0.0 && z.abs() <= s[i] {
                    Tangential::Stick
                } else {
                    Tangential::Slip(z > 0.0)
                }
            })
            .collect();
        (n_set, tang)
    }
}

/// The working sets of a multiplier warm start (the last load step's
/// answer, docs/methods.md §9.5): rows with λ_n > 0 in contact; of those,
/// a row slips (with the sign of λ_t) where |λ_t| reaches its bound s =
/// μλ_n (Tresca: the given s) within [`crate::qp::STICK_MARGIN`],
/// and sticks otherwise.
pub(super) fn warm_sets(fr: &Friction, l: &crate::qp::Multipliers) -> (Vec<bool>, Vec<Tangential>) {
    let s = fr.slip_bound(&l.normal);
    let in_n: Vec<bool> = l.normal.iter().map(|&v| v > 0.0).collect();
    let tang = (0..in_n.len())
        .map(|i| {
            let lt = l.tangential[i];
            if in_n[i] && s[i] > 0.0 && lt.abs() < (1.0 - crate::qp::STICK_MARGIN) * s[i] {
                Tangential::Stick
            } else {
                Tangential::Slip(lt >= 0.0)
            }
        })
        .collect();
    (in_n, tang)
}
