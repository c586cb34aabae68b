//! Depth-buffer difference between two meshes (the perturbation paper's third measure): both
//! are rendered by orthographic rasterisation into depth buffers from the same views, and the
//! mean absolute difference of the depths over the pixels either covers is reported.
//!
//! Views: the six axis directions and the eight cube corners, 14 in all, each looking at the
//! centre of the sphere around both bounding boxes, the image square spanning the sphere's
//! diameter. Depth is measured along the view from the sphere's near side; a pixel one mesh
//! misses takes the far side (the diameter), so a missing part counts with the depth it would
//! have left empty.

use glam::{DVec3, Vec3};
use pgvol_mesh::Mesh;
use rayon::prelude::*;
use serde::Serialize;

/// Pixels per side of each depth buffer.
pub const DEPTH_RESOLUTION: usize = 256;

/// The 14 view directions (unit, the direction the camera looks along).
pub fn view_directions() -> Vec<DVec3> {
    let mut views = vec![
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ];
    for k in 0..8 {
        let s = |bit: u32| if k >> bit & 1 == 1 { -1.0 } else { 1.0 };
        views.push(DVec3::new(s(0), s(1), s(2)).normalize());
    }
    views
}

/// One view's comparison.
#[derive(Clone, Debug, Serialize)]
pub struct ViewDifference {
    pub direction: [f64; 3],
    /// Pixels covered by either mesh.
    pub covered: usize,
    /// Mean absolute depth difference over those pixels, in mesh units.
    pub mean_abs: f64,
}

/// The depth buffers' comparison over all views.
#[derive(Clone, Debug, Serialize)]
pub struct DepthDifference {
    pub views: Vec<ViewDifference>,
    pub resolution: usize,
    /// Mean absolute difference over every covered pixel of every view, in mesh units.
    pub mean_abs: f64,
}

/// The orthographic frame of one view: depth axis and the two image axes.
struct Frame {
    centre: DVec3,
    radius: f64,
    view: DVec3,
    right: DVec3,
    up: DVec3,
    resolution: usize,
}

impl Frame {
    fn new(centre: DVec3, radius: f64, view: DVec3, resolution: usize) -> Self {
        let helper = if view.z.abs() > 0.9 {
            DVec3::X
        } else {
            DVec3::Z
        };
        let right = view.cross(helper).normalize();
        let up = right.cross(view);
        Self {
            centre,
            radius,
            view,
            right,
            up,
            resolution,
        }
    }

    /// Pixel coordinates (continuous, pixel centres at half-integers) and depth of `p`.
    fn project(&self, p: Vec3) -> DVec3 {
        let d = p.as_dvec3() - self.centre;
        let scale = self.resolution as f64 / (2.0 * self.radius);
        DVec3::new(
            (d.dot(self.right) + self.radius) * scale,
            (d.dot(self.up) + self.radius) * scale,
            d.dot(self.view) + self.radius,
        )
    }

    /// The depth buffer of `mesh`, `None` where no triangle covers the pixel centre.
    fn render(&self, mesh: &Mesh) -> Vec<Option<f64>> {
        let n = self.resolution;
        let mut depth: Vec<Option<f64>> = vec![None; n * n];
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.triangle(t).map(|p| self.project(p));
            let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            if area == 0.0 || !area.is_finite() {
                continue;
            }
            let lo = a.min(b).min(c);
            let hi = a.max(b).max(c);
            let x0 = (lo.x - 0.5).ceil().max(0.0) as usize;
            let y0 = (lo.y - 0.5).ceil().max(0.0) as usize;
            let x1 = ((hi.x - 0.5).floor() as i64).min(n as i64 - 1);
            let y1 = ((hi.y - 0.5).floor() as i64).min(n as i64 - 1);
            if x1 < 0 || y1 < 0 {
                continue;
            }
            for y in y0..=y1 as usize {
                for x in x0..=x1 as usize {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    // Barycentric weights by edge functions; either winding counts.
                    let wa = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
                    let wb = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
                    let wc = 1.0 - wa - wb;
                    if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                        continue;
                    }
                    let z = wa * a.z + wb * b.z + wc * c.z;
                    let cell = &mut depth[y * n + x];
                    if cell.is_none_or(|old| z < old) {
                        *cell = Some(z);
                    }
                }
            }
        }
        depth
    }
}

/// Renders `a` and `b` from the 14 views at `resolution` pixels per side and compares the
/// depth buffers. `None` when neither mesh has a vertex.
pub fn depth_difference(a: &Mesh, b: &Mesh, resolution: usize) -> Option<DepthDifference> {
    let (la, ha) = a.bounds()?;
    let (lb, hb) = b.bounds()?;
    let (lo, hi) = (la.min(lb).as_dvec3(), ha.max(hb).as_dvec3());
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(f64::MIN_POSITIVE) * 1.01;
    let resolution = resolution.max(1);
    let views: Vec<ViewDifference> = view_directions()
        .par_iter()
        .map(|&view| {
            let frame = Frame::new(centre, radius, view, resolution);
            let (da, db) = rayon::join(|| frame.render(a), || frame.render(b));
            let far = 2.0 * radius;
            let (mut covered, mut sum) = (0usize, 0.0);
            for (x, y) in da.iter().zip(&db) {
                if x.is_none() && y.is_none() {
                    continue;
                }
                covered += 1;
                sum += (x.unwrap_or(far) - y.unwrap_or(far)).abs();
            }
            ViewDifference {
                direction: view.to_array(),
                covered,
                mean_abs: if covered > 0 {
                    sum / covered as f64
                } else {
                    0.0
                },
            }
        })
        .collect();
    let covered: usize = views.iter().map(|v| v.covered).sum();
    let sum: f64 = views.iter().map(|v| v.mean_abs * v.covered as f64).sum();
    Some(DepthDifference {
        views,
        resolution,
        mean_abs: if covered > 0 {
            sum / covered as f64
        } else {
            0.0
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_mesh::shapes::{cuboid, octasphere};

    #[test]
    fn a_mesh_against_itself_differs_by_zero() {
        let m = octasphere(3);
        let d = depth_difference(&m, &m, 128).unwrap();
        assert_eq!(d.views.len(), 14);
        assert!(d.views.iter().all(|v| v.covered > 1000));
        assert_eq!(d.mean_abs, 0.0);
    }

    #[test]
    fn a_shift_along_a_view_shows_as_that_shift() {
        let a = cuboid(Vec3::ZERO, Vec3::ONE);
        let s = 0.1;
        let mut b = a.clone();
        for p in &mut b.positions {
            p.x += s;
        }
        let d = depth_difference(&a, &b, 128).unwrap();
        // Looking along ±x both silhouettes are the same square: every pixel differs by s.
        for v in &d.views[..2] {
            assert!((v.mean_abs - s as f64).abs() < 1e-5, "{v:?}");
        }
        // Along y and z the faces seen are at the same depth; only the strips the shift
        // uncovers (s wide of a 1 + s wide union) differ, by the far-plane gap.
        for v in &d.views[2..6] {
            assert!(v.mean_abs > 0.0, "{v:?}");
        }
        assert!(d.mean_abs > 0.0);
        // Twice the shift, twice the difference along ±x.
        let mut c = a.clone();
        for p in &mut c.positions {
            p.x += 2.0 * s;
        }
        let d2 = depth_difference(&a, &c, 128).unwrap();
        assert!((d2.views[0].mean_abs - 2.0 * s as f64).abs() < 1e-5);
    }
}
