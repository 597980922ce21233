//! `render_uv`: the UV layout drawn as a wireframe over the mesh's texture (or white), with
//! flipped triangles filled red, for a quick look at a parameterization.

use super::triangles::fan_triangles;
use super::uv_metrics::uv_metrics;
use cgnodes_api::prelude::*;

/// Draws the UV layout of `triangles` (UVs `uvs`) into a `size` x `size` image. When every UV
/// lies in [0,1]^2 the image shows that square, otherwise the bounding square of the UVs,
/// with a 2% margin. The background samples `texture` at each pixel's UV (repeating), or is
/// white; triangles in `flipped` are filled red; edges are dark lines.
pub fn render_uv_layout(
    triangles: &[[u32; 3]],
    uvs: &[[f64; 2]],
    texture: Option<&Image>,
    flipped: &[bool],
    size: u32,
) -> Image {
    let size = size.max(2);
    let view = UvView::fit(uvs, size);
    let mut img = Image::new(size, size, [1.0; 4]);
    if let Some(tex) = texture.filter(|t| t.width > 0 && t.height > 0) {
        draw_texture(&mut img, &view, tex);
    }
    for (t, _) in triangles.iter().zip(flipped).filter(|(_, &f)| f) {
        fill_triangle(&mut img, t.map(|v| view.to_px(uvs[v as usize])), FLIPPED);
    }
    draw_wireframe(&mut img, &view, triangles, uvs);
    img
}

/// Colour of a flipped triangle.
const FLIPPED: [f32; 4] = [0.9, 0.1, 0.1, 1.0];
/// Colour of the edges.
const LINE: [f32; 4] = [0.1, 0.1, 0.2, 1.0];

/// The square of UV space the image shows: `origin` at the bottom-left, `extent` on a side,
/// over `size` pixels.
struct UvView {
    origin: [f64; 2],
    extent: f64,
    size: f64,
}

impl UvView {
    /// [0,1]^2 when every UV is inside it, else the bounding square of the finite UVs; both
    /// with a 2% margin.
    fn fit(uvs: &[[f64; 2]], size: u32) -> UvView {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for t in uvs.iter().filter(|t| t[0].is_finite() && t[1].is_finite()) {
            for k in 0..2 {
                lo[k] = lo[k].min(t[k]);
                hi[k] = hi[k].max(t[k]);
            }
        }
        let eps = 1e-9;
        let (origin, extent) =
            if lo[0] >= -eps && lo[1] >= -eps && hi[0] <= 1.0 + eps && hi[1] <= 1.0 + eps {
                ([-0.02, -0.02], 1.04)
            } else if lo[0].is_finite() {
                let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12) * 1.04;
                let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
                ([c[0] - 0.5 * ext, c[1] - 0.5 * ext], ext)
            } else {
                ([0.0, 0.0], 1.0)
            };
        UvView {
            origin,
            extent,
            size: size as f64,
        }
    }

    /// Pixel coordinates (x right, y down) of a UV.
    fn to_px(&self, t: [f64; 2]) -> [f64; 2] {
        [
            (t[0] - self.origin[0]) / self.extent * self.size,
            (1.0 - (t[1] - self.origin[1]) / self.extent) * self.size,
        ]
    }

    /// The UV at the centre of pixel (x, y).
    fn to_uv(&self, x: u32, y: u32) -> [f64; 2] {
        [
            self.origin[0] + (x as f64 + 0.5) / self.size * self.extent,
            self.origin[1] + (1.0 - (y as f64 + 0.5) / self.size) * self.extent,
        ]
    }
}

/// Background: `tex` sampled at each pixel's UV (repeating), lightened so that the wireframe
/// stands out.
fn draw_texture(img: &mut Image, view: &UvView, tex: &Image) {
    for y in 0..img.height {
        for x in 0..img.width {
            let [u, v] = view.to_uv(x, y);
            let tx = ((u.rem_euclid(1.0)) * tex.width as f64) as u32;
            let ty = ((1.0 - v.rem_euclid(1.0)) * tex.height as f64) as u32;
            let c = tex.get(tx.min(tex.width - 1), ty.min(tex.height - 1));
            img.set(
                x,
                y,
                [0.5 + 0.5 * c[0], 0.5 + 0.5 * c[1], 0.5 + 0.5 * c[2], 1.0],
            );
        }
    }
}

