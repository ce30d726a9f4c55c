//! Forces an engineer checks first: the reactions of the Dirichlet and slip
//! groups and the resultant of the contact pressure on each interface.
//!
//! The QP has eliminated the prescribed DOFs, so the reactions come from the
//! unreduced element forces: at every point R_p = Σ_e (K_e u_e)_p − f_p − c_p,
//! f the applied loads and c the contact forces (−λ_r times the row's
//! coefficients at p). Equilibrium makes R_p zero in the directions left free
//! (up to the solver's residual); its component in the directions fixed by
//! the conditions at p is the support's reaction. Forces carry the thickness
//! (N in plane stress with thickness t, N per metre in plane strain), like λ;
//! moments are about the origin, m = x F_y − y F_x at the undeformed point.
//!
//! A contact row's forces sum to zero but act at points an initial gap
//! apart, so with friction they make a couple (−λ_t·g0 on a node-to-segment
//! row): the moment balance is loads + reactions + contact couple = 0
//! (docs/methods.md §9.5), and the couple is reported per interface.

use crate::fem::element::{Point, Vector};
use crate::fem::{element, Model};
use crate::problem::Material;
use std::collections::BTreeMap;

/// A force resultant and its moment about the origin.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Resultant {
    pub force: Vector,
    pub moment: f64,
}

impl Resultant {
    /// Add the force `f` acting at `x`.
    pub fn add(&mut self, x: Point, f: Vector) {
        self.force[0] += f[0];
        self.force[1] += f[1];
        self.moment += x[0] * f[1] - x[1] * f[0];
    }
}

/// The reaction of one physical group carrying `[[dirichlet]]` and/or `[[slip]]`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GroupReaction {
    /// The physical group name (`on`).
    pub on: String,
    /// "dirichlet", "slip", or "dirichlet+slip".
    pub kind: String,
    /// Points the group constrains.
    pub points: usize,
    #[serde(flatten)]
    pub resultant: Resultant,
}

/// The resultant of the contact forces on one `[[contact]]` interface.
#[derive(Debug, Clone, serde::Serialize)]
pub struct InterfaceForce {
    /// The interface name: `on`, or "slave->master".
    pub name: String,
    /// The side the resultant acts on: the slave curve (non-matching) or
    /// the body of lower index (conforming `on =`), by body name; bodies
    /// joined by `+` when that side spans several.
    pub on_body: String,
    #[serde(flatten)]
    pub resultant: Resultant,
    /// The resultant on the other side (master, or the higher body): equal
    /// and opposite up to round-off.
    #[serde(skip)]
    pub other: Resultant,
    /// The rows it was discretized with: `"node-to-node"` (a conforming
    /// `on =` pair), `"mortar"` or `"nts"` (a non-matching pair,
    /// `[[contact]] discretization`; docs/problem-format.md §2).
    pub discretization: &'static str,
    /// Contact rows of the interface, rows with λ > 0 (active).
    pub rows: usize,
    pub active: usize,
    /// The largest nodal pressure λ/(t·tributary length) of a row: the peak
    /// of the node-to-node ripple of a P1 contact, not a smoothed peak.
    pub max_pressure: f64,
    /// Σλ / (t·Σ tributary length) over the active rows: the
    /// tributary-weighted mean of the nodal pressures over the contact zone
    /// (0 without an active row).
    pub mean_pressure: f64,
    /// The moment of the interface's contact forces on both sides together
    /// (N·m per m in plane strain): the couple its rows make across their
    /// initial gaps, zero when every row's forces are collinear
    /// (node-to-segment or conforming rows without friction, or without a
    /// gap); mortar rows spread a slave force over master points off its
    /// line of action and make one without friction too.
    pub couple: f64,
    /// Where the active rows lie along the interface (None: no active row).
    pub extent: Option<Extent>,
}

