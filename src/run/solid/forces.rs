//! What a solved 3D model's answer means at its nodes: the reactions and
//! interface resultants (3-vectors with moments about [`super::MOMENT_POINT`]),
//! the contact surface's values, the probes (docs/problem-format.md §7, §12).

use super::{GroupReaction3, Interface3, Probe3, Resultant3, SolidPrepared};
use crate::fem::element::{ElementKind, Point3, Vector3};
use crate::fem::solid::SolidModel;
use crate::mesh::Mesh;
use crate::output::SolidContactOutput;
use std::collections::BTreeMap;

/// The forces of a solved 3D model (as 2D's `post::forces`, without
/// contact).
pub(super) struct Forces3 {
    pub groups: Vec<GroupReaction3>,
    pub interfaces: BTreeMap<String, Interface3>,
    pub loads: Resultant3,
    pub strain_energy: f64,
    pub load_work: f64,
    /// Each point's reaction (zero off the supports).
    pub reaction: Vec<Vector3>,
}

/// Reactions R_p = (K u)_p − f_p at the held nodes, in the directions the
/// conditions fix; a node held by several groups shares its reaction
/// between them by the least-norm split over their condition directions
/// (each direction wholly to the one group that fixes it; equally between
/// groups that fix the same one). Strain energy ½uᵀKu and fᵀu.
pub(super) fn forces(
    prep: &SolidPrepared,
    m: &SolidModel,
    u: &[Vector3],
    contact: &SolidContactOutput,
) -> Forces3 {
    // The contact forces on the points, −λ c_p for each row Σ c_p·u_p ≤ g
    // (K u = f + contact + reaction), and each interface's resultant on
    // its slave side.
    let mut fc = vec![[0.0; 3]; m.points.len()];
    let mut interfaces: BTreeMap<String, Interface3> = BTreeMap::new();
    for (r, row) in m.contact.iter().enumerate() {
        let lam = contact.multiplier[r];
        let name = m.interface_names[row.interface as usize].clone();
        let it = interfaces.entry(name).or_default();
        it.rows += 1;
        it.active += usize::from(contact.active[r]);
        it.max_pressure = it.max_pressure.max(contact.pressure[r]);
        let slave_body = m.point_body[row.slave];
        // With friction the tangential force F on the slave point, −w F on
        // each master (−λ_t c_p of the tangential rows, docs/methods.md §12.6).
        let ft = contact.tangential_force.get(r).copied();
        for (p, c) in row.coefficients() {
            let mut f = c.map(|ck| -lam * ck);
            if let Some(ft) = ft {
                let w = if p == row.slave {
                    -1.0
                } else {
                    row.masters.iter().find(|q| q.0 == p).map_or(0.0, |q| q.1)
                };
                for k in 0..3 {
                    f[k] -= w * ft[k];
                }
            }
            for k in 0..3 {
                fc[p][k] += f[k];
            }
            if m.point_body[p] == slave_body {
                it.resultant.add(m.points[p], f);
            }
        }
    }
    let kind = ElementKind::Solid;
    let mats: Vec<_> = m
        .material_names
        .iter()
        .map(|n| kind.material(&prep.problem.file.materials[n]))
        .collect();
    let mut fint = vec![[0.0; 3]; m.points.len()];
    let mut strain_energy = 0.0;
    for (t, &mi) in m.tets.iter().zip(&m.tet_material) {
        let k = kind.tet_stiffness(&t.map(|v| m.points[v]), &mats[mi as usize]);
        let ue: [f64; 12] = std::array::from_fn(|i| u[t[i / 3]][i % 3]);
        for i in 0..12 {
            let fi: f64 = (0..12).map(|j| k[i][j] * ue[j]).sum();
            fint[t[i / 3]][i % 3] += fi;
            strain_energy += 0.5 * ue[i] * fi;
        }
    }
    let mut loads = Resultant3::default();
    let mut load_work = 0.0;
    for ((x, f), ui) in m.points.iter().zip(&m.loads).zip(u) {
        loads.add(*x, *f);
        load_work += f[0] * ui[0] + f[1] * ui[1] + f[2] * ui[2];
    }
    // The condition directions of each group at each node.
    let f = &prep.problem.file;
    let mut held: Vec<Vec<(usize, Vector3)>> = vec![vec![]; m.points.len()];
    let mut names: Vec<(String, String)> = vec![];
    let mut group = |on: &str, kind: &str| -> usize {
        match names.iter().position(|(n, _)| n == on) {
            Some(i) => {
                if !names[i].1.contains(kind) {
                    names[i].1 = format!("{}+{kind}", names[i].1);
                }
                i
            }
            None => {
                names.push((on.to_string(), kind.to_string()));
                names.len() - 1
            }
        }
    };
    let mesh = &prep.mesh;
    // The points of each node (one per body on a contact surface).
    let mut node_ptr = vec![0usize; mesh.nodes.len() + 1];
    for &v in &m.point_node {
        node_ptr[v + 1] += 1;
    }
    for v in 0..mesh.nodes.len() {
        node_ptr[v + 1] += node_ptr[v];
    }
    let nodes_of = |on: &str| -> Vec<usize> {
        let Some(g) = mesh.group_any(on) else {
            return vec![];
        };
        let mut v: Vec<usize> = match g.dim {
            0 => g.elements.iter().map(|&e| mesh.points[e]).collect(),
            1 => g.elements.iter().flat_map(|&e| mesh.lines[e]).collect(),
            2 => g.elements.iter().flat_map(|&e| mesh.triangles[e]).collect(),
            _ => g.elements.iter().flat_map(|&e| mesh.tets[e]).collect(),
        };
        v.sort_unstable();
        v.dedup();
        // Every point of those nodes: a condition holds each copy.
        v.iter()
            .flat_map(|&n| node_ptr[n]..node_ptr[n + 1])
            .collect()
    };
    // The model's size, as the build measured it for a turn's axis.
    let size = || crate::problem::model_size((0..mesh.nodes.len()).map(|i| mesh.node::<3>(i)));
    for d in &f.dirichlet {
        let gi = group(&d.on, "dirichlet");
        let comps = d.value.components();
        if let crate::problem::Prescribed::Turn(t) = d.value {
            // Held along each node's e_θ (none on the axis).
            let size = size();
            for v in nodes_of(&d.on) {
                if let Some((r, _)) = t.condition(m.points[v], size) {
                    held[v].push((gi, r));
                }
            }
        }
        for v in nodes_of(&d.on) {
            for (k, c) in comps.iter().enumerate() {
                if c.is_some() {
                    let mut r = [0.0; 3];
                    r[k] = 1.0;
                    held[v].push((gi, r));
                }
            }
        }
    }
    for s in &f.slip {
        let gi = group(&s.on, "slip");
        let nodes = nodes_of(&s.on);
        // The plane's normal: the fixed direction the elimination left
        // (the complement of the node's free directions), projected.
        let Some(n) = slip_normal(mesh, &s.on) else {
            continue;
        };
        for v in nodes {
            held[v].push((gi, n));
        }
    }
    let mut groups: Vec<GroupReaction3> = names
        .iter()
        .map(|(on, kind)| GroupReaction3 {
            on: on.clone(),
            kind: kind.clone(),
            points: 0,
            resultant: Resultant3::default(),
        })
        .collect();
    let mut reaction = vec![[0.0; 3]; m.points.len()];
    for (p, dirs) in held.iter().enumerate() {
        if dirs.is_empty() {
            continue;
        }
        let r = [0, 1, 2].map(|k| fint[p][k] - m.loads[p][k] - fc[p][k]);
        // α = Mᵀ (M Mᵀ)⁺ r: the least-norm split of r over the directions.
        let mut mmt = vec![vec![0.0; 3]; 3];
        for (_, d) in dirs {
            for i in 0..3 {
                for j in 0..3 {
                    mmt[i][j] += d[i] * d[j];
                }
            }
        }
        let (vals, vecs) = crate::linalg::dense::sym_eigen(&mmt);
        let top = vals.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let mut y = [0.0; 3];
        // sym_eigen gives the eigenvectors as rows: vecs[k] (read as
        // columns before, which only axis-aligned directions survived).
        for (k, &l) in vals.iter().enumerate() {
            if l.abs() > 1e-12 * top {
                let c: f64 = (0..3).map(|i| vecs[k][i] * r[i]).sum::<f64>() / l;
                for i in 0..3 {
                    y[i] += c * vecs[k][i];
                }
            }
        }
        let mut counted: Vec<usize> = vec![];
        for &(g, d) in dirs {
            let a = d[0] * y[0] + d[1] * y[1] + d[2] * y[2];
            groups[g].resultant.add(m.points[p], d.map(|c| a * c));
            for k in 0..3 {
                reaction[p][k] += a * d[k];
            }
            if !counted.contains(&g) {
                counted.push(g);
                groups[g].points += 1;
            }
        }
    }
    Forces3 {
        groups,
        interfaces,
        loads,
        strain_energy,
        load_work,
        reaction,
    }
}

