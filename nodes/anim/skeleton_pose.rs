//! `skeleton_pose`: a skeleton's joint transforms at a USD time code, as a table, and a mesh
//! of its bones (one thin box from each joint's parent to the joint) for looking at.

use super::pose::skel_transforms;
use cgnodes_api::prelude::*;
use cgnodes_formats::usda::transform::Mat4;

/// Thin boxes from each joint's parent origin to its origin (skeleton space), `width` times
/// the bone's length across; zero-length bones are skipped.
pub fn bones_mesh(skel: &Skeleton, xf: &[Mat4], width: f64) -> Mesh {
    use cgnodes_api::types::vec3::*;
    let origin = |m: &Mat4| [m[(3, 0)], m[(3, 1)], m[(3, 2)]];
    let mut pos = Vec::new();
    let mut counts = Vec::new();
    let mut idx = Vec::new();
    for (j, joint) in skel.joints.iter().enumerate() {
        let Some(p) = joint.parent else { continue };
        let (a, b) = (origin(&xf[p]), origin(&xf[j]));
        let d = sub(b, a);
        let len = norm(d);
        if len.is_nan() || len <= 1e-12 {
            continue;
        }
        let t = scale(d, 1.0 / len);
        let helper = if t[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let u = unit(cross(t, helper));
        let v = cross(t, u);
        let h = 0.5 * width * len;
        let base = pos.len() as u32;
        for end in [a, b] {
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                pos.push(add(end, add(scale(u, su * h), scale(v, sv * h))));
            }
        }
        // Outward-facing quads: the two caps, then the four sides.
        let quads = [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ];
        for q in quads {
            counts.push(4);
            idx.extend(q.iter().map(|&k| base + k));
        }
    }
    Mesh::new(pos, counts, idx).unwrap_or_default()
}

/// The joint transforms as a table: `joint`, `parent` (-1 for a root), the origin `x y z`,
/// and the 16 entries `m00 .. m33` of each skeleton-space matrix (USD rows).
pub fn pose_table(skel: &Skeleton, xf: &[Mat4]) -> Table {
    let mut names: Vec<String> = vec![
        "joint".into(),
        "parent".into(),
        "x".into(),
        "y".into(),
        "z".into(),
    ];
    for r in 0..4 {
        for c in 0..4 {
            names.push(format!("m{r}{c}"));
        }
    }
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let mut t = Table::with_columns(&refs);
    for (j, (joint, m)) in skel.joints.iter().zip(xf).enumerate() {
        let mut row = vec![
            j as f64,
            joint.parent.map_or(-1.0, |p| p as f64),
            m[(3, 0)],
            m[(3, 1)],
            m[(3, 2)],
        ];
        for r in 0..4 {
            for c in 0..4 {
                row.push(m[(r, c)]);
            }
        }
        t.push_row(&row);
    }
    t.meta.insert(
        "joints".into(),
        skel.joints
            .iter()
            .map(|j| j.path.as_str())
            .collect::<Vec<_>>()
            .join(" "),
    );
    t
}

fn declare(b: &mut NodeBuilder) {
    b.doc("A skeleton's joint transforms at a time code (table) and a mesh of its bones.");
    b.add_input::<Skeleton>("skeleton");
    b.add_input::<f64>("time")
        .default(0.0)
        .doc("USD time code; outside the animation's samples the ends are held.");
    b.add_input::<f64>("width")
        .default(0.1)
        .range(0.0, 10.0)
        .doc("Bone box width as a fraction of the bone's length.");
    b.add_output::<Table>("transforms");
    b.add_output::<Mesh>("bones");
}

fn execute(ctx: &mut ExecContext) -> Result<(), NodeError> {
    let skel: Arc<Skeleton> = ctx.input("skeleton")?;
    let time: f64 = ctx.input("time")?;
    let width: f64 = ctx.input("width")?;
    if !time.is_finite() {
        return Err(NodeError::invalid(
            "time",
            format!("time {time} is not finite"),
        ));
    }
    let xf =
        skel_transforms(&skel, time).map_err(|e| NodeError::invalid("skeleton", e.to_string()))?;
    ctx.set_output("transforms", pose_table(&skel, &xf));
    ctx.set_output("bones", bones_mesh(&skel, &xf, width));
    Ok(())
}

/// Registers `skeleton_pose`.
pub fn register(r: &mut Registry) {
    r.add("skeleton_pose", declare, execute);
}

#[cfg(test)]
mod tests {
    use super::*;
    use cgnodes_api::types::{Joint, IDENTITY_MATRIX};

    #[test]
    fn one_box_per_bone_spanning_the_bone() {
        let mut up = IDENTITY_MATRIX;
        up[3][2] = 2.0;
        let s = Skeleton {
            prim: "/S".into(),
            joints: vec![
                Joint {
                    path: "A".into(),
                    parent: None,
                    bind: IDENTITY_MATRIX,
                    rest: IDENTITY_MATRIX,
                },
                Joint {
                    path: "A/B".into(),
                    parent: Some(0),
                    bind: up,
                    rest: up,
                },
            ],
            animation: None,
        };
        let xf = skel_transforms(&s, 0.0).unwrap();
        let m = bones_mesh(&s, &xf, 0.1);
        assert_eq!((m.num_vertices(), m.num_faces()), (8, 6));
        let zs: Vec<f64> = m.positions.iter().map(|p| p[2]).collect();
        assert_eq!(zs.iter().cloned().fold(f64::MAX, f64::min), 0.0);
        assert_eq!(zs.iter().cloned().fold(f64::MIN, f64::max), 2.0);
        assert!(m
            .positions
            .iter()
            .all(|p| p[0].abs() <= 0.1 + 1e-12 && p[1].abs() <= 0.1 + 1e-12));
        let t = pose_table(&s, &xf);
        assert_eq!(t.column("z").unwrap(), &[0.0, 2.0]);
        assert_eq!(t.column("parent").unwrap(), &[-1.0, 0.0]);
    }
}