/// The active part of an interface along its curve (docs/problem-format.md
/// §7): from the first to the last active row point in the order of the
/// rows along the curve, on the side named by `on_body`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Extent {
    /// The first and the last active row's point (undeformed coordinates).
    pub start: Point,
    pub end: Point,
    /// Arc length from `start` to `end` along the interface, open stretches
    /// between contact zones included; summed over the pieces of an
    /// interface made of disjoint curves.
    pub length: f64,
    /// Maximal runs of adjacent active rows (contact zones).
    pub zones: usize,
    /// Σ arc length of the zones (= `length` with one zone).
    pub active_length: f64,
}

/// Everything [`compute`] finds.
#[derive(Debug, Clone, Default)]
pub struct Forces {
    /// Reaction force at each point (zero where nothing is prescribed).
    pub point_reaction: Vec<Vector>,
    /// Contact force on each point (from every row touching it).
    pub point_contact: Vec<Vector>,
    pub groups: Vec<GroupReaction>,
    pub interfaces: Vec<InterfaceForce>,
    /// The applied loads (tractions, point forces, gravity) summed.
    pub loads: Resultant,
    /// All reactions summed.
    pub reactions: Resultant,
    /// Σ of the interfaces' couples: loads + reactions + couple = 0 in moment.
    pub couple: f64,
    /// The physical strain energy ½ uᵀK u of the full displacement
    /// (prescribed parts included), unlike the QP objective.
    pub strain_energy: f64,
    /// The work of the applied loads on u: fᵀu.
    pub load_work: f64,
}

/// (K u)_p per point: the element forces C_e u_e summed at each vertex.
fn internal_forces(
    model: &Model,
    materials: &BTreeMap<String, Material>,
    u: &[Vector],
) -> Vec<Vector> {
    element_pass(model, materials, u, false).1
}

/// Elements per chunk of [`element_pass`]: its per-element results (a few
/// MB) are reused from chunk to chunk while still in cache, instead of one
/// array over all the elements allocated at every step.
const CHUNK: usize = 1 << 15;

/// One pass over the elements: the stress of each (σ = D B u_e, with
/// `stresses`; else empty) and (K u)_p per point, the element forces
/// C_e u_e summed at each vertex. Elements are computed in parallel chunk
/// by chunk and summed into the points in element order: the same bits as
/// the sequential loop on any number of threads, and as
/// [`ElementKind::stress`](element::ElementKind::stress) and
/// [`ElementKind::stiffness`](element::ElementKind::stiffness) element by element.
pub(crate) fn element_pass(
    model: &Model,
    materials: &BTreeMap<String, Material>,
    u: &[Vector],
    stresses: bool,
) -> (Vec<[f64; 4]>, Vec<Vector>) {
    use rayon::prelude::*;
    let t = &model.topo;
    let kind = model.kind;
    // D once per material index, not a map lookup per element.
    let mats: Vec<element::MaterialMatrix> = t
        .material_names
        .iter()
        .map(|m| kind.material(&materials[m]))
        .collect();
    let mut stress = Vec::with_capacity(if stresses { t.triangles.len() } else { 0 });
    let mut ku = vec![[0.0f64; 2]; t.points.len()];
    let mut buf: Vec<([f64; 4], [Vector; 3])> = Vec::with_capacity(CHUNK);
    for (tris, tmat) in t.triangles.chunks(CHUNK).zip(t.tri_material.chunks(CHUNK)) {
        tris.par_iter()
            .zip(tmat.par_iter())
            .map(|(tri, &mi)| {
                let d = &mats[mi as usize];
                let p = [t.points[tri[0]], t.points[tri[1]], t.points[tri[2]]];
                let ue = [
                    u[tri[0]][0],
                    u[tri[0]][1],
                    u[tri[1]][0],
                    u[tri[1]][1],
                    u[tri[2]][0],
                    u[tri[2]][1],
                ];
                let s = if stresses {
                    kind.stress(&p, d, &ue)
                } else {
                    [0.0; 4]
                };
                let ke = kind.stiffness(&p, d);
                let mut fe = [[0.0f64; 2]; 3];
                for (a, fa) in fe.iter_mut().enumerate() {
                    for (k, fak) in fa.iter_mut().enumerate() {
                        *fak = (0..6).map(|j| ke[2 * a + k][j] * ue[j]).sum::<f64>();
                    }
                }
                (s, fe)
            })
            .collect_into_vec(&mut buf);
        for (tri, (s, fe)) in tris.iter().zip(&buf) {
            if stresses {
                stress.push(*s);
            }
            for (a, &v) in tri.iter().enumerate() {
                for k in 0..2 {
                    ku[v][k] += fe[a][k];
                }
            }
        }
    }
    (stress, ku)
}

