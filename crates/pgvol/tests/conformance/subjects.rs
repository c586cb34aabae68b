//! The shapes the fields under test stand for, built once, and what is known of each field: the
//! shape's exact distance, where the field is differentiable, and the bounds it is held to.

use std::sync::OnceLock;

use pgvol::glam::{EulerRot, Quat, Vec3};
use pgvol::mesh::shapes;
use pgvol::perturbation::{PerturbOptions, PerturbationField};
use pgvol::sdf::MeshSdf;
use pgvol::{Basis, CoefficientVolume, EncodeOptions, GridSpec, Mesh, SignMode, Silent};

/// What a field is held to, in the units of its shape.
pub struct Spec {
    /// Random points are drawn from this box.
    pub region: (Vec3, Vec3),
    /// The exact signed distance of the shape the field stands for, computed independently of
    /// the field.
    pub reference: fn(Vec3) -> f32,
    /// Largest difference between the value alone and the value given with the gradient.
    pub paths_agree_within: f32,
    /// Where `|reference| < near`, the field is within `accuracy` of it.
    pub near: f32,
    pub accuracy: f32,
    /// Where `|reference| >= sign_margin`, the field has the reference's sign.
    pub sign_margin: f32,
    /// Whether the field is differentiable on the ball of radius `r` around `p`, from what is
    /// known of the shape and the basis, never from the field itself.
    pub smooth: Box<dyn Fn(Vec3, f32) -> bool + Send + Sync>,
    /// Central-difference step, and the largest distance allowed between the gradient and the
    /// differences.
    pub fd_step: f32,
    pub fd_tolerance: f32,
    /// `|f(a) − f(b)| <= lipschitz · |a − b|` for `a`, `b` where `lipschitz_where` holds, at
    /// most `lipschitz_reach` apart.
    pub lipschitz: f32,
    pub lipschitz_where: Box<dyn Fn(Vec3) -> bool + Send + Sync>,
    pub lipschitz_reach: f32,
}

/// An exact signed distance: equal to the reference up to rounding, 1-Lipschitz everywhere.
fn exact_spec(
    region: (Vec3, Vec3),
    reference: fn(Vec3) -> f32,
    smooth: impl Fn(Vec3, f32) -> bool + Send + Sync + 'static,
) -> Spec {
    Spec {
        region,
        reference,
        paths_agree_within: 0.0,
        near: f32::INFINITY,
        // Rounding of coordinates near 1 and of the closest-point arithmetic.
        accuracy: 1e-6,
        sign_margin: 1e-5,
        smooth: Box::new(smooth),
        fd_step: 1e-4,
        // Rounding of values near 1 over a step of 1e-4 is about 1e-3 per component.
        fd_tolerance: 1e-2,
        lipschitz: 1.0 + 1e-5,
        lipschitz_where: Box::new(|_| true),
        lipschitz_reach: f32::INFINITY,
    }
}

/// Whether a point inside an axis-aligned box `[lo, hi]` is off its medial axis by more than
/// `margin`: one face is nearer than every other by twice that.
fn one_face_nearest(p: Vec3, lo: Vec3, hi: Vec3, margin: f32) -> bool {
    let mut gaps = [
        p.x - lo.x,
        hi.x - p.x,
        p.y - lo.y,
        hi.y - p.y,
        p.z - lo.z,
        hi.z - p.z,
    ];
    gaps.sort_by(f32::total_cmp);
    gaps[1] - gaps[0] > 2.0 * margin
}

/// Exact signed distance of the axis-aligned box `[lo, hi]`.
fn box_sdf(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let q = (p - (lo + hi) * 0.5).abs() - (hi - lo) * 0.5;
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

/// A box's distance is differentiable outside it (it is convex), with a gradient that turns at
/// rate 1/d around edges and corners, so differences need d well above their step; and inside
/// wherever one face is clearly nearest.
fn box_smooth(p: Vec3, r: f32, lo: Vec3, hi: Vec3) -> bool {
    let d = box_sdf(p, lo, hi);
    if d > 0.0 {
        d >= 20.0 * r
    } else {
        one_face_nearest(p, lo, hi, 2.0 * r)
    }
}

// ---------------------------------------------------------------------------------------------
// The box mesh: a distance known in closed form, for the exact mesh fields.

/// Corners of the box mesh: unequal sides, off the origin, so no axis or sign is special.
pub const BOX_LO: Vec3 = Vec3::new(-0.6, -0.45, -0.3);
pub const BOX_HI: Vec3 = Vec3::new(0.5, 0.55, 0.4);

/// The box mesh and its prepared distance query.
pub fn box_mesh() -> &'static (Mesh, MeshSdf) {
    static BOX: OnceLock<(Mesh, MeshSdf)> = OnceLock::new();
    BOX.get_or_init(|| {
        let mesh = shapes::cuboid(BOX_LO, BOX_HI);
        let sdf = MeshSdf::new(&mesh, SignMode::Auto).unwrap();
        (mesh, sdf)
    })
}

