//! A 1024³ encode and decode of a small mesh stays within a memory bound that a dense grid
//! could not meet (one f32 per node is 4.3 GB). Peak memory is the process's, so this file holds
//! a single test.

use pgvol::{DecodeOptions, EncodeOptions, GridSpec, Silent, StorageOptions};

mod common;

use common::assert_peak_below;

#[test]
fn a_1024_cubed_encode_and_decode_stays_within_a_sparse_memory_bound() {
    // Measured 0.66 GB after encoding, 0.97 GB after writing and 1.53 GB after decoding the
    // sphere into millions of triangles; the coefficients alone would be 4.3 GB dense.
    const BOUND: u64 = 2_000_000_000;
    let mesh = pgvol::mesh::shapes::octasphere(4);
    let options = EncodeOptions {
        grid: GridSpec::Res(1024),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&mesh, &options, &Silent).unwrap();
    let grid = encoded.file.volume.grid;
    assert_eq!(grid.dims, [1024; 3]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.pgv");
    pgvol::io::write_pgv(&path, &encoded.file, &StorageOptions::default()).unwrap();
    drop(encoded);

    let file = pgvol::io::read_pgv(&path).unwrap();
    let stored = file.volume.coeffs.stored_count();
    let all: usize = file.volume.coeffs.brick_counts().iter().product();
    assert!(stored * 10 < all, "{stored} of {all} bricks stored");
    let mesh_out = pgvol::Field::from_volume(file.volume.clone())
        .to_mesh(&DecodeOptions::default(), &Silent)
        .unwrap();

    // The octasphere's vertices lie on the unit sphere and its faces within 0.3 % of it: every
    // output vertex lies within that plus a fraction of a spacing of radius 1.
    let h = grid.spacing;
    let worst = mesh_out
        .positions
        .iter()
        .map(|p| (p.length() - 1.0).abs())
        .fold(0.0f32, f32::max);
    assert!(
        worst < 0.004 + 0.5 * h,
        "vertex {worst} from the sphere, h = {h}"
    );
    assert!(mesh_out.triangles.len() > 1_000_000);
    let stats = mesh_out.stats();
    assert!(
        stats.watertight && stats.euler_characteristic == 2,
        "{stats:?}"
    );

    assert_peak_below(BOUND);
}
