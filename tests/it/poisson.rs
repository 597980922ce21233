//! `poisson_blend` through the node interface: the table's facts (pixels, residual, reuse of
//! the factorization), the empty-mask warning, and errors naming their socket.

use crate::common::{poisson_lock, run_node, NodeOutputs};
use cgnodes::node::FileEnv;
use cgnodes::types::{Image, Table, Value};
use std::collections::BTreeMap;

/// Runs `poisson_blend` outside a graph: its outputs and log lines, or the error text.
fn blend(inputs: Vec<(&str, Value)>) -> Result<NodeOutputs, String> {
    run_node("poisson_blend", inputs, &FileEnv::default())
}

fn table(out: &BTreeMap<String, Value>) -> Table {
    match &out["table"] {
        Value::Table(t) => (**t).clone(),
        v => panic!("table expected, got {v:?}"),
    }
}

fn image(out: &BTreeMap<String, Value>) -> Image {
    match &out["image"] {
        Value::Image(i) => (**i).clone(),
        v => panic!("image expected, got {v:?}"),
    }
}

/// A smooth image with a ramp per channel.
fn ramp(w: u32, h: u32, k: f32) -> Image {
    let mut img = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
            img.set(x, y, [fx * k, fy, (fx * fy * 7.0).sin().abs(), 1.0]);
        }
    }
    img
}

/// A ring-shaped mask (white inside) of a `w x h` source: a shape with a hole.
fn ring(w: u32, h: u32) -> Image {
    let mut m = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x as f32 - w as f32 / 2.0, y as f32 - h as f32 / 2.0);
            let r2 = dx * dx + dy * dy;
            if r2 < (w as f32 * 0.45).powi(2) && r2 > 9.0 {
                m.set(x, y, [1.0; 4]);
            }
        }
    }
    m
}

fn inputs(
    target: &Image,
    source: &Image,
    mask: &Image,
    offset: [f64; 2],
    mode: &str,
) -> Vec<(&'static str, Value)> {
    vec![
        ("target", Value::from(target.clone())),
        ("source", Value::from(source.clone())),
        ("mask", Value::from(mask.clone())),
        ("offset", Value::Vec2(offset)),
        ("mode", Value::from(mode)),
    ]
}

#[test]
fn second_paste_with_the_same_mask_shape_reuses_the_factorization() {
    let _lock = poisson_lock();
    let target = ramp(120, 90, 1.0);
    let source = ramp(41, 37, 3.0);
    let mask = ring(41, 37); // a shape only this test uses
    let (a, _) = blend(inputs(&target, &source, &mask, [10.0, 12.0], "seamless")).unwrap();
    let ta = table(&a);
    assert!(ta.column("pixels").unwrap()[0] > 500.0);
    assert!(ta.column("residual").unwrap()[0] < 1e-10);
    // moved: the same shape elsewhere, factor from the cache
    let (b, _) = blend(inputs(&target, &source, &mask, [60.2, 40.4], "seamless")).unwrap();
    let tb = table(&b);
    assert_eq!(tb.column("reused").unwrap()[0], 1.0);
    assert!(tb.column("residual").unwrap()[0] < 1e-10);
    // the same result as a fresh factorization of the same system
    use cgnodes::nodes::image::poisson_blend::poisson::{guidance, system, MaskShape, Mode};
    let shape = MaskShape::from_image(&mask);
    let f = system::factor(&shape).unwrap();
    let mut x = guidance::right_hand_side(&shape, &target, &source, [60, 40], Mode::Seamless);
    f.solve_in_place(x.as_mut());
    let img = image(&b);
    let mut worst = 0.0f64;
    for (k, &[px, py]) in shape.inside.iter().enumerate() {
        let p = img.get(px + 60, py + 40);
        for c in 0..3 {
            worst = worst.max((p[c] as f64 - x[(k, c)]).abs());
        }
    }
    // the image holds f32: equal to the fresh f64 solution up to its rounding
    assert!(worst < 1e-6, "{worst}");
}

