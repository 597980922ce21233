//! The region Ω of a Poisson paste (Pérez et al. 2003, §2): which source pixels are inside,
//! how the unknowns are numbered, where the source may land, and the shape key under which
//! the factorization is cached.

use cgnodes_api::types::Image;
use rayon::prelude::*;

/// The inside pixels of a mask (the unknowns of the Poisson system), numbered row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct MaskShape {
    /// Mask (= source) width in pixels.
    pub width: u32,
    /// Mask (= source) height in pixels.
    pub height: u32,
    /// The inside pixels `[x, y]` in row-major order: unknown `k` is pixel `inside[k]`.
    pub inside: Vec<[u32; 2]>,
    /// For each mask pixel (row-major), its unknown's number, or `u32::MAX` outside.
    pub index: Vec<u32>,
    /// `bbox()`, found once: several checks of every paste ask for it.
    bbox: Option<[u32; 4]>,
}

/// The shape of Ω up to translation. Two masks with equal keys give the same matrix.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ShapeKey {
    /// Ω is a whole `w x h` rectangle (solved by the fast sine-transform solver).
    Rect {
        /// Width in pixels.
        w: u32,
        /// Height in pixels.
        h: u32,
    },
    /// Any other Ω: its inside pixels relative to the bounding box's top-left corner.
    Cells {
        /// Hash of `cells` (compared first).
        hash: u64,
        /// Inside pixels relative to the bounding box, row-major.
        cells: Vec<[u32; 2]>,
    },
}

impl MaskShape {
    /// The shape with `inside[y * width + x]` marking the inside pixels.
    pub fn from_flags(width: u32, height: u32, inside: &[bool]) -> MaskShape {
        let mut index = vec![u32::MAX; inside.len()];
        let mut cells = Vec::new();
        let mut bbox: Option<[u32; 4]> = None;
        for (i, _) in inside.iter().enumerate().filter(|(_, &b)| b) {
            index[i] = cells.len() as u32;
            let (x, y) = ((i % width as usize) as u32, (i / width as usize) as u32);
            cells.push([x, y]);
            let b = bbox.get_or_insert([x, y, x, y]);
            (b[0], b[2], b[3]) = (b[0].min(x), b[2].max(x), y);
        }
        MaskShape {
            width,
            height,
            inside: cells,
            index,
            bbox,
        }
    }

    /// The inside pixels of a mask image: alpha above one half, or, when every pixel is
    /// opaque (a black-and-white mask), luminance (Rec. 709 weights) above one half.
    pub fn from_image(mask: &Image) -> MaskShape {
        let opaque = mask.pixels.par_iter().all(|p| p[3] >= 1.0);
        let flags: Vec<bool> = mask
            .pixels
            .par_iter()
            .map(|p| {
                if opaque {
                    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] > 0.5
                } else {
                    p[3] > 0.5
                }
            })
            .collect();
        MaskShape::from_flags(mask.width, mask.height, &flags)
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.inside.len()
    }

    /// Whether no pixel is inside.
    pub fn is_empty(&self) -> bool {
        self.inside.is_empty()
    }

    /// The unknown at mask pixel `(x, y)`, `None` outside Ω or outside the mask.
    pub fn unknown(&self, x: i64, y: i64) -> Option<usize> {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return None;
        }
        let k = self.index[y as usize * self.width as usize + x as usize];
        (k != u32::MAX).then_some(k as usize)
    }

    /// The unknowns right, left, below and above unknown `k` (`u32::MAX` where that
    /// neighbour is outside Ω or outside the mask): the matrix's off-diagonal entries of row
    /// `k`, found without the bounds arithmetic of four `unknown` calls.
    #[inline]
    pub fn neighbours(&self, k: usize) -> [u32; 4] {
        let [x, y] = self.inside[k];
        let w = self.width as usize;
        let i = y as usize * w + x as usize;
        let at = |ok: bool, j: usize| if ok { self.index[j] } else { u32::MAX };
        [
            at(x + 1 < self.width, i + 1),
            at(x > 0, i.wrapping_sub(1)),
            at(y + 1 < self.height, i + w),
            at(y > 0, i.wrapping_sub(w)),
        ]
    }

    /// The bounding box of the inside pixels, `[x0, y0, x1, y1]` inclusive; `None` if empty.
    pub fn bbox(&self) -> Option<[u32; 4]> {
        self.bbox
    }

    /// The offsets (where the mask's top-left corner lands in a `w x h` target) that keep
    /// Ω and its one-pixel boundary ∂Ω inside the target: `[[x_min, x_max], [y_min, y_max]]`,
    /// `None` when no offset does (or Ω is empty). Ω must not touch the target's border,
    /// because every inside pixel needs its four neighbours (Pérez eq. 7, |N_p| = 4).
    pub fn offset_range(&self, w: u32, h: u32) -> Option<[[i64; 2]; 2]> {
        let [x0, y0, x1, y1] = self.bbox()?.map(i64::from);
        let xr = [1 - x0, w as i64 - 2 - x1];
        let yr = [1 - y0, h as i64 - 2 - y1];
        (xr[0] <= xr[1] && yr[0] <= yr[1]).then_some([xr, yr])
    }

    /// The size `[w, h]` of Ω when it fills its bounding box, `None` otherwise.
    pub fn rectangle(&self) -> Option<[u32; 2]> {
        let [x0, y0, x1, y1] = self.bbox()?;
        let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
        (w as usize * h as usize == self.len()).then_some([w, h])
    }

    /// The cache key of this shape (translation-invariant).
    pub fn key(&self) -> ShapeKey {
        if let Some([w, h]) = self.rectangle() {
            return ShapeKey::Rect { w, h };
        }
        let [x0, y0, ..] = self.bbox().unwrap_or([0; 4]);
        let cells: Vec<[u32; 2]> = self.inside.iter().map(|&[x, y]| [x - x0, y - y0]).collect();
        ShapeKey::Cells {
            hash: hash_cells(&cells),
            cells,
        }
    }
}

