//! `set_vert_color`: one display colour per vertex (Framework3D's `geom_set_vert_color`),
//! given as a list or computed from a per-vertex attribute (e.g. `speed`) through the jet
//! colour map of the course's SPH code. `mesh_save` writes the colours to USDA as
//! `primvars:displayColor`.

use cgnodes_api::prelude::*;
pub use cgnodes_geometry::colormap::*;

fn declare(b: &mut NodeBuilder) {
    b.doc("Sets one display colour per vertex: a colour list, or a vertex attribute through the jet colour map.");
    b.add_input::<Mesh>("mesh");
    b.add_input::<Vec<[f64; 3]>>("colors").optional().doc(
        "One RGB colour per vertex (e.g. sph_fluid's colors); when absent, `attribute` is mapped.",
    );
    b.add_input::<String>("attribute").default("speed").doc(
        "Vertex attribute mapped through jet when no colours are linked (vectors by their length).",
    );
    b.add_input::<f64>("min")
        .default(0.0)
        .doc("Value at the blue end; min = max = 0 takes the attribute's own range.");
    b.add_input::<f64>("max")
        .default(0.0)
        .doc("Value at the red end.");
    b.add_output::<Mesh>("mesh");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let mesh: Arc<Mesh> = ctx.input("mesh")?;
    let n = mesh.num_vertices();
    let colors = match ctx.input_opt::<Vec<[f64; 3]>>("colors")? {
        Some(c) => {
            if c.len() != n {
                return Err(NodeError::invalid(
                    "colors",
                    format!("{} colours for {n} vertices", c.len()),
                ));
            }
            if c.iter().flatten().any(|x| !x.is_finite()) {
                return Err(NodeError::invalid("colors", "colours must be finite"));
            }
            c
        }
        None => {
            let name: String = ctx.input("attribute")?;
            let v = vertex_values(&mesh, &name).map_err(|e| NodeError::invalid("attribute", e))?;
            let (lo, hi): (f64, f64) = (ctx.input("min")?, ctx.input("max")?);
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(NodeError::invalid("min", "min and max must be finite"));
            }
            let range = (lo != 0.0 || hi != 0.0).then_some((lo, hi));
            jet_colors(&v, range)
        }
    };
    let mut out = (*mesh).clone();
    out.colors = Some(Attribute {
        domain: Domain::Vertex,
        values: colors,
    });
    ctx.set_output("mesh", out);
    Ok(())
}

/// Registers `set_vert_color`.
pub fn register(r: &mut Registry) {
    r.add("set_vert_color", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of the course's `colormap_jet.h` (256 entries), copied from the file.
    const TABLE: [(usize, [f64; 3]); 7] = [
        (0, [0.0, 0.0, 0.5]),
        (28, [0.0, 0.0, 0.99910873]),
        (32, [0.0, 0.00196078, 1.0]),
        (127, [0.47754586, 1.0, 0.49019608]),
        (128, [0.49019608, 1.0, 0.47754586]),
        (232, [0.90998217, 0.00072622, 0.0]),
        (255, [0.5, 0.0, 0.0]),
    ];

    #[test]
    fn jet_matches_the_course_table() {
        for (i, want) in TABLE {
            let got = jet(i as f64 / 255.0);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() < 2e-6,
                    "entry {i}: {got:?} against {want:?}"
                );
            }
        }
    }

    #[test]
    fn jet_colors_normalize_like_the_course() {
        // min -> entry 0, max -> entry 255, the middle value -> floor(0.5 * 255) = 127.
        let c = jet_colors(&[2.0, 4.0, 3.0], None);
        assert_eq!(c[0], jet(0.0));
        assert_eq!(c[1], jet(1.0));
        assert_eq!(c[2], jet(127.0 / 255.0));
        // All equal: entry 0 (dark blue), as the course does.
        assert!(jet_colors(&[1.0, 1.0], None)
            .iter()
            .all(|c| *c == [0.0, 0.0, 0.5]));
        // A given range clamps values outside it.
        let c = jet_colors(&[-5.0, 50.0], Some((0.0, 10.0)));
        assert_eq!(c, vec![jet(0.0), jet(1.0)]);
    }

    #[test]
    fn vector_attributes_map_by_length() {
        let mut m = Mesh::new(vec![[0.0; 3]; 2], Vec::new(), Vec::new()).unwrap();
        m.attributes.insert(
            "velocity".into(),
            AttributeData::Vec3(Attribute {
                domain: Domain::Vertex,
                values: vec![[3.0, 4.0, 0.0], [0.0, 0.0, 1.0]],
            }),
        );
        assert_eq!(vertex_values(&m, "velocity").unwrap(), vec![5.0, 1.0]);
        assert!(vertex_values(&m, "speed")
            .unwrap_err()
            .to_string()
            .contains("velocity"));
    }
}
