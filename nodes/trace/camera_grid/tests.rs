//! Tests of `CameraGrid`: its hits against the BVH's, its lists, clipping and refusal.

use super::*;
use crate::bvh::Bvh;
use cgnodes_api::rng::Pcg32;
use cgnodes_api::types::Camera;

pub(super) fn camera(eye: [f64; 3], target: [f64; 3], w: u32, h: u32, fov: f64) -> PinholeCamera {
    PinholeCamera::new(&Camera {
        eye,
        target,
        width: w,
        height: h,
        fov_deg: fov,
        far: 1e30,
        ..Default::default()
    })
    .unwrap()
}

/// A test camera: eye, target, width, height, field of view (degrees).
pub(super) type TestCamera = ([f64; 3], [f64; 3], u32, u32, f64);

/// Cameras outside, inside and at the edge of `soup`, wide and narrow, square and not.
pub(super) const CAMERAS: [TestCamera; 4] = [
    ([0.0, 0.0, 6.0], [0.0, 0.0, 0.0], 48, 40, 45.0),
    ([0.3, 0.2, 0.4], [0.0, -0.3, -1.0], 40, 40, 120.0),
    ([4.0, 3.0, -2.0], [0.0, 0.0, 0.0], 64, 24, 10.0),
    ([0.0, 0.0, 0.2], [0.0, 0.0, -2.0], 30, 50, 170.0),
];

