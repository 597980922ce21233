//! Enlarging by seam insertion (Avidan & Shamir 2007, §3.4): to add k seams, find the k
//! seams that removal would take out first (on a copy) and duplicate all of them in the
//! original, each new pixel the average of the seam pixel and its right neighbour. Taking k
//! distinct seams avoids duplicating the one lowest seam k times (a stretch artefact). More
//! than half the width at once is done in several rounds, as §3.4 suggests.

use super::dp::find_seam;
use super::Grid;

/// Inserts `k` vertical seams into `g`; returns the `origin` of every duplicated pixel (to
/// draw the seams) and the energy of the seams found.
pub fn insert_seams(g: &mut Grid, mut k: usize) -> (Vec<u32>, f64) {
    let (mut marks, mut energy) = (Vec::new(), 0.0);
    while k > 0 {
        let step = k.min((g.w / 2).max(1));
        energy += insert_round(g, step, &mut marks);
        k -= step;
    }
    (marks, energy)
}

/// One round: `k` ≤ max(1, w / 2) seams.
fn insert_round(g: &mut Grid, k: usize, marks: &mut Vec<u32>) -> f64 {
    let (w, h) = (g.w, g.h);
    let mut copy = g.clone();
    copy.origin = (0..(w * h) as u32).collect(); // positions in g
    let mut dup = vec![false; w * h];
    let mut energy = 0.0;
    for _ in 0..k {
        if copy.w == 1 {
            // a one-pixel-wide image: its only column is the seam
            for y in 0..h {
                dup[copy.origin[y] as usize] = true;
            }
            continue;
        }
        let s = find_seam(&copy);
        for (y, &x) in s.columns.iter().enumerate() {
            dup[copy.origin[y * copy.w + x] as usize] = true;
        }
        energy += s.energy;
        copy.remove_seam(&s.columns);
    }
    let n = (w + k) * h;
    let (mut color, mut gray) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut origin, mut mask) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            color.push(g.color[i]);
            gray.push(g.gray[i]);
            origin.push(g.origin[i]);
            mask.push(g.mask[i]);
            if dup[i] {
                let j = if x + 1 < w { i + 1 } else { i };
                let (a, b) = (g.color[i], g.color[j]);
                color.push(std::array::from_fn(|c| 0.5 * (a[c] + b[c])));
                gray.push(0.5 * (g.gray[i] + g.gray[j]));
                origin.push(g.origin[i]);
                mask.push(g.mask[i]);
                marks.push(g.origin[i]);
            }
        }
    }
    (g.color, g.gray, g.origin, g.mask) = (color, gray, origin, mask);
    g.w = w + k;
    g.recompute_energy();
    energy
}
