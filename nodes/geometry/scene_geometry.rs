//! Scene geometry flattened for rasterization: world-space triangles with per-corner
//! normals, UVs and tangent frames, and the material of each triangle.
//!
//! Tangent frames follow Lengyel, "Computing Tangent Space Basis Vectors for an Arbitrary
//! Mesh" (2001): per triangle, T and B solve `e1 = du1 T + dv1 B`, `e2 = du2 T + dv2 B`;
//! they are summed at the vertices, T is made orthogonal to the normal (Gram-Schmidt) and
//! the handedness `w = sign((N x T) . B)` is kept so `B = w N x T`.

use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{cross, dot, normalize, scale, sub};
use cgnodes_api::types::Domain;
use rayon::prelude::*;

/// All triangles of a scene, with their corner attributes.
#[derive(Clone, Debug, Default)]
pub struct SceneGeometry {
    /// World positions of the three corners.
    pub pos: Vec<[[f64; 3]; 3]>,
    /// Unit shading normals at the corners.
    pub nrm: Vec<[[f64; 3]; 3]>,
    /// UVs at the corners (zeros when the mesh has none).
    pub uv: Vec<[[f64; 2]; 3]>,
    /// Tangents with handedness (x, y, z, w) at the corners (zeros without UVs).
    pub tan: Vec<[[f64; 4]; 3]>,
    /// Index into `materials` of each triangle.
    pub mat: Vec<u32>,
    /// Whether the triangle's mesh has UVs.
    pub has_uv: Vec<bool>,
    /// The materials (resolved: object's, else mesh's, else the default).
    pub materials: Vec<Arc<Material>>,
    /// Bounding box of all positions.
    pub bounds: ([f64; 3], [f64; 3]),
}

impl SceneGeometry {
    /// Empties every array, keeping its capacity, and drops the materials.
    pub fn clear(&mut self) {
        self.pos.clear();
        self.nrm.clear();
        self.uv.clear();
        self.tan.clear();
        self.mat.clear();
        self.has_uv.clear();
        self.materials.clear();
        self.bounds = ([0.0; 3], [0.0; 3]);
    }
}

/// Flattens a scene's meshes to triangles (polygons fan-triangulated). Normals come from
/// the mesh when it has them, else area-weighted vertex normals; tangents from the UVs.
pub fn scene_geometry(scene: &Scene) -> Result<SceneGeometry, SceneGeometryError> {
    scene_geometry_creased(scene, 180.0)
}

/// `scene_geometry` where the computed vertex normals (meshes without normals) average only
/// the faces around a vertex whose normals are within `crease_deg` of the corner's own face
/// (180 smooths everything, 0 gives flat shading), so the edges of a box stay sharp while a
/// tessellated sphere shades smooth. The tracers use it with a crease angle.
pub fn scene_geometry_creased(
    scene: &Scene,
    crease_deg: f64,
) -> Result<SceneGeometry, SceneGeometryError> {
    scene_geometry_in(scene, crease_deg, SceneGeometry::default())
}

/// `scene_geometry_creased` writing into the arrays of `g` (cleared first, their capacity
/// kept): a caller rendering frame after frame passes the previous frame's geometry, so the
/// arrays (about 45 MB for 154k triangles) are neither reallocated nor page-faulted again.
/// Every array is reserved for the scene's triangle count up front and filled in place.
pub fn scene_geometry_in(
    scene: &Scene,
    crease_deg: f64,
    g: SceneGeometry,
) -> Result<SceneGeometry, SceneGeometryError> {
    flatten(scene, crease_deg, g, true)
}

/// `scene_geometry_creased` without the corner UVs and tangents (`uv` and `tan` left
/// empty; `has_uv` still filled): what a renderer needs when no material has a texture,
/// without writing their 22 MB of zeros for 154k triangles.
pub fn scene_shape_creased(
    scene: &Scene,
    crease_deg: f64,
) -> Result<SceneGeometry, SceneGeometryError> {
    flatten(scene, crease_deg, SceneGeometry::default(), false)
}

