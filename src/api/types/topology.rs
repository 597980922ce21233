//! Mesh connectivity built once per mesh: undirected edges with their faces, vertex
//! one-rings, ordered boundary loops, connected components and manifoldness.

use super::Mesh;

mod build;

/// Marks an absent face in `edge_faces`.
pub const NONE: u32 = u32::MAX;

/// The connectivity of a polygon mesh. Works on any mesh; non-manifold parts are recorded
/// (`nonmanifold_edges`, `nonmanifold_vertices`) rather than refused, so that nodes needing a
/// manifold can say exactly what is wrong.
#[derive(Clone, Debug)]
pub struct Topology {
    /// Number of vertices of the mesh.
    pub num_vertices: usize,
    /// Number of faces of the mesh.
    pub num_faces: usize,
    /// Unique undirected edges, each with its smaller vertex index first.
    pub edges: Vec<[u32; 2]>,
    /// The first two faces of each edge (`NONE` where absent).
    pub edge_faces: Vec<[u32; 2]>,
    /// For each face corner `c`, the edge from that corner to the next corner of its face.
    pub corner_edge: Vec<u32>,
    /// For each corner, its face.
    pub corner_face: Vec<u32>,
    neighbor_start: Vec<u32>,
    neighbors: Vec<u32>,
    vface_start: Vec<u32>,
    vfaces: Vec<u32>,
    /// Boundary loops, vertices in order with the faces on the left (counter-clockwise for a
    /// disk whose faces are counter-clockwise).
    pub boundary_loops: Vec<Vec<u32>>,
    /// Component id of each vertex (isolated vertices get their own component).
    pub vertex_component: Vec<u32>,
    /// Number of connected components (counting isolated vertices).
    pub num_components: usize,
    /// Vertices used by no face.
    pub isolated_vertices: usize,
    /// Edges with more than two faces.
    pub nonmanifold_edges: Vec<u32>,
    /// Vertices whose faces do not form a single fan.
    pub nonmanifold_vertices: Vec<u32>,
    /// Edges whose two faces run along them in the same direction (inconsistent orientation).
    pub misoriented_edges: Vec<u32>,
}

impl Topology {
    /// Builds the connectivity of `mesh`.
    pub fn build(mesh: &Mesh) -> Topology {
        let nv = mesh.num_vertices();
        let corners = build::Corners::new(mesh.face_indices(), mesh.face_starts());
        let mut t = build::Edges::build(&corners, nv);
        let (neighbor_start, neighbors) =
            compressed_rows(nv, t.edges.iter().flat_map(|&[a, b]| [(a, b), (b, a)]));
        let (vface_start, vfaces) = compressed_rows(
            nv,
            corners
                .idx
                .iter()
                .copied()
                .zip(corners.face.iter().copied()),
        );
        let (boundary_loops, mut nonmanifold_vertices) = build::boundary(&corners, &t, nv);
        nonmanifold_vertices.extend(build::split_fans(&corners, &mut t.fan, nv));
        nonmanifold_vertices.sort_unstable();
        nonmanifold_vertices.dedup();
        let (vertex_component, num_components) = build::components(&t.edges, nv);
        let isolated_vertices = (0..nv)
            .filter(|&v| vface_start[v] == vface_start[v + 1])
            .count();
        Topology {
            num_vertices: nv,
            num_faces: mesh.num_faces(),
            edges: t.edges,
            edge_faces: t.edge_faces,
            corner_edge: t.corner_edge,
            corner_face: corners.face,
            neighbor_start,
            neighbors,
            vface_start,
            vfaces,
            boundary_loops,
            vertex_component,
            num_components,
            isolated_vertices,
            nonmanifold_edges: t.nonmanifold_edges,
            nonmanifold_vertices,
            misoriented_edges: t.misoriented_edges,
        }
    }

    /// The vertices joined to `v` by an edge.
    pub fn neighbors(&self, v: usize) -> &[u32] {
        &self.neighbors[self.neighbor_start[v] as usize..self.neighbor_start[v + 1] as usize]
    }

