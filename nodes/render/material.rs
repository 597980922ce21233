//! `material`: a surface's appearance, shared by the rasterizer (Blinn-Phong from base
//! colour, metallic and roughness) and the tracers (the scattering `kind`).

use cgnodes_api::prelude::*;

/// The scattering model named by the `kind` socket (`MaterialKind` without its parameters,
/// which come from the `ior` and `roughness` sockets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Diffuse,
    Mirror,
    Dielectric,
    Conductor,
}

impl Choice for Kind {
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("diffuse", Kind::Diffuse),
        ("mirror", Kind::Mirror),
        ("dielectric", Kind::Dielectric),
        ("conductor", Kind::Conductor),
    ];
}

fn declare(b: &mut NodeBuilder) {
    b.doc("A surface material: base colour or texture, metallic, roughness, normal map, emission.");
    b.add_choice::<Kind>("kind")
        .doc("Scattering model for the tracers.");
    b.add_input::<Color>("base_color")
        .default(Color([0.8, 0.8, 0.8]))
        .doc("Linear base colour (multiplies the texture).");
    b.add_input::<Image>("texture")
        .optional()
        .doc("Base colour texture (linear), sampled through the mesh's UVs.");
    b.add_input::<f64>("metallic")
        .default(0.0)
        .range(0.0, 1.0)
        .doc("Metallic, 0 to 1.");
    b.add_input::<f64>("roughness")
        .default(0.5)
        .range(0.0, 1.0)
        .doc("Roughness, 0 to 1.");
    b.add_input::<Image>("normal_map")
        .optional()
        .doc("Tangent-space normal map (raw values, load it with color_space = raw).");
    b.add_input::<Color>("emission")
        .default(Color([0.0, 0.0, 0.0]))
        .doc("Emitted radiance (linear RGB).");
    b.add_input::<bool>("two_sided")
        .default(false)
        .doc("Whether the emission leaves both sides.");
    b.add_input::<f64>("ior")
        .default(1.5)
        .range(1.0, 4.0)
        .doc("Index of refraction (dielectric).");
    b.add_output::<Material>("material");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let kind = ctx.choice::<Kind>("kind")?;
    let base: Color = ctx.input("base_color")?;
    let emission: Color = ctx.input("emission")?;
    let metallic: f64 = ctx.input("metallic")?;
    let roughness: f64 = ctx.input("roughness")?;
    let ior: f64 = ctx.input("ior")?;
    // metallic, roughness and ior lie in their declared ranges (checked by the runtime).
    for (name, c) in [("base_color", base.0), ("emission", emission.0)] {
        if c.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(NodeError::invalid(name, "must be finite and not negative"));
        }
    }
    let kind = match kind {
        Kind::Diffuse => MaterialKind::Diffuse,
        Kind::Mirror => MaterialKind::Mirror,
        Kind::Dielectric => MaterialKind::Dielectric { ior },
        Kind::Conductor => MaterialKind::Conductor { roughness },
    };
    let m = Material {
        name: ctx.node_id.to_string(),
        kind,
        base_color: base.0,
        base_color_texture: ctx.input_opt("texture")?,
        metallic,
        roughness,
        normal_map: ctx.input_opt("normal_map")?,
        emission: emission.0,
        two_sided_emission: ctx.input("two_sided")?,
    };
    ctx.set_output("material", m);
    Ok(())
}

/// Registers `material`.
pub fn register(r: &mut Registry) {
    r.add("material", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn run(inputs: BTreeMap<String, Value>) -> Result<Material, NodeError> {
        match &super::super::run_node("material", inputs)?["material"] {
            Value::Material(m) => Ok((**m).clone()),
            _ => panic!("not a material"),
        }
    }

    #[test]
    fn kinds_and_fields() {
        let m = run(BTreeMap::new()).unwrap();
        assert_eq!(m.kind, MaterialKind::Diffuse);
        assert_eq!(m.base_color, [0.8, 0.8, 0.8]);
        assert!(m.base_color_texture.is_none());
        let mut inp = BTreeMap::new();
        inp.insert("kind".into(), Value::from("dielectric"));
        inp.insert("ior".into(), Value::Float(1.33));
        inp.insert("texture".into(), Value::from(Image::new(2, 2, [1.0; 4])));
        inp.insert("two_sided".into(), Value::Bool(true));
        let m = run(inp).unwrap();
        assert_eq!(m.kind, MaterialKind::Dielectric { ior: 1.33 });
        assert_eq!(m.base_color_texture.unwrap().width, 2);
        assert!(m.two_sided_emission);
        let mut inp = BTreeMap::new();
        inp.insert("kind".into(), Value::from("conductor"));
        inp.insert("roughness".into(), Value::Float(0.3));
        assert_eq!(
            run(inp).unwrap().kind,
            MaterialKind::Conductor { roughness: 0.3 }
        );
    }

    #[test]
    fn bad_values_are_errors() {
        let mut inp = BTreeMap::new();
        inp.insert("roughness".into(), Value::Float(2.0));
        assert!(run(inp).is_err());
        let mut inp = BTreeMap::new();
        inp.insert("base_color".into(), Value::Color([f64::NAN, 0.0, 0.0]));
        assert!(run(inp).is_err());
    }
}
