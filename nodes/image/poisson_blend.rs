//! `poisson_blend`: Poisson image editing (Pérez, Gangnet, Blake 2003), seamless cloning and
//! mixed gradients, with the mask's factorization (sine transforms for a rectangle, a
//! multigrid hierarchy or sparse Cholesky otherwise) reused across calls (see
//! `poisson/mod.rs`).

#[path = "poisson/mod.rs"]
pub mod poisson;

use cgnodes_api::prelude::*;
use poisson::{MaskShape, Mode, ShapeKey, Solver};
use rayon::prelude::*;
use std::borrow::Borrow;
use std::sync::{Mutex, Weak};

/// Whether any value of `pixels` is NaN or infinite: exactly when its exponent bits are all
/// ones (an OR over comparisons, which vectorizes).
fn any_non_finite(pixels: &[[f32; 4]]) -> bool {
    const EXP: u32 = 0x7f80_0000;
    pixels
        .iter()
        .flatten()
        .fold(false, |acc, v| acc | (v.to_bits() & EXP == EXP))
}

/// A NaN or infinite pixel in an image that must be finite (the first in row-major order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("pixel ({x}, {y}) is not finite")]
pub struct NonFinitePixel {
    /// Column.
    pub x: usize,
    /// Row.
    pub y: usize,
}

/// The first non-finite pixel of `img` in row-major order within `[x0, y0, x1, y1]`
/// (inclusive, clipped to the image).
fn check_finite_in(img: &Image, [x0, y0, x1, y1]: [i64; 4]) -> Result<(), NonFinitePixel> {
    let (w, h) = (i64::from(img.width), i64::from(img.height));
    let (x0, x1) = (x0.clamp(0, w) as usize, (x1 + 1).clamp(0, w) as usize);
    let (y0, y1) = (y0.clamp(0, h) as usize, (y1 + 1).clamp(0, h) as usize);
    if x0 >= x1 || y0 >= y1 {
        return Ok(());
    }
    let row = |y: usize| &img.pixels[y * w as usize + x0..y * w as usize + x1];
    // rows in parallel tasks of about 16k pixels
    let min_rows = (1 << 14) / (x1 - x0);
    let bad = (y0..y1)
        .into_par_iter()
        .with_min_len(min_rows.max(1))
        .any(|y| any_non_finite(row(y)));
    if !bad {
        return Ok(());
    }
    for y in y0..y1 {
        if let Some(i) = row(y).iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(NonFinitePixel { x: x0 + i, y });
        }
    }
    Ok(())
}

/// The first non-finite pixel of `img`.
fn check_finite(img: &Image) -> Result<(), NonFinitePixel> {
    check_finite_in(
        img,
        [0, 0, i64::from(img.width) - 1, i64::from(img.height) - 1],
    )
}

/// The result of `poisson_blend`: the image, and the table's facts.
#[derive(Clone, Debug)]
pub struct Blend {
    /// The target with Ω replaced (the target itself for an empty mask).
    pub image: Image,
    /// The solve, `None` for an empty mask.
    pub solution: Option<poisson::Solution>,
    /// Unknowns solved.
    pub pixels: usize,
}

/// Pastes `source` into `target` with its top-left corner at `offset` (rounded to whole
/// pixels) over the inside of `mask` (the source's alpha when `None`; see
/// `MaskShape::from_image`). Errors name the socket at fault.
pub fn poisson_blend(
    target: &Image,
    source: &Image,
    mask: Option<&Image>,
    offset: [f64; 2],
    mode: Mode,
) -> Result<Blend, NodeError> {
    poisson::with_companion(|| {
        blend_found(
            target,
            source,
            || Region::new(source, mask),
            offset,
            mode,
            Solver::Auto,
            poisson::DEFAULT_TOLERANCE,
        )
    })
}

/// Ω of a paste, from the mask or the source's alpha, with its cache key: found once per
/// mask image (the node keeps the last one, so that a frame sequence that only moves the
/// offset does not scan the mask again).
pub struct Region {
    shape: MaskShape,
    key: ShapeKey,
    /// The socket Ω came from (`mask`, or `source` for the default mask).
    socket: &'static str,
}