/// `scene_geometry_in`, with the corner UVs and tangents only when `attributes`.
fn flatten(
    scene: &Scene,
    crease_deg: f64,
    mut g: SceneGeometry,
    attributes: bool,
) -> Result<SceneGeometry, SceneGeometryError> {
    g.clear();
    g.reserve_triangles(scene);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let default_mat = Arc::new(Material::default());
    for (oi, obj, mesh, tris) in object_triangles(scene) {
        if mesh.positions.iter().flatten().any(|x| !x.is_finite()) {
            return Err(SceneGeometryError::NonFinitePositions { object: oi });
        }
        let material = obj
            .material
            .clone()
            .or_else(|| mesh.material.clone())
            .unwrap_or_else(|| default_mat.clone());
        let mi = g.material_index(material);
        let p = &mesh.positions;
        for q in p {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        // Every array is filled in place from index `base` (reserved above).
        let base = g.pos.len();
        let nt = tris.len();
        g.push_normals(&mesh, &tris, crease_deg);
        let has_uv = if attributes {
            g.push_uvs(&mesh, &tris)
        } else {
            uvs_fit(&mesh, &tris)
        };
        if !attributes {
            // Neither UVs nor tangents.
        } else if has_uv {
            let (tan, nrm, uv) = (&mut g.tan, &g.nrm[base..], &g.uv[base..]);
            push_tangents(tan, p, &tris, nrm, uv);
        } else {
            g.tan.par_extend(rayon::iter::repeat_n([[0.0; 4]; 3], nt));
        }
        g.pos
            .par_extend(tris.par_iter().map(|tri| tri.map(|v| p[v as usize])));
        g.has_uv.resize(g.has_uv.len() + nt, has_uv);
        g.mat.resize(g.mat.len() + nt, mi);
    }
    if g.pos.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    g.bounds = (lo, hi);
    Ok(g)
}

/// The objects that have triangles, in scene order, each with its index, its mesh as
/// triangles and their corners: the walk `flatten` and `scene_positions` share, so that
/// their triangles come in the same order.
fn object_triangles(
    scene: &Scene,
) -> impl Iterator<Item = (usize, &SceneObject, Arc<Mesh>, Vec<[u32; 3]>)> {
    scene.objects.iter().enumerate().filter_map(|(oi, obj)| {
        let mesh = obj.mesh.triangulated();
        let tris = mesh.triangles().unwrap_or_default();
        (!tris.is_empty()).then_some((oi, obj, mesh, tris))
    })
}

/// The world positions of the triangles of `scene_shape_creased` (and
/// `scene_geometry_creased`), in the same order, without their normals: a renderer can
/// start its BVH on them while the normals are computed.
pub fn scene_positions(scene: &Scene) -> Vec<[[f32; 3]; 3]> {
    let mut pos = Vec::new();
    for (_, _, mesh, tris) in object_triangles(scene) {
        let p = &mesh.positions;
        let f = |v: u32| p[v as usize].map(|x| x as f32);
        pos.par_extend(tris.par_iter().map(|t| t.map(f)));
    }
    pos
}

/// Why a scene cannot be flattened.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneGeometryError {
    /// An object's mesh has a NaN or infinite position.
    #[error("mesh {object} has non-finite positions")]
    NonFinitePositions {
        /// The object's index in the scene.
        object: usize,
    },
}

/// The renderers report errors as text: the message unchanged.
impl From<SceneGeometryError> for String {
    fn from(e: SceneGeometryError) -> String {
        e.to_string()
    }
}

