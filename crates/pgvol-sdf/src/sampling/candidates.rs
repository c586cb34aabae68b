//! The candidate leaves of one brick in groups of eight (one array per field within a group), and
//! the closest-point scan of a node over them: eight leaf boxes and eight triangles per step.
//!
//! The scan makes the decisions of [`Bvh::closest_among`] in the same order (which leaves to
//! open, which triangle wins), so its answers are identical; the wide steps only compute the
//! same box and triangle distances several at a time. It runs as an AVX2 build where the CPU
//! has it and as a baseline SSE2 build otherwise, with identical answers.
//!
//! It also skips the leaves whose oriented box (see `leaf_bounds.rs`) lies no nearer than the
//! best distance so far. None of their triangles is nearer, and a triangle wins only by being
//! strictly nearer, so skipping them changes no answer: the same triangles win in the same
//! order.

use glam::{Vec3, Vec3A};

use crate::{
    bvh::{Bvh, Closest},
    leaf_bounds::SHRINK,
    wide::{Pair, Wide},
};

/// Leaves per step of the box test, and triangles per step of a leaf scan.
const STEP: usize = 8;
const _: () = assert!(crate::bvh::MAX_LEAF <= STEP, "a leaf must fit in one step");

/// Relative slack on the distances that decide where a node's scan stops: a few hundred times
/// their rounding error.
const CUT_SLACK: f32 = 1e-5;

/// The leaves from [`Bvh::leaves_near_box`] for one brick in groups of [`STEP`], one array
/// per field within a group, the last group padded with boxes at infinity. One group is one
/// step of the scan: its fields sit together in memory and need no bounds checks.
#[derive(Default)]
pub(super) struct LeafTable {
    /// The centre of the box the leaves were gathered for.
    centre: Vec3A,
    groups: Vec<Group>,
    /// Per group, the leaves' oriented boxes (filled only when they are used).
    oriented_groups: Vec<OrientedGroup>,
    /// Whether the scans run their AVX2 build.
    avx2: bool,
    /// Whether leaves are skipped by their oriented boxes.
    oriented: bool,
}

/// [`STEP`] leaves: their axis-aligned boxes and triangles.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Group {
    min: [[f32; STEP]; 3],
    max: [[f32; STEP]; 3],
    /// Distance from the brick's centre to each leaf's box, ascending over the table.
    centre_distance: [f32; STEP],
    first: [u32; STEP],
    count: [u32; STEP],
}

impl Group {
    /// Padding: boxes at infinity, never within reach, with no triangles.
    const EMPTY: Group = Group {
        min: [[f32::INFINITY; STEP]; 3],
        max: [[f32::INFINITY; STEP]; 3],
        centre_distance: [f32::INFINITY; STEP],
        first: [0; STEP],
        count: [0; STEP],
    };
}

/// The oriented boxes (see `leaf_bounds.rs`) of a group's leaves: first two axes and half
/// extents.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct OrientedGroup {
    first_axis: [[f32; STEP]; 3],
    second_axis: [[f32; STEP]; 3],
    half: [[f32; STEP]; 3],
}

impl OrientedGroup {
    const EMPTY: OrientedGroup = OrientedGroup {
        first_axis: [[f32::INFINITY; STEP]; 3],
        second_axis: [[f32::INFINITY; STEP]; 3],
        half: [[f32::INFINITY; STEP]; 3],
    };
}

impl LeafTable {
    /// Refills the table with `leaves`, as [`Bvh::leaves_near_box`] returns them for a box
    /// centred on `centre`. `oriented` turns the skipping of leaves by their oriented boxes on.
    pub fn fill(
        &mut self,
        bvh: &Bvh,
        centre: Vec3A,
        leaves: &[(f32, u32)],
        avx2: bool,
        oriented: bool,
    ) {
        self.centre = centre;
        self.avx2 = avx2;
        self.oriented = oriented;
        let groups = leaves.len().div_ceil(STEP);
        self.groups.clear();
        self.groups.resize(groups, Group::EMPTY);
        self.oriented_groups.clear();
        if oriented {
            self.oriented_groups.resize(groups, OrientedGroup::EMPTY);
        }
        for (i, &(distance, id)) in leaves.iter().enumerate() {
            let (g, lane) = (i / STEP, i % STEP);
            let node = &bvh.nodes[id as usize];
            let group = &mut self.groups[g];
            for axis in 0..3 {
                group.min[axis][lane] = node.min[axis];
                group.max[axis][lane] = node.max[axis];
            }
            group.centre_distance[lane] = distance;
            group.first[lane] = node.first;
            group.count[lane] = node.count;
            if oriented {
                let (group, box_) = (&mut self.oriented_groups[g], &bvh.oriented[id as usize]);
                for c in 0..3 {
                    group.first_axis[c][lane] = box_.first[c];
                    group.second_axis[c][lane] = box_.second[c];
                    group.half[c][lane] = box_.half[c];
                }
            }
        }
    }