impl Region {
    /// Ω of `mask` (checked: finite, the source's size), or of the source's alpha.
    pub fn new(source: &Image, mask: Option<&Image>) -> Result<Region, NodeError> {
        let shape = match mask {
            Some(m) => {
                check_finite(m).map_err(|e| NodeError::invalid("mask", e.to_string()))?;
                MaskShape::from_image(m)
            }
            None => {
                // the source's alpha; an opaque source is inside everywhere
                let opaque = source.pixels.iter().all(|p| p[3] >= 1.0);
                let flags: Vec<bool> = source.pixels.iter().map(|p| opaque || p[3] > 0.5).collect();
                MaskShape::from_flags(source.width, source.height, &flags)
            }
        };
        Ok(Region {
            key: shape.key(),
            shape,
            socket: if mask.is_some() { "mask" } else { "source" },
        })
    }
}

/// `poisson_blend` with Ω given (`Region::new` of this source's mask or alpha), by `solver`,
/// multigrid stopping at a relative residual of `tolerance`.
pub fn blend_region(
    target: &Image,
    source: &Image,
    region: &Region,
    offset: [f64; 2],
    mode: Mode,
    solver: Solver,
    tolerance: f64,
) -> Result<Blend, NodeError> {
    blend_found(
        target,
        source,
        || Ok(region),
        offset,
        mode,
        solver,
        tolerance,
    )
}

/// `blend_region` with Ω found by `find_region` on this core while another copies the
/// target: the copy (fresh pages, about 1.2 ms on the course's target) overlaps the mask
/// scan, the right-hand side and the hierarchy, not only the solve.
fn blend_found<R: Borrow<Region> + Send>(
    target: &Image,
    source: &Image,
    find_region: impl FnOnce() -> Result<R, NodeError> + Send,
    offset: [f64; 2],
    mode: Mode,
    solver: Solver,
    tolerance: f64,
) -> Result<Blend, NodeError> {
    if offset.iter().any(|v| !v.is_finite()) {
        return Err(NodeError::invalid("offset", "the offset is not finite"));
    }
    let (solved, copy) = rayon::join(
        || -> Result<Option<(R, [i64; 2], poisson::Solution)>, NodeError> {
            let region = find_region()?;
            let r = region.borrow();
            let Some(off) = checked_offset(target, source, r, offset, solver)? else {
                return Ok(None);
            };
            let sol = poisson::solve_keyed(
                &r.shape, &r.key, target, source, off, mode, solver, tolerance,
            )
            .map_err(|e| NodeError::singular(format!("Poisson system: {e}")))?;
            Ok(Some((region, off, sol)))
        },
        || poisson::copy_target(target),
    );
    let solved = solved?;
    let mut image = copy.map_err(|e| NodeError::invalid("target", e.to_string()))?;
    let Some((region, off, sol)) = solved else {
        // an empty Ω: the target unchanged (checked finite by the copy)
        return Ok(Blend {
            image,
            solution: None,
            pixels: 0,
        });
    };
    let shape = &region.borrow().shape;
    poisson::write_solution(&mut image, shape, off, &sol.values);
    Ok(Blend {
        image,
        pixels: shape.len(),
        solution: Some(sol),
    })
}