/// A soup of triangles of every size (some far larger than the view, some behind the
/// eye, some through the plane of the eye), a closed sphere mesh (shared edges, where
/// ties happen), and optionally a huge ground plane.
pub(super) fn soup(rng: &mut Pcg32, eye: V3, ground: bool) -> Vec<[V3; 3]> {
    let mut tris = Vec::new();
    if ground {
        // A ground plane 1e5 units across: the clipping plane moves out to 0.01.
        tris.push([[-1e5, -4.0, -1e5], [0.0, -4.0, 1e5], [1e5, -4.0, -1e5]]);
    }
    let mut r = |s: f32| (rng.next_f32() * 2.0 - 1.0) * s;
    for k in 0..300 {
        let s = [0.02, 0.3, 3.0, 40.0][k % 4];
        let c = [r(3.0), r(3.0), r(3.0)];
        tris.push([0, 1, 2].map(|_| [c[0] + r(s), c[1] + r(s), c[2] + r(s)]));
    }
    // Triangles passing a hair in front of, beside and behind the eye.
    for k in 0..20 {
        let d = [1e-6, 1e-4, 1e-2][k % 3];
        let c = [eye[0] + r(d), eye[1] + r(d), eye[2] + r(d)];
        // Centred on c, so its plane passes within d of the eye.
        let (e, f) = ([r(1.0), r(1.0), r(1.0)], [r(1.0), r(1.0), r(1.0)]);
        tris.push([
            [c[0] + e[0], c[1] + e[1], c[2] + e[2]],
            [c[0] + f[0], c[1] + f[1], c[2] + f[2]],
            [c[0] - e[0] - f[0], c[1] - e[1] - f[1], c[2] - e[2] - f[2]],
        ]);
    }
    let (n, m) = (12, 24);
    let at = |i: usize, j: usize| {
        let (th, ph) = (
            std::f32::consts::PI * i as f32 / n as f32,
            std::f32::consts::TAU * j as f32 / m as f32,
        );
        [th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin() - 0.5]
    };
    for i in 0..n {
        for j in 0..m {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    tris
}

/// Every camera ray's grid answer is the BVH's: the same distance bit for bit, and the
/// same triangle unless another one ties with it at that distance; over cameras outside,
/// inside and at the edge of the soup, wide and narrow, square and not.
#[test]
fn grid_hits_are_the_bvh_hits() {
    let mut rng = Pcg32::new(7, 11);
    let (mut hits, mut ties) = (0, 0);
    for (eye, target, w, h, fov) in CAMERAS {
        let cam = camera(eye, target, w, h, fov);
        let tris = soup(&mut rng, cam.eye, fov > 100.0);
        let bvh = Bvh::build(&tris);
        let grid = CameraGrid::build(&tris, &cam).expect("the soup fits the budget");
        for y in 0..h {
            for x in 0..w {
                for s in 0..4 {
                    // Jittered, plus the pixel's corners and edges.
                    let (a, b) = match s {
                        0 => (0.0, 0.0),
                        1 => (1.0 - f32::EPSILON, 0.5),
                        _ => (rng.next_f32(), rng.next_f32()),
                    };
                    let dir = cam.ray_dir(x as f32 + a, y as f32 + b);
                    let want = bvh.intersect(cam.eye, dir, cam.far);
                    let got = grid.intersect(&tris, (x, y), cam.eye, dir, cam.far);
                    match (want, got) {
                        (None, None) => {}
                        (Some(p), Some(q)) => {
                            assert_eq!(p.t.to_bits(), q.t.to_bits(), "pixel {x},{y}");
                            hits += 1;
                            if p.prim != q.prim {
                                let r = RayPre::new(cam.eye, dir);
                                let t = crate::bvh::intersect_triangle(
                                    &r,
                                    &tris[p.prim as usize],
                                    f32::INFINITY,
                                );
                                assert_eq!(t.map(|t| t.0.to_bits()), Some(q.t.to_bits()));
                                ties += 1;
                            }
                        }
                        _ => panic!("pixel {x},{y}: BVH {want:?}, grid {got:?}"),
                    }
                }
            }
        }
    }
    assert!(hits > 10_000, "{hits} hits");
    assert!(ties < hits / 100, "{ties} ties in {hits} hits");
}

/// Each pixel's candidates are nearest first by their distance bounds (ties by
/// triangle), which the closest-hit loop's early stop relies on, and each bound is at
/// most the distance of any hit on its triangle through the pixel.
#[test]
fn lists_are_nearest_first_and_bound_their_hits() {
    let mut rng = Pcg32::new(3, 5);
    let mut checked = 0;
    for (eye, target, w, h, fov) in CAMERAS {
        let cam = camera(eye, target, w, h, fov);
        let tris = soup(&mut rng, cam.eye, fov > 100.0);
        let grid = CameraGrid::build(&tris, &cam).expect("the soup fits the budget");
        for px in 0..(w * h) as usize {
            let list = &grid.cand[grid.start[px] as usize..grid.start[px + 1] as usize];
            for pair in list.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                assert!(
                    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1),
                    "pixel {px}: {a:?} {b:?}"
                );
            }
            let (x, y) = ((px % w as usize) as f32, (px / w as usize) as f32);
            let dir = cam.ray_dir(x + rng.next_f32(), y + rng.next_f32());
            let r = RayPre::new(cam.eye, dir);
            for &(key, i) in list {
                let tri = &tris[i as usize];
                if let Some((t, _, _)) = crate::bvh::intersect_triangle(&r, tri, f32::MAX) {
                    assert!(key <= t, "pixel {px}: bound {key} above hit {t}");
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1000, "{checked} hits checked");
}

/// Clipping at the eye's plane keeps what is in front: a triangle through the eye's
/// plane covers exactly its visible part.
#[test]
fn clipping_keeps_the_front() {
    let (p, n) = clip_near([[0.0, 0.0, -1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], 0.5);
    assert_eq!(n, 4);
    assert!(p[..n].iter().all(|q| q[2] >= 0.5));
    assert_eq!(clip_near([[0.0, 0.0, -1.0]; 3], 0.5).1, 0);
    assert_eq!(clip_near([[0.0, 0.0, 1.0]; 3], 0.5).1, 3);
}

/// Far more coverage than the film has pixels: no grid, the camera rays take the BVH.
#[test]
fn overfull_grid_is_refused() {
    let cam = camera([0.0, 0.0, 3.0], [0.0; 3], 64, 64, 45.0);
    let big = [[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [0.0, 50.0, 0.0]];
    assert!(CameraGrid::build(&vec![big; 10], &cam).is_some());
    assert!(CameraGrid::build(&vec![big; 400], &cam).is_none());
    assert!(CameraGrid::build(&[], &cam).is_none());
    // Many triangles through the eye: no grid either.
    let through = [[-1.0, -1.0, 3.0], [1.0, -1.0, 3.0], [0.0, 1.0, 3.0]];
    assert!(CameraGrid::build(&vec![through; 10], &cam).is_some());
    assert!(CameraGrid::build(&vec![through; 100], &cam).is_none());
}
