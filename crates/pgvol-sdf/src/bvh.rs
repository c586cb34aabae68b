//! A bounding volume hierarchy over a mesh's triangles with nearest-first closest-point queries.
//!
//! The tree is built by the binned surface area heuristic ([`crate::bvh_build`]) straight into
//! the layout the queries walk, with the triangles' corners stored in leaf order.

use glam::{Vec3, Vec3A};
use pgvol_mesh::Mesh;

pub use crate::bvh_build::Node;
use crate::{
    bvh_build::{self, Costs, ItemBox},
    lanes::{TriangleLanes, LANES},
    leaf_bounds::OrientedBox,
    triangle::{closest_point_and_distance, Feature},
};

/// The hierarchy. Leaf slot `n` holds mesh triangle `tri_ids[n]`, whose corners `lanes` keeps
/// (for scans four or eight at a time, and [`Bvh::corners`]).
#[derive(Clone, Debug)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    /// Per node, the oriented box around a leaf's triangles (`OrientedBox::EVERYWHERE` for
    /// inner nodes).
    pub oriented: Vec<OrientedBox>,
    pub tri_ids: Vec<u32>,
    pub lanes: TriangleLanes,
    /// Per leaf slot, its place in its leaf (low 4 bits) and the leaf's triangle count (high 4
    /// bits): a byte where the first slot and the count took 8 ([`Bvh::leaf_of_slot`]).
    slot_in_leaf: Vec<u8>,
}

/// The corners of a leaf's triangles, in leaf order.
pub struct LeafTriangles {
    corners: [[Vec3A; 3]; MAX_LEAF],
    len: usize,
}

impl std::ops::Deref for LeafTriangles {
    type Target = [[Vec3A; 3]];

    fn deref(&self) -> &[[Vec3A; 3]] {
        &self.corners[..self.len]
    }
}

/// The closest point of the mesh to a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    pub point: Vec3,
    pub distance_squared: f32,
    /// Triangle index in the original mesh.
    pub triangle: u32,
    /// Position of that triangle in leaf order (a hint for the next query).
    pub slot: u32,
    pub feature: Feature,
}

/// Most triangles in a leaf: one step of the eight-lane scans.
pub const MAX_LEAF: usize = 8;

/// More than any tree's depth (the builder keeps it under [`bvh_build::HEURISTIC_DEPTH`] plus
/// the log of the triangle count); deeper trees would spill to the heap.
const STACK: usize = 96;

/// The cost of visiting an inner node against 1 for testing a triangle, for the builder.
/// Set by encoding the capped bunny, fandisk and the rocker arm at 1024^3 (see
/// `docs/algorithms.md`, "Signed distance").
const TRAVERSAL_COST: f32 = 6.0;