/// The exact mesh fields on the box mesh.
pub fn box_mesh_spec() -> Spec {
    exact_spec(
        (BOX_LO - Vec3::splat(0.4), BOX_HI + Vec3::splat(0.4)),
        |p| box_sdf(p, BOX_LO, BOX_HI),
        |p, r| box_smooth(p, r, BOX_LO, BOX_HI),
    )
}

// ---------------------------------------------------------------------------------------------
// Analytic solids, for the closed-form implementors.

pub const BALL: pgvol::field::analytic::Sphere = pgvol::field::analytic::Sphere {
    centre: Vec3::new(0.1, -0.2, 0.05),
    radius: 0.7,
};

pub fn ball_spec() -> Spec {
    let c = BALL.centre;
    exact_spec(
        (c - Vec3::splat(1.0), c + Vec3::splat(1.0)),
        |p| p.distance(BALL.centre) - BALL.radius,
        // The medial axis is the centre, where the gradient turns at rate 1/|p − c|.
        move |p, r| p.distance(c) >= 20.0 * r,
    )
}

pub fn slab() -> pgvol::field::analytic::RotatedBox {
    pgvol::field::analytic::RotatedBox {
        centre: Vec3::new(0.1, 0.0, -0.1),
        half: Vec3::new(0.5, 0.3, 0.4),
        rotation: Quat::from_euler(EulerRot::XYZ, 0.3, 0.5, 0.2),
    }
}

/// `p` in the frame of [`slab`], whose box is `[-half, half]` there.
fn slab_local(p: Vec3) -> Vec3 {
    let s = slab();
    s.rotation.inverse() * (p - s.centre)
}

pub fn slab_spec() -> Spec {
    let half = slab().half;
    exact_spec(
        (Vec3::splat(-0.9), Vec3::splat(0.9)),
        |p| box_sdf(slab_local(p), -slab().half, slab().half),
        move |p, r| box_smooth(slab_local(p), r, -half, half),
    )
}

pub const RING: pgvol::field::analytic::Torus = pgvol::field::analytic::Torus {
    centre: Vec3::new(0.0, 0.1, -0.1),
    major: 0.6,
    minor: 0.25,
};

/// Distance to the torus's core circle and to its axis, in that order.
fn ring_coordinates(p: Vec3) -> (f32, f32) {
    let v = p - RING.centre;
    let rho = v.truncate().length();
    ((rho - RING.major).hypot(v.z), rho)
}

pub fn ring_spec() -> Spec {
    let reach = RING.major + RING.minor + 0.3;
    exact_spec(
        (
            RING.centre - Vec3::new(reach, reach, 0.6),
            RING.centre + Vec3::new(reach, reach, 0.6),
        ),
        |p| ring_coordinates(p).0 - RING.minor,
        // The medial axis is the core circle inside and the axis outside.
        |p, r| {
            let (core, axis) = ring_coordinates(p);
            core >= 20.0 * r && axis >= 20.0 * r
        },
    )
}

// ---------------------------------------------------------------------------------------------
// The sphere mesh, which the coefficient volumes are encoded from.

/// Nodes per axis of the encoded volumes: coarse, so fits take milliseconds.
pub const RES: usize = 32;

/// The sphere mesh and its prepared distance query.
pub fn sphere_mesh() -> &'static (Mesh, MeshSdf) {
    static SPHERE: OnceLock<(Mesh, MeshSdf)> = OnceLock::new();
    SPHERE.get_or_init(|| {
        let mesh = shapes::octasphere(3);
        let sdf = MeshSdf::new(&mesh, SignMode::Auto).unwrap();
        (mesh, sdf)
    })
}

/// Exact signed distance of the sphere mesh.
pub fn sphere_distance(p: Vec3) -> f32 {
    sphere_mesh().1.signed_distance(p)
}

/// The sphere mesh encoded in `basis` by the facade, as `pgvol encode` would.
pub fn encoded(basis: Basis) -> CoefficientVolume {
    let options = EncodeOptions {
        grid: GridSpec::Res(RES),
        basis,
        ..EncodeOptions::default()
    };
    pgvol::encode(&sphere_mesh().0, &options, &Silent)
        .unwrap()
        .file
        .volume
}

