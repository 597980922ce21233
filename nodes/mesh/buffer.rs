//! Framework3D's buffer nodes: `buffer_decompose2`/`buffer_decompose3` split a list of
//! 2-/3-vectors into coordinate lists, `buffer_compose2`/`buffer_compose3` zip them back
//! (used by imported graphs, e.g. "vertex X, Y become texcoords"); `buffer_repeat`,
//! `buffer_repeat2`, `buffer_repeat3` and `buffer_repeat_int` fill a list with `size` copies
//! of one value (Framework3D's Create Buffer nodes).

use cgnodes_api::prelude::*;

/// Zips coordinate lists into vectors; all lists must have the same length.
pub fn zip<const N: usize>(cols: [&[f64]; N]) -> Result<Vec<[f64; N]>, String> {
    let n = cols[0].len();
    if let Some(k) = cols.iter().position(|c| c.len() != n) {
        return Err(format!(
            "coordinate lists differ in length: {} has {}, the first has {n}",
            ["x", "y", "z"][k],
            cols[k].len()
        ));
    }
    Ok((0..n)
        .map(|i| std::array::from_fn(|k| cols[k][i]))
        .collect())
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn reg_decompose<const N: usize>(r: &mut Registry, name: &str)
where
    [f64; N]: Typed + FromValue + Into<Value>,
{
    r.add(
        name,
        |b| {
            b.doc("Splits a list of vectors into one list per coordinate (Framework3D's buffer decompose).");
            b.add_input::<Vec<[f64; N]>>("buffer");
            for a in &AXES[..N] {
                b.add_output::<Vec<f64>>(a);
            }
            b.add_output::<i64>("size");
        },
        |ctx| {
            let v: Vec<[f64; N]> = ctx.input("buffer")?;
            for (k, a) in AXES[..N].iter().enumerate() {
                ctx.set_output(a, v.iter().map(|x| x[k]).collect::<Vec<f64>>());
            }
            ctx.set_output("size", v.len() as i64);
            Ok(())
        },
    );
}

fn reg_compose<const N: usize>(r: &mut Registry, name: &str)
where
    [f64; N]: Typed + FromValue + Into<Value>,
{
    r.add(
        name,
        |b| {
            b.doc("Zips coordinate lists into a list of vectors (Framework3D's buffer compose).");
            for a in &AXES[..N] {
                b.add_input::<Vec<f64>>(a);
            }
            b.add_output::<Vec<[f64; N]>>("buffer");
        },
        |ctx| {
            let mut cols: Vec<Vec<f64>> = Vec::new();
            for a in &AXES[..N] {
                cols.push(ctx.input(a)?);
            }
            let refs: [&[f64]; N] = std::array::from_fn(|k| cols[k].as_slice());
            let v = zip(refs).map_err(|e| NodeError::invalid("y", e))?;
            ctx.set_output("buffer", v);
            Ok(())
        },
    );
}

/// `size` copies of `value`: a constant buffer (Framework3D's `func_create_buffer*`).
pub fn repeat<T: Clone>(value: T, size: usize) -> Vec<T> {
    vec![value; size]
}

/// The largest `size` of `buffer_repeat*` (a guard against a mistyped count filling memory).
pub const MAX_REPEAT: f64 = 1e7;

/// The `size` input, checked against 0..=MAX_REPEAT (also when it arrives through a link).
fn size(ctx: &mut ExecContext) -> Result<usize, NodeError> {
    let n: i64 = ctx.input("size")?;
    usize::try_from(n)
        .ok()
        .filter(|&n| n as f64 <= MAX_REPEAT)
        .ok_or_else(|| NodeError::invalid("size", format!("{n} is outside 0..={MAX_REPEAT}")))
}

fn declare_size(b: &mut NodeBuilder) {
    b.add_input::<i64>("size")
        .default(1i64)
        .range(0.0, MAX_REPEAT)
        .doc("Number of copies.");
}

fn reg_repeat<const N: usize>(r: &mut Registry, name: &str)
where
    [f64; N]: Typed + FromValue + Into<Value>,
{
    r.add(
        name,
        |b| {
            b.doc("A list of `size` copies of one vector (Framework3D's Create Buffer).");
            for a in &AXES[..N] {
                b.add_input::<f64>(a)
                    .default(0.0)
                    .doc("Coordinate of every entry.");
            }
            declare_size(b);
            b.add_output::<Vec<[f64; N]>>("buffer");
        },
        |ctx| {
            let mut v = [0.0; N];
            for (k, a) in AXES[..N].iter().enumerate() {
                v[k] = ctx.input(a)?;
            }
            let n = size(ctx)?;
            ctx.set_output("buffer", repeat(v, n));
            Ok(())
        },
    );
}

/// Registers the buffer nodes.
pub fn register(r: &mut Registry) {
    reg_decompose::<2>(r, "buffer_decompose2");
    reg_decompose::<3>(r, "buffer_decompose3");
    reg_compose::<2>(r, "buffer_compose2");
    reg_compose::<3>(r, "buffer_compose3");
    reg_repeat::<2>(r, "buffer_repeat2");
    reg_repeat::<3>(r, "buffer_repeat3");
    r.add(
        "buffer_repeat",
        |b| {
            b.doc("A list of `size` copies of one number (Framework3D's Create Buffer1f).");
            b.add_input::<f64>("x")
                .default(0.0)
                .doc("Value of every entry.");
            declare_size(b);
            b.add_output::<Vec<f64>>("buffer");
        },
        |ctx| {
            let x: f64 = ctx.input("x")?;
            let n = size(ctx)?;
            ctx.set_output("buffer", repeat(x, n));
            Ok(())
        },
    );
    r.add(
        "buffer_repeat_int",
        |b| {
            b.doc("A list of `size` copies of one integer (Framework3D's Create Buffer1i).");
            b.add_input::<i64>("x")
                .default(0i64)
                .doc("Value of every entry.");
            declare_size(b);
            b.add_output::<Vec<i64>>("buffer");
        },
        |ctx| {
            let x: i64 = ctx.input("x")?;
            let n = size(ctx)?;
            ctx.set_output("buffer", repeat(x, n));
            Ok(())
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zip_checks_lengths() {
        assert_eq!(
            zip([&[1.0, 2.0][..], &[3.0, 4.0][..]]).unwrap(),
            vec![[1.0, 3.0], [2.0, 4.0]]
        );
        assert!(zip([&[1.0][..], &[3.0, 4.0][..]])
            .unwrap_err()
            .contains("y has 2"));
    }
}
