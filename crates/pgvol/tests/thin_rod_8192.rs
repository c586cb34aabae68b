//! The largest grid, 8192³, for a part with little surface: a thin rod is accepted under the
//! machine's memory, its distances hold along its whole length (its side faces are slivers 200
//! long and 0.196 wide), and an offset of it keeps one piece. Peak memory is the process's, so
//! this file holds a single test.

use glam::DVec3;
use pgvol::{EncodeOptions, Field, GridSpec, Silent};

mod common;

use common::{assert_peak_below, thin_rod};

#[test]
fn a_thin_rod_at_8192_cubed_encodes_and_offsets_in_one_piece() {
    // Measured 2.6 GB for the encode, about 2.9 GB with the offset.
    const BOUND: u64 = 5_000_000_000;
    // 8192 nodes along the rod, 37 across.
    let rod = thin_rod();
    let options = EncodeOptions {
        grid: GridSpec::Res(pgvol::limits::MAX_RES as usize),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&rod, &options, &Silent).unwrap();
    let volume = &encoded.file.volume;
    assert_eq!(volume.grid.dims, [8192; 3]);
    let spacing = volume.grid.spacing as f64;
    let field = Field::from_file(encoded.file);

    // Just outside the middle of a side face, from one end of the rod to the other: the face's
    // distance, not a far edge's (the sliver's face was lost from mid-length on).
    let k = 32.0f64;
    let (t0, t1) = (0.0, 2.0 * std::f64::consts::PI / k);
    let mid = 0.5 * (t0 + t1);
    let apothem = (0.5 * (t1 - t0)).cos();
    let off = 0.3 * spacing;
    let points: Vec<DVec3> = (1..20)
        .map(|i| {
            let r = apothem + off;
            DVec3::new(r * mid.cos(), r * mid.sin(), -100.0 + 10.0 * i as f64)
        })
        .collect();
    for (p, e) in points.iter().zip(field.eval(&points)) {
        assert!(e.exact, "{p}");
        assert!(
            (e.value as f64 - off).abs() < 0.1 * spacing,
            "at z = {}: {} against {off}",
            p.z,
            e.value
        );
    }

    let grown = field.offset((1.1 * spacing) as f32).unwrap();
    let back = grown.eval(&points);
    assert!(back.iter().all(|e| e.value < 0.0));
    assert_peak_below(BOUND);
}