/// Measured bounds of an encoded volume, in grid spacings where they scale with the grid.
pub struct Fitted {
    /// Largest `|f − d|` where `|d|` is within two spacings, in spacings.
    pub accuracy: f32,
    /// Largest `|∇f|` where `|d|` is within two spacings.
    pub lipschitz: f32,
}

/// An encoded volume: checked inside its grid, where it is smooth (the hat basis only within
/// cells), close to the distance within two spacings of the surface, and Lipschitz there.
pub fn encoded_spec(volume: &CoefficientVolume, bounds: Fitted) -> Spec {
    let grid = volume.grid;
    let h = grid.spacing;
    let (lo, hi) = (grid.origin, grid.max_corner());
    let kinks_at_cell_faces = volume.basis == Basis::Trilinear;
    let inside = move |p: Vec3, r: f32| p.cmpge(lo + r).all() && p.cmple(hi - r).all();
    Spec {
        region: (lo + Vec3::splat(h), hi - Vec3::splat(h)),
        reference: sphere_distance,
        // The cubic B-spline's contouring path differs from its general one in rounding only.
        paths_agree_within: 1e-6,
        near: 2.0 * h,
        accuracy: bounds.accuracy * h,
        sign_margin: bounds.accuracy * h,
        smooth: Box::new(move |p, r| {
            let within_cells = grid
                .to_grid(p)
                .to_array()
                .iter()
                .all(|u| (u - u.round()).abs() > r / h + 1e-3);
            inside(p, r) && (within_cells || !kinks_at_cell_faces)
        }),
        fd_step: 1e-3 * h,
        // Rounding of values of a few spacings over a step of 1e-3 spacings.
        fd_tolerance: 1e-2,
        lipschitz: bounds.lipschitz,
        lipschitz_where: Box::new(move |p| inside(p, 0.0) && sphere_distance(p).abs() < 2.0 * h),
        lipschitz_reach: 2.0 * h,
    }
}

// ---------------------------------------------------------------------------------------------
// The bumpy sphere mesh, which the perturbation field is built from.

/// A unit octasphere with two smooth bumps and one dent, far from any quadric, so the field
/// under test holds many perturbations.
pub fn bumpy_mesh() -> &'static (Mesh, MeshSdf) {
    static BUMPY: OnceLock<(Mesh, MeshSdf)> = OnceLock::new();
    BUMPY.get_or_init(|| {
        let mut mesh = shapes::octasphere(4);
        for p in &mut mesh.positions {
            let d = p.normalize();
            let bump = |axis: Vec3, h: f32| h * (-(1.0 - d.dot(axis.normalize())) * 10.0).exp();
            *p = d
                * (1.0 + bump(Vec3::X, 0.25) + bump(Vec3::new(-1.0, 1.0, 0.5), 0.2)
                    - bump(Vec3::new(0.0, -1.0, -1.0), 0.15));
        }
        let sdf = MeshSdf::new(&mesh, SignMode::Auto).unwrap();
        (mesh, sdf)
    })
}

/// Exact signed distance of the bumpy mesh.
pub fn bumpy_distance(p: Vec3) -> f32 {
    bumpy_mesh().1.signed_distance(p)
}

/// The perturbation field of the bumpy mesh, as `pgvol perturb` builds it, and its bounds.
///
/// Measured over 200 000 points of [−1.5, 1.5]³: within 0.05 of the surface the value is
/// within 0.049 of the distance (held to 0.08 within 0.08, where enough random points fall);
/// no point farther than 0.053 from the surface has the wrong sign (held at 0.065); within
/// 0.3 of the surface the gradient norm is at most 2.65 (held to 3.2).
pub fn perturbation() -> (PerturbationField, Spec) {
    let options = PerturbOptions {
        max_functions: 300,
        tolerance: 1e-3,
        ..Default::default()
    };
    let built = pgvol::perturbation::perturb(&bumpy_mesh().0, &options, &Silent).unwrap();
    assert!(built.field.terms().len() > 50, "{:?}", built.report.stop);
    let spec = Spec {
        region: (Vec3::splat(-1.3), Vec3::splat(1.3)),
        reference: bumpy_distance,
        // Both paths sum the same terms in the same order in double precision.
        paths_agree_within: 1e-6,
        near: 0.08,
        accuracy: 0.08,
        sign_margin: 0.065,
        // Q³ keeps the value and the gradient continuous everywhere.
        smooth: Box::new(|_, _| true),
        fd_step: 1e-3,
        fd_tolerance: 2e-2,
        lipschitz: 3.2,
        lipschitz_where: Box::new(|p| bumpy_distance(p).abs() < 0.3),
        lipschitz_reach: 0.1,
    };
    (built.field, spec)
}
