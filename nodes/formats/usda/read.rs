//! Reading a `Mesh` prim into a `Mesh`: points, faces, normals, UVs, display colours, simple
//! primvars (with `:indices` expanded and interpolation mapped to a domain), the prim's
//! world transform, and `leftHanded` orientation.

use super::access::{
    absolute_path, check_time_samples, find_prim_chain, floats, ints, mesh_paths, tuples,
};
use super::error::UsdaError;
use super::layer::{parse_usda, UsdAttr, UsdLayer, UsdPrim, UsdValue};
use super::lexer::err;
use super::transform::{transform_normals, transform_points, world_transform, Mat4};
use cgnodes_api::prelude::*;

/// Finds the prim at `path` (or the first `Mesh`, depth first, when `path` is empty) and
/// the chain of its ancestors, root first.
fn find_mesh<'a>(layer: &'a UsdLayer, path: &str) -> Result<Vec<&'a UsdPrim>, UsdaError> {
    let norm = absolute_path(path);
    let want: Box<dyn Fn(&UsdPrim) -> bool> = if norm.is_empty() {
        Box::new(|p: &UsdPrim| p.type_name == "Mesh" && p.specifier != "class")
    } else {
        Box::new(move |p: &UsdPrim| p.path == norm)
    };
    if let Some(chain) = find_prim_chain(layer, &*want) {
        let last = chain[chain.len() - 1];
        if last.type_name != "Mesh" {
            return Err(UsdaError::WrongType {
                path: last.path.clone(),
                line: last.line,
                found: last.type_name.clone(),
                wanted: "Mesh",
                kinds: "meshes",
                others: mesh_paths(layer).join(", "),
            });
        }
        return Ok(chain);
    }
    if path.is_empty() {
        Err(UsdaError::NoneOfType("Mesh"))
    } else {
        Err(UsdaError::NoPrimAt {
            path: path.to_string(),
            kinds: "meshes",
            found: mesh_paths(layer).join(", "),
        })
    }
}

fn interpolation(a: &UsdAttr) -> Result<Option<Domain>, UsdaError> {
    let i = a.meta.iter().find(|(k, _)| k == "interpolation");
    Ok(match i.map(|(_, v)| v) {
        None => None,
        Some(UsdValue::Str(s) | UsdValue::Ident(s)) => match s.as_str() {
            "vertex" | "varying" => Some(Domain::Vertex),
            "faceVarying" => Some(Domain::Corner),
            "uniform" => Some(Domain::Face),
            "constant" => None,
            other => return Err(err(a.line, format!("unknown interpolation '{other}'"))),
        },
        Some(other) => return Err(err(a.line, format!("bad interpolation {other:?}"))),
    })
}

fn element_size(a: &UsdAttr) -> Result<usize, UsdaError> {
    match a.meta.iter().find(|(k, _)| k == "elementSize") {
        None => Ok(1),
        Some((_, UsdValue::Num(n))) if *n >= 1.0 && n.fract() == 0.0 => Ok(*n as usize),
        Some((_, v)) => Err(err(a.line, format!("bad elementSize {v:?}"))),
    }
}

/// Picks the domain whose size matches an attribute's length, preferring its declared
/// interpolation; `constant` (one value) is broadcast to every vertex.
fn domain_for<T: Clone>(
    a: &UsdAttr,
    values: Vec<T>,
    declared: Option<Domain>,
    counts: (usize, usize, usize),
) -> Result<Attribute<T>, UsdaError> {
    let (nv, nc, nf) = counts;
    let size = |d: Domain| match d {
        Domain::Vertex => nv,
        Domain::Corner => nc,
        Domain::Face => nf,
    };
    let constant = a.meta.iter().any(|(k, v)| {
        k == "interpolation"
            && matches!(v, UsdValue::Str(s) | UsdValue::Ident(s) if s == "constant")
    });
    if constant {
        if values.len() != 1 {
            return Err(err(
                a.line,
                format!("'{}' is constant but has {} values", a.name, values.len()),
            ));
        }
        return Ok(Attribute {
            domain: Domain::Vertex,
            values: vec![values[0].clone(); nv],
        });
    }
    // USD's default interpolation for primvars is constant; for `normals` it is vertex.
    let d = declared.unwrap_or(Domain::Vertex);
    if values.len() != size(d) {
        return Err(err(
            a.line,
            format!(
                "'{}' has {} values but its {:?} interpolation needs {}",
                a.name,
                values.len(),
                d,
                size(d)
            ),
        ));
    }
    Ok(Attribute { domain: d, values })
}

