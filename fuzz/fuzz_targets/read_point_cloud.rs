#![no_main]
//! Any bytes read as a point cloud, as text (`x y z [nx ny nz]` per line) and as PLY: an
//! error naming the file, or points that are finite and within the accepted range, with
//! finite normals, one per point, when there are any.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol::io::read_cloud_text;
use pgvol_mesh::{read_ply_points, MAX_COORDINATE};

const TEXT_SEED: &[u8] = include_bytes!("../corpus/read_point_cloud/cloud.xyz");
const PLY_SEED: &[u8] = include_bytes!("../corpus/read_point_cloud/cloud.ply");

static SEEDS_READ: Once = Once::new();

fn check(points: &[pgvol::glam::Vec3], normals: Option<&Vec<pgvol::glam::Vec3>>) {
    assert!(!points.is_empty());
    for p in points {
        assert!(
            p.is_finite() && p.abs().max_element() < MAX_COORDINATE,
            "{p}"
        );
    }
    if let Some(n) = normals {
        assert_eq!(n.len(), points.len());
        assert!(n.iter().all(|v| v.is_finite()));
    }
}

fuzz_target!(|data: &[u8]| {
    SEEDS_READ.call_once(|| {
        read_cloud_text(TEXT_SEED, Path::new("seed.xyz")).expect("the text seed reads");
        read_ply_points(PLY_SEED, Path::new("seed.ply")).expect("the PLY seed reads");
    });
    match read_cloud_text(data, Path::new("fuzz.xyz")) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.xyz: "), "{e}"),
        Ok(cloud) => check(&cloud.points, cloud.normals.as_ref()),
    }
    match read_ply_points(data, Path::new("fuzz.ply")) {
        Err(e) => assert!(e.to_string().starts_with("fuzz.ply: "), "{e}"),
        Ok((points, normals)) => check(&points, normals.as_ref()),
    }
});