/// Reactions and interface resultants of a solved step: `u` the point
/// displacements, `lambda` the multiplier of every contact row (0 for rows
/// left out of the QP), `pressure` the contact pressure per row;
/// `materials` the model's `[materials]`.
pub fn compute(
    model: &Model,
    materials: &BTreeMap<String, Material>,
    u: &[Vector],
    lambda: &[f64],
    pressure: &[f64],
) -> Forces {
    compute_with_friction(model, materials, u, lambda, &[], pressure)
}

/// [`compute`] with the tangential force λ_t of every contact row (empty:
/// frictionless), which acts along the row's tangential coefficients
/// (docs/methods.md §9).
pub fn compute_with_friction(
    model: &Model,
    materials: &BTreeMap<String, Material>,
    u: &[Vector],
    lambda: &[f64],
    lambda_t: &[f64],
    pressure: &[f64],
) -> Forces {
    let ku = internal_forces(model, materials, u);
    compute_from(model, u, &ku, lambda, lambda_t, pressure)
}

/// [`compute_with_friction`] from `ku` = (K u)_p per point
/// ([`element_pass`]).
pub(crate) fn compute_from(
    model: &Model,
    u: &[Vector],
    ku: &[Vector],
    lambda: &[f64],
    lambda_t: &[f64],
    pressure: &[f64],
) -> Forces {
    let mut lap = crate::fem::Lap::new("post::forces");
    let t = &model.topo;
    let np = t.points.len();
    let mut contact = vec![[0.0f64; 2]; np];
    for (row, &l) in t.contact.iter().zip(lambda) {
        for (p, c) in row.coefficients() {
            contact[p][0] -= l * c[0];
            contact[p][1] -= l * c[1];
        }
    }
    for (row, &l) in t.contact.iter().zip(lambda_t) {
        for (p, c) in crate::fem::friction::tangential_coefficients(row) {
            contact[p][0] -= l * c[0];
            contact[p][1] -= l * c[1];
        }
    }

    let mut reaction = vec![[0.0f64; 2]; np];
    let mut groups: Vec<GroupReaction> = vec![];
    let mut group_of = vec![usize::MAX; model.cond_groups.len()];
    for (i, (kind, on)) in model.cond_groups.iter().enumerate() {
        let g = match groups.iter().position(|g| &g.on == on) {
            Some(g) => {
                if !groups[g].kind.split('+').any(|k| k == *kind) {
                    groups[g].kind = format!("{}+{kind}", groups[g].kind);
                }
                g
            }
            None => {
                groups.push(GroupReaction {
                    on: on.clone(),
                    kind: kind.to_string(),
                    points: 0,
                    resultant: Resultant::default(),
                });
                groups.len() - 1
            }
        };
        group_of[i] = g;
    }
    // Conditions are stored point by point.
    let conds = &model.conditions;
    let mut i = 0;
    while i < conds.len() {
        let p = conds[i].0;
        let mut j = i;
        while j < conds.len() && conds[j].0 == p {
            j += 1;
        }
        let here = &conds[i..j];
        i = j;
        let r = [
            ku[p][0] - model.loads[p][0] - contact[p][0],
            ku[p][1] - model.loads[p][1] - contact[p][1],
        ];
        // An orthonormal basis of the fixed directions: the complement of T.
        let pd = &model.dofs[p];
        let fixed: Vec<Vector> = match pd.ndof {
            0 => vec![[1.0, 0.0], [0.0, 1.0]],
            1 => vec![[-pd.t[0][1], pd.t[0][0]]],
            _ => vec![],
        };
        // Each group's fixed directions at p, orthonormalised.
        let mut gs: Vec<(usize, Vec<Vector>)> = vec![];
        for &(_, dir, src) in here {
            let g = group_of[src as usize];
            let k = match gs.iter().position(|x| x.0 == g) {
                Some(k) => k,
                None => {
                    gs.push((g, vec![]));
                    gs.len() - 1
                }
            };
            let basis = &mut gs[k].1;
            let mut v = dir;
            for b in basis.iter() {
                let c = v[0] * b[0] + v[1] * b[1];
                v = [v[0] - c * b[0], v[1] - c * b[1]];
            }
            let n = v[0].hypot(v[1]);
            if n > 1e-8 {
                basis.push([v[0] / n, v[1] / n]);
            }
        }
        for (g, _) in &gs {
            groups[*g].points += 1;
        }
        // Each fixed direction's share of R goes to the groups that fix it,
        // in proportion to how much of it each group fixes.
        for e in &fixed {
            let comp = r[0] * e[0] + r[1] * e[1];
            let w: Vec<f64> = gs
                .iter()
                .map(|(_, basis)| {
                    basis
                        .iter()
                        .map(|b| (b[0] * e[0] + b[1] * e[1]).powi(2))
                        .sum::<f64>()
                })
                .collect();
            let wsum: f64 = w.iter().sum();
            if wsum.is_nan() || wsum <= 0.0 {
                continue;
            }
            let fe = [comp * e[0], comp * e[1]];
            reaction[p][0] += fe[0];
            reaction[p][1] += fe[1];
            for ((g, _), wk) in gs.iter().zip(&w) {
                let s = wk / wsum;
                groups[*g]
                    .resultant
                    .add(t.points[p], [s * fe[0], s * fe[1]]);
            }
        }
    }
    lap.lap("reactions");
    let mut interfaces: Vec<InterfaceForce> = t
        .interface_names
        .iter()
        .zip(&t.interface_kinds)
        .map(|(n, k)| InterfaceForce {
            name: n.clone(),
            on_body: String::new(),
            resultant: Resultant::default(),
            other: Resultant::default(),
            discretization: k.discretization(),
            rows: 0,
            active: 0,
            max_pressure: 0.0,
            mean_pressure: 0.0,
            couple: 0.0,
            extent: None,
        })
        .collect();
    // Σλ and Σ tributary length of the active rows, per interface.
    let mut active_sums = vec![(0.0f64, 0.0f64); interfaces.len()];
    // The bodies of the rows' first points, in row order: a slave curve
    // may run over several bodies, and the resultant is on all of them.
    let mut sides: Vec<Vec<u32>> = vec![vec![]; interfaces.len()];
    for (r, row) in t.contact.iter().enumerate() {
        let it = &mut interfaces[row.interface as usize];
        let l = lambda.get(r).copied().unwrap_or(0.0);
        it.rows += 1;
        if l > 0.0 {
            it.active += 1;
            if row.trib > 0.0 {
                let a = &mut active_sums[row.interface as usize];
                a.0 += l;
                a.1 += row.trib;
            }
        }
        if let Some(&pr) = pressure.get(r) {
            it.max_pressure = it.max_pressure.max(pr);
        }
        // The row's moment about its first point plus that of its net
        // force (zero up to round-off) at the first point: the couple
        // without the cancellation of two large moments about the origin.
        let x0 = t.points[row.first];
        let mut net = [0.0f64; 2];
        let mut couple = 0.0;
        let lt = lambda_t.get(r).copied();
        let tang = lt.map(|_| crate::fem::friction::tangential_coefficients(row));
        let parts = row
            .coefficients()
            .into_iter()
            .map(|pc| (pc, l))
            .chain(tang.into_iter().flatten().map(|pc| (pc, lt.unwrap_or(0.0))));
        for ((p, c), m) in parts {
            let f = [-m * c[0], -m * c[1]];
            let d = [t.points[p][0] - x0[0], t.points[p][1] - x0[1]];
            couple += d[0] * f[1] - d[1] * f[0];
            net = [net[0] + f[0], net[1] + f[1]];
        }
        it.couple += couple + (x0[0] * net[1] - x0[1] * net[0]);
        let body = t.point_body[row.first];
        if !sides[row.interface as usize].contains(&body) {
            sides[row.interface as usize].push(body);
        }
        for (p, c) in row.coefficients() {
            let f = [-l * c[0], -l * c[1]];
            if p == row.first {
                it.resultant.add(t.points[p], f);
            } else {
                it.other.add(t.points[p], f);
            }
        }
        if let Some(&lt) = lambda_t.get(r) {
            for (p, c) in crate::fem::friction::tangential_coefficients(row) {
                let f = [-lt * c[0], -lt * c[1]];
                if p == row.first {
                    it.resultant.add(t.points[p], f);
                } else {
                    it.other.add(t.points[p], f);
                }
            }
        }
    }
    let te = model.t_eff();
    for (i, it) in interfaces.iter_mut().enumerate() {
        let (sl, st) = active_sums[i];
        if st > 0.0 {
            it.mean_pressure = sl / (te * st);
        }
        it.extent = extent(t, lambda, i as u32);
    }
    let couple = interfaces.iter().fold(0.0, |a, i| a + i.couple);
    for (it, bodies) in interfaces.iter_mut().zip(&sides) {
        it.on_body = bodies
            .iter()
            .map(|&b| {
                model
                    .body_names
                    .get(b as usize)
                    .cloned()
                    .unwrap_or_default()
            })
            .collect::<Vec<_>>()
            .join("+");
    }
    lap.lap("interfaces");
    let mut loads = Resultant::default();
    let mut reactions = Resultant::default();
    let (mut strain_energy, mut load_work) = (0.0, 0.0);
    for p in 0..np {
        strain_energy += 0.5 * (u[p][0] * ku[p][0] + u[p][1] * ku[p][1]);
        load_work += u[p][0] * model.loads[p][0] + u[p][1] * model.loads[p][1];
        loads.add(t.points[p], model.loads[p]);
        reactions.add(t.points[p], reaction[p]);
    }
    lap.lap("totals");
    Forces {
        point_reaction: reaction,
        point_contact: contact,
        groups,
        interfaces,
        loads,
        reactions,
        couple,
        strain_energy,
        load_work,
    }
}