/// The paste's whole-pixel offset after the checks of Ω against the images and `solver`
/// (`None` for an empty Ω, which has nothing to check).
fn checked_offset(
    target: &Image,
    source: &Image,
    region: &Region,
    offset: [f64; 2],
    solver: Solver,
) -> Result<Option<[i64; 2]>, NodeError> {
    let (shape, socket) = (&region.shape, region.socket);
    if (shape.width, shape.height) != (source.width, source.height) {
        return Err(NodeError::invalid(
            "mask",
            format!(
                "the mask is {}x{} but the source is {}x{}",
                shape.width, shape.height, source.width, source.height
            ),
        ));
    }
    if shape.is_empty() {
        return Ok(None);
    }
    let Some([xr, yr]) = shape.offset_range(target.width, target.height) else {
        let [x0, y0, x1, y1] = shape.bbox().unwrap_or([0; 4]);
        return Err(NodeError::invalid(
            socket,
            format!(
                "the masked region is {}x{} pixels but must fit inside the {}x{} target with a \
                 one-pixel margin (the target's border is the Dirichlet boundary)",
                x1 - x0 + 1,
                y1 - y0 + 1,
                target.width,
                target.height
            ),
        ));
    };
    // round half away from zero to whole pixels
    let off = [offset[0].round() as i64, offset[1].round() as i64];
    if !(xr[0]..=xr[1]).contains(&off[0]) || !(yr[0]..=yr[1]).contains(&off[1]) {
        return Err(NodeError::invalid(
            "offset",
            format!(
                "offset ({}, {}) puts the masked region on or past the target's border; \
                 allowed: x in [{}, {}], y in [{}, {}]",
                off[0], off[1], xr[0], xr[1], yr[0], yr[1]
            ),
        ));
    }
    // the pixels the right-hand side reads: Ω and its four neighbours in both images (the
    // rest of the target is checked as `copy_target` copies it)
    let [x0, y0, x1, y1] = shape.bbox().map_or([0; 4], |b| b.map(i64::from));
    let around = [x0 - 1, y0 - 1, x1 + 1, y1 + 1];
    check_finite_in(source, around).map_err(|e| NodeError::invalid("source", e.to_string()))?;
    let moved = [
        around[0] + off[0],
        around[1] + off[1],
        around[2] + off[0],
        around[3] + off[1],
    ];
    check_finite_in(target, moved).map_err(|e| NodeError::invalid("target", e.to_string()))?;
    if solver == Solver::SineTransform && shape.rectangle().is_none() {
        return Err(NodeError::invalid(
            "solver",
            poisson::PoissonError::NotARectangle.to_string(),
        ));
    }
    Ok(Some(off))
}

/// The last mask image the node found Ω of (held weakly: its allocation cannot be reused by
/// another image while this lives, and an image behind an `Arc` is not changed) and Ω.
type LastRegion = Option<(Weak<Image>, Arc<Region>)>;
static LAST_REGION: Mutex<LastRegion> = Mutex::new(None);

/// Ω of `mask` (or of the source's alpha), from `LAST_REGION` when it is the same image.
fn region_of(source: &Arc<Image>, mask: Option<&Arc<Image>>) -> Result<Arc<Region>, NodeError> {
    let image = mask.unwrap_or(source);
    {
        let last = LAST_REGION.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((w, r)) = last.as_ref() {
            if std::ptr::eq(w.as_ptr(), Arc::as_ptr(image))
                && (r.socket == "mask") == mask.is_some()
            {
                return Ok(r.clone());
            }
        }
    }
    let region = Arc::new(Region::new(source, mask.map(|m| &**m))?);
    *LAST_REGION.lock().unwrap_or_else(|e| e.into_inner()) =
        Some((Arc::downgrade(image), region.clone()));
    Ok(region)
}

