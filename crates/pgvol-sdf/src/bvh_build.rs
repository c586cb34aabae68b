//! Builds a binary tree over boxes by the surface area heuristic, binned, top-down.
//!
//! The tree is written straight into the layout the queries walk ([`Node`]): node 0 is the
//! root, an inner node's children sit side by side after it, and a leaf names a run of the
//! returned order. Its working memory is one box per triangle and one index per triangle, so
//! the build's peak is a third of a PLOC builder's, which keeps per-cluster arrays beside the
//! finished tree.

use glam::Vec3A;

/// One node: a box and either two children (`count == 0`, children at `first` and `first + 1`)
/// or `count` items starting at `first` in leaf order.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    pub min: Vec3A,
    pub max: Vec3A,
    pub first: u32,
    pub count: u32,
}

impl Node {
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn distance_squared(&self, p: Vec3A) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3A::ZERO);
        d.length_squared()
    }
}

/// Candidate split planes per axis, between `BINS` bins of the centroids' extent.
const BINS: usize = 16;

/// Ranges with more triangles than this are split on two threads and bin in parallel chunks.
const PARALLEL_RANGE: usize = 1 << 15;

/// Below this depth, ranges are split at the median centre along their longest axis instead of
/// by the heuristic, which may peel off a few items at a time (items spaced geometrically): the
/// tree's depth stays under this plus the log of the item count, so neither the build's
/// recursion nor the queries' stacks grow with hostile input.
pub const HEURISTIC_DEPTH: usize = 48;

/// A box per item: `[min, max]`.
pub type ItemBox = [Vec3A; 2];

/// The built tree: its nodes (leaves index `order`) and the items in leaf order.
pub struct Tree {
    pub nodes: Vec<Node>,
    pub order: Vec<u32>,
}

/// The cost of visiting an inner node, against 1 for testing one item. A leaf is kept whole
/// while testing all its items costs no more than splitting it would.
#[derive(Clone, Copy, Debug)]
pub struct Costs {
    pub traversal: f32,
    /// Leaves hold at most this many items.
    pub max_leaf: usize,
}

/// The tree over `boxes` (an empty tree for no boxes). Deterministic: the same boxes give the
/// same tree on any number of threads.
pub fn build(boxes: &[ItemBox], costs: Costs) -> Tree {
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    if boxes.is_empty() {
        return Tree {
            nodes: Vec::new(),
            order,
        };
    }
    let bounds = bounds_of(boxes, &order);
    let nodes = subtree(boxes, &mut order, 0, 0, bounds, costs);
    Tree { nodes, order }
}

/// The subtree over `ids`, which start at `offset` in the leaf order, its root at `depth`: its
/// root first, child indices relative to the returned nodes.
fn subtree(
    boxes: &[ItemBox],
    ids: &mut [u32],
    offset: u32,
    depth: usize,
    bounds: Bounds,
    costs: Costs,
) -> Vec<Node> {
    if ids.len() > PARALLEL_RANGE {
        if let Some((left_len, left, right)) = choose_split(boxes, ids, depth, bounds, costs) {
            let (l_ids, r_ids) = ids.split_at_mut(left_len);
            let right_offset = offset + left_len as u32;
            let (l, r) = rayon::join(
                || subtree(boxes, l_ids, offset, depth + 1, left, costs),
                || subtree(boxes, r_ids, right_offset, depth + 1, right, costs),
            );
            return joined(bounds, l, r);
        }
    }
    let mut nodes = Vec::with_capacity(2 * ids.len().div_ceil(costs.max_leaf.max(1)));
    nodes.push(leaf(bounds, offset, ids.len()));
    let at = Place {
        offset,
        node: 0,
        depth,
    };
    grow(boxes, ids, at, bounds, costs, &mut nodes);
    nodes
}

/// Where a range sits: its first place in the leaf order, its node, its depth.
#[derive(Clone, Copy)]
struct Place {
    offset: u32,
    node: usize,
    depth: usize,
}

/// A parent over two finished subtrees: the parent, both roots, then the rest of each.
fn joined(bounds: Bounds, left: Vec<Node>, right: Vec<Node>) -> Vec<Node> {
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node {
        min: bounds.min,
        max: bounds.max,
        first: 1,
        count: 0,
    });
    // The roots take slots 1 and 2, so the rest of the left subtree starts at 3 and of the
    // right one after it.
    let (l_shift, r_shift) = (2, 1 + left.len() as u32);
    let moved = |n: &Node, shift: u32| Node {
        first: if n.is_leaf() {
            n.first
        } else {
            n.first + shift
        },
        ..*n
    };
    nodes.push(moved(&left[0], l_shift));
    nodes.push(moved(&right[0], r_shift));
    nodes.extend(left[1..].iter().map(|n| moved(n, l_shift)));
    nodes.extend(right[1..].iter().map(|n| moved(n, r_shift)));
    nodes
}

