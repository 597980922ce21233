//! `CameraGrid::intersect8`: the grid's camera-ray test for eight rays through one pixel
//! at once (a path's starts come eight at a time, and at eight or more samples per pixel
//! the eight share a pixel, so they share its candidate list): each candidate triangle is
//! tested for the eight rays on eight lanes.

use super::CameraGrid;
use crate::bvh::{sheared_test, Hit, RayPre};
use crate::lane_math::Lane;
use crate::sampling::V3;

impl CameraGrid {
    /// `intersect` for the eight camera rays `eye + t dirs[.][i]` (unit directions, axis
    /// by ray) through pixel `(x, y)`, on eight lanes (`F`: one AVX register in the lane
    /// loop's x86-64-v3 build, two SSE halves elsewhere): each candidate
    /// triangle is tested once for all eight rays instead of once per ray. `None` when the
    /// rays do not share their axis permutation of the watertight test (the caller then
    /// traces them one by one). Each lane computes the scalar test's operations in its
    /// order and a ray whose edge functions need the double-precision fallback takes the
    /// scalar test's second half, so every hit is bit for bit `intersect`'s.
    #[inline(always)]
    pub(crate) fn intersect8<F: Lane>(
        &self,
        tris: &[[V3; 3]],
        (x, y): (u32, u32),
        eye: V3,
        dirs: &[[f32; 8]; 3],
        tmax: f32,
    ) -> Option<[Option<Hit>; 8]> {
        let axes = RayPre::new(eye, [dirs[0][0], dirs[1][0], dirs[2][0]]).axes();
        let (kx, ky, kz) = axes;
        let d = dirs.map(F::from_array);
        // `RayPre::new`'s choice of kz and of the swap, lane by lane.
        let a = d.map(|v| v.abs());
        let m01 = a[0].simd_gt(a[1]).to_bitmask();
        let m02 = a[0].simd_gt(a[2]).to_bitmask();
        let m12 = a[1].simd_gt(a[2]).to_bitmask();
        let same_kz = match kz {
            0 => m01 & m02,
            1 => !m01 & m12,
            _ => (m01 & !m02) | (!m01 & !m12),
        } & 0xff;
        let neg = d[kz].simd_lt(F::splat(0.0)).to_bitmask() & 0xff;
        if same_kz != 0xff || (neg != 0 && neg != 0xff) {
            return None;
        }
        // The shear (`RayPre`: sz = 1 / dir[kz], sx = dir[kx] sz, sy = dir[ky] sz).
        let sz = F::splat(1.0) / d[kz];
        let ray = Rays8 {
            eye,
            axes,
            sh: [d[kx] * sz, d[ky] * sz, sz],
        };
        let mut tm = [tmax; 8];
        let mut best = [None; 8];
        for &i in &self.near {
            ray.test(tris, i, 0xff, &mut tm, &mut best);
        }
        let px = y as usize * self.width as usize + x as usize;
        for &(key, i) in &self.cand[self.start[px] as usize..self.start[px + 1] as usize] {
            // The rays whose loop would not have stopped yet (`key >= tmax` stops it).
            let live = !F::from_array(tm).simd_le(F::splat(key)).to_bitmask() & 0xff;
            if live == 0 {
                break;
            }
            ray.test(tris, i, live, &mut tm, &mut best);
        }
        Some(best)
    }
}

/// Eight camera rays sharing the eye and the watertight test's axis permutation, with
/// each ray's shear (sx, sy, sz) on a lane.
struct Rays8<F> {
    eye: V3,
    axes: (usize, usize, usize),
    sh: [F; 3],
}