/// Expands an indexed primvar (`primvars:st:indices`).
fn expand_indexed<T: Clone>(
    prim: &UsdPrim,
    a: &UsdAttr,
    values: Vec<T>,
) -> Result<Vec<T>, UsdaError> {
    let Some(ix) = prim.attr(&format!("{}:indices", a.name)) else {
        return Ok(values);
    };
    ints(ix)?
        .into_iter()
        .map(|i| {
            values
                .get(i as usize)
                .cloned()
                .filter(|_| i >= 0)
                .ok_or_else(|| {
                    err(
                        ix.line,
                        format!(
                            "index {i} out of range for '{}' ({} values)",
                            a.name,
                            values.len()
                        ),
                    )
                })
        })
        .collect()
}

/// Reads the mesh at `prim_path` (the first Mesh when empty) from USDA text, with the
/// transforms of the prim and its ancestors applied when `apply_transform` is set.
pub fn read_usda(text: &str, prim_path: &str, apply_transform: bool) -> Result<Mesh, UsdaError> {
    let layer = parse_usda(text)?;
    let chain = find_mesh(&layer, prim_path)?;
    read_mesh_chain(&layer, &chain, apply_transform)
}

/// Reads the `Mesh` prim at the end of `chain` (its ancestors, root first) of a parsed
/// layer, with the chain's transforms applied when `apply_transform` is set (the stage
/// reader walks a layer once and reads every mesh through this).
pub fn read_mesh_chain(
    layer: &UsdLayer,
    chain: &[&UsdPrim],
    apply_transform: bool,
) -> Result<Mesh, UsdaError> {
    let prim = chain[chain.len() - 1];
    check_mesh_animation(prim)?;
    let need = |n: &str| {
        prim.attr(n).ok_or_else(|| {
            UsdaError::prim(
                &prim.path,
                format!("Mesh '{}' (line {}) has no '{n}'", prim.path, prim.line),
            )
        })
    };
    let pa = need("points")?;
    let mut positions = tuples::<3>(pa)?;
    let ca = need("faceVertexCounts")?;
    let ia = need("faceVertexIndices")?;
    let nv = positions.len();
    let (c32, i32v) = face_topology(ca, ia, nv)?;
    let sizes = (nv, i32v.len(), c32.len());
    let mut normals = None;
    let na = prim.attr("primvars:normals").or(prim.attr("normals"));
    if let Some(a) = na {
        let v = expand_indexed(prim, a, tuples::<3>(a)?)?;
        normals = Some(domain_for(a, v, interpolation(a)?, sizes)?);
    }
    let mut uvs = None;
    let ua = prim
        .attr("primvars:UVMap")
        .or(prim.attr("primvars:st"))
        .or(prim.attr("primvars:uv"));
    if let Some(a) = ua {
        let v = expand_indexed(prim, a, tuples::<2>(a)?)?;
        uvs = Some(domain_for(a, v, interpolation(a)?, sizes)?);
    }
    let mut colors = None;
    if let Some(a) = prim.attr("primvars:displayColor") {
        let v = expand_indexed(prim, a, tuples::<3>(a)?)?;
        colors = Some(domain_for(a, v, interpolation(a)?, sizes)?);
    }
    let attributes = generic_primvars(prim, [ua, na], sizes)?;
    // Left-handed meshes wind clockwise: reverse faces so outputs are counter-clockwise.
    let left = prim
        .attr("orientation")
        .and_then(|a| a.value.as_ref())
        .is_some_and(|v| matches!(v, UsdValue::Str(s) | UsdValue::Ident(s) if s == "leftHanded"));
    let mut applied = None;
    if apply_transform {
        let m = world_transform(chain)?;
        if m != Mat4::identity() {
            applied = Some(m);
            transform_points(&m, &mut positions);
            if let Some(n) = normals.as_mut() {
                transform_normals(&m, &mut n.values).ok_or_else(|| {
                    UsdaError::prim(
                        &prim.path,
                        format!("the transform of '{}' is singular", prim.path),
                    )
                })?;
            }
        }
    }
    let mut mesh = Mesh::new(positions, c32, i32v).map_err(|e| match e {
        MeshError::NonFinite { .. } => err(pa.line, e),
        _ => err(ia.line, e),
    })?;
    mesh.normals = normals;
    mesh.uvs = uvs;
    mesh.colors = colors;
    mesh.attributes = attributes;
    mesh.skin = super::skel::read_binding(layer, chain, nv, applied.as_ref(), apply_transform)?
        .map(std::sync::Arc::new);
    if left {
        reverse_faces(&mut mesh);
    }
    mesh.check()
        .map_err(|e| UsdaError::prim(&prim.path, e.to_string()))?;
    Ok(mesh)
}

