//! The right-hand side of the discrete Poisson equation (Pérez et al. 2003, eq. 7):
//! `b_p = Σ_{q ∈ N_p ∩ ∂Ω} f*_q + Σ_{q ∈ N_p} v_pq`, with the target f* as Dirichlet values
//! on ∂Ω and the guidance `v_pq` per oriented edge:
//! - seamless cloning (eq. 11): `v_pq = g_p - g_q`, the source gradient;
//! - mixed gradients (eq. 13): `v_pq = f*_p - f*_q` where it is larger in magnitude than
//!   `g_p - g_q`, the source's otherwise (per colour channel).
//!
//! A neighbour q of an inside pixel may lie outside the source image (Ω touching the
//! source's edge); the source is then extended by its nearest pixel, so `g_p - g_q = 0` there.

use super::mask::MaskShape;
use cgnodes_api::types::Image;
use faer::Mat;
use rayon::prelude::*;

/// Which guidance field to use (Pérez et al. 2003, §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Source gradients (seamless cloning, eq. 11).
    Seamless,
    /// Per edge and channel the stronger of the source and target gradients (eq. 13).
    Mixed,
}

impl cgnodes_api::node::Choice for Mode {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("seamless", Mode::Seamless), ("mixed", Mode::Mixed)];
}

/// The `n x 3` right-hand side (RGB) for Ω = `shape` with the source's top-left corner at
/// target pixel `offset`. The caller checked that Ω and ∂Ω lie inside the target
/// (`MaskShape::offset_range`) and that the source has the mask's size.
pub fn right_hand_side(
    shape: &MaskShape,
    target: &Image,
    source: &Image,
    offset: [i64; 2],
    mode: Mode,
) -> Mat<f64> {
    let mut b = Mat::<f64>::zeros(shape.len(), 3);
    right_hand_side_into(shape, target, source, offset, mode, &mut b);
    b
}

/// `right_hand_side` written over `b` (resized to `n x 3` when its size differs), so that a
/// caller can keep the buffer between pastes: memory written before does not fault again.
pub fn right_hand_side_into(
    shape: &MaskShape,
    target: &Image,
    source: &Image,
    offset: [i64; 2],
    mode: Mode,
    b: &mut Mat<f64>,
) {
    let (sw, sh) = (source.width as i64, source.height as i64);
    let tw = target.width as i64;
    let n = shape.len();
    let mixed = mode == Mode::Mixed;
    let row_of = |k: usize| {
        let [px, py] = shape.inside[k];
        let (px, py) = (px as i64, py as i64);
        let s0 = (py * sw + px) as usize;
        let t0 = ((py + offset[1]) * tw + px + offset[0]) as usize;
        let (gp, fp) = (source.pixels[s0], target.pixels[t0]);
        // neighbours right, left, below, above; the source clamped to its edge (a zero
        // source gradient there)
        let s_of = |q: usize| match q {
            0 if px + 1 < sw => s0 + 1,
            1 if px > 0 => s0 - 1,
            2 if py + 1 < sh => s0 + sw as usize,
            3 if py > 0 => s0 - sw as usize,
            _ => s0,
        };
        let t_of = [t0 + 1, t0 - 1, t0 + tw as usize, t0 - tw as usize];
        let nb = shape.neighbours(k);
        let mut row = [0.0f64; 4];
        for q in 0..4 {
            let gq = source.pixels[s_of(q)];
            let fq = target.pixels[t_of[q]];
            let boundary = if nb[q] == u32::MAX { 1.0 } else { 0.0 };
            // all four lanes, then selects: LLVM makes vector blends of these, where a
            // branch per channel would mispredict on mixed gradients
            let mut v = [0.0f64; 4];
            for c in 0..4 {
                let vs = f64::from(gp[c]) - f64::from(gq[c]);
                let vt = f64::from(fp[c]) - f64::from(fq[c]);
                let take_t = mixed && vt.abs() > vs.abs();
                v[c] = if take_t { vt } else { vs };
            }
            for c in 0..4 {
                row[c] += v[c] + boundary * f64::from(fq[c]);
            }
        }
        [row[0], row[1], row[2]]
    };
    // the three channel columns filled in parallel chunks of unknowns (every entry written)
    super::shape_mat(b, n, 3);
    {
        let (r, rest) = b.as_mut().split_at_col_mut(1);
        let (g, bl) = rest.split_at_col_mut(1);
        fn slice(m: faer::MatMut<'_, f64>) -> &mut [f64] {
            m.col_mut(0)
                .try_as_col_major_mut()
                .expect("a Mat's column is contiguous")
                .as_slice_mut()
        }
        let (r, g, bl) = (slice(r), slice(g), slice(bl));
        r.par_chunks_mut(CHUNK)
            .zip(g.par_chunks_mut(CHUNK))
            .zip(bl.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(i, ((r, g), b))| {
                for j in 0..r.len() {
                    let v = row_of(i * CHUNK + j);
                    (r[j], g[j], b[j]) = (v[0], v[1], v[2]);
                }
            });
    }
}

/// Unknowns per parallel task.
const CHUNK: usize = 1 << 12;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_pixel_region() {
        // Ω = {(1,1)} of a 3x3 source at offset (1,1) in a 5x5 target: 4 f_p = Σ f*_q + Σ v_pq
        let mut target = Image::new(5, 5, [0.0; 4]);
        for (x, y, v) in [
            (3, 2, 1.0),
            (1, 2, 2.0),
            (2, 3, 3.0),
            (2, 1, 4.0),
            (2, 2, 9.0),
        ] {
            target.set(x, y, [v, 0.0, 0.0, 1.0]);
        }
        let mut source = Image::new(3, 3, [0.0; 4]);
        source.set(1, 1, [0.5, 0.0, 0.0, 1.0]);
        source.set(2, 1, [0.25, 0.0, 0.0, 1.0]);
        let mut flags = vec![false; 9];
        flags[4] = true;
        let shape = MaskShape::from_flags(3, 3, &flags);
        let b = right_hand_side(&shape, &target, &source, [1, 1], Mode::Seamless);
        // boundary 1+2+3+4 = 10, source gradients 0.25 + 3 * 0.5 = 1.75
        assert!((b[(0, 0)] - 11.75).abs() < 1e-12);
        // mixed: target gradients 9-1, 9-2, 9-3, 9-4 all exceed the source's
        let b = right_hand_side(&shape, &target, &source, [1, 1], Mode::Mixed);
        assert!((b[(0, 0)] - (10.0 + 36.0 - 10.0)).abs() < 1e-12);
    }
}
