//! `animate_mesh`: Framework3D's "Animate Mesh" (`geom_animate_mesh`, course assignment 10):
//! the mesh read with its skeleton, skinned by linear blend skinning at the time code the
//! reader was evaluated at. Framework3D's `Animator` takes the skeleton's local transforms at
//! the stage's current time, builds world transforms down the joint tree and updates the
//! vertices; here the time is an input (link the frame's time to it) and the work is `skin`'s.

use super::skin::{skin_mesh, SkinMethod};
use cgnodes_api::prelude::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Framework3D's Animate Mesh: a UsdSkel-bound mesh skinned (LBS) at a USD time code.");
    b.add_input::<Mesh>("mesh")
        .doc("A mesh with a skeleton binding (mesh_load of a UsdSkel .usda).");
    b.add_input::<f64>("time")
        .default(0.0)
        .doc("USD time code; outside the animation's samples the ends are held.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let time: f64 = ctx.input("time")?;
    let s = skin_mesh(&mesh, None, time, SkinMethod::Lbs)?;
    for w in s.warnings {
        ctx.log(w);
    }
    ctx.set_output("mesh", s.mesh);
    Ok(())
}

/// Registers `animate_mesh`.
pub fn register(r: &mut Registry) {
    r.add("animate_mesh", declare, execute);
}