impl Bvh {
    /// Builds the hierarchy. The mesh must have at least one triangle.
    pub fn build(mesh: &Mesh) -> Bvh {
        use rayon::prelude::*;
        let boxes: Vec<ItemBox> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|t| {
                let [a, b, c] = mesh.triangle(t).map(Vec3A::from);
                [a.min(b).min(c), a.max(b).max(c)]
            })
            .collect();
        let costs = Costs {
            traversal: TRAVERSAL_COST,
            max_leaf: MAX_LEAF,
        };
        let tree = bvh_build::build(&boxes, costs);
        drop(boxes);
        let mut lanes = TriangleLanes::with_len(tree.order.len());
        for (slot, &t) in tree.order.iter().enumerate() {
            lanes.set(slot, &mesh.triangle(t as usize).map(Vec3A::from));
        }
        let mut out = Bvh {
            nodes: tree.nodes,
            oriented: Vec::new(),
            tri_ids: tree.order,
            lanes,
            slot_in_leaf: Vec::new(),
        };
        const _: () = assert!(MAX_LEAF < 16, "a leaf's place and count fit in 4 bits each");
        out.slot_in_leaf = vec![0; out.tri_ids.len()];
        for n in out.nodes.iter().filter(|n| n.is_leaf()) {
            for (place, slot) in (n.first..n.first + n.count).enumerate() {
                out.slot_in_leaf[slot as usize] = (n.count << 4) as u8 | place as u8;
            }
        }
        out.oriented = out
            .nodes
            .iter()
            .map(|n| {
                if n.is_leaf() {
                    OrientedBox::around(&out.leaf(n), n.min, n.max)
                } else {
                    OrientedBox::EVERYWHERE
                }
            })
            .collect();
        out
    }

    /// The closest point of the mesh to `p`, or `None` for an empty tree or when nothing is
    /// closer than `sqrt(bound_squared)`.
    pub fn closest(&self, p: Vec3, bound_squared: f32) -> Option<Closest> {
        self.closest_with_hint(p, bound_squared, None)
    }

    /// As [`Bvh::closest`], starting from the distance to the triangle at leaf slot `hint`
    /// (typically the previous query's answer), which prunes most of the tree for nearby queries.
    pub fn closest_with_hint(
        &self,
        p: Vec3,
        bound_squared: f32,
        hint: Option<u32>,
    ) -> Option<Closest> {
        if self.nodes.is_empty() {
            return None;
        }
        let q = Vec3A::from(p);
        let mut best: Option<Closest> = None;
        let mut best_d2 = bound_squared;
        let consider = |slot: u32, best: &mut Option<Closest>, best_d2: &mut f32| {
            let [a, b, c] = self.corners(slot);
            let (point, feature, d2) = closest_point_and_distance(q, a, b, c);
            if d2 < *best_d2 || (best.is_none() && d2 <= *best_d2) {
                *best_d2 = d2;
                *best = Some(Closest {
                    point: point.into(),
                    distance_squared: d2,
                    triangle: self.tri_ids[slot as usize],
                    slot,
                    feature,
                });
            }
        };
        if let Some(h) = hint.filter(|&h| (h as usize) < self.tri_ids.len()) {
            consider(h, &mut best, &mut best_d2);
        }
        let mut stack = [0u32; STACK];
        let mut spill: Vec<u32> = Vec::new();
        let mut top = 1usize;
        stack[0] = 0;
        loop {
            let id = if let Some(id) = spill.pop() {
                id
            } else if top > 0 {
                top -= 1;
                stack[top]
            } else {
                break;
            };
            let node = &self.nodes[id as usize];
            if node.distance_squared(q) > best_d2 {
                continue;
            }
            if node.is_leaf() {
                for slot in node.first..node.first + node.count {
                    consider(slot, &mut best, &mut best_d2);
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let dl = self.nodes[l as usize].distance_squared(q);
            let dr = self.nodes[r as usize].distance_squared(q);
            // Push the farther child first so the nearer one is visited next.
            let (near, far, dfar, dnear) = if dl <= dr {
                (l, r, dr, dl)
            } else {
                (r, l, dl, dr)
            };
            for (child, d) in [(far, dfar), (near, dnear)] {
                if d <= best_d2 {
                    if top < STACK && spill.is_empty() {
                        stack[top] = child;
                        top += 1;
                    } else {
                        spill.push(child);
                    }
                }
            }
        }
        best
    }
}

/// Squared distance between two boxes (0 when they overlap).
#[inline]
fn box_box_distance_squared(lo: Vec3A, hi: Vec3A, node: &Node) -> f32 {
    let d = (node.min - hi).max(lo - node.max).max(Vec3A::ZERO);
    d.length_squared()
}

impl Bvh {
    /// Leaves whose box lies within `sqrt(bound_squared)` of the box `[lo, hi]`: every triangle
    /// that can be closest to a point of the box, given that each such point is within that
    /// bound of the surface. Returned as `(distance from the box's centre to the leaf's box,
    /// node id)`, sorted by that distance: for a point `p` of the box at `r` from the centre, a
    /// leaf's distance minus `r` bounds its distance to `p` from below, so a scan from `p` can
    /// stop where that bound passes its best.
    pub fn leaves_near_box(
        &self,
        lo: Vec3A,
        hi: Vec3A,
        bound_squared: f32,
        out: &mut Vec<(f32, u32)>,
    ) {
        out.clear();
        if self.nodes.is_empty() {
            return;
        }
        let centre = (lo + hi) * 0.5;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id as usize];
            if box_box_distance_squared(lo, hi, node) > bound_squared {
                continue;
            }
            if node.is_leaf() {
                out.push((node.distance_squared(centre).sqrt(), id));
            } else {
                stack.push(node.first);
                stack.push(node.first + 1);
            }
        }
        // By distance, then id. Distances are not negative, so their bits sort as they do, and
        // one integer key sorts faster than a comparison of pairs.
        out.sort_unstable_by_key(|&(d, id)| (u64::from(d.to_bits()) << 32) | u64::from(id));
    }

    /// The closest point to `p` among the triangles of `leaves` (from [`Bvh::leaves_near_box`])
    /// and of the leaf holding slot `start` (typically a neighbour's answer): that leaf first,
    /// then the others in their order, a triangle winning only by being strictly nearer than
    /// the best so far. Triangles farther than `sqrt(limit_squared)` are not looked for: the
    /// answer is exact when the closest distance is within that limit, and otherwise some
    /// triangle beyond it. The reference the grid scans are tested against: it tests every
    /// leaf's box.
    pub fn closest_among(
        &self,
        p: Vec3,
        leaves: &[(f32, u32)],
        start: u32,
        limit_squared: f32,
    ) -> Closest {
        let q = Vec3A::from(p);
        let [first, count] = self.leaf_of_slot(start);
        let mut best: Option<Closest> = None;
        let scan = |first: usize, end: usize, best: &mut Option<Closest>| {
            // Four triangles per step; only those that improve are looked at one by one, by
            // the same arithmetic, so the answer is the scalar scan's.
            for step in (first..end).step_by(LANES) {
                let d2 = self.lanes.distances_squared(q, step).to_array();
                for (lane, &d2) in d2.iter().enumerate().take(end - step) {
                    let best_d2 = best.map_or(f32::INFINITY, |b| b.distance_squared);
                    if d2.is_nan() || d2 < best_d2 || best.is_none() {
                        let c = self.closest_on_slot(p, (step + lane) as u32);
                        if c.distance_squared < best_d2 || best.is_none() {
                            *best = Some(c);
                        }
                    }
                }
            }
        };
        scan(first as usize, (first + count) as usize, &mut best);
        for &(_, id) in leaves {
            let node = &self.nodes[id as usize];
            let reach = best.map_or(f32::INFINITY, |b| b.distance_squared);
            if node.first == first || node.distance_squared(q) > reach.min(limit_squared) {
                continue;
            }
            scan(
                node.first as usize,
                (node.first + node.count) as usize,
                &mut best,
            );
        }
        best.expect("a leaf holds at least one triangle")
    }

    /// The box of every triangle; `None` for an empty tree.
    pub fn bounds(&self) -> Option<(Vec3A, Vec3A)> {
        self.nodes.first().map(|root| (root.min, root.max))
    }

    /// Whether `p` lies outside the box of every triangle (always, for an empty tree).
    pub fn is_outside_box(&self, p: Vec3A) -> bool {
        self.bounds()
            .is_none_or(|(min, max)| p.cmplt(min).any() || p.cmpgt(max).any())
    }

    /// The change of the generalized winding number from `a` to `b` caused by the triangles the
    /// segment crosses: +1 for each triangle crossed from its front to its back (into the
    /// inside), −1 the other way. `None` when a crossing is too close to an edge, a vertex or an
    /// end of the segment to count reliably.
    pub fn winding_jump(&self, a: Vec3, b: Vec3) -> Option<i32> {
        let (pa, pb) = (Vec3A::from(a), Vec3A::from(b));
        let (lo, hi) = (pa.min(pb), pa.max(pb));
        let outside = |node: &Node| node.min.cmpgt(hi).any() || node.max.cmplt(lo).any();
        self.segment_crossings(pa, pb - pa, JUMP_END_MARGIN, outside)
            .map(|(into_back, into_front)| into_back - into_front)
    }

    /// The one triangle the segment from `a` to `b` crosses, with where: the Hermite data of a
    /// grid edge whose ends lie on either side of the surface. Anything else (no crossing,
    /// several, or one too close to an edge, a vertex or an end of the segment to be sure of)
    /// is [`SegmentHit::NotOne`], for the caller's own fallback.
    pub fn segment_hit(&self, a: Vec3, b: Vec3) -> SegmentHit {
        let (pa, pb) = (Vec3A::from(a), Vec3A::from(b));
        let (lo, hi) = (pa.min(pb), pa.max(pb));
        let dir = pb - pa;
        let mut found = None;
        let mut stack: Vec<u32> = Vec::with_capacity(32);
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id as usize];
            if node.min.cmpgt(hi).any() || node.max.cmplt(lo).any() {
                continue;
            }
            if !node.is_leaf() {
                stack.push(node.first);
                stack.push(node.first + 1);
                continue;
            }
            for slot in node.first..node.first + node.count {
                let t = &self.corners(slot);
                match segment_crossing(pa, dir, t, JUMP_END_MARGIN) {
                    Crossing::None => {}
                    Crossing::Unsure => return SegmentHit::NotOne,
                    Crossing::IntoBack(s) | Crossing::IntoFront(s) => {
                        if found.is_some() {
                            return SegmentHit::NotOne;
                        }
                        let [p, q, r] = *t;
                        found = Some(SegmentHit::One {
                            point: (pa + dir * s).into(),
                            normal: (q - p).cross(r - p).normalize_or_zero().into(),
                            triangle: self.tri_ids[slot as usize],
                        });
                    }
                }
            }
        }
        found.unwrap_or(SegmentHit::NotOne)
    }

    /// How many triangles the ray `origin + s·dir`, `s > 0`, crosses; `None` when a crossing is
    /// too close to an edge, a vertex or the origin to count reliably.
    pub fn ray_crossings(&self, origin: Vec3, dir: Vec3) -> Option<u32> {
        let Some(root) = self.nodes.first() else {
            return Some(0);
        };
        let o = Vec3A::from(origin);
        let d = Vec3A::from(dir);
        let inv = d.recip();
        // A segment long enough to leave the whole mesh stands in for the ray.
        let reach = (root.max - root.min).length() + (o - (root.min + root.max) * 0.5).length();
        let missed = |node: &Node| {
            let t1 = (node.min - o) * inv;
            let t2 = (node.max - o) * inv;
            t1.min(t2).max_element().max(0.0) > t1.max(t2).min_element()
        };
        // The segment is far longer than the mesh: only a tiny end margin near the origin.
        self.segment_crossings(o, d * reach, 1e-7, missed)
            .map(|(b, f)| (b + f) as u32)
    }

    /// Counts the triangles the segment `a + s·dir`, `s ∈ [0, 1]`, crosses against their normal
    /// and along it, visiting only nodes that `pruned` does not reject; `None` when a crossing is
    /// ambiguous (see `segment_crossing`).
    fn segment_crossings(
        &self,
        a: Vec3A,
        dir: Vec3A,
        end_margin: f32,
        pruned: impl Fn(&Node) -> bool,
    ) -> Option<(i32, i32)> {
        let (mut into_back, mut into_front) = (0i32, 0i32);
        if self.nodes.is_empty() {
            return Some((0, 0));
        }
        let mut stack: Vec<u32> = Vec::with_capacity(32);
        stack.push(0);
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id as usize];
            if pruned(node) {
                continue;
            }
            if !node.is_leaf() {
                stack.push(node.first);
                stack.push(node.first + 1);
                continue;
            }
            for t in self.leaf(node).iter() {
                match segment_crossing(a, dir, t, end_margin) {
                    Crossing::None => {}
                    Crossing::Unsure => return None,
                    Crossing::IntoBack(_) => into_back += 1,
                    Crossing::IntoFront(_) => into_front += 1,
                }
            }
        }
        Some((into_back, into_front))
    }

    /// The first slot of the leaf holding `slot`, and the leaf's triangle count.
    #[inline]
    pub fn leaf_of_slot(&self, slot: u32) -> [u32; 2] {
        let packed = u32::from(self.slot_in_leaf[slot as usize]);
        [slot - (packed & 15), packed >> 4]
    }

    /// The corners of the triangle at leaf slot `slot`.
    #[inline]
    pub fn corners(&self, slot: u32) -> [Vec3A; 3] {
        self.lanes.corners(slot as usize)
    }

    /// The corners of a leaf's triangles.
    pub fn leaf(&self, node: &Node) -> LeafTriangles {
        let mut leaf = LeafTriangles {
            corners: [[Vec3A::ZERO; 3]; MAX_LEAF],
            len: node.count as usize,
        };
        for (i, slot) in (node.first..node.first + node.count).enumerate() {
            leaf.corners[i] = self.corners(slot);
        }
        leaf
    }

    /// Closest point to `p` on the triangle at leaf slot `slot`.
    pub fn closest_on_slot(&self, p: Vec3, slot: u32) -> Closest {
        let q = Vec3A::from(p);
        let [a, b, c] = self.corners(slot);
        let (point, feature, distance_squared) = closest_point_and_distance(q, a, b, c);
        Closest {
            point: point.into(),
            distance_squared,
            triangle: self.tri_ids[slot as usize],
            slot,
            feature,
        }
    }
}