    /// The faces that use vertex `v`.
    pub fn vertex_faces(&self, v: usize) -> &[u32] {
        &self.vfaces[self.vface_start[v] as usize..self.vface_start[v + 1] as usize]
    }

    /// Whether vertex `v` lies on a boundary loop.
    pub fn is_boundary_vertex(&self, v: usize) -> bool {
        let nb = self.neighbors(v);
        // A vertex is on the boundary when one of its edges has a single face.
        nb.iter().any(|&w| {
            self.edge_index(v as u32, w)
                .is_some_and(|e| self.edge_faces[e][1] == NONE)
        })
    }

    /// The index of the edge between `a` and `b`, if there is one.
    pub fn edge_index(&self, a: u32, b: u32) -> Option<usize> {
        let key = if a < b { [a, b] } else { [b, a] };
        self.edges.binary_search(&key).ok()
    }

    /// Number of undirected edges.
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }

    /// V - E + F, counting only vertices that some face uses.
    pub fn euler_characteristic(&self) -> i64 {
        (self.num_vertices - self.isolated_vertices) as i64 - self.edges.len() as i64
            + self.num_faces as i64
    }

    /// Whether every edge has at most two faces, consistently oriented, and every vertex is a
    /// single fan.
    pub fn is_manifold(&self) -> bool {
        self.nonmanifold_edges.is_empty()
            && self.nonmanifold_vertices.is_empty()
            && self.misoriented_edges.is_empty()
    }

    /// Number of connected components that have faces.
    pub fn num_face_components(&self) -> usize {
        self.num_components - self.isolated_vertices
    }

    /// Genus of a connected orientable manifold: chi = 2 - 2g - b. `None` for anything else.
    pub fn genus(&self) -> Option<i64> {
        if !self.is_manifold() || self.num_face_components() != 1 {
            return None;
        }
        let g2 = 2 - self.euler_characteristic() - self.boundary_loops.len() as i64;
        (g2 >= 0 && g2 % 2 == 0).then_some(g2 / 2)
    }

    /// Checks that the mesh is a topological disk (one component, manifold, one boundary loop,
    /// Euler characteristic 1), saying what is wrong otherwise.
    pub fn check_disk(&self) -> Result<(), NotADisk> {
        if !self.nonmanifold_edges.is_empty() || !self.nonmanifold_vertices.is_empty() {
            return Err(NotADisk::NonManifold {
                edges: self.nonmanifold_edges.len(),
                vertices: self.nonmanifold_vertices.len(),
            });
        }
        if !self.misoriented_edges.is_empty() {
            return Err(NotADisk::Misoriented(self.misoriented_edges.len()));
        }
        if self.num_face_components() != 1 {
            return Err(NotADisk::Components(self.num_face_components()));
        }
        match self.boundary_loops.len() {
            0 => return Err(NotADisk::Closed),
            1 => {}
            n => return Err(NotADisk::Holes(n)),
        }
        let chi = self.euler_characteristic();
        if chi != 1 {
            return Err(NotADisk::Genus(chi));
        }
        Ok(())
    }
}

/// Why a mesh is not a topological disk (`Topology::check_disk`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NotADisk {
    /// Edges with more than two faces or non-manifold vertices.
    #[error("mesh is not manifold ({edges} edges with more than two faces, {vertices} non-manifold vertices); a disk is needed")]
    NonManifold {
        /// Edges with more than two faces.
        edges: usize,
        /// Non-manifold vertices.
        vertices: usize,
    },
    /// Edges whose two faces disagree on orientation.
    #[error("mesh faces are inconsistently oriented ({0} edges); a disk is needed")]
    Misoriented(usize),
    /// More than one connected component.
    #[error("mesh has {0} connected components; a disk is needed")]
    Components(usize),
    /// No boundary.
    #[error("mesh is closed (no boundary loop); a disk is needed: cut it open first")]
    Closed,
    /// Several boundary loops.
    #[error("mesh has {0} boundary loops; a disk is needed; use holes: fill")]
    Holes(usize),
    /// One boundary but handles.
    #[error("mesh has Euler characteristic {0} (genus > 0); a disk has 1")]
    Genus(i64),
}

