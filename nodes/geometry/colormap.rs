//! Colour maps of per-vertex values (jet), shared by the colouring nodes and the simulations.

use cgnodes_api::prelude::*;

/// The jet colour map at `t` in [0, 1] (clamped): matplotlib's `jet`, piecewise linear in
/// each channel, which is the 256-entry table `colormap_jet.h` of the course's SPH code
/// samples at `t = i / 255`.
pub fn jet(t: f64) -> [f64; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    // (x, value) breakpoints of each channel.
    const R: [(f64, f64); 5] = [
        (0.0, 0.0),
        (0.35, 0.0),
        (0.66, 1.0),
        (0.89, 1.0),
        (1.0, 0.5),
    ];
    const G: [(f64, f64); 6] = [
        (0.0, 0.0),
        (0.125, 0.0),
        (0.375, 1.0),
        (0.64, 1.0),
        (0.91, 0.0),
        (1.0, 0.0),
    ];
    const B: [(f64, f64); 5] = [
        (0.0, 0.5),
        (0.11, 1.0),
        (0.34, 1.0),
        (0.65, 0.0),
        (1.0, 0.0),
    ];
    fn lerp(pts: &[(f64, f64)], t: f64) -> f64 {
        for w in pts.windows(2) {
            let ((x0, y0), (x1, y1)) = (w[0], w[1]);
            if t <= x1 {
                return y0 + (y1 - y0) * (t - x0) / (x1 - x0);
            }
        }
        pts[pts.len() - 1].1
    }
    [lerp(&R, t), lerp(&G, t), lerp(&B, t)]
}

/// Colours of `values` through the jet map as the course's `get_vel_color_jet` does: entry
/// `floor((v - lo) / (hi - lo) * 255)` of the 256-entry table, where `lo`, `hi` is `range`
/// or else the values' own minimum and maximum (all entry 0 when they differ by 1e-6 or less).
pub fn jet_colors(values: &[f64], range: Option<(f64, f64)>) -> Vec<[f64; 3]> {
    let (lo, hi) = range.unwrap_or_else(|| {
        values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            })
    });
    values
        .iter()
        .map(|&v| {
            let idx = if (hi - lo).abs() > 1e-6 {
                ((v - lo) / (hi - lo) * 255.0).floor().clamp(0.0, 255.0)
            } else {
                0.0
            };
            jet(idx / 255.0)
        })
        .collect()
}

/// The per-vertex numbers of attribute `name`: a float or integer attribute as it is, a
/// vector attribute by its length (so `velocity` gives speed).
pub fn vertex_values(mesh: &Mesh, name: &str) -> Result<Vec<f64>, VertexValuesError> {
    let a = mesh
        .attributes
        .get(name)
        .ok_or_else(|| VertexValuesError::NoAttribute {
            name: name.to_string(),
            names: mesh
                .attributes
                .keys()
                .cloned()
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let (d, v): (Domain, Vec<f64>) = match a {
        AttributeData::Float(x) => (x.domain, x.values.clone()),
        AttributeData::Int(x) => (x.domain, x.values.iter().map(|&i| i as f64).collect()),
        AttributeData::Vec2(x) => (
            x.domain,
            x.values.iter().map(|p| p[0].hypot(p[1])).collect(),
        ),
        AttributeData::Vec3(x) => (
            x.domain,
            x.values
                .iter()
                .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
                .collect(),
        ),
    };
    if d != Domain::Vertex {
        return Err(VertexValuesError::NotPerVertex {
            name: name.to_string(),
            domain: d,
        });
    }
    Ok(v)
}

/// Why an attribute gives no per-vertex numbers.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VertexValuesError {
    /// No attribute of that name.
    #[error("the mesh has no attribute '{name}' (it has: {names})")]
    NoAttribute {
        /// The name asked for.
        name: String,
        /// The mesh's attribute names, comma-separated.
        names: String,
    },
    /// The attribute lives on corners or faces.
    #[error("attribute '{name}' is not per vertex ({domain:?})")]
    NotPerVertex {
        /// The attribute's name.
        name: String,
        /// Its domain.
        domain: Domain,
    },
}

/// The nodes report errors as text: the message unchanged.
impl From<VertexValuesError> for String {
    fn from(e: VertexValuesError) -> String {
        e.to_string()
    }
}