fn declare(b: &mut NodeBuilder) {
    b.doc(
        "Poisson image editing (Pérez et al. 2003): pastes the source's gradients into the \
         target over a mask, seamlessly. A rectangular mask is solved by sine transforms \
         (O(n log n)), any other by multigrid-preconditioned conjugate gradients or sparse \
         Cholesky (`solver`); the factorization or multigrid hierarchy is reused by later \
         calls with the same mask shape (e.g. when only the offset moves).",
    );
    b.add_input::<Image>("target")
        .doc("The image pasted into; its pixels around the mask are the boundary values.");
    b.add_input::<Image>("source").doc(
        "The image whose gradients are pasted (same size as the mask); its pixels under \
             the mask and their neighbours must be finite.",
    );
    b.add_input::<Image>("mask").optional().doc(
        "Inside where alpha > 0.5, or, for an opaque mask, where luminance > 0.5. \
         Default: the source's alpha (the whole source when it is opaque).",
    );
    b.add_input::<[f64; 2]>("offset").default([0.0, 0.0]).doc(
        "Where the source's top-left corner lands in the target, in pixels (x right, y down); \
         rounded to whole pixels. The masked region must stay one pixel away from the \
         target's border.",
    );
    b.add_choice::<Mode>("mode").doc(
        "seamless: source gradients; mixed: per edge and channel the stronger of the source \
         and target gradients (transparent objects, holes).",
    );
    b.add_choice::<Solver>("solver").doc(
        "auto: sine transforms for a rectangular mask, multigrid for a mask of at least 4096 \
         pixels filling a quarter of its bounding box (switching to sparse Cholesky after 3 \
         pastes of one shape, 6 from 100k pixels), sparse Cholesky otherwise; cholesky: \
         sparse Cholesky (fastest when one large mask shape is pasted many times); multigrid: \
         geometric multigrid-preconditioned conjugate gradients (fastest first paste of a \
         large mask); sine_transform: rectangular masks only (an error otherwise).",
    );
    b.add_input::<f64>("tolerance")
        .default(poisson::DEFAULT_TOLERANCE)
        .range(1e-13, 1e-2)
        .doc(
            "Relative residual ‖b − A x‖ / ‖b‖ at which multigrid stops (the direct solvers \
             are exact up to rounding). The largest pixel error is about this value: the \
             default keeps the course paste within 1e-5 of the exact solution (a 400th of an \
             8-bit level); 8e-11 for a reference solve.",
        );
    b.add_output::<Image>("image");
    b.add_output::<Table>("table").doc(
        "pixels solved, relative residual of the Poisson system, reused (0/1: the \
             factorization or multigrid hierarchy came from the cache), sine_transform (1: \
             the rectangle's fast solver), multigrid (1: multigrid, 0 with sine_transform 0: \
             sparse Cholesky), iterations (multigrid CG iterations), time_ms.",
    );
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let target: Arc<Image> = ctx.input("target")?;
    let source: Arc<Image> = ctx.input("source")?;
    let mask: Option<Arc<Image>> = ctx.input_opt("mask")?;
    let offset: [f64; 2] = ctx.input("offset")?;
    let mode = ctx.choice::<Mode>("mode")?;
    let solver = ctx.choice::<Solver>("solver")?;
    let tolerance: f64 = ctx.input("tolerance")?;
    let t0 = std::time::Instant::now();
    let r = poisson::with_companion(|| {
        blend_found(
            &target,
            &source,
            || region_of(&source, mask.as_ref()),
            offset,
            mode,
            solver,
            tolerance,
        )
    })?;
    let millis = t0.elapsed().as_secs_f64() * 1e3;
    if r.solution.is_none() {
        ctx.log("warning: the mask is empty; the target is returned unchanged");
    }
    let (residual, reused, rect, mg, iterations) =
        r.solution.as_ref().map_or((0.0, 0.0, 0.0, 0.0, 0.0), |s| {
            let flag = |b: bool| f64::from(u8::from(b));
            (
                s.residual,
                flag(s.reused),
                flag(s.solver == "sine_transform"),
                flag(s.solver == "multigrid"),
                s.iterations as f64,
            )
        });
    ctx.set_output("image", r.image);
    if let Some(s) = r.solution {
        poisson::recycle(s.values);
    }
    ctx.set_output(
        "table",
        Table::from_row(&[
            ("pixels", r.pixels as f64),
            ("residual", residual),
            ("reused", reused),
            ("sine_transform", rect),
            ("multigrid", mg),
            ("iterations", iterations),
            ("time_ms", millis),
        ]),
    );
    Ok(())
}

