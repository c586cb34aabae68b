//! Exact signed distance functions of simple solids with their gradients, for tests and
//! measurements where the true field is known everywhere.

use glam::{Quat, Vec3};

use crate::distance::SignedDistance;

/// A ball.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    pub centre: Vec3,
    pub radius: f32,
}

/// A box with half-extents `half`, rotated by `rotation` about its centre.
#[derive(Clone, Copy, Debug)]
pub struct RotatedBox {
    pub centre: Vec3,
    pub half: Vec3,
    pub rotation: Quat,
}

/// A torus around the z axis through `centre`: tube of radius `minor` around a circle of
/// radius `major`.
#[derive(Clone, Copy, Debug)]
pub struct Torus {
    pub centre: Vec3,
    pub major: f32,
    pub minor: f32,
}

impl SignedDistance for Sphere {
    fn distance(&self, p: Vec3) -> f32 {
        (p - self.centre).length() - self.radius
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let v = p - self.centre;
        let l = v.length();
        let n = if l > 0.0 { v / l } else { Vec3::X };
        (l - self.radius, n)
    }
}

impl SignedDistance for RotatedBox {
    fn distance(&self, p: Vec3) -> f32 {
        self.distance_gradient(p).0
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let local = self.rotation.inverse() * (p - self.centre);
        let sign = Vec3::select(local.cmplt(Vec3::ZERO), Vec3::NEG_ONE, Vec3::ONE);
        let q = local.abs() - self.half;
        let outer = q.max(Vec3::ZERO);
        let (d, g) = if outer.length_squared() > 0.0 {
            let l = outer.length();
            (l, sign * outer / l)
        } else {
            // Inside: the nearest face is the one with the largest (least negative) q.
            let axis = if q.x >= q.y && q.x >= q.z {
                Vec3::X
            } else if q.y >= q.z {
                Vec3::Y
            } else {
                Vec3::Z
            };
            (q.max_element(), sign * axis)
        };
        (d, self.rotation * g)
    }
}

impl SignedDistance for Torus {
    fn distance(&self, p: Vec3) -> f32 {
        self.distance_gradient(p).0
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let v = p - self.centre;
        let rho = (v.x * v.x + v.y * v.y).sqrt();
        let radial = if rho > 0.0 {
            Vec3::new(v.x / rho, v.y / rho, 0.0)
        } else {
            Vec3::X
        };
        let (qx, qz) = (rho - self.major, v.z);
        let l = (qx * qx + qz * qz).sqrt();
        let g = if l > 0.0 {
            radial * (qx / l) + Vec3::Z * (qz / l)
        } else {
            Vec3::Z
        };
        (l - self.minor, g)
    }
}

/// The half-space `normal · p ≤ offset` (`normal` of unit length): its boundary plane.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub normal: Vec3,
    pub offset: f32,
}

/// An infinite solid cylinder of `radius` around the line through `point` along unit `axis`.
#[derive(Clone, Copy, Debug)]
pub struct Cylinder {
    pub point: Vec3,
    pub axis: Vec3,
    pub radius: f32,
}

impl SignedDistance for Plane {
    fn distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        (self.distance(p), self.normal)
    }
}

impl SignedDistance for Cylinder {
    fn distance(&self, p: Vec3) -> f32 {
        self.distance_gradient(p).0
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let d = p - self.point;
        let radial = d - self.axis * d.dot(self.axis);
        let l = radial.length();
        let n = if l > 0.0 {
            radial / l
        } else {
            self.axis.any_orthonormal_vector()
        };
        (l - self.radius, n)
    }
}

/// `sdf` sampled on `grid` as the encoder samples a mesh: the bricks holding a node within
/// `band` spacings of the surface stored, their values clamped to ±`band` spacings, every other
/// brick absent on its side. For tests and studies of the sparse fits.
pub fn banded_samples(
    sdf: &dyn SignedDistance,
    grid: &pgvol_core::Grid,
    band: f32,
) -> pgvol_core::SparseGrid {
    use pgvol_core::sparse::brick_offset;
    use pgvol_core::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};

    let clamp = band * grid.spacing;
    let mut out = SparseGrid::new(grid.dims, Background::clamp(clamp));
    let bricks: Vec<[usize; 3]> = out.all_bricks().collect();
    // Half the diagonal of a brick: a brick whose centre is farther than this past the band
    // holds no node within it, and all its nodes are on the centre's side.
    let reach = clamp + 0.5 * 3f32.sqrt() * (BRICK_EDGE - 1) as f32 * grid.spacing;
    for b in bricks {
        let (lo, m) = out.brick_extent(b);
        let centre = grid.point(lo[0], lo[1], lo[2])
            + 0.5 * (BRICK_EDGE - 1) as f32 * Vec3::splat(grid.spacing);
        let d = sdf.distance(centre);
        if d.abs() > reach {
            out.set_inside(b, d < 0.0);
            continue;
        }
        let mut values = Box::new([clamp; BRICK_NODES]);
        let (mut near, mut inside) = (false, false);
        for k in 0..m[2] {
            for j in 0..m[1] {
                for i in 0..m[0] {
                    let d = sdf.distance(grid.point(lo[0] + i, lo[1] + j, lo[2] + k));
                    near |= d.abs() < clamp;
                    inside = d < 0.0;
                    values[brick_offset([i, j, k])] = d.clamp(-clamp, clamp);
                }
            }
        }
        if near {
            out.insert(b, values);
        } else if inside {
            out.set_inside(b, true);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_gradient(s: &dyn SignedDistance, p: Vec3) {
        let (_, g) = s.distance_gradient(p);
        let e = 1e-3;
        let fd = Vec3::new(
            s.distance(p + Vec3::X * e) - s.distance(p - Vec3::X * e),
            s.distance(p + Vec3::Y * e) - s.distance(p - Vec3::Y * e),
            s.distance(p + Vec3::Z * e) - s.distance(p - Vec3::Z * e),
        ) / (2.0 * e);
        assert!((g - fd).length() < 1e-2, "{p}: {g} vs {fd}");
        assert!((g.length() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn gradients_are_unit_and_match_differences() {
        let b = RotatedBox {
            centre: Vec3::new(0.1, 0.0, -0.1),
            half: Vec3::new(0.5, 0.3, 0.4),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.5, 0.2),
        };
        let t = Torus {
            centre: Vec3::ZERO,
            major: 0.5,
            minor: 0.2,
        };
        let s = Sphere {
            centre: Vec3::splat(0.1),
            radius: 0.6,
        };
        let plane = Plane {
            normal: Vec3::Y,
            offset: 0.2,
        };
        let cylinder = Cylinder {
            point: Vec3::ZERO,
            axis: Vec3::Z,
            radius: 0.5,
        };
        for p in [
            Vec3::new(0.7, 0.2, 0.1),
            Vec3::new(0.05, 0.02, -0.01),
            Vec3::new(-0.3, 0.6, 0.4),
        ] {
            check_gradient(&b, p);
            check_gradient(&t, p);
            check_gradient(&s, p);
            check_gradient(&plane, p);
            check_gradient(&cylinder, p);
        }
        assert!((cylinder.distance(Vec3::new(3.0, 0.0, 7.0)) - 2.5).abs() < 1e-6);
        assert!((plane.distance(Vec3::new(0.0, 2.0, 0.0)) - 1.8).abs() < 1e-6);
        assert!((b.distance(b.centre) + 0.3).abs() < 1e-6);
        assert!((t.distance(Vec3::new(0.5, 0.0, 0.0)) + 0.2).abs() < 1e-6);
    }
}
