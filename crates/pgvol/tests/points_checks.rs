//! Point clouds are checked before a fit: clouds too sparse for the grid are refused with the
//! grid that would work, inconsistent or inward normals are repaired and reported through the
//! warning channel, and the solid comes out whole.

use std::sync::Mutex;

use glam::Vec3;
use pgvol::reconstruct::PointCloud;
use pgvol::{ErrorKind, GridSpec, PointsOptions, Progress};

/// Collects warnings.
#[derive(Default)]
struct Warnings(Mutex<Vec<String>>);

impl Progress for Warnings {
    fn warn(&self, message: &str) {
        self.0.lock().unwrap().push(message.to_string());
    }
}

/// `n` random points on the unit sphere with outward normals.
fn random_sphere(n: usize, seed: u64) -> PointCloud {
    // xorshift64*: uniform in [0, 1).
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut uniform = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    };
    let points: Vec<Vec3> = (0..n)
        .map(|_| loop {
            let p = Vec3::new(uniform(), uniform(), uniform()) * 2.0 - 1.0;
            if (0.01..=1.0).contains(&p.length_squared()) {
                break p.normalize();
            }
        })
        .collect();
    PointCloud {
        normals: Some(points.clone()),
        points,
    }
}

fn options(res: usize) -> PointsOptions {
    PointsOptions {
        grid: GridSpec::Res(res),
        ..Default::default()
    }
}

/// The fit of `cloud` at `res`: its warnings, enclosed volume, pieces, and value at the centre.
fn fit(cloud: &PointCloud, res: usize) -> (Vec<String>, f64, usize, f32) {
    let warnings = Warnings::default();
    let fitted = pgvol::reconstruct::points(cloud, &options(res), &warnings).expect("fit");
    let volume = &fitted.file.volume;
    let mesh = pgvol::Field::from_volume((*volume).clone())
        .to_mesh(&pgvol::DecodeOptions::default(), &pgvol::Silent)
        .unwrap();
    let stats = mesh.stats();
    let centre = volume.value(Vec3::ZERO);
    (
        warnings.0.into_inner().unwrap(),
        stats.volume,
        stats.components,
        centre,
    )
}

const BALL: f64 = 4.0 / 3.0 * std::f64::consts::PI;

#[test]
fn a_cloud_too_sparse_for_the_grid_is_refused_with_the_grid_that_works() {
    // 800 random points: 6 neighbours within about 0.17, 10 grid spacings at 128³.
    let cloud = random_sphere(800, 1);
    let e = pgvol::reconstruct::points(&cloud, &options(128), &pgvol::Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    let msg = e.to_string();
    assert!(msg.contains("too sparse for the grid"), "{msg}");
    assert!(!msg.contains("--"), "the library names no flags: {msg}");
    // The message's node count works: a whole ball, the centre inside.
    let nodes: usize = msg
        .split("about ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no node count in {msg}"));
    assert!((40..128).contains(&nodes), "{msg}");
    let (warnings, volume, pieces, centre) = fit(&cloud, nodes);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(pieces, 1);
    assert!(centre < 0.0, "the centre evaluates outside: {centre}");
    assert!((volume - BALL).abs() < 0.05 * BALL, "volume {volume}");
}

#[test]
fn every_other_normal_flipped_is_re_oriented_and_said() {
    let mut cloud = random_sphere(3000, 2);
    for n in cloud.normals.as_mut().unwrap().iter_mut().step_by(2) {
        *n = -*n;
    }
    let (warnings, volume, pieces, centre) = fit(&cloud, 64);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("re-oriented"), "{warnings:?}");
    assert_eq!(pieces, 1);
    assert!(centre < 0.0, "{centre}");
    assert!((volume - BALL).abs() < 0.03 * BALL, "volume {volume}");
}

#[test]
fn inward_normals_are_flipped_and_said() {
    let mut cloud = random_sphere(3000, 3);
    for n in cloud.normals.as_mut().unwrap() {
        *n = -*n;
    }
    let (warnings, volume, pieces, centre) = fit(&cloud, 64);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("flipped"), "{warnings:?}");
    assert_eq!(pieces, 1);
    assert!(centre < 0.0, "{centre}");
    assert!((volume - BALL).abs() < 0.03 * BALL, "volume {volume}");
}

#[test]
fn consistent_clouds_fit_without_warnings() {
    let (warnings, volume, pieces, _) = fit(&random_sphere(3000, 4), 64);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(pieces, 1);
    assert!((volume - BALL).abs() < 0.03 * BALL, "volume {volume}");
}

/// The estimate checked against the memory limit counts every brick the band really stores,
/// with what the fit keeps per brick (samples, coefficients, the solver's vectors and copies:
/// at least 18 KiB), however unevenly the points are spread.
#[test]
fn the_memory_estimate_counts_the_bricks_the_fit_stores() {
    let cloud = random_sphere(3000, 5);
    let options = options(128);
    let fitted = pgvol::reconstruct::points(&cloud, &options, &pgvol::Silent).unwrap();
    let r = &fitted.report;
    let grid = fitted.file.volume.grid;
    let estimate = pgvol::reconstruct::points_bytes(&cloud.points, r.spacing, &grid, &options);
    let bricks = r.bricks as u64;
    assert!(bricks > 1000, "{r:?}");
    assert!(
        (18 * 1024 * bricks..40 * 1024 * bricks).contains(&estimate),
        "{estimate} bytes for {bricks} bricks"
    );
}
