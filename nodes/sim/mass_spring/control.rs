//! Control points: cloth vertices that follow a moving body (Framework3D's
//! `geom_mass_spring_with_control_points`). Each paired cloth vertex is a fixed (Dirichlet)
//! vertex whose position is set to its body vertex before every step; the integrators then
//! treat it like any fixed vertex, so this works with all three of them.
//!
//! Pairing follows the course's `MassSpring::init_dirichlet_bc_vertices_control_pair`: every
//! fixed cloth vertex is paired with the nearest selected body vertex at the start (the first
//! of equally near ones), and snaps to it. Between two frames the body positions are
//! interpolated linearly across the sub-steps (the course steps once per frame, where
//! interpolation and no interpolation agree).

/// Why control pairs cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PairError {
    /// There are fixed cloth vertices but no selected body vertex.
    #[error("no body vertex is selected to pair the fixed cloth vertices with")]
    NoBodyVertex,
    /// The flat pair list has an odd length.
    #[error("{0} numbers; pairs need an even count (cloth, body, cloth, body, ...)")]
    OddCount(usize),
    /// A cloth vertex index is out of range.
    #[error("cloth vertex {vertex} is outside 0..{count}")]
    ClothVertex {
        /// The index given.
        vertex: i64,
        /// Number of cloth vertices.
        count: usize,
    },
    /// A body vertex index is out of range.
    #[error("body vertex {vertex} is outside 0..{count}")]
    BodyVertex {
        /// The index given.
        vertex: i64,
        /// Number of body vertices.
        count: usize,
    },
}

/// Pairs (cloth vertex, body vertex): each of `fixed` with the nearest of `selected` body
/// vertices. `Err` when there are fixed vertices but no selected body vertex.
pub fn pair_nearest(
    cloth: &[[f64; 3]],
    fixed: &[usize],
    body: &[[f64; 3]],
    selected: &[usize],
) -> Result<Vec<(usize, usize)>, PairError> {
    if fixed.is_empty() {
        return Ok(Vec::new());
    }
    if selected.is_empty() {
        return Err(PairError::NoBodyVertex);
    }
    let d2 = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>();
    Ok(fixed
        .iter()
        .map(|&i| {
            let mut best = (f64::INFINITY, selected[0]);
            for &j in selected {
                let d = d2(cloth[i], body[j]);
                if d < best.0 {
                    best = (d, j);
                }
            }
            (i, best.1)
        })
        .collect())
}

/// Explicit pairs from a flat list `cloth0, body0, cloth1, body1, ...`, checked against the
/// vertex counts.
pub fn pairs_from_list(
    list: &[i64],
    n_cloth: usize,
    n_body: usize,
) -> Result<Vec<(usize, usize)>, PairError> {
    if !list.len().is_multiple_of(2) {
        return Err(PairError::OddCount(list.len()));
    }
    list.chunks(2)
        .map(|p| {
            let (c, b) = (p[0], p[1]);
            if c < 0 || c as usize >= n_cloth {
                return Err(PairError::ClothVertex {
                    vertex: c,
                    count: n_cloth,
                });
            }
            if b < 0 || b as usize >= n_body {
                return Err(PairError::BodyVertex {
                    vertex: b,
                    count: n_body,
                });
            }
            Ok((c as usize, b as usize))
        })
        .collect()
}

/// Where each paired cloth vertex goes at fraction `s` (0 = `prev`, 1 = `cur`) of the way
/// between two body poses.
pub fn control_targets(
    pairs: &[(usize, usize)],
    prev: &[[f64; 3]],
    cur: &[[f64; 3]],
    s: f64,
) -> Vec<(usize, [f64; 3])> {
    pairs
        .iter()
        .map(|&(i, j)| {
            let (a, b) = (prev[j], cur[j]);
            if s >= 1.0 {
                return (i, b); // exactly on the body at the frame's end
            }
            (i, std::array::from_fn(|c| a[c] + s * (b[c] - a[c])))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_pairing_as_the_course_does() {
        // hw10's cloth row y = -0.5 and the arm's two top vertices (ControlPoints 1 1 0 ...).
        let cloth = [[-0.5, -0.5, 4.0], [0.0, -0.5, 4.0], [0.5, -0.5, 4.0]];
        let body = [[0.5, -0.5, 4.0], [-0.5, -0.5, 4.0], [0.5, 0.5, 4.0]];
        let p = pair_nearest(&cloth, &[0, 2], &body, &[0, 1]).unwrap();
        assert_eq!(p, vec![(0, 1), (2, 0)]);
        // Equally near: the first selected wins.
        let p = pair_nearest(&cloth, &[1], &body, &[0, 1]).unwrap();
        assert_eq!(p, vec![(1, 0)]);
        assert!(pair_nearest(&cloth, &[1], &body, &[]).is_err());
        assert!(pair_nearest(&cloth, &[], &body, &[]).unwrap().is_empty());
    }

    #[test]
    fn explicit_pairs_are_checked_and_targets_interpolate() {
        assert_eq!(
            pairs_from_list(&[2, 0, 0, 1], 3, 2).unwrap(),
            vec![(2, 0), (0, 1)]
        );
        assert!(pairs_from_list(&[2, 0, 0], 3, 2).is_err());
        assert!(pairs_from_list(&[3, 0], 3, 2)
            .unwrap_err()
            .to_string()
            .contains("cloth vertex 3"));
        assert!(pairs_from_list(&[0, -1], 3, 2)
            .unwrap_err()
            .to_string()
            .contains("body vertex -1"));
        let prev = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]];
        let cur = [[2.0, 0.0, -4.0], [1.0, 1.0, 1.0]];
        let t = control_targets(&[(5, 0), (6, 1)], &prev, &cur, 0.25);
        assert_eq!(t, vec![(5, [0.5, 0.0, -1.0]), (6, [1.0, 1.0, 1.0])]);
        let t = control_targets(&[(5, 0)], &prev, &cur, 1.0);
        assert_eq!(t, vec![(5, cur[0])]);
    }
}