    /// As [`Bvh::closest_among`] over the table's leaves and the leaf of slot `start`, for a
    /// point `p` of the brick, but without the closest point itself (see [`Nearest::closest`]).
    #[inline]
    pub fn closest(&self, bvh: &Bvh, p: Vec3A, start: u32, limit_squared: f32) -> Nearest {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where `wide::avx2_available` said the CPU has AVX2.
            return unsafe { self.closest_avx2(bvh, p, start, limit_squared) };
        }
        self.closest_wide::<Pair>(bvh, p, start, limit_squared)
    }

    /// The AVX2 build of the scan.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn closest_avx2(&self, bvh: &Bvh, p: Vec3A, start: u32, limit_squared: f32) -> Nearest {
        self.closest_wide::<crate::wide::Avx>(bvh, p, start, limit_squared)
    }

    #[inline(always)]
    fn closest_wide<W: Wide>(
        &self,
        bvh: &Bvh,
        p: Vec3A,
        start: u32,
        limit_squared: f32,
    ) -> Nearest {
        debug_assert_eq!(W::LANES, STEP);
        // The start's leaf first, whole: the scan below skips it.
        let [start_first, start_count] = bvh.leaf_of_slot(start);
        let mut scan = Scan {
            bvh,
            p,
            best_squared: f32::INFINITY,
            best_slot: None,
            limit_squared,
        };
        scan.start_leaf::<W>(start_first as usize, start_count as usize);
        let (px, py, pz) = (W::splat(p.x), W::splat(p.y), W::splat(p.z));
        let mut box_distances = [0.0f32; STEP];
        let mut oriented_bounds = [0.0f32; STEP];
        // Leaves are sorted by their distance from the centre, which less `p`'s distance from
        // it bounds their distance to `p` from below: from the first one whose bound is beyond
        // the reach on, none can be opened. The relative slack covers the rounding of the
        // three distances, so the scan never stops before a leaf its box test would open.
        let from_centre = (p - self.centre).length() * (1.0 + CUT_SLACK);
        for (g, group) in self.groups.iter().enumerate() {
            let below = group.centre_distance[0] * (1.0 - CUT_SLACK) - from_centre;
            if below > 0.0 && below * below > scan.reach() * (1.0 + CUT_SLACK) {
                break;
            }
            // The arithmetic of `Node::distance_squared`, lane by lane.
            let dx = gap::<W>(group, 0, px);
            let dy = gap::<W>(group, 1, py);
            let dz = gap::<W>(group, 2, pz);
            let d2 = dx * dx + dy * dy + dz * dz;
            let mut open = W::bits(d2.le(W::splat(scan.reach())));
            if open == 0 {
                continue;
            }
            if self.oriented {
                let bound = self.oriented_bound::<W>(g, [px, py, pz]);
                open &= W::bits(bound.lt(W::splat(scan.best_squared)));
                bound.store(&mut oriented_bounds);
            }
            d2.store(&mut box_distances);
            while open != 0 {
                let lane = open.trailing_zeros() as usize;
                open &= open - 1;
                // The best only shrinks: a leaf may fall out as the leaves before it open.
                if self.oriented && oriented_bounds[lane] >= scan.best_squared {
                    continue;
                }
                if group.first[lane] == start_first {
                    continue;
                }
                scan.leaf::<W>(
                    box_distances[lane],
                    group.first[lane] as usize,
                    group.count[lane] as usize,
                );
            }
        }
        Nearest {
            distance_squared: scan.best_squared,
            slot: scan.best_slot.expect("the start leaf sets a best") as u32,
        }
    }
}

/// How far `p` lies outside the boxes of the group's leaves along `axis` (0 inside).
#[inline(always)]
fn gap<W: Wide>(group: &Group, axis: usize, p: W) -> W {
    let lo = W::load(&group.min[axis]);
    let hi = W::load(&group.max[axis]);
    (lo - p).max(p - hi).max(W::splat(0.0))
}

/// The answer of [`LeafTable::closest`]: the squared distance to the mesh and the leaf slot of
/// a closest triangle.
#[derive(Clone, Copy, Debug)]
pub(super) struct Nearest {
    pub distance_squared: f32,
    pub slot: u32,
}

impl Nearest {
    /// The closest point, as [`Bvh::closest_among`] finds it. Only the pseudonormal sign needs
    /// it.
    pub fn closest(&self, bvh: &Bvh, p: Vec3A) -> Closest {
        bvh.closest_on_slot(Vec3::from(p), self.slot)
    }
}

