//! Leaning parts: regions of neighbouring planes that belong together but barely overlap.
//!
//! Interpolating distances joins two regions only where they overlap: between two discs side
//! by side a point is outside both, so each closes halfway to the other and a leaning part
//! falls into pieces. Here the outer regions of neighbouring planes are matched (mutually
//! nearest centroids, not too far apart) and, where a matched pair overlaps by less than half
//! the smaller region, the pair is also interpolated in a frame that moves with the centroid:
//! at a fraction t of the way up, (1 − t) d_A(p − tΔ) + t d_B(p + (1 − t)Δ), Δ the centroid
//! shift (shape-based interpolation with correspondence). The stack takes the smaller of this
//! and its own interpolation between the planes, so the pair joins and nothing else changes;
//! for convex regions the sheared interpolation already holds the plain one (the distance to a
//! convex region is convex).

use crate::contours::{inside_loop, ContourPlane};
use crate::plane_distance::{plane_distance, Lattice};

/// Matched regions are bridged when they share less than this fraction of the smaller one's
/// nodes.
const MAX_OVERLAP: f32 = 0.5;

/// Matched regions are bridged only when their centroids are less than this many times the
/// sum of their radii (of the discs of the same areas) apart …
const MAX_SHIFT_RADII: f32 = 2.0;

/// … and less than this many layer distances apart (a lean of at most 76° from the axis).
const MAX_SHIFT_LAYERS: f32 = 4.0;

/// A matched pair of regions on planes `lower` and `lower + 1` and their distances on a
/// sub-lattice of the plane lattice around both.
pub struct Bridge {
    pub lower: usize,
    shift: [f32; 2],
    /// First node (u, v) of the sub-lattice in the plane lattice.
    first: [usize; 2],
    sub: Lattice,
    below: Vec<f32>,
    above: Vec<f32>,
    reach: f32,
}

impl Bridge {
    /// Whether node column (i, j) of the plane lattice lies in the bridge's sub-lattice.
    pub fn covers(&self, i: usize, j: usize) -> bool {
        let [nu, nv] = self.sub.dims;
        (self.first[0]..self.first[0] + nu).contains(&i)
            && (self.first[1]..self.first[1] + nv).contains(&j)
    }

    /// The sheared interpolation at node column (i, j) a fraction `t` of the way up.
    pub fn value(&self, i: usize, j: usize, t: f32) -> f32 {
        let p = [
            self.sub.origin[0] + self.sub.spacing * (i - self.first[0]) as f32,
            self.sub.origin[1] + self.sub.spacing * (j - self.first[1]) as f32,
        ];
        let (dx, dy) = (self.shift[0], self.shift[1]);
        let below = self.sample(&self.below, [p[0] - t * dx, p[1] - t * dy]);
        let above = self.sample(&self.above, [p[0] + (1.0 - t) * dx, p[1] + (1.0 - t) * dy]);
        (1.0 - t) * below + t * above
    }

    /// Bilinear interpolation of a sub-lattice field; `reach` (far outside) off the lattice.
    fn sample(&self, field: &[f32], p: [f32; 2]) -> f32 {
        let [nu, nv] = self.sub.dims;
        let x = (p[0] - self.sub.origin[0]) / self.sub.spacing;
        let y = (p[1] - self.sub.origin[1]) / self.sub.spacing;
        if !(x >= 0.0 && y >= 0.0 && x <= (nu - 1) as f32 && y <= (nv - 1) as f32) {
            return self.reach;
        }
        let (i, j) = ((x as usize).min(nu - 2), (y as usize).min(nv - 2));
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |a: usize, b: usize| field[a + nu * b];
        (1.0 - fy) * ((1.0 - fx) * at(i, j) + fx * at(i + 1, j))
            + fy * ((1.0 - fx) * at(i, j + 1) + fx * at(i + 1, j + 1))
    }
}

/// An outer loop of a plane with the loops inside it (its holes and their islands).
struct Region {
    loops: Vec<Vec<[f32; 2]>>,
    centroid: [f32; 2],
    radius: f32,
    lo: [f32; 2],
    hi: [f32; 2],
}

