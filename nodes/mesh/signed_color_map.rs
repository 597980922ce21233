//! `signed_color_map`: Framework3D's `geom_func_color_map` (Func Color Map), which colours a
//! signed scalar per vertex (e.g. Gaussian curvature) red to green: values in [min, 0] and
//! in (0, max] are each normalised to half of [0, 1] and coloured by the node's two ramps.

use cgnodes_api::prelude::*;

/// The course node's colours for `values`: `t = (v - min) / (0 - min) / 2` for `v <= 0`,
/// `t = 1/2 + v / max / 2` above; colour `(2 (1/2 - t), 1 - 2 (1/2 - t), 0)` for
/// `t <= 1/2`, else `(2 (1 - t), 2 (t - 1/2), 0)` (both halves run red to green, as in the
/// course's code). Where the course divides by zero (`min = 0` or `max = 0`), `t = 1/2`.
pub fn signed_color_map(values: &[f64]) -> Vec<[f64; 3]> {
    let (min, max) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    values
        .iter()
        .map(|&v| {
            let t = if v <= 0.0 {
                if min < 0.0 {
                    (v - min) / (0.0 - min) * 0.5
                } else {
                    0.5
                }
            } else if max > 0.0 {
                0.5 + v / max * 0.5
            } else {
                0.5
            };
            if t <= 0.5 {
                [2.0 * (0.5 - t), 1.0 - 2.0 * (0.5 - t), 0.0]
            } else {
                [2.0 * (1.0 - t), 2.0 * (t - 0.5), 0.0]
            }
        })
        .collect()
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Colours a signed value per vertex red to green as Framework3D's Func Color Map (negative and positive halves normalised separately).");
    b.add_input::<Vec<f64>>("values")
        .doc("Values, e.g. gaussian_curvature's output.");
    b.add_output::<Vec<[f64; 3]>>("colors")
        .doc("One RGB colour per value (into set_vert_color).");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let v: Vec<f64> = ctx.input("values")?;
    if v.is_empty() {
        return Err(NodeError::invalid("values", "no values to colour"));
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(NodeError::invalid("values", "values must be finite"));
    }
    ctx.set_output("colors", signed_color_map(&v));
    Ok(())
}

/// Registers `signed_color_map`.
pub fn register(r: &mut Registry) {
    r.add("signed_color_map", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_hand_computed_course_values() {
        // min -2, max 4. v=-2: t=0 -> (1,0,0). v=-1: t=0.25 -> (0.5,0.5,0).
        // v=0: t=0.5 -> (0,1,0). v=2: t=0.75 -> (0.5,0.5,0). v=4: t=1 -> (0,1,0).
        let c = signed_color_map(&[-2.0, -1.0, 0.0, 2.0, 4.0]);
        let want = [
            [1.0, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.0, 1.0, 0.0],
        ];
        for (g, w) in c.iter().zip(want) {
            for k in 0..3 {
                assert!((g[k] - w[k]).abs() < 1e-12, "{g:?} against {w:?}");
            }
        }
        // All positive (min > 0): no division by zero, finite colours.
        assert!(signed_color_map(&[1.0, 3.0])
            .iter()
            .flatten()
            .all(|x| x.is_finite()));
    }
}
