//! Orientation repair: faces turned consistently within each connected piece, and each piece
//! turned outward, so that distance signs do not depend on how the faces were wound.

use glam::DVec3;
use rayon::prelude::*;

use super::Mesh;

impl Mesh {
    /// Turns faces so that neighbours across every edge shared by exactly two triangles agree,
    /// each connected piece keeping the winding of most of its area; then, when the whole mesh
    /// encloses negative volume (wound inside out), turns every face. Pieces wound consistently
    /// keep their winding, so a cavity that faces into itself stays a cavity. Returns the number
    /// of triangles turned.
    pub fn orient_outward(&mut self) -> usize {
        let pieces = self.turn_consistently();
        let mut turned = pieces.flips;
        for members in &pieces.members {
            // Keep the winding of the larger share of the piece's area.
            let (mut kept, mut flipped) = (0.0, 0.0);
            for &t in members {
                let area = self.area(t);
                if turned[t] {
                    flipped += area;
                } else {
                    kept += area;
                }
            }
            if flipped > kept {
                for &t in members {
                    turned[t] = !turned[t];
                }
            }
        }
        if self.signed_volume(&turned) < 0.0 {
            turned.iter_mut().for_each(|t| *t = !*t);
        }
        let mut count = 0;
        for (tri, &flip) in self.triangles.iter_mut().zip(&turned) {
            if flip {
                tri.swap(1, 2);
                count += 1;
            }
        }
        if count > 0 {
            // Known normals agreed with the old winding.
            self.normals.clear();
        }
        count
    }

    /// Connected pieces across two-triangle edges, with the flips that make each consistent.
    /// A depth-first walk from each unvisited triangle in index order, its three edges in
    /// order.
    fn turn_consistently(&self) -> Pieces {
        let n = self.triangles.len();
        let across = self.across_two_triangle_edges();
        let mut flips = vec![false; n];
        let mut piece = vec![usize::MAX; n];
        let mut members: Vec<Vec<usize>> = Vec::new();
        let mut stack = Vec::new();
        for seed in 0..n {
            if piece[seed] != usize::MAX {
                continue;
            }
            let id = members.len();
            members.push(Vec::new());
            piece[seed] = id;
            stack.push(seed);
            while let Some(t) = stack.pop() {
                members[id].push(t);
                let tri = self.triangles[t];
                for (k, &other) in across[t].iter().enumerate() {
                    let Some((u, u_forward)) = other.get() else {
                        continue;
                    };
                    if piece[u] != usize::MAX {
                        continue;
                    }
                    let forward = (tri[k] < tri[(k + 1) % 3]) != flips[t];
                    // Consistent neighbours run the shared edge in opposite directions.
                    flips[u] = u_forward == forward;
                    piece[u] = id;
                    stack.push(u);
                }
            }
        }
        Pieces { members, flips }
    }

    /// For each triangle's edge `k` (from corner `k` to `k + 1`), the other triangle when
    /// exactly two triangles use the edge, with whether that one runs it from the smaller
    /// vertex index to the larger. Found by sorting the edges, not by a map of lists: a
    /// 1.3 M-triangle mesh spent most of its orientation time allocating those lists.
    fn across_two_triangle_edges(&self) -> Vec<[Across; 3]> {
        let n = self.triangles.len();
        // (smaller vertex, larger vertex, triangle, edge): sorted, equal edges are adjacent and
        // in triangle order.
        let mut ends: Vec<(u64, usize)> = (0..3 * n)
            .into_par_iter()
            .map(|at| {
                let tri = self.triangles[at / 3];
                let (a, b) = (tri[at % 3], tri[(at % 3 + 1) % 3]);
                (super::edge_key(a, b), at)
            })
            .collect();
        ends.par_sort_unstable();
        let mut across = vec![[Across::NONE; 3]; n];
        let mut i = 0;
        while i < ends.len() {
            let mut j = i + 1;
            while j < ends.len() && ends[j].0 == ends[i].0 {
                j += 1;
            }
            if j - i == 2 {
                let [(_, p), (_, q)] = [ends[i], ends[i + 1]];
                if p / 3 != q / 3 {
                    let forward = |at: usize| {
                        let tri = self.triangles[at / 3];
                        tri[at % 3] < tri[(at % 3 + 1) % 3]
                    };
                    across[p / 3][p % 3] = Across::new(q / 3, forward(q));
                    across[q / 3][q % 3] = Across::new(p / 3, forward(p));
                }
            }
            i = j;
        }
        across
    }

