//! Animated USDA output: one layer holding a mesh's points (and normals) as `timeSamples`, one
//! sample per frame, so that usdview and Blender play the sequence. `mesh_save` with
//! `animated` on reads the samples it wrote for earlier frames back from the file, adds (or
//! replaces) the current frame's and rewrites the whole layer atomically: no state is kept
//! between frames, so the file is complete after every frame.

use super::access::{find_prim_chain, ints, tuples};
use super::layer::{parse_usda, UsdValue};
use super::write::{usd_identifier, write_usda};
use cgnodes_api::prelude::*;

/// Frames of an animated mesh: sample times with points and, when every frame has them,
/// normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Samples {
    /// Increasing times (USD time codes; `mesh_save` uses the frame number).
    pub times: Vec<f64>,
    /// Points per time.
    pub points: Vec<Vec<[f64; 3]>>,
    /// Normals per time (all or none).
    pub normals: Option<Vec<Vec<[f64; 3]>>>,
}

impl Samples {
    /// Inserts the sample at `time`, replacing one at the same time.
    pub fn insert(&mut self, time: f64, points: Vec<[f64; 3]>, normals: Option<Vec<[f64; 3]>>) {
        let k = self.times.partition_point(|&t| t < time);
        let same = self.times.get(k) == Some(&time);
        let keep_normals = normals.is_some()
            && (self.normals.is_some() || self.times.is_empty() || same && self.times.len() == 1);
        if same {
            self.points[k] = points;
        } else {
            self.times.insert(k, time);
            self.points.insert(k, points);
        }
        match (keep_normals, normals) {
            (true, Some(n)) => {
                let all = self.normals.get_or_insert_with(Vec::new);
                if same && all.len() > k {
                    all[k] = n;
                } else {
                    all.insert(k.min(all.len()), n);
                }
            }
            _ => self.normals = None,
        }
    }
}

fn prim_path(parts: &[String]) -> String {
    parts.iter().map(|p| format!("/{p}")).collect()
}

fn parts_of(prim: &str) -> Vec<String> {
    let p: Vec<String> = prim
        .split('/')
        .filter(|s| !s.is_empty())
        .map(usd_identifier)
        .collect();
    if p.is_empty() {
        vec!["mesh".into(), "mesh".into()]
    } else {
        p
    }
}

/// The samples of an animated layer `write_animated` wrote for `prim` with the same faces as
/// `mesh`; `None` when the text is not such a layer (another mesh, another writer).
pub fn read_samples(text: &str, prim: &str, mesh: &Mesh) -> Option<Samples> {
    if !text.contains("doc = \"written by cgnodes (animated)\"") {
        return None;
    }
    let layer = parse_usda(text).ok()?;
    let path = prim_path(&parts_of(prim));
    let chain = find_prim_chain(&layer, &|p| p.path == path)?;
    let p = chain[chain.len() - 1];
    let counts = ints(p.attr("faceVertexCounts")?).ok()?;
    let idx = ints(p.attr("faceVertexIndices")?).ok()?;
    let same = counts
        .iter()
        .map(|&c| c as u32)
        .eq(mesh.face_counts().iter().copied())
        && idx
            .iter()
            .map(|&c| c as u32)
            .eq(mesh.face_indices().iter().copied());
    if !same {
        return None;
    }
    let dict = |name: &str| -> Option<Vec<(f64, Vec<[f64; 3]>)>> {
        let a = p.attr(name)?;
        let Some(UsdValue::Dict(items)) = &a.value else {
            return None;
        };
        items
            .iter()
            .map(|(k, v)| {
                let UsdValue::Num(t) = k else { return None };
                let fake = super::layer::UsdAttr {
                    value: Some(v.clone()),
                    ..a.clone()
                };
                Some((*t, tuples::<3>(&fake).ok()?))
            })
            .collect()
    };
    let pts = dict("points.timeSamples")?;
    let mut s = Samples {
        times: pts.iter().map(|x| x.0).collect(),
        points: pts.into_iter().map(|x| x.1).collect(),
        normals: None,
    };
    if let Some(ns) = dict("normals.timeSamples") {
        if ns.iter().map(|x| x.0).eq(s.times.iter().copied()) {
            s.normals = Some(ns.into_iter().map(|x| x.1).collect());
        }
    }
    if s.points.iter().any(|p| p.len() != mesh.num_vertices()) {
        return None;
    }
    Some(s)
}

