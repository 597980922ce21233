//! The passes `Topology::build` makes over a mesh's corners: undirected edges with their
//! faces and the fans they join, boundary loops, non-manifold vertices and components.

use super::NONE;

/// Corner tables: each corner's face and the next corner around that face.
pub(super) struct Corners<'m> {
    /// Vertex of each corner.
    pub idx: &'m [u32],
    pub face: Vec<u32>,
    pub next: Vec<u32>,
}

impl<'m> Corners<'m> {
    pub fn new(idx: &'m [u32], starts: &[u32]) -> Self {
        let nc = idx.len();
        let mut face = vec![0u32; nc];
        let mut next = vec![0u32; nc];
        for f in 0..starts.len().saturating_sub(1) {
            let (s, e) = (starts[f] as usize, starts[f + 1] as usize);
            for c in s..e {
                face[c] = f as u32;
                next[c] = if c + 1 == e { s as u32 } else { c as u32 + 1 };
            }
        }
        Corners { idx, face, next }
    }

    /// The vertices of corner `c`'s outgoing edge, smaller first.
    fn ends(&self, c: usize) -> (u32, u32) {
        let (a, b) = (self.idx[c], self.idx[self.next[c] as usize]);
        if a < b {
            (a, b)
        } else {
            (b, a)
        }
    }
}

/// The undirected edges and what walking them finds.
pub(super) struct Edges {
    pub edges: Vec<[u32; 2]>,
    pub edge_faces: Vec<[u32; 2]>,
    pub corner_edge: Vec<u32>,
    pub nonmanifold_edges: Vec<u32>,
    pub misoriented_edges: Vec<u32>,
    /// Union-find over corners: corners at one vertex whose faces share an edge there.
    pub fan: Vec<u32>,
}

/// Union-find root of `x`, halving the path.
pub(super) fn root(p: &mut [u32], mut x: u32) -> u32 {
    while p[x as usize] != x {
        p[x as usize] = p[p[x as usize] as usize];
        x = p[x as usize];
    }
    x
}

