//! Buffers kept from one render to the next: the triangle setups of the camera and of the
//! shadow maps, the flattened scene, the geometric normals, the shadow-bias factors and the shadow maps' depths.
//!
//! A 1920x1080 render of a 154k-triangle mesh with two 2048^2 shadow maps allocates about
//! 100 MB of such buffers, and 45 MB for the flattened scene (`GEOMETRY`); fresh ones are page-faulted and zeroed by the kernel at every
//! render (13% of the CPU time of repeated renders, `docs/rendering.md`). A frame sequence
//! or a benchmark renders again and again at one size, so `render` takes its buffers from
//! these pools and gives them back when done: a second render of the same size writes into
//! pages already mapped. The pools keep at most `KEEP` buffers each (the largest), so a
//! process holds about one render's worth after its last render; `release_scratch` frees
//! them. Contents are never read before being written (each taker clears or fills).

use super::geometry::SceneGeometry;
use super::rasterize::TriSetup;
use std::sync::Mutex;

/// Buffers kept per pool: two lights' maps and setups, plus the camera's setups.
const KEEP: usize = 4;

/// A pool of vectors of `T`, shared by every thread.
pub(super) struct Pool<T> {
    free: Mutex<Vec<Vec<T>>>,
}

impl<T> Pool<T> {
    const fn new() -> Self {
        Pool {
            free: Mutex::new(Vec::new()),
        }
    }

    /// An empty vector with room for `len` items: the smallest pooled one that is large
    /// enough, else a fresh allocation.
    pub(super) fn take(&self, len: usize) -> Vec<T> {
        let mut free = self.free.lock().unwrap_or_else(|e| e.into_inner());
        let best = free
            .iter()
            .enumerate()
            .filter(|(_, v)| v.capacity() >= len)
            .min_by_key(|(_, v)| v.capacity())
            .map(|(i, _)| i);
        match best {
            Some(i) => free.swap_remove(i),
            None => Vec::with_capacity(len),
        }
    }

    /// Gives a vector back (cleared); past `KEEP` buffers the smallest is dropped.
    pub(super) fn give(&self, mut v: Vec<T>) {
        if v.capacity() == 0 {
            return;
        }
        v.clear();
        let mut free = self.free.lock().unwrap_or_else(|e| e.into_inner());
        free.push(v);
        if free.len() > KEEP {
            if let Some(i) = (0..free.len()).min_by_key(|&i| free[i].capacity()) {
                free.swap_remove(i);
            }
        }
    }

    fn clear(&self) {
        self.free.lock().unwrap_or_else(|e| e.into_inner()).clear();
    }
}

/// Triangle setups (camera and shadow maps).
pub(super) static SETUPS: Pool<Option<TriSetup>> = Pool::new();
/// Geometric normals of the camera's triangles.
pub(super) static NORMALS: Pool<Option<[f64; 3]>> = Pool::new();
/// Shadow-map depths.
pub(super) static DEPTHS: Pool<f32> = Pool::new();
/// Per-triangle shadow-bias factors of directional lights.
pub(super) static FACTORS: Pool<f64> = Pool::new();

/// The flattened scene of the last render (its arrays, emptied).
static GEOMETRY: Mutex<Option<SceneGeometry>> = Mutex::new(None);

/// The last render's scene geometry, emptied, to be refilled (`geometry::scene_geometry_in`).
pub(super) fn take_geometry() -> SceneGeometry {
    let mut g = GEOMETRY.lock().unwrap_or_else(|e| e.into_inner());
    g.take().unwrap_or_default()
}

/// Keeps `g`'s arrays for the next render (emptied: no mesh or material stays alive).
pub(super) fn give_geometry(mut g: SceneGeometry) {
    g.clear();
    *GEOMETRY.lock().unwrap_or_else(|e| e.into_inner()) = Some(g);
}

/// Frees the buffers the rasterizer keeps between renders (see the module doc); the next
/// render allocates fresh ones.
pub fn release_scratch() {
    SETUPS.clear();
    NORMALS.clear();
    DEPTHS.clear();
    FACTORS.clear();
    *GEOMETRY.lock().unwrap_or_else(|e| e.into_inner()) = None;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pool_hands_back_the_smallest_large_enough_buffer() {
        let p: Pool<u32> = Pool::new();
        p.give(Vec::with_capacity(100));
        p.give(Vec::with_capacity(10));
        p.give(vec![7; 50]);
        let v = p.take(40);
        assert!(v.is_empty() && v.capacity() >= 50 && v.capacity() < 100);
        assert!(p.take(200).capacity() >= 200);
        for c in [1, 2, 3, 4, 5, 6] {
            p.give(Vec::with_capacity(c * 1000));
        }
        let free = p.free.lock().unwrap();
        assert_eq!(free.len(), KEEP);
        assert!(free.iter().all(|v| v.capacity() >= 3000));
    }
}