#[test]
fn source_equal_to_target_gives_the_target_back() {
    let _lock = poisson_lock();
    let target = ramp(64, 64, 1.0);
    let max_diff = |img: &Image| {
        img.pixels
            .iter()
            .zip(&target.pixels)
            .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()))
            .fold(0.0f32, f32::max)
    };
    // the source is the target itself, pasted in place over a ring: f = f* solves eq. 7
    // exactly (f32 output of an f64 solution equal to f32 inputs)
    for mode in ["seamless", "mixed"] {
        let (out, _) = blend(inputs(&target, &target, &ring(64, 64), [0.0, 0.0], mode)).unwrap();
        assert!(max_diff(&image(&out)) < 1e-6, "{mode}");
        assert!(table(&out).column("residual").unwrap()[0] < 1e-10);
    }
    // a crop of the target pasted back over its whole rectangle: Ω touches the source's edges,
    // where the source is extended by its nearest pixel (g_p - g_q = 0); mixed mode takes the
    // target's gradient there and is exact, seamless is not (the membrane takes over there)
    let mut source = Image::new(30, 20, [0.0; 4]);
    for y in 0..20 {
        for x in 0..30 {
            source.set(x, y, target.get(x + 17, y + 23));
        }
    }
    let full = Image::new(30, 20, [1.0; 4]);
    let (out, _) = blend(inputs(&target, &source, &full, [17.0, 23.0], "mixed")).unwrap();
    assert!(max_diff(&image(&out)) < 1e-6);
    let (out, _) = blend(inputs(&target, &source, &full, [17.0, 23.0], "seamless")).unwrap();
    assert!(max_diff(&image(&out)) > 1e-4);
}

#[test]
fn empty_mask_warns_and_returns_the_target() {
    let _lock = poisson_lock();
    let target = ramp(16, 16, 1.0);
    let source = ramp(4, 4, 2.0);
    let mask = Image::new(4, 4, [0.0, 0.0, 0.0, 1.0]);
    let (out, logs) = blend(inputs(&target, &source, &mask, [2.0, 2.0], "seamless")).unwrap();
    assert_eq!(image(&out), target);
    assert_eq!(table(&out).column("pixels").unwrap()[0], 0.0);
    assert!(logs
        .iter()
        .any(|l| l.contains("warning") && l.contains("empty")));
}

#[test]
fn bad_inputs_get_errors_naming_the_socket() {
    let _lock = poisson_lock();
    let target = ramp(16, 16, 1.0);
    let source = ramp(6, 6, 2.0);
    let full = Image::new(6, 6, [1.0; 4]);
    let err = |ins| blend(ins).unwrap_err();
    let e = err(inputs(&target, &source, &full, [0.0, 3.0], "seamless"));
    assert!(
        e.contains("socket 'offset'") && e.contains("x in [1, 9], y in [1, 9]"),
        "{e}"
    );
    let e = err(inputs(&target, &source, &full, [9.0, 9.6], "seamless"));
    assert!(e.contains("socket 'offset'"), "{e}");
    let e = err(inputs(
        &ramp(7, 7, 1.0),
        &source,
        &full,
        [1.0, 1.0],
        "seamless",
    ));
    assert!(e.contains("socket 'mask'") && e.contains("margin"), "{e}");
    let e = err(inputs(
        &target,
        &source,
        &Image::new(5, 6, [1.0; 4]),
        [2.0, 2.0],
        "mixed",
    ));
    assert!(e.contains("socket 'mask'") && e.contains("5x6"), "{e}");
    let mut nan = source.clone();
    nan.set(1, 1, [f32::NAN; 4]);
    let e = err(inputs(&target, &nan, &full, [2.0, 2.0], "seamless"));
    assert!(
        e.contains("socket 'source'") && e.contains("not finite"),
        "{e}"
    );
    let e = err(inputs(&target, &source, &full, [2.0, 2.0], "poisson"));
    assert!(e.contains("socket 'mode'"), "{e}");
}

