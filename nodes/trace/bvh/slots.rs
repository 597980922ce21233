//! Which binary subtrees become the children of each 8-wide node (`wide::collapse`):
//! chosen by dynamic programming over the binary tree to minimise the wide tree's cost by
//! the surface area heuristic (Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray
//! Traversal on GPUs Through Compressed Wide BVHs", section 4.1), rather than by opening,
//! node by node, the child of largest area until eight remain, which left many nodes near
//! the leaves with two children.

use super::{BvhNode, W};

/// Cost of a node step relative to a leaf test (the lane loop's instructions for each:
/// about 60 and 110).
const C_NODE: f32 = 1.0;
/// Cost of a leaf test (one to four triangles on four lanes cost about the same).
const C_LEAF: f32 = 1.8;

/// Per binary node (root first, children at `first` and `first + 1` after their parent):
/// the first triangle below it and how many there are.
pub(super) fn subtrees(nodes: &[BvhNode]) -> Vec<(u32, u32)> {
    let mut under = vec![(0u32, 0u32); nodes.len()];
    // Children come after their parent, so a backward pass sees them first.
    for k in (0..nodes.len()).rev() {
        let n = &nodes[k];
        under[k] = if n.count > 0 {
            (n.first, n.count)
        } else {
            let (l, r) = (under[n.first as usize], under[n.first as usize + 1]);
            (l.0, l.1 + r.1)
        };
    }
    under
}

/// The solved program: per binary node, the least cost of its subtree spread over at most
/// `j` children of a wide node, and how.
pub(super) struct Slots {
    /// `cost[n][j]`, j in 1..=W.
    cost: Vec<[f32; W + 1]>,
    /// `split[n][j]`: 0 when j - 1 children do as well, else the children the left
    /// subtree takes (the right one takes the rest).
    split: Vec<[u8; W + 1]>,
    /// Per binary node made a wide node: the children its left subtree takes of the W
    /// (at least one); 0 for a wide leaf (at most four triangles below it).
    wide_split: Vec<u8>,
}

impl Slots {
    /// Solves the program for the binary tree `nodes`, `under` its `subtrees`.
    pub(super) fn solve(nodes: &[BvhNode], under: &[(u32, u32)]) -> Slots {
        let n = nodes.len();
        let mut s = Slots {
            cost: vec![[0.0; W + 1]; n],
            split: vec![[0; W + 1]; n],
            wide_split: vec![0; n],
        };
        for k in (0..n).rev() {
            let area = nodes[k].bounds.half_area().max(0.0);
            if under[k].1 <= 4 {
                s.cost[k] = [area * C_LEAF; W + 1];
                continue;
            }
            let (l, r) = (nodes[k].first as usize, nodes[k].first as usize + 1);
            // dist[j]: both subtrees over j children in all.
            let mut dist = [f32::INFINITY; W + 1];
            let mut arg = [0u8; W + 1];
            for j in 2..=W {
                for kl in 1..j {
                    let c = s.cost[l][kl] + s.cost[r][j - kl];
                    if c < dist[j] {
                        dist[j] = c;
                        arg[j] = kl as u8;
                    }
                }
            }
            // One child: a wide node of its own over the W children.
            s.cost[k][1] = area * C_NODE + dist[W];
            s.wide_split[k] = arg[W];
            for j in 2..=W {
                if dist[j] < s.cost[k][j - 1] {
                    s.cost[k][j] = dist[j];
                    s.split[k][j] = arg[j];
                } else {
                    s.cost[k][j] = s.cost[k][j - 1];
                }
            }
        }
        s
    }

    /// Whether binary node `k` becomes a wide leaf.
    pub(super) fn is_leaf(&self, k: usize) -> bool {
        self.wide_split[k] == 0
    }

    /// The binary nodes that become the children of the wide node made for binary node
    /// `k` (not a leaf), left to right.
    pub(super) fn children(&self, nodes: &[BvhNode], k: usize) -> Vec<usize> {
        let mut out = Vec::with_capacity(W);
        let (l, r) = (nodes[k].first as usize, nodes[k].first as usize + 1);
        let kl = self.wide_split[k] as usize;
        self.place(nodes, l, kl, &mut out);
        self.place(nodes, r, W - kl, &mut out);
        out
    }