/// The [`Extent`] of interface `iface`: its rows joined into curves by the
/// contact segments (and rows at one point, a corner's two normals), each
/// curve walked in order; `lambda` > 0 marks the active rows.
/// A curve that closes on itself (a ring) is cut at its longest open
/// stretch; one that branches (never built by the pairs of
/// docs/problem-format.md §4, kept for safety) counts the edges left after
/// pruning its open ends. Pieces come in the order of their lowest row.
pub fn extent(t: &crate::fem::Topology, lambda: &[f64], iface: u32) -> Option<Extent> {
    let rows: Vec<usize> = (0..t.contact.len())
        .filter(|&r| t.contact[r].interface == iface)
        .collect();
    let on = |r: usize| lambda.get(r).is_some_and(|&l| l > 0.0);
    if !rows.iter().any(|&r| on(r)) {
        return None;
    }
    let x = |r: usize| t.points[t.contact[r].first];
    let dist = |a: usize, b: usize| {
        let (p, q) = (x(a), x(b));
        (q[0] - p[0]).hypot(q[1] - p[1])
    };
    let adj = adjacency(t, &rows);
    let mut seen: std::collections::BTreeSet<usize> = Default::default();
    let mut pieces: Vec<Extent> = vec![];
    for &r0 in &rows {
        if seen.contains(&r0) {
            continue;
        }
        // The piece of r0 (rows ascending).
        let mut comp = vec![r0];
        seen.insert(r0);
        let mut k = 0;
        while k < comp.len() {
            for &q in &adj[&comp[k]] {
                if seen.insert(q) {
                    comp.push(q);
                }
            }
            k += 1;
        }
        comp.sort_unstable();
        if !comp.iter().any(|&r| on(r)) {
            continue;
        }
        let edges = comp.iter().map(|r| adj[r].len()).sum::<usize>() / 2;
        let deg2 = comp.iter().all(|r| adj[r].len() <= 2);
        let order = if deg2 && edges + 1 == comp.len() {
            // A path: from its end of lower row index.
            comp.iter()
                .find(|r| adj[*r].len() <= 1)
                .map(|&start| walk(&adj, start, comp.len()))
        } else if deg2 && edges == comp.len() {
            // A ring: cut at the longest stretch between active rows that
            // holds an open row (all active: one zone round the ring).
            let ring = walk(&adj, comp[0], comp.len());
            let n = ring.len();
            let act: Vec<usize> = (0..n).filter(|&i| on(ring[i])).collect();
            if act.len() == n {
                let per: f64 = (0..n).map(|i| dist(ring[i], ring[(i + 1) % n])).sum();
                pieces.push(Extent {
                    start: x(ring[0]),
                    end: x(ring[0]),
                    length: per,
                    zones: 1,
                    active_length: per,
                });
                continue;
            }
            let mut best = (f64::NEG_INFINITY, 0);
            for (j, &a) in act.iter().enumerate() {
                let b = act[(j + 1) % act.len()];
                let steps = (b + n - a) % n;
                let steps = if steps == 0 { n } else { steps };
                if steps < 2 {
                    continue;
                }
                let len: f64 = (0..steps)
                    .map(|s| dist(ring[(a + s) % n], ring[(a + s + 1) % n]))
                    .sum();
                if len > best.0 {
                    best = (len, (a + 1) % n);
                }
            }
            // The path starts just past the cut's first active row.
            Some((0..n).map(|s| ring[(best.1 + s) % n]).collect())
        } else {
            None
        };
        match order {
            Some(path) => pieces.push(path_extent(&path, &on, &x)),
            None => pieces.push(branch_extent(&comp, &adj, &on, &x)),
        }
    }
    let (first, last) = (pieces.first()?, pieces.last()?);
    Some(Extent {
        start: first.start,
        end: last.end,
        length: pieces.iter().map(|p| p.length).sum(),
        zones: pieces.iter().map(|p| p.zones).sum(),
        active_length: pieces.iter().map(|p| p.active_length).sum(),
    })
}

