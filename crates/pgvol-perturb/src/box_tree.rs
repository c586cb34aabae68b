//! A bounding-volume hierarchy over axis-aligned boxes: a point query visits only the boxes
//! that contain it, so evaluating a field of many local terms costs the terms that reach the
//! point, not all of them. (The mesh BVH of `pgvol-sdf` holds triangles and is out of reach of
//! this crate, which the file reader depends on.)

use glam::Vec3;

const LEAF_SIZE: usize = 4;

#[derive(Clone, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: the first item and the count. Inner: `count == 0`, the left child follows the
    /// node and `start` is the right child.
    start: u32,
    count: u32,
}

/// Boxes by index, for point queries.
#[derive(Clone, Debug, Default)]
pub struct BoxTree {
    nodes: Vec<Node>,
    items: Vec<u32>,
    /// The boxes in `items` order, so a leaf tests its boxes without an indirection.
    item_boxes: Vec<(Vec3, Vec3)>,
}

impl BoxTree {
    /// The tree over `boxes` (`(lo, hi)` each), split at the median centre along the longest
    /// axis of the centres' box.
    pub fn build(boxes: &[(Vec3, Vec3)]) -> Self {
        let mut items: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len() / LEAF_SIZE + 1);
        if !boxes.is_empty() {
            build_node(boxes, &mut items, 0, &mut nodes);
        }
        let item_boxes = items.iter().map(|&i| boxes[i as usize]).collect();
        Self {
            nodes,
            items,
            item_boxes,
        }
    }

    /// Calls `visit` with every box index whose box contains `p`.
    pub fn for_each_containing(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let index = stack[top] as usize;
            let node = &self.nodes[index];
            if p.cmplt(node.lo).any() || p.cmpgt(node.hi).any() {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                let range = s..s + node.count as usize;
                for (&item, (lo, hi)) in self.items[range.clone()]
                    .iter()
                    .zip(&self.item_boxes[range])
                {
                    if p.cmpge(*lo).all() && p.cmple(*hi).all() {
                        visit(item);
                    }
                }
            } else {
                stack[top] = node.start;
                stack[top + 1] = index as u32 + 1;
                top += 2;
            }
        }
    }
}

fn build_node(boxes: &[(Vec3, Vec3)], items: &mut [u32], first: usize, nodes: &mut Vec<Node>) {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (mut clo, mut chi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in items.iter() {
        let (a, b) = boxes[i as usize];
        lo = lo.min(a);
        hi = hi.max(b);
        let c = (a + b) * 0.5;
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let index = nodes.len();
    nodes.push(Node {
        lo,
        hi,
        start: first as u32,
        count: items.len() as u32,
    });
    // The depth stays below the query stack's 64 entries: each split halves the items.
    if items.len() <= LEAF_SIZE {
        return;
    }
    let axis = (chi - clo).max_position();
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |&a, &b| {
        let ca = boxes[a as usize].0[axis] + boxes[a as usize].1[axis];
        let cb = boxes[b as usize].0[axis] + boxes[b as usize].1[axis];
        ca.total_cmp(&cb)
    });
    let (left, right) = items.split_at_mut(mid);
    build_node(boxes, left, first, nodes);
    let right_index = nodes.len() as u32;
    build_node(boxes, right, first + mid, nodes);
    nodes[index].count = 0;
    nodes[index].start = right_index;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_find_exactly_the_containing_boxes() {
        let mut s = 3u64;
        let mut r = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let boxes: Vec<(Vec3, Vec3)> = (0..500)
            .map(|_| {
                let c = Vec3::new(r(), r(), r());
                let h = Vec3::new(r(), r(), r()) * 0.1;
                (c - h, c + h)
            })
            .collect();
        let tree = BoxTree::build(&boxes);
        for _ in 0..300 {
            let p = Vec3::new(r(), r(), r());
            let mut found = Vec::new();
            tree.for_each_containing(p, |i| found.push(i));
            found.sort_unstable();
            let expected: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| {
                    let (a, b) = boxes[i as usize];
                    p.cmpge(a).all() && p.cmple(b).all()
                })
                .collect();
            assert_eq!(found, expected);
        }
    }
}
