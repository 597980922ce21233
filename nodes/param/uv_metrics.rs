//! `uv_metrics`: distortion of a parameterization from each triangle's Jacobian.
//!
//! For every triangle the map from its 3D plane to UV is linear with Jacobian `J`; its singular
//! values `s1 >= s2` measure the stretch (Sander et al. 2001; Hormann et al. 2007, "Mesh
//! Parameterization: Theory and Practice", sec. 2). The UVs are first scaled so the total UV
//! area equals the total 3D area, which makes the measures independent of the layout's size.
//! Per triangle: angle distortion `s1 / s2` (1 for conformal), area distortion
//! `max(s1 s2, 1 / (s1 s2))` (1 for equiareal), ARAP energy `(s1 - 1)^2 + (s2 - 1)^2` (Liu et
//! al. 2008, eq. 3, with `s2` negative on a flipped triangle), symmetric Dirichlet
//! `s1^2 + s2^2 + s1^-2 + s2^-2` (Smith and Schaefer 2015; 4 for an isometry). Means are
//! area-weighted over the 3D triangles. A triangle is flipped when its UV orientation disagrees
//! with the majority's.

use super::triangles::fan_triangles;
use cgnodes_api::prelude::*;
use cgnodes_api::types::vec3::{cross, norm, sub};

/// Distortion measures of a triangle mesh's UVs.
#[derive(Clone, Debug, Default)]
pub struct UvMetrics {
    /// Triangles whose UV orientation is opposite to the majority's.
    pub flipped: usize,
    /// Triangles of (numerically) zero UV area.
    pub collapsed: usize,
    /// Triangles of zero 3D area, left out of the means.
    pub degenerate: usize,
    /// Area-weighted mean of `s1 / s2`.
    pub angle_distortion_mean: f64,
    /// Largest `s1 / s2`.
    pub angle_distortion_max: f64,
    /// Area-weighted mean of `max(s1 s2, 1 / (s1 s2))`.
    pub area_distortion_mean: f64,
    /// Largest `max(s1 s2, 1 / (s1 s2))`.
    pub area_distortion_max: f64,
    /// `sum A ((s1 - 1)^2 + (s2 - 1)^2) / sum A`.
    pub arap_energy: f64,
    /// `sum A (s1^2 + s2^2 + s1^-2 + s2^-2) / sum A` (4 for an isometry; infinite with collapsed triangles).
    pub symmetric_dirichlet: f64,
    /// The factor the UVs were scaled by to match the 3D area.
    pub uv_scale: f64,
    /// Per triangle: `s1 / s2` (infinite when collapsed, 0 for degenerate 3D triangles).
    pub face_angle_distortion: Vec<f64>,
    /// Per triangle: whether it is flipped.
    pub face_flipped: Vec<bool>,
}

/// Singular values of a 2x2 matrix `[[a, b], [c, d]]`, the second signed like the determinant
/// (closed form via the conformal / anti-conformal split).
pub fn signed_singular_values_2x2(a: f64, b: f64, c: f64, d: f64) -> (f64, f64) {
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = e.hypot(h);
    let r = f.hypot(g);
    (q + r, q - r)
}

