//! `particles_in_box` and `particles_around_box`: particle positions on a lattice inside a
//! box and in a shell around it, as points-only meshes (Framework3D's Sample Particles In a
//! box / around a box, which feed its SPH homework; cgnodes' `sph_fluid` fills its own box,
//! so these serve imported graphs and visualizations).
//!
//! In the box: `n` particles per axis at `min + i (max - min) / n`, `i = 0..n` (the
//! framework's `ParticleSystem::sample_particle_pos_in_a_box`: the lattice starts on `min`
//! and stops one step short of `max`). Around it: the same lattice step continued over the
//! box grown by `scale` times its size on every side, keeping the points outside the box
//! (the framework's `add_boundary_particles_around_box`, whose growth `s` the node's
//! `scale factor` sets; the 2024 sampler's own source is not in the public history we read).

use cgnodes_api::prelude::*;

/// The framework's point width (0.05): the `radius` attribute is half of it.
pub const POINT_RADIUS: f64 = 0.025;

/// Checks the box and counts shared by both samplers; returns the counts as integers.
fn check(min: [f64; 3], max: [f64; 3], n: [f64; 3]) -> Result<[usize; 3], NodeError> {
    if (0..3).any(|a| !(min[a].is_finite() && max[a].is_finite()) || max[a] < min[a]) {
        return Err(NodeError::invalid(
            "box_max",
            format!("the box {min:?}..{max:?} is not finite or has max < min"),
        ));
    }
    let mut out = [0usize; 3];
    for a in 0..3 {
        if !(n[a].is_finite() && n[a] >= 1.0 && n[a] <= 1e4) {
            return Err(NodeError::invalid(
                "num_particle_per_axis",
                format!("{} particles along axis {a}: must be 1 to 10000", n[a]),
            ));
        }
        out[a] = n[a] as usize;
    }
    if out.iter().product::<usize>() > 50_000_000 {
        return Err(NodeError::invalid(
            "num_particle_per_axis",
            format!("{out:?} is more than 50 million particles"),
        ));
    }
    Ok(out)
}

/// Lattice points `min + i step` for `i` in `0..n` on each axis, x slowest (the framework's order).
pub fn sample_in_box(min: [f64; 3], max: [f64; 3], n: [usize; 3]) -> Vec<[f64; 3]> {
    let step: [f64; 3] = std::array::from_fn(|a| (max[a] - min[a]) / n[a] as f64);
    let mut out = Vec::with_capacity(n.iter().product());
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                let idx = [i, j, k];
                out.push(std::array::from_fn(|a| min[a] + idx[a] as f64 * step[a]));
            }
        }
    }
    out
}

