//! `.vdb` level sets through the facade: `Field::open` and `io::encode_vdb` on files OpenVDB 10
//! wrote (`fixtures/vdb`, see `tools/fixtures/make_vdb_fixtures.cpp`).

use std::path::PathBuf;

use glam::Vec3;
use pgvol::{Field, OpenOptions, Silent};

fn value(field: &Field, p: Vec3) -> f32 {
    field.eval(&[p.as_dvec3()])[0].value
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/vdb")
        .join(name)
}

/// The ball is OpenVDB's sphere of radius 3.5 about (12, 12, 12), voxel size 1, band 3: the
/// field is its distance near the surface, clamped to ±3 beyond, with the sign inside.
#[test]
fn a_vdb_ball_opens_as_its_distance_with_the_band_and_the_inside() {
    for name in ["ball_blosc.vdb", "ball_none.vdb", "ball_half_blosc.vdb"] {
        let field = Field::open(fixture(name), &OpenOptions::default(), &Silent).unwrap();
        assert_eq!(field.grid().spacing, 1.0, "{name}");
        let centre = Vec3::splat(12.0);
        for dir in [Vec3::X, -Vec3::Y, Vec3::new(1.0, 1.0, 1.0).normalize()] {
            for d in [-1.5f32, -0.5, 0.0, 0.5, 1.5] {
                let v = value(&field, centre + dir * (3.5 + d));
                // OpenVDB's sphere distances are exact to well within a tenth of a voxel.
                assert!((v - d).abs() < 0.1, "{name}: {dir} {d}: {v}");
            }
        }
        assert!(
            value(&field, centre) < -2.5,
            "{name}: the inside lost its sign"
        );
        assert!(value(&field, centre + Vec3::splat(7.0)) > 2.5, "{name}");
        assert_eq!(pgvol::io::recorded_band(field.file()), Some(3.0), "{name}");
    }
}

/// Written to `.pgv` bytes and read back, the file keeps the band and the fitted values; a
/// grid named wrongly is refused with the file's grids listed.
#[test]
fn encoded_vdb_files_read_back_and_wrong_grid_names_are_refused() {
    let path = fixture("several_grids.vdb");
    let options = pgvol::io::VdbEncodeOptions {
        grid_name: Some("second".into()),
        ..Default::default()
    };
    let encoded = pgvol::io::encode_vdb(&path, &options, &Silent).unwrap();
    let storage = pgvol::StorageOptions::default();
    let bytes = pgvol::io::pgv_bytes(&encoded.file, &storage).unwrap().bytes;
    let back = pgvol::io::read_pgv_bytes(&bytes, "second.pgv").unwrap();
    assert_eq!(pgvol::io::recorded_band(&back), Some(3.0));
    let field = Field::from_file(back);
    // 'second' is OpenVDB's sphere of radius 2.5 about (12, 12, 12).
    let v = value(&field, Vec3::new(12.0, 12.0, 14.5));
    assert!(v.abs() < 0.1, "{v}");
    let options = pgvol::io::VdbEncodeOptions {
        grid_name: Some("missing".into()),
        ..Default::default()
    };
    let e = pgvol::io::encode_vdb(&path, &options, &Silent)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("several_grids.vdb") && e.contains("'moved'"),
        "{e}"
    );
}