/// Each interface's rows that stick and that slip (`stick_slip`, by
/// interface id; empty without friction) into the summary's interfaces.
pub(super) fn add_stick_slip(m: &SolidModel, f: &mut Forces3, stick_slip: &[(usize, usize)]) {
    for (i, &(stick, slip)) in stick_slip.iter().enumerate() {
        if let Some(it) = f.interfaces.get_mut(&m.interface_names[i]) {
            it.stick = Some(stick);
            it.slip = Some(slip);
        }
    }
}

/// The unit normal of the plane slip surface `on` (fem::solid has checked
/// that it is plane): its first triangle's.
fn slip_normal(mesh: &Mesh, on: &str) -> Option<Vector3> {
    let g = mesh.group(on, 2)?;
    let t = mesh.triangles[*g.elements.first()?];
    let p = t.map(|v| mesh.node::<3>(v));
    let (_, n) = ElementKind::Solid.facet_weight(&p);
    Some(n)
}

/// Each probe's nearest node and its displacement.
pub(super) fn probes(prep: &SolidPrepared, u: &[Vector3]) -> BTreeMap<String, Probe3> {
    let pts = &prep.model.points;
    prep.problem
        .file
        .output
        .probes
        .iter()
        .filter(|_| !pts.is_empty())
        .map(|(name, x)| {
            let x = x.xyz();
            let d2 = |p: &Point3| (0..3).map(|k| (p[k] - x[k]).powi(2)).sum::<f64>();
            let node = (0..pts.len())
                .min_by(|&a, &b| d2(&pts[a]).total_cmp(&d2(&pts[b])))
                .unwrap_or(0);
            (
                name.clone(),
                Probe3 {
                    x: pts[node][0],
                    y: pts[node][1],
                    z: pts[node][2],
                    node,
                    tag: prep.mesh.node_tags[prep.model.point_node[node]],
                    u: u[node],
                },
            )
        })
        .collect()
}

