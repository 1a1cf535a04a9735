//! Nested dissection of the block graph (one node per block) by breadth-first level sets, the
//! fill-reducing ordering the sparse path can use instead of faer's minimum degree
//! (`SparseOrdering::BlockDissection`, docs/contact-solve.md §20).
//!
//! The separator of a connected part is the middle level of a breadth-first search from a
//! pseudo-peripheral block (George and Liu's automatic nested dissection): on the planar
//! contact graph of a 2D assembly a level is a "cut" across the part, O(√n) blocks wide, which
//! is what gives nested dissection its O(n^1.5) factorization work in 2D. No geometry needed.

/// Order the `n` nodes of the undirected graph `adj` (neighbours per node; self-loops and
/// duplicates allowed) by nested dissection: each part's two halves first, its separator
/// last. Parts of at most `leaf` nodes (and parts whose level structure is too shallow to
/// cut) are ordered by `order_leaf`, which gets the part's nodes and returns them in
/// elimination order. Returns the nodes in elimination order (a permutation of 0..n).
pub fn nested_dissection(
    adj: &[Vec<usize>],
    leaf: usize,
    order_leaf: &mut dyn FnMut(&[usize]) -> Vec<usize>,
) -> Vec<usize> {
    let n = adj.len();
    let mut ws = Workspace {
        part: vec![0; n],
        level: vec![usize::MAX; n],
        next_part: 1,
    };
    let mut order = Vec::with_capacity(n);
    let all: Vec<usize> = (0..n).collect();
    dissect(adj, &all, leaf.max(1), order_leaf, &mut ws, &mut order);
    order
}

/// Per node: the id of the part it currently belongs to, and its breadth-first level (scratch).
struct Workspace {
    part: Vec<usize>,
    level: Vec<usize>,
    next_part: usize,
}

impl Workspace {
    fn new_part(&mut self, nodes: &[usize]) -> usize {
        let id = self.next_part;
        self.next_part += 1;
        for &v in nodes {
            self.part[v] = id;
        }
        id
    }

    /// Breadth-first levels from `root` within part `id`; returns the nodes reached in order
    /// and the depth (number of levels). Leaves `level` set for the reached nodes.
    fn bfs(&mut self, adj: &[Vec<usize>], root: usize, id: usize) -> (Vec<usize>, usize) {
        let mut queue = vec![root];
        self.level[root] = 0;
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head];
            head += 1;
            for &w in &adj[v] {
                if self.part[w] == id && self.level[w] == usize::MAX {
                    self.level[w] = self.level[v] + 1;
                    queue.push(w);
                }
            }
        }
        let depth = queue.last().map_or(0, |&v| self.level[v] + 1);
        (queue, depth)
    }

    fn clear_levels(&mut self, nodes: &[usize]) {
        for &v in nodes {
            self.level[v] = usize::MAX;
        }
    }
}

/// Degree of `v` within part `id` (for the choice of the pseudo-peripheral root).
fn degree_in(adj: &[Vec<usize>], v: usize, id: usize, part: &[usize]) -> usize {
    adj[v].iter().filter(|&&w| w != v && part[w] == id).count()
}

/// Pseudo-peripheral root searches (each a breadth-first search of the part): the level
/// structure's depth stops growing after two or three on mesh-like graphs.
const ROOT_SEARCHES: usize = 4;