/// One node's scan.
///
/// It makes the scalar scan's decisions in its order: a leaf is opened only if its box is within
/// the reach when its turn comes, and a triangle wins only if its distance is smaller than the
/// best so far. (Two small leaves sharing a step saved little and delayed the first one's
/// answer, which opened more leaves: a step per leaf made 12-14 % fewer mispredicted branches.)
struct Scan<'a> {
    bvh: &'a Bvh,
    p: Vec3A,
    /// The smallest squared distance so far, and the slot of its triangle (`None` before the
    /// start's leaf). Lanes hold the scalar code's distances, so only the winner's closest
    /// point is needed.
    best_squared: f32,
    best_slot: Option<usize>,
    limit_squared: f32,
}

impl Scan<'_> {
    /// The scalar scan's reach: leaves farther than this are not opened.
    #[inline(always)]
    fn reach(&self) -> f32 {
        self.best_squared.min(self.limit_squared)
    }

    /// The start's leaf, before any other: its nearest triangle, the first of equals (as
    /// [`Bvh::closest_among`] takes it), found without a branch per triangle. Leaves hold at
    /// most [`STEP`] triangles (see `Bvh::build`).
    #[inline(always)]
    fn start_leaf<W: Wide>(&mut self, first: usize, count: usize) {
        assert!((1..=STEP).contains(&count), "a leaf of {count} triangles");
        let mut d2 = self.bvh.lanes.distances_squared_wide::<W>(self.p, first);
        let valid = (1u32 << count) - 1;
        let mut lanes = [f32::INFINITY; STEP];
        d2.store(&mut lanes);
        let mut nan = !W::bits(d2.le(W::splat(f32::INFINITY))) & valid;
        if nan != 0 {
            while nan != 0 {
                let lane = nan.trailing_zeros() as usize;
                nan &= nan - 1;
                lanes[lane] = self
                    .bvh
                    .closest_on_slot(Vec3::from(self.p), (first + lane) as u32)
                    .distance_squared;
            }
            d2 = W::load(&lanes);
        }
        let mut best = f32::INFINITY;
        for &d in &lanes[..count] {
            best = best.min(d);
        }
        let lane = (W::bits(d2.le(W::splat(best))) & valid).trailing_zeros() as usize;
        self.best_squared = best;
        self.best_slot = Some(first + lane.min(count - 1));
    }

    /// Opens the leaf whose triangles are `first .. first + count`, at squared distance
    /// `distance_squared` from the node, if it is within reach: one kernel step, as leaves
    /// hold at most [`STEP`] triangles. NaN lanes (degenerate triangles) are asked of the
    /// scalar code.
    #[inline(always)]
    fn leaf<W: Wide>(&mut self, distance_squared: f32, first: usize, count: usize) {
        if distance_squared > self.reach() {
            return;
        }
        let d2 = self.bvh.lanes.distances_squared_wide::<W>(self.p, first);
        let valid = (1u32 << count.min(STEP)) - 1;
        let mut ask = W::bits(!d2.ge(W::splat(self.best_squared))) & valid;
        if ask == 0 {
            return;
        }
        let mut lanes = [0.0; STEP];
        d2.store(&mut lanes);
        while ask != 0 {
            let lane = ask.trailing_zeros() as usize;
            ask &= ask - 1;
            let mut d2 = lanes[lane];
            if d2.is_nan() {
                d2 = self
                    .bvh
                    .closest_on_slot(Vec3::from(self.p), (first + lane) as u32)
                    .distance_squared;
            }
            if d2 < self.best_squared {
                self.best_squared = d2;
                self.best_slot = Some(first + lane);
            }
        }
    }
}