fn tuples_text(v: &[[f64; 3]]) -> String {
    let items: Vec<String> = v
        .iter()
        .map(|p| format!("({}, {}, {})", p[0], p[1], p[2]))
        .collect();
    format!("[{}]", items.join(", "))
}

fn samples_text(ind: &str, times: &[f64], values: &[Vec<[f64; 3]>]) -> String {
    let mut s = String::from("{\n");
    for (t, v) in times.iter().zip(values) {
        s.push_str(&format!("{ind}    {t}: {},\n", tuples_text(v)));
    }
    s.push_str(&format!("{ind}}}"));
    s
}

/// Writes `mesh` (faces, UVs, colours, attributes of the current frame) as a layer whose
/// points and normals are `samples`, with `startTimeCode`/`endTimeCode` spanning them and
/// 24 time codes per second.
pub fn write_animated(
    mesh: &Mesh,
    prim: &str,
    samples: &Samples,
    w: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let mut buf = Vec::new();
    write_usda(mesh, prim, &mut buf)?;
    let text = String::from_utf8_lossy(&buf).into_owned();
    let ind = "    ".repeat(parts_of(prim).len());
    let (t0, t1) = (
        samples.times.first().copied().unwrap_or(0.0),
        samples.times.last().copied().unwrap_or(0.0),
    );
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in samples.points.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let mut out = String::with_capacity(text.len() * (samples.times.len() + 1));
    for line in text.lines() {
        if line == "    doc = \"written by cgnodes\"" {
            out.push_str("    doc = \"written by cgnodes (animated)\"\n");
            out.push_str(&format!(
                "    startTimeCode = {t0}\n    endTimeCode = {t1}\n    timeCodesPerSecond = 24\n"
            ));
            continue;
        }
        if let Some(rest) = line.strip_prefix(&ind) {
            if rest.starts_with("float3[] extent = ") && !samples.times.is_empty() {
                out.push_str(&format!(
                    "{ind}float3[] extent = {}\n",
                    tuples_text(&[lo, hi])
                ));
                continue;
            }
            if rest.starts_with("point3f[] points = ") {
                out.push_str(&format!(
                    "{ind}point3f[] points.timeSamples = {}\n",
                    samples_text(&ind, &samples.times, &samples.points)
                ));
                continue;
            }
            if rest.starts_with("normal3f[] normals = ") {
                if let Some(ns) = &samples.normals {
                    out.push_str(&format!(
                        "{ind}normal3f[] normals.timeSamples = {} (\n",
                        samples_text(&ind, &samples.times, ns)
                    ));
                    continue;
                }
            }
        }
        out.push_str(line);
        out.push('\n');
    }
    w.write_all(out.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_accumulate_and_read_back_exactly() {
        let mut m = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        )
        .unwrap();
        m.normals = Some(Attribute {
            domain: Domain::Vertex,
            values: vec![[0.0, 0.0, 1.0]; 3],
        });
        let mut s = Samples::default();
        for f in [2.0, 0.0, 1.0, 1.0] {
            let pts: Vec<[f64; 3]> = m
                .positions
                .iter()
                .map(|p| [p[0] + f, p[1], p[2] + 0.1 * f])
                .collect();
            s.insert(f, pts, m.normals.as_ref().map(|n| n.values.clone()));
        }
        assert_eq!(s.times, vec![0.0, 1.0, 2.0]);
        let mut buf = Vec::new();
        write_animated(&m, "/a/b", &s, &mut buf).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(
            text.contains("points.timeSamples")
                && text.contains("startTimeCode = 0")
                && text.contains("endTimeCode = 2")
        );
        let back = read_samples(&text, "/a/b", &m).unwrap();
        assert_eq!(back, s);
        // Another mesh's faces: not ours to extend.
        let other = Mesh::from_triangles(m.positions.clone(), &[[0, 2, 1]]).unwrap();
        assert!(read_samples(&text, "/a/b", &other).is_none());
    }
}
