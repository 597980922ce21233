//! `seam_carve`: content-aware resizing by seam carving (Avidan & Shamir 2007; forward
//! energy of Rubinstein, Shamir & Avidan 2008), with protection and object-removal masks.
//! The algorithms are in `seam/`; this file drives the removals and insertions and keeps
//! the record of which input pixels they touched.

#[path = "seam/mod.rs"]
pub mod seam;

use cgnodes_api::prelude::*;
use seam::{dp::find_seam, insert::insert_seams, order, Energy, Grid, Order, MASK_ENERGY};

/// What to produce.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    /// Target width; 0 only with a remove mask (then: the input's width).
    pub width: usize,
    /// Target height; 0 only with a remove mask (then: the input's height).
    pub height: usize,
    /// Energy of the seams.
    pub energy: Energy,
    /// Order of the two dimensions.
    pub order: Order,
}

/// The result of `seam_carve`.
#[derive(Clone, Debug)]
pub struct Carved {
    /// The resized image.
    pub image: Image,
    /// Which input pixels a removed or inserted seam went through.
    pub marked: Vec<bool>,
    /// Seams removed.
    pub removed: usize,
    /// Seams inserted.
    pub inserted: usize,
    /// Energy of the removed seams (without the mask terms).
    pub energy_removed: f64,
    /// Protected pixels a seam had to take (all of a row or column protected).
    pub protected_removed: usize,
    /// Pixels of the remove mask still there (when a dimension reached one pixel).
    pub remove_left: usize,
    /// Notes for the log (fallbacks).
    pub notes: Vec<String>,
}

/// The carving state: the grid (transposed while horizontal seams are worked on) and the
/// record of what was done.
struct Carver {
    grid: Grid,
    transposed: bool,
    out: Carved,
}

impl Carver {
    fn orient(&mut self, horizontal: bool) {
        if self.transposed != horizontal {
            self.grid.transpose();
            self.transposed = horizontal;
        }
    }

    /// Current (width, height) of the image.
    fn size(&self) -> (usize, usize) {
        if self.transposed {
            (self.grid.h, self.grid.w)
        } else {
            (self.grid.w, self.grid.h)
        }
    }

    fn remove(&mut self, horizontal: bool) {
        self.orient(horizontal);
        let s = find_seam(&self.grid);
        for (y, &x) in s.columns.iter().enumerate() {
            let i = y * self.grid.w + x;
            self.out.marked[self.grid.origin[i] as usize] = true;
            self.out.protected_removed += usize::from(self.grid.mask[i] > 0.0);
        }
        self.grid.remove_seam(&s.columns);
        self.out.removed += 1;
        self.out.energy_removed += s.energy;
    }

    fn insert(&mut self, horizontal: bool, k: usize) {
        self.orient(horizontal);
        let (marks, _) = insert_seams(&mut self.grid, k);
        for o in marks {
            self.out.marked[o as usize] = true;
        }
        self.out.inserted += k;
    }

    /// Removes or inserts seams until the width (or, `horizontal`, the height) is `target`.
    fn resize(&mut self, horizontal: bool, target: usize) {
        let (w, h) = self.size();
        let cur = if horizontal { h } else { w };
        if target > cur {
            self.insert(horizontal, target - cur);
        }
        for _ in target..cur {
            self.remove(horizontal);
        }
    }

    fn remove_left(&self) -> usize {
        self.grid.mask.iter().filter(|&&m| m < 0.0).count()
    }
}

/// The mask energies of the input pixels: luminance (or, for a transparent mask, alpha)
/// above one half selects a pixel.
fn mask_energy(img: &Image, protect: Option<&Image>, remove: Option<&Image>) -> Vec<f64> {
    let n = img.pixels.len();
    let flags = |m: Option<&Image>| -> Vec<bool> {
        let Some(m) = m else {
            return vec![false; n];
        };
        if m.pixels.iter().any(|q| q[3] < 1.0) {
            m.pixels.iter().map(|p| p[3] > 0.5).collect()
        } else {
            m.pixels
                .iter()
                .map(|p| seam::energy::luminance(*p) > 0.5)
                .collect()
        }
    };
    let (prot, rem) = (flags(protect), flags(remove));
    // the removal wins where both are set
    (0..n)
        .map(|i| {
            if rem[i] {
                -MASK_ENERGY
            } else if prot[i] {
                MASK_ENERGY
            } else {
                0.0
            }
        })
        .collect()
}

