//! UsdSkel reading: a `Skeleton` prim (joints, bind and rest transforms) with its bound
//! `SkelAnimation` (`skel:animationSource`), and a mesh's binding (`skel:skeleton`,
//! `primvars:skel:jointIndices` / `jointWeights` with `elementSize`, vertex or constant
//! interpolation, `primvars:skel:geomBindTransform`, the mesh's own `skel:joints` order).
//! Errors name the prim and the line.

use super::access::{
    absolute_path, find_prim_chain, floats, ints, list, prim_paths_of_type, tuple_n,
};
use super::error::UsdaError;
use super::layer::{UsdAttr, UsdLayer, UsdPrim, UsdValue};
use super::lexer::err;
use super::transform::{matrix, world_transform, Mat4};
use cgnodes_api::types::{Joint, RowMatrix, SkelAnimation, Skeleton, SkinBinding, Track};
use std::sync::Arc;

/// A `Mat4` as rows.
pub fn to_rows(m: &Mat4) -> RowMatrix {
    let mut r = [[0.0; 4]; 4];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = m[(i, j)];
        }
    }
    r
}

/// Rows as a `Mat4`.
pub fn from_rows(r: &RowMatrix) -> Mat4 {
    Mat4::from_fn(|i, j| r[i][j])
}

fn chain_to<'a>(layer: &'a UsdLayer, path: &str) -> Option<Vec<&'a UsdPrim>> {
    let norm = absolute_path(path);
    find_prim_chain(layer, &|p: &UsdPrim| p.path == norm)
}

/// The target path of relationship `name` on the last prim of `chain`, else on the nearest
/// ancestor that has it (UsdSkel bindings are inherited).
fn inherited_rel<'a>(chain: &[&'a UsdPrim], name: &str) -> Option<(&'a UsdPrim, &'a UsdAttr)> {
    chain
        .iter()
        .rev()
        .find_map(|p| p.attr(name).map(|a| (*p, a)))
}

fn rel_target(a: &UsdAttr) -> Result<String, UsdaError> {
    match &a.value {
        Some(UsdValue::Path(p)) => Ok(p.clone()),
        Some(UsdValue::List(v)) if v.len() == 1 => match &v[0] {
            UsdValue::Path(p) => Ok(p.clone()),
            other => Err(err(
                a.line,
                format!("'{}' expects a path, found {other:?}", a.name),
            )),
        },
        other => Err(err(
            a.line,
            format!("'{}' expects one path, found {other:?}", a.name),
        )),
    }
}

fn tokens(a: &UsdAttr) -> Result<Vec<String>, UsdaError> {
    list(a)?
        .iter()
        .map(|v| match v {
            UsdValue::Str(s) | UsdValue::Ident(s) => Ok(s.clone()),
            other => Err(err(
                a.line,
                format!("'{}' expects tokens, found {other:?}", a.name),
            )),
        })
        .collect()
}

fn matrices(a: &UsdAttr) -> Result<Vec<RowMatrix>, UsdaError> {
    list(a)?
        .iter()
        .map(|v| matrix(v, a.line, &a.name).map(|m| to_rows(&m)))
        .collect()
}

/// Reads the Skeleton at `path` (the first Skeleton when empty), with its animation.
pub fn read_skeleton(layer: &UsdLayer, path: &str) -> Result<Skeleton, UsdaError> {
    let chain = if path.is_empty() {
        find_prim_chain(layer, &|p: &UsdPrim| {
            p.type_name == "Skeleton" && p.specifier != "class"
        })
        .ok_or(UsdaError::NoneOfType("Skeleton"))?
    } else {
        chain_to(layer, path).ok_or_else(|| UsdaError::NoPrimAt {
            path: path.to_string(),
            kinds: "skeletons",
            found: prim_paths_of_type(layer, "Skeleton").join(", "),
        })?
    };
    skeleton_from_chain(layer, &chain)
}

