//! Tests of `seam_carve` and its parts.

use super::seam::energy::{backward_map, luminance};
use super::*;

/// A deterministic textured image: smooth waves plus noise (`crate::test_images::waves`).
fn image(w: u32, h: u32, seed: u64) -> Image {
    crate::test_images::waves(w, h, seed, [0.4, 0.25], 0.2)
}

fn req(width: usize, height: usize, energy: Energy) -> Request {
    Request {
        width,
        height,
        energy,
        order: Order::WidthFirst,
    }
}

/// Every vertical seam of a `w x h` grid, by enumeration.
fn all_seams(w: usize, h: usize) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = (0..w).map(|x| vec![x]).collect();
    for _ in 1..h {
        let mut next = Vec::new();
        for s in &out {
            let x = *s.last().unwrap() as isize;
            for d in -1..=1 {
                let nx = x + d;
                if (0..w as isize).contains(&nx) {
                    let mut t = s.clone();
                    t.push(nx as usize);
                    next.push(t);
                }
            }
        }
        out = next;
    }
    out
}

/// The energy of a seam by the definitions, independently of the DP.
fn seam_energy(g: &Grid, s: &[usize]) -> f64 {
    let (w, h) = (g.w, g.h);
    let at = |x: isize, y: usize| g.gray[y * w + x.clamp(0, w as isize - 1) as usize];
    let e = backward_map(&g.gray, w, h);
    (0..h)
        .map(|y| {
            let x = s[y];
            match g.mode {
                Energy::Backward => e[y * w + x],
                Energy::Forward => {
                    let xi = x as isize;
                    let c_u = (at(xi + 1, y) - at(xi - 1, y)).abs();
                    if y == 0 {
                        c_u
                    } else if s[y - 1] + 1 == x {
                        c_u + (at(xi, y - 1) - at(xi - 1, y)).abs()
                    } else if s[y - 1] == x + 1 {
                        c_u + (at(xi, y - 1) - at(xi + 1, y)).abs()
                    } else {
                        c_u
                    }
                }
            }
        })
        .sum()
}

#[test]
fn dp_finds_the_minimal_seam() {
    let img = image(6, 5, 1);
    for mode in [Energy::Backward, Energy::Forward] {
        let g = Grid::new(&img, vec![0.0; 30], mode);
        let s = find_seam(&g);
        let best = all_seams(6, 5)
            .iter()
            .map(|t| seam_energy(&g, t))
            .fold(f64::INFINITY, f64::min);
        assert!(
            (s.energy - best).abs() < 1e-12,
            "{mode:?}: {} vs {best}",
            s.energy
        );
        assert!((seam_energy(&g, &s.columns) - best).abs() < 1e-12);
    }
}

#[test]
fn local_energy_update_matches_a_full_recompute() {
    let img = image(30, 20, 2);
    let mut g = Grid::new(&img, vec![0.0; 600], Energy::Backward);
    for _ in 0..12 {
        let s = find_seam(&g);
        g.remove_seam(&s.columns);
        let full = backward_map(&g.gray, g.w, g.h);
        assert_eq!(g.energy, full);
    }
    g.transpose();
    let s = find_seam(&g);
    g.remove_seam(&s.columns);
    assert_eq!(g.energy, backward_map(&g.gray, g.w, g.h));
}

/// The marked pixels form `k` seams: per row (vertical) exactly k of them.
fn marked_per_line(marked: &[bool], w: usize, h: usize, vertical: bool) -> Vec<usize> {
    if vertical {
        (0..h)
            .map(|y| (0..w).filter(|&x| marked[y * w + x]).count())
            .collect()
    } else {
        (0..w)
            .map(|x| (0..h).filter(|&y| marked[y * w + x]).count())
            .collect()
    }
}