fn check(img: &Image, socket: &str, size: Option<(u32, u32)>) -> Result<(), NodeError> {
    if img.width == 0 || img.height == 0 {
        return Err(NodeError::invalid(socket, "the image is empty"));
    }
    if let Some((w, h)) = size {
        if (img.width, img.height) != (w, h) {
            return Err(NodeError::invalid(
                socket,
                format!(
                    "the mask is {}x{} but the image is {w}x{h}",
                    img.width, img.height
                ),
            ));
        }
    }
    if let Some(i) = img
        .pixels
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        let w = img.width as usize;
        return Err(NodeError::invalid(
            socket,
            format!("pixel ({}, {}) is not finite", i % w, i / w),
        ));
    }
    Ok(())
}

/// Resizes `img` to `req`'s size by removing and inserting seams, after removing the
/// `remove` mask's object if given. Errors name the socket at fault.
pub fn seam_carve(
    img: &Image,
    protect: Option<&Image>,
    remove: Option<&Image>,
    req: Request,
) -> Result<Carved, NodeError> {
    check(img, "image", None)?;
    let size = Some((img.width, img.height));
    if let Some(m) = protect {
        check(m, "protect", size)?;
    }
    if let Some(m) = remove {
        check(m, "remove", size)?;
    }
    let (w0, h0) = (img.width as usize, img.height as usize);
    let mut target = [req.width, req.height];
    for (t, (name, orig)) in target.iter_mut().zip([("width", w0), ("height", h0)]) {
        if *t == 0 {
            if remove.is_none() {
                return Err(NodeError::invalid(
                    name,
                    format!("{name} 0: give the target {name} in pixels (0 means the input's {name} only with a remove mask)"),
                ));
            }
            *t = orig;
        }
        if *t > 16 * orig {
            return Err(NodeError::invalid(
                name,
                format!("{name} {t} is more than 16 times the input's {orig}"),
            ));
        }
    }
    let mut c = Carver {
        grid: Grid::new(img, mask_energy(img, protect, remove), req.energy),
        transposed: false,
        out: Carved {
            image: Image::new(0, 0, [0.0; 4]),
            marked: vec![false; img.pixels.len()],
            removed: 0,
            inserted: 0,
            energy_removed: 0.0,
            protected_removed: 0,
            remove_left: 0,
            notes: Vec::new(),
        },
    };
    if remove.is_some() {
        remove_object(&mut c);
    }
    let [tw, th] = target;
    let (w, h) = c.size();
    match req.order {
        Order::Optimal if tw < w && th < h => {
            let need = order::memory_needed(w, h, w - tw);
            if need > order::MEMORY_BUDGET {
                c.out.notes.push(format!(
                    "the transport map would hold about {} MB of images; removed width first",
                    need >> 20
                ));
                c.resize(false, tw);
                c.resize(true, th);
            } else {
                c.orient(false);
                let (seq, _) = order::optimal_order(&c.grid, h - th, w - tw);
                for hz in seq {
                    c.remove(hz);
                }
            }
        }
        Order::HeightFirst => {
            c.resize(true, th);
            c.resize(false, tw);
        }
        other => {
            if other == Order::Optimal && (tw, th) != (w, h) {
                c.out.notes.push(
                    "order optimal applies when both dimensions shrink; resized width first".into(),
                );
            }
            c.resize(false, tw);
            c.resize(true, th);
        }
    }
    c.orient(false);
    c.out.remove_left = c.remove_left();
    c.out.image = c.grid.to_image();
    Ok(c.out)
}

/// Object removal: seams through the remove mask (very negative energy) until none of it
/// is left, in the direction needing fewer seams (the most masked pixels in one row for
/// vertical seams, in one column for horizontal ones).
fn remove_object(c: &mut Carver) {
    let (w, h) = (c.grid.w, c.grid.h);
    let m = &c.grid.mask;
    let row_max = (0..h)
        .map(|y| (0..w).filter(|&x| m[y * w + x] < 0.0).count())
        .max()
        .unwrap_or(0);
    let col_max = (0..w)
        .map(|x| (0..h).filter(|&y| m[y * w + x] < 0.0).count())
        .max()
        .unwrap_or(0);
    let horizontal = col_max < row_max;
    while c.remove_left() > 0 {
        let (w, h) = c.size();
        if (if horizontal { h } else { w }) <= 1 {
            break;
        }
        c.remove(horizontal);
    }
}

