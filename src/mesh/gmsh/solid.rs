//! The checks of a 3D mesh (one with tetrahedra): every tetrahedron has a
//! volume, a Physical Volume is oriented one way (reordered when it is the
//! negative one, as a 2D body of clockwise triangles is; a tetrahedron
//! against the rest of its volume is refused), and every triangle is a face
//! of the volume mesh (a 2D surface beside 3D volumes is refused). The
//! messages name the file and the group (docs/problem-format.md §3D).

use crate::mesh::{Mesh, MeshError};
use std::collections::{HashMap, HashSet};

/// Six times the signed volume of `p`: positive when (p1 − p0, p2 − p0,
/// p3 − p0) is right-handed.
pub fn volume6(p: &[[f64; 3]; 4]) -> f64 {
    let d = |k: usize| [0, 1, 2].map(|i| p[k][i] - p[0][i]);
    let (a, b, c) = (d(1), d(2), d(3));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The name of the first physical group of dimension `dim` holding each
/// element of that dimension ("" for none), `n` elements.
fn group_of(mesh: &Mesh, dim: u8, n: usize) -> Vec<&str> {
    let mut g = vec![""; n];
    for grp in mesh.groups.iter().filter(|g| g.dim == dim) {
        for &e in &grp.elements {
            if let Some(s) = g.get_mut(e) {
                if s.is_empty() {
                    *s = grp.name.as_str();
                }
            }
        }
    }
    g
}

fn label(kind: &str, name: &str) -> String {
    if name.is_empty() {
        format!("(in no physical {kind})")
    } else {
        format!("of physical {kind} '{name}'")
    }
}

/// Check a 3D mesh and orient its tetrahedra positively (see the module).
pub(super) fn check(mesh: &mut Mesh) -> Result<(), MeshError> {
    let invalid = |msg: String| MeshError::Invalid {
        path: mesh.path.clone(),
        msg,
    };
    let vol_group = group_of(mesh, 3, mesh.tets.len());
    // Signed volumes, zero-volume tetrahedra refused.
    let mut sign = Vec::with_capacity(mesh.tets.len());
    for (t, tet) in mesh.tets.iter().enumerate() {
        let p = tet.map(|v| mesh.node::<3>(v));
        let v6 = volume6(&p);
        let mut e2 = 0.0f64;
        for i in 0..4 {
            for j in i + 1..4 {
                e2 = e2.max((0..3).map(|k| (p[i][k] - p[j][k]).powi(2)).sum());
            }
        }
        // false for NaN too
        if !(v6.abs() > 1e-12 * e2.powf(1.5)) {
            return Err(invalid(format!(
                "tetrahedron {} {} has zero volume ({:.3e}): a flat or collapsed element; re-mesh",
                mesh.tet_tags[t],
                label("volume", vol_group[t]),
                v6 / 6.0
            )));
        }
        sign.push(v6 > 0.0);
    }
    // One orientation per volume: the majority's; the rest is refused.
    let mut count: HashMap<&str, (usize, usize)> = HashMap::new();
    for (t, &s) in sign.iter().enumerate() {
        let c = count.entry(vol_group[t]).or_default();
        if s {
            c.0 += 1;
        } else {
            c.1 += 1;
        }
    }
    for (t, &s) in sign.iter().enumerate() {
        let (pos, neg) = count[vol_group[t]];
        let majority_pos = pos >= neg;
        if s != majority_pos {
            return Err(invalid(format!(
                "tetrahedron {} {} is inverted (its orientation differs from the rest of the volume)",
                mesh.tet_tags[t],
                label("volume", vol_group[t])
            )));
        }
    }
    for (t, tet) in mesh.tets.iter_mut().enumerate() {
        if !sign[t] {
            tet.swap(2, 3);
        }
    }
    // Every triangle a face of the volume mesh.
    let mut faces: HashSet<[usize; 3]> = HashSet::with_capacity(4 * mesh.tets.len());
    let mut on_tet = vec![false; mesh.nodes.len()];
    for tet in &mesh.tets {
        for skip in 0..4 {
            let mut f = [0usize; 3];
            let mut k = 0;
            for (i, &v) in tet.iter().enumerate() {
                if i != skip {
                    f[k] = v;
                    k += 1;
                }
            }
            f.sort_unstable();
            faces.insert(f);
        }
        for &v in tet {
            on_tet[v] = true;
        }
    }
    let surf_group = group_of(mesh, 2, mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut f = *tri;
        f.sort_unstable();
        if faces.contains(&f) {
            continue;
        }
        let what = label("surface", surf_group[t]);
        return Err(invalid(if tri.iter().all(|&v| !on_tet[v]) {
            format!(
                "triangle {} {what} lies away from every tetrahedron: the mesh mixes 2D surfaces and 3D volumes; a 3D model's bodies are Physical Volumes and its surfaces their boundary",
                mesh.triangle_tags[t]
            )
        } else {
            format!(
                "triangle {} {what} is not a face of the volume mesh: a boundary surface must be made of faces of the tetrahedra (mesh the surface with its volume, `gmsh -3`)",
                mesh.triangle_tags[t]
            )
        }));
    }
    Ok(())
}
