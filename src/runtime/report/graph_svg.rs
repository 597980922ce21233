//! The graph drawn as SVG for the run report, without Graphviz: a layered layout (Sugiyama
//! et al. 1981, first step only) where a node's layer is the length of the longest path
//! reaching it, so every link goes left to right, as `cgnodes dot` draws with `rankdir=LR`.
//! Nodes are boxes coloured by their status in the run; links are cubic curves labelled with
//! the output and input sockets on hover (`<title>`).

use super::{esc, Status};
use crate::validate::{InputSource, ValidGraph};

const BOX_W: f64 = 170.0;
const BOX_H: f64 = 46.0;
const GAP_X: f64 = 60.0;
const GAP_Y: f64 = 18.0;

/// Layer of each node (in the graph's topological order): 0 for nodes that read from none,
/// else one more than the largest layer among the nodes it reads from.
pub fn layers(g: &ValidGraph) -> Vec<usize> {
    let mut l = vec![0usize; g.nodes.len()];
    for (i, n) in g.nodes.iter().enumerate() {
        l[i] = n
            .deps
            .iter()
            .filter(|&&d| d < i)
            .map(|&d| l[d] + 1)
            .max()
            .unwrap_or(0);
    }
    l
}

/// The graph as an SVG element: `status(i)` gives node `i`'s status in the run.
pub fn graph_svg(g: &ValidGraph, status: &dyn Fn(usize) -> Status) -> String {
    let layer = layers(g);
    let mut row = vec![0usize; g.nodes.len()];
    let mut count = vec![0usize; layer.iter().max().map_or(0, |m| m + 1)];
    for (i, &l) in layer.iter().enumerate() {
        row[i] = count[l];
        count[l] += 1;
    }
    let rows = count.iter().copied().max().unwrap_or(0);
    let pos = |i: usize| {
        (
            10.0 + layer[i] as f64 * (BOX_W + GAP_X),
            10.0 + row[i] as f64 * (BOX_H + GAP_Y),
        )
    };
    let width = 20.0 + count.len() as f64 * (BOX_W + GAP_X) - GAP_X;
    let height = 20.0 + rows as f64 * (BOX_H + GAP_Y) - GAP_Y;
    let mut s = format!(
        "<svg class=\"graph\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{height:.0}\" viewBox=\"0 0 {width:.0} {height:.0}\" font-family=\"sans-serif\" font-size=\"12\">\n"
    );
    for (i, n) in g.nodes.iter().enumerate() {
        for (socket, src) in &n.inputs {
            if let InputSource::Links(ls) = src {
                for (from, out) in ls {
                    let (x0, y0) = pos(*from);
                    let (x1, y1) = pos(i);
                    let (ax, ay) = (x0 + BOX_W, y0 + BOX_H / 2.0);
                    let (bx, by) = (x1, y1 + BOX_H / 2.0);
                    let c = (bx - ax) / 2.0;
                    s.push_str(&format!(
                        "<path d=\"M{ax:.1},{ay:.1} C{:.1},{ay:.1} {:.1},{by:.1} {bx:.1},{by:.1}\" fill=\"none\" stroke=\"#667\" stroke-width=\"1.3\"><title>{}.{} -&gt; {}.{}</title></path>\n",
                        ax + c,
                        bx - c,
                        esc(&g.nodes[*from].id),
                        esc(out),
                        esc(&n.id),
                        esc(socket)
                    ));
                }
            }
        }
    }
    for (i, n) in g.nodes.iter().enumerate() {
        let (x, y) = pos(i);
        let st = status(i);
        s.push_str(&format!(
            "<g class=\"node {}\" data-node=\"{}\"><title>{} ({}): {}</title><rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"{BOX_W}\" height=\"{BOX_H}\" rx=\"6\" fill=\"{}\" stroke=\"#334\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-weight=\"bold\">{}</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" fill=\"#334\">{}</text></g>\n",
            st.name(),
            esc(&n.id),
            esc(&n.id),
            esc(&n.decl.type_name),
            st.name(),
            st.color(),
            x + BOX_W / 2.0,
            y + 19.0,
            esc(&clip(&n.id, 24)),
            x + BOX_W / 2.0,
            y + 36.0,
            esc(&clip(&n.decl.type_name, 26)),
        ));
    }
    s.push_str("</svg>\n");
    s
}

/// `s` cut to `n` characters with an ellipsis.
fn clip(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        s.chars().take(n - 1).chain(std::iter::once('…')).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_follow_the_longest_path_and_boxes_get_their_status() {
        let text = r#"{"format": "cgnodes-graph", "version": 1, "nodes": {
            "a": {"type": "value_float", "params": {"value": 1}},
            "b": {"type": "math", "inputs": {"a": "a.value"}},
            "c": {"type": "math", "inputs": {"a": "a.value", "b": "b.value"}}}}"#;
        let g = crate::graph::parse(
            text,
            std::path::Path::new("t.json"),
            std::path::Path::new("."),
        )
        .unwrap();
        let v = crate::validate::validate(&g, &crate::test_registry()).unwrap();
        let l = layers(&v);
        let at = |id: &str| l[v.index[id]];
        assert_eq!((at("a"), at("b"), at("c")), (0, 1, 2));
        let svg = graph_svg(&v, &|i| {
            if v.nodes[i].id == "c" {
                Status::Failed
            } else {
                Status::Ran
            }
        });
        assert_eq!(svg.matches("class=\"node failed\"").count(), 1);
        assert_eq!(svg.matches("class=\"node ran\"").count(), 2);
        assert_eq!(svg.matches("<path").count(), 3);
    }
}