/// The input with every marked pixel red.
pub fn draw_seams(img: &Image, marked: &[bool]) -> Image {
    let mut out = img.clone();
    for (p, &m) in out.pixels.iter_mut().zip(marked) {
        if m {
            *p = [1.0, 0.0, 0.0, 1.0];
        }
    }
    out
}

fn declare(b: &mut NodeBuilder) {
    b.doc(
        "Content-aware resizing by seam carving (Avidan & Shamir 2007): removes or inserts \
         seams of low energy; optional masks protect pixels or remove an object.",
    );
    b.add_input::<Image>("image");
    b.add_input::<i64>("width").default(0).range(0.0, 1e6).doc(
        "Target width in pixels (smaller removes seams, larger inserts them). 0 only with a \
         remove mask: back to the input's width after the object is gone.",
    );
    b.add_input::<i64>("height")
        .default(0)
        .range(0.0, 1e6)
        .doc("Target height in pixels; 0 as for width.");
    b.add_choice::<Energy>("energy").doc(
        "backward: gradient magnitude e1 (Sobel) summed along the seam; forward: the \
         energy the removal inserts (Rubinstein et al. 2008).",
    );
    b.add_input::<Image>("protect")
        .optional()
        .doc("Mask (white, or alpha > 0.5) of pixels seams must avoid.");
    b.add_input::<Image>("remove")
        .optional()
        .doc("Mask of an object to remove: seams go through it until none of it is left.");
    b.add_choice::<Order>("order").doc(
        "width_first, height_first, or optimal (the transport map of §3.3, when both \
         dimensions shrink).",
    );
    b.add_output::<Image>("image");
    b.add_output::<Image>("seams")
        .doc("The input with every removed or inserted seam in red.");
    b.add_output::<Table>("table").doc(
        "seams_removed, seams_inserted, energy_removed, protected_removed (pixels), \
         time_ms.",
    );
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let img: Arc<Image> = ctx.input("image")?;
    let protect: Option<Arc<Image>> = ctx.input_opt("protect")?;
    let remove: Option<Arc<Image>> = ctx.input_opt("remove")?;
    let dims = [ctx.input::<i64>("width")?, ctx.input::<i64>("height")?];
    for (d, name) in dims.iter().zip(["width", "height"]) {
        if *d < 0 {
            return Err(NodeError::invalid(
                name,
                format!("{name} must not be negative"),
            ));
        }
    }
    // the grid (44 bytes per pixel) and its copy while inserting, at the larger of the input
    // and the target size in each dimension
    let (w, h) = (
        dims[0].max(img.width as i64) as u64,
        dims[1].max(img.height as i64) as u64,
    );
    let what = format!("seam carving at {w}x{h} pixels");
    let socket = if dims[0] > img.width as i64 {
        "width"
    } else {
        "height"
    };
    ctx.reserve_bytes(socket, &what, cgnodes_api::node::bytes_of(&[w, h, 2 * 44]))?;
    let req = Request {
        width: dims[0] as usize,
        height: dims[1] as usize,
        energy: ctx.choice::<Energy>("energy")?,
        order: ctx.choice::<Order>("order")?,
    };
    let t0 = std::time::Instant::now();
    let r = seam_carve(&img, protect.as_deref(), remove.as_deref(), req)?;
    let millis = t0.elapsed().as_secs_f64() * 1e3;
    for n in &r.notes {
        ctx.log(format!("note: {n}"));
    }
    if r.protected_removed > 0 {
        ctx.log(format!(
            "warning: {} protected pixels were removed (a whole row or column was protected)",
            r.protected_removed
        ));
    }
    if r.remove_left > 0 {
        ctx.log(format!(
            "warning: {} pixels of the remove mask are left (the image became one pixel wide)",
            r.remove_left
        ));
    }
    ctx.set_output("seams", draw_seams(&img, &r.marked));
    ctx.set_output("image", r.image);
    ctx.set_output(
        "table",
        Table::from_row(&[
            ("seams_removed", r.removed as f64),
            ("seams_inserted", r.inserted as f64),
            ("energy_removed", r.energy_removed),
            ("protected_removed", r.protected_removed as f64),
            ("time_ms", millis),
        ]),
    );
    Ok(())
}

/// Registers `seam_carve`.
pub fn register(r: &mut Registry) {
    r.add("seam_carve", declare, execute);
}

#[cfg(test)]
#[path = "seam/tests.rs"]
mod tests;
