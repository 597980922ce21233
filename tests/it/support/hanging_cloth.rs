//! The course's hanging cloth, shared by `tests/it/mass_spring.rs` and `tests/it/mass_spring_node.rs`.

use cgnodes::nodes::mesh::mesh_grid::grid_mesh;
use cgnodes::nodes::sim::mass_spring::{
    springs_from_mesh, Method, Model, Simulator, SolverOptions, SpringKinds,
};
use cgnodes::types::Mesh;

/// A 10x10-cell course-like grid hanging from its top corners (xy plane, gravity along -z).
pub fn hanging(method: Method, h: f64) -> (Simulator, Vec<usize>) {
    let mesh = grid_mesh(10, 10, [2.0, 2.0], "xy", [0.0; 3], true).unwrap();
    let fixed = cgnodes::nodes::mesh::vertex_select::select_vertices(
        &mesh,
        "top_corners",
        [0.0, 0.0, -9.8],
    )
    .unwrap();
    assert_eq!(fixed, vec![120, 110]);
    let mut f = vec![false; mesh.num_vertices()];
    for &i in &fixed {
        f[i] = true;
    }
    (course_cloth(&mesh, f, method, h), fixed)
}

/// The course's cloth on `mesh`: default springs with k = 1000, total mass 1, gravity along
/// -z, damping 0.995, the given fixed vertices.
pub fn course_cloth(mesh: &Mesh, fixed: Vec<bool>, method: Method, h: f64) -> Simulator {
    let n = mesh.num_vertices();
    let model = Model {
        springs: springs_from_mesh(mesh, 1000.0, SpringKinds::default()),
        mass: vec![1.0 / n as f64; n],
        fixed,
        gravity: [0.0, 0.0, -9.8],
        damping: 0.995,
    };
    Simulator::new(
        model,
        mesh.positions.clone(),
        None,
        method,
        h,
        SolverOptions::default(),
    )
    .unwrap()
}
