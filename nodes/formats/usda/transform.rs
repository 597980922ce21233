//! `xformOp` transforms (USD row-vector convention, `p_world = p * M_local * M_parent ...`):
//! the local matrix of a prim from its `xformOpOrder`, the world matrix of an ancestor chain,
//! and applying it to points and normals.

use super::access::{list, num, tuple_n};
use super::error::UsdaError;
use super::layer::{UsdPrim, UsdValue};
use super::lexer::err;
use nalgebra::{Matrix3, Matrix4, RowVector3, RowVector4};

/// A 4x4 transform in USD's row-vector convention: `m[(i, j)]` is row `i`, column `j` of the
/// matrix as written in the file, and a point transforms as `p' = p * m`.
pub type Mat4 = Matrix4<f64>;

/// A `matrix4d` value (four 4-tuples), rows as written.
pub fn matrix(v: &UsdValue, line: usize, name: &str) -> Result<Mat4, UsdaError> {
    match v {
        UsdValue::Tuple(rows) if rows.len() == 4 => {
            let mut m = Mat4::zeros();
            for (r, row) in rows.iter().enumerate() {
                let t = tuple_n::<4>(row, line, name)?;
                for (c, x) in t.into_iter().enumerate() {
                    m[(r, c)] = x;
                }
            }
            Ok(m)
        }
        other => Err(err(
            line,
            format!("'{name}' expects a 4x4 matrix, found {other:?}"),
        )),
    }
}

/// Row-vector rotation about axis `k` by `deg` degrees (USD `xformOp:rotateX/Y/Z`).
pub fn rotation(k: usize, deg: f64) -> Mat4 {
    let (s, c) = deg.to_radians().sin_cos();
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let mut m = Mat4::identity();
    // p' = p * M: the column-vector rotation transposed.
    m[(i, i)] = c;
    m[(i, j)] = s;
    m[(j, i)] = -s;
    m[(j, j)] = c;
    m
}

/// The local transform of a prim from its `xformOpOrder` (row vectors: the first op in the
/// order applies last, `M = op_n * ... * op_1`).
pub fn local_transform(p: &UsdPrim) -> Result<Mat4, UsdaError> {
    let Some(order) = p.attr("xformOpOrder") else {
        if let Some(a) = p.attrs.iter().find(|a| a.name.starts_with("xformOp:")) {
            return Err(err(
                a.line,
                format!("'{}' is set but '{}' has no xformOpOrder", a.name, p.path),
            ));
        }
        return Ok(Mat4::identity());
    };
    let mut m = Mat4::identity();
    for op in list(order)? {
        let (UsdValue::Str(name) | UsdValue::Ident(name)) = op else {
            return Err(err(order.line, "xformOpOrder expects op names"));
        };
        let a = p.attr(name).ok_or_else(|| {
            err(
                order.line,
                format!("xformOpOrder names '{name}' but the prim has no such attribute"),
            )
        })?;
        let v = a
            .value
            .as_ref()
            .ok_or_else(|| err(a.line, format!("'{name}' has no value")))?;
        if matches!(v, UsdValue::Dict(_)) {
            return Err(err(
                a.line,
                format!("'{name}' is animated; only static transforms are supported"),
            ));
        }
        let kind = name.strip_prefix("xformOp:").unwrap_or("");
        let kind = kind.split(':').next().unwrap_or("");
        let op_m = match kind {
            "transform" => matrix(v, a.line, name)?,
            "translate" => {
                let t = tuple_n::<3>(v, a.line, name)?;
                let mut m = Mat4::identity();
                for k in 0..3 {
                    m[(3, k)] = t[k];
                }
                m
            }
            "scale" => {
                let s = tuple_n::<3>(v, a.line, name)?;
                let mut m = Mat4::identity();
                for k in 0..3 {
                    m[(k, k)] = s[k];
                }
                m
            }
            "rotateX" | "rotateY" | "rotateZ" => {
                let k = (kind.as_bytes()[6] - b'X') as usize;
                rotation(k, num(v, a.line)?)
            }
            "rotateXYZ" => {
                // Rotate about X first, then Y, then Z.
                let r = tuple_n::<3>(v, a.line, name)?;
                rotation(0, r[0]) * rotation(1, r[1]) * rotation(2, r[2])
            }
            _ => {
                return Err(err(
                    a.line,
                    format!("transform op '{name}' is not supported (transform, translate, scale, rotateX/Y/Z, rotateXYZ are)"),
                ))
            }
        };
        m = op_m * m;
    }
    Ok(m)
}

/// The world transform of the last prim of `chain` (root first): its local transform, then
/// each ancestor's (`world = local(prim) * local(parent) * ...`).
pub fn world_transform(chain: &[&UsdPrim]) -> Result<Mat4, UsdaError> {
    let mut m = Mat4::identity();
    for p in chain {
        // prepend each deeper prim
        m = local_transform(p)? * m;
    }
    Ok(m)
}

/// Transforms points as row vectors, `p' = (p, 1) * m`, dividing by `w` when it is neither
/// 1 nor 0.
pub fn transform_points(m: &Mat4, positions: &mut [[f64; 3]]) {
    for p in positions.iter_mut() {
        let o = RowVector4::new(p[0], p[1], p[2], 1.0) * m;
        let mut o = [o[0], o[1], o[2], o[3]];
        let wh = o[3];
        if wh != 1.0 && wh != 0.0 {
            for x in o.iter_mut().take(3) {
                *x /= wh;
            }
        }
        *p = [o[0], o[1], o[2]];
    }
}

/// Transforms normals by the inverse transpose of `m`'s linear part and renormalizes them;
/// `None` when that part is singular.
pub fn transform_normals(m: &Mat4, normals: &mut [[f64; 3]]) -> Option<()> {
    let a: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let inv_t = a.try_inverse()?.transpose();
    for v in normals.iter_mut() {
        // row vector n' = n * (A^-1)^T
        let r = RowVector3::new(v[0], v[1], v[2]) * inv_t;
        let len = r.norm();
        *v = if len > 0.0 {
            [r[0] / len, r[1] / len, r[2] / len]
        } else {
            [r[0], r[1], r[2]]
        };
    }
    Some(())
}