/// The Jacobian `[[a, b], [c, d]]` of the linear map from triangle `p` (in its own plane, first
/// edge along x) to UV triangle `t`, or `None` for a zero-area 3D triangle. Also returns the
/// triangle's 3D area.
pub fn triangle_jacobian(p: [[f64; 3]; 3], t: [[f64; 2]; 3]) -> Option<([f64; 4], f64)> {
    let e1 = sub(p[1], p[0]);
    let e2 = sub(p[2], p[0]);
    let l1 = norm(e1);
    let cr = norm(cross(e1, e2));
    if l1 <= 0.0 || cr <= 1e-300 {
        return None;
    }
    // local coordinates: x1 = (l1, 0), x2 = (e2 . e1 / l1, |e1 x e2| / l1)
    let x2 = (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / l1;
    let y2 = cr / l1;
    let u1 = [t[1][0] - t[0][0], t[1][1] - t[0][1]];
    let u2 = [t[2][0] - t[0][0], t[2][1] - t[0][1]];
    // J [l1 x2; 0 y2] = [u1 u2]  =>  J = [u1 u2] [1/l1, -x2/(l1 y2); 0, 1/y2]
    let inv = [1.0 / l1, -x2 / (l1 * y2), 1.0 / y2];
    let j = [
        u1[0] * inv[0],
        u1[0] * inv[1] + u2[0] * inv[2],
        u1[1] * inv[0],
        u1[1] * inv[1] + u2[1] * inv[2],
    ];
    Some((j, 0.5 * cr))
}

/// Metrics of a triangle mesh's UVs after scaling total UV area to total 3D area; flips counted
/// against the majority orientation.
pub fn uv_metrics(positions: &[[f64; 3]], triangles: &[[u32; 3]], uvs: &[[f64; 2]]) -> UvMetrics {
    let nt = triangles.len();
    let mut jac = Vec::with_capacity(nt);
    let (mut area3, mut area_uv) = (0.0, 0.0);
    let (mut pos, mut neg) = (0usize, 0usize);
    for tri in triangles {
        let p = tri.map(|v| positions[v as usize]);
        let t = tri.map(|v| uvs[v as usize]);
        let j = triangle_jacobian(p, t);
        let uv_area2 =
            (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
        area_uv += 0.5 * uv_area2.abs();
        if let Some((_, a)) = j {
            area3 += a;
        }
        if uv_area2 > 0.0 {
            pos += 1;
        } else if uv_area2 < 0.0 {
            neg += 1;
        }
        jac.push(j);
    }
    let majority = if neg > pos { -1.0 } else { 1.0 };
    let scale = if area_uv > 0.0 && area_uv.is_finite() {
        (area3 / area_uv).sqrt()
    } else {
        f64::INFINITY
    };
    let mut m = UvMetrics {
        uv_scale: scale,
        face_angle_distortion: vec![0.0; nt],
        face_flipped: vec![false; nt],
        ..Default::default()
    };
    let (mut sa, mut sarea, mut sarap, mut ssd, mut wsum) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (f, j) in jac.iter().enumerate() {
        let Some((j, a)) = j else {
            m.degenerate += 1;
            continue;
        };
        let (s1, s2) =
            signed_singular_values_2x2(j[0] * scale, j[1] * scale, j[2] * scale, j[3] * scale);
        let s2 = s2 * majority;
        let s2abs = s2.abs();
        let tiny = 1e-12 * s1.max(1e-300);
        let collapsed = s2abs <= tiny || !s1.is_finite();
        if collapsed {
            m.collapsed += 1;
        } else if s2 < 0.0 {
            m.flipped += 1;
            m.face_flipped[f] = true;
        }
        let angle = if collapsed { f64::INFINITY } else { s1 / s2abs };
        let det = s1 * s2abs;
        let area = if collapsed {
            f64::INFINITY
        } else {
            det.max(1.0 / det)
        };
        let sd = if collapsed {
            f64::INFINITY
        } else {
            s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2)
        };
        m.face_angle_distortion[f] = angle;
        m.angle_distortion_max = m.angle_distortion_max.max(angle);
        m.area_distortion_max = m.area_distortion_max.max(area);
        sa += a * angle;
        sarea += a * area;
        sarap += a * ((s1 - 1.0).powi(2) + (s2 - 1.0).powi(2));
        ssd += a * sd;
        wsum += a;
    }
    if wsum > 0.0 {
        m.angle_distortion_mean = sa / wsum;
        m.area_distortion_mean = sarea / wsum;
        m.arap_energy = sarap / wsum;
        m.symmetric_dirichlet = ssd / wsum;
    }
    m
}

impl UvMetrics {
    /// The scalar measures as a one-row table.
    pub fn to_table(&self) -> Table {
        Table::from_row(&[
            ("flipped", self.flipped as f64),
            ("collapsed", self.collapsed as f64),
            ("degenerate", self.degenerate as f64),
            ("angle_distortion_mean", self.angle_distortion_mean),
            ("angle_distortion_max", self.angle_distortion_max),
            ("area_distortion_mean", self.area_distortion_mean),
            ("area_distortion_max", self.area_distortion_max),
            ("arap_energy", self.arap_energy),
            ("symmetric_dirichlet", self.symmetric_dirichlet),
            ("uv_scale", self.uv_scale),
        ])
    }
}

/// A blue (1) to red (`hi` and beyond) colour ramp for per-face distortion.
pub fn distortion_color(x: f64, hi: f64) -> [f64; 3] {
    let s = if x.is_finite() {
        ((x - 1.0) / (hi - 1.0).max(1e-12)).clamp(0.0, 1.0)
    } else {
        1.0
    };
    [s, 0.2 * (1.0 - s), 1.0 - s]
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Distortion of a mesh's UVs: flipped triangles, angle and area distortion, ARAP and symmetric Dirichlet energies.");
    b.add_input::<Mesh>("mesh")
        .doc("A mesh with per-vertex UVs (polygons are fan-triangulated).");
    b.add_output::<Table>("table").doc("One row of metrics.");
    b.add_output::<Mesh>("mesh").doc(
        "The (triangulated) mesh with per-face `angle_distortion`, `flipped` and face colours.",
    );
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let uvs = mesh.vertex_uvs().ok_or_else(|| {
        NodeError::invalid(
            "mesh",
            "mesh has no per-vertex UVs (run tutte or arap first, or the UVs have seams)",
        )
    })?;
    let tris = fan_triangles(&mesh);
    let m = uv_metrics(&mesh.positions, &tris, &uvs);
    ctx.log(format!(
        "{} flipped, angle distortion mean {:.4}, ARAP energy {:.4}",
        m.flipped, m.angle_distortion_mean, m.arap_energy
    ));
    let mut out = (*mesh.triangulated()).clone();
    out.attributes.insert(
        "angle_distortion".into(),
        AttributeData::Float(Attribute {
            domain: Domain::Face,
            values: m.face_angle_distortion.clone(),
        }),
    );
    out.attributes.insert(
        "flipped".into(),
        AttributeData::Int(Attribute {
            domain: Domain::Face,
            values: m.face_flipped.iter().map(|&f| f as i64).collect(),
        }),
    );
    out.colors = Some(Attribute {
        domain: Domain::Face,
        values: m
            .face_angle_distortion
            .iter()
            .zip(&m.face_flipped)
            .map(|(&a, &f)| {
                if f {
                    [1.0, 1.0, 0.0]
                } else {
                    distortion_color(a, 3.0)
                }
            })
            .collect(),
    });
    ctx.set_output("table", m.to_table());
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `uv_metrics`.
pub fn register(r: &mut Registry) {
    r.add("uv_metrics", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn singular_values_of_known_matrices() {
        // diag(3, 2) rotated by 30 degrees: singular values 3 and 2
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (s1, s2) = signed_singular_values_2x2(3.0 * c, -2.0 * s, 3.0 * s, 2.0 * c);
        assert!((s1 - 3.0).abs() < 1e-12 && (s2 - 2.0).abs() < 1e-12);
        // a reflection gives a negative second value
        let (s1, s2) = signed_singular_values_2x2(1.0, 0.0, 0.0, -0.5);
        assert!((s1 - 1.0).abs() < 1e-12 && (s2 + 0.5).abs() < 1e-12);
    }

    #[test]
    fn isometry_scores_perfect_and_stretch_and_flip_are_seen() {
        // a tilted 3D square split in two, UVs an isometric copy scaled by 10 (scale is removed)
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 0.0],
        ];
        let r2 = 2f64.sqrt();
        let uv: Vec<[f64; 2]> = vec![[0.0, 0.0], [10.0 * r2, 0.0], [10.0 * r2, 10.0], [0.0, 10.0]];
        let t = [[0, 1, 2], [0, 2, 3]];
        let m = uv_metrics(&p, &t, &uv);
        assert_eq!(m.flipped, 0);
        assert!((m.angle_distortion_mean - 1.0).abs() < 1e-12);
        assert!((m.area_distortion_mean - 1.0).abs() < 1e-12);
        assert!(m.arap_energy.abs() < 1e-20);
        assert!((m.symmetric_dirichlet - 4.0).abs() < 1e-12);
        // stretch u by 2 on a flat square: s = (sqrt 2, 1/sqrt 2) after area normalisation
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let uv = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
        let m = uv_metrics(&p, &t, &uv);
        assert!((m.angle_distortion_mean - 2.0).abs() < 1e-12);
        let want = (r2 - 1.0).powi(2) + (1.0 / r2 - 1.0).powi(2);
        assert!((m.arap_energy - want).abs() < 1e-12);
        // flip one triangle of three: mirror vertex 4 across the shared edge
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.5, 0.0],
        ];
        let t = [[0, 1, 2], [0, 2, 3], [1, 4, 2]];
        let mut uv: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        assert_eq!(uv_metrics(&p, &t, &uv).flipped, 0);
        uv[4] = [0.5, 0.5];
        let m = uv_metrics(&p, &t, &uv);
        assert_eq!(m.flipped, 1);
        assert!(m.face_flipped[2]);
    }
}
