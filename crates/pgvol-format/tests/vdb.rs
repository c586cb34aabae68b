//! The `.vdb` reader against files OpenVDB 10 wrote (`tools/fixtures/make_vdb_fixtures.cpp`)
//! and the voxels OpenVDB itself listed for them.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use pgvol_format::vdb::read::{decode_vdb, read_vdb, VdbLevelSet};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/vdb")
        .join(name)
}

/// Every voxel of `set`'s leaves by index coordinate: value and whether active.
fn voxels(set: &VdbLevelSet) -> HashMap<[i32; 3], (f32, bool)> {
    let mut out = HashMap::new();
    for leaf in &set.leaves {
        for n in 0..512usize {
            let ijk = [
                leaf.origin[0] + (n >> 6) as i32,
                leaf.origin[1] + ((n >> 3) & 7) as i32,
                leaf.origin[2] + (n & 7) as i32,
            ];
            let active = leaf.active[n / 64] >> (n % 64) & 1 == 1;
            out.insert(ijk, (leaf.values[n], active));
        }
    }
    out
}

/// OpenVDB's listing of the ball: active voxel values, and per leaf the inactive signs.
struct Reference {
    background: f32,
    active: Vec<([i32; 3], f32)>,
    leaves: Vec<([i32; 3], Vec<u8>)>,
}

fn reference(name: &str) -> Reference {
    let text = std::fs::read_to_string(fixture(name)).unwrap();
    let mut r = Reference {
        background: 0.0,
        active: Vec::new(),
        leaves: Vec::new(),
    };
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        let ijk = |f: &[&str]| [1, 2, 3].map(|i| f[i].parse::<i32>().unwrap());
        match f[0] {
            "#" if f[1] == "background" => r.background = f[2].parse().unwrap(),
            "v" => r.active.push((ijk(&f), f[4].parse().unwrap())),
            "l" => r.leaves.push((ijk(&f), f[4].as_bytes().to_vec())),
            _ => {}
        }
    }
    r
}

/// `set` holds OpenVDB's values (within `tolerance`) and inactive signs for the ball.
fn assert_matches_ball(set: &VdbLevelSet, tolerance: f32) {
    let r = reference("ball_voxels.txt");
    assert_eq!(set.background, r.background);
    assert_eq!(set.voxel_size, 1.0);
    assert_eq!(set.translation, [0.0; 3]);
    assert_eq!(set.leaves.len(), r.leaves.len());
    let got = voxels(set);
    let active = got.values().filter(|v| v.1).count();
    assert_eq!(active, r.active.len());
    for (ijk, want) in &r.active {
        let (value, on) = got[ijk];
        assert!(on, "{ijk:?} inactive");
        assert!(
            (value - want).abs() <= tolerance,
            "{ijk:?}: {value} vs {want}"
        );
    }
    for (origin, signs) in &r.leaves {
        for (n, &s) in signs.iter().enumerate() {
            let ijk = [
                origin[0] + (n >> 6) as i32,
                origin[1] + ((n >> 3) & 7) as i32,
                origin[2] + (n & 7) as i32,
            ];
            let (value, on) = got[&ijk];
            match s {
                b'.' => assert!(on),
                b'+' => assert!(!on && value == r.background, "{ijk:?} {value}"),
                _ => assert!(!on && value == -r.background, "{ijk:?} {value}"),
            }
        }
    }
    // The ball is centred at (12, 12, 12), so the inside holds tiles or leaves of −background.
    assert!(got[&[12, 12, 12]].0 < 0.0 || set.tiles.iter().any(|t| t.value < 0.0));
}

#[test]
fn blosc_and_raw_chunks_give_openvdbs_values() {
    for (name, compression) in [("ball_blosc.vdb", 0x6), ("ball_none.vdb", 0x2)] {
        let set = read_vdb(&fixture(name), None).unwrap();
        assert_eq!(set.name, "ball", "{name}");
        assert_eq!(set.compression, compression, "{name}");
        assert_eq!(set.file_version, 224);
        assert!(!set.half);
        assert_matches_ball(&set, 0.0);
    }
}