impl SceneGeometry {
    /// Reserves every array for the scene's triangles: fan triangulation gives n - 2
    /// triangles per polygon of n corners.
    fn reserve_triangles(&mut self, scene: &Scene) {
        let total: usize = scene
            .objects
            .iter()
            .map(|o| {
                let c = o.mesh.face_counts().iter();
                c.map(|&n| (n as usize).saturating_sub(2)).sum::<usize>()
            })
            .sum();
        self.pos.reserve_exact(total);
        self.nrm.reserve_exact(total);
        self.uv.reserve_exact(total);
        self.tan.reserve_exact(total);
        self.mat.reserve_exact(total);
        self.has_uv.reserve_exact(total);
    }

    /// The index of `material` in `materials` (by pointer), appending it when new.
    fn material_index(&mut self, material: Arc<Material>) -> u32 {
        (match self
            .materials
            .iter()
            .position(|m| Arc::ptr_eq(m, &material))
        {
            Some(i) => i,
            None => {
                self.materials.push(material);
                self.materials.len() - 1
            }
        }) as u32
    }

    /// Appends the corner normals of the triangles `tris` of `mesh`: its own normals when
    /// they fit, else crease-angle normals (`crease_deg` under 180), else area-weighted
    /// vertex normals.
    fn push_normals(&mut self, mesh: &Mesh, tris: &[[u32; 3]], crease_deg: f64) {
        let p = &mesh.positions;
        match &mesh.normals {
            Some(a) if attr_len_ok(a.domain, a.values.len(), p.len(), tris.len()) => self
                .nrm
                .par_extend((0..tris.len()).into_par_iter().map(|t| {
                    std::array::from_fn(|k| {
                        let v = match a.domain {
                            Domain::Vertex => a.values[tris[t][k] as usize],
                            Domain::Corner => a.values[3 * t + k],
                            Domain::Face => a.values[t],
                        };
                        normalize(v).unwrap_or([0.0, 0.0, 1.0])
                    })
                })),
            _ if crease_deg < 180.0 => creased_normals_into(&mut self.nrm, p, tris, crease_deg),
            _ => {
                let mut vn = vec![[0.0; 3]; p.len()];
                for t in tris {
                    let n = cross(
                        sub(p[t[1] as usize], p[t[0] as usize]),
                        sub(p[t[2] as usize], p[t[0] as usize]),
                    );
                    for &v in t {
                        for k in 0..3 {
                            vn[v as usize][k] += n[k];
                        }
                    }
                }
                self.nrm.par_extend(tris.par_iter().map(|t| {
                    let f = normalize(cross(
                        sub(p[t[1] as usize], p[t[0] as usize]),
                        sub(p[t[2] as usize], p[t[0] as usize]),
                    ))
                    .unwrap_or([0.0, 0.0, 1.0]);
                    std::array::from_fn(|k| normalize(vn[t[k] as usize]).unwrap_or(f))
                }))
            }
        };
    }

    /// Appends the corner UVs of the triangles `tris` of `mesh` (zeros when it has none that
    /// fit); whether it had them.
    fn push_uvs(&mut self, mesh: &Mesh, tris: &[[u32; 3]]) -> bool {
        match &mesh.uvs {
            Some(a) if attr_len_ok(a.domain, a.values.len(), mesh.positions.len(), tris.len()) => {
                self.uv.extend((0..tris.len()).map(|t| {
                    std::array::from_fn(|k| match a.domain {
                        Domain::Vertex => a.values[tris[t][k] as usize],
                        Domain::Corner => a.values[3 * t + k],
                        Domain::Face => a.values[t],
                    })
                }));
                true
            }
            // Zeros for a mesh without UVs, written in parallel.
            _ => {
                self.uv
                    .par_extend(rayon::iter::repeat_n([[0.0; 2]; 3], tris.len()));
                false
            }
        }
    }
}