impl<F: Lane> Rays8<F> {
    /// `tri_test` of triangle `i` for the rays in `live` (bits), each against its own
    /// closest distance so far `tm`; a hit lowers it and becomes the ray's `best`.
    #[inline(always)]
    fn test(
        &self,
        tris: &[[V3; 3]],
        i: u32,
        live: u32,
        tm: &mut [f32; 8],
        best: &mut [Option<Hit>; 8],
    ) {
        let (kx, ky, kz) = self.axes;
        let [sx, sy, sz] = self.sh;
        let t = &tris[i as usize];
        let rel = |p: V3| [p[0] - self.eye[0], p[1] - self.eye[1], p[2] - self.eye[2]];
        let (a, b, c) = (rel(t[0]), rel(t[1]), rel(t[2]));
        let sp = F::splat;
        // Shear and scale the corners (Woop et al. 2013, eq. 5), as `tri_test`.
        let ax = sp(a[kx]) - sx * sp(a[kz]);
        let ay = sp(a[ky]) - sy * sp(a[kz]);
        let bx = sp(b[kx]) - sx * sp(b[kz]);
        let by = sp(b[ky]) - sy * sp(b[kz]);
        let cx = sp(c[kx]) - sx * sp(c[kz]);
        let cy = sp(c[ky]) - sy * sp(c[kz]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let z = F::splat(0.0);
        let m = |x: F| x.to_bitmask() & 0xff;
        let edge = m(u.simd_eq(z) | v.simd_eq(z) | w.simd_eq(z)) & live;
        let outside = m((u.simd_lt(z) | v.simd_lt(z) | w.simd_lt(z))
            & (u.simd_gt(z) | v.simd_gt(z) | w.simd_gt(z)));
        let det = u + v + w;
        let tt = u * (sz * sp(a[kz])) + v * (sz * sp(b[kz])) + w * (sz * sp(c[kz]));
        // The sign-aware depth test (section 3.4).
        let td = F::from_array(*tm) * det;
        let pos = m(det.simd_gt(z));
        let reject =
            (pos & m(tt.simd_le(z) | td.simd_le(tt))) | (!pos & m(z.simd_le(tt) | tt.simd_le(td)));
        let hit = live & !edge & !outside & !m(det.simd_eq(z)) & !reject;
        if hit | edge == 0 {
            return;
        }
        let rcp = sp(1.0) / det;
        let (th, hu, hv) = (
            (tt * rcp).to_array(),
            (v * rcp).to_array(),
            (w * rcp).to_array(),
        );
        let mut todo = hit | edge;
        while todo != 0 {
            let l = todo.trailing_zeros() as usize;
            todo &= todo - 1;
            let found = if hit & (1 << l) != 0 {
                Some((th[l], hu[l], hv[l]))
            } else {
                let lane = |x: F| x.to_array()[l];
                let sheared = [ax, ay, bx, by, cx, cy].map(lane);
                sheared_test(sheared, [a[kz], b[kz], c[kz]], lane(sz), tm[l])
            };
            if let Some((t, u, v)) = found {
                tm[l] = t;
                best[l] = Some(Hit { t, prim: i, u, v });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{camera, soup, CAMERAS};
    use super::*;
    use cgnodes_api::rng::Pcg32;
    use wide::f32x8;

    /// Every lane of `intersect8` is `intersect` of its ray, bit for bit (distance,
    /// triangle, barycentrics): eight rays per pixel (its corner and seven jittered) over
    /// the soups and cameras of `grid_hits_are_the_bvh_hits`.
    #[test]
    fn eight_rays_are_the_single_ones() {
        let mut rng = Pcg32::new(3, 5);
        let (mut together, mut apart, mut hits) = (0, 0, 0);
        for (eye, target, w, h, fov) in CAMERAS {
            let cam = camera(eye, target, w, h, fov);
            // The first soup whose grid fits the budget (wide views of a random soup
            // often put too many triangles in front of the eye).
            let (tris, grid) = (0..64)
                .find_map(|seed| {
                    let tris = soup(&mut Pcg32::new(seed, 11), cam.eye, fov > 100.0);
                    CameraGrid::build(&tris, &cam).map(|g| (tris, g))
                })
                .expect("a soup that fits the budget");
            for y in 0..h {
                for x in 0..w {
                    let mut jitter = |i: usize| if i == 0 { 0.0 } else { rng.next_f32() };
                    let fx: [f32; 8] = std::array::from_fn(|i| x as f32 + jitter(i));
                    let fy: [f32; 8] = std::array::from_fn(|i| y as f32 + jitter(i));
                    let dirs = cam.ray_dirs(&fx, &fy);
                    let got = grid.intersect8::<f32x8>(&tris, (x, y), cam.eye, &dirs, cam.far);
                    let Some(got) = got else {
                        apart += 1;
                        continue;
                    };
                    together += 1;
                    for (i, got) in got.iter().enumerate() {
                        let dir = [dirs[0][i], dirs[1][i], dirs[2][i]];
                        let want = grid.intersect(&tris, (x, y), cam.eye, dir, cam.far);
                        assert_eq!(
                            want.map(Hit::bits),
                            got.map(Hit::bits),
                            "pixel {x},{y}, ray {i}"
                        );
                        hits += want.is_some() as usize;
                    }
                }
            }
        }
        assert!(hits > 20_000, "{hits} hits");
        assert!(
            together > 20 * apart,
            "{together} pixels together, {apart} apart"
        );
    }

    /// Rays through a triangle's corner: their edge functions are zero, so the
    /// double-precision fallback decides the hit, lane by lane as for one ray.
    #[test]
    fn corner_rays_take_the_fallback_as_one_ray_does() {
        let cam = camera([0.0; 3], [0.0, 0.0, -1.0], 3, 3, 60.0);
        let tris = [[[0.0, 0.0, -2.0], [1.0, 0.0, -2.0], [0.0, 1.0, -2.0]]];
        let grid = CameraGrid::build(&tris, &cam).expect("one triangle");
        let dirs = cam.ray_dirs(&[1.5; 8], &[1.5; 8]);
        assert_eq!([dirs[0][0], dirs[1][0], dirs[2][0]], [0.0, 0.0, -1.0]);
        let got = grid
            .intersect8::<f32x8>(&tris, (1, 1), cam.eye, &dirs, cam.far)
            .expect("one permutation");
        let want = grid.intersect(&tris, (1, 1), cam.eye, [0.0, 0.0, -1.0], cam.far);
        assert_eq!(want.map(|h| h.t), Some(2.0));
        assert!(got.iter().all(|g| g.map(Hit::bits) == want.map(Hit::bits)));
    }
}
