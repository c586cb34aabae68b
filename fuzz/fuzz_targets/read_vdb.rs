#![no_main]
//! Any bytes read as an OpenVDB file, for its first float level set and for a grid by name:
//! errors name the file; a level set has a positive finite voxel size, background and
//! translation, leaves on the 8-voxel lattice with finite values, and tiles of the tree's sizes.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol_format::vdb::read::{decode_vdb, VdbLevelSet};

/// The seed corpus, written by OpenVDB 10: Blosc, raw and half-float chunks.
const BLOSC: &[u8] = include_bytes!("../corpus/read_vdb/ball_blosc.vdb");
const RAW: &[u8] = include_bytes!("../corpus/read_vdb/ball_none.vdb");
const HALF: &[u8] = include_bytes!("../corpus/read_vdb/ball_half_blosc.vdb");

fn check_set(set: &VdbLevelSet) {
    assert!(set.voxel_size.is_finite() && set.voxel_size > 0.0);
    assert!(set.translation.iter().all(|t| t.is_finite()));
    assert!(set.background.is_finite() && set.background > 0.0);
    for leaf in &set.leaves {
        assert!(leaf.origin.iter().all(|o| o % 8 == 0), "{:?}", leaf.origin);
        assert!(leaf.values.iter().all(|v| v.is_finite()));
    }
    for tile in &set.tiles {
        assert!([3, 7, 12].contains(&tile.log2_edge), "{tile:?}");
        assert!(tile.value.is_finite());
    }
}

fn check(data: &[u8], name: Option<&str>) {
    match decode_vdb(data, Path::new("fuzz.vdb"), name) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.vdb: "), "{e}"),
        Ok(set) => check_set(&set),
    }
}

static SEEDS_READ: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEEDS_READ.call_once(|| {
        let path = Path::new("seed.vdb");
        for seed in [BLOSC, RAW, HALF] {
            let set = decode_vdb(seed, path, None).expect("the seed reads");
            assert!(!set.leaves.is_empty());
            check_set(&set);
        }
    });
    check(data, None);
    check(data, Some("ball"));
});