fn dissect(
    adj: &[Vec<usize>],
    nodes: &[usize],
    leaf: usize,
    order_leaf: &mut dyn FnMut(&[usize]) -> Vec<usize>,
    ws: &mut Workspace,
    order: &mut Vec<usize>,
) {
    if nodes.len() <= leaf {
        order.extend(order_leaf(nodes));
        return;
    }
    let id = ws.new_part(nodes);
    // Connected components first: each is dissected on its own.
    let (reached, _) = ws.bfs(adj, nodes[0], id);
    if reached.len() < nodes.len() {
        let rest: Vec<usize> = nodes
            .iter()
            .copied()
            .filter(|&v| ws.level[v] == usize::MAX)
            .collect();
        ws.clear_levels(&reached);
        dissect(adj, &reached, leaf, order_leaf, ws, order);
        dissect(adj, &rest, leaf, order_leaf, ws, order);
        return;
    }
    // A pseudo-peripheral root: restart from a smallest-degree node of the last level while
    // the depth grows.
    let (mut levels, mut depth) = (reached, 0);
    if let Some(&v) = levels.last() {
        depth = ws.level[v] + 1;
    }
    for _ in 0..ROOT_SEARCHES {
        let last = ws.level[*levels.last().unwrap_or(&nodes[0])];
        let root = levels
            .iter()
            .copied()
            .filter(|&v| ws.level[v] == last)
            .min_by_key(|&v| degree_in(adj, v, id, &ws.part))
            .unwrap_or(nodes[0]);
        ws.clear_levels(&levels);
        let (l, d) = ws.bfs(adj, root, id);
        let grew = d > depth;
        (levels, depth) = (l, d);
        if !grew {
            break;
        }
    }
    if depth < 3 {
        ws.clear_levels(&levels);
        order.extend(order_leaf(nodes));
        return;
    }
    // The separator level: the first level at which half the nodes have been reached; kept to
    // its nodes that touch the next level (the others join the first half).
    let cut = ws.level[levels[levels.len() / 2]].clamp(1, depth - 2);
    let (mut first, mut second, mut separator) = (Vec::new(), Vec::new(), Vec::new());
    for &v in &levels {
        let l = ws.level[v];
        if l < cut {
            first.push(v);
        } else if l > cut {
            second.push(v);
        } else if adj[v]
            .iter()
            .any(|&w| ws.part[w] == id && ws.level[w] == cut + 1)
        {
            separator.push(v);
        } else {
            first.push(v);
        }
    }
    ws.clear_levels(&levels);
    dissect(adj, &first, leaf, order_leaf, ws, order);
    dissect(adj, &second, leaf, order_leaf, ws, order);
    // The separator's own blocks form a dense front; order them as a leaf.
    order.extend(order_leaf(&separator));
}

/// Order the nodes of `adj` by nested dissection with straight cuts: each part is split at
/// the median of its longer coordinate extent (`position`, one point per node), the separator
/// being the nodes of the upper side that touch the lower side; halves first, separator last.
/// On a 2D mesh a straight cut is as short as a separator gets (a King's-move grid of k × k
/// blocks: k blocks, where a breadth-first level from a corner is an L of about 1.4 k).
/// Parts of at most `leaf` nodes, and separators, are ordered by `order_leaf`.
pub fn coordinate_dissection(
    adj: &[Vec<usize>],
    position: &[[f64; 2]],
    leaf: usize,
    order_leaf: &mut dyn FnMut(&[usize]) -> Vec<usize>,
) -> Vec<usize> {
    let n = adj.len();
    let mut side = vec![0u8; n];
    let mut order = Vec::with_capacity(n);
    let all: Vec<usize> = (0..n).collect();
    cut(
        adj,
        position,
        &all,
        leaf.max(2),
        order_leaf,
        &mut side,
        &mut order,
    );
    order
}

