//! The mesh as a graph: its edges (each with the one or two triangles it
//! borders) and a union-find over triangles, from which `topology.rs` cuts
//! the bodies (docs/methods.md §2.1, §2.3).

/// "No triangle" / "no body" in the u32 index arrays.
pub(super) const NONE32: u32 = u32::MAX;

/// The edges of a triangle mesh, grouped by their lower node: the edges
/// (a, b), a < b, of node a are `hi[ptr[a]..ptr[a + 1]]` (sorted by b), and
/// edge e borders the triangles `tri[e]` (the second NONE32 on a boundary).
/// An edge is found by a binary search in its lower node's list.
#[derive(Debug, Clone, Default)]
pub(super) struct Edges {
    ptr: Vec<usize>,
    hi: Vec<u32>,
    pub(super) tri: Vec<[u32; 2]>,
}

impl Edges {
    /// The edges of `tris` (nodes < nn < 2^32 − 1, fewer than (2^32 − 1) / 3
    /// triangles). Err((a, b)): the first edge (in triangle order, then
    /// local edge order) that a third triangle shares, as that triangle
    /// lists it.
    pub(super) fn build(nn: usize, tris: &[[usize; 3]]) -> Result<Edges, (usize, usize)> {
        // Half-edges (lower node, higher node, 3 × triangle + local edge),
        // sorted by lower node and, for one node, in (triangle, local
        // edge) order.
        let half_edges = || {
            tris.iter().enumerate().flat_map(|(t, tri)| {
                (0..3).map(move |k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    (a.min(b) as u32, a.max(b) as u32, (3 * t + k) as u32)
                })
            })
        };
        let (mut half, ptr) = super::sort::bucket_sort(half_edges, |h| h.0 as usize, nn);
        let mut out = Edges {
            ptr: Vec::with_capacity(nn + 1),
            hi: Vec::with_capacity(half.len() / 2 + nn),
            tri: Vec::with_capacity(half.len() / 2 + nn),
        };
        out.ptr.push(0);
        // The third half-edge (3t + k) of an overfull edge that comes first.
        let mut overfull: Option<u32> = None;
        for lo in 0..nn {
            let list = &mut half[ptr[lo]..ptr[lo + 1]];
            list.sort_unstable();
            let mut i = 0;
            while i < list.len() {
                let hi = list[i].1;
                let mut j = i + 1;
                while j < list.len() && list[j].1 == hi {
                    j += 1;
                }
                if j - i > 2 {
                    let third = list[i + 2].2;
                    if overfull.map(|o| third < o).unwrap_or(true) {
                        overfull = Some(third);
                    }
                }
                out.hi.push(hi);
                out.tri.push([
                    list[i].2 / 3,
                    if j - i > 1 { list[i + 1].2 / 3 } else { NONE32 },
                ]);
                i = j;
            }
            out.ptr.push(out.hi.len());
        }
        if let Some(tk) = overfull {
            let tri = tris[tk as usize / 3];
            let k = tk as usize % 3;
            return Err((tri[k], tri[(k + 1) % 3]));
        }
        Ok(out)
    }

    pub(super) fn len(&self) -> usize {
        self.hi.len()
    }

    /// The index of edge (a, b), if it is an edge of the mesh.
    pub(super) fn find(&self, a: usize, b: usize) -> Option<usize> {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        let (s, e) = (*self.ptr.get(lo)?, *self.ptr.get(lo + 1)?);
        let hi = u32::try_from(hi).ok()?;
        self.hi[s..e].binary_search(&hi).ok().map(|k| s + k)
    }
}

/// Union-find over fewer than 2^32 elements; a set's root is its lowest
/// element.
pub(super) struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    pub(super) fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }
    pub(super) fn find(&mut self, x: usize) -> usize {
        let mut x = x as u32;
        while self.parent[x as usize] != x {
            let g = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = g;
            x = g;
        }
        x as usize
    }
    pub(super) fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb) as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Edge (a, b), a < b → its triangles.
    type EdgeMap = HashMap<(usize, usize), Vec<usize>>;

    /// The former edge map (a HashMap filled in triangle order).
    fn edge_map(tris: &[[usize; 3]]) -> Result<EdgeMap, (usize, usize)> {
        let mut m: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (t, tri) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = m.entry((a.min(b), a.max(b))).or_default();
                if e.len() == 2 {
                    return Err((a, b));
                }
                e.push(t);
            }
        }
        Ok(m)
    }

    fn check_edges(nn: usize, tris: &[[usize; 3]]) {
        let reference = edge_map(tris);
        let edges = Edges::build(nn, tris);
        match (reference, edges) {
            (Err(a), Err(b)) => assert_eq!(a, b),
            (Ok(m), Ok(e)) => {
                assert_eq!(m.len(), e.len());
                for (&(a, b), ts) in &m {
                    let i = e.find(a, b).unwrap();
                    assert_eq!(e.find(b, a), Some(i));
                    let got: Vec<usize> = e.tri[i]
                        .iter()
                        .filter(|&&x| x != NONE32)
                        .map(|&x| x as usize)
                        .collect();
                    assert_eq!(&got, ts);
                }
            }
            (r, e) => panic!("{:?} vs {:?}", r.err(), e.err()),
        }
    }

    #[test]
    fn edges_match_a_hash_map() {
        for (_, _, mesh) in crate::shipped_examples() {
            check_edges(mesh.nodes.len(), &mesh.triangles);
        }
        // Random small "meshes" with shared and overfull edges.
        let mut s = 0x1234_5678_9abc_def1u64;
        let mut next = |n: u64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % n) as usize
        };
        for case in 0..2000 {
            let nn = 3 + next(8);
            let nt = 1 + next(12);
            let tris: Vec<[usize; 3]> = (0..nt)
                .map(|_| loop {
                    let t = [next(nn as u64), next(nn as u64), next(nn as u64)];
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        break t;
                    }
                })
                .collect();
            check_edges(nn, &tris);
            let _ = case;
        }
    }
}
