//! A 2048³ encode of a thin rod and its decode from the file, window by window, stay within a
//! memory bound that follows the rod's small surface: one f32 per node would be 34 GB, one
//! byte per node 8.6 GB. Peak memory is the process's, so this file holds a single test.

use pgvol::{DecodeOptions, EncodeOptions, GridSpec, Silent, StorageOptions};

mod common;

use common::{assert_peak_below, thin_rod};

#[test]
fn a_thin_rod_at_2048_cubed_encodes_and_decodes_within_a_surface_memory_bound() {
    // Measured 73 MB for both in this process.
    const BOUND: u64 = 250_000_000;
    // 2048 nodes along the rod, 9 across.
    let rod = thin_rod();
    let exact = rod.stats().volume;
    let options = EncodeOptions {
        grid: GridSpec::Res(2048),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&rod, &options, &Silent).unwrap();
    assert_eq!(encoded.file.volume.grid.dims, [2048; 3]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rod.pgv");
    pgvol::io::write_pgv(&path, &encoded.file, &StorageOptions::default()).unwrap();
    drop(encoded);

    let mesh = pgvol::stream::decode_file(&path, &DecodeOptions::default(), &Silent).unwrap();
    let stats = mesh.stats();
    assert!(
        stats.watertight && stats.euler_characteristic == 2,
        "{stats:?}"
    );
    assert!(
        (stats.volume - exact).abs() < 0.01 * exact,
        "{stats:?} vs {exact}"
    );
    assert_peak_below(BOUND);
}
