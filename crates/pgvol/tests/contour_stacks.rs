//! Contour stacks with uneven layer spacing: identical unit circles at any heights give one
//! solid, the stacked cylinder, whatever the distances between the planes.

use pgvol::{Axis, DecodeOptions, Layer, PointsOptions, Silent};

/// A counter-clockwise unit circle of 256 points.
fn circle() -> pgvol::slicing::Loop {
    let points = (0..256)
        .map(|k| {
            let a = k as f32 / 256.0 * std::f32::consts::TAU;
            [a.cos(), a.sin()]
        })
        .collect();
    pgvol::slicing::Loop {
        points,
        hole: false,
    }
}

fn layers(heights: &[f32]) -> Vec<Layer> {
    heights
        .iter()
        .map(|&height| Layer {
            height,
            loops: vec![circle()],
        })
        .collect()
}

/// The decoded stack of unit circles at `heights`, every piece kept, and the volume of the
/// cylinder they stack into: the caps lie half the outermost layer distances beyond the
/// outermost planes.
fn stack(heights: &[f32]) -> (pgvol::core::MeshStats, f64) {
    let fit = pgvol::reconstruct::contours(
        &layers(heights),
        Axis::Z,
        &PointsOptions::default(),
        &Silent,
    )
    .unwrap();
    let options = DecodeOptions {
        min_component: Some(0.0),
        ..DecodeOptions::default()
    };
    let mesh = pgvol::Field::from_volume(fit.file.volume.clone())
        .to_mesh(&options, &Silent)
        .unwrap();
    let n = heights.len();
    let length =
        f64::from(1.5 * (heights[n - 1] - heights[0]) - 0.5 * (heights[n - 2] - heights[1]));
    (mesh.stats(), std::f64::consts::PI * length)
}

#[test]
fn unevenly_spaced_planes_give_one_solid_without_cavities() {
    for heights in [
        [0.0, 0.5, 1.0, 1.5, 2.0, 2.01],
        [0.0, 0.1, 0.11, 0.5, 2.0, 2.01],
    ] {
        let (stats, cylinder) = stack(&heights);
        // One closed piece of genus 0: a cavity would be a second boundary, Euler 4.
        assert_eq!(stats.components, 1, "{heights:?}: {stats:?}");
        assert_eq!(stats.euler_characteristic, 2, "{heights:?}: {stats:?}");
        assert!(stats.watertight, "{heights:?}");
        // A top cap half of 0.01 out is moved to two grid spacings (0.04): 1 % more.
        let ratio = stats.volume / cylinder;
        assert!(
            (0.98..1.03).contains(&ratio),
            "{heights:?}: volume {ratio:.3} of the cylinder's"
        );
    }
}

#[test]
fn two_layers_at_one_height_are_refused_by_name() {
    let e = pgvol::reconstruct::contours(
        &layers(&[0.0, 0.5, 0.5, 1.0]),
        Axis::Z,
        &PointsOptions::default(),
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.kind(), pgvol::ErrorKind::InputFile);
    assert!(e.message().contains("height 0.5"), "{e}");
}