#[test]
fn removes_exactly_the_requested_seams_each_8_connected() {
    let img = image(40, 30, 3);
    for mode in [Energy::Backward, Energy::Forward] {
        let r = seam_carve(&img, None, None, req(31, 30, mode)).unwrap();
        assert_eq!((r.image.width, r.image.height), (31, 30));
        assert_eq!((r.removed, r.inserted), (9, 0));
        assert!(marked_per_line(&r.marked, 40, 30, true)
            .iter()
            .all(|&n| n == 9));
        // one seam: 8-connected and one pixel in every row, every column for horizontal
        let one = seam_carve(&img, None, None, req(39, 30, mode)).unwrap();
        let cols: Vec<usize> = (0..30)
            .map(|y| (0..40).find(|&x| one.marked[y * 40 + x]).unwrap())
            .collect();
        assert!(cols.windows(2).all(|p| p[0].abs_diff(p[1]) <= 1));
        let one = seam_carve(&img, None, None, req(40, 29, mode)).unwrap();
        assert_eq!((one.image.width, one.image.height), (40, 29));
        assert!(marked_per_line(&one.marked, 40, 30, false)
            .iter()
            .all(|&n| n == 1));
        let rows: Vec<usize> = (0..40)
            .map(|x| (0..30).find(|&y| one.marked[y * 40 + x]).unwrap())
            .collect();
        assert!(rows.windows(2).all(|p| p[0].abs_diff(p[1]) <= 1));
        // the kept pixels are the input's, in order, in every row
        for y in 0..30u32 {
            let kept: Vec<[f32; 4]> = (0..40)
                .filter(|&x| !r.marked[(y * 40 + x) as usize])
                .map(|x| img.get(x, y))
                .collect();
            let out: Vec<[f32; 4]> = (0..31).map(|x| r.image.get(x, y)).collect();
            assert_eq!(kept, out);
        }
    }
}

#[test]
fn a_protected_region_survives() {
    // a flat block that unprotected seams go through
    let mut img = image(40, 24, 4);
    for y in 4..20 {
        for x in 10..22 {
            img.set(x, y, [0.3, 0.3, 0.3, 1.0]);
        }
    }
    let mut mask = Image::new(40, 24, [0.0, 0.0, 0.0, 1.0]);
    for y in 4..20 {
        for x in 10..22 {
            mask.set(x, y, [1.0; 4]);
        }
    }
    let inside = |r: &Carved| {
        (0..24 * 40)
            .filter(|&i| r.marked[i] && mask.pixels[i][0] > 0.5)
            .count()
    };
    let free = seam_carve(&img, None, None, req(28, 24, Energy::Backward)).unwrap();
    assert!(
        inside(&free) > 0,
        "the test needs seams through the block without protection"
    );
    for mode in [Energy::Backward, Energy::Forward] {
        let r = seam_carve(&img, Some(&mask), None, req(28, 24, mode)).unwrap();
        assert_eq!(inside(&r), 0);
        assert_eq!(r.protected_removed, 0);
        // the block is still there, whole: 12 x 16 gray pixels in a rectangle
        let gray = |x: u32, y: u32| r.image.get(x, y) == [0.3, 0.3, 0.3, 1.0];
        let x0 = (0..28).find(|&x| gray(x, 4)).unwrap();
        assert!((4..20).all(|y| (x0..x0 + 12).all(|x| gray(x, y))));
    }
}

#[test]
fn remove_then_insert_returns_the_original_size() {
    let img = image(36, 28, 5);
    let mut mask = Image::new(36, 28, [0.0, 0.0, 0.0, 1.0]);
    for y in 9..17 {
        for x in 14..19 {
            mask.set(x, y, [1.0; 4]);
        }
    }
    let r = seam_carve(&img, None, Some(&mask), req(0, 0, Energy::Forward)).unwrap();
    assert_eq!((r.image.width, r.image.height), (36, 28));
    assert!(
        r.removed >= 5 && r.inserted == r.removed,
        "{} {}",
        r.removed,
        r.inserted
    );
    assert_eq!(r.remove_left, 0);
    // every masked pixel was taken by a seam
    assert!((0..36 * 28).all(|i| mask.pixels[i][0] < 0.5 || r.marked[i]));
}