/// Refuses time samples on the attributes a mesh reads (points, topology, normals, primvars,
/// transform ops): a static mesh cannot honour them. Animation elsewhere is harmless.
fn check_mesh_animation(prim: &UsdPrim) -> Result<(), UsdaError> {
    for a in &prim.attrs {
        check_time_samples(a).or_else(|e| {
            let base = a.name.trim_end_matches(".timeSamples");
            if ["points", "faceVertexCounts", "faceVertexIndices", "normals"].contains(&base)
                || base.starts_with("primvars:")
                || base.starts_with("xformOp:")
            {
                Err(e)
            } else {
                Ok(())
            }
        })?;
    }
    Ok(())
}

/// Checks `faceVertexCounts` and `faceVertexIndices` against each other and the `nv` points
/// and returns them as `u32` (counts, indices).
fn face_topology(ca: &UsdAttr, ia: &UsdAttr, nv: usize) -> Result<(Vec<u32>, Vec<u32>), UsdaError> {
    let counts = ints(ca)?;
    let idx = ints(ia)?;
    // Counts are checked before anything is sized from them (issue 23): each between 3 and
    // the number of indices, so `as u32` cannot truncate, and their sum with checked
    // arithmetic (an i64 sum of hostile counts overflowed).
    let mut c32 = Vec::with_capacity(counts.len());
    let mut sum: u64 = 0;
    for (f, &c) in counts.iter().enumerate() {
        if c < 3 {
            return Err(err(
                ca.line,
                format!("face {f} has {c} corners; a face needs at least 3"),
            ));
        }
        sum = sum.saturating_add(c as u64);
        if sum > idx.len() as u64 {
            return Err(err(
                ia.line,
                format!(
                    "faceVertexCounts add up to more than the {} entries of faceVertexIndices (at face {f}, {c} corners)",
                    idx.len()
                ),
            ));
        }
        c32.push(c as u32);
    }
    let mut i32v = Vec::with_capacity(idx.len());
    for (k, &i) in idx.iter().enumerate() {
        if i < 0 || i as usize >= nv {
            return Err(err(
                ia.line,
                format!("faceVertexIndices[{k}] = {i} is out of range ({nv} points)"),
            ));
        }
        i32v.push(i as u32);
    }
    if sum != idx.len() as u64 {
        return Err(err(
            ia.line,
            format!(
                "faceVertexCounts add up to {sum} but faceVertexIndices has {} entries",
                idx.len()
            ),
        ));
    }
    Ok((c32, i32v))
}

