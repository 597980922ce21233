//! Typed access to parsed USDA values (numbers, integer arrays, tuple arrays) and prim lookup
//! by path, with errors that name the attribute's line. Shared by every schema reader.

use super::error::UsdaError;
use super::layer::{UsdAttr, UsdLayer, UsdPrim, UsdValue};
use super::lexer::err;

/// A number value.
pub fn num(v: &UsdValue, line: usize) -> Result<f64, UsdaError> {
    match v {
        UsdValue::Num(x) => Ok(*x),
        other => Err(err(line, format!("expected a number, found {other:?}"))),
    }
}

/// An attribute's array value (refusing time samples).
pub fn list(a: &UsdAttr) -> Result<&[UsdValue], UsdaError> {
    match &a.value {
        Some(UsdValue::List(v)) => Ok(v),
        Some(UsdValue::Dict(_)) => Err(err(
            a.line,
            format!(
                "'{}' is animated (timeSamples); only static meshes are supported",
                a.name
            ),
        )),
        Some(other) => Err(err(
            a.line,
            format!("'{}' should be an array, found {other:?}", a.name),
        )),
        None => Err(err(a.line, format!("'{}' has no value", a.name))),
    }
}

/// Refuses an animated (`.timeSamples`) attribute.
pub fn check_time_samples(a: &UsdAttr) -> Result<(), UsdaError> {
    if a.name.ends_with(".timeSamples") {
        return Err(err(
            a.line,
            format!("'{}' is animated; only static meshes are supported", a.name),
        ));
    }
    Ok(())
}

/// An integer array attribute.
pub fn ints(a: &UsdAttr) -> Result<Vec<i64>, UsdaError> {
    list(a)?
        .iter()
        .map(|v| {
            let x = num(v, a.line)?;
            if x.fract() != 0.0 {
                return Err(err(a.line, format!("'{}' holds non-integer {x}", a.name)));
            }
            // Past 2^53 a double no longer holds every integer, and `as i64` would saturate
            // 1e300 to i64::MAX without a word (issue 23).
            const EXACT: f64 = 9_007_199_254_740_992.0;
            if x.abs() > EXACT {
                return Err(err(
                    a.line,
                    format!(
                        "'{}' holds {x}, beyond the exact integers of a double",
                        a.name
                    ),
                ));
            }
            Ok(x as i64)
        })
        .collect()
}

/// An `N`-tuple of numbers.
pub fn tuple_n<const N: usize>(
    v: &UsdValue,
    line: usize,
    name: &str,
) -> Result<[f64; N], UsdaError> {
    match v {
        UsdValue::Tuple(t) if t.len() == N => {
            let mut out = [0.0; N];
            for (o, x) in out.iter_mut().zip(t) {
                *o = num(x, line)?;
            }
            Ok(out)
        }
        other => Err(err(
            line,
            format!("'{name}' expects {N}-tuples, found {other:?}"),
        )),
    }
}

/// An array-of-`N`-tuples attribute (`point3f[]`, `texCoord2f[]`, ...).
pub fn tuples<const N: usize>(a: &UsdAttr) -> Result<Vec<[f64; N]>, UsdaError> {
    list(a)?
        .iter()
        .map(|v| tuple_n::<N>(v, a.line, &a.name))
        .collect()
}

/// A number array attribute.
pub fn floats(a: &UsdAttr) -> Result<Vec<f64>, UsdaError> {
    list(a)?.iter().map(|v| num(v, a.line)).collect()
}

/// `path` made absolute (a leading `/` added); empty stays empty.
pub fn absolute_path(path: &str) -> String {
    if path.is_empty() || path.starts_with('/') {
        path.to_string()
    } else {
        format!("/{path}")
    }
}

/// The first prim, depth first in file order, for which `want` holds, with its ancestors:
/// root first, the prim itself last.
pub fn find_prim_chain<'a>(
    layer: &'a UsdLayer,
    want: &dyn Fn(&UsdPrim) -> bool,
) -> Option<Vec<&'a UsdPrim>> {
    fn walk<'a>(
        p: &'a UsdPrim,
        chain: &mut Vec<&'a UsdPrim>,
        want: &dyn Fn(&UsdPrim) -> bool,
    ) -> bool {
        chain.push(p);
        if want(p) {
            return true;
        }
        for c in &p.children {
            if walk(c, chain, want) {
                return true;
            }
        }
        chain.pop();
        false
    }
    let mut chain = Vec::new();
    for p in &layer.prims {
        if walk(p, &mut chain, want) {
            return Some(chain);
        }
    }
    None
}

/// Paths of every prim of schema type `type_name` (e.g. `Mesh`, `Skeleton`), depth first.
pub fn prim_paths_of_type(layer: &UsdLayer, type_name: &str) -> Vec<String> {
    fn walk(p: &UsdPrim, type_name: &str, out: &mut Vec<String>) {
        if p.type_name == type_name {
            out.push(p.path.clone());
        }
        for c in &p.children {
            walk(c, type_name, out);
        }
    }
    let mut out = Vec::new();
    for p in &layer.prims {
        walk(p, type_name, &mut out);
    }
    out
}

/// Paths of every `Mesh` prim in the layer.
pub fn mesh_paths(layer: &UsdLayer) -> Vec<String> {
    prim_paths_of_type(layer, "Mesh")
}
