#![no_main]
//! Any bytes read as an SVG layer file (as `pgvol contours` reads them): an error naming the
//! file, or layers with finite heights whose loops have at least three points, all finite.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol::slicing::read_svg;

const SEED: &[u8] = include_bytes!("../corpus/read_svg/layers.svg");

static SEEDS_READ: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEEDS_READ.call_once(|| {
        let seed = std::str::from_utf8(SEED).expect("the seed is UTF-8");
        let layers = read_svg(seed, Path::new("seed.svg")).expect("the seed reads");
        assert_eq!(layers.len(), 3, "the seed has three layers");
    });
    // The facade refuses bytes that are not UTF-8 before the reader sees them.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match read_svg(text, Path::new("fuzz.svg")) {
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz.svg: "), "{e}");
            assert!(!e.problem.is_empty());
        }
        Ok(layers) => {
            assert!(layers.iter().any(|l| !l.loops.is_empty()));
            for layer in &layers {
                assert!(layer.height.is_finite());
                for lp in &layer.loops {
                    assert!(lp.points.len() >= 3);
                    assert!(lp.points.iter().flatten().all(|c| c.is_finite()));
                }
            }
        }
    }
});