fn skeleton_from_chain(layer: &UsdLayer, chain: &[&UsdPrim]) -> Result<Skeleton, UsdaError> {
    let prim = chain[chain.len() - 1];
    if prim.type_name != "Skeleton" {
        return Err(UsdaError::WrongType {
            path: prim.path.clone(),
            line: prim.line,
            found: prim.type_name.clone(),
            wanted: "Skeleton",
            kinds: "skeletons",
            others: prim_paths_of_type(layer, "Skeleton").join(", "),
        });
    }
    let here = |what: &str| {
        UsdaError::prim(
            &prim.path,
            format!("Skeleton '{}' (line {}) {what}", prim.path, prim.line),
        )
    };
    let ja = prim.attr("joints").ok_or_else(|| here("has no joints"))?;
    let paths = tokens(ja)?;
    if paths.is_empty() {
        return Err(here("has no joints"));
    }
    let ba = prim
        .attr("bindTransforms")
        .ok_or_else(|| here("has no bindTransforms"))?;
    let bind = matrices(ba)?;
    if bind.len() != paths.len() {
        return Err(err(
            ba.line,
            format!(
                "bindTransforms has {} matrices for {} joints",
                bind.len(),
                paths.len()
            ),
        ));
    }
    let parents = joint_parents(ja, &paths)?;
    let rest = rest_transforms(prim, ba, &paths, &bind, &parents)?;
    let joints = paths
        .into_iter()
        .zip(parents)
        .zip(bind.into_iter().zip(rest))
        .map(|((path, parent), (bind, rest))| Joint {
            path,
            parent,
            bind,
            rest,
        })
        .collect();
    let mut skel = Skeleton {
        prim: prim.path.clone(),
        joints,
        animation: None,
    };
    if let Some((_, a)) = inherited_rel(chain, "skel:animationSource") {
        let target = rel_target(a)?;
        let achain = chain_to(layer, &target).ok_or_else(|| {
            err(
                a.line,
                format!("skel:animationSource names '{target}', which does not exist"),
            )
        })?;
        skel.animation = Some(read_animation(achain[achain.len() - 1], &skel)?);
    }
    Ok(skel)
}

/// Each joint's parent index: the nearest ancestor path that is itself a joint
/// (UsdSkelTopology). Refuses repeated joints and a joint listed before its parent.
fn joint_parents(ja: &UsdAttr, paths: &[String]) -> Result<Vec<Option<usize>>, UsdaError> {
    let mut parents = Vec::with_capacity(paths.len());
    for (i, p) in paths.iter().enumerate() {
        if paths[..i].contains(p) {
            return Err(err(ja.line, format!("joint '{p}' appears twice")));
        }
        // The parent is the nearest ancestor path that is itself a joint (UsdSkelTopology).
        let mut parent = None;
        let mut q = p.as_str();
        while let Some(k) = q.rfind('/') {
            q = &q[..k];
            if let Some(j) = paths.iter().position(|x| x == q) {
                if j > i {
                    return Err(err(
                        ja.line,
                        format!("joint '{p}' comes before its parent '{q}'"),
                    ));
                }
                parent = Some(j);
                break;
            }
        }
        parents.push(parent);
    }
    Ok(parents)
}

/// The joints' rest transforms (local): `restTransforms` when authored, else derived from the
/// bind transforms.
fn rest_transforms(
    prim: &UsdPrim,
    ba: &UsdAttr,
    paths: &[String],
    bind: &[RowMatrix],
    parents: &[Option<usize>],
) -> Result<Vec<RowMatrix>, UsdaError> {
    Ok(match prim.attr("restTransforms") {
        Some(ra) => {
            let r = matrices(ra)?;
            if r.len() != paths.len() {
                return Err(err(
                    ra.line,
                    format!(
                        "restTransforms has {} matrices for {} joints",
                        r.len(),
                        paths.len()
                    ),
                ));
            }
            r
        }
        // Without rest transforms the bind pose is the rest pose: local = bind * bind_parent^-1.
        None => {
            let mut r = Vec::with_capacity(paths.len());
            for (i, b) in bind.iter().enumerate() {
                let local = match parents[i] {
                    None => *b,
                    Some(p) => {
                        let inv = from_rows(&bind[p]).try_inverse().ok_or_else(|| {
                            err(
                                ba.line,
                                format!(
                                    "the bind transform of joint '{}' is not invertible",
                                    paths[p]
                                ),
                            )
                        })?;
                        to_rows(&(from_rows(b) * inv))
                    }
                };
                r.push(local);
            }
            r
        }
    })
}

