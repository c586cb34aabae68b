//! Rim edges: edges whose oriented uses by the triangles do not cancel (open boundaries, edges
//! used twice in the same direction). Off the surface, the gradient of the generalized winding
//! number is the Biot–Savart field of the rims (each triangle's solid-angle gradient is that of
//! its boundary loop, and shared edges cancel), so the rims bound how fast it can change:
//!
//! `|∇w(p)| ≤ Σ_e |n_e| · length_e / (4π · dist(p, e)²)`, with `n_e` the edge's net uses.
//!
//! A small tree over the rims answers that bound for a box in logarithmic time.

use glam::Vec3A;
use pgvol_core::mesh::edge_key;
use pgvol_mesh::Mesh;
use rayon::prelude::*;

const FOUR_PI: f32 = 4.0 * std::f32::consts::PI;

/// Rim edges per tree leaf.
const LEAF_EDGES: usize = 4;

/// A node whose box is farther than this many box diagonals from the query counts as one
/// edge of its total weight at its box distance: the bound loosens by at most a few percent.
const FAR_DIAGONALS: f32 = 4.0;

#[derive(Clone, Copy, Debug)]
struct RimEdge {
    a: Vec3A,
    b: Vec3A,
    /// `|n_e| · length / 4π`: the edge's gradient bound at unit distance.
    weight: f32,
}

#[derive(Clone, Copy, Debug)]
struct RimNode {
    min: Vec3A,
    max: Vec3A,
    /// Sum of the weights below.
    weight: f32,
    /// Leaves: edges `first..first + count`; inner nodes (`count == 0`): children `first`
    /// and `first + 1`.
    first: u32,
    count: u32,
}

/// The rim edges of a mesh, in a tree for gradient bounds.
#[derive(Clone, Debug, Default)]
pub struct Rims {
    edges: Vec<RimEdge>,
    nodes: Vec<RimNode>,
}

/// Each edge `(smaller vertex, larger vertex)` whose uses by the triangles do not cancel, with
/// its net uses (+1 for a use from the smaller vertex to the larger), in edge order (the tree,
/// and so every bound, follows it). The 3n uses are sorted in parallel and summed along runs
/// of equal edges: a hash map of the edges, on one thread, was a tenth of a small encode's time
/// on a 1.3 M-triangle mesh. A use is one word, its two vertices in the order of use, written
/// in place: on that mesh a list of (edge, direction) pairs collected in parallel held 124 MB
/// at the encode's peak memory, these 31 MB.
fn net_uses(mesh: &Mesh) -> Vec<((u32, u32), i32)> {
    let mut uses = vec![0u64; 3 * mesh.triangles.len()];
    uses.par_chunks_exact_mut(3)
        .zip(&mesh.triangles)
        .for_each(|(out, t)| {
            for (c, used) in out.iter_mut().enumerate() {
                *used = (t[c] as u64) << 32 | t[(c + 1) % 3] as u64;
            }
        });
    let ends = |used: u64| ((used >> 32) as u32, used as u32);
    let edge = |used: u64| {
        let (a, b) = ends(used);
        edge_key(a, b)
    };
    uses.par_sort_unstable_by_key(|&used| edge(used));
    let mut net = Vec::new();
    for run in uses.chunk_by(|&x, &y| edge(x) == edge(y)) {
        let n: i32 = run
            .iter()
            .map(|&used| {
                let (a, b) = ends(used);
                if a < b {
                    1
                } else {
                    -1
                }
            })
            .sum();
        if n != 0 {
            let key = edge(run[0]);
            net.push((((key >> 32) as u32, key as u32), n));
        }
    }
    net
}

impl Rims {
    pub fn new(mesh: &Mesh) -> Rims {
        let mut edges: Vec<RimEdge> = net_uses(mesh)
            .into_iter()
            .map(|((a, b), n)| {
                let a = Vec3A::from(mesh.positions[a as usize]);
                let b = Vec3A::from(mesh.positions[b as usize]);
                RimEdge {
                    a,
                    b,
                    weight: n.unsigned_abs() as f32 * a.distance(b) / FOUR_PI,
                }
            })
            .collect();
        let mut nodes = Vec::new();
        if !edges.is_empty() {
            nodes.push(RimNode {
                min: Vec3A::ZERO,
                max: Vec3A::ZERO,
                weight: 0.0,
                first: 0,
                count: 0,
            });
            build(&mut edges, 0, 0, &mut nodes);
        }
        Rims { edges, nodes }
    }

    /// Number of rim edges (0 for closed, consistently oriented meshes).
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// An upper bound on `|∇w|` over the box `[lo, hi]`: infinite when a rim edge comes
    /// near enough to touch it, 0 without rims.
    pub fn gradient_bound(&self, lo: Vec3A, hi: Vec3A) -> f32 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let (centre, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        let mut total = 0.0f32;
        let mut stack: Vec<u32> = Vec::with_capacity(32);
        stack.push(0);
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id as usize];
            let d2 = box_distance_squared(lo, hi, node.min, node.max);
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for e in &self.edges[range] {
                    // Two lower bounds on the distance: between the boxes, and from the
                    // query box's centre to the edge less the box's radius.
                    let boxes = box_distance_squared(lo, hi, e.a.min(e.b), e.a.max(e.b)).sqrt();
                    let d = boxes.max(segment_distance(centre, e.a, e.b) - radius);
                    if d <= 0.0 {
                        return f32::INFINITY;
                    }
                    total += e.weight / (d * d);
                }
            } else if d2 > FAR_DIAGONALS * FAR_DIAGONALS * (node.max - node.min).length_squared() {
                total += node.weight / d2;
            } else {
                stack.push(node.first);
                stack.push(node.first + 1);
            }
        }
        total
    }
}