/// The contact surface's values (docs/problem-format.md §12): per row its
/// slave point, normal, gaps, λ and λ / area, active; the slave surfaces'
/// triangles on the rows.
pub(super) fn contact_output(
    prep: &SolidPrepared,
    m: &SolidModel,
    u: &[Vector3],
    lambda: &[f64],
    active: &[bool],
) -> SolidContactOutput {
    let r = m.contact.len();
    let mut multiplier = vec![0.0; r];
    let mut on = vec![false; r];
    for (i, &row) in m.qp_rows.iter().enumerate() {
        multiplier[row] = lambda.get(i).copied().unwrap_or(0.0);
        on[row] = active.get(i).copied().unwrap_or(false);
    }
    let mut c = SolidContactOutput {
        triangles: vec![],
        multiplier,
        active: on,
        ..Default::default()
    };
    for (k, row) in m.contact.iter().enumerate() {
        let moved: f64 = row
            .coefficients()
            .iter()
            .map(|(p, cp)| (0..3).map(|j| cp[j] * u[*p][j]).sum::<f64>())
            .sum();
        c.points.push(m.points[row.slave]);
        c.slave.push(row.slave);
        c.normal.push(row.normal);
        c.interface.push(row.interface);
        c.gap0.push(row.gap0);
        c.gap.push(row.gap0 - moved);
        c.pressure.push(c.multiplier[k] / row.area);
    }
    // Slave-surface triangles: (interface, node) → row.
    let mut row_of: std::collections::HashMap<(u32, usize), usize> =
        std::collections::HashMap::with_capacity(r);
    for (k, row) in m.contact.iter().enumerate() {
        row_of
            .entry((row.interface, m.point_node[row.slave]))
            .or_insert(k);
    }
    let mesh = &prep.mesh;
    for (i, pair) in prep.problem.file.contact.iter().enumerate() {
        let slave = match &pair.pair {
            crate::problem::ContactPair::Conforming { on, .. } => on,
            crate::problem::ContactPair::NonMatching(p) => &p.slave,
        };
        let Some(g) = mesh.group(slave, 2) else {
            continue;
        };
        for &e in &g.elements {
            let t = mesh.triangles[e];
            let rows: Vec<usize> = t
                .iter()
                .filter_map(|&v| row_of.get(&(i as u32, v)).copied())
                .collect();
            if let [a, b, d] = rows[..] {
                c.triangles.push([a, b, d]);
            }
        }
    }
    c
}