/// Registers `poisson_blend`.
pub fn register(r: &mut Registry) {
    r.add("poisson_blend", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::poisson::system;
    use super::*;

    /// A deterministic image with smooth structure and noise (`crate::test_images::waves`).
    fn image(w: u32, h: u32, seed: u64) -> Image {
        crate::test_images::waves(w, h, seed, [0.3, 0.2], 0.1)
    }

    /// An opaque mask: a disc of radius `r` at the centre of a `w x h` image (white inside).
    fn disc(w: u32, h: u32, r: f32) -> Image {
        let mut m = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (
                    x as f32 + 0.5 - w as f32 / 2.0,
                    y as f32 + 0.5 - h as f32 / 2.0,
                );
                if dx * dx + dy * dy < r * r {
                    m.set(x, y, [1.0; 4]);
                }
            }
        }
        m
    }

    fn crop(img: &Image, x0: u32, y0: u32, w: u32, h: u32) -> Image {
        let mut out = Image::new(w, h, [0.0; 4]);
        for y in 0..h {
            for x in 0..w {
                out.set(x, y, img.get(x + x0, y + y0));
            }
        }
        out
    }

    fn solved(b: &Blend) -> &poisson::Solution {
        b.solution.as_ref().unwrap()
    }

    /// The solved values against the target's own values under Ω.
    fn max_diff_from_target(b: &Blend, target: &Image, mask: &Image, off: [i64; 2]) -> f64 {
        let shape = MaskShape::from_image(mask);
        let mut worst = 0.0f64;
        for (k, &[x, y]) in shape.inside.iter().enumerate() {
            let t = target.get((x as i64 + off[0]) as u32, (y as i64 + off[1]) as u32);
            for (c, &tc) in t.iter().take(3).enumerate() {
                worst = worst.max((solved(b).values[(k, c)] - tc as f64).abs());
            }
        }
        worst
    }

    #[test]
    fn source_equal_to_target_returns_the_target() {
        let target = image(40, 30, 1);
        let source = crop(&target, 10, 6, 20, 18);
        let mask = disc(20, 18, 8.5);
        for mode in [Mode::Seamless, Mode::Mixed] {
            let b = poisson_blend(&target, &source, Some(&mask), [10.0, 6.0], mode).unwrap();
            assert!(b.pixels > 200);
            assert!(max_diff_from_target(&b, &target, &mask, [10, 6]) < 1e-12);
            assert!(solved(&b).residual < 1e-10);
        }
    }

    #[test]
    fn solution_satisfies_the_discrete_equation() {
        let target = image(64, 48, 2);
        let source = image(30, 25, 3);
        let mut mask = disc(30, 25, 11.0);
        mask.set(0, 0, [1.0; 4]); // a second component on the source's corner
        for mode in [Mode::Seamless, Mode::Mixed] {
            let b = poisson_blend(&target, &source, Some(&mask), [20.4, 9.6], mode).unwrap();
            let s = solved(&b);
            assert!(s.residual < 1e-10, "{mode:?}: {}", s.residual);
            // and independently: A x = b recomputed here
            let shape = MaskShape::from_image(&mask);
            let rhs = poisson::guidance::right_hand_side(&shape, &target, &source, [20, 10], mode);
            let r = system::apply(&shape, s.values.as_ref()) - &rhs;
            assert!(r.norm_l2() < 1e-10 * rhs.norm_l2());
            // the pixels outside Ω are the target's
            assert_eq!(b.image.get(0, 0), target.get(0, 0));
            assert_eq!(b.image.get(20, 10)[3], target.get(20, 10)[3]);
        }
    }

    #[test]
    fn mixed_with_a_flat_source_returns_the_target() {
        let target = image(32, 32, 4);
        let source = Image::new(16, 12, [0.3, 0.6, 0.1, 1.0]);
        let mask = disc(16, 12, 5.0);
        let b = poisson_blend(&target, &source, Some(&mask), [7.0, 9.0], Mode::Mixed).unwrap();
        assert!(max_diff_from_target(&b, &target, &mask, [7, 9]) < 1e-12);
        // seamless with the flat source is the membrane interpolant instead: not the target
        let b = poisson_blend(&target, &source, Some(&mask), [7.0, 9.0], Mode::Seamless).unwrap();
        assert!(max_diff_from_target(&b, &target, &mask, [7, 9]) > 1e-3);
    }

    #[test]
    fn same_shape_reuses_the_factorization_and_matches_a_fresh_solve() {
        let target = image(50, 50, 5);
        let source = image(13, 11, 6);
        let mask = disc(13, 11, 4.7); // a shape no other unit test uses
        let first = poisson_blend(&target, &source, Some(&mask), [5.0, 5.0], Mode::Seamless);
        assert!(first.is_ok());
        let again = poisson_blend(&target, &source, Some(&mask), [30.0, 21.0], Mode::Seamless);
        let s = solved(again.as_ref().unwrap());
        assert!(s.reused);
        let shape = MaskShape::from_image(&mask);
        let f = system::factor(&shape).unwrap();
        let mut x =
            poisson::guidance::right_hand_side(&shape, &target, &source, [30, 21], Mode::Seamless);
        f.solve_in_place(x.as_mut());
        assert!((&x - &s.values).norm_max() < 1e-12);
    }

    #[test]
    fn rectangular_mask_uses_the_sine_transform_and_matches_cholesky() {
        let target = image(60, 40, 12);
        let source = image(23, 17, 13); // opaque: the whole rectangle is Ω
        let shape = MaskShape::from_flags(23, 17, &[true; 23 * 17]);
        let f = system::factor(&shape).unwrap();
        for mode in [Mode::Seamless, Mode::Mixed] {
            let b = poisson_blend(&target, &source, None, [20.0, 11.0], mode).unwrap();
            let s = solved(&b);
            assert_eq!(s.solver, "sine_transform");
            assert!(s.residual < 1e-10, "{mode:?}: {}", s.residual);
            // the same system by sparse Cholesky
            let mut x =
                poisson::guidance::right_hand_side(&shape, &target, &source, [20, 11], mode);
            f.solve_in_place(x.as_mut());
            assert!((&x - &s.values).norm_max() < 1e-12 * x.norm_max());
        }
        // a source equal to the target under a rectangle (inside the source) returns the target
        let source = crop(&target, 9, 5, 22, 20);
        let mut rect = Image::new(22, 20, [0.0, 0.0, 0.0, 1.0]);
        for y in 1..19 {
            for x in 1..21 {
                rect.set(x, y, [1.0; 4]);
            }
        }
        let b = poisson_blend(&target, &source, Some(&rect), [9.0, 5.0], Mode::Seamless).unwrap();
        assert_eq!(solved(&b).solver, "sine_transform");
        assert!(max_diff_from_target(&b, &target, &rect, [9, 5]) < 1e-12);
        // an irregular mask stays on Cholesky
        let b = poisson_blend(
            &target,
            &source,
            Some(&disc(22, 20, 7.0)),
            [9.0, 5.0],
            Mode::Seamless,
        );
        assert_eq!(solved(b.as_ref().unwrap()).solver, "cholesky");
    }

    #[test]
    fn default_mask_is_the_source_alpha() {
        let target = image(20, 20, 7);
        let mut source = image(6, 6, 8);
        for p in source.pixels.iter_mut() {
            p[3] = 0.0;
        }
        source.set(2, 3, [0.1, 0.2, 0.3, 1.0]);
        let b = poisson_blend(&target, &source, None, [4.0, 4.0], Mode::Seamless).unwrap();
        assert_eq!(b.pixels, 1);
        // opaque source: all 36 pixels
        let b = poisson_blend(&target, &image(6, 6, 9), None, [4.0, 4.0], Mode::Seamless);
        assert_eq!(b.unwrap().pixels, 36);
    }

    #[test]
    fn bad_inputs_name_their_socket() {
        let target = image(20, 20, 10);
        let source = image(8, 8, 11);
        let mask = disc(8, 8, 3.0); // inside x, y in 1..=6 of the mask
        let sock = |r: Result<Blend, NodeError>| r.unwrap_err().socket.unwrap();
        let run = |t: &Image, s: &Image, m: Option<&Image>, o: [f64; 2]| {
            poisson_blend(t, s, m, o, Mode::Seamless)
        };
        // touching the border (offset 0 puts mask pixel 1 at target column 1: fine; -1 not)
        assert!(run(&target, &source, Some(&mask), [0.0, 0.0]).is_ok());
        let e = run(&target, &source, Some(&mask), [-1.0, 0.0]).unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("offset"));
        assert!(
            e.message.contains("x in [0, 12], y in [0, 12]"),
            "{}",
            e.message
        );
        assert_eq!(
            sock(run(&target, &source, Some(&mask), [13.0, 3.0])),
            "offset"
        );
        assert_eq!(
            sock(run(&target, &source, Some(&mask), [3.0, 40.0])),
            "offset"
        );
        assert_eq!(
            sock(run(&target, &source, Some(&mask), [f64::NAN, 3.0])),
            "offset"
        );
        // a region larger than the target's interior
        let small = image(7, 7, 12);
        assert_eq!(sock(run(&small, &source, Some(&mask), [0.0, 0.0])), "mask");
        assert_eq!(sock(run(&small, &source, None, [0.0, 0.0])), "source");
        // sizes
        assert_eq!(
            sock(run(&target, &source, Some(&disc(9, 8, 3.0)), [4.0, 4.0])),
            "mask"
        );
        // NaN
        let mut bad = source.clone();
        bad.set(3, 3, [f32::NAN, 0.0, 0.0, 1.0]);
        assert_eq!(sock(run(&target, &bad, Some(&mask), [4.0, 4.0])), "source");
        let mut bad = target.clone();
        bad.set(0, 0, [0.0, f32::INFINITY, 0.0, 1.0]);
        assert_eq!(sock(run(&bad, &source, Some(&mask), [4.0, 4.0])), "target");
        let mut bad = mask.clone();
        bad.set(0, 0, [0.0, 0.0, f32::NAN, 1.0]);
        assert_eq!(sock(run(&target, &source, Some(&bad), [4.0, 4.0])), "mask");
    }

    #[test]
    fn the_node_finds_omega_again_for_another_mask_image() {
        let source = Arc::new(image(12, 12, 21));
        let a = Arc::new(disc(12, 12, 5.0));
        let ra = region_of(&source, Some(&a)).unwrap();
        // the same image: the same region, not scanned again
        assert!(Arc::ptr_eq(&ra, &region_of(&source, Some(&a)).unwrap()));
        let pixels = ra.shape.len();
        drop((ra, a));
        // a new image (perhaps where the old one was): its own region
        let b = Arc::new(disc(12, 12, 3.0));
        let rb = region_of(&source, Some(&b)).unwrap();
        assert_eq!(rb.shape, MaskShape::from_image(&b));
        assert!(rb.shape.len() < pixels);
        // the source as its own mask (luminance) is not the default mask (its alpha)
        assert_eq!(region_of(&source, Some(&source)).unwrap().socket, "mask");
        let alpha = region_of(&source, None).unwrap();
        assert_eq!((alpha.socket, alpha.shape.len()), ("source", 144));
        // a bad mask is an error every time
        let mut bad = disc(12, 12, 3.0);
        bad.set(0, 0, [f32::NAN; 4]);
        let bad = Arc::new(bad);
        for _ in 0..2 {
            let e = region_of(&source, Some(&bad)).err().unwrap();
            assert_eq!(e.socket.as_deref(), Some("mask"));
        }
    }

    #[test]
    fn empty_mask_returns_the_target() {
        let target = image(10, 10, 13);
        let source = image(4, 4, 14);
        let empty = Image::new(4, 4, [0.0, 0.0, 0.0, 1.0]);
        // even an offset off the target is fine: nothing is pasted
        let b = poisson_blend(&target, &source, Some(&empty), [50.0, 0.0], Mode::Mixed).unwrap();
        assert_eq!(b.image, target);
        assert!(b.solution.is_none());
    }

    /// A course image, linear (the `image_load` node's default sRGB decoding, as `raw`
    /// false) or raw (a mask).
    fn course_image(name: &str, raw: bool) -> Image {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/images")
            .join(name);
        let img = image::open(&path).expect("course image").to_rgba32f();
        let mut out = Image::new(img.width(), img.height(), [0.0; 4]);
        for (d, s) in out.pixels.iter_mut().zip(img.pixels()) {
            let lin = |c: f32| if raw { c } else { c.powf(2.2) };
            *d = [lin(s.0[0]), lin(s.0[1]), lin(s.0[2]), s.0[3]];
        }
        out
    }

    /// The default tolerance's multigrid paste of the course (BearInWater into
    /// NewBackGround, 14.9k unknowns, both modes) stays within 2e-5 of the exact discrete
    /// solution (sparse Cholesky of the same system), a 200th of an 8-bit level, with its
    /// residual below the tolerance; the reference tolerance gets within 1e-9.
    #[test]
    fn default_tolerance_is_within_1e5_of_the_exact_course_paste() {
        let sea = course_image("NewBackGround.jpg", false);
        let bear = course_image("BearInWater.jpg", false);
        let mask = course_image("BearInWater_mask.png", true);
        let region = Region::new(&bear, Some(&mask)).unwrap();
        for mode in [Mode::Seamless, Mode::Mixed] {
            let off = [62.0, 162.0];
            let exact = blend_region(&sea, &bear, &region, off, mode, Solver::Cholesky, 1e-10);
            let exact = solved(exact.as_ref().unwrap()).values.clone();
            for (tol, bound) in [(poisson::DEFAULT_TOLERANCE, 2e-5), (8e-11, 1e-9)] {
                let mg = blend_region(&sea, &bear, &region, off, mode, Solver::Multigrid, tol);
                let s = solved(mg.as_ref().unwrap());
                let err = (&s.values - &exact).norm_max();
                assert_eq!(s.solver, "multigrid");
                eprintln!(
                    "{mode:?} tolerance {tol:e}: {} iterations, residual {:e}, max error {err:e}",
                    s.iterations, s.residual
                );
                assert!(s.residual <= tol, "{mode:?} {tol:e}: {}", s.residual);
                assert!(err < bound, "{mode:?} {tol:e}: {err:e}");
            }
        }
    }
}