/// Appends the corner tangents (Lengyel 2001) of the triangles `tris` over positions `p`,
/// accumulated per position vertex from the corner UVs `uvs` and made orthogonal to the
/// corner normals `corner_normals`, with the handedness in w.
fn push_tangents(
    tan: &mut Vec<[[f64; 4]; 3]>,
    p: &[[f64; 3]],
    tris: &[[u32; 3]],
    corner_normals: &[[[f64; 3]; 3]],
    uvs: &[[[f64; 2]; 3]],
) {
    let mut tv = vec![[0.0; 3]; p.len()];
    let mut bv = vec![[0.0; 3]; p.len()];
    for (t, tri) in tris.iter().enumerate() {
        let [p0, p1, p2] = tri.map(|v| p[v as usize]);
        let [w0, w1, w2] = uvs[t];
        let (e1, e2) = (sub(p1, p0), sub(p2, p0));
        let (du1, dv1) = (w1[0] - w0[0], w1[1] - w0[1]);
        let (du2, dv2) = (w2[0] - w0[0], w2[1] - w0[1]);
        let det = du1 * dv2 - du2 * dv1;
        if det.abs() < 1e-20 {
            continue;
        }
        let r = 1.0 / det;
        let tt: [f64; 3] = std::array::from_fn(|k| (e1[k] * dv2 - e2[k] * dv1) * r);
        let bb: [f64; 3] = std::array::from_fn(|k| (e2[k] * du1 - e1[k] * du2) * r);
        for &v in tri {
            for k in 0..3 {
                tv[v as usize][k] += tt[k];
                bv[v as usize][k] += bb[k];
            }
        }
    }
    tan.par_extend((0..tris.len()).into_par_iter().map(|t| {
        std::array::from_fn(|k| {
            let v = tris[t][k] as usize;
            let n = corner_normals[t][k];
            let tt = tv[v];
            let ortho = sub(tt, scale(n, dot(n, tt)));
            match normalize(ortho) {
                Some(o) => {
                    let w = if dot(cross(n, o), bv[v]) < 0.0 {
                        -1.0
                    } else {
                        1.0
                    };
                    [o[0], o[1], o[2], w]
                }
                None => [0.0; 4],
            }
        })
    }));
}

/// Per-corner normals averaging, area-weighted (the unnormalised cross products), the
/// faces around the corner's vertex whose unit normals are within `crease_deg` of the
/// corner's face (the crease-angle smoothing of modelling packages, e.g. Blender's auto
/// smooth). Degenerate faces take +z.
pub fn creased_normals(p: &[[f64; 3]], tris: &[[u32; 3]], crease_deg: f64) -> Vec<[[f64; 3]; 3]> {
    let mut out = Vec::new();
    creased_normals_into(&mut out, p, tris, crease_deg);
    out
}