#[test]
fn half_float_grids_read_within_half_precision() {
    for name in ["ball_half_blosc.vdb", "ball_half_none.vdb"] {
        let set = read_vdb(&fixture(name), None).unwrap();
        assert!(set.half, "{name}");
        // A half float keeps 11 significant bits: 2e-3 of values below 4.
        assert_matches_ball(&set, 2e-3);
    }
}

#[test]
fn the_first_level_set_is_read_with_its_translation_and_others_by_name() {
    let path = fixture("several_grids.vdb");
    let set = read_vdb(&path, None).unwrap();
    assert_eq!(set.name, "moved");
    assert_eq!(set.map, "UniformScaleTranslateMap");
    assert_eq!(set.voxel_size, 0.5);
    assert_eq!(set.translation, [1.25, -2.5, 0.75]);
    let got = voxels(&set);
    let text = std::fs::read_to_string(fixture("moved_active.txt")).unwrap();
    let mut count = 0;
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let f: Vec<f32> = line
            .split_whitespace()
            .map(|s| s.parse().unwrap())
            .collect();
        let ijk = [f[0] as i32, f[1] as i32, f[2] as i32];
        assert_eq!(got[&ijk], (f[3], true), "{ijk:?}");
        count += 1;
    }
    assert_eq!(got.values().filter(|v| v.1).count(), count);
    let second = read_vdb(&path, Some("second")).unwrap();
    assert_eq!((second.name.as_str(), second.voxel_size), ("second", 1.0));
    let e = read_vdb(&path, Some("density")).unwrap_err().to_string();
    assert!(
        e.contains("several_grids.vdb") && e.contains("fog volume"),
        "{e}"
    );
    let e = read_vdb(&path, Some("velocity")).unwrap_err().to_string();
    assert!(e.contains("Tree_vec3s"), "{e}");
    let e = read_vdb(&path, Some("nope")).unwrap_err().to_string();
    assert!(e.contains("'density'") && e.contains("'second'"), "{e}");
}

#[test]
fn other_transforms_are_refused_by_name() {
    let e = read_vdb(&fixture("stretched.vdb"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("stretched.vdb") && e.contains("ScaleMap"), "{e}");
}

#[test]
fn every_truncation_and_corrupted_count_is_an_error_naming_the_file() {
    let path = Path::new("cut.vdb");
    for name in ["ball_blosc.vdb", "ball_half_blosc.vdb", "several_grids.vdb"] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        let step = (bytes.len() / 400).max(1);
        for cut in (0..bytes.len()).step_by(step).chain([bytes.len() - 1]) {
            let e = decode_vdb(&bytes[..cut], path, None).unwrap_err();
            assert!(e.to_string().starts_with("cut.vdb: "), "{e}");
        }
        // Each byte flipped in turn (sampled) reads or fails, never panics.
        for at in (0..bytes.len()).step_by(step) {
            let mut b = bytes.clone();
            b[at] ^= 0xa5;
            let _ = decode_vdb(&b, path, None);
        }
    }
}

#[test]
fn header_counts_beyond_the_file_are_refused_before_allocation() {
    let mut bytes = std::fs::read(fixture("ball_blosc.vdb")).unwrap();
    // Magic (8), version (4), library (8), offsets flag (1), UUID (36), file metadata count.
    let meta = 8 + 4 + 8 + 1 + 36;
    assert_eq!(&bytes[meta..meta + 4], &[0, 0, 0, 0]);
    bytes[meta..meta + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = decode_vdb(&bytes, Path::new("x.vdb"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("claims 4294967295 file metadata entries"), "{e}");
    let mut bytes = std::fs::read(fixture("ball_blosc.vdb")).unwrap();
    bytes[8..12].copy_from_slice(&220u32.to_le_bytes());
    let e = decode_vdb(&bytes, Path::new("x.vdb"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("version 220"), "{e}");
    let e = decode_vdb(b"not a vdb at all", Path::new("x.vdb"), None).unwrap_err();
    assert!(e.to_string().contains("not an OpenVDB file"), "{e}");
}
