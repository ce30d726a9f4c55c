//! From what the sections read to a [`Mesh`]: node tags to dense indices,
//! elements and physical groups checked and collected.

use super::{Parser, Version};
use crate::mesh::{Mesh, MeshError, PhysicalGroup};
use std::collections::HashMap;

impl<'a> Parser<'a> {
    // ----- assembly -----

    pub(super) fn finish(mut self) -> Result<Mesh, MeshError> {
        if !self.have_nodes {
            return Err(self.invalid("no $Nodes section"));
        }
        if !self.have_elements {
            return Err(self.invalid("no $Elements section"));
        }

        // Physical groups of 4.1 element blocks, through their entities.
        if self.version == Version::V41 {
            let blocks = std::mem::take(&mut self.blocks);
            if let Some(ents) = &self.entities {
                for (&(d, _), phys) in ents {
                    for &p in phys {
                        self.groups.entry((d, p)).or_default();
                    }
                }
                for b in &blocks {
                    let d = b.kind.dim();
                    let Some(phys) = ents.get(&(d, b.entity)) else {
                        return Err(self.invalid(format!(
                            "$Elements: an element block refers to entity {} of dimension {d}, \
                             which is not in $Entities",
                            b.entity
                        )));
                    };
                    for &p in phys {
                        self.groups
                            .entry((d, p))
                            .or_default()
                            .extend(b.start..b.start + b.len);
                    }
                }
            }
            for g in self.groups.values_mut() {
                g.sort_unstable();
                g.dedup();
            }
        }
        for &k in self.names.keys() {
            self.groups.entry(k).or_default();
        }

        // Dense node numbering in increasing tag order.
        let n = self.node_tags.len();
        let sorted = self.node_tags.windows(2).all(|w| w[0] < w[1]);
        let (tags, xy) = if sorted {
            (
                std::mem::take(&mut self.node_tags),
                std::mem::take(&mut self.node_xy),
            )
        } else {
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_unstable_by_key(|&i| self.node_tags.get(i).copied().unwrap_or_default());
            let tags: Vec<u64> = order
                .iter()
                .map(|&i| self.node_tags.get(i).copied().unwrap_or_default())
                .collect();
            if let Some(w) = tags.windows(2).find(|w| w[0] == w[1]) {
                return Err(self.invalid(format!("$Nodes: duplicate node tag {}", w[0])));
            }
            let xy: Vec<[f64; 2]> = order
                .iter()
                .map(|&i| self.node_xy.get(i).copied().unwrap_or_default())
                .collect();
            (tags, xy)
        };
        let map = NodeMap::new(&tags);
        let lookup = |etag: u64, ntag: u64| -> Result<usize, MeshError> {
            map.get(ntag).ok_or_else(|| {
                self.invalid(format!(
                    "$Elements: element {etag} refers to node {ntag}, which is not in $Nodes"
                ))
            })
        };

        let e = &self.elems;
        let mut points = Vec::with_capacity(e.points.len());
        for (&t, &nd) in e.point_tags.iter().zip(&e.points) {
            points.push(lookup(t, nd)?);
        }
        let mut lines = Vec::with_capacity(e.lines.len());
        for (&t, nd) in e.line_tags.iter().zip(&e.lines) {
            lines.push([lookup(t, nd[0])?, lookup(t, nd[1])?]);
        }
        let mut triangles = Vec::with_capacity(e.tris.len());
        for (&t, nd) in e.tri_tags.iter().zip(&e.tris) {
            triangles.push([lookup(t, nd[0])?, lookup(t, nd[1])?, lookup(t, nd[2])?]);
        }
        let mut tets = Vec::with_capacity(e.tets.len());
        for (&t, nd) in e.tet_tags.iter().zip(&e.tets) {
            tets.push(
                nd.map(|v| lookup(t, v))
                    .into_iter()
                    .collect::<Result<Vec<_>, _>>()?,
            );
        }
        let tets: Vec<[usize; 4]> = tets.into_iter().map(|v| [v[0], v[1], v[2], v[3]]).collect();
        if triangles.is_empty() && tets.is_empty() {
            return Err(self.invalid(
                "$Elements: no triangles: the mesh has no 3-node triangle elements (type 2) \
                 (only elements in physical groups are saved by gmsh unless Mesh.SaveAll=1)",
            ));
        }

        let names = std::mem::take(&mut self.names);
        let groups = std::mem::take(&mut self.groups)
            .into_iter()
            .map(|((dim, tag), elements)| PhysicalGroup {
                dim,
                tag,
                name: names
                    .get(&(dim, tag))
                    .cloned()
                    .unwrap_or_else(|| tag.to_string()),
                elements,
            })
            .collect();

        let z = if tets.is_empty() {
            vec![]
        } else if sorted {
            std::mem::take(&mut self.node_z)
        } else {
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_unstable_by_key(|&i| self.node_tags.get(i).copied().unwrap_or_default());
            order
                .iter()
                .map(|&i| self.node_z.get(i).copied().unwrap_or_default())
                .collect()
        };
        let mut mesh = Mesh {
            path: self.path.to_path_buf(),
            nodes: xy,
            node_tags: tags,
            points,
            lines,
            triangle_tags: std::mem::take(&mut self.elems.tri_tags),
            triangles,
            groups,
            z,
            tets,
            tet_tags: std::mem::take(&mut self.elems.tet_tags),
        };
        if !mesh.tets.is_empty() {
            super::solid::check(&mut mesh)?;
        }
        Ok(mesh)
    }
}

/// Node tag -> dense index.
enum NodeMap {
    Dense { min: u64, idx: Vec<usize> },
    Sparse(HashMap<u64, usize>),
}

impl NodeMap {
    /// `tags` sorted, without duplicates.
    fn new(tags: &[u64]) -> NodeMap {
        let (Some(&min), Some(&max)) = (tags.first(), tags.last()) else {
            return NodeMap::Sparse(HashMap::new());
        };
        let range = max - min;
        if range <= 2 * tags.len() as u64 + 1024 {
            let mut idx = vec![usize::MAX; range as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                if let Some(slot) = idx.get_mut((t - min) as usize) {
                    *slot = i;
                }
            }
            NodeMap::Dense { min, idx }
        } else {
            NodeMap::Sparse(tags.iter().enumerate().map(|(i, &t)| (t, i)).collect())
        }
    }

    fn get(&self, tag: u64) -> Option<usize> {
        match self {
            NodeMap::Dense { min, idx } => {
                let k = usize::try_from(tag.checked_sub(*min)?).ok()?;
                idx.get(k).copied().filter(|&i| i != usize::MAX)
            }
            NodeMap::Sparse(m) => m.get(&tag).copied(),
        }
    }
}