impl LeafTable {
    /// [`OrientedBox::distance_squared_bound`](crate::leaf_bounds::OrientedBox) for `p` and
    /// the leaves of group `g`, by the same arithmetic.
    #[inline(always)]
    fn oriented_bound<W: Wide>(&self, g: usize, p: [W; 3]) -> W {
        let (group, oriented) = (&self.groups[g], &self.oriented_groups[g]);
        // No closures: outside the AVX2 build they are not always inlined.
        let mut d = [W::splat(0.0); 3];
        let (mut a, mut b, mut half) = (d, d, d);
        for c in 0..3 {
            let (lo, hi) = (W::load(&group.min[c]), W::load(&group.max[c]));
            d[c] = p[c] - (lo + hi) * W::splat(0.5);
            a[c] = W::load(&oriented.first_axis[c]);
            b[c] = W::load(&oriented.second_axis[c]);
            half[c] = W::load(&oriented.half[c]);
        }
        let third = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let zero = W::splat(0.0);
        let mut sum = zero;
        for (axis, half) in [a, b, third].into_iter().zip(half) {
            let along = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
            let gap = (along - half).max(zero - along - half).max(zero);
            sum = sum + gap * gap;
        }
        sum * W::splat(SHRINK)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{triangle::closest_point_and_distance, wide::avx2_available};
    use glam::Vec3;
    use pgvol_mesh::Mesh;
    use rand::{Rng, SeedableRng};

    /// Small triangles in clusters, as on a finely tessellated surface, with degenerate ones
    /// (points, segments, collinear corners) mixed in.
    fn soup(seed: u64) -> Mesh {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for t in 0..3000u32 {
            let c = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 2.0;
            let corner = |rng: &mut rand_pcg::Pcg64| {
                c + (Vec3::new(rng.gen(), rng.gen(), rng.gen()) - 0.5) * 0.05
            };
            let (a, b) = (corner(&mut rng), corner(&mut rng));
            let c = match t % 50 {
                0 => a,
                1 => b,
                2 => a + (b - a) * 2.0,
                _ => corner(&mut rng),
            };
            positions.extend([a, b, c]);
            triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        Mesh::new(positions, triangles)
    }

    #[test]
    fn table_scans_match_the_scalar_scan_and_brute_force() {
        let mesh = soup(7);
        let tris: Vec<[Vec3A; 3]> = (0..mesh.triangles.len())
            .map(|t| mesh.triangle(t).map(Vec3A::from))
            .collect();
        let bvh = Bvh::build(&mesh);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(8);
        let (mut leaves, mut table) = (Vec::new(), LeafTable::default());
        for _ in 0..60 {
            let lo = Vec3A::new(rng.gen(), rng.gen(), rng.gen()) * 3.0 - 0.5;
            let hi = lo + Vec3A::splat(0.06);
            let seed = bvh.closest((lo + hi).into(), f32::INFINITY).unwrap();
            let bound = (0..8)
                .map(|c| {
                    let corner =
                        Vec3A::select(glam::BVec3A::new(c & 1 > 0, c & 2 > 0, c & 4 > 0), hi, lo);
                    bvh.closest_on_slot(corner.into(), seed.slot)
                        .distance_squared
                })
                .fold(0.0f32, f32::max);
            bvh.leaves_near_box(lo, hi, bound * (1.0 + 1e-4), &mut leaves);
            for (avx2, oriented) in [(false, false), (false, true), (avx2_available(), true)] {
                table.fill(&bvh, (lo + hi) * 0.5, &leaves, avx2, oriented);
                if oriented {
                    oriented_bounds_match_the_scalar_ones(&bvh, &table, &leaves, lo, hi);
                }
                let mut slot = seed.slot;
                for n in 0..27 {
                    let f = Vec3A::new((n % 3) as f32, ((n / 3) % 3) as f32, (n / 9) as f32) / 2.0;
                    let p = lo + (hi - lo) * f;
                    for limit in [f32::INFINITY, seed.distance_squared] {
                        let want = bvh.closest_among(p.into(), &leaves, slot, limit);
                        let got = table.closest(&bvh, p, slot, limit);
                        assert_eq!(
                            got.distance_squared.to_bits(),
                            want.distance_squared.to_bits()
                        );
                        assert_eq!(got.slot, want.slot);
                        assert_eq!(got.closest(&bvh, p), want);
                    }
                    let got = table.closest(&bvh, p, slot, f32::INFINITY);
                    let brute = tris
                        .iter()
                        .map(|&[a, b, c]| closest_point_and_distance(p, a, b, c).2)
                        .fold(f32::INFINITY, f32::min);
                    assert_eq!(got.distance_squared, brute, "point {p}");
                    slot = got.slot;
                }
            }
        }
    }

    /// The wide oriented bounds are [`OrientedBox::distance_squared_bound`]'s, bit for bit.
    fn oriented_bounds_match_the_scalar_ones(
        bvh: &Bvh,
        table: &LeafTable,
        leaves: &[(f32, u32)],
        lo: Vec3A,
        hi: Vec3A,
    ) {
        for n in 0..5 {
            let p = lo + (hi - lo) * (n as f32 / 4.0);
            let splat = [p.x, p.y, p.z].map(Pair::splat);
            for at in (0..leaves.len()).step_by(STEP) {
                let mut wide = [0.0; STEP];
                table
                    .oriented_bound::<Pair>(at / STEP, splat)
                    .store(&mut wide);
                for (lane, &(_, id)) in leaves[at..].iter().take(STEP).enumerate() {
                    let node = &bvh.nodes[id as usize];
                    let scalar =
                        bvh.oriented[id as usize].distance_squared_bound(p, node.min, node.max);
                    assert_eq!(wide[lane].to_bits(), scalar.to_bits());
                }
            }
        }
    }
}
