//! Slicing a file with sharp-feature vertices keeps the corners of a prism's sections: each
//! layer's contour passes within a twentieth of a spacing of every true corner (0.010 spacing
//! measured; the issue asks 0.1), where the smooth field alone rounds them off by 0.48.

use glam::{Mat3, Vec3};
use pgvol::{EncodeOptions, Field, GridSpec, Silent, SliceOptions};

/// A turned prism's file with its sharp section, and the turn.
fn prism_field() -> (Field, Mat3) {
    let turn = Mat3::from_rotation_z(0.5);
    let mut prism =
        pgvol::mesh::shapes::cuboid(Vec3::new(-0.5, -0.5, -0.6), Vec3::new(0.5, 0.5, 0.6));
    for p in &mut prism.positions {
        *p = turn * *p;
    }
    let options = EncodeOptions {
        grid: GridSpec::Res(64),
        sharp: pgvol::sharp::SharpOptions {
            enabled: true,
            ..Default::default()
        },
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&prism, &options, &Silent).unwrap();
    assert!(encoded.sharp.stored_cells > 0, "{:?}", encoded.sharp);
    (Field::from_file(encoded.file), turn)
}

/// The farthest, over the layers and over the prism's four vertical edges,
/// of the distance from the edge's point in the layer to the nearest contour point, in
/// spacings; with the file's sharp section or without it.
fn corner_error(with_section: bool) -> f32 {
    let (mut field, turn) = prism_field();
    if !with_section {
        let mut file = field.file().clone();
        file.header.sharp = None;
        field = Field::from_file(file);
    }
    let spacing = field.volume().grid.spacing;
    let sliced = field.slice(&SliceOptions::new(spacing), &Silent).unwrap();
    let corners: Vec<Vec3> = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]
        .iter()
        .map(|&[x, y]| turn * Vec3::new(x, y, 0.0))
        .collect();
    let mut worst = 0.0f32;
    let mut layers = 0;
    for layer in &sliced.layers {
        if layer.height.abs() > 0.6 {
            continue;
        }
        layers += 1;
        for c in &corners {
            let nearest = layer
                .loops
                .iter()
                .flat_map(|l| &l.points)
                .map(|p| (p[0] - c.x).hypot(p[1] - c.y))
                .fold(f32::INFINITY, f32::min);
            worst = worst.max(nearest / spacing);
        }
    }
    assert!(layers > 40, "{layers} layers");
    worst
}

#[test]
fn a_prisms_layers_keep_their_corners_with_the_sharp_section() {
    let sharp = corner_error(true);
    let smooth = corner_error(false);
    assert!(
        sharp <= 0.05,
        "corners {sharp} spacings off with the section"
    );
    assert!(
        smooth > 2.0 * sharp,
        "corners {smooth} spacings off without it, {sharp} with it"
    );
}

#[test]
fn slicing_in_parts_puts_the_same_corners_back() {
    use pgvol::distributed::{plan_slice, sharpen_layers, slice_part, slice_part_bricks};
    let (field, _) = prism_field();
    let settings = SliceOptions::new(field.volume().grid.spacing);
    let whole = field.slice(&settings, &Silent).unwrap().layers;
    for parts in [1, 3] {
        let mut got = Vec::new();
        for range in plan_slice(&field, &settings, parts).unwrap() {
            let bricks = slice_part_bricks(&field, &settings, range.clone()).unwrap();
            got.extend(slice_part(&bricks, field.bounds(), &settings, range).unwrap());
        }
        assert!(got != whole, "the parts' layers are the smooth field's");
        sharpen_layers(&field, &settings, &mut got).unwrap();
        assert_eq!(got, whole, "{parts} parts");
    }
}