/// The rows of `rows` as a graph: contact segments, and rows at one point
/// (a corner's two normals); neighbours ascending, edges once each.
fn adjacency(t: &crate::fem::Topology, rows: &[usize]) -> Adjacency {
    // Adjacency (row → neighbours), edges once each.
    let mut adj: Adjacency = rows.iter().map(|&r| (r, vec![])).collect();
    let mut link = |a: usize, b: usize| {
        if a != b && adj.contains_key(&a) && adj.contains_key(&b) && !adj[&a].contains(&b) {
            adj.entry(a).or_default().push(b);
            adj.entry(b).or_default().push(a);
        }
    };
    for &[a, b] in &t.contact_segments {
        link(a, b);
    }
    let mut at_point: std::collections::BTreeMap<usize, usize> = Default::default();
    for &r in rows {
        match at_point.get(&t.contact[r].first) {
            Some(&q) => link(q, r),
            None => {
                at_point.insert(t.contact[r].first, r);
            }
        }
    }
    for v in adj.values_mut() {
        v.sort_unstable();
    }
    adj
}

/// Row → its neighbours ([`adjacency`]).
type Adjacency = std::collections::BTreeMap<usize, Vec<usize>>;

/// The extent of a path of rows (in order): from its first active row to
/// its last, the zones being the runs of active rows.
fn path_extent(path: &[usize], on: &dyn Fn(usize) -> bool, x: &dyn Fn(usize) -> Point) -> Extent {
    let dist = |a: usize, b: usize| {
        let (p, q) = (x(a), x(b));
        (q[0] - p[0]).hypot(q[1] - p[1])
    };
    // A piece reaches here only with an active row (extent skips others).
    let first = path.iter().position(|&r| on(r)).unwrap_or(0);
    let last = path.iter().rposition(|&r| on(r)).unwrap_or(0);
    let (mut length, mut active_length, mut zones) = (0.0, 0.0, 1);
    for i in first..last {
        let d = dist(path[i], path[i + 1]);
        length += d;
        match (on(path[i]), on(path[i + 1])) {
            (true, true) => active_length += d,
            (false, true) => zones += 1,
            _ => {}
        }
    }
    Extent {
        start: x(path[first]),
        end: x(path[last]),
        length,
        zones,
        active_length,
    }
}

