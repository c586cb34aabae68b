//! Orientation repair: faces turned consistently within each connected piece, and each piece
//! turned outward, so that distance signs do not depend on how the faces were wound.

use std::collections::HashMap;

use glam::DVec3;

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
        count
    }

    /// Connected pieces across two-triangle edges, with the flips that make each consistent.
    fn turn_consistently(&self) -> Pieces {
        let n = self.triangles.len();
        let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::with_capacity(3 * n / 2);
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                edges
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push((t, a < b));
            }
        }
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
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    let Some(sharing) = edges.get(&(a.min(b), a.max(b))) else {
                        continue;
                    };
                    if sharing.len() != 2 {
                        continue;
                    }
                    let forward = (a < b) != flips[t];
                    for &(u, u_forward) in sharing {
                        if u == t || piece[u] != usize::MAX {
                            continue;
                        }
                        // Consistent neighbours run the shared edge in opposite directions.
                        flips[u] = u_forward == forward;
                        piece[u] = id;
                        stack.push(u);
                    }
                }
            }
        }
        Pieces { members, flips }
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
        assert_eq!(m.orient_outward(), 12);
        assert!((volume(&m) - 1.0).abs() < 1e-6);
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
