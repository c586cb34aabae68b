//! One brick of nodes: its geometry, the candidate leaves for its nodes' closest points, and
//! the triangles a segment inside it can cross.

use glam::{Vec3, Vec3A};

use super::carry::{bend_point, Segment};
use crate::{
    bvh::{triangle_jump, Closest},
    grid::Grid,
    sdf::MeshSdf,
};

/// Nodes `lo..hi` (exclusive) of the grid.
pub(super) struct Brick {
    pub lo: [usize; 3],
    pub hi: [usize; 3],
    /// Positions of the first and the last node.
    pub pmin: Vec3A,
    pub pmax: Vec3A,
}

impl Brick {
    pub fn new(grid: &Grid, lo: [usize; 3], hi: [usize; 3]) -> Brick {
        Brick {
            lo,
            hi,
            pmin: grid.point(lo[0], lo[1], lo[2]).into(),
            pmax: grid.point(hi[0] - 1, hi[1] - 1, hi[2] - 1).into(),
        }
    }

    pub fn centre(&self) -> Vec3A {
        (self.pmin + self.pmax) * 0.5
    }

    pub fn half_diagonal(&self) -> f32 {
        (self.pmax - self.pmin).length() * 0.5
    }

    /// Whether `p` lies in the box of the nodes.
    pub fn contains(&self, p: Vec3A) -> bool {
        p.cmpge(self.pmin).all() && p.cmple(self.pmax).all()
    }

    /// Every node with its position, x fastest.
    pub fn for_each_node(&self, grid: &Grid, mut f: impl FnMut([usize; 3], Vec3A)) {
        for k in self.lo[2]..self.hi[2] {
            for j in self.lo[1]..self.hi[1] {
                for i in self.lo[0]..self.hi[0] {
                    f([i, j, k], grid.point(i, j, k).into());
                }
            }
        }
    }
}

impl MeshSdf {
    /// The leaves that can hold the closest triangle of a node of `brick` whose distance is at
    /// most `sqrt(limit_squared)`, nearest to its centre first, given `seed`, the closest triangle to the
    /// centre. The distance to `seed`'s triangle is convex, so its largest value over the brick,
    /// at a corner, bounds every node's distance.
    pub(super) fn brick_leaves(
        &self,
        brick: &Brick,
        seed: &Closest,
        limit_squared: f32,
        leaves: &mut Vec<(f32, u32)>,
    ) {
        let bvh = self.bvh();
        let (pmin, pmax) = (brick.pmin, brick.pmax);
        let mut bound = 0.0f32;
        for c in 0..8 {
            let corner = Vec3::new(
                if c & 1 == 0 { pmin.x } else { pmax.x },
                if c & 2 == 0 { pmin.y } else { pmax.y },
                if c & 4 == 0 { pmin.z } else { pmax.z },
            );
            bound = bound.max(bvh.closest_on_slot(corner, seed.slot).distance_squared);
        }
        // The slack covers rounding in the bound.
        let bound = bound * (1.0 + 1e-4) + 1e-30;
        bvh.leaves_near_box(pmin, pmax, bound.min(limit_squared), leaves);
    }

    /// The triangles of `leaves` (from [`MeshSdf::brick_leaves`]) that meet the box of the
    /// brick's nodes: the only ones a segment between two of its nodes can cross.
    pub(super) fn brick_triangles(
        &self,
        brick: &Brick,
        leaves: &[(f32, u32)],
        out: &mut Vec<LocalTriangle>,
    ) {
        out.clear();
        let bvh = self.bvh();
        for &(_, id) in leaves {
            let node = &bvh.nodes[id as usize];
            if !(node.min.cmple(brick.pmax).all() && node.max.cmpge(brick.pmin).all()) {
                continue;
            }
            for t in bvh.leaf(node).iter() {
                let (min, max) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                if min.cmple(brick.pmax).all() && max.cmpge(brick.pmin).all() {
                    out.push(LocalTriangle {
                        corners: *t,
                        min,
                        max,
                    });
                }
            }
        }
    }
}

/// A triangle with its bounding box.
pub(super) struct LocalTriangle {
    corners: [Vec3A; 3],
    min: Vec3A,
    max: Vec3A,
}

/// Segments that start in the brick or enter it from the previous point of the row.
pub(super) struct BrickSegment<'a> {
    pub sdf: &'a MeshSdf,
    pub brick: &'a Brick,
    /// The triangles meeting the brick's box (see [`MeshSdf::brick_triangles`]).
    pub triangles: &'a [LocalTriangle],
    /// Whether the segment entering the brick is known to cross no triangle.
    pub entry_is_clear: bool,
    /// A bound on the winding number's gradient over the brick and the entering segment.
    pub gradient: f32,
}

impl Segment for BrickSegment<'_> {
    fn jump(&self, a: Vec3A, b: Vec3A) -> Option<i32> {
        if self.brick.contains(a) {
            let (lo, hi) = (a.min(b), a.max(b));
            let mut total = 0;
            for t in self.triangles {
                if t.min.cmple(hi).all() && t.max.cmpge(lo).all() {
                    total += triangle_jump(a, b, &t.corners)?;
                }
            }
            Some(total)
        } else if self.entry_is_clear {
            Some(0)
        } else {
            self.sdf.bvh().winding_jump(a.into(), b.into())
        }
    }

    fn bend(&self, a: Vec3A, b: Vec3A, side: f32) -> Option<Vec3A> {
        let m = bend_point(a, b, side);
        if self.brick.contains(a) {
            // Both legs stay in the brick, whose triangles are the only ones they can cross.
            Some(m.clamp(self.brick.pmin, self.brick.pmax))
        } else if self.entry_is_clear {
            // Only the straight entry is known to be clear (and is never unsure).
            None
        } else {
            Some(m)
        }
    }

    fn gradient(&self) -> f32 {
        self.gradient
    }
}