/// The fan triangulation of polygon faces given by their corner counts: for a face `f` whose
/// corners are `s..s + n`, the triangles `(s, s + k, s + k + 1)` for `k` in `1..n - 1`, as
/// `(f, [corner; 3])` in face order. Corners index the mesh's `face_indices`, so per-corner
/// and per-face data can follow the triangles. Exact for convex polygons; see
/// `nodes::mesh::mesh_triangulate` for ear clipping of non-convex ones.
pub fn fan_corners(face_counts: &[u32]) -> impl Iterator<Item = (usize, [usize; 3])> + '_ {
    face_counts
        .iter()
        .scan(0usize, |start, &n| {
            let s = *start;
            *start += n as usize;
            Some((s, n as usize))
        })
        .enumerate()
        .flat_map(|(f, (s, n))| (1..n.saturating_sub(1)).map(move |k| (f, [s, s + k, s + k + 1])))
}

impl Mesh {
    /// The faces as triangles: the faces themselves for a triangle mesh, otherwise every
    /// polygon split into a fan from its first corner (`fan_corners`). Unlike
    /// `triangulated()`, only the vertex indices, without copying the mesh's data.
    pub fn fan_triangles(&self) -> Vec<[u32; 3]> {
        if let Some(t) = self.triangles() {
            return t;
        }
        let idx = self.face_indices();
        fan_corners(self.face_counts())
            .map(|(_, c)| [idx[c[0]], idx[c[1]], idx[c[2]]])
            .collect()
    }
}

impl Topology {
    /// The triangles around each of `n` vertices in compressed rows (`start`, `triangle`):
    /// vertex `v`'s triangles are `triangle[start[v]..start[v + 1]]`, in increasing order.
    /// For triangle lists that are not a mesh's faces (e.g. after fan triangulation).
    pub fn vertex_triangles(n: usize, triangles: &[[u32; 3]]) -> (Vec<usize>, Vec<u32>) {
        let pairs = triangles
            .iter()
            .enumerate()
            .flat_map(|(t, tri)| tri.iter().map(move |&v| (v, t as u32)));
        let (start, list) = compressed_rows(n, pairs);
        (start.into_iter().map(|s| s as usize).collect(), list)
    }
}