/// An attribute's track: its `timeSamples` when authored, else its default value.
fn track<T: Clone, F>(
    prim: &UsdPrim,
    name: &str,
    n: usize,
    elem: F,
) -> Result<Option<Track<T>>, UsdaError>
where
    F: Fn(&UsdValue, usize, &str) -> Result<T, UsdaError>,
{
    let sampled = prim.attr(&format!("{name}.timeSamples"));
    let Some(a) = sampled.or(prim.attr(name)) else {
        return Ok(None);
    };
    let array = |v: &UsdValue| -> Result<Vec<T>, UsdaError> {
        let UsdValue::List(items) = v else {
            return Err(err(
                a.line,
                format!("'{}' expects an array, found {v:?}", a.name),
            ));
        };
        if items.len() != n {
            return Err(err(
                a.line,
                format!(
                    "'{}' of SkelAnimation '{}' has {} values for {} joints",
                    a.name,
                    prim.path,
                    items.len(),
                    n
                ),
            ));
        }
        items.iter().map(|x| elem(x, a.line, &a.name)).collect()
    };
    let Some(v) = &a.value else {
        return Err(err(a.line, format!("'{}' has no value", a.name)));
    };
    let mut t = Track {
        times: Vec::new(),
        values: Vec::new(),
    };
    match v {
        UsdValue::Dict(samples) => {
            for (k, v) in samples {
                let UsdValue::Num(time) = k else {
                    return Err(err(
                        a.line,
                        format!("'{}' has a non-numeric time {k:?}", a.name),
                    ));
                };
                t.times.push(*time);
                t.values.push(array(v)?);
            }
            if t.times.is_empty() {
                return Err(err(a.line, format!("'{}' has no time samples", a.name)));
            }
            // Sort by time (a layer may author them in any order).
            let mut order: Vec<usize> = (0..t.times.len()).collect();
            order.sort_by(|&i, &j| t.times[i].total_cmp(&t.times[j]));
            t.times = order.iter().map(|&i| t.times[i]).collect();
            t.values = order.iter().map(|&i| t.values[i].clone()).collect();
        }
        other => t.values.push(array(other)?),
    }
    Ok(Some(t))
}

fn read_animation(prim: &UsdPrim, skel: &Skeleton) -> Result<SkelAnimation, UsdaError> {
    if prim.type_name != "SkelAnimation" {
        return Err(UsdaError::prim(
            &skel.prim,
            format!(
                "skel:animationSource of '{}' names '{}' (line {}), a '{}', not a SkelAnimation",
                skel.prim, prim.path, prim.line, prim.type_name
            ),
        ));
    }
    let need = |what: &str| {
        UsdaError::prim(
            &prim.path,
            format!(
                "SkelAnimation '{}' (line {}) has no {what}",
                prim.path, prim.line
            ),
        )
    };
    let ja = prim.attr("joints").ok_or_else(|| need("joints"))?;
    let mut joints = Vec::new();
    for name in tokens(ja)? {
        let j = skel.joint_index(&name).ok_or_else(|| {
            err(
                ja.line,
                format!(
                    "SkelAnimation '{}' animates joint '{name}', which Skeleton '{}' does not have",
                    prim.path, skel.prim
                ),
            )
        })?;
        joints.push(j);
    }
    let n = joints.len();
    let translations =
        track(prim, "translations", n, tuple_n::<3>)?.ok_or_else(|| need("translations"))?;
    let rotations = track(prim, "rotations", n, tuple_n::<4>)?.ok_or_else(|| need("rotations"))?;
    let scales = track(prim, "scales", n, tuple_n::<3>)?;
    Ok(SkelAnimation {
        prim: prim.path.clone(),
        joints,
        translations,
        rotations,
        scales,
    })
}