#[test]
fn solver_choice_multigrid_and_cholesky_agree_and_sine_transform_needs_a_rectangle() {
    let _lock = poisson_lock();
    let target = ramp(200, 180, 1.0);
    let source = ramp(97, 83, 2.5);
    let mask = ring(97, 83); // 4,500 pixels: `auto` picks multigrid (a shape only this test uses)
    let with = |solver: &str, off: [f64; 2]| {
        let mut ins = inputs(&target, &source, &mask, off, "mixed");
        ins.push(("solver", Value::from(solver)));
        // a reference solve (the default stops at 1e-5)
        ins.push(("tolerance", Value::from(8e-11)));
        blend(ins)
    };
    let col = |t: &Table, c: &str| t.column(c).unwrap()[0];
    let (chol, _) = with("cholesky", [20.0, 30.0]).unwrap();
    let tc = table(&chol);
    assert!(col(&tc, "pixels") > 4096.0);
    assert_eq!((col(&tc, "multigrid"), col(&tc, "iterations")), (0.0, 0.0));
    for (i, solver) in ["multigrid", "auto"].iter().enumerate() {
        let (mg, _) = with(solver, [20.0, 30.0]).unwrap();
        let tm = table(&mg);
        assert_eq!(col(&tm, "multigrid"), 1.0, "{solver}");
        // `auto` shares the hierarchy `multigrid` built
        assert_eq!(col(&tm, "reused"), i as f64, "{solver}");
        assert!(col(&tm, "residual") < 1e-10);
        // the repeated identical paste starts from its own solution: no iteration needed
        let it = col(&tm, "iterations");
        assert!(
            if i == 0 {
                (1.0..=30.0).contains(&it)
            } else {
                it == 0.0
            },
            "{solver}: {it}"
        );
        // the same pixels as Cholesky up to the f32 image's rounding
        let (a, b) = (image(&chol), image(&mg));
        let worst = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()));
        assert!(worst.fold(0.0f32, f32::max) < 1e-5);
    }
    // moved: the hierarchy is reused, warm-started from the last solution
    let (moved, _) = with("multigrid", [90.0, 80.0]).unwrap();
    let tm = table(&moved);
    assert_eq!(col(&tm, "reused"), 1.0);
    assert!(col(&tm, "residual") < 1e-10);
    assert!(col(&tm, "iterations") >= 1.0);
    // three multigrid pastes of this shape so far: `auto` switches to Cholesky (the
    // ski-rental rule, `AUTO_CHOLESKY_AFTER`), here the factor the first paste made
    assert_eq!(
        cgnodes::nodes::image::poisson_blend::poisson::AUTO_CHOLESKY_AFTER,
        3
    );
    for off in [[60.0, 50.0], [30.0, 40.0]] {
        let (late, _) = with("auto", off).unwrap();
        let tl = table(&late);
        assert_eq!((col(&tl, "multigrid"), col(&tl, "reused")), (0.0, 1.0));
        assert!(col(&tl, "residual") < 1e-10);
    }
    // an explicit choice is kept
    let (mg, _) = with("multigrid", [60.0, 50.0]).unwrap();
    assert_eq!(col(&table(&mg), "multigrid"), 1.0);
    // the sine transform only for a rectangle
    let e = with("sine_transform", [20.0, 30.0]).unwrap_err();
    assert!(
        e.contains("socket 'solver'") && e.contains("rectangular"),
        "{e}"
    );
    let full = Image::new(97, 83, [1.0; 4]);
    let mut ins = inputs(&target, &source, &full, [20.0, 30.0], "seamless");
    ins.push(("solver", Value::from("sine_transform")));
    let (rect, _) = blend(ins).unwrap();
    assert_eq!(col(&table(&rect), "sine_transform"), 1.0);
    let e = {
        let mut ins = inputs(&target, &source, &mask, [20.0, 30.0], "seamless");
        ins.push(("solver", Value::from("fastest")));
        blend(ins).unwrap_err()
    };
    assert!(e.contains("socket 'solver'"), "{e}");
}
