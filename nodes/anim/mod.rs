//! Character animation: UsdSkel skeletons posed over time (`pose.rs`), linear blend skinning
//! (`lbs.rs`) and dual-quaternion skinning (`dqs.rs`), and the nodes over them (`skeleton_load`,
//! `skeleton_pose`, `skin`, and Framework3D's `animate_mesh`). The USDA reading is in
//! `nodes::mesh::usda::skel`; the data types in `crate::types` (`Skeleton`, `SkinBinding`).

crate::node_domain! {
    category: "anim",
    nodes: [animate_mesh, skeleton_load, skeleton_pose, skin],
    modules: [dqs, lbs, pose],
}