/// Fills `nodes[slot]` with the subtree over `edges` (which start at `offset` in the final
/// order), splitting at the median midpoint along the longest axis.
fn build(edges: &mut [RimEdge], offset: usize, slot: usize, nodes: &mut Vec<RimNode>) {
    let (mut min, mut max) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for e in edges.iter() {
        min = min.min(e.a).min(e.b);
        max = max.max(e.a).max(e.b);
    }
    nodes[slot] = RimNode {
        min,
        max,
        weight: edges.iter().map(|e| e.weight).sum(),
        first: offset as u32,
        count: edges.len() as u32,
    };
    if edges.len() <= LEAF_EDGES {
        return;
    }
    let extent = max - min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let half = edges.len() / 2;
    edges.select_nth_unstable_by(half, |p, q| {
        let key = |e: &RimEdge| [e.a.to_array(), e.b.to_array()].map(|v| v.map(f32::to_bits));
        (p.a + p.b)[axis]
            .total_cmp(&(q.a + q.b)[axis])
            .then_with(|| key(p).cmp(&key(q)))
    });
    let (left, right) = edges.split_at_mut(half);
    // Children are adjacent, like the triangle BVH's.
    let children = nodes.len();
    nodes.extend([nodes[slot]; 2]);
    nodes[slot].first = children as u32;
    nodes[slot].count = 0;
    build(left, offset, children, nodes);
    build(right, offset + half, children + 1, nodes);
}

/// Distance from `p` to the segment `[a, b]`.
fn segment_distance(p: Vec3A, a: Vec3A, b: Vec3A) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Squared distance between two boxes (0 when they touch).
#[inline]
fn box_distance_squared(lo: Vec3A, hi: Vec3A, min: Vec3A, max: Vec3A) -> f32 {
    (min - hi).max(lo - max).max(Vec3A::ZERO).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::winding::exact_winding;
    use glam::Vec3;
    use pgvol_mesh::shapes::octasphere as sphere;
    use rand::{Rng, SeedableRng};

    /// The net uses summed by a hash map and sorted afterwards, as the reference: random faces
    /// over few vertices, so edges are used once, cancelled, or used twice the same way.
    #[test]
    fn net_uses_sum_as_a_map_does() {
        use std::collections::HashMap;
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move |m: u32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as u32
        };
        for (vertices, faces) in [(4u32, 3), (8, 30), (40, 500)] {
            let triangles: Vec<[u32; 3]> = (0..faces)
                .map(|_| [next(vertices), next(vertices), next(vertices)])
                .collect();
            let mesh = Mesh::new(vec![Vec3::ZERO; vertices as usize], triangles);
            let mut map: HashMap<(u32, u32), i32> = HashMap::new();
            for t in &mesh.triangles {
                for c in 0..3 {
                    let (a, b) = (t[c], t[(c + 1) % 3]);
                    *map.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
                }
            }
            let mut want: Vec<_> = map.into_iter().filter(|&(_, n)| n != 0).collect();
            want.sort_unstable();
            assert!(!want.is_empty());
            assert_eq!(net_uses(&mesh), want);
        }
    }

    #[test]
    fn closed_meshes_have_no_rims() {
        let rims = Rims::new(&sphere(2));
        assert!(rims.is_empty());
        assert_eq!(rims.gradient_bound(Vec3A::ZERO, Vec3A::ONE), 0.0);
    }

    /// The bound must hold against finite differences of the exact winding number.
    #[test]
    fn gradient_bound_holds_around_an_open_sphere() {
        let mut mesh = sphere(3);
        mesh.triangles.retain(|t| {
            let c = t.iter().map(|&i| mesh.positions[i as usize]).sum::<Vec3>() / 3.0;
            c.z < 0.5 && !(c.x > 0.6 && c.y > 0.0)
        });
        let rims = Rims::new(&mesh);
        assert!(rims.len() > 20, "{} rims", rims.len());
        let tris: Vec<[Vec3; 3]> = (0..mesh.triangles.len())
            .map(|t| mesh.triangle(t))
            .collect();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        let step = 1e-3f32;
        let mut checked = 0;
        for _ in 0..400 {
            let p = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 3.0 - Vec3::splat(1.5);
            let half = Vec3A::splat(0.05);
            let bound = rims.gradient_bound(Vec3A::from(p) - half, Vec3A::from(p) + half);
            if !bound.is_finite() {
                continue;
            }
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                let a = exact_winding(&tris, p - axis * step);
                let b = exact_winding(&tris, p + axis * step);
                // A jump means the difference crossed the surface: not a gradient.
                if (a - b).abs() > 0.5 {
                    continue;
                }
                let slope = ((b - a) / (2.0 * step as f64)).abs() as f32;
                assert!(
                    slope <= bound * 1.01 + 1e-3,
                    "{p}: slope {slope} > bound {bound}"
                );
                checked += 1;
            }
        }
        assert!(checked > 300, "{checked} checks");
    }
}