/// `creased_normals` appended to `out`, written in place (no second copy of the corner
/// normals, 11 MB for 154k triangles).
pub fn creased_normals_into(
    out: &mut Vec<[[f64; 3]; 3]>,
    p: &[[f64; 3]],
    tris: &[[u32; 3]],
    crease_deg: f64,
) {
    // Per face: the area-weighted normal and the unit one.
    let faces: Vec<([f64; 3], [f64; 3])> = tris
        .par_iter()
        .map(|t| {
            let n = cross(
                sub(p[t[1] as usize], p[t[0] as usize]),
                sub(p[t[2] as usize], p[t[0] as usize]),
            );
            (n, normalize(n).unwrap_or([0.0, 0.0, 1.0]))
        })
        .collect();
    // Faces around each vertex (compressed rows).
    let mut start = vec![0usize; p.len() + 1];
    for t in tris {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..p.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; start[p.len()]];
    for (f, t) in tris.iter().enumerate() {
        for &v in t {
            around[fill[v as usize]] = f as u32;
            fill[v as usize] += 1;
        }
    }
    let crease = crease_deg.clamp(0.0, 180.0).to_radians();
    let cos_c = crease.cos() - 1e-9;
    // A vertex whose faces all lie within half the crease angle (less 1e-6 rad, far above
    // the dot products' round-off) of their area-weighted mean passes the crease test for
    // every pair of its faces, so each of its corners gets the full sum: computed once per
    // vertex, in the corners' order (the same bits), instead of once per corner.
    let cos_half = if crease / 2.0 > 1e-6 {
        (crease / 2.0 - 1e-6).cos()
    } else {
        f64::INFINITY
    };
    let whole: Vec<Option<[f64; 3]>> = (0..p.len())
        .into_par_iter()
        .map(|v| {
            let around = &around[start[v]..start[v + 1]];
            let mut n = [0.0; 3];
            for &f in around {
                let area_n = faces[f as usize].0;
                for c in 0..3 {
                    n[c] += area_n[c];
                }
            }
            let m = normalize(n)?;
            let inside = |&f: &u32| dot(faces[f as usize].1, m) >= cos_half;
            around.iter().all(inside).then_some(m)
        })
        .collect();
    out.par_extend((0..tris.len()).into_par_iter().map(|t| {
        let unit = faces[t].1;
        std::array::from_fn(|k| {
            let v = tris[t][k] as usize;
            if let Some(m) = whole[v] {
                return m;
            }
            let mut n = [0.0; 3];
            for &f in &around[start[v]..start[v + 1]] {
                let (area_n, unit_f) = faces[f as usize];
                if dot(unit_f, unit) >= cos_c {
                    for c in 0..3 {
                        n[c] += area_n[c];
                    }
                }
            }
            normalize(n).unwrap_or(unit)
        })
    }));
}

/// The normal `n` (unit, at barycentrics `b` of a triangle with corner tangents `tan`)
/// perturbed by a tangent-space normal-map texel `c` (components in 0..1 encoding -1..1):
/// `q.x T + q.y B + q.z N` with T the interpolated tangent made orthogonal to `n` and
/// `B = w N x T`. `None` when the triangle has no tangent frame. Shared by the rasterizer
/// and the tracers.
pub fn normal_mapped(
    n: [f64; 3],
    tan: &[[f64; 4]; 3],
    b: [f64; 3],
    c: [f32; 4],
) -> Option<[f64; 3]> {
    let tt: [f64; 3] =
        std::array::from_fn(|k| b[0] * tan[0][k] + b[1] * tan[1][k] + b[2] * tan[2][k]);
    let tt = normalize(sub(tt, scale(n, dot(n, tt))))?;
    let w = if tan[0][3] < 0.0 { -1.0 } else { 1.0 };
    let bb = scale(cross(n, tt), w);
    let q = [0, 1, 2].map(|k| 2.0 * c[k] as f64 - 1.0);
    normalize(std::array::from_fn(|k| {
        q[0] * tt[k] + q[1] * bb[k] + q[2] * n[k]
    }))
}

/// Whether `mesh` has UVs that fit its triangles `tris` (as `push_uvs` decides).
fn uvs_fit(mesh: &Mesh, tris: &[[u32; 3]]) -> bool {
    let fits = |a: &Attribute<[f64; 2]>| {
        attr_len_ok(a.domain, a.values.len(), mesh.positions.len(), tris.len())
    };
    mesh.uvs.as_ref().is_some_and(fits)
}

