//! Seam carving (Avidan & Shamir 2007, "Seam Carving for Content-Aware Image Resizing"):
//! removing or inserting 8-connected paths of low energy, one pixel per row (vertical seams)
//! or per column (horizontal seams, done as vertical seams of the transposed grid).
//!
//! `energy.rs` holds the gradient energy e1 and its local update, `dp.rs` the dynamic
//! programming for one seam (backward energy, or forward energy of Rubinstein, Shamir &
//! Avidan 2008), `insert.rs` enlarging (§3.4), `order.rs` the transport map (§3.3); this
//! file the pixel grid with everything carried through removals.

pub mod dp;
pub mod energy;
pub mod insert;
pub mod order;

use cgnodes_api::node::Choice;
use cgnodes_api::types::Image;

/// The energy a seam minimizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Energy {
    /// Avidan & Shamir's e1 = |∂I/∂x| + |∂I/∂y| (Sobel derivatives), summed along the seam.
    Backward,
    /// Rubinstein et al. 2008: the gradient energy the removal inserts (eq. 4).
    Forward,
}

impl Choice for Energy {
    const CHOICES: &'static [(&'static str, Self)] =
        &[("backward", Energy::Backward), ("forward", Energy::Forward)];
}

/// In which order the two dimensions change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// All vertical seams, then all horizontal ones.
    WidthFirst,
    /// All horizontal seams, then all vertical ones.
    HeightFirst,
    /// The transport map of §3.3 (when both dimensions shrink; otherwise width first).
    Optimal,
}

impl Choice for Order {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("width_first", Order::WidthFirst),
        ("height_first", Order::HeightFirst),
        ("optimal", Order::Optimal),
    ];
}

/// The extra energy of protected pixels, and minus that of pixels to remove: larger than any
/// seam of gradient energy can reach (gray values are in [0, 1] in practice, |e1| ≤ 8).
pub const MASK_ENERGY: f64 = 1e6;

/// A pixel grid being carved: row-major `w x h`, with each pixel's colour, gray value, index
/// in the input image (to draw seams on it), mask energy and (backward mode) energy.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Width.
    pub w: usize,
    /// Height.
    pub h: usize,
    /// Linear RGBA.
    pub color: Vec<[f32; 4]>,
    /// Luminance, the image the energy is taken of.
    pub gray: Vec<f64>,
    /// Index of the input pixel this one is (or, inserted, duplicates).
    pub origin: Vec<u32>,
    /// +MASK_ENERGY protected, -MASK_ENERGY to remove, 0 otherwise.
    pub mask: Vec<f64>,
    /// The backward energy e1 of every pixel, kept current through removals (empty in
    /// forward mode, which computes its costs from `gray` inside the DP).
    pub energy: Vec<f64>,
    /// Which energy the seams minimize.
    pub mode: Energy,
}

impl Grid {
    /// A grid of `img` with per-pixel mask energies `mask` (`img.pixels.len()` of them).
    pub fn new(img: &Image, mask: Vec<f64>, mode: Energy) -> Grid {
        let mut g = Grid {
            w: img.width as usize,
            h: img.height as usize,
            color: img.pixels.clone(),
            gray: img.pixels.iter().map(|p| energy::luminance(*p)).collect(),
            origin: (0..img.pixels.len() as u32).collect(),
            mask,
            energy: Vec::new(),
            mode,
        };
        g.recompute_energy();
        g
    }

    /// The colours as an image.
    pub fn to_image(&self) -> Image {
        Image {
            width: self.w as u32,
            height: self.h as u32,
            pixels: self.color.clone(),
        }
    }

    /// Recomputes the whole energy map (backward mode).
    pub fn recompute_energy(&mut self) {
        self.energy = match self.mode {
            Energy::Backward => energy::backward_map(&self.gray, self.w, self.h),
            Energy::Forward => Vec::new(),
        };
    }

    /// Swaps rows and columns, so horizontal seams become vertical ones.
    pub fn transpose(&mut self) {
        let (w, h) = (self.w, self.h);
        fn t<T: Copy>(v: &[T], w: usize, h: usize) -> Vec<T> {
            let mut out = Vec::with_capacity(v.len());
            for x in 0..w {
                for y in 0..h {
                    out.push(v[y * w + x]);
                }
            }
            out
        }
        self.color = t(&self.color, w, h);
        self.gray = t(&self.gray, w, h);
        self.origin = t(&self.origin, w, h);
        self.mask = t(&self.mask, w, h);
        // e1 = |Sobel x| + |Sobel y| with clamped borders is symmetric under transposition
        if !self.energy.is_empty() {
            self.energy = t(&self.energy, w, h);
        }
        (self.w, self.h) = (h, w);
    }

    /// Removes the vertical seam `seam` (one column per row) and updates the energy only
    /// where it changed: the Sobel stencil of a pixel reaches one pixel around it, and a
    /// seam moves at most one column per row, so in row y only columns seam[y] - 3 ..=
    /// seam[y] + 2 of the narrower grid see new neighbours.
    pub fn remove_seam(&mut self, seam: &[usize]) {
        let (w, h) = (self.w, self.h);
        // row y's pixels before the seam move left by y, those after it by y + 1
        fn compact<T: Copy>(v: &mut Vec<T>, w: usize, seam: &[usize]) {
            for (y, &s) in seam.iter().enumerate() {
                let (row, dst) = (y * w, y * (w - 1));
                v.copy_within(row..row + s, dst);
                v.copy_within(row + s + 1..row + w, dst + s);
            }
            v.truncate(seam.len() * (w - 1));
        }
        compact(&mut self.color, w, seam);
        compact(&mut self.gray, w, seam);
        compact(&mut self.origin, w, seam);
        compact(&mut self.mask, w, seam);
        self.w = w - 1;
        if self.mode == Energy::Backward && self.w > 0 {
            compact(&mut self.energy, w, seam);
            for (y, &s) in seam.iter().enumerate().take(h) {
                let x0 = s.saturating_sub(3);
                let x1 = (s + 2).min(self.w - 1);
                for x in x0..=x1 {
                    self.energy[y * self.w + x] = energy::backward_at(&self.gray, self.w, h, x, y);
                }
            }
        }
    }
}