#[test]
fn insertion_duplicates_distinct_seams() {
    let img = image(20, 10, 6);
    let r = seam_carve(&img, None, None, req(27, 10, Energy::Backward)).unwrap();
    assert_eq!((r.image.width, r.image.height), (27, 10));
    assert_eq!(r.inserted, 7);
    // 7 distinct pixels per row were duplicated, and every input pixel is in the output
    assert!(marked_per_line(&r.marked, 20, 10, true)
        .iter()
        .all(|&n| n == 7));
    for y in 0..10u32 {
        let out: Vec<[f32; 4]> = (0..27).map(|x| r.image.get(x, y)).collect();
        let mut k = 0;
        for x in 0..20 {
            k += out[k..]
                .iter()
                .position(|p| *p == img.get(x, y))
                .expect("input pixel kept")
                + 1;
        }
    }
    // more than doubling works in rounds
    let big = seam_carve(&img, None, None, req(50, 25, Energy::Forward)).unwrap();
    assert_eq!((big.image.width, big.image.height), (50, 25));
}

#[test]
fn optimal_order_costs_no_more_than_either_fixed_order() {
    let img = image(16, 14, 7);
    let g = Grid::new(&img, vec![0.0; 16 * 14], Energy::Backward);
    let (seq, total) = order::optimal_order(&g, 3, 4);
    assert_eq!(seq.iter().filter(|&&h| h).count(), 3);
    let fixed = |order| {
        let r = seam_carve(
            &img,
            None,
            None,
            Request {
                order,
                ..req(12, 11, Energy::Backward)
            },
        );
        r.unwrap().energy_removed
    };
    assert!(total <= fixed(Order::WidthFirst) + 1e-9);
    assert!(total <= fixed(Order::HeightFirst) + 1e-9);
    let r = seam_carve(
        &img,
        None,
        None,
        Request {
            order: Order::Optimal,
            ..req(12, 11, Energy::Backward)
        },
    )
    .unwrap();
    assert_eq!((r.image.width, r.image.height), (12, 11));
    assert!((r.energy_removed - total).abs() < 1e-9);
}

#[test]
fn bad_inputs_name_their_socket() {
    let img = image(10, 8, 8);
    let sock = |r: Result<Carved, NodeError>| r.unwrap_err().socket.unwrap();
    assert_eq!(
        sock(seam_carve(&img, None, None, req(0, 8, Energy::Backward))),
        "width"
    );
    assert_eq!(
        sock(seam_carve(&img, None, None, req(8, 0, Energy::Backward))),
        "height"
    );
    assert_eq!(
        sock(seam_carve(&img, None, None, req(161, 8, Energy::Backward))),
        "width"
    );
    let wrong = Image::new(9, 8, [1.0; 4]);
    assert_eq!(
        sock(seam_carve(
            &img,
            Some(&wrong),
            None,
            req(8, 8, Energy::Backward)
        )),
        "protect"
    );
    assert_eq!(
        sock(seam_carve(
            &img,
            None,
            Some(&wrong),
            req(8, 8, Energy::Backward)
        )),
        "remove"
    );
    let mut bad = img.clone();
    bad.set(3, 2, [f32::NAN, 0.0, 0.0, 1.0]);
    let e = seam_carve(&bad, None, None, req(8, 8, Energy::Backward)).unwrap_err();
    assert_eq!(e.socket.as_deref(), Some("image"));
    assert!(e.message.contains("(3, 2)"));
    let empty = Image::new(0, 0, [0.0; 4]);
    assert_eq!(
        sock(seam_carve(&empty, None, None, req(1, 1, Energy::Backward))),
        "image"
    );
    assert!(luminance([1.0, 1.0, 1.0, 1.0]) > 0.999);
}
