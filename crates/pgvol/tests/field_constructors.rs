//! The `Field` constructors beyond meshes and files (primitives, points, contours, the
//! perturbation method) and the methods that fit a field again (resample, blend, denoise),
//! measured against the analytic solids they stand for.

use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use pgvol::edit::{BlendOperator, BlendOptions, Mask};
use pgvol::field::analytic::Sphere;
use pgvol::reconstruct::PointCloud;
use pgvol::{
    Axis, DecodeOptions, Field, GridSpec, Operand, PointsOptions, Primary, ResampleOptions, Silent,
    SliceOptions,
};

fn ball(centre: Vec3, radius: f32, res: usize) -> Field {
    let options = ResampleOptions {
        res,
        ..ResampleOptions::default()
    };
    Field::primitive(
        Primary::Sphere(Sphere { centre, radius }),
        &options,
        &Silent,
    )
    .unwrap()
}

/// The volume enclosed by the field's surface, contoured on its own grid.
fn volume(field: &Field) -> f64 {
    let mesh = field.to_mesh(&DecodeOptions::default(), &Silent).unwrap();
    let stats = mesh.stats();
    assert!(stats.watertight, "{stats:?}");
    stats.volume
}

fn ball_volume(radius: f64) -> f64 {
    4.0 / 3.0 * PI * radius.powi(3)
}

#[test]
fn a_primitive_ball_encloses_the_ball_volume() {
    let field = ball(Vec3::ZERO, 0.5, 96);
    assert_eq!(field.grid().dims, [96, 96, 96]);
    let error = volume(&field) / ball_volume(0.5) - 1.0;
    assert!(error.abs() < 0.005, "{error}");
    // Near the surface the field is the ball's distance.
    let at = field.eval(&[DVec3::new(0.52, 0.0, 0.0), DVec3::new(0.0, -0.48, 0.0)]);
    assert!(
        at[0].exact && (at[0].value - 0.02).abs() < 1e-3,
        "{:?}",
        at[0]
    );
    assert!(
        at[1].exact && (at[1].value + 0.02).abs() < 1e-3,
        "{:?}",
        at[1]
    );
}

#[test]
fn resampling_keeps_the_shape_on_the_new_grid() {
    let fine = ball(Vec3::new(0.1, 0.0, -0.1), 0.5, 96);
    let options = ResampleOptions {
        res: 48,
        ..ResampleOptions::default()
    };
    let coarse = fine.resample(&options, &Silent).unwrap();
    assert_eq!(coarse.grid().dims, [48, 48, 48]);
    assert_eq!(coarse.header().metadata["operation"], "resample 48");
    let error = volume(&coarse) / ball_volume(0.5) - 1.0;
    assert!(error.abs() < 0.01, "{error}");
}

/// The analytic solid of an operand's text form, as a field over the box [-1, 1]³.
/// Exact within the reach of the blend's operands.
fn primitive(text: &str, res: usize) -> Field {
    let Operand::Primary(primary) = Operand::parse(text).unwrap() else {
        panic!("{text} is not a primary");
    };
    let options = ResampleOptions {
        res,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        band: 12.0,
    };
    Field::primitive(primary, &options, &Silent).unwrap()
}

#[test]
fn resampling_a_field_far_from_the_origin_is_refused_by_name() {
    let mut mesh = pgvol::mesh::shapes::octasphere(3);
    mesh.offset = DVec3::splat(1e6);
    let options = pgvol::EncodeOptions {
        grid: GridSpec::Res(32),
        ..Default::default()
    };
    let far = Field::from_mesh(&mesh, &options, &Silent).unwrap();
    let e = far
        .resample(&ResampleOptions::default(), &Silent)
        .unwrap_err();
    assert_eq!(e.kind(), pgvol::ErrorKind::BadParameter, "{e}");
    assert!(e.message().contains("resampling"), "{e}");
}