/// The outer regions of a plane: loops inside no other loop, each with the loops inside it.
fn regions(plane: &ContourPlane) -> Vec<Region> {
    let boxes: Vec<([f32; 2], [f32; 2])> = plane.loops.iter().map(|lp| bounds(lp)).collect();
    // Loop i lies inside loop j when its first point does (loops do not cross); the boxes spare
    // the even-odd test for most pairs of a plane with many loops.
    let inside_of = |i: usize, j: usize| {
        let (lo, hi) = boxes[j];
        i != j
            && plane.loops[i].first().is_some_and(|&p| {
                (lo[0]..=hi[0]).contains(&p[0])
                    && (lo[1]..=hi[1]).contains(&p[1])
                    && inside_loop(&plane.loops[j], p)
            })
    };
    let n = plane.loops.len();
    (0..n)
        .filter(|&i| !(0..n).any(|j| inside_of(i, j)))
        .map(|i| {
            let outer = &plane.loops[i];
            let mut loops = vec![outer.clone()];
            loops.extend(
                (0..n)
                    .filter(|&j| inside_of(j, i))
                    .map(|j| plane.loops[j].clone()),
            );
            let (mut area, mut cx, mut cy) = (0.0f64, 0.0f64, 0.0f64);
            for k in 0..outer.len() {
                let (a, b) = (outer[k], outer[(k + 1) % outer.len()]);
                let cross = f64::from(a[0] * b[1] - b[0] * a[1]);
                area += cross;
                cx += f64::from(a[0] + b[0]) * cross;
                cy += f64::from(a[1] + b[1]) * cross;
            }
            let (lo, hi) = boxes[i];
            let centroid = if area.abs() > 0.0 {
                [(cx / (3.0 * area)) as f32, (cy / (3.0 * area)) as f32]
            } else {
                [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
            };
            let radius = ((area.abs() / 2.0) / std::f64::consts::PI).sqrt() as f32;
            Region {
                loops,
                centroid,
                radius,
                lo,
                hi,
            }
        })
        .collect()
}

/// The bridges between neighbouring planes of `planes` (sorted by height) on `lattice`, with
/// distances exact within `reach`.
pub fn find_bridges(planes: &[ContourPlane], lattice: &Lattice, reach: f32) -> Vec<Bridge> {
    let all: Vec<Vec<Region>> = planes.iter().map(regions).collect();
    let mut bridges = Vec::new();
    for k in 0..planes.len().saturating_sub(1) {
        let gap = planes[k + 1].height - planes[k].height;
        let (below, above) = (&all[k], &all[k + 1]);
        let nearest = |r: &Region, others: &[Region]| {
            others
                .iter()
                .enumerate()
                .map(|(i, o)| (i, distance(r.centroid, o.centroid)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| i)
        };
        for (ia, a) in below.iter().enumerate() {
            let Some(ib) = nearest(a, above) else {
                continue;
            };
            let b = &above[ib];
            if nearest(b, below) != Some(ia) {
                continue;
            }
            let shift = [b.centroid[0] - a.centroid[0], b.centroid[1] - a.centroid[1]];
            let length = distance(a.centroid, b.centroid);
            if length >= MAX_SHIFT_RADII * (a.radius + b.radius) || length >= MAX_SHIFT_LAYERS * gap
            {
                continue;
            }
            let Some((first, sub)) = sub_lattice(lattice, a, b, reach) else {
                continue;
            };
            let field = |r: &Region| {
                let plane = ContourPlane {
                    height: 0.0,
                    loops: r.loops.clone(),
                };
                plane_distance(&plane, &sub, reach)
            };
            let (da, db) = (field(a), field(b));
            let count = |f: &dyn Fn(usize) -> bool| (0..da.len()).filter(|&n| f(n)).count();
            let na = count(&|n| da[n] < 0.0);
            let nb = count(&|n| db[n] < 0.0);
            let both = count(&|n| da[n] < 0.0 && db[n] < 0.0);
            if both as f32 >= MAX_OVERLAP * na.min(nb) as f32 && both > 0 {
                continue;
            }
            bridges.push(Bridge {
                lower: k,
                shift,
                first,
                sub,
                below: da,
                above: db,
                reach,
            });
        }
    }
    bridges
}

/// The box of a loop's points.
fn bounds(lp: &[[f32; 2]]) -> ([f32; 2], [f32; 2]) {
    lp.iter().fold(
        ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}

fn distance(a: [f32; 2], b: [f32; 2]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// The nodes of `lattice` within `reach` of either region's box: the first node and the
/// sub-lattice, or `None` when the boxes lie off the lattice.
fn sub_lattice(
    lattice: &Lattice,
    a: &Region,
    b: &Region,
    reach: f32,
) -> Option<([usize; 2], Lattice)> {
    let mut first = [0; 2];
    let mut dims = [0; 2];
    let mut origin = [0.0; 2];
    for axis in 0..2 {
        let lo = a.lo[axis].min(b.lo[axis]) - reach;
        let hi = a.hi[axis].max(b.hi[axis]) + reach;
        let to = |x: f32| (x - lattice.origin[axis]) / lattice.spacing;
        let n = lattice.dims[axis] as f32;
        let i0 = to(lo).floor().clamp(0.0, n - 1.0) as usize;
        let i1 = to(hi).ceil().clamp(0.0, n - 1.0) as usize;
        if i1 < i0 + 1 {
            return None;
        }
        first[axis] = i0;
        dims[axis] = i1 - i0 + 1;
        origin[axis] = lattice.origin[axis] + lattice.spacing * i0 as f32;
    }
    Some((
        first,
        Lattice {
            origin,
            spacing: lattice.spacing,
            dims,
        },
    ))
}
