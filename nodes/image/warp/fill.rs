//! Filling forward mapping's holes, and the holes mask image.

use super::Fill;
use cgnodes_api::types::Image;
use std::collections::VecDeque;

/// The mask image of `holes` (row-major, `w` x `h`): opaque white at a hole, opaque black
/// elsewhere. An empty `holes` means no hole.
pub fn holes_image(w: u32, h: u32, holes: &[bool]) -> Image {
    let mut im = Image::new(w, h, [0.0, 0.0, 0.0, 1.0]);
    for (p, &hole) in im.pixels.iter_mut().zip(holes) {
        if hole {
            *p = [1.0; 4];
        }
    }
    im
}

/// Gives the pixels of `img` marked in `holes` a colour from the others by `fill`; returns
/// how many holes got one (none when no pixel was mapped).
pub fn fill_holes(img: &mut Image, holes: &[bool], fill: Fill) -> usize {
    let count = holes.iter().filter(|&&h| h).count();
    if count == 0 || count == holes.len() {
        return 0;
    }
    match fill {
        Fill::None => 0,
        Fill::Nearest => fill_nearest(img, holes),
        Fill::PushPull => {
            push_pull(img, holes);
            count
        }
    }
}

/// Breadth-first growth from the mapped pixels over 8-neighbours: each hole takes the colour
/// of the mapped pixel it was reached from (nearest in the chessboard distance, ties broken
/// by scan order).
fn fill_nearest(img: &mut Image, holes: &[bool]) -> usize {
    let (w, h) = (img.width as i64, img.height as i64);
    let mut done: Vec<bool> = holes.iter().map(|&b| !b).collect();
    let mut queue: VecDeque<usize> = (0..holes.len()).filter(|&k| done[k]).collect();
    let mut filled = 0;
    while let Some(k) = queue.pop_front() {
        let (x, y) = ((k as i64) % w, (k as i64) / w);
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w || ny >= h {
                    continue;
                }
                let n = (ny * w + nx) as usize;
                if !done[n] {
                    done[n] = true;
                    img.pixels[n] = img.pixels[k];
                    filled += 1;
                    queue.push_back(n);
                }
            }
        }
    }
    filled
}

/// Push-pull hole filling (Gortler et al. 1996, "The Lumigraph", §3.4): push builds a pyramid
/// whose pixels are weight-averaged 2x2 children with weight min(1, sum of child weights);
/// pull replaces each level's colour c of weight w by w c + (1 - w) times the next coarser
/// level sampled bilinearly at the pixel's centre. Holes get the pulled colour, mapped pixels
/// keep theirs.
fn push_pull(img: &mut Image, holes: &[bool]) {
    struct Level {
        im: Image,
        w: Vec<f32>,
    }
    let mut levels = vec![Level {
        im: img.clone(),
        w: holes.iter().map(|&h| if h { 0.0 } else { 1.0 }).collect(),
    }];
    while {
        let l = &levels[levels.len() - 1].im;
        l.width > 1 || l.height > 1
    } {
        let fine = &levels[levels.len() - 1];
        let (fw, fh) = (fine.im.width, fine.im.height);
        let (cw, ch) = (fw.div_ceil(2), fh.div_ceil(2));
        let mut im = Image::new(cw, ch, [0.0; 4]);
        let mut wts = vec![0.0f32; (cw * ch) as usize];
        for y in 0..ch {
            for x in 0..cw {
                let (mut s, mut sw) = ([0.0f32; 4], 0.0f32);
                for (cx, cy) in [
                    (2 * x, 2 * y),
                    (2 * x + 1, 2 * y),
                    (2 * x, 2 * y + 1),
                    (2 * x + 1, 2 * y + 1),
                ] {
                    if cx < fw && cy < fh {
                        let k = (cy * fw + cx) as usize;
                        let wk = fine.w[k];
                        for (sc, pc) in s.iter_mut().zip(fine.im.pixels[k]) {
                            *sc += wk * pc;
                        }
                        sw += wk;
                    }
                }
                let k = (y * cw + x) as usize;
                if sw > 0.0 {
                    im.pixels[k] = s.map(|v| v / sw);
                }
                wts[k] = sw.min(1.0);
            }
        }
        levels.push(Level { im, w: wts });
    }
    for l in (0..levels.len() - 1).rev() {
        let (lo, hi) = levels.split_at_mut(l + 1);
        let (fine, coarse) = (&mut lo[l], &hi[0]);
        let fw = fine.im.width;
        for (k, p) in fine.im.pixels.iter_mut().enumerate() {
            let wk = fine.w[k];
            if wk < 1.0 {
                let (x, y) = ((k as u32 % fw) as f64, (k as u32 / fw) as f64);
                let up = coarse.im.sample_bilinear((x + 0.5) / 2.0, (y + 0.5) / 2.0);
                for c in 0..4 {
                    p[c] = wk * p[c] + (1.0 - wk) * up[c];
                }
                fine.w[k] = 1.0;
            }
        }
    }
    for (k, &h) in holes.iter().enumerate() {
        if h {
            img.pixels[k] = levels[0].im.pixels[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_holes() -> (Image, Vec<bool>) {
        // 5x4, mapped pixels are a left column of red and a right column of blue.
        let mut im = Image::new(5, 4, [0.0; 4]);
        let mut holes = vec![true; 20];
        for y in 0..4u32 {
            im.set(0, y, [1.0, 0.0, 0.0, 1.0]);
            im.set(4, y, [0.0, 0.0, 1.0, 1.0]);
            holes[(y * 5) as usize] = false;
            holes[(y * 5 + 4) as usize] = false;
        }
        (im, holes)
    }

    #[test]
    fn nearest_takes_the_closest_column_and_push_pull_blends_inside_the_range() {
        let (mut im, holes) = with_holes();
        assert_eq!(fill_holes(&mut im.clone(), &holes, Fill::None), 0);
        assert_eq!(fill_holes(&mut im, &holes, Fill::Nearest), 12);
        assert_eq!(im.get(1, 2), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(im.get(3, 0), [0.0, 0.0, 1.0, 1.0]);
        let (mut im, holes) = with_holes();
        assert_eq!(fill_holes(&mut im, &holes, Fill::PushPull), 12);
        for p in &im.pixels {
            // Every hole is an average of red and blue: opaque, red + blue = 1.
            assert!(
                (p[3] - 1.0).abs() < 1e-6 && (p[0] + p[2] - 1.0).abs() < 1e-6,
                "{p:?}"
            );
        }
        // Mapped pixels kept; nearer red is redder.
        assert_eq!(im.get(0, 1), [1.0, 0.0, 0.0, 1.0]);
        assert!(im.get(1, 1)[0] > im.get(3, 1)[0]);
        let m = holes_image(5, 4, &holes);
        assert_eq!(m.get(2, 2), [1.0; 4]);
        assert_eq!(m.get(0, 2), [0.0, 0.0, 0.0, 1.0]);
    }
}
