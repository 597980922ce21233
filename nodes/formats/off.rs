//! Object File Format (`.off`, Geomview): `OFF`, counts, vertices, then polygons as
//! `n i1 ... in` (trailing face colours are ignored).

use cgnodes_api::prelude::*;
use std::io::Write;

/// Why OFF text is not a mesh: the line at fault where there is one.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OffError {
    /// No non-comment line.
    #[error("empty file")]
    Empty,
    /// The header ends before the counts.
    #[error("missing vertex/face counts")]
    NoCounts,
    /// A malformed line.
    #[error("line {line}: {message}")]
    Line {
        /// The 1-based line.
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// The file ends before the declared vertices or faces.
    #[error("file ends after {read} of {declared} {what}")]
    EndsEarly {
        /// Items read.
        read: usize,
        /// Items the header declares.
        declared: usize,
        /// "vertices" or "faces".
        what: &'static str,
    },
    /// The faces do not make a valid mesh (`Mesh::new`).
    #[error("{0}")]
    Mesh(String),
}

/// An `OffError` at line `line`.
fn at(line: usize, message: String) -> OffError {
    OffError::Line { line, message }
}

/// Reads OFF text. Errors carry the line number.
pub fn read_off(text: &str) -> Result<Mesh, OffError> {
    // Tokens with their line numbers, comments removed.
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());
    let (nv, nf) = off_header(&mut lines)?;
    // The header's counts are not trusted for allocation: a vertex line takes at least 5 bytes
    // ("0 0 0") and a face line at least 7 ("3 0 1 2"), so no file holds more than that.
    let mut positions = Vec::with_capacity(nv.min(text.len() / 5));
    for k in 0..nv {
        let (ln, l) = lines.next().ok_or(OffError::EndsEarly {
            read: k,
            declared: nv,
            what: "vertices",
        })?;
        positions.push(off_vertex(ln, l, k)?);
    }
    let mut fc = Vec::with_capacity(nf.min(text.len() / 7));
    let mut fi = Vec::with_capacity(nf.saturating_mul(3).min(text.len() / 2));
    for k in 0..nf {
        let (ln, l) = lines.next().ok_or(OffError::EndsEarly {
            read: k,
            declared: nf,
            what: "faces",
        })?;
        fc.push(off_face(ln, l, nv, &mut fi)?);
    }
    Mesh::new(positions, fc, fi).map_err(|e| OffError::Mesh(e.to_string()))
}

/// The `OFF` (or `COFF`) keyword and the vertex and face counts after it, on its line or the
/// next.
fn off_header<'a>(
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
) -> Result<(usize, usize), OffError> {
    let (ln, head) = lines.next().ok_or(OffError::Empty)?;
    let rest_of_head = if let Some(r) = head.strip_prefix("COFF") {
        r
    } else if let Some(r) = head.strip_prefix("OFF") {
        r
    } else {
        return Err(at(ln, format!("expected 'OFF', found '{head}'")));
    };
    let (ln, counts_line) = if rest_of_head.trim().is_empty() {
        lines.next().ok_or(OffError::NoCounts)?
    } else {
        (ln, rest_of_head.trim())
    };
    let counts: Vec<usize> = counts_line
        .split_whitespace()
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            at(
                ln,
                format!("expected vertex, face and edge counts, found '{counts_line}'"),
            )
        })?;
    if counts.len() < 2 {
        return Err(at(
            ln,
            format!("expected vertex, face and edge counts, found '{counts_line}'"),
        ));
    }
    Ok((counts[0], counts[1]))
}

/// Vertex `k` from its line `l` (number `ln`): three finite coordinates, extra columns
/// (colours) ignored.
fn off_vertex(ln: usize, l: &str, k: usize) -> Result<[f64; 3], OffError> {
    let v: Vec<f64> = l
        .split_whitespace()
        .map(|s| s.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| at(ln, format!("malformed vertex '{l}'")))?;
    if v.len() < 3 {
        return Err(at(ln, format!("a vertex needs 3 coordinates: '{l}'")));
    }
    if v[..3].iter().any(|x| !x.is_finite()) {
        return Err(at(
            ln,
            format!("vertex {k} has a non-finite coordinate: '{l}'"),
        ));
    }
    Ok([v[0], v[1], v[2]])
}

