//! Cross-sections of the field through a point cloud, cut from the field itself while it is
//! fitted: circles of the right radius on a unit sphere's cloud, close to the sections of the
//! resampled volume without being them, empty planes warned of, and heights outside the grid's
//! box refused before any work.

use std::sync::Mutex;

use glam::Vec3;
use pgvol::reconstruct::{PointCloud, PointsMethod, SectionOptions};
use pgvol::{Axis, ErrorKind, GridSpec, Layer, PointsOptions, Progress};

/// Collects warnings.
#[derive(Default)]
struct Warnings(Mutex<Vec<String>>);

impl Progress for Warnings {
    fn warn(&self, message: &str) {
        self.0.lock().unwrap().push(message.to_string());
    }
}

/// `n` points spread evenly (Fibonacci lattice) on the unit sphere, with outward normals.
fn sphere(n: usize) -> PointCloud {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let points: Vec<Vec3> = (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let rho = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            Vec3::new(rho * phi.cos(), y, rho * phi.sin())
        })
        .collect();
    PointCloud {
        normals: Some(points.clone()),
        points,
    }
}

fn options(method: PointsMethod) -> PointsOptions {
    PointsOptions {
        grid: GridSpec::Res(64),
        method,
        ..Default::default()
    }
}

/// The distances of a one-loop layer's vertices from the axis, in its plane.
fn radii(layer: &Layer) -> Vec<f32> {
    assert_eq!(layer.loops.len(), 1, "{layer:?}");
    assert!(!layer.loops[0].hole);
    layer.loops[0]
        .points
        .iter()
        .map(|p| p[0].hypot(p[1]))
        .collect()
}

/// The section of `volume` by the plane at `h` along `axis`, at the grid's spacing.
fn volume_section(volume: &pgvol::CoefficientVolume, axis: Axis, h: f32) -> Layer {
    let a = axis.indices()[0];
    let (mut lo, mut hi) = (volume.grid.origin, volume.grid.max_corner());
    lo[a] = h;
    hi[a] = h;
    let mut options = pgvol::slicing::SliceOptions::new(axis, 1.0, volume.grid.spacing);
    options.first = Some(h);
    pgvol::slicing::slice_volume(volume, (lo, hi), &options, pgvol_core::progress::QUIET)
        .unwrap()
        .remove(0)
}

#[test]
fn sections_of_a_unit_sphere_cloud_are_its_circles() {
    let cloud = sphere(4000);
    let warnings = Warnings::default();
    let settings = SectionOptions::new(Axis::Z, vec![0.5, 0.0, 1.05]);
    let (fitted, sections) = pgvol::reconstruct::points_with_sections(
        &cloud,
        &options(PointsMethod::RbfWendland),
        &settings,
        &warnings,
    )
    .unwrap();
    let volume = &fitted.file.volume;
    let h = volume.grid.spacing;
    assert_eq!(sections.resolution, h);
    let heights: Vec<f32> = sections.layers.iter().map(|l| l.height).collect();
    assert_eq!(heights, [0.0, 0.5, 1.05], "bottom first");
    // The plane above the sphere (the grid's box reaches 1.1) is empty, listed and warned of.
    assert!(sections.layers[2].loops.is_empty());
    assert_eq!(sections.empty, [1.05]);
    let warned = warnings.0.into_inner().unwrap();
    assert_eq!(warned.len(), 1, "{warned:?}");
    assert!(warned[0].contains("z = 1.05") && warned[0].contains("empty"));
    for layer in &sections.layers[..2] {
        let z = layer.height;
        let r = (1.0 - z * z).sqrt();
        let radii = radii(layer);
        let mean = radii.iter().sum::<f32>() / radii.len() as f32;
        let worst = radii.iter().map(|x| (x - r).abs()).fold(0.0, f32::max);
        let circle = std::f64::consts::PI * f64::from(r * r);
        let area_error = (layer.area() - circle) / circle;
        // The resampled volume's section: the same circle, traced independently.
        let other = volume_section(volume, Axis::Z, z);
        let other_error = (other.area() - circle) / circle;
        eprintln!(
            "z = {z}: {} vertices, area error {:+.3} % (volume's section {:+.3} %), mean radius \
             {mean:.5} (r = {r:.5}), worst vertex {worst:.1e} off",
            radii.len(),
            100.0 * area_error,
            100.0 * other_error
        );
        assert!(area_error.abs() < 0.01, "z = {z}: area {}", layer.area());
        assert!((mean - r).abs() < 1e-3, "z = {z}: radius {mean}, want {r}");
        assert!(worst < 0.005, "z = {z}: a vertex {worst} off the circle");
        assert!((other_error - area_error).abs() < 0.002, "z = {z}");
        assert_ne!(*layer, other, "z = {z}: the same as the volume's section");
    }
}

#[test]
fn every_axis_cuts_a_counter_clockwise_circle() {
    let cloud = sphere(3000);
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let settings = SectionOptions {
            axis,
            heights: vec![-0.5],
            resolution: Some(0.02),
        };
        let (_, sections) = pgvol::reconstruct::points_with_sections(
            &cloud,
            &options(PointsMethod::Spline),
            &settings,
            &pgvol::Silent,
        )
        .unwrap();
        assert_eq!(sections.resolution, 0.02);
        let layer = &sections.layers[0];
        let r = 0.75f32.sqrt();
        let mean = radii(layer).iter().sum::<f32>() / layer.loops[0].points.len() as f32;
        assert!((mean - r).abs() < 2e-3, "{axis:?}: radius {mean}");
        // Outer loops are counter-clockwise: positive area.
        assert!(
            layer.area() > 0.99 * std::f64::consts::PI * 0.75,
            "{axis:?}"
        );
    }
}

#[test]
fn heights_outside_the_grid_box_are_refused_before_the_fit() {
    let cloud = sphere(3000);
    for (heights, says) in [
        (vec![0.0, 3.0], "z = 3 is outside the grid box"),
        (vec![f32::NAN], "not a finite number"),
        (vec![-1e9], "not a finite number below 1e8"),
        (vec![], "no section heights"),
    ] {
        let settings = SectionOptions::new(Axis::Z, heights);
        // A method that would refuse this cloud (too many points for the dense solve) shows
        // the sections were checked first.
        let e = pgvol::reconstruct::points_with_sections(
            &cloud,
            &options(PointsMethod::RbfCubic),
            &settings,
            &pgvol::Silent,
        )
        .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        let msg = e.to_string();
        assert!(msg.contains(says), "{msg}");
        assert!(!msg.contains("--"), "the library names no flags: {msg}");
    }
    let e = pgvol::reconstruct::points_with_sections(
        &cloud,
        &options(PointsMethod::Spline),
        &SectionOptions::new(Axis::Y, vec![-1.5]),
        &pgvol::Silent,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("y = -1.5") && e.contains("spans y from -1."),
        "{e}"
    );
}

#[test]
fn clouds_given_directly_are_checked_for_range() {
    let mut cloud = sphere(100);
    cloud.points[7] = Vec3::new(0.0, f32::INFINITY, 0.0);
    let e = pgvol::reconstruct::points(&cloud, &options(PointsMethod::Spline), &pgvol::Silent)
        .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    assert!(e.to_string().contains("point 7"), "{e}");
}