    /// Places the subtree of binary node `k` in at most `j` children.
    fn place(&self, nodes: &[BvhNode], k: usize, mut j: usize, out: &mut Vec<usize>) {
        if self.is_leaf(k) {
            out.push(k);
            return;
        }
        loop {
            if j == 1 {
                out.push(k);
                return;
            }
            match self.split[k][j] as usize {
                0 => j -= 1,
                kl => {
                    let (l, r) = (nodes[k].first as usize, nodes[k].first as usize + 1);
                    self.place(nodes, l, kl, out);
                    self.place(nodes, r, j - kl, out);
                    return;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::Bvh;
    use crate::sampling::{Pcg32, V3};

    fn area(nodes: &[BvhNode], k: usize) -> f32 {
        nodes[k].bounds.half_area().max(0.0)
    }

    /// Every way to cover the triangles below binary node `k` with at most `max` subtrees.
    fn frontiers(nodes: &[BvhNode], c: &[u32], k: usize, max: usize) -> Vec<Vec<usize>> {
        let mut out = vec![vec![k]];
        if c[k] <= 4 || max < 2 {
            return out;
        }
        let (l, r) = (nodes[k].first as usize, nodes[k].first as usize + 1);
        for fl in frontiers(nodes, c, l, max - 1) {
            for fr in frontiers(nodes, c, r, max - fl.len()) {
                out.push(fl.iter().chain(&fr).copied().collect());
            }
        }
        out
    }

    /// The least cost of a wide node made for binary node `k`, by trying every choice of
    /// children at every level.
    fn brute_node(nodes: &[BvhNode], c: &[u32], k: usize) -> f32 {
        let (l, r) = (nodes[k].first as usize, nodes[k].first as usize + 1);
        let mut best = f32::INFINITY;
        for fl in frontiers(nodes, c, l, W - 1) {
            for fr in frontiers(nodes, c, r, W - fl.len()) {
                let kids = fl.iter().chain(&fr).map(|&f| {
                    if c[f] <= 4 {
                        area(nodes, f) * C_LEAF
                    } else {
                        brute_node(nodes, c, f)
                    }
                });
                best = best.min(area(nodes, k) * C_NODE + kids.sum::<f32>());
            }
        }
        best
    }

    /// The cost of the wide tree `children` builds below binary node `k`.
    fn built(s: &Slots, nodes: &[BvhNode], k: usize) -> f32 {
        let kids = s.children(nodes, k);
        assert!(kids.len() <= W);
        let sum: f32 = kids
            .iter()
            .map(|&f| {
                if s.is_leaf(f) {
                    area(nodes, f) * C_LEAF
                } else {
                    built(s, nodes, f)
                }
            })
            .sum();
        area(nodes, k) * C_NODE + sum
    }

    #[test]
    fn children_are_the_least_cost_choice() {
        for (n, seed) in [(20, 1), (45, 2), (70, 3)] {
            let mut r = Pcg32::new(seed, 7);
            // Clusters of triangles at several scales, so that the choices differ.
            let tris: Vec<[V3; 3]> = (0..n)
                .map(|i| {
                    let s = [0.05, 0.5, 3.0][i % 3];
                    let c = [r.next_f32() * 8.0, r.next_f32() * 2.0, r.next_f32() * 4.0];
                    let mut p = || c.map(|x| x + (r.next_f32() - 0.5) * s);
                    [p(), p(), p()]
                })
                .collect();
            let bvh = Bvh::build(&tris);
            let under = subtrees(&bvh.nodes);
            let c: Vec<u32> = under.iter().map(|u| u.1).collect();
            assert!(c[0] > 4);
            let s = Slots::solve(&bvh.nodes, &under);
            let dp = s.cost[0][1];
            let brute = brute_node(&bvh.nodes, &c, 0);
            let tree = built(&s, &bvh.nodes, 0);
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs());
            assert!(
                close(dp, brute),
                "{n} triangles: program {dp}, every choice {brute}"
            );
            assert!(close(tree, dp), "{n} triangles: built {tree}, program {dp}");
        }
    }
}