/// What [`Bvh::segment_hit`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegmentHit {
    /// The segment crosses exactly one triangle, well inside it: the crossing, the triangle's
    /// unit normal (by its winding, counter-clockwise seen from its front) and its index in the
    /// mesh.
    One {
        point: Vec3,
        normal: Vec3,
        triangle: u32,
    },
    /// No crossing, several, or one too close to a triangle's edge or the segment's ends.
    NotOne,
}

/// Crossings this close to an end of a segment (as a fraction of its length) are unsure.
const JUMP_END_MARGIN: f32 = 1e-4;

/// The part of [`Bvh::winding_jump`] due to one triangle: the same arithmetic, so a sum over the
/// triangles that can meet the segment gives the same answer.
pub(crate) fn triangle_jump(a: Vec3A, b: Vec3A, t: &[Vec3A; 3]) -> Option<i32> {
    match segment_crossing(a, b - a, t, JUMP_END_MARGIN) {
        Crossing::None => Some(0),
        Crossing::Unsure => None,
        Crossing::IntoBack(_) => Some(1),
        Crossing::IntoFront(_) => Some(-1),
    }
}

/// How a segment meets a triangle.
enum Crossing {
    None,
    /// Too close to an edge, a vertex or a segment end, or parallel within rounding.
    Unsure,
    /// Through the triangle against its normal (from outside to inside), at this parameter
    /// of the segment.
    IntoBack(f32),
    /// Through the triangle along its normal.
    IntoFront(f32),
}