/// Joins the sets of `a` and `b` under the smaller root.
fn join(p: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (root(p, a), root(p, b));
    if ra != rb {
        p[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// Every corner's outgoing edge, bucketed by its smaller vertex (counting sort): bucket `lo`
/// is `keyed[bucket[lo]..bucket[lo + 1]]`, each entry (larger vertex, corner).
fn bucket_corners(c: &Corners, nv: usize) -> (Vec<u32>, Vec<(u32, u32)>) {
    let nc = c.idx.len();
    let mut bucket = vec![0u32; nv + 1];
    for k in 0..nc {
        bucket[c.ends(k).0 as usize + 1] += 1;
    }
    for v in 0..nv {
        bucket[v + 1] += bucket[v];
    }
    let mut slot = bucket.clone();
    let mut keyed: Vec<(u32, u32)> = vec![(0, 0); nc];
    for k in 0..nc {
        let (lo, hi) = c.ends(k);
        keyed[slot[lo as usize] as usize] = (hi, k as u32);
        slot[lo as usize] += 1;
    }
    (bucket, keyed)
}

impl Edges {
    /// Undirected edges: each short bucket of `bucket_corners` sorted by the larger vertex,
    /// so edges come out in (min, max) order without a global sort. Fans: corners at the
    /// same vertex whose faces share an edge at that vertex are joined (union-find over
    /// corners); a vertex with corners in two groups is not manifold.
    pub fn build(c: &Corners, nv: usize) -> Edges {
        let nc = c.idx.len();
        let (bucket, mut keyed) = bucket_corners(c, nv);
        let mut t = Edges {
            edges: Vec::with_capacity(nc / 2 + nv),
            edge_faces: Vec::with_capacity(nc / 2 + nv),
            corner_edge: vec![0u32; nc],
            nonmanifold_edges: Vec::new(),
            misoriented_edges: Vec::new(),
            fan: (0..nc as u32).collect(),
        };
        for lo in 0..nv {
            let run = &mut keyed[bucket[lo] as usize..bucket[lo + 1] as usize];
            run.sort_unstable();
            let mut i = 0;
            while i < run.len() {
                let hi = run[i].0;
                let j = i + run[i..].iter().take_while(|r| r.0 == hi).count();
                t.add_edge(c, [lo as u32, hi], &run[i..j]);
                i = j;
            }
        }
        t
    }

    /// Edge `ends` with the corners `run` (larger vertex, corner) running along it.
    fn add_edge(&mut self, c: &Corners, ends: [u32; 2], run: &[(u32, u32)]) {
        let e = self.edges.len() as u32;
        let mut ef = [NONE, NONE];
        let mut cs = [0u32; 2];
        for (k, &(_, corner)) in run.iter().enumerate() {
            self.corner_edge[corner as usize] = e;
            if k < 2 {
                ef[k] = c.face[corner as usize];
                cs[k] = corner;
            }
        }
        self.edges.push(ends);
        self.edge_faces.push(ef);
        if run.len() < 2 {
            return;
        }
        // the first two faces are joined across the edge, as for a manifold edge
        let [c0, c1] = cs;
        let (n0, n1) = (c.next[c0 as usize], c.next[c1 as usize]);
        let same_direction = c.idx[c0 as usize] == c.idx[c1 as usize];
        if same_direction {
            join(&mut self.fan, c0, c1);
            join(&mut self.fan, n0, n1);
        } else {
            join(&mut self.fan, c0, n1);
            join(&mut self.fan, n0, c1);
        }
        if run.len() > 2 {
            self.nonmanifold_edges.push(e);
        } else if same_direction {
            self.misoriented_edges.push(e);
        }
    }
}

/// Boundary loops, walked along the boundary half-edges (corners whose edge has a single
/// face), and the vertices with more than one boundary half-edge leaving them.
pub(super) fn boundary(c: &Corners, t: &Edges, nv: usize) -> (Vec<Vec<u32>>, Vec<u32>) {
    let idx = c.idx;
    let boundary_out = |k: usize| t.edge_faces[t.corner_edge[k] as usize][1] == NONE;
    let (out_start, out_corner) = super::compressed_rows(
        nv,
        (0..idx.len())
            .filter(|&k| boundary_out(k))
            .map(|k| (idx[k], k as u32)),
    );
    let nonmanifold_vertices = (0..nv)
        .filter(|&v| out_start[v + 1] - out_start[v] > 1)
        .map(|v| v as u32)
        .collect();
    let mut used = vec![false; out_corner.len()];
    let mut loops = Vec::new();
    for start in 0..out_corner.len() {
        if used[start] {
            continue;
        }
        let mut lp = Vec::new();
        let mut h = start;
        loop {
            used[h] = true;
            let k = out_corner[h] as usize;
            lp.push(idx[k]);
            let w = idx[c.next[k] as usize] as usize;
            let cand = (out_start[w]..out_start[w + 1])
                .map(|k| k as usize)
                .find(|&k| !used[k]);
            match cand {
                Some(k) => h = k,
                None => break,
            }
        }
        loops.push(lp);
    }
    (loops, nonmanifold_vertices)
}

/// Interior fans: the vertices whose corners fall into several groups (two cones touching at
/// a tip).
pub(super) fn split_fans(c: &Corners, fan: &mut [u32], nv: usize) -> Vec<u32> {
    let mut fans_at = vec![0u8; nv];
    for k in 0..c.idx.len() {
        if root(fan, k as u32) == k as u32 {
            let f = &mut fans_at[c.idx[k] as usize];
            *f = f.saturating_add(1);
        }
    }
    (0..nv as u32)
        .filter(|&v| fans_at[v as usize] > 1)
        .collect()
}

/// Component id of each vertex, numbered in vertex order, by union-find over `edges`; and
/// the number of components.
pub(super) fn components(edges: &[[u32; 2]], nv: usize) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..nv as u32).collect();
    for &[a, b] in edges {
        join(&mut parent, a, b);
    }
    let mut comp_id = vec![NONE; nv];
    let mut vertex_component = vec![0u32; nv];
    let mut num_components = 0;
    for (v, comp) in vertex_component.iter_mut().enumerate() {
        let r = root(&mut parent, v as u32) as usize;
        if comp_id[r] == NONE {
            comp_id[r] = num_components as u32;
            num_components += 1;
        }
        *comp = comp_id[r];
    }
    (vertex_component, num_components)
}