#[test]
fn the_blend_method_is_the_blend_of_the_two_fields() {
    // P₁ = x, P₂ = y, C = (−x − y − 0.6)/√2, λ = ½: on the bisector x = y = −s the blend
    // vanishes where (2s − 0.6)² / 2 = s², s = 0.6 / (2 + √2).
    let a = primitive("plane:1,0,0,0", 64);
    let b = primitive("plane:0,1,0,0", 64);
    let operator = BlendOperator::Liming {
        cut: Operand::parse("plane:-1,-1,0,0.6").unwrap(),
        lambda: 0.5,
    };
    let options = BlendOptions {
        res: 64,
        bounds: Some((Vec3::splat(-1.0), Vec3::splat(1.0))),
        ..BlendOptions::default()
    };
    let method = a.blend(&b, &operator, &options, &Silent).unwrap();
    let operands = [Operand::from(a.clone()), Operand::from(b.clone())];
    let function = pgvol::edit::blend(&operands, &operator, &options, &Silent).unwrap();
    let bytes = |f: &Field| f.to_bytes(&Default::default()).unwrap();
    assert_eq!(bytes(&method.field), bytes(&function.field));
    let s = 0.6 / (2.0 + std::f64::consts::SQRT_2);
    let on = method.field.eval(&[DVec3::new(-s, -s, 0.1)])[0].value;
    assert!(on.abs() < 0.02, "{on}");
}

#[test]
fn denoising_is_a_repair_that_smooths() {
    let field = ball(Vec3::ZERO, 0.5, 64);
    let masks = [Mask {
        lo: Vec3::new(0.3, -0.2, -0.2),
        hi: Vec3::new(0.7, 0.2, 0.2),
    }];
    let denoised = field.denoise(&masks, 8, &Silent).unwrap();
    let repaired = field
        .repair(&masks, pgvol::edit::Restore::Denoise { coarse: 8 }, &Silent)
        .unwrap();
    let bytes = |f: &Field| f.to_bytes(&Default::default()).unwrap();
    assert_eq!(bytes(&denoised.field), bytes(&repaired.field));
    assert_eq!(denoised.masks.len(), 1);
    assert!(denoised.masks[0].nodes > 0);
}

/// `n` points on the unit sphere (a Fibonacci spiral) with their normals.
fn sphere_cloud(n: usize) -> PointCloud {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let points: Vec<Vec3> = (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let t = golden * i as f32;
            Vec3::new(r * t.cos(), y, r * t.sin())
        })
        .collect();
    PointCloud {
        normals: Some(points.clone()),
        points,
    }
}

#[test]
fn a_field_from_points_passes_through_them() {
    let options = PointsOptions {
        grid: GridSpec::Res(64),
        ..PointsOptions::default()
    };
    let field = Field::from_points(&sphere_cloud(4000), &options, &Silent).unwrap();
    let error = volume(&field) / ball_volume(1.0) - 1.0;
    assert!(error.abs() < 0.01, "{error}");
}

#[test]
fn slices_of_a_ball_rebuild_the_ball_through_from_contours() {
    let field = ball(Vec3::ZERO, 0.5, 64);
    let sliced = field.slice(&SliceOptions::new(0.05), &Silent).unwrap();
    assert!(sliced.layers.len() >= 19, "{}", sliced.layers.len());
    let options = PointsOptions {
        grid: GridSpec::Res(64),
        ..PointsOptions::default()
    };
    let rebuilt = Field::from_contours(&sliced.layers, Axis::Z, &options, &Silent).unwrap();
    // The stack ends half a layer beyond its outer planes, so the caps are flattened.
    let error = volume(&rebuilt) / ball_volume(0.5) - 1.0;
    assert!(error.abs() < 0.05, "{error}");
}

#[test]
fn a_perturbation_field_resampled_is_a_field_on_its_grid() {
    let mesh = pgvol::mesh::shapes::octasphere(3);
    let options = pgvol::perturbation::PerturbOptions {
        max_functions: 20,
        ..Default::default()
    };
    let field = Field::perturb(&mesh, &options, GridSpec::Res(32), &Silent).unwrap();
    assert_eq!(field.grid().dims, [32, 32, 32]);
    assert_eq!(field.header().metadata["source"], "perturbation");
    let reference = mesh.stats().volume;
    let error = volume(&field) / reference - 1.0;
    assert!(error.abs() < 0.05, "{error}");
}