/// Splits the leaf at `nodes[at.node]` (over `ids`) while the heuristic says so, depth first.
fn grow(
    boxes: &[ItemBox],
    ids: &mut [u32],
    at: Place,
    bounds: Bounds,
    costs: Costs,
    nodes: &mut Vec<Node>,
) {
    let Some((left_len, left, right)) = choose_split(boxes, ids, at.depth, bounds, costs) else {
        return;
    };
    let child = nodes.len();
    nodes[at.node].first = child as u32;
    nodes[at.node].count = 0;
    let right_offset = at.offset + left_len as u32;
    nodes.push(leaf(left, at.offset, left_len));
    nodes.push(leaf(right, right_offset, ids.len() - left_len));
    let (l_ids, r_ids) = ids.split_at_mut(left_len);
    let depth = at.depth + 1;
    let l_at = Place {
        offset: at.offset,
        node: child,
        depth,
    };
    let r_at = Place {
        offset: right_offset,
        node: child + 1,
        depth,
    };
    grow(boxes, l_ids, l_at, left, costs, nodes);
    grow(boxes, r_ids, r_at, right, costs, nodes);
}

fn leaf(bounds: Bounds, first: u32, count: usize) -> Node {
    Node {
        min: bounds.min,
        max: bounds.max,
        first,
        count: count as u32,
    }
}

#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    fn grow(&mut self, other: Bounds) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    /// Half the surface area (the heuristic compares ratios only).
    fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

fn bounds_of(boxes: &[ItemBox], ids: &[u32]) -> Bounds {
    let mut b = Bounds::EMPTY;
    for &i in ids {
        let [min, max] = boxes[i as usize];
        b.grow(Bounds { min, max });
    }
    b
}

fn centre(b: &ItemBox) -> Vec3A {
    (b[0] + b[1]) * 0.5
}

/// Per axis and bin, the items' count and bounds.
#[derive(Clone, Copy)]
struct Bins {
    count: [[u32; BINS]; 3],
    bounds: [[Bounds; BINS]; 3],
}

impl Bins {
    fn empty() -> Bins {
        Bins {
            count: [[0; BINS]; 3],
            bounds: [[Bounds::EMPTY; BINS]; 3],
        }
    }

    fn add(&mut self, bin: [usize; 3], b: Bounds) {
        for (axis, &at) in bin.iter().enumerate() {
            self.count[axis][at] += 1;
            self.bounds[axis][at].grow(b);
        }
    }

    fn merged(mut self, other: &Bins) -> Bins {
        for axis in 0..3 {
            for bin in 0..BINS {
                self.count[axis][bin] += other.count[axis][bin];
                self.bounds[axis][bin].grow(other.bounds[axis][bin]);
            }
        }
        self
    }
}

/// Maps centres to bins along each axis; an axis where all centres coincide has none.
#[derive(Clone, Copy)]
struct Binning {
    min: Vec3A,
    scale: Vec3A,
}

impl Binning {
    fn bin(&self, c: Vec3A) -> [usize; 3] {
        let f = ((c - self.min) * self.scale).max(Vec3A::ZERO);
        [f.x, f.y, f.z].map(|v| (v as usize).min(BINS - 1))
    }
}