    fn corners(&self, t: usize) -> Option<[DVec3; 3]> {
        let [a, b, c] = self.triangles[t];
        let get = |i: u32| self.positions.get(i as usize).map(|p| p.as_dvec3());
        Some([get(a)?, get(b)?, get(c)?])
    }

    fn area(&self, t: usize) -> f64 {
        self.corners(t)
            .map_or(0.0, |[a, b, c]| (b - a).cross(c - a).length() / 2.0)
    }

    /// Volume enclosed with the given triangles turned, about the first vertex to keep the
    /// sums small.
    fn signed_volume(&self, turned: &[bool]) -> f64 {
        let Some(origin) = self.positions.first().map(|p| p.as_dvec3()) else {
            return 0.0;
        };
        (0..self.triangles.len())
            .filter_map(|t| {
                let [a, b, c] = self.corners(t)?;
                let v = (a - origin).dot((b - origin).cross(c - origin)) / 6.0;
                Some(if turned[t] { -v } else { v })
            })
            .sum()
    }
}

/// The triangle across an edge and the direction it runs the edge in, packed in one word;
/// `NONE` where the edge is not shared by exactly two triangles.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Across(u64);

impl Across {
    const NONE: Across = Across(u64::MAX);

    fn new(triangle: usize, forward: bool) -> Across {
        Across(((triangle as u64) << 1) | forward as u64)
    }

    fn get(self) -> Option<(usize, bool)> {
        (self != Across::NONE).then_some(((self.0 >> 1) as usize, self.0 & 1 == 1))
    }
}

/// Triangles grouped into pieces connected across two-triangle edges.
struct Pieces {
    members: Vec<Vec<usize>>,
    /// Per triangle, whether turning it makes its piece consistent.
    flips: Vec<bool>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cube(lo: f32, hi: f32) -> Mesh {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let positions = vec![
            p(lo, lo, lo),
            p(hi, lo, lo),
            p(hi, hi, lo),
            p(lo, hi, lo),
            p(lo, lo, hi),
            p(hi, lo, hi),
            p(hi, hi, hi),
            p(lo, hi, hi),
        ];
        let triangles = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        Mesh::new(positions, triangles)
    }

