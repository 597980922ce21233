//! Framework3D's buffer nodes: `buffer_decompose2`/`buffer_decompose3` split a list of
//! 2-/3-vectors into coordinate lists, `buffer_compose2`/`buffer_compose3` zip them back
//! (used by imported graphs, e.g. "vertex X, Y become texcoords").

use crate::prelude::*;

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

/// Registers the buffer nodes.
pub fn register(r: &mut Registry) {
    reg_decompose::<2>(r, "buffer_decompose2");
    reg_decompose::<3>(r, "buffer_decompose3");
    reg_compose::<2>(r, "buffer_compose2");
    reg_compose::<3>(r, "buffer_compose3");
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