/// The best split of `ids` by the heuristic, partitioning them in place: the left part's
/// length and both parts' bounds. `None` keeps them as one leaf.
fn choose_split(
    boxes: &[ItemBox],
    ids: &mut [u32],
    depth: usize,
    bounds: Bounds,
    costs: Costs,
) -> Option<(usize, Bounds, Bounds)> {
    let n = ids.len();
    if n <= 1 {
        return None;
    }
    let centres = centre_bounds(boxes, ids);
    let extent = centres.max - centres.min;
    if depth >= HEURISTIC_DEPTH {
        if n <= costs.max_leaf {
            return None;
        }
        // The median along the longest axis; ties are broken by id, so the split is the same
        // on every run.
        let axis = extent.max_position();
        let half = n / 2;
        let key = |i: &u32| centre(&boxes[*i as usize])[axis];
        ids.select_nth_unstable_by(half, |a, b| key(a).total_cmp(&key(b)).then(a.cmp(b)));
        let (l, r) = ids.split_at(half);
        return Some((half, bounds_of(boxes, l), bounds_of(boxes, r)));
    }
    let scale = Vec3A::select(
        extent.cmpgt(Vec3A::ZERO),
        Vec3A::splat(BINS as f32 * (1.0 - 1e-6)) / extent,
        Vec3A::ZERO,
    );
    if scale == Vec3A::ZERO {
        // Every centre in one point: no plane separates them, so halve the run as it stands.
        if n <= costs.max_leaf {
            return None;
        }
        let half = n / 2;
        let (l, r) = ids.split_at(half);
        return Some((half, bounds_of(boxes, l), bounds_of(boxes, r)));
    }
    let binning = Binning {
        min: centres.min,
        scale,
    };
    let bins = binned(boxes, ids, binning);
    // Sweep each axis from the right, then from the left, keeping the cheapest plane.
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if scale[axis] == 0.0 {
            continue;
        }
        let mut right_area = [0.0f32; BINS];
        let mut acc = Bounds::EMPTY;
        for bin in (1..BINS).rev() {
            acc.grow(bins.bounds[axis][bin]);
            right_area[bin] = acc.half_area();
        }
        let (mut left, mut left_count, mut right_count) = (Bounds::EMPTY, 0u32, n as u32);
        for (bin, &right_area) in right_area.iter().enumerate().skip(1) {
            left.grow(bins.bounds[axis][bin - 1]);
            left_count += bins.count[axis][bin - 1];
            right_count -= bins.count[axis][bin - 1];
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = left.half_area() * left_count as f32 + right_area * right_count as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, bin));
            }
        }
    }
    let (cost, axis, split_bin) = best?;
    let split_cost = costs.traversal + cost / bounds.half_area().max(f32::MIN_POSITIVE);
    if n <= costs.max_leaf && n as f32 <= split_cost {
        return None;
    }
    let goes_left = |i: &u32| binning.bin(centre(&boxes[*i as usize]))[axis] < split_bin;
    let left_len = partition(ids, goes_left);
    let (mut left, mut right) = (Bounds::EMPTY, Bounds::EMPTY);
    for bin in 0..BINS {
        let side = if bin < split_bin {
            &mut left
        } else {
            &mut right
        };
        side.grow(bins.bounds[axis][bin]);
    }
    Some((left_len, left, right))
}

fn centre_bounds(boxes: &[ItemBox], ids: &[u32]) -> Bounds {
    let of = |ids: &[u32]| {
        let mut b = Bounds::EMPTY;
        for &i in ids {
            let c = centre(&boxes[i as usize]);
            b.grow(Bounds { min: c, max: c });
        }
        b
    };
    if ids.len() <= PARALLEL_RANGE {
        return of(ids);
    }
    use rayon::prelude::*;
    ids.par_chunks(PARALLEL_RANGE / 4).map(of).reduce(
        || Bounds::EMPTY,
        |mut a, b| {
            a.grow(b);
            a
        },
    )
}

fn binned(boxes: &[ItemBox], ids: &[u32], binning: Binning) -> Bins {
    let of = |ids: &[u32]| {
        let mut bins = Bins::empty();
        for &i in ids {
            let b = &boxes[i as usize];
            bins.add(
                binning.bin(centre(b)),
                Bounds {
                    min: b[0],
                    max: b[1],
                },
            );
        }
        bins
    };
    if ids.len() <= PARALLEL_RANGE {
        return of(ids);
    }
    use rayon::prelude::*;
    // Counts add and bounds take minima and maxima, so chunks merge to the serial answer.
    ids.par_chunks(PARALLEL_RANGE / 4)
        .map(of)
        .reduce(Bins::empty, |a, b| a.merged(&b))
}

