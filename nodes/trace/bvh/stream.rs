//! Ray streams: many rays traced through the 4-wide tree together, node by node, instead
//! of one ray walking the tree at a time (Tsakok 2009, "Faster incoherent rays:
//! Multi-BVH ray stream tracing"; Barringer and Akenine-Möller 2014, "Dynamic ray stream
//! traversal"). A node is loaded once for every ray of the stream that reaches it, and the
//! rays' box tests have no data dependence on one another, so the out-of-order core
//! overlaps them; the price is that the children are visited in one order for the whole
//! stream (nearest mean entry distance first), not in each ray's own order.
//!
//! Each ray's answer is the one of `intersect` or `occluded`: the closest hit has the same
//! `t` (every triangle's test is computed the same way, and a ray accepts a hit only when
//! it is closer than its current one), but when two triangles are hit at exactly the same
//! `t` the one found first is kept, which may be the other one.

use super::lanes::{tri4, Dyn};
use super::pair::Segment;
use super::traverse::RayPre;
use super::wide::LEAF;
use super::{Bvh, Hit};
use std::cell::RefCell;

/// Rays per lane group of the box test.
const W: usize = 8;
pub static NODE_TESTS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
pub static LEAF_TESTS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Working memory of a stream query, kept per thread and reused.
#[derive(Default)]
struct Scratch {
    pre: Vec<RayPre>,
    /// Origins and inverse directions, axis by axis.
    org: [Vec<f32>; 3],
    inv: [Vec<f32>; 3],
    tmax: Vec<f32>,
    /// Ray index lists of the pending nodes, one after the other.
    ids: Vec<u32>,
    /// Per ray of the node being split: its entered children.
    masks: Vec<u8>,
    /// Pending (child code, start in `ids`, length).
    stack: Vec<(u32, u32, u32)>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl Bvh {
    /// The closest hit of each ray (`out[i]` for `rays[i]`), traced as one stream: the same
    /// answers as `intersect` for each (up to which of two triangles hit at exactly the
    /// same distance is reported).
    pub fn intersect_stream(&self, rays: &[Segment], out: &mut [Option<Hit>]) {
        debug_assert_eq!(rays.len(), out.len());
        out.fill(None);
        if self.wide.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.intersect(r.0, r.1, r.2);
            }
            return;
        }
        with_scratch(|s| self.stream::<false>(rays, out, s));
    }

    /// Whether anything blocks each ray (`out[i]` for `rays[i]`), traced as one stream: the
    /// same answers as `occluded` for each.
    pub fn occluded_stream(&self, rays: &[Segment], out: &mut [bool]) {
        debug_assert_eq!(rays.len(), out.len());
        if self.wide.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.occluded(r.0, r.1, r.2);
            }
            return;
        }
        with_scratch(|s| {
            let mut hits = vec![None; rays.len()];
            self.stream::<true>(rays, &mut hits, s);
            for (o, h) in out.iter_mut().zip(&hits) {
                *o = h.is_some();
            }
        });
    }

    fn stream<const ANY: bool>(&self, rays: &[Segment], best: &mut [Option<Hit>], s: &mut Scratch) {
        let n = rays.len();
        s.pre.clear();
        s.pre.extend(rays.iter().map(|r| RayPre::new(r.0, r.1)));
        for k in 0..3 {
            s.org[k].clear();
            s.org[k].extend(s.pre.iter().map(|r| r.org[k]));
            s.inv[k].clear();
            s.inv[k].extend(s.pre.iter().map(|r| r.inv[k]));
        }
        s.tmax.clear();
        s.tmax.extend(rays.iter().map(|r| r.2));
        s.ids.clear();
        s.ids.extend(0..n as u32);
        s.stack.clear();
        s.stack.push((0, 0, n as u32));
        while let Some((c, start, len)) = s.stack.pop() {
            let (start, end) = (start as usize, (start + len) as usize);
            s.ids.truncate(end);
            if c & LEAF != 0 {
                let q = &self.wide_tris[((c & !LEAF) >> 3) as usize];
                let count = (c & 7) as usize;
                LEAF_TESTS.fetch_add(end - start, std::sync::atomic::Ordering::Relaxed);
                for &i in &s.ids[start..end] {
                    let i = i as usize;
                    let r = &s.pre[i];
                    let tmax = &mut s.tmax[i];
                    if ANY && *tmax < 0.0 {
                        continue;
                    }
                    let b = &mut best[i];
                    let found = tri4::<ANY, _>(r, Dyn(r.kx, r.ky, r.kz), q, count, tmax, |t, u, v, l| {
                        *b = Some(Hit {
                            t,
                            prim: q.prim[l],
                            u,
                            v,
                        })
                    });
                    if ANY && found {
                        // Done: no box is entered before a negative `tmax`.
                        *tmax = f32::NEG_INFINITY;
                    }
                }
                s.ids.truncate(start);
                continue;
            }
            let nd = &self.wide[c as usize];
            NODE_TESTS.fetch_add(end - start, std::sync::atomic::Ordering::Relaxed);
            // Pass 1: each ray's entered children, their counts and summed entry distances,
            // eight rays at a time on eight lanes (gathered into lanes from the rays'
            // arrays), one child box at a time.
            s.masks.clear();
            let mut cnt = [0u32; 4];
            let mut tsum = [0.0f32; 4];
            for chunk in s.ids[start..end].chunks(W) {
                let mut o = [[0.0f32; W]; 3];
                let mut iv = [[0.0f32; W]; 3];
                let mut tm = [f32::NEG_INFINITY; W];
                for (j, &i) in chunk.iter().enumerate() {
                    let i = i as usize;
                    for k in 0..3 {
                        o[k][j] = s.org[k][i];
                        iv[k][j] = s.inv[k][i];
                    }
                    tm[j] = s.tmax[i];
                }
                let mut m = [0u8; W];
                for l in 0..4 {
                    let mut t0 = [0.0f32; W];
                    let mut t1 = tm;
                    for k in 0..3 {
                        let (lo, hi) = (nd.min[k][l], nd.max[k][l]);
                        for j in 0..W {
                            let (near, far) = if iv[k][j] < 0.0 { (hi, lo) } else { (lo, hi) };
                            let a = (near - o[k][j]) * iv[k][j];
                            let b = (far - o[k][j]) * iv[k][j];
                            t0[j] = if a > t0[j] { a } else { t0[j] };
                            t1[j] = if b < t1[j] { b } else { t1[j] };
                        }
                    }
                    let mut hit = [0u8; W];
                    let mut te = [0.0f32; W];
                    for j in 0..W {
                        let h = t0[j] <= t1[j] * 1.000_000_4;
                        hit[j] = h as u8;
                        te[j] = if h { t0[j] } else { 0.0 };
                    }
                    for j in 0..W {
                        m[j] |= hit[j] << l;
                    }
                    cnt[l] += hit.iter().map(|&h| h as u32).sum::<u32>();
                    tsum[l] += te.iter().sum::<f32>();
                }
                s.masks.extend_from_slice(&m[..chunk.len()]);
            }
            // The order the children are visited in: nearest mean entry first (any order
            // for any-hit queries, which stop at their first hit).
            let mut order = [0usize, 1, 2, 3];
            if !ANY {
                let mean = |l: usize| tsum[l] / cnt[l].max(1) as f32;
                order.sort_by(|&a, &b| mean(a).total_cmp(&mean(b)));
            }
            // Pass 2: the lists, farthest child lowest so that the nearest is popped first.
            let base = s.ids.len();
            let mut off = [0usize; 4];
            let mut at = base;
            for &l in order.iter().rev() {
                off[l] = at;
                at += cnt[l] as usize;
            }
            s.ids.resize(at, 0);
            for (k, &m) in s.masks.iter().enumerate() {
                let i = s.ids[start + k];
                let mut m = m;
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    s.ids[off[l]] = i;
                    off[l] += 1;
                }
            }
            let mut at = base;
            for &l in order.iter().rev() {
                if cnt[l] > 0 {
                    s.stack.push((nd.child[l], at as u32, cnt[l]));
                }
                at += cnt[l] as usize;
            }
        }
    }
}

/// Runs `f` with this thread's scratch (a fresh one if it is in use).
fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => f(&mut s),
        Err(_) => f(&mut Scratch::default()),
    })
}