    /// The walk by a map from each edge to the triangles using it, in triangle order: what the
    /// sorted edges must reproduce, flips and the order of each piece's members alike.
    fn by_edge_map(mesh: &Mesh) -> (Vec<Vec<usize>>, Vec<bool>) {
        use std::collections::HashMap;
        let n = mesh.triangles.len();
        let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                edges
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push((t, a < b));
            }
        }
        let (mut flips, mut piece) = (vec![false; n], vec![usize::MAX; n]);
        let mut members: Vec<Vec<usize>> = Vec::new();
        for seed in 0..n {
            if piece[seed] != usize::MAX {
                continue;
            }
            let id = members.len();
            members.push(Vec::new());
            piece[seed] = id;
            let mut stack = vec![seed];
            while let Some(t) = stack.pop() {
                members[id].push(t);
                let tri = mesh.triangles[t];
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    let sharing = &edges[&(a.min(b), a.max(b))];
                    if sharing.len() != 2 {
                        continue;
                    }
                    let forward = (a < b) != flips[t];
                    for &(u, u_forward) in sharing {
                        if u == t || piece[u] != usize::MAX {
                            continue;
                        }
                        flips[u] = u_forward == forward;
                        piece[u] = id;
                        stack.push(u);
                    }
                }
            }
        }
        (members, flips)
    }

    /// Random faces on few vertices (so edges are shared by one, two or more triangles, some
    /// faces repeat a vertex, and pieces cannot always be made consistent) and a grid of
    /// randomly wound quads: the same pieces, members in the same order, and flips.
    #[test]
    fn sorted_edges_walk_as_an_edge_map_does() {
        let mut state = 0x853c_49e6_748f_ea9bu64;
        let mut next = move |m: u32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as u32
        };
        let mut meshes = Vec::new();
        for (vertices, faces) in [(6, 10), (12, 40), (30, 200), (200, 300)] {
            let triangles = (0..faces)
                .map(|_| [next(vertices), next(vertices), next(vertices)])
                .collect();
            meshes.push(Mesh::new(vec![Vec3::ZERO; vertices as usize], triangles));
        }
        let side = 20u32;
        let mut grid = Vec::new();
        for j in 0..side - 1 {
            for i in 0..side - 1 {
                let v = j * side + i;
                let (a, b) = ([v, v + 1, v + side + 1], [v, v + side + 1, v + side]);
                for t in [a, b] {
                    grid.push(if next(2) == 0 { t } else { [t[0], t[2], t[1]] });
                }
            }
        }
        meshes.push(Mesh::new(vec![Vec3::ZERO; (side * side) as usize], grid));
        for mesh in &meshes {
            let pieces = mesh.turn_consistently();
            let (members, flips) = by_edge_map(mesh);
            assert_eq!(pieces.members, members);
            assert_eq!(pieces.flips, flips);
        }
        // The grid is one piece, turned to agree everywhere.
        assert_eq!(meshes.last().unwrap().turn_consistently().members.len(), 1);
    }

    fn volume(mesh: &Mesh) -> f32 {
        mesh.stats().volume as f32
    }

    #[test]
    fn an_outward_cube_is_left_alone() {
        let mut m = cube(0.0, 1.0);
        assert_eq!(m.orient_outward(), 0);
        assert!((volume(&m) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_reversed_cube_is_turned_outward() {
        let mut m = cube(0.0, 1.0);
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        m.normals = vec![Vec3::X; m.positions.len()];
        assert_eq!(m.orient_outward(), 12);
        assert!((volume(&m) - 1.0).abs() < 1e-6);
        // Normals that went with the old winding are not kept.
        assert!(m.normals.is_empty());
        let mut kept = cube(0.0, 1.0);
        kept.normals = vec![Vec3::X; kept.positions.len()];
        kept.orient_outward();
        assert_eq!(kept.normals.len(), kept.positions.len());
    }

    #[test]
    fn half_reversed_faces_become_consistent_and_outward() {
        let mut m = cube(0.0, 1.0);
        for t in m.triangles.iter_mut().step_by(2) {
            t.swap(1, 2);
        }
        m.orient_outward();
        let stats = m.stats();
        assert!(stats.winding_consistent);
        assert!((stats.volume - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_cavity_stays_a_cavity_when_both_shells_are_wound_alike() {
        for (flip_outer, flip_inner) in [(false, false), (true, true)] {
            let mut outer = cube(0.0, 3.0);
            let mut inner = cube(1.0, 2.0);
            // A cavity's boundary faces into the cavity.
            for t in &mut inner.triangles {
                t.swap(1, 2);
            }
            for (m, flip) in [(&mut outer, flip_outer), (&mut inner, flip_inner)] {
                if flip {
                    for t in &mut m.triangles {
                        t.swap(1, 2);
                    }
                }
            }
            let offset = outer.positions.len() as u32;
            outer.positions.extend(inner.positions);
            outer
                .triangles
                .extend(inner.triangles.iter().map(|t| t.map(|i| i + offset)));
            outer.orient_outward();
            assert!(
                (volume(&outer) - 26.0).abs() < 1e-4,
                "{flip_outer} {flip_inner}"
            );
        }
    }
}