/// A world transform of `chain` that reads a time-sampled `xformOp` holding one value (as
/// Blender writes for a static skeleton) as that value; other animated ops are errors.
fn static_world(chain: &[&UsdPrim]) -> Result<Mat4, UsdaError> {
    let mut owned: Vec<UsdPrim> = Vec::with_capacity(chain.len());
    for p in chain {
        let mut q = UsdPrim {
            children: Vec::new(),
            ..(*p).clone()
        };
        for a in &mut q.attrs {
            if let (Some(base), Some(UsdValue::Dict(s))) =
                (a.name.strip_suffix(".timeSamples"), &a.value)
            {
                if base.starts_with("xformOp:") && !s.is_empty() && s.iter().all(|x| x.1 == s[0].1)
                {
                    a.value = Some(s[0].1.clone());
                    a.name = base.to_string();
                }
            }
        }
        owned.push(q);
    }
    let refs: Vec<&UsdPrim> = owned.iter().collect();
    world_transform(&refs)
}

/// The skinning binding of the mesh at the end of `chain` with `nv` points, or `None` when the
/// mesh (and its ancestors) bind no skeleton. `points_to_mesh` is the transform the loader
/// applied to the points (folded into the geom bind transform); with `world` set the skinned
/// points come back in world space (the Skeleton prim's world transform).
pub fn read_binding(
    layer: &UsdLayer,
    chain: &[&UsdPrim],
    nv: usize,
    points_to_mesh: Option<&Mat4>,
    world: bool,
) -> Result<Option<SkinBinding>, UsdaError> {
    let prim = chain[chain.len() - 1];
    let Some((_, rel)) = inherited_rel(chain, "skel:skeleton") else {
        return Ok(None);
    };
    let target = rel_target(rel)?;
    let schain = chain_to(layer, &target).ok_or_else(|| {
        err(
            rel.line,
            format!(
                "skel:skeleton of '{}' names '{target}', which does not exist",
                prim.path
            ),
        )
    })?;
    let skeleton = skeleton_from_chain(layer, &schain)?;
    let here = |what: String| {
        UsdaError::prim(
            &prim.path,
            format!("Mesh '{}' (line {}) {what}", prim.path, prim.line),
        )
    };
    let ia = prim.attr("primvars:skel:jointIndices").ok_or_else(|| {
        here("is bound to a skeleton but has no primvars:skel:jointIndices".into())
    })?;
    let wa = prim.attr("primvars:skel:jointWeights").ok_or_else(|| {
        here("is bound to a skeleton but has no primvars:skel:jointWeights".into())
    })?;
    let (k, idx, w) = influences(prim, ia, wa, nv)?;
    let joint_indices = skeleton_joint_indices(chain, &skeleton, ia, &idx)?;
    let mut geom_bind = match prim.attr("primvars:skel:geomBindTransform") {
        Some(a) => {
            let v = a
                .value
                .as_ref()
                .ok_or_else(|| err(a.line, "geomBindTransform has no value"))?;
            matrix(v, a.line, &a.name)?
        }
        None => Mat4::identity(),
    };
    if let Some(m) = points_to_mesh {
        let inv = m.try_inverse().ok_or_else(|| {
            here("has a singular transform; load it with transform off to skin it".into())
        })?;
        geom_bind = inv * geom_bind;
    }
    let skel_to_world = if world {
        static_world(&schain).map_err(|e| {
            UsdaError::prim(
                &skeleton.prim,
                format!("the transform of Skeleton '{}': {e} (load with transform off to skin in skeleton space)", skeleton.prim),
            )
        })?
    } else {
        Mat4::identity()
    };
    Ok(Some(SkinBinding {
        prim: prim.path.clone(),
        skeleton: Arc::new(skeleton),
        influences: k,
        joint_indices,
        joint_weights: w,
        geom_bind: to_rows(&geom_bind),
        skel_to_world: to_rows(&skel_to_world),
    }))
}

