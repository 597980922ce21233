//! A complete `cgnodes` binary with one node of its own, `twist`, defined outside cgnodes.
//!
//! This is all a crate needs to add nodes: write `declare` and `execute` against the public
//! node API (the same one every built-in node uses), register them next to the built-in
//! nodes, and hand the registry to `cgnodes::cli::main_with`. Build and try it:
//!
//! ```sh
//! cargo run --example custom_node -- describe twist
//! cargo run --example custom_node -- run my_graph.json --out out
//! ```

use cgnodes::prelude::*;

/// Twists points about the y axis: a point at height `y` turns by `rate_deg * y` degrees
/// (Barr, "Global and local deformations of solid primitives", SIGGRAPH 1984, twist along
/// an axis).
pub fn twist(positions: &[[f64; 3]], rate_deg: f64) -> Vec<[f64; 3]> {
    positions
        .iter()
        .map(|&[x, y, z]| {
            let (s, c) = (rate_deg.to_radians() * y).sin_cos();
            [c * x + s * z, y, -s * x + c * z]
        })
        .collect()
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Twists a mesh about the y axis, by an angle proportional to height.")
        .category("mesh")
        .source("example crate custom_node");
    b.add_input::<Mesh>("mesh");
    b.add_input::<f64>("rate")
        .default(90.0)
        .range(-3600.0, 3600.0)
        .doc("Degrees of turn per unit of height.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let rate: f64 = ctx.input("rate")?;
    let mut out = (*mesh).clone();
    out.positions = twist(&mesh.positions, rate);
    ctx.set_output("mesh", out);
    Ok(())
}

fn main() {
    let mut registry = cgnodes::nodes::builtin_registry();
    registry.add("twist", declare, execute);
    std::process::exit(cgnodes::cli::main_with(registry));
}