/// Moves the ids for which `left` holds to the front, returning how many there are.
fn partition(ids: &mut [u32], left: impl Fn(&u32) -> bool) -> usize {
    let (mut i, mut j) = (0, ids.len());
    while i < j {
        if left(&ids[i]) {
            i += 1;
        } else {
            j -= 1;
            ids.swap(i, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    const COSTS: Costs = Costs {
        traversal: 6.0,
        max_leaf: 8,
    };

    fn random_boxes(n: usize, seed: u64) -> Vec<ItemBox> {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let c = Vec3A::new(rng.gen(), rng.gen(), rng.gen()) * 10.0;
                let h = Vec3A::new(rng.gen(), rng.gen(), rng.gen()) * 0.2;
                [c - h, c + h]
            })
            .collect()
    }

    /// Checks the layout the queries rely on and returns the tree's depth: every item in
    /// exactly one leaf of 1 to `max_leaf` items, children after their parent, and every
    /// node's box the union of its items' boxes.
    fn check(tree: &Tree, boxes: &[ItemBox], costs: Costs) -> usize {
        let mut order = tree.order.clone();
        order.sort_unstable();
        assert_eq!(order, (0..boxes.len() as u32).collect::<Vec<_>>());
        if boxes.is_empty() {
            assert!(tree.nodes.is_empty());
            return 0;
        }
        let mut covered = vec![0u32; boxes.len()];
        let mut deepest = 0;
        let mut stack = vec![(0usize, 0usize)];
        // Returns each subtree's box so the parent can compare.
        fn union(tree: &Tree, boxes: &[ItemBox], id: usize) -> Bounds {
            let n = &tree.nodes[id];
            let mut b = Bounds::EMPTY;
            if n.is_leaf() {
                for &i in &tree.order[n.first as usize..(n.first + n.count) as usize] {
                    let [min, max] = boxes[i as usize];
                    b.grow(Bounds { min, max });
                }
            } else {
                for child in [n.first as usize, n.first as usize + 1] {
                    let c = &tree.nodes[child];
                    b.grow(Bounds {
                        min: c.min,
                        max: c.max,
                    });
                }
            }
            b
        }
        while let Some((id, depth)) = stack.pop() {
            deepest = deepest.max(depth);
            let n = tree.nodes[id];
            let b = union(tree, boxes, id);
            assert_eq!((n.min, n.max), (b.min, b.max), "node {id}'s box");
            if n.is_leaf() {
                assert!(n.count as usize <= costs.max_leaf, "a leaf of {}", n.count);
                for slot in n.first..n.first + n.count {
                    covered[slot as usize] += 1;
                }
            } else {
                assert!(
                    n.first as usize > id,
                    "children before their parent at {id}"
                );
                stack.push((n.first as usize, depth + 1));
                stack.push((n.first as usize + 1, depth + 1));
            }
        }
        assert!(
            covered.iter().all(|&c| c == 1),
            "a slot in no leaf or in two"
        );
        deepest
    }

    #[test]
    fn every_item_lies_in_one_small_leaf_under_boxes_that_hold_it() {
        // Sizes on both sides of the parallel split, and the degenerate small ones.
        for n in [0, 1, 2, 8, 9, 1000, 3 * PARALLEL_RANGE] {
            let boxes = random_boxes(n, n as u64);
            let tree = build(&boxes, COSTS);
            let depth = check(&tree, &boxes, COSTS);
            assert!(
                depth <= 2 * (n.max(2).ilog2() as usize) + 2,
                "depth {depth} for {n}"
            );
        }
    }

    #[test]
    fn items_at_one_point_are_halved_into_leaves() {
        let b = [Vec3A::splat(1.0), Vec3A::splat(2.0)];
        let boxes = vec![b; 100];
        let tree = build(&boxes, COSTS);
        check(&tree, &boxes, COSTS);
        assert!(tree.nodes.iter().filter(|n| n.is_leaf()).count() >= 100 / 8);
    }

    #[test]
    fn geometric_spacing_keeps_the_depth_bounded() {
        // Each box 1.1 times farther out than the last: the heuristic would peel them off a
        // few at a time, a chain as deep as there are items.
        let boxes: Vec<ItemBox> = (0..900)
            .map(|i| {
                let x = 1.1f32.powi(i);
                [Vec3A::new(x, 0.0, 0.0), Vec3A::new(x * 1.01, 1.0, 1.0)]
            })
            .collect();
        let tree = build(&boxes, COSTS);
        let depth = check(&tree, &boxes, COSTS);
        assert!(
            depth > 12,
            "the spacing no longer stresses the heuristic: depth {depth}"
        );
        assert!(depth <= HEURISTIC_DEPTH + 10 + 1, "depth {depth}");
    }

    #[test]
    fn the_tree_is_the_same_on_one_thread_and_on_two() {
        let boxes = random_boxes(3 * PARALLEL_RANGE, 9);
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| build(&boxes, COSTS))
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(one.order, two.order);
        let key = |t: &Tree| {
            t.nodes
                .iter()
                .map(|n| (n.min.to_array(), n.max.to_array(), n.first, n.count))
                .collect::<Vec<_>>()
        };
        assert_eq!(key(&one), key(&two));
    }
}