/// The extent of a branching piece (never built by the pairs of
/// docs/problem-format.md §4, kept for safety): open leaves pruned, the
/// edges left summed.
fn branch_extent(
    comp: &[usize],
    adj: &Adjacency,
    on: &dyn Fn(usize) -> bool,
    x: &dyn Fn(usize) -> Point,
) -> Extent {
    let dist = |a: usize, b: usize| {
        let (p, q) = (x(a), x(b));
        (q[0] - p[0]).hypot(q[1] - p[1])
    };
    let mut deg: std::collections::BTreeMap<usize, usize> =
        comp.iter().map(|&r| (r, adj[&r].len())).collect();
    let mut gone: std::collections::BTreeSet<usize> = Default::default();
    let mut stack: Vec<usize> = comp
        .iter()
        .copied()
        .filter(|&r| !on(r) && deg[&r] <= 1)
        .collect();
    while let Some(r) = stack.pop() {
        if !gone.insert(r) {
            continue;
        }
        for &q in &adj[&r] {
            if !gone.contains(&q) {
                let d = deg.entry(q).or_insert(1);
                *d = d.saturating_sub(1);
                if *d <= 1 && !on(q) {
                    stack.push(q);
                }
            }
        }
    }
    let (mut length, mut active_length) = (0.0, 0.0);
    let mut zone_links = 0;
    for &a in comp {
        for &b in &adj[&a] {
            if a < b && !gone.contains(&a) && !gone.contains(&b) {
                length += dist(a, b);
                if on(a) && on(b) {
                    active_length += dist(a, b);
                    zone_links += 1;
                }
            }
        }
    }
    let act: Vec<usize> = comp.iter().copied().filter(|&r| on(r)).collect();
    Extent {
        start: x(act[0]),
        end: x(act[act.len() - 1]),
        length,
        // Exact on a forest of active rows; a lower bound else.
        zones: act.len().saturating_sub(zone_links).max(1),
        active_length,
    }
}

/// The rows of a path or ring (every row of degree ≤ 2) from `start`: each
/// step goes on to the neighbour it did not come from (the lower one first).
fn walk(adj: &std::collections::BTreeMap<usize, Vec<usize>>, start: usize, n: usize) -> Vec<usize> {
    let mut path = vec![start];
    let mut prev = usize::MAX;
    while path.len() < n {
        let Some(&cur) = path.last() else { break };
        match adj[&cur].iter().find(|&&q| q != prev) {
            Some(&q) => {
                prev = cur;
                path.push(q);
            }
            None => break,
        }
    }
    path
}