/// Node marks of `cut`: 0 outside the part being cut, 1 lower side, 2 upper side.
fn cut(
    adj: &[Vec<usize>],
    position: &[[f64; 2]],
    nodes: &[usize],
    leaf: usize,
    order_leaf: &mut dyn FnMut(&[usize]) -> Vec<usize>,
    side: &mut [u8],
    order: &mut Vec<usize>,
) {
    if nodes.len() <= leaf {
        order.extend(order_leaf(nodes));
        return;
    }
    let extent = |axis: usize| {
        let (lo, hi) = nodes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(position[v][axis]), hi.max(position[v][axis]))
            });
        hi - lo
    };
    let axis = if extent(0) >= extent(1) { 0 } else { 1 };
    let mut sorted = nodes.to_vec();
    sorted.sort_by(|&a, &b| position[a][axis].total_cmp(&position[b][axis]));
    let (lower, upper) = sorted.split_at(sorted.len() / 2);
    for &v in lower {
        side[v] = 1;
    }
    for &v in upper {
        side[v] = 2;
    }
    let (mut rest, mut separator) = (Vec::new(), Vec::new());
    for &v in upper {
        if adj[v].iter().any(|&w| side[w] == 1) {
            separator.push(v);
        } else {
            rest.push(v);
        }
    }
    for &v in nodes {
        side[v] = 0;
    }
    if rest.is_empty() {
        // Nothing left above the cut (a part one node wide across its longer extent).
        order.extend(order_leaf(nodes));
        return;
    }
    let lower = lower.to_vec();
    cut(adj, position, &lower, leaf, order_leaf, side, order);
    cut(adj, position, &rest, leaf, order_leaf, side, order);
    order.extend(order_leaf(&separator));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A w×h grid graph (4-neighbour), node (i, j) = j·w + i.
    fn grid(w: usize, h: usize) -> Vec<Vec<usize>> {
        let mut adj = vec![Vec::new(); w * h];
        for j in 0..h {
            for i in 0..w {
                let v = j * w + i;
                if i + 1 < w {
                    adj[v].push(v + 1);
                    adj[v + 1].push(v);
                }
                if j + 1 < h {
                    adj[v].push(v + w);
                    adj[v + w].push(v);
                }
            }
        }
        adj
    }

    /// Σ over the columns of the Cholesky factor of c² (c the column count), by symbolic
    /// elimination on the graph in the given order: the factorization work, up to a constant.
    fn factor_work(adj: &[Vec<usize>], order: &[usize]) -> f64 {
        use std::collections::BTreeSet;
        let n = adj.len();
        let mut pos = vec![0; n];
        for (k, &v) in order.iter().enumerate() {
            pos[v] = k;
        }
        let mut sets: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
        for v in 0..n {
            for &w in &adj[v] {
                if pos[w] > pos[v] {
                    sets[pos[v]].insert(pos[w]);
                }
            }
        }
        let mut work = 0.0;
        for k in 0..n {
            let s = std::mem::take(&mut sets[k]);
            let c = s.len() as f64 + 1.0;
            work += c * c;
            if let Some(&parent) = s.iter().next() {
                for &w in s.iter().skip(1) {
                    sets[parent].insert(w);
                }
            }
        }
        work
    }

    /// A permutation of the nodes, and on a 40×40 grid far less fill than the natural
    /// (banded) order: nested dissection's work grows as n^1.5, the band's as n²; the band of
    /// width 40 costs about 1600·41² ≈ 2.7e6, dissection about 3× less (measured 4e5–6e5 on
    /// grids this size; the bound 2× leaves room for the separator choice).
    #[test]
    fn dissection_of_a_grid_is_a_permutation_with_less_fill_than_the_band() {
        let (w, h) = (40, 40);
        let adj = grid(w, h);
        let order = nested_dissection(&adj, 8, &mut |p| p.to_vec());
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..w * h).collect::<Vec<_>>());
        let natural: Vec<usize> = (0..w * h).collect();
        let (nd, band) = (factor_work(&adj, &order), factor_work(&adj, &natural));
        assert!(2.0 * nd < band, "dissection {nd:.3e} vs band {band:.3e}");
    }

    /// The straight cuts on a 40 × 40 King's-move grid (each node coupled to its 8 neighbours,
    /// as the pile's aligned blocks meeting corner to corner): a permutation, with less than
    /// half the band's work and no more than the level-set dissection's (a breadth-first level
    /// from a corner of a King's-move grid is an L, about 1.4× a straight cut; on the 4-neighbour
    /// grid the levels are diagonals that cost less, so the comparison is for this graph).
    #[test]
    fn coordinate_dissection_of_a_grid() {
        let (w, h) = (40, 40);
        let mut adj = grid(w, h);
        for j in 0..h - 1 {
            for i in 0..w {
                let v = j * w + i;
                if i + 1 < w {
                    adj[v].push(v + w + 1);
                    adj[v + w + 1].push(v);
                }
                if i > 0 {
                    adj[v].push(v + w - 1);
                    adj[v + w - 1].push(v);
                }
            }
        }
        let position: Vec<[f64; 2]> = (0..w * h)
            .map(|v| [(v % w) as f64, (v / w) as f64])
            .collect();
        let order = coordinate_dissection(&adj, &position, 8, &mut |p| p.to_vec());
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..w * h).collect::<Vec<_>>());
        let natural: Vec<usize> = (0..w * h).collect();
        let levels = nested_dissection(&adj, 8, &mut |p| p.to_vec());
        let (nd, band, bfs) = (
            factor_work(&adj, &order),
            factor_work(&adj, &natural),
            factor_work(&adj, &levels),
        );
        assert!(2.0 * nd < band, "dissection {nd:.3e} vs band {band:.3e}");
        assert!(nd <= bfs, "straight cuts {nd:.3e} vs level sets {bfs:.3e}");
    }

    /// Disconnected parts (two grids side by side, isolated nodes) are each ordered whole.
    #[test]
    fn disconnected_parts_are_all_ordered() {
        let mut adj = grid(10, 10);
        let off = adj.len();
        for v in grid(7, 3) {
            adj.push(v.into_iter().map(|w| w + off).collect());
        }
        adj.push(Vec::new());
        let order = nested_dissection(&adj, 4, &mut |p| p.to_vec());
        let mut seen = order;
        seen.sort_unstable();
        assert_eq!(seen, (0..adj.len()).collect::<Vec<_>>());
    }
}
