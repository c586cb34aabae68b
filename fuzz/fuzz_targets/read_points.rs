#![no_main]
//! Any bytes read as a points file (CSV and the like): an error naming the file, or points that
//! are finite, within the accepted range, and read back the same from their `x,y,z` text.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol::io::read_points;
use pgvol_mesh::MAX_COORDINATE;

/// Valid files of the seed corpus.
const SEEDS: [&[u8]; 2] = [
    include_bytes!("../corpus/read_points/points.csv"),
    include_bytes!("../corpus/read_points/points-bom.csv"),
];

static SEEDS_READ: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEEDS_READ.call_once(|| {
        for seed in SEEDS {
            read_points(seed, Path::new("seed.csv")).expect("a seed file reads");
        }
    });
    let name = Path::new("fuzz.csv");
    match read_points(data, name) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.csv: "), "{e}"),
        Ok(points) => {
            assert!(!points.is_empty());
            for p in &points {
                assert!(
                    p.is_finite() && p.abs().max_element() < f64::from(MAX_COORDINATE),
                    "{p}"
                );
            }
            let text: String = points
                .iter()
                .map(|p| format!("{},{},{}\n", p.x, p.y, p.z))
                .collect();
            let back = read_points(text.as_bytes(), name).expect("written points read back");
            assert_eq!(back, points);
        }
    }
});
