//! Continuous fields with gradients for the dual contouring and surface nets tests.

use glam::{Mat3, Vec3};
use pgvol_contour::{dual_contour, surface_nets, DualContourOptions, Field};
use pgvol_core::Mesh;

use crate::grids::Samples;

/// Sphere of radius `r` about the origin.
pub fn sphere(r: f32) -> impl Fn(Vec3) -> (f32, Vec3) + Sync {
    move |p: Vec3| (p.length() - r, p.normalize_or(Vec3::X))
}

/// Torus about the z axis.
pub fn torus(major: f32, minor: f32) -> impl Fn(Vec3) -> (f32, Vec3) + Sync {
    move |p: Vec3| {
        let ring = p.truncate().normalize_or(glam::Vec2::X) * major;
        let d = p - ring.extend(0.0);
        (d.length() - minor, d.normalize_or(Vec3::Z))
    }
}

/// The rotation used for the tilted cube: 30° about x, then 30° about y.
pub fn tilt() -> Mat3 {
    Mat3::from_rotation_y(30f32.to_radians()) * Mat3::from_rotation_x(30f32.to_radians())
}

/// Exact signed distance and gradient of a cube of half-side `s` centred at the origin and
/// rotated by `rot`.
pub fn rotated_cube(s: f32, rot: Mat3) -> impl Fn(Vec3) -> (f32, Vec3) + Sync {
    move |p: Vec3| {
        let l = rot.transpose() * p;
        let q = l.abs() - Vec3::splat(s);
        let sign = Vec3::select(l.cmplt(Vec3::ZERO), Vec3::NEG_ONE, Vec3::ONE);
        let (d, g) = if q.max_element() > 0.0 {
            let out = q.max(Vec3::ZERO);
            (out.length(), out.normalize() * sign)
        } else {
            let a = if q.x >= q.y && q.x >= q.z {
                0
            } else if q.y >= q.z {
                1
            } else {
                2
            };
            let mut g = Vec3::ZERO;
            g[a] = sign[a];
            (q[a], g)
        };
        (d, rot * g)
    }
}

/// Outward normal of the face of the rotated cube whose pyramid holds `p`.
pub fn cube_face_normal(rot: Mat3, p: Vec3) -> Vec3 {
    let l = rot.transpose() * p;
    let a = l.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let mut n = Vec3::ZERO;
    n[axis] = l[axis].signum();
    rot * n
}

/// Trilinear interpolation of the samples, with its gradient, continuing the border cells'
/// interpolants beyond the grid. It equals the samples at the nodes.
pub fn trilinear(s: &Samples) -> impl Fn(Vec3) -> (f32, Vec3) + Sync + '_ {
    move |p: Vec3| {
        let u = (p - s.origin) / s.spacing;
        let mut cell = [0usize; 3];
        let mut t = Vec3::ZERO;
        for a in 0..3 {
            let c = (u[a].floor().max(0.0) as usize).min(s.dims[a] - 2);
            cell[a] = c;
            t[a] = u[a] - c as f32;
        }
        let at = |c: usize| {
            let (i, j, k) = (
                cell[0] + (c & 1),
                cell[1] + ((c >> 1) & 1),
                cell[2] + (c >> 2),
            );
            s.values[i + s.dims[0] * (j + s.dims[1] * k)]
        };
        let (mut v, mut g) = (0.0, Vec3::ZERO);
        for c in 0..8 {
            let w = |a: usize| if (c >> a) & 1 == 1 { t[a] } else { 1.0 - t[a] };
            let dw = |a: usize| if (c >> a) & 1 == 1 { 1.0 } else { -1.0 };
            let x = at(c);
            v += x * w(0) * w(1) * w(2);
            g += x * Vec3::new(
                dw(0) * w(1) * w(2),
                w(0) * dw(1) * w(2),
                w(0) * w(1) * dw(2),
            );
        }
        (v, g / s.spacing)
    }
}

impl Samples {
    pub fn dual(&self, iso: f32, field: &dyn Field) -> Mesh {
        self.dual_with(iso, field, &DualContourOptions::default())
    }

    pub fn dual_with(&self, iso: f32, field: &dyn Field, options: &DualContourOptions) -> Mesh {
        dual_contour(
            &self.values,
            self.dims,
            self.origin,
            self.spacing,
            iso,
            field,
            options,
        )
    }

    pub fn nets(&self, iso: f32, field: &dyn Field) -> Mesh {
        surface_nets(
            &self.values,
            self.dims,
            self.origin,
            self.spacing,
            iso,
            field,
        )
    }

    /// Dual contouring with the trilinear interpolant of the samples as the field.
    pub fn dual_trilinear(&self, iso: f32) -> Mesh {
        self.dual(iso, &trilinear(self))
    }

    pub fn nets_trilinear(&self, iso: f32) -> Mesh {
        self.nets(iso, &trilinear(self))
    }
}