/// The lattice of step `(max - min) / n` from `min - scale (max - min)` up to
/// `max + scale (max - min)`, keeping points outside `[min, max]`.
pub fn sample_around_box(min: [f64; 3], max: [f64; 3], n: [usize; 3], scale: f64) -> Vec<[f64; 3]> {
    let step: [f64; 3] = std::array::from_fn(|a| (max[a] - min[a]) / n[a] as f64);
    // lattice indices relative to min: from -ceil(scale n) to n + ceil(scale n), clipped to
    // the grown box (a tolerance of 1e-9 steps keeps the lattice's own end points)
    let range = |a: usize| {
        let lo = (-(scale * n[a] as f64) - 1e-9).ceil() as i64;
        let hi = (n[a] as f64 * (1.0 + scale) + 1e-9).floor() as i64;
        lo..=hi
    };
    let mut out = Vec::new();
    for i in range(0) {
        for j in range(1) {
            for k in range(2) {
                let p: [f64; 3] = std::array::from_fn(|a| min[a] + [i, j, k][a] as f64 * step[a]);
                // zero-size axes: the box is a plane or a line there
                let inside = (0..3).all(|a| p[a] >= min[a] - 1e-12 && p[a] <= max[a] + 1e-12);
                if !inside {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// A points-only mesh with the framework's point radius.
fn points_mesh(points: Vec<[f64; 3]>) -> Result<Mesh, NodeError> {
    let n = points.len();
    let mut m = Mesh::new(points, Vec::new(), Vec::new())
        .map_err(|e| NodeError::invalid("num_particle_per_axis", e.to_string()))?;
    m.attributes.insert(
        "radius".into(),
        AttributeData::Float(Attribute {
            domain: Domain::Vertex,
            values: vec![POINT_RADIUS; n],
        }),
    );
    Ok(m)
}

fn declare_box(b: &mut NodeBuilder) {
    b.add_input::<[f64; 3]>("box_min")
        .default([0.0, 0.0, 0.0])
        .doc("Lower corner of the box.");
    b.add_input::<[f64; 3]>("box_max")
        .default([1.0, 1.0, 1.0])
        .doc("Upper corner of the box.");
    b.add_input::<[f64; 3]>("num_particle_per_axis")
        .default([10.0, 10.0, 10.0])
        .doc("Particles along x, y, z (whole numbers, 1 to 10000).");
}

fn declare_in(b: &mut NodeBuilder) {
    b.doc("Particles on a lattice filling a box (Framework3D's Sample Particles In a box).");
    declare_box(b);
    b.add_output::<Mesh>("particles")
        .doc("A points-only mesh with a radius attribute.");
}

fn execute_in(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let (min, max): ([f64; 3], [f64; 3]) = (ctx.input("box_min")?, ctx.input("box_max")?);
    let n = check(min, max, ctx.input("num_particle_per_axis")?)?;
    ctx.set_output("particles", points_mesh(sample_in_box(min, max, n))?);
    Ok(())
}

fn declare_around(b: &mut NodeBuilder) {
    b.doc(
        "Boundary particles in a shell around a box (Framework3D's Sample Particles around a box).",
    );
    declare_box(b);
    b.add_input::<f64>("scale_factor")
        .default(0.2)
        .range(0.0, 1.0)
        .doc("How far the shell reaches, as a fraction of the box's size on each side.");
    b.add_output::<Mesh>("particles")
        .doc("A points-only mesh with a radius attribute.");
}

fn execute_around(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let (min, max): ([f64; 3], [f64; 3]) = (ctx.input("box_min")?, ctx.input("box_max")?);
    let n = check(min, max, ctx.input("num_particle_per_axis")?)?;
    let s: f64 = ctx.input("scale_factor")?;
    ctx.set_output("particles", points_mesh(sample_around_box(min, max, n, s))?);
    Ok(())
}

/// Registers `particles_in_box` and `particles_around_box`.
pub fn register(r: &mut Registry) {
    r.add("particles_in_box", declare_in, execute_in);
    r.add("particles_around_box", declare_around, execute_around);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_lattice_starts_on_min_and_stops_a_step_short_of_max() {
        let p = sample_in_box([0.0, 1.0, 2.0], [1.0, 2.0, 4.0], [2, 4, 2]);
        assert_eq!(p.len(), 16);
        assert_eq!(p[0], [0.0, 1.0, 2.0]);
        // x slowest, z fastest
        assert_eq!(p[1], [0.0, 1.0, 3.0]);
        assert_eq!(p[15], [0.5, 1.75, 3.0]);
    }

    #[test]
    fn shell_surrounds_the_box_and_keeps_out_of_it() {
        // unit cube, 4 per axis (step 0.25), grown by 0.5 on each side: indices -2..=6
        let p = sample_around_box([0.0; 3], [1.0; 3], [4, 4, 4], 0.5);
        // 9^3 lattice points in the grown box, minus the 5^3 inside the closed box
        assert_eq!(p.len(), 9 * 9 * 9 - 5 * 5 * 5);
        for q in &p {
            assert!(
                q.iter().any(|&c| !(0.0..=1.0).contains(&c)),
                "{q:?} is inside"
            );
            assert!(q.iter().all(|&c| (-0.5 - 1e-12..=1.5 + 1e-12).contains(&c)));
        }
        // scale 0: nothing outside the box
        assert!(sample_around_box([0.0; 3], [1.0; 3], [4, 4, 4], 0.0).is_empty());
    }

    #[test]
    fn bad_boxes_and_counts_name_their_socket() {
        let e = check([0.0; 3], [-1.0, 1.0, 1.0], [2.0; 3]).unwrap_err();
        assert!(e.to_string().contains("box_max"), "{e}");
        let e = check([0.0; 3], [1.0; 3], [0.0, 2.0, 2.0]).unwrap_err();
        assert!(e.to_string().contains("num_particle_per_axis"), "{e}");
        let e = check([0.0; 3], [1.0; 3], [f64::NAN, 2.0, 2.0]).unwrap_err();
        assert!(e.to_string().contains("num_particle_per_axis"), "{e}");
    }
}