/// A face line `n i1 ... in`: pushes its corners onto `fi` and returns `n`, refusing faces
/// under 3 corners, indices past the `nv` vertices and repeated vertices.
fn off_face(ln: usize, l: &str, nv: usize, fi: &mut Vec<u32>) -> Result<u32, OffError> {
    let mut w = l.split_whitespace();
    let n: usize = w
        .next()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| at(ln, format!("malformed face '{l}'")))?;
    if n < 3 {
        return Err(at(ln, format!("degenerate face with {n} corners")));
    }
    let start = fi.len();
    // Repeats: a scan for small faces, a set for large ones (a scan per corner was
    // quadratic, so one line of a million indices took minutes). Not sized from `n`.
    let mut seen = std::collections::HashSet::new();
    for _ in 0..n {
        let i: usize = w
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| at(ln, format!("malformed face '{l}'")))?;
        if i >= nv {
            return Err(at(
                ln,
                format!("vertex index {i} out of range ({nv} vertices)"),
            ));
        }
        let repeated = if n > 32 {
            !seen.insert(i)
        } else {
            fi[start..].contains(&(i as u32))
        };
        if repeated {
            return Err(at(ln, format!("degenerate face, vertex {i} appears twice")));
        }
        fi.push(i as u32);
    }
    Ok(n as u32)
}

/// Writes OFF text (positions and faces only).
pub fn write_off(mesh: &Mesh, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "OFF")?;
    writeln!(w, "{} {} 0", mesh.num_vertices(), mesh.num_faces())?;
    for p in &mesh.positions {
        writeln!(w, "{} {} {}", p[0], p[1], p[2])?;
    }
    for f in mesh.faces() {
        write!(w, "{}", f.len())?;
        for v in f {
            write!(w, " {v}")?;
        }
        writeln!(w)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_square_and_reports_lines() {
        let t = "OFF\n# a square\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let m = read_off(t).unwrap();
        assert_eq!(m.face(0), &[0, 1, 2, 3]);
        let e = read_off(&t.replace("4 0 1 2 3", "4 0 1 2 9"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 8:"), "{e}");
        let e = read_off(&t.replace("1 1 0", "1 inf 0"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 6:"), "{e}");
    }

    /// Huge declared counts (issue 23: `OFF\n100000000000 0 0` aborted on allocation, and
    /// `nf * 3` could overflow) are an error about the missing data, not an abort.
    #[test]
    fn huge_header_counts_are_refused_without_allocating() {
        let e = read_off("OFF\n100000000000 0 0").unwrap_err().to_string();
        assert!(
            e.contains("file ends after 0 of 100000000000 vertices"),
            "{e}"
        );
        let e = read_off(&format!("OFF\n3 {} 0\n0 0 0\n1 0 0\n0 1 0\n", usize::MAX))
            .unwrap_err()
            .to_string();
        assert!(e.contains("file ends after 0 of"), "{e}");
    }

    /// A face line with many corners is checked for repeats in linear time, and the repeat
    /// is still reported with its line.
    #[test]
    fn repeats_in_large_faces_are_found() {
        let n = 3000;
        let mut t = format!("OFF\n{n} 1 0\n");
        for k in 0..n {
            t.push_str(&format!("{k} {} 0\n", k * k));
        }
        let mut idx: Vec<String> = (0..n).map(|k| k.to_string()).collect();
        let ok = format!("{t}{n} {}\n", idx.join(" "));
        assert_eq!(read_off(&ok).unwrap().face(0).len(), n);
        idx[n - 1] = "7".into();
        let e = read_off(&format!("{t}{n} {}\n", idx.join(" ")))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            format!("line {}: degenerate face, vertex 7 appears twice", n + 3)
        );
    }
}