fn attr_len_ok(d: Domain, n: usize, nv: usize, nt: usize) -> bool {
    match d {
        Domain::Vertex => n == nv,
        Domain::Corner => n == 3 * nt,
        Domain::Face => n == nt,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube (corners at ±1) as twelve triangles, counter-clockwise from outside.
    fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let p: Vec<[f64; 3]> = (0..8)
            .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { 1.0 } else { -1.0 }))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, t)
    }

    /// Below the crease angle a cube keeps its face normals; at 180 degrees a corner's
    /// normal points into its vertex's octant; a fine sphere's creased normals are radial
    /// within a degree; appending to a non-empty array keeps what was there.
    #[test]
    fn creased_normals_keep_edges_and_smooth_curved_surfaces() {
        let (p, t) = cube();
        let unit = |t: &[u32; 3]| {
            normalize(cross(
                sub(p[t[1] as usize], p[t[0] as usize]),
                sub(p[t[2] as usize], p[t[0] as usize]),
            ))
            .unwrap()
        };
        for (tri, c) in t.iter().zip(creased_normals(&p, &t, 60.0)) {
            let f = unit(tri);
            assert!(dot(f, p[tri[0] as usize]) > 0.0, "outward");
            for n in c {
                assert!(dot(n, f) > 1.0 - 1e-12, "{n:?} against {f:?}");
            }
        }
        for (tri, c) in t.iter().zip(creased_normals(&p, &t, 180.0)) {
            for (k, n) in c.iter().enumerate() {
                let v = p[tri[k] as usize];
                assert!((0..3).all(|a| n[a] * v[a] > 0.0), "{n:?} at {v:?}");
            }
        }
        // A UV sphere of 64 x 32 segments (poles as fans).
        let (nu, nv) = (64u32, 32u32);
        let mut sp = vec![[0.0, 0.0, 1.0]];
        for j in 1..nv {
            let th = std::f64::consts::PI * j as f64 / nv as f64;
            for i in 0..nu {
                let ph = std::f64::consts::TAU * i as f64 / nu as f64;
                sp.push([th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]);
            }
        }
        sp.push([0.0, 0.0, -1.0]);
        let ring = |j: u32, i: u32| 1 + (j - 1) * nu + i % nu;
        let mut st = Vec::new();
        for i in 0..nu {
            st.push([0, ring(1, i), ring(1, i + 1)]);
            st.push([sp.len() as u32 - 1, ring(nv - 1, i + 1), ring(nv - 1, i)]);
            for j in 1..nv - 1 {
                let (a, b) = (ring(j, i), ring(j, i + 1));
                let (c, d) = (ring(j + 1, i), ring(j + 1, i + 1));
                st.push([a, c, d]);
                st.push([a, d, b]);
            }
        }
        let mut out = vec![[[7.0; 3]; 3]];
        creased_normals_into(&mut out, &sp, &st, 60.0);
        assert_eq!(out.len(), st.len() + 1);
        assert_eq!(out[0], [[7.0; 3]; 3]);
        for (tri, c) in st.iter().zip(&out[1..]) {
            for (k, n) in c.iter().enumerate() {
                let radial = sp[tri[k] as usize];
                assert!(
                    dot(*n, radial) > 1f64.to_radians().cos(),
                    "{n:?} at {radial:?}"
                );
            }
        }
    }

    /// The per-vertex shortcut of `creased_normals` changes no bit: against the definition
    /// computed corner by corner (the faces around the corner's vertex, in face order, whose
    /// unit normals are within the crease angle of the corner's face), on a bumpy grid with
    /// a fold, a sliver and a degenerate face, at crease angles from 0 to 180 degrees.
    #[test]
    fn creased_normals_are_the_corner_by_corner_definition() {
        let n = 24u32;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                // Gentle bumps, and a sharp fold along x = 0.5.
                let z = 0.05 * (7.0 * x).sin() * (5.0 * y).cos() + 0.4 * (x - 0.5).abs();
                p.push([x, y, z]);
            }
        }
        let id = |i: u32, j: u32| j * (n + 1) + i;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        t.push([id(3, 3), id(3, 3), id(4, 3)]); // degenerate
        p.push([0.25, 0.25, 0.0100001]);
        t.push([id(10, 10), id(11, 10), p.len() as u32 - 1]); // sliver
        let area = |t: &[u32; 3]| {
            cross(
                sub(p[t[1] as usize], p[t[0] as usize]),
                sub(p[t[2] as usize], p[t[0] as usize]),
            )
        };
        let unit = |t: &[u32; 3]| normalize(area(t)).unwrap_or([0.0, 0.0, 1.0]);
        for crease in [0.0, 1.0, 15.0, 30.0, 60.0, 89.0, 120.0, 180.0] {
            let cos_c = f64::to_radians(crease).cos() - 1e-9;
            let got = creased_normals(&p, &t, crease);
            let mut shared = 0;
            for (tri, c) in t.iter().zip(&got) {
                for k in 0..3 {
                    let mut s = [0.0; 3];
                    let mut all = true;
                    for f in t.iter().filter(|f| f.contains(&tri[k])) {
                        if dot(unit(f), unit(tri)) >= cos_c {
                            let a = area(f);
                            (0..3).for_each(|c| s[c] += a[c]);
                        } else {
                            all = false;
                        }
                    }
                    let want = normalize(s).unwrap_or(unit(tri));
                    assert_eq!(c[k].map(f64::to_bits), want.map(f64::to_bits), "{crease}");
                    shared += all as usize;
                }
            }
            assert!(
                shared > 0,
                "some corner sums every face at {crease} degrees"
            );
        }
    }

    #[test]
    fn plane_tangents_follow_u_and_materials_resolve() {
        // The plane's u runs along +x and v along -z, normal +y: T = +x, B = -z, and
        // (N x T) = y x x = -z, so the handedness is +1.
        let m = crate::plane::plane_mesh(2.0, [0.0; 3], 2, 1.0);
        let red = Arc::new(Material {
            base_color: [1.0, 0.0, 0.0],
            ..Default::default()
        });
        let scene = Scene {
            objects: vec![
                SceneObject {
                    mesh: Arc::new(m.clone()),
                    material: None,
                },
                SceneObject {
                    mesh: Arc::new(m),
                    material: Some(red.clone()),
                },
            ],
            ..Default::default()
        };
        let g = scene_geometry(&scene).unwrap();
        assert_eq!(g.pos.len(), 16);
        assert_eq!(g.materials.len(), 2);
        assert_eq!(g.materials[1], red);
        for t in &g.tan {
            for c in t {
                assert!((c[0] - 1.0).abs() < 1e-12 && c[1].abs() < 1e-12 && c[3] == 1.0);
            }
        }
        assert_eq!(g.bounds, ([-1.0, 0.0, -1.0], [1.0, 0.0, 1.0]));
        // The shape alone: the same positions, normals, materials and UV flags, no UVs
        // or tangents; a mesh without UVs is flagged so.
        let (p, t) = cube();
        let mut cube = Mesh::from_triangles(p, &t).unwrap();
        cube.uvs = None;
        let mut scene = scene;
        scene.objects.push(SceneObject {
            mesh: Arc::new(cube),
            material: None,
        });
        let full = scene_geometry_creased(&scene, 60.0).unwrap();
        let shape = scene_shape_creased(&scene, 60.0).unwrap();
        assert_eq!(shape.pos, full.pos);
        assert_eq!(shape.nrm, full.nrm);
        assert_eq!(shape.mat, full.mat);
        assert_eq!(shape.materials, full.materials);
        assert_eq!(shape.bounds, full.bounds);
        assert_eq!(shape.has_uv, full.has_uv);
        assert_eq!(full.has_uv.iter().filter(|&&h| !h).count(), 12);
        assert!(shape.uv.is_empty() && shape.tan.is_empty());
        assert_eq!(full.uv.len(), full.pos.len());
        // The bare positions: the same triangles in the same order, past an empty mesh.
        scene.objects.insert(
            1,
            SceneObject {
                mesh: Arc::new(Mesh::default()),
                material: None,
            },
        );
        let shape = scene_shape_creased(&scene, 60.0).unwrap();
        let f32s: Vec<[[f32; 3]; 3]> = shape
            .pos
            .iter()
            .map(|t| t.map(|p| p.map(|x| x as f32)))
            .collect();
        assert_eq!(shape.pos.len(), 28);
        assert_eq!(scene_positions(&scene), f32s);
    }
}