/// A 64-bit hash of the cells, one multiply-rotate step per cell (the hash only sorts out
/// most unequal keys before their cells are compared, so it need not resist collisions;
/// SipHash of each coordinate took about 0.15 ms on the course's 14.9k-pixel mask).
fn hash_cells(cells: &[[u32; 2]]) -> u64 {
    // the odd constants of SplitMix64 (Steele, Lea and Flood 2014)
    const K: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut h = cells.len() as u64 ^ 0xbf58_476d_1ce4_e5b9;
    for &[x, y] in cells {
        h = (h ^ (u64::from(x) << 32 | u64::from(y)))
            .wrapping_mul(K)
            .rotate_left(29);
    }
    h ^ (h >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(w: u32, h: u32, x0: u32, y0: u32, s: u32) -> MaskShape {
        let flags: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                x >= x0 && x < x0 + s && y >= y0 && y < y0 + s
            })
            .collect();
        MaskShape::from_flags(w, h, &flags)
    }

    #[test]
    fn numbering_bbox_and_offset_range() {
        let m = square(6, 5, 2, 1, 2);
        assert_eq!(m.inside, vec![[2, 1], [3, 1], [2, 2], [3, 2]]);
        assert_eq!(m.unknown(3, 2), Some(3));
        assert_eq!(m.unknown(1, 1), None);
        assert_eq!(m.unknown(-1, 0), None);
        assert_eq!(m.bbox(), Some([2, 1, 3, 2]));
        // target 10 x 8: x + 2 >= 1 and x + 3 <= 8; y + 1 >= 1 and y + 2 <= 6
        assert_eq!(m.offset_range(10, 8), Some([[-1, 5], [0, 4]]));
        assert_eq!(m.offset_range(3, 8), None);
        assert!(square(4, 4, 0, 0, 0).offset_range(10, 10).is_none());
    }

    #[test]
    fn key_is_translation_invariant() {
        let a = square(8, 8, 1, 1, 3);
        let b = square(9, 7, 4, 2, 3);
        let c = square(8, 8, 1, 1, 4);
        assert_eq!(a.key(), b.key());
        assert_ne!(a.key(), c.key());
        assert_eq!(a.key(), ShapeKey::Rect { w: 3, h: 3 });
        // an L is not a rectangle
        let mut l = a.clone();
        l.inside.pop();
        assert_eq!(l.rectangle(), None);
        assert!(matches!(l.key(), ShapeKey::Cells { .. }));
    }

    #[test]
    fn alpha_rule_and_luminance_rule() {
        let mut m = Image::new(2, 1, [1.0, 1.0, 1.0, 0.2]);
        m.set(1, 0, [0.0, 0.0, 0.0, 0.9]);
        assert_eq!(MaskShape::from_image(&m).inside, vec![[1, 0]]);
        let mut m = Image::new(2, 1, [1.0, 1.0, 1.0, 1.0]);
        m.set(1, 0, [0.1, 0.1, 0.1, 1.0]);
        assert_eq!(MaskShape::from_image(&m).inside, vec![[0, 0]]);
    }
}
