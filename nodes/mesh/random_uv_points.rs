//! `random_uv_points`: Framework3D's `geom_random_uv_points`, `count` points uniformly at
//! random in the unit square `[0, 1)^2` at z = 0, each with a `width` (a points-only mesh).
//! The framework draws them with `std::default_random_engine(seed)`; cgnodes uses its own
//! counter-based generator (SplitMix64), so the points differ from the framework's but follow
//! the same distribution.

use cgnodes_api::prelude::*;
use cgnodes_api::rng::splitmix64;

/// `count` points uniform in `[0, 1)^2 x {0}`, reproducible from `seed`.
pub fn random_uv_points(count: usize, seed: i64) -> Vec<[f64; 3]> {
    let base = splitmix64(seed as u64);
    // 53 random bits as a float in [0, 1).
    let u = |k: u64| (splitmix64(base ^ splitmix64(k)) >> 11) as f64 / (1u64 << 53) as f64;
    (0..count as u64)
        .map(|i| [u(2 * i), u(2 * i + 1), 0.0])
        .collect()
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Random points in the unit UV square (Framework3D's Random UV Points), a points-only mesh with a per-vertex width.");
    b.add_input::<i64>("count")
        .default(10i64)
        .range(1.0, 1e7)
        .doc("Number of points.");
    b.add_input::<i64>("seed").default(0i64).doc("Random seed.");
    b.add_input::<f64>("width")
        .default(0.1)
        .range(0.0, 1e6)
        .doc("Point width, stored as the vertex attribute `width`.");
    b.add_output::<Mesh>("points");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    // count and width lie in their declared ranges (checked by the runtime).
    let count: i64 = ctx.input("count")?;
    let width: f64 = ctx.input("width")?;
    let p = random_uv_points(count as usize, ctx.input("seed")?);
    let n = p.len();
    let mut m = Mesh::new(p, Vec::new(), Vec::new())
        .map_err(|e| NodeError::invalid("count", e.to_string()))?;
    m.attributes.insert(
        "width".into(),
        AttributeData::Float(Attribute {
            domain: Domain::Vertex,
            values: vec![width; n],
        }),
    );
    ctx.set_output("points", m);
    Ok(())
}

/// Registers `random_uv_points`.
pub fn register(r: &mut Registry) {
    r.add("random_uv_points", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_in_the_unit_square_and_seeded() {
        let p = random_uv_points(10_000, 3);
        assert_eq!(p.len(), 10_000);
        assert!(p
            .iter()
            .all(|q| (0.0..1.0).contains(&q[0]) && (0.0..1.0).contains(&q[1]) && q[2] == 0.0));
        // Mean of U(0,1) is 1/2 with standard error 0.289 / 100; 0.015 is five of those.
        for k in 0..2 {
            let mean = p.iter().map(|q| q[k]).sum::<f64>() / p.len() as f64;
            assert!((mean - 0.5).abs() < 0.015, "mean {mean}");
        }
        // A quarter of the points in the lower-left quadrant (standard error 0.0043).
        let q = p.iter().filter(|q| q[0] < 0.5 && q[1] < 0.5).count() as f64 / 1e4;
        assert!((q - 0.25).abs() < 0.02, "{q}");
        assert_eq!(random_uv_points(5, 3), random_uv_points(5, 3));
        assert_ne!(random_uv_points(5, 3), random_uv_points(5, 4));
    }
}