/// The triangles of a grid of `cells_u x cells_v` squares, each split along its
/// `(i, j)-(i+1, j+1)` diagonal, counter-clockwise when `i` runs along x and `j` along y.
/// Vertex `(i, j)` is `id(i, j)` for `i` in `0..=cells_u`, `j` in `0..=cells_v` (row by row:
/// `grid_triangles`); the squares come row by row.
pub fn grid_triangles_with(
    cells_u: usize,
    cells_v: usize,
    id: impl Fn(usize, usize) -> u32,
) -> Vec<[u32; 3]> {
    let mut t = Vec::with_capacity(2 * cells_u * cells_v);
    for j in 0..cells_v {
        for i in 0..cells_u {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    t
}

/// `grid_triangles_with` for the vertices numbered row by row, `(i, j)` at
/// `j (cells_u + 1) + i` (the numbering of the `mesh_grid` node).
pub fn grid_triangles(cells_u: usize, cells_v: usize) -> Vec<[u32; 3]> {
    grid_triangles_with(cells_u, cells_v, |i, j| (j * (cells_u + 1) + i) as u32)
}

/// Compressed rows from (row, value) pairs: row `r` holds its values, in pair order, at
/// `values[start[r]..start[r + 1]]` (a counting sort by row).
fn compressed_rows(
    n: usize,
    pairs: impl Iterator<Item = (u32, u32)> + Clone,
) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; n + 1];
    for (r, _) in pairs.clone() {
        start[r as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut vals = vec![0u32; start[n] as usize];
    for (r, v) in pairs {
        vals[fill[r as usize] as usize] = v;
        fill[r as usize] += 1;
    }
    (start, vals)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Mesh {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push([i as f64, j as f64, 0.0]);
            }
        }
        let t = grid_triangles(n, n);
        Mesh::from_triangles(p, &t).unwrap()
    }

    #[test]
    fn grid_is_a_disk_with_ccw_boundary() {
        let m = grid(3);
        let t = m.topology();
        assert_eq!(t.num_edges(), 3 * 4 * 2 + 9);
        assert_eq!(t.euler_characteristic(), 1);
        assert_eq!(t.boundary_loops.len(), 1);
        assert_eq!(t.boundary_loops[0].len(), 12);
        assert!(t.check_disk().is_ok());
        assert_eq!(t.genus(), Some(0));
        // counter-clockwise: signed area of the loop is positive
        let lp = &t.boundary_loops[0];
        let mut area = 0.0;
        for k in 0..lp.len() {
            let a = m.positions[lp[k] as usize];
            let b = m.positions[lp[(k + 1) % lp.len()] as usize];
            area += a[0] * b[1] - a[1] * b[0];
        }
        assert!(area > 0.0);
        assert_eq!(t.neighbors(5).len(), 6);
        assert!(!t.is_boundary_vertex(5));
        assert!(t.is_boundary_vertex(0));
    }

    #[test]
    fn closed_tetrahedron_and_bowtie() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let m = Mesh::from_triangles(p, &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]).unwrap();
        let t = m.topology();
        assert_eq!(t.euler_characteristic(), 2);
        assert!(t.boundary_loops.is_empty());
        assert!(t.check_disk().unwrap_err().to_string().contains("closed"));
        // two triangles sharing only a vertex
        let p = vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
        ];
        let m = Mesh::from_triangles(p, &[[0, 1, 2], [0, 3, 4]]).unwrap();
        assert_eq!(m.topology().nonmanifold_vertices, vec![0]);
        assert!(!m.topology().is_manifold());
    }

    #[test]
    fn two_closed_cones_touching_at_a_tip_are_not_manifold() {
        // two tetrahedra sharing vertex 0 only: every edge has two faces, consistently
        // oriented, and no boundary, so only the fan test at vertex 0 can see the problem
        let p = vec![
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, -1.0],
        ];
        let tet = |a: u32, b: u32, c: u32| [[0, b, a], [0, a, c], [a, b, c], [0, c, b]];
        let mut tris = tet(1, 2, 3).to_vec();
        tris.extend(tet(4, 5, 6));
        let m = Mesh::from_triangles(p, &tris).unwrap();
        let t = m.topology();
        assert!(t.nonmanifold_edges.is_empty() && t.misoriented_edges.is_empty());
        assert_eq!(t.nonmanifold_vertices, vec![0]);
        // one tetrahedron alone is manifold at every vertex
        let p1 = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let one = Mesh::from_triangles(p1, &tet(1, 2, 3)).unwrap();
        assert!(one.topology().is_manifold());
    }

    #[test]
    fn fans_and_vertex_triangles() {
        let p = vec![[0.0; 3]; 6];
        // a pentagon and a triangle
        let m = Mesh::new(p, vec![5, 3], vec![0, 1, 2, 3, 4, 0, 4, 5]).unwrap();
        let fans: Vec<_> = fan_corners(m.face_counts()).collect();
        assert_eq!(
            fans,
            vec![
                (0, [0, 1, 2]),
                (0, [0, 2, 3]),
                (0, [0, 3, 4]),
                (1, [5, 6, 7])
            ]
        );
        let t = m.fan_triangles();
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);
        let (start, list) = Topology::vertex_triangles(6, &t);
        assert_eq!(start, vec![0, 4, 5, 7, 9, 11, 12]);
        assert_eq!(&list[..4], &[0, 1, 2, 3]);
        assert_eq!(&list[start[4]..start[5]], &[2, 3]);
    }
}