/// The mesh's other per-element primvars (float, int, 2- and 3-vectors) as named attributes;
/// `taken` are the UV and normal primvars already read, skipped here with the display colour,
/// index arrays, the skeleton binding and multi-influence primvars.
fn generic_primvars(
    prim: &UsdPrim,
    taken: [Option<&UsdAttr>; 2],
    sizes: (usize, usize, usize),
) -> Result<std::collections::BTreeMap<String, AttributeData>, UsdaError> {
    let mut attributes = std::collections::BTreeMap::new();
    for a in &prim.attrs {
        let Some(name) = a.name.strip_prefix("primvars:") else {
            continue;
        };
        if name.ends_with(":indices")
            || name.starts_with("skel:") // the skeleton binding, read by skel::read_binding
            || taken.iter().any(|t| t.is_some_and(|u| std::ptr::eq(u, a)))
            || name == "displayColor"
            || a.value.is_none()
        {
            continue;
        }
        if element_size(a)? != 1 {
            continue; // e.g. skinning weights with several influences: not a per-element value
        }
        let d = interpolation(a)?;
        let ty = a.type_name.trim_start_matches("uniform ");
        let data = match ty {
            "float[]" | "double[]" | "half[]" => AttributeData::Float(domain_for(
                a,
                expand_indexed(prim, a, floats(a)?)?,
                d,
                sizes,
            )?),
            "int[]" | "bool[]" => {
                AttributeData::Int(domain_for(a, expand_indexed(prim, a, ints(a)?)?, d, sizes)?)
            }
            "float2[]" | "double2[]" | "texCoord2f[]" | "texCoord2d[]" => AttributeData::Vec2(
                domain_for(a, expand_indexed(prim, a, tuples::<2>(a)?)?, d, sizes)?,
            ),
            "float3[]" | "double3[]" | "color3f[]" | "normal3f[]" | "vector3f[]" | "point3f[]" => {
                AttributeData::Vec3(domain_for(
                    a,
                    expand_indexed(prim, a, tuples::<3>(a)?)?,
                    d,
                    sizes,
                )?)
            }
            _ => continue, // other primvars (matrices, tokens) carry no per-element data
        };
        attributes.insert(name.to_string(), data);
    }
    Ok(attributes)
}

/// Reverses the winding of every face, carrying per-corner data along.
pub fn reverse_faces(mesh: &mut Mesh) {
    let starts = mesh.face_starts().to_vec();
    let nc = mesh.face_indices().len();
    let mut perm: Vec<usize> = (0..nc).collect();
    for f in 0..mesh.num_faces() {
        perm[starts[f] as usize..starts[f + 1] as usize].reverse();
    }
    let idx: Vec<u32> = perm.iter().map(|&c| mesh.face_indices()[c]).collect();
    let counts = mesh.face_counts().to_vec();
    fn re<T: Clone>(a: &mut Option<Attribute<T>>, perm: &[usize]) {
        if let Some(a) = a.as_mut().filter(|a| a.domain == Domain::Corner) {
            a.values = perm.iter().map(|&c| a.values[c].clone()).collect();
        }
    }
    let mut uvs = mesh.uvs.take();
    let mut normals = mesh.normals.take();
    let mut colors = mesh.colors.take();
    re(&mut uvs, &perm);
    re(&mut normals, &perm);
    re(&mut colors, &perm);
    let mut attrs = std::mem::take(&mut mesh.attributes);
    for a in attrs.values_mut() {
        macro_rules! fix {
            ($x:expr) => {
                if $x.domain == Domain::Corner {
                    $x.values = perm.iter().map(|&c| $x.values[c].clone()).collect();
                }
            };
        }
        match a {
            AttributeData::Float(x) => fix!(x),
            AttributeData::Vec2(x) => fix!(x),
            AttributeData::Vec3(x) => fix!(x),
            AttributeData::Int(x) => fix!(x),
        }
    }
    mesh.set_faces(counts, idx);
    mesh.uvs = uvs;
    mesh.normals = normals;
    mesh.colors = colors;
    mesh.attributes = attrs;
}
