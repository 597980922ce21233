//! Phase timings of the course paste (BearInWater into NewBackGround), first and reused, as
//! `bench/peers/poisson_opencv.py` chains them: `cargo test --release -p cgnodes-image
//! course_paste_phases -- --ignored --nocapture`. Measurements only (no assertion on time).

use super::*;
use std::path::Path;

fn load(name: &str, raw: bool) -> Image {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/images")
        .join(name);
    let img = image::open(&path).expect("course image").to_rgba32f();
    let mut out = Image::new(img.width(), img.height(), [0.0; 4]);
    for (d, s) in out.pixels.iter_mut().zip(img.pixels()) {
        *d = if raw {
            s.0
        } else {
            [s.0[0].powf(2.2), s.0[1].powf(2.2), s.0[2].powf(2.2), s.0[3]]
        };
    }
    out
}

/// The course's target, source and mask.
fn course_images() -> (Image, Image, Image) {
    (
        load("NewBackGround.jpg", false),
        load("BearInWater.jpg", false),
        load("BearInWater_mask.png", true),
    )
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[test]
#[ignore]
fn course_paste_phases() {
    let (sea, bear, mask) = course_images();
    for mode in [Mode::Seamless, Mode::Mixed] {
        // a warm-up paste of another shape (the mask less its first inside row)
        let t = Instant::now();
        let shape = MaskShape::from_image(&mask);
        let key = shape.key();
        let t_region = ms(t);
        let mut flags: Vec<bool> = shape.index.iter().map(|&k| k != u32::MAX).collect();
        let first_row = shape.inside[0][1] as usize * mask.width as usize;
        flags[first_row..first_row + mask.width as usize].fill(false);
        let warm = MaskShape::from_flags(mask.width, mask.height, &flags);
        let s = solve_keyed(
            &warm,
            &warm.key(),
            &sea,
            &bear,
            [62, 162],
            mode,
            Solver::Auto,
            DEFAULT_TOLERANCE,
        )
        .unwrap();
        recycle(s.values);
        let mut target = sea.clone();
        for (i, off) in [
            [40, 150],
            [90, 170],
            [20, 140],
            [100, 160],
            [50, 155],
            [80, 165],
        ]
        .into_iter()
        .enumerate()
        {
            let t = Instant::now();
            let mut b = RHS_BUFFER.take();
            guidance::right_hand_side_into(&shape, &target, &bear, off, mode, &mut b);
            let t_rhs = ms(t);
            let t = Instant::now();
            let (factor, reused) = cached_factor_keyed(&shape, &key, Solver::Auto).unwrap();
            let t_factor = ms(t);
            let t = Instant::now();
            let mut x = b.clone();
            let (it, _) = factor
                .solve_in_place(x.as_mut(), DEFAULT_TOLERANCE)
                .unwrap();
            let t_solve = ms(t);
            let t = Instant::now();
            let r = system::residual_norm(&shape, x.as_ref(), b.as_ref());
            let t_res = ms(t);
            let t = Instant::now();
            let mut out = copy_target(&target).unwrap();
            let t_copy = ms(t);
            let t = Instant::now();
            write_solution(&mut out, &shape, off, &x);
            let t_write = ms(t);
            let t = Instant::now();
            let s = solve_keyed(
                &shape,
                &key,
                &target,
                &bear,
                off,
                mode,
                Solver::Auto,
                DEFAULT_TOLERANCE,
            )
            .unwrap();
            let t_again = ms(t);
            eprintln!(
                "{mode:?} paste {i}: region {t_region:.2} rhs {t_rhs:.2} factor {t_factor:.2} ({}, reused {reused}) \
                 solve {t_solve:.2} ({it} it.) residual {t_res:.2} ({r:.1e}) copy {t_copy:.2} write {t_write:.2}; whole solve again {t_again:.2} ({} it.)",
                factor.name(), s.iterations
            );
            RHS_BUFFER.keep(b);
            recycle(s.values);
            target = out;
        }
    }
}

/// The first paste of a new mask shape, by phase (median of 20 shapes, each the course
/// mask less one of its rows): `Region::new` (checks, Ω, key), the right-hand side, the
/// hierarchy, the cold solve, and what recomputing the residual would cost (the node takes
/// multigrid's own). `cargo test --release -p cgnodes-image course_first_paste_phases --
/// --ignored --nocapture`.
#[test]
#[ignore]
fn course_first_paste_phases() {
    let (sea, bear, mask) = course_images();
    // on a pool thread, as the node runs: a call from outside the pool would pay a hand-off
    // to the pool in every parallel loop
    rayon::scope(|_| first_pastes(&sea, &bear, &mask));
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn first_pastes(sea: &Image, bear: &Image, mask: &Image) {
    let (src, m) = (
        std::sync::Arc::new(bear.clone()),
        std::sync::Arc::new(mask.clone()),
    );
    let region = median(
        (0..20)
            .map(|_| {
                let t = Instant::now();
                let r = crate::poisson_blend::Region::new(&src, Some(&m));
                assert!(r.is_ok());
                ms(t)
            })
            .collect(),
    );
    let shape = MaskShape::from_image(mask);
    let (first_row, w) = (shape.inside[0][1] as usize, mask.width as usize);
    for mode in [Mode::Seamless, Mode::Mixed] {
        let mut rows = Vec::new();
        for i in 0..25 {
            // a new shape every time: the mask less row first_row + 20 + i
            let mut flags: Vec<bool> = shape.index.iter().map(|&k| k != u32::MAX).collect();
            let y = first_row + 20 + i;
            flags[y * w..(y + 1) * w].fill(false);
            let s = MaskShape::from_flags(mask.width, mask.height, &flags);
            let key = s.key();
            let t = Instant::now();
            let mut b = RHS_BUFFER.take();
            guidance::right_hand_side_into(&s, sea, bear, [62, 162], mode, &mut b);
            let t_rhs = ms(t);
            let t = Instant::now();
            let (factor, reused) = cached_factor_keyed(&s, &key, Solver::Auto).unwrap();
            let t_factor = ms(t);
            assert!(!reused);
            let t = Instant::now();
            let mut x = copy_of_rhs(&b);
            let (it, _) = factor
                .solve_in_place(x.as_mut(), DEFAULT_TOLERANCE)
                .unwrap();
            let t_solve = ms(t);
            let t = Instant::now();
            let r = relative_residual(&s, x.as_ref(), b.as_ref());
            let t_res = ms(t);
            assert!(r <= 1.01 * DEFAULT_TOLERANCE);
            RHS_BUFFER.keep(b);
            recycle(x);
            rows.push([t_rhs, t_factor, t_solve, t_res, it as f64]);
        }
        let med = |k: usize| median(rows[5..].iter().map(|r| r[k]).collect());
        eprintln!(
            "{mode:?} new shape, medians (ms): region {region:.3} rhs {:.3} hierarchy {:.3} \
             solve {:.3} ({} it.) residual {:.3}",
            med(0),
            med(1),
            med(2),
            med(4),
            med(3)
        );
    }
}

/// The first paste of a new mask shape (mixed gradients) in three orders, alternated in one
/// process, medians of 30 shapes each (the course mask less one pixel): Ω found first and the
/// target copied beside the solve, with no companion (`blend_region`); the same beside
/// `with_companion`; and the node's order, the copy beside Ω's scan as well, with the
/// companion (`poisson_blend`). `cargo test --release -p cgnodes-image
/// course_first_paste_companion -- --ignored --nocapture`.
#[test]
#[ignore]
fn course_first_paste_companion() {
    let (sea, bear, mask) = course_images();
    let shape = MaskShape::from_image(&mask);
    let w = mask.width as usize;
    rayon::scope(|_| {
        let mut times = [Vec::new(), Vec::new(), Vec::new()];
        for i in 0..90 {
            let mut m = mask.clone();
            // a new shape every time: the mask less one of its pixels
            let [x, y] = shape.inside[(i * 211 + 7) % shape.len()];
            m.pixels[y as usize * w + x as usize] = [0.0, 0.0, 0.0, 1.0];
            let paste = || {
                let region = crate::poisson_blend::Region::new(&bear, Some(&m)).unwrap();
                crate::poisson_blend::blend_region(
                    &sea,
                    &bear,
                    &region,
                    [62.0, 162.0],
                    Mode::Mixed,
                    Solver::Auto,
                    DEFAULT_TOLERANCE,
                )
                .unwrap()
            };
            let t = Instant::now();
            let b = match i % 3 {
                0 => paste(),
                1 => with_companion(paste),
                _ => crate::poisson_blend::poisson_blend(
                    &sea,
                    &bear,
                    Some(&m),
                    [62.0, 162.0],
                    Mode::Mixed,
                )
                .unwrap(),
            };
            times[i % 3].push(ms(t));
            if let Some(s) = b.solution {
                recycle(s.values);
            }
        }
        let [a, c, e] = times.map(median);
        eprintln!(
            "first paste, mixed, medians (ms): no companion {a:.3}, companion {c:.3}, \
             companion and the copy beside the scan (the node) {e:.3}"
        );
    });
}
