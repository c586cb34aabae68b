//! Planar contour stacks (slices of CT scans, layer files) as oriented points for the
//! reconstruction: points along every loop with the in-plane outward normal, and caps where a
//! layer's region is not covered by the next layer up or down (tops, bottoms, branches ending,
//! the overhang of a leaning part), half a layer beyond it, facing along the stacking axis.

use glam::Vec3;

use crate::PointCloud;

/// One plane of closed loops in its own coordinates (u, v); loops of any orientation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContourPlane {
    pub height: f32,
    pub loops: Vec<Vec<[f32; 2]>>,
}

/// Points of a contour stack stacked along axis `axis` (0, 1, 2 for x, y, z; the plane's u, v
/// are the next two axes cyclically, as `pgvol slice` writes them), spaced `step` along the
/// loops and over the caps. Planes must be sorted by height; the caps lie half the local
/// layer distance beyond the planes.
pub fn contour_points(planes: &[ContourPlane], axis: usize, step: f32) -> PointCloud {
    let to_3d = |h: f32, u: f32, v: f32| {
        let mut p = [0.0; 3];
        p[axis % 3] = h;
        p[(axis + 1) % 3] = u;
        p[(axis + 2) % 3] = v;
        Vec3::from_array(p)
    };
    let mut cloud = PointCloud {
        points: Vec::new(),
        normals: Some(Vec::new()),
    };
    let mut normals = Vec::new();
    for plane in planes {
        for (i, lp) in plane.loops.iter().enumerate() {
            // Outer boundaries counter-clockwise, holes clockwise, by nesting depth.
            let depth = plane
                .loops
                .iter()
                .enumerate()
                .filter(|&(j, other)| j != i && lp.first().is_some_and(|&p| inside_loop(other, p)))
                .count();
            let flip = (signed_area(lp) > 0.0) != (depth % 2 == 0);
            let sign = if flip { -1.0 } else { 1.0 };
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                let d = [b[0] - a[0], b[1] - a[1]];
                let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
                if len <= 0.0 {
                    continue;
                }
                // Right of the direction of travel is outside for a counter-clockwise loop.
                let n = [sign * d[1] / len, -sign * d[0] / len];
                let pieces = (len / step).ceil().max(1.0) as usize;
                for s in 0..pieces {
                    let t = s as f32 / pieces as f32;
                    cloud
                        .points
                        .push(to_3d(plane.height, a[0] + t * d[0], a[1] + t * d[1]));
                    normals.push(to_3d(0.0, n[0], n[1]));
                }
            }
        }
    }
    for (i, plane) in planes.iter().enumerate() {
        for (neighbour, dir) in [(i.checked_sub(1), -1.0f32), (Some(i + 1), 1.0)] {
            let other = neighbour.and_then(|j| planes.get(j));
            let gap = match other {
                Some(o) => (o.height - plane.height).abs(),
                None => planes
                    .get(if dir > 0.0 { i.wrapping_sub(1) } else { i + 1 })
                    .map_or(step, |o| (o.height - plane.height).abs()),
            };
            let h = plane.height + dir * 0.5 * gap;
            for [u, v] in region_samples(plane, step) {
                if other.is_some_and(|o| inside_region(o, [u, v])) {
                    continue;
                }
                cloud.points.push(to_3d(h, u, v));
                normals.push(to_3d(dir, 0.0, 0.0));
            }
        }
    }
    cloud.normals = Some(normals);
    cloud
}

/// Twice the signed area: positive for counter-clockwise loops.
fn signed_area(lp: &[[f32; 2]]) -> f32 {
    (0..lp.len())
        .map(|k| {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// Even-odd test of `p` against one loop.
pub(crate) fn inside_loop(lp: &[[f32; 2]], p: [f32; 2]) -> bool {
    let mut inside = false;
    for k in 0..lp.len() {
        let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let u = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if u > p[0] {
                inside = !inside;
            }
        }
    }
    inside
}

/// Even-odd test against every loop of a plane: holes and islands alike.
pub(crate) fn inside_region(plane: &ContourPlane, p: [f32; 2]) -> bool {
    plane.loops.iter().filter(|lp| inside_loop(lp, p)).count() % 2 == 1
}

/// Points `step` apart on a square lattice inside the plane's region, found row by row from
/// the crossings of every loop edge with the row.
fn region_samples(plane: &ContourPlane, step: f32) -> Vec<[f32; 2]> {
    let all = plane.loops.iter().flatten();
    let (lo, hi) = all.fold(
        ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let mut out = Vec::new();
    if lo[0] > hi[0] || lo[0].is_nan() || step.is_nan() || step <= 0.0 || step.is_infinite() {
        return out;
    }
    let rows = ((hi[1] - lo[1]) / step).floor() as usize;
    let mut crossings = Vec::new();
    for r in 0..=rows {
        let v = lo[1] + (r as f32 + 0.5) * step;
        crossings.clear();
        for lp in &plane.loops {
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                if (a[1] > v) != (b[1] > v) {
                    crossings.push(a[0] + (v - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
                }
            }
        }
        crossings.sort_by(f32::total_cmp);
        for pair in crossings.chunks_exact(2) {
            // Lattice columns inside [pair[0], pair[1]].
            let first = ((pair[0] - lo[0]) / step - 0.5).ceil().max(0.0) as usize;
            let mut c = first;
            loop {
                let u = lo[0] + (c as f32 + 0.5) * step;
                if u > pair[1] {
                    break;
                }
                out.push([u, v]);
                c += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: [f32; 2], r: f32, ccw: bool) -> Vec<[f32; 2]> {
        let mut s = vec![
            [c[0] - r, c[1] - r],
            [c[0] + r, c[1] - r],
            [c[0] + r, c[1] + r],
            [c[0] - r, c[1] + r],
        ];
        if !ccw {
            s.reverse();
        }
        s
    }

    #[test]
    fn normals_point_out_of_the_solid_whatever_the_loop_orientation() {
        // A square with a square hole, both given clockwise.
        let plane = ContourPlane {
            height: 0.0,
            loops: vec![
                square([0.0, 0.0], 1.0, false),
                square([0.0, 0.0], 0.5, false),
            ],
        };
        let cloud = contour_points(&[plane], 2, 0.1);
        let normals = cloud.normals.unwrap();
        for (p, n) in cloud.points.iter().zip(&normals) {
            if p.z != 0.0 {
                continue;
            }
            let r = p.x.abs().max(p.y.abs());
            // Outer boundary faces away from the centre, the hole's towards it.
            let out = Vec3::new(p.x, p.y, 0.0).dot(*n);
            if (r - 1.0).abs() < 1e-4 {
                assert!(out > 0.0, "{p} {n}");
            } else {
                assert!((r - 0.5).abs() < 1e-4 && out < 0.0, "{p} {n}");
            }
        }
        // Caps above and below, only over the ring.
        let caps: Vec<_> = cloud.points.iter().filter(|p| p.z != 0.0).collect();
        assert!(!caps.is_empty());
        assert!(caps.iter().all(|p| p.x.abs().max(p.y.abs()) > 0.5));
    }
}