/// Fills the triangle with corners `p` (pixel coordinates, either orientation) in `colour`:
/// a scan over its bounding box with edge functions.
fn fill_triangle(img: &mut Image, p: [[f64; 2]; 3], colour: [f32; 4]) {
    let (w, h) = (img.width as f64, img.height as f64);
    let bound = |k: usize, hi: f64| {
        let lo = p.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min);
        let up = p.iter().map(|q| q[k]).fold(f64::NEG_INFINITY, f64::max);
        (lo.max(0.0) as u32, up.min(hi - 1.0) as u32)
    };
    let ((xmin, xmax), (ymin, ymax)) = (bound(0, w), bound(1, h));
    let edge = |a: [f64; 2], b: [f64; 2], q: [f64; 2]| {
        (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
    };
    for y in ymin..=ymax {
        for x in xmin..=xmax {
            let q = [x as f64 + 0.5, y as f64 + 0.5];
            let e = [
                edge(p[0], p[1], q),
                edge(p[1], p[2], q),
                edge(p[2], p[0], q),
            ];
            if e.iter().all(|&v| v >= 0.0) || e.iter().all(|&v| v <= 0.0) {
                img.set(x, y, colour);
            }
        }
    }
}

/// Every triangle edge as a dark line, once per triangle (shared edges drawn twice,
/// harmless); edges with a non-finite end are skipped.
fn draw_wireframe(img: &mut Image, view: &UvView, triangles: &[[u32; 3]], uvs: &[[f64; 2]]) {
    let s = view.size;
    for t in triangles {
        for k in 0..3 {
            let a = view.to_px(uvs[t[k] as usize]);
            let b = view.to_px(uvs[t[(k + 1) % 3] as usize]);
            if !(a[0].is_finite() && a[1].is_finite() && b[0].is_finite() && b[1].is_finite()) {
                continue;
            }
            let steps = (b[0] - a[0])
                .abs()
                .max((b[1] - a[1]).abs())
                .ceil()
                .clamp(1.0, 4.0 * s);
            for i in 0..=steps as usize {
                let f = i as f64 / steps;
                let x = a[0] + f * (b[0] - a[0]);
                let y = a[1] + f * (b[1] - a[1]);
                if x >= 0.0 && y >= 0.0 && x < s && y < s {
                    img.set(x as u32, y as u32, LINE);
                }
            }
        }
    }
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Draws a mesh's UV layout as a wireframe over its texture, flipped triangles in red.");
    b.add_input::<Mesh>("mesh");
    b.add_input::<i64>("size")
        .default(512i64)
        .range(16.0, 8192.0)
        .doc("Image width and height in pixels.");
    b.add_output::<Image>("image");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let size: i64 = ctx.input("size")?;
    let uvs = mesh
        .vertex_uvs()
        .ok_or_else(|| NodeError::invalid("mesh", "mesh has no per-vertex UVs to draw"))?;
    let tris = fan_triangles(&mesh);
    let m = uv_metrics(&mesh.positions, &tris, &uvs);
    let tex = mesh
        .material
        .as_ref()
        .and_then(|m| m.base_color_texture.clone());
    let size = size.clamp(16, 8192) as u32;
    let what = format!("a {size}x{size} image");
    let bytes = cgnodes_api::node::bytes_of(&[size as u64, size as u64, 16]);
    ctx.reserve_bytes("size", &what, bytes)?;
    let img = render_uv_layout(&tris, &uvs, tex.as_deref(), &m.face_flipped, size);
    ctx.set_output("image", img);
    Ok(())
}

/// Registers `render_uv`.
pub fn register(r: &mut Registry) {
    r.add("render_uv", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_edges_and_fills_flipped_triangles() {
        // two triangles of the unit square; the second marked flipped
        let uvs = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let img = render_uv_layout(&tris, &uvs, None, &[false, true], 64);
        // the diagonal from (0,0) (bottom-left) to (1,1) (top-right) is drawn
        assert!((31..34).any(|x| (31..34).any(|y| img.get(x, y)[0] < 0.2)));
        // upper-left half (second triangle) is red, lower-right half white
        assert_eq!(img.get(10, 30), [0.9, 0.1, 0.1, 1.0]);
        assert_eq!(img.get(50, 40), [1.0; 4]);
    }
}
