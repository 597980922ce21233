//! `points_to_mesh`: particles as a points-only mesh (vertices, no faces), so that mesh nodes
//! (`set_vert_color`, `mesh_transform`, `mesh_save`) take them. Scalar attributes become
//! per-vertex float attributes, vector attributes per-vertex vectors, and a `color` vector
//! attribute the mesh's display colours. An optional `radius` adds a per-vertex `radius`
//! attribute (USD's point widths are diameters, twice it).

use cgnodes_api::prelude::*;

/// A points-only mesh of `points`: positions, attributes as vertex attributes, `color` as the
/// display colour, and a constant `radius` attribute when `radius` is given. `Err` when a
/// position is not finite.
pub fn points_to_mesh(points: &Points, radius: Option<f64>) -> Result<Mesh, MeshError> {
    let n = points.positions.len();
    let mut m = Mesh::new(points.positions.clone(), Vec::new(), Vec::new())?;
    for (name, v) in &points.scalars {
        if v.len() == n {
            m.attributes.insert(
                name.clone(),
                AttributeData::Float(Attribute {
                    domain: Domain::Vertex,
                    values: v.clone(),
                }),
            );
        }
    }
    for (name, v) in &points.vectors {
        if v.len() != n {
            continue;
        }
        let a = Attribute {
            domain: Domain::Vertex,
            values: v.clone(),
        };
        if name == "color" {
            m.colors = Some(a);
        } else {
            m.attributes.insert(name.clone(), AttributeData::Vec3(a));
        }
    }
    if let Some(r) = radius {
        m.attributes.insert(
            "radius".into(),
            AttributeData::Float(Attribute {
                domain: Domain::Vertex,
                values: vec![r; n],
            }),
        );
    }
    Ok(m)
}

/// A points-only copy of `mesh`: the same vertices with their per-vertex data, no faces.
pub fn mesh_vertices(mesh: &Mesh, radius: Option<f64>) -> Result<Mesh, MeshError> {
    let vertex = |d: Domain| d == Domain::Vertex;
    let mut m = Mesh::new(mesh.positions.clone(), Vec::new(), Vec::new())?;
    m.colors = mesh.colors.clone().filter(|a| vertex(a.domain));
    m.normals = mesh.normals.clone().filter(|a| vertex(a.domain));
    m.uvs = mesh.uvs.clone().filter(|a| vertex(a.domain));
    for (name, a) in &mesh.attributes {
        let d = match a {
            AttributeData::Float(x) => x.domain,
            AttributeData::Vec2(x) => x.domain,
            AttributeData::Vec3(x) => x.domain,
            AttributeData::Int(x) => x.domain,
        };
        if vertex(d) {
            m.attributes.insert(name.clone(), a.clone());
        }
    }
    if let Some(r) = radius {
        m.attributes.insert(
            "radius".into(),
            AttributeData::Float(Attribute {
                domain: Domain::Vertex,
                values: vec![r; m.positions.len()],
            }),
        );
    }
    Ok(m)
}

fn declare(b: &mut NodeBuilder) {
    b.doc("Particles (or a mesh's vertices) as a points-only mesh with their attributes, colours and an optional radius.");
    b.add_input::<Points>("points")
        .optional()
        .doc("Particles, e.g. sph_fluid's points.");
    b.add_input::<Mesh>("mesh")
        .optional()
        .doc("Or a mesh: its vertices and per-vertex data are kept, its faces dropped.");
    b.add_input::<f64>("radius")
        .default(0.0)
        .range(0.0, 1e6)
        .doc("Adds a per-vertex `radius` attribute when positive.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    // In its declared range 0..1e6 (checked by the runtime).
    let r: f64 = ctx.input("radius")?;
    let radius = (r > 0.0).then_some(r);
    let points = ctx.input_opt::<Arc<Points>>("points")?;
    let mesh = ctx.input_opt::<Arc<Mesh>>("mesh")?;
    let out = match (points, mesh) {
        (Some(p), None) => points_to_mesh(&p, radius),
        (None, Some(m)) => mesh_vertices(&m, radius),
        (Some(_), Some(_)) => {
            return Err(NodeError::invalid(
                "mesh",
                "link either points or mesh, not both",
            ))
        }
        (None, None) => return Err(NodeError::invalid("points", "link points or a mesh")),
    }
    .map_err(|e| NodeError::invalid("points", e.to_string()))?;
    out.check()
        .map_err(|e| NodeError::invalid("points", e.to_string()))?;
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `points_to_mesh`.
pub fn register(r: &mut Registry) {
    r.add("points_to_mesh", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_keep_positions_attributes_and_colours() {
        let mut p = Points {
            dim: 3,
            positions: vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
            ..Default::default()
        };
        p.scalars.insert("speed".into(), vec![0.5, 2.0]);
        p.vectors
            .insert("color".into(), vec![[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
        p.vectors
            .insert("velocity".into(), vec![[0.0; 3], [1.0, 2.0, 3.0]]);
        let m = points_to_mesh(&p, Some(0.25)).unwrap();
        m.check().unwrap();
        assert_eq!(m.positions, p.positions);
        assert_eq!(m.num_faces(), 0);
        assert_eq!(m.colors.as_ref().unwrap().values[1], [0.0, 0.0, 1.0]);
        match &m.attributes["speed"] {
            AttributeData::Float(a) => assert_eq!(a.values, vec![0.5, 2.0]),
            other => panic!("{other:?}"),
        }
        match &m.attributes["velocity"] {
            AttributeData::Vec3(a) => assert_eq!(a.values[1], [1.0, 2.0, 3.0]),
            other => panic!("{other:?}"),
        }
        match &m.attributes["radius"] {
            AttributeData::Float(a) => assert_eq!(a.values, vec![0.25, 0.25]),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn mesh_vertices_drop_faces_and_corner_data() {
        let mut m = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        )
        .unwrap();
        m.uvs = Some(Attribute {
            domain: Domain::Corner,
            values: vec![[0.0; 2]; 3],
        });
        m.colors = Some(Attribute {
            domain: Domain::Vertex,
            values: vec![[0.5; 3]; 3],
        });
        let p = mesh_vertices(&m, None).unwrap();
        p.check().unwrap();
        assert_eq!(p.positions, m.positions);
        assert_eq!(p.num_faces(), 0);
        assert!(p.uvs.is_none());
        assert_eq!(p.colors, m.colors);
        assert!(!p.attributes.contains_key("radius"));
    }
}
