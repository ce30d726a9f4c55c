//! The contact rows: their form on points, Σ c_p·u_p ≤ g (conforming or
//! node-to-segment, built in `pairs.rs`), and their form in the reduced
//! unknowns, the rows of A and g of the QP (docs/methods.md §2.7–2.8, §7).

use super::conditions::PointDofs;
use super::element::Vector;
use super::topology::Topology;
use super::FemError;
use crate::mesh::Mesh;
use crate::qp::Csr;
use std::path::Path;

/// How a contact row couples points: n·(u_first − u_second) ≤ g (conforming,
/// n outward of the lower body), n·(Σ w u_master − u_slave) ≤ g (non-matching
/// node-to-segment, n outward of the master), or the same with the mortar
/// weights M_jm / D_jj of any number of master points (docs/methods.md §7.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowKind {
    Conforming,
    NonMatching,
    Mortar,
}

impl RowKind {
    /// The discretization the outputs record for an interface of such
    /// rows: `"node-to-node"`, `"nts"` or `"mortar"` (the value of
    /// `[[contact]] discretization` for a non-matching pair).
    pub fn discretization(self) -> &'static str {
        match self {
            RowKind::Conforming => "node-to-node",
            RowKind::NonMatching => crate::problem::Discretization::Nts.name(),
            RowKind::Mortar => crate::problem::Discretization::Mortar.name(),
        }
    }
}

/// One contact constraint row (docs/methods.md §2.7, §7 for non-matching).
#[derive(Clone)]
pub struct ContactRow {
    pub kind: RowKind,
    /// Point of body k (conforming) or the slave point.
    pub first: usize,
    /// Point of body l (weight 1), or the two master points with (1−ξ, ξ).
    pub second: [(usize, f64); 2],
    /// Contract normal: outward of body k, or of the master segment.
    pub normal: Vector,
    /// Initial gap g ≥ 0.
    pub gap0: f64,
    /// Length that the row's force acts on (half the adjacent segments), or
    /// the mortar weight D_jj of a mortar row (so that λ / trib is the
    /// mortar multiplier, a traction).
    pub trib: f64,
    pub interface: u32,
    /// Mortar rows: every master point with its weight M_jm / D_jj (empty
    /// for the other kinds; `second` then holds the two heaviest of them).
    pub masters: Vec<(usize, f64)>,
}

/// The derived format, with `masters` only on mortar rows: the text of the
/// other rows (tests/fem_dump.rs compares models by it) stays as it was.
impl std::fmt::Debug for ContactRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("ContactRow");
        d.field("kind", &self.kind)
            .field("first", &self.first)
            .field("second", &self.second)
            .field("normal", &self.normal)
            .field("gap0", &self.gap0)
            .field("trib", &self.trib)
            .field("interface", &self.interface);
        if !self.masters.is_empty() {
            d.field("masters", &self.masters);
        }
        d.finish()
    }
}

impl ContactRow {
    /// Coefficients c_p (2-vectors) of the row Σ c_p·u_p ≤ g.
    pub fn coefficients(&self) -> Vec<(usize, Vector)> {
        let n = self.normal;
        match self.kind {
            RowKind::Conforming => vec![(self.first, n), (self.second[0].0, [-n[0], -n[1]])],
            RowKind::NonMatching => {
                let mut v = vec![(self.first, [-n[0], -n[1]])];
                for &(p, w) in &self.second {
                    if w != 0.0 {
                        v.push((p, [w * n[0], w * n[1]]));
                    }
                }
                v
            }
            RowKind::Mortar => {
                let mut v = vec![(self.first, [-n[0], -n[1]])];
                v.extend(self.masters.iter().map(|&(p, w)| (p, [w * n[0], w * n[1]])));
                v
            }
        }
    }
}

/// The contact rows in the reduced unknowns: A = rows · T and
/// g = gap0 − rows · u0 (docs/methods.md §2.7–2.8), and the contact row of
/// each QP row. A row whose points are all fixed is left out, and refused
/// if the prescribed displacements alone violate it.
pub(super) fn reduced_rows(
    mesh: &Mesh,
    topo: &Topology,
    dofs: &[PointDofs],
    n: usize,
    path: &Path,
) -> Result<(Csr, Vec<f64>, Vec<usize>), FemError> {
    let mut atrip = vec![];
    let mut g = vec![];
    let mut qp_rows = vec![];
    for (r, row) in topo.contact.iter().enumerate() {
        let mut gr = row.gap0;
        let mut entries = vec![];
        for (p, cvec) in row.coefficients() {
            let pd = dofs[p];
            gr -= cvec[0] * pd.u0[0] + cvec[1] * pd.u0[1];
            for k in 0..pd.ndof {
                let v = cvec[0] * pd.t[k][0] + cvec[1] * pd.t[k][1];
                if v.abs() > 1e-14 {
                    entries.push((pd.start + k, v));
                }
            }
        }
        if entries.is_empty() {
            if gr < -1e-12 * (1.0 + row.gap0.abs()) {
                return Err(FemError::new(
                    path,
                    format!(
                        "contact row at node {} of \"{}\" is violated by the prescribed displacements alone",
                        mesh.node_tags[topo.point_node[row.first]],
                        topo.interface_names[row.interface as usize]
                    ),
                ));
            }
            continue;
        }
        let qi = qp_rows.len();
        for (j, v) in entries {
            atrip.push((qi, j, v));
        }
        g.push(gr);
        qp_rows.push(r);
    }
    let a = Csr::from_triplets(qp_rows.len(), n, &atrip);
    Ok((a, g, qp_rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The row as it was before mortar rows (derived Debug).
    #[derive(Debug)]
    #[allow(dead_code)]
    struct ContactRow {
        kind: RowKind,
        first: usize,
        second: [(usize, f64); 2],
        normal: Vector,
        gap0: f64,
        trib: f64,
        interface: u32,
    }

    #[test]
    fn debug_text_of_non_mortar_rows_is_unchanged() {
        let row = super::ContactRow {
            kind: RowKind::NonMatching,
            first: 3,
            second: [(7, 0.25), (8, 0.75)],
            normal: [0.6, -0.8],
            gap0: 1e-3,
            trib: 0.125,
            interface: 2,
            masters: vec![],
        };
        let old = ContactRow {
            kind: row.kind,
            first: row.first,
            second: row.second,
            normal: row.normal,
            gap0: row.gap0,
            trib: row.trib,
            interface: row.interface,
        };
        assert_eq!(format!("{row:?}"), format!("{old:?}"));
        assert_eq!(format!("{:?}", [&row]), format!("{:?}", [&old]));
        let mortar = super::ContactRow {
            kind: RowKind::Mortar,
            masters: vec![(7, 0.5), (8, 0.5)],
            ..row
        };
        assert!(format!("{mortar:?}").contains("masters: [(7, 0.5), (8, 0.5)]"));
    }
}