/// A skinning primvar's `elementSize` (influences per point), 1 when not authored.
fn skin_element_size(a: &UsdAttr) -> Result<usize, UsdaError> {
    match a.meta.iter().find(|(k, _)| k == "elementSize") {
        None => Ok(1),
        Some((_, UsdValue::Num(n))) if *n >= 1.0 && n.fract() == 0.0 && *n < 1e6 => Ok(*n as usize),
        Some((_, v)) => Err(err(a.line, format!("bad elementSize {v:?}"))),
    }
}

/// Whether a primvar's interpolation is `constant` (one value for every point).
fn is_constant(a: &UsdAttr) -> bool {
    a.meta.iter().any(|(k, v)| {
        k == "interpolation"
            && matches!(v, UsdValue::Str(s) | UsdValue::Ident(s) if s == "constant")
    })
}

/// The influences per point `k` and the joint indices and weights of the `nv` points
/// (`k` each, constant interpolation broadcast), checked against each other.
fn influences(
    prim: &UsdPrim,
    ia: &UsdAttr,
    wa: &UsdAttr,
    nv: usize,
) -> Result<(usize, Vec<i64>, Vec<f64>), UsdaError> {
    let k = skin_element_size(ia)?;
    if skin_element_size(wa)? != k {
        return Err(err(
            wa.line,
            format!(
                "jointWeights has elementSize {} but jointIndices has {k}",
                skin_element_size(wa)?
            ),
        ));
    }
    let mut idx = ints(ia)?;
    let mut w = floats(wa)?;
    if idx.len() != w.len() {
        return Err(err(
            wa.line,
            format!(
                "'{}' has {} jointWeights but {} jointIndices",
                prim.path,
                w.len(),
                idx.len()
            ),
        ));
    }
    let want = if is_constant(ia) { k } else { nv * k };
    if idx.len() != want {
        return Err(err(
            ia.line,
            format!(
                "jointIndices has {} values; {} points with elementSize {k} need {want}",
                idx.len(),
                if is_constant(ia) { 1 } else { nv }
            ),
        ));
    }
    if is_constant(ia) {
        idx = idx.repeat(nv);
        w = w.repeat(nv);
    }
    Ok((k, idx, w))
}

/// The skeleton joint of each influence: the mesh's own joint order (`skel:joints`, inherited)
/// maps its indices onto the skeleton's; each index is checked against that order.
fn skeleton_joint_indices(
    chain: &[&UsdPrim],
    skeleton: &Skeleton,
    ia: &UsdAttr,
    idx: &[i64],
) -> Result<Vec<u32>, UsdaError> {
    // The mesh's own joint order (`skel:joints`) maps its indices onto the skeleton's.
    let map: Option<Vec<usize>> = match inherited_rel(chain, "skel:joints") {
        None => None,
        Some((_, a)) => Some(
            tokens(a)?
                .iter()
                .map(|t| {
                    skeleton.joint_index(t).ok_or_else(|| {
                        err(
                            a.line,
                            format!(
                                "skel:joints names '{t}', which Skeleton '{}' does not have",
                                skeleton.prim
                            ),
                        )
                    })
                })
                .collect::<Result<_, _>>()?,
        ),
    };
    let nj = map.as_ref().map_or(skeleton.joints.len(), |m| m.len());
    let mut joint_indices = Vec::with_capacity(idx.len());
    for (i, &j) in idx.iter().enumerate() {
        if j < 0 || j as usize >= nj {
            return Err(err(
                ia.line,
                format!(
                    "jointIndices[{i}] = {j} is out of range: Skeleton '{}' has {nj} joints",
                    skeleton.prim
                ),
            ));
        }
        let j = map.as_ref().map_or(j as usize, |m| m[j as usize]);
        joint_indices.push(j as u32);
    }
    Ok(joint_indices)
}
