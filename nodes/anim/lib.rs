//! Character animation: UsdSkel skeletons posed over time (`pose.rs`), linear blend skinning
//! (`lbs.rs`) and dual-quaternion skinning (`dqs.rs`), and the nodes over them (`skeleton_load`,
//! `skeleton_pose`, `skin`, and Framework3D's `animate_mesh`). The USDA reading is in
//! `nodes::mesh::usda::skel`; the data types in `cgnodes_api::types` (`Skeleton`, `SkinBinding`).

pub mod animate_mesh;
pub mod dqs;
pub mod lbs;
pub mod pose;
pub mod skeleton_load;
pub mod skeleton_pose;
pub mod skin;

use cgnodes_api::registry::Registry;

/// Registers this family's nodes, in the `anim` category.
pub fn register(r: &mut Registry) {
    r.with_category("anim", |r| {
        animate_mesh::register(r);
        skeleton_load::register(r);
        skeleton_pose::register(r);
        skin::register(r);
    });
}
