//! Experiment: packets of 16 rays through the 4-wide tree, one SIMD lane per ray.

use super::pair::Segment;
use super::traverse::RayPre;
use super::wide::LEAF;
use super::{Bvh, Hit};

/// Rays per packet.
pub const P: usize = 16;
type L = [f32; P];

#[inline(always)]
fn sel(m: &[bool; P], a: &L, b: &L) -> L {
    let mut r = [0.0; P];
    for j in 0..P {
        r[j] = if m[j] { a[j] } else { b[j] };
    }
    r
}

impl Bvh {
    /// Closest hits (or, with `ANY`, whether blocked) of up to 16 rays traced as one packet.
    pub fn trace_packet<const ANY: bool>(&self, rays: &[Segment], out: &mut [Option<Hit>]) {
        let n = rays.len().min(P);
        let mut org = [[0.0f32; P]; 3];
        let mut inv = [[0.0f32; P]; 3];
        let mut tmax = [f32::NEG_INFINITY; P];
        let mut s = [[0.0f32; P]; 3];
        let mut kxm = [[false; P]; 3];
        let mut kym = [[false; P]; 3];
        let mut kzm = [[false; P]; 3];
        let mut pre = Vec::with_capacity(n);
        for j in 0..n {
            let r = RayPre::new(rays[j].0, rays[j].1);
            for k in 0..3 {
                org[k][j] = r.org[k];
                inv[k][j] = r.inv[k];
                kxm[k][j] = r.kx == k;
                kym[k][j] = r.ky == k;
                kzm[k][j] = r.kz == k;
            }
            s[0][j] = r.sx;
            s[1][j] = r.sy;
            s[2][j] = r.sz;
            tmax[j] = rays[j].2;
            pre.push(r);
        }
        let mut best: [Option<Hit>; P] = [None; P];
        let mut stack: Vec<(u32, u32)> = Vec::with_capacity(64);
        let live0: u32 = if n == 32 { u32::MAX } else { (1u32 << n) - 1 };
        stack.push((0, live0));
        while let Some((c, mut mask)) = stack.pop() {
            // Drop lanes already finished (any-hit).
            if ANY {
                for j in 0..n {
                    if tmax[j] < 0.0 {
                        mask &= !(1 << j);
                    }
                }
                if mask == 0 {
                    continue;
                }
            }
            if c & LEAF != 0 {
                let q = &self.wide_tris[((c & !LEAF) >> 3) as usize];
                for l in 0..(c & 7) as usize {
                    // Corner minus origin, per axis, per lane; then the lane's permutation.
                    let corner = |cn: usize| {
                        let mut a = [[0.0f32; P]; 3];
                        for k in 0..3 {
                            let v = q.v[cn][k][l];
                            for j in 0..P {
                                a[k][j] = v - org[k][j];
                            }
                        }
                        let pick = |m: &[[bool; P]; 3]| sel(&m[0], &a[0], &sel(&m[1], &a[1], &a[2]));
                        let (x, y, z) = (pick(&kxm), pick(&kym), pick(&kzm));
                        let mut px = [0.0f32; P];
                        let mut py = [0.0f32; P];
                        let mut pz = [0.0f32; P];
                        for j in 0..P {
                            px[j] = x[j] - s[0][j] * z[j];
                            py[j] = y[j] - s[1][j] * z[j];
                            pz[j] = s[2][j] * z[j];
                        }
                        (px, py, pz)
                    };
                    let (ax, ay, az) = corner(0);
                    let (bx, by, bz) = corner(1);
                    let (cx, cy, cz) = corner(2);
                    let mut cand = 0u32;
                    let mut edge = 0u32;
                    let mut tt = [0.0f32; P];
                    let mut dd = [0.0f32; P];
                    let mut uu = [0.0f32; P];
                    let mut vv = [0.0f32; P];
                    let mut ww = [0.0f32; P];
                    for j in 0..P {
                        let u = cx[j] * by[j] - cy[j] * bx[j];
                        let v = ax[j] * cy[j] - ay[j] * cx[j];
                        let w = bx[j] * ay[j] - by[j] * ax[j];
                        let e = u == 0.0 || v == 0.0 || w == 0.0;
                        let out = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
                        let det = u + v + w;
                        let t = u * az[j] + v * bz[j] + w * cz[j];
                        let td = tmax[j] * det;
                        let ok = if det > 0.0 {
                            t > 0.0 && t < td
                        } else {
                            t < 0.0 && t > td
                        };
                        cand |= ((!e && !out && det != 0.0 && ok) as u32) << j;
                        edge |= (e as u32) << j;
                        tt[j] = t;
                        dd[j] = det;
                        uu[j] = u;
                        vv[j] = v;
                        ww[j] = w;
                    }
                    let _ = &uu;
                    let mut m = (cand | edge) & mask;
                    while m != 0 {
                        let j = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let found = if edge & (1 << j) != 0 {
                            super::traverse::intersect_triangle(&pre[j], &q.get(l), tmax[j])
                        } else {
                            let rcp = 1.0 / dd[j];
                            Some((tt[j] * rcp, vv[j] * rcp, ww[j] * rcp))
                        };
                        if let Some((t, u, v)) = found {
                            tmax[j] = if ANY { f32::NEG_INFINITY } else { t };
                            best[j] = Some(Hit {
                                t,
                                prim: q.prim[l],
                                u,
                                v,
                            });
                        }
                    }
                }
                continue;
            }
            let nd = &self.wide[c as usize];
            let mut hits = [0u32; 4];
            let mut tsum = [0.0f32; 4];
            for l in 0..4 {
                let mut t0 = [0.0f32; P];
                let mut t1 = tmax;
                for k in 0..3 {
                    let (lo, hi) = (nd.min[k][l], nd.max[k][l]);
                    for j in 0..P {
                        let (near, far) = if inv[k][j] < 0.0 { (hi, lo) } else { (lo, hi) };
                        let a = (near - org[k][j]) * inv[k][j];
                        let b = (far - org[k][j]) * inv[k][j];
                        t0[j] = if a > t0[j] { a } else { t0[j] };
                        t1[j] = if b < t1[j] { b } else { t1[j] };
                    }
                }
                let mut h = 0u32;
                let mut ts = 0.0f32;
                for j in 0..P {
                    let e = t0[j] <= t1[j] * 1.000_000_4;
                    h |= (e as u32) << j;
                    ts += if e { t0[j] } else { 0.0 };
                }
                hits[l] = h & mask;
                tsum[l] = ts;
            }
            let mut order = [0usize, 1, 2, 3];
            if !ANY {
                let mean = |l: usize| tsum[l] / hits[l].count_ones().max(1) as f32;
                order.sort_by(|&a, &b| mean(b).total_cmp(&mean(a)));
            }
            for &l in &order {
                if hits[l] != 0 {
                    stack.push((nd.child[l], hits[l]));
                }
            }
        }
        for j in 0..n {
            out[j] = best[j];
        }
    }
}
