//! Encoding stores the sharp-feature section when `EncodeOptions::sharp` asks: the same file as
//! attaching the section to a plain encoding, with the same coefficients, and a turned cube's
//! corners kept by dual contouring and surface nets of the file (at 64³, where every corner's
//! cell is crossed; a corner whose tip lies in a cell no crossed edge reaches stays up to half
//! a cell off: `docs/algorithms.md`, "Vertices outside their cells"). An encode in parts refuses
//! it.

use glam::{Mat3, Vec3};
use pgvol::sharp::{SharpOptions, SharpReport};
use pgvol::{DecodeOptions, EncodeOptions, ErrorKind, Field, GridSpec, Method, Silent};

fn turned_cube() -> (pgvol::Mesh, Vec<Vec3>) {
    let turn = Mat3::from_rotation_y(0.5) * Mat3::from_rotation_x(0.5);
    let mut cube = pgvol::mesh::shapes::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5));
    for p in &mut cube.positions {
        *p = turn * *p;
    }
    let corners = (0..8)
        .map(|i| turn * (Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2) as f32) - 0.5))
        .collect();
    (cube, corners)
}

fn options(sharp: bool) -> EncodeOptions {
    EncodeOptions {
        grid: GridSpec::Res(64),
        sharp: SharpOptions {
            enabled: sharp,
            ..SharpOptions::default()
        },
        ..EncodeOptions::default()
    }
}

/// The farthest of `corners` from the nearest vertex of `field` contoured by `method`, in
/// spacings.
fn corner_gap(field: &Field, method: Method, corners: &[Vec3]) -> f32 {
    let decode = DecodeOptions {
        method,
        ..DecodeOptions::default()
    };
    let mesh = field.to_mesh(&decode, &Silent).unwrap();
    let spacing = field.volume().grid.spacing;
    corners
        .iter()
        .map(|c| {
            let nearest = mesh.positions.iter().map(|p| p.distance(*c));
            nearest.fold(f32::INFINITY, f32::min) / spacing
        })
        .fold(0.0, f32::max)
}

#[test]
fn encoding_stores_the_section_it_is_asked_for() {
    let (cube, corners) = turned_cube();
    let plain = pgvol::encode(&cube, &options(false), &Silent).unwrap();
    assert!(plain.file.header.sharp.is_none());
    assert_eq!(plain.sharp, SharpReport::default());
    let sharp = pgvol::encode(&cube, &options(true), &Silent).unwrap();
    assert!(sharp.sharp.stored_cells > 0, "{:?}", sharp.sharp);
    assert_eq!(sharp.file.volume, plain.file.volume);
    // The same section as attaching it to the plain file.
    let mut attached = plain.file.clone();
    let report = pgvol::sharp::attach(
        &mut attached,
        &cube,
        pgvol::SignMode::Auto,
        &options(true).sharp,
        &Silent,
    )
    .unwrap();
    assert_eq!(report, sharp.sharp);
    assert_eq!(attached, sharp.file);
    let (with, without) = (Field::from_file(sharp.file), Field::from_file(plain.file));
    for method in [Method::DualContouring, Method::SurfaceNets] {
        let (near, far) = (
            corner_gap(&with, method, &corners),
            corner_gap(&without, method, &corners),
        );
        // Measured 0.004 spacing with the section, 0.38 (dc) and 0.89 (sn) without.
        assert!(
            near < 0.1 && near < 0.5 * far,
            "{method:?}: {near} against {far}"
        );
    }
}

#[test]
fn a_bad_crease_angle_is_refused_in_one_process_and_in_parts() {
    let (cube, _) = turned_cube();
    for angle in [0.0, 180.0, f32::NAN] {
        let mut bad = options(true);
        bad.sharp.angle = angle;
        for e in [
            pgvol::encode(&cube, &bad, &Silent).unwrap_err(),
            pgvol::distributed::plan_encode(&cube, &bad, 2).unwrap_err(),
        ] {
            assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
            assert!(e.to_string().contains("crease angle"), "{e}");
        }
    }
    // Parts compute coefficients only; the vertices are chosen where the file is written.
    assert!(pgvol::distributed::plan_encode(&cube, &options(true), 2).is_ok());
}

#[test]
fn a_field_opened_from_a_mesh_stores_the_section_when_asked() {
    let (cube, corners) = turned_cube();
    let options = pgvol::OpenOptions {
        res: 64,
        sharp: options(true).sharp,
        ..pgvol::OpenOptions::default()
    };
    let field = Field::for_operations(cube.clone(), &options, &Silent).unwrap();
    assert!(field.header().sharp.is_some());
    assert!(corner_gap(&field, Method::DualContouring, &corners) < 0.1);
    let plain = Field::for_operations(cube, &pgvol::OpenOptions::default(), &Silent).unwrap();
    assert!(plain.header().sharp.is_none());
    // A file keeps the section it was encoded with: asking for one is refused.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.pgv");
    plain
        .save(&path, &pgvol::StorageOptions::default())
        .unwrap();
    let e = Field::open(&path, &options, &Silent).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
    assert!(e.to_string().contains("from a mesh"), "{e}");
}