/// Möller–Trumbore on the segment `a + s·dir`, `s ∈ [0, 1]`, with margins (1e-4 in barycentric
/// coordinates, `end_margin` in `s`) that turn near misses and grazing hits into `Unsure`
/// rather than guesses.
#[inline]
fn segment_crossing(a: Vec3A, dir: Vec3A, t: &[Vec3A; 3], end_margin: f32) -> Crossing {
    const EDGE: f32 = 1e-4;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    let scale = e1.length() * e2.length() * dir.length();
    if det.abs() <= 1e-6 * scale {
        // Parallel: a crossing is impossible unless the segment lies in the plane.
        let n = e1.cross(e2);
        let off = (a - t[0]).dot(n);
        return if off.abs() <= 1e-6 * n.length() * dir.length().max(1e-30) {
            Crossing::Unsure
        } else {
            Crossing::None
        };
    }
    let inv = 1.0 / det;
    let tvec = a - t[0];
    let u = tvec.dot(pvec) * inv;
    let q = tvec.cross(e1);
    let v = dir.dot(q) * inv;
    let s = e2.dot(q) * inv;
    let w = 1.0 - u - v;
    if u < -EDGE || v < -EDGE || w < -EDGE || !(-end_margin..=1.0 + end_margin).contains(&s) {
        return Crossing::None;
    }
    if u < EDGE || v < EDGE || w < EDGE || !(end_margin..=1.0 - end_margin).contains(&s) {
        return Crossing::Unsure;
    }
    // det > 0 means dir · normal < 0: the segment enters through the front face.
    if det > 0.0 {
        Crossing::IntoBack(s)
    } else {
        Crossing::IntoFront(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use pgvol_mesh::shapes::octasphere;
    use rand::{Rng, SeedableRng};

    pub(crate) fn random_soup(n: usize, seed: u64) -> Mesh {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for t in 0..n {
            let c = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 4.0;
            for _ in 0..3 {
                positions.push(c + Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 0.5);
            }
            let b = 3 * t as u32;
            triangles.push([b, b + 1, b + 2]);
        }
        Mesh::new(positions, triangles)
    }

    /// On a sphere of 8192 triangles, a short segment across the surface crosses one
    /// triangle: the point must lie on the segment and in that triangle's plane, with the
    /// triangle's own normal pointing out of the sphere; a segment through the whole sphere
    /// crosses two and one outside it none.
    #[test]
    fn segment_hits_give_the_one_crossed_triangle_and_its_normal() {
        let mesh = octasphere(5);
        let bvh = Bvh::build(&mesh);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut found = 0;
        for _ in 0..500 {
            let d = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 2.0 - Vec3::ONE;
            let Some(d) = d.try_normalize() else { continue };
            let (a, b) = (d * 0.9, d * 1.1);
            let SegmentHit::One {
                point,
                normal,
                triangle,
            } = bvh.segment_hit(a, b)
            else {
                continue;
            };
            found += 1;
            let [p, q, r] = mesh.triangle(triangle as usize);
            let plane = (q - p).cross(r - p).normalize();
            assert!(
                (point - p).dot(plane).abs() < 1e-5,
                "{point} off its triangle"
            );
            assert!(
                (point - a).cross(b - a).length() < 1e-5,
                "{point} off the segment"
            );
            assert!(normal.distance(plane) < 1e-5 && normal.dot(d) > 0.9);
        }
        // Only segments through a triangle's edge or corner (within 1e-4) are unsure.
        assert!(found > 480, "{found} of 500");
        let through = bvh.segment_hit(Vec3::new(-2.0, 0.1, 0.2), Vec3::new(2.0, 0.1, 0.2));
        assert_eq!(through, SegmentHit::NotOne);
        let outside = bvh.segment_hit(Vec3::new(2.0, 0.1, 0.2), Vec3::new(3.0, 0.1, 0.2));
        assert_eq!(outside, SegmentHit::NotOne);
    }

    #[test]
    fn every_triangle_appears_once_in_leaf_order() {
        let mesh = random_soup(1000, 1);
        let bvh = Bvh::build(&mesh);
        let mut ids = bvh.tri_ids.clone();
        ids.sort_unstable();
        assert_eq!(ids, (0..1000).collect::<Vec<u32>>());
        // Each slot's corners are its mesh triangle's, and its leaf is the one naming it.
        for (slot, &t) in bvh.tri_ids.iter().enumerate() {
            assert_eq!(
                bvh.corners(slot as u32),
                mesh.triangle(t as usize).map(Vec3A::from)
            );
        }
        for n in bvh.nodes.iter().filter(|n| n.is_leaf()) {
            for slot in n.first..n.first + n.count {
                assert_eq!(bvh.leaf_of_slot(slot), [n.first, n.count], "slot {slot}");
            }
        }
    }

    #[test]
    fn closest_matches_brute_force() {
        let mesh = random_soup(500, 2);
        let bvh = Bvh::build(&mesh);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let mut hint = None;
        for _ in 0..2000 {
            let p = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 6.0 - Vec3::ONE;
            let got = bvh.closest_with_hint(p, f32::INFINITY, hint).unwrap();
            hint = Some(got.slot);
            let brute = (0..mesh.triangles.len())
                .map(|t| {
                    let [a, b, c] = mesh.triangle(t);
                    closest_point_and_distance(p.into(), a.into(), b.into(), c.into()).2
                })
                .fold(f32::INFINITY, f32::min);
            assert_eq!(got.distance_squared, brute, "query {p}");
            let [a, b, c] = mesh.triangle(got.triangle as usize);
            let (q, _, _) = closest_point_and_distance(p.into(), a.into(), b.into(), c.into());
            assert_eq!(Vec3::from(q), got.point);
        }
    }

    #[test]
    fn winding_jumps_count_crossings_with_direction() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
        let bvh = Bvh::build(&mesh);
        // The normal is +z: going down crosses into the back (inside), +1.
        assert_eq!(
            bvh.winding_jump(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, -1.0)),
            Some(1)
        );
        assert_eq!(
            bvh.winding_jump(Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.2, 0.2, 1.0)),
            Some(-1)
        );
        assert_eq!(
            bvh.winding_jump(Vec3::new(2.0, 0.2, 1.0), Vec3::new(2.0, 0.2, -1.0)),
            Some(0)
        );
        // Through an edge: unsure.
        assert_eq!(
            bvh.winding_jump(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.5, 0.0, -1.0)),
            None
        );
        // Ending on the triangle: unsure.
        assert_eq!(
            bvh.winding_jump(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, 0.0)),
            None
        );
    }

    #[test]
    fn single_triangle_and_bounds() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
        let bvh = Bvh::build(&mesh);
        let c = bvh
            .closest(Vec3::new(0.2, 0.2, 2.0), f32::INFINITY)
            .unwrap();
        assert!((c.distance_squared - 4.0).abs() < 1e-6);
        assert!(bvh.closest(Vec3::new(0.2, 0.2, 2.0), 1.0).is_none());
    }

    /// A fine sphere, and the bunny when `PGVOL_SHARED_MESHES` names the shared meshes' folder.
    fn meshes() -> Vec<Mesh> {
        let mut meshes = vec![octasphere(5)];
        if let Some(dir) = std::env::var_os("PGVOL_SHARED_MESHES") {
            let path = std::path::Path::new(&dir).join("stanford-bunny.obj");
            meshes.push(pgvol_mesh::read(&path).expect("the shared bunny"));
        }
        meshes
    }

    /// The exact distance from `p` to the triangle, in f64: the smallest over its plane's
    /// foot point (when inside) and its three edges.
    fn exact_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
        let segment = |a: DVec3, b: DVec3| {
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            p.distance(a + ab * t)
        };
        let mut best = segment(a, b).min(segment(b, c)).min(segment(c, a));
        let n = (b - a).cross(c - a);
        if n.length_squared() > 0.0 {
            let foot = p - n * ((p - a).dot(n) / n.length_squared());
            let inside = [(a, b), (b, c), (c, a)]
                .iter()
                .all(|&(u, v)| (v - u).cross(foot - u).dot(n) >= 0.0);
            if inside {
                best = best.min(p.distance(foot));
            }
        }
        best
    }

    #[test]
    fn bounds_never_exceed_the_distance_to_a_leaf_triangle() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        for mesh in meshes() {
            let bvh = Bvh::build(&mesh);
            let leaves = bvh.nodes.iter().enumerate().filter(|(_, n)| n.is_leaf());
            for (id, node) in leaves.step_by(7) {
                let tris = bvh.leaf(node);
                let oriented = &bvh.oriented[id];
                let size = (node.max - node.min).length();
                for _ in 0..40 {
                    let [a, b, c] = tris[rng.gen_range(0..tris.len())];
                    let (u, v): (f32, f32) = (rng.gen(), rng.gen());
                    let (u, v) = if u + v > 1.0 {
                        (1.0 - u, 1.0 - v)
                    } else {
                        (u, v)
                    };
                    let on = a + (b - a) * u + (c - a) * v;
                    let direction = Vec3A::new(rng.gen(), rng.gen(), rng.gen()) - 0.5;
                    // On a triangle, a hair away, near, and far.
                    let offset = [0.0, 1e-6, 1e-3, 0.3, 3.0, 100.0][rng.gen_range(0..6)];
                    let p = on + direction * (offset * size);
                    let bound = oriented.distance_squared_bound(p, node.min, node.max);
                    for &[a, b, c] in tris.iter() {
                        let scanned = closest_point_and_distance(p, a, b, c).2;
                        assert!(bound <= scanned, "{bound} > {scanned} at {p}");
                        let corners = [a, b, c].map(|x| DVec3::from(Vec3::from(x)));
                        let exact = exact_distance(DVec3::from(Vec3::from(p)), corners);
                        assert!(f64::from(bound) <= exact * exact, "{bound} at {p}");
                    }
                }
            }
        }
    }
}
