//! Geometric nested dissection: a fill-reducing elimination order for the sparse Cholesky
//! factorization of mesh Laplacians (George 1973, "Nested dissection of a regular finite
//! element mesh"; coordinate bisection as in Heath and Raghavan 1995).
//!
//! The vertices are split at the median of their widest coordinate; the vertices of one half
//! that touch the other half form a separator, ordered last; both halves are ordered
//! recursively first. The factor has more entries than with approximate minimum degree, but
//! the order costs one `select_nth` per level instead of a degree-update graph elimination,
//! and the two top-level halves, having no edge between them, can be factored on two cores
//! (`TwoDomainFactor`). faer still does all the factorization work.

/// Below this many unknowns AMD is cheap enough and nested dissection is not used.
pub const ND_MIN_ROWS: usize = 4000;

/// A nested-dissection elimination order and its top-level split.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Dissection {
    /// The `k`-th entry is the vertex eliminated `k`-th.
    pub order: Vec<usize>,
    /// Sizes of the two halves the first split made: `order` holds the first half, then the
    /// second, then the separator between them (no edge joins the two halves). `None` when
    /// the graph was not split.
    pub halves: Option<[usize; 2]>,
}

/// Elimination order (the `k`-th entry is the vertex eliminated `k`-th) of the graph with
/// symmetric adjacency in compressed rows (`adj_start`, `adj`), from the vertex coordinates.
/// Subsets of at most `leaf` vertices keep their input order.
pub fn nested_dissection_order(
    adj_start: &[usize],
    adj: &[u32],
    coords: &[[f64; 3]],
    leaf: usize,
) -> Vec<usize> {
    nested_dissection(adj_start, adj, coords, leaf).order
}

/// `nested_dissection_order` with the sizes of the top-level halves, which can be factored
/// independently (`TwoDomainFactor`).
pub fn nested_dissection(
    adj_start: &[usize],
    adj: &[u32],
    coords: &[[f64; 3]],
    leaf: usize,
) -> Dissection {
    let n = coords.len();
    let mut verts: Vec<u32> = (0..n as u32).collect();
    let mut label = vec![0u32; n];
    let mut next_label = 1u32;
    let mut order = Vec::with_capacity(n);
    let halves = dissect(
        &mut verts,
        adj_start,
        adj,
        coords,
        leaf.max(1),
        &mut label,
        &mut next_label,
        &mut order,
    );
    Dissection { order, halves }
}

#[allow(clippy::too_many_arguments)]
fn dissect(
    verts: &mut [u32],
    adj_start: &[usize],
    adj: &[u32],
    coords: &[[f64; 3]],
    leaf: usize,
    label: &mut [u32],
    next_label: &mut u32,
    order: &mut Vec<usize>,
) -> Option<[usize; 2]> {
    if verts.len() <= leaf {
        order.extend(verts.iter().map(|&v| v as usize));
        return None;
    }
    // widest axis
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &v in verts.iter() {
        let c = coords[v as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mid = verts.len() / 2;
    verts.select_nth_unstable_by(mid, |&a, &b| {
        coords[a as usize][axis].total_cmp(&coords[b as usize][axis])
    });
    // label the right half, then move left vertices touching it to the end of the left half
    let right_label = *next_label;
    *next_label += 1;
    for &v in &verts[mid..] {
        label[v as usize] = right_label;
    }
    let (left, right) = verts.split_at_mut(mid);
    let mut keep = 0;
    for k in 0..left.len() {
        let v = left[k] as usize;
        let touches = adj[adj_start[v]..adj_start[v + 1]]
            .iter()
            .any(|&u| label[u as usize] == right_label);
        if !touches {
            left.swap(keep, k);
            keep += 1;
        }
    }
    let (inner, sep) = left.split_at_mut(keep);
    let sep: Vec<u32> = sep.to_vec();
    // relabel so that later checks in sub-problems never see stale labels
    for &v in right.iter() {
        label[v as usize] = 0;
    }
    let halves =
        if inner.is_empty() || right.is_empty() || sep.len() * 2 > verts_len(inner, right, &sep) {
            // no useful split (tiny or degenerate geometry): keep the input order
            order.extend(inner.iter().chain(right.iter()).map(|&v| v as usize));
            None
        } else {
            let halves = [inner.len(), right.len()];
            dissect(
                inner, adj_start, adj, coords, leaf, label, next_label, order,
            );
            dissect(
                right, adj_start, adj, coords, leaf, label, next_label, order,
            );
            Some(halves)
        };
    order.extend(sep.iter().map(|&v| v as usize));
    halves
}

fn verts_len(a: &[u32], b: &[u32], c: &[u32]) -> usize {
    a.len() + b.len() + c.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_is_a_permutation_with_the_top_separator_last() {
        // 20 x 20 grid graph
        let m = 20;
        let id = |i: usize, j: usize| j * m + i;
        let mut start = vec![0usize];
        let mut adj = Vec::new();
        let mut coords = Vec::new();
        for j in 0..m {
            for i in 0..m {
                coords.push([i as f64, j as f64 * 0.9, 0.0]);
                if i > 0 {
                    adj.push(id(i - 1, j) as u32);
                }
                if i + 1 < m {
                    adj.push(id(i + 1, j) as u32);
                }
                if j > 0 {
                    adj.push(id(i, j - 1) as u32);
                }
                if j + 1 < m {
                    adj.push(id(i, j + 1) as u32);
                }
                start.push(adj.len());
            }
        }
        let Dissection { order: ord, halves } = nested_dissection(&start, &adj, &coords, 8);
        // the halves are the columns left and right of i = 9, so no edge joins them
        assert_eq!(halves, Some([9 * m, 10 * m]));
        assert!(ord[..9 * m].iter().all(|&v| v % m < 9));
        assert!(ord[9 * m..19 * m].iter().all(|&v| v % m > 9));
        let mut seen = ord.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..m * m).collect::<Vec<_>>());
        // widest axis is x: the last 20 vertices eliminated form the column i = 9
        let last: Vec<usize> = ord[ord.len() - m..].iter().map(|&v| v % m).collect();
        assert!(last.iter().all(|&i| i == 9), "{last:?}");
    }
}
