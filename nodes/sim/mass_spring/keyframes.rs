//! Keyframed positions for the `mass_spring` node's moving sphere collider: the
//! `"frame:x,y,z; frame:x,y,z"` parameter parsed into sorted keys and interpolated linearly
//! at fractional frames (sub-steps fall between frames).

use cgnodes_api::types::vec3::{axpy, sub};

/// Sphere centre at fractional frame `f` from keyframes `"frame:x,y,z; frame:x,y,z"`
/// (linear between keys, held outside them); `None` when there are no keys.
pub fn keyframed_center(keys: &[(f64, [f64; 3])], f: f64) -> Option<[f64; 3]> {
    let first = keys.first()?;
    if f <= first.0 {
        return Some(first.1);
    }
    for w in keys.windows(2) {
        let ((f0, c0), (f1, c1)) = (w[0], w[1]);
        if f <= f1 {
            let s = if f1 > f0 { (f - f0) / (f1 - f0) } else { 1.0 };
            return Some(axpy(c0, s, sub(c1, c0)));
        }
    }
    keys.last().map(|k| k.1)
}

/// Parses `"frame:x,y,z; frame:x,y,z"` keyframes, sorted by frame.
pub fn parse_keyframes(s: &str) -> Result<Vec<(f64, [f64; 3])>, String> {
    let mut out = Vec::new();
    for part in s.split(';').map(str::trim).filter(|p| !p.is_empty()) {
        let (f, c) = part
            .split_once(':')
            .ok_or_else(|| format!("keyframe '{part}' is not 'frame:x,y,z'"))?;
        let f: f64 = f
            .trim()
            .parse()
            .map_err(|_| format!("keyframe '{part}': bad frame"))?;
        let c: Vec<f64> = c
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("keyframe '{part}': bad coordinates"))?;
        if c.len() != 3 || !f.is_finite() || c.iter().any(|x| !x.is_finite()) {
            return Err(format!(
                "keyframe '{part}' needs a frame and 3 finite numbers"
            ));
        }
        out.push((f, [c[0], c[1], c[2]]));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyframes_interpolate_linearly() {
        let k = parse_keyframes("10: 0,0,1; 0:0,0,-1").unwrap();
        assert_eq!(keyframed_center(&k, -3.0), Some([0.0, 0.0, -1.0]));
        assert_eq!(keyframed_center(&k, 5.0), Some([0.0, 0.0, 0.0]));
        assert_eq!(keyframed_center(&k, 20.0), Some([0.0, 0.0, 1.0]));
        assert_eq!(keyframed_center(&[], 1.0), None);
        assert!(parse_keyframes("1:0,0").is_err());
        assert!(parse_keyframes("x:0,0,0").is_err());
    }
}
