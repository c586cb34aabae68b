//! Helpers shared by the integration tests: locating the shared meshes, seeded random points
//! and the shipped encode/decode pipeline through the `pgvol` library.

#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};

use glam::Vec3;
use pgvol::{CoefficientVolume, Mesh};
use rand::{Rng, SeedableRng};

/// Every mesh of the shared folder, by file stem.
pub const SHARED_MESHES: [&str; 7] = [
    "stanford-bunny",
    "spot",
    "cow",
    "fandisk",
    "rocker-arm",
    "teapot",
    "suzanne",
];

/// The folder with the shared meshes: `PGVOL_SHARED_MESHES` if set, otherwise `shared/meshes`
/// next to the workspace. Panics (never skips) when it is missing, so a broken checkout cannot
/// pass the suite by testing nothing.
pub fn shared_meshes_dir() -> PathBuf {
    let (dir, origin) = match std::env::var_os("PGVOL_SHARED_MESHES") {
        Some(d) => (PathBuf::from(d), "PGVOL_SHARED_MESHES"),
        None => (
            // This crate sits at the workspace root, so two levels up is the workspace's parent.
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/meshes"),
            "the default location (set PGVOL_SHARED_MESHES to override)",
        ),
    };
    existing_dir(dir, origin)
}

fn existing_dir(dir: PathBuf, origin: &str) -> PathBuf {
    assert!(
        dir.is_dir(),
        "shared meshes folder {} (from {origin}) does not exist: the integration tests need \
         the shared meshes and refuse to pass without them",
        dir.display()
    );
    dir
}

/// Path of the shared mesh `name` (file stem), panicking with a clear message if it is absent.
pub fn shared_mesh_path(name: &str) -> PathBuf {
    let path = shared_meshes_dir().join(format!("{name}.obj"));
    assert!(
        path.is_file(),
        "shared mesh {} is missing: the integration tests need it",
        path.display()
    );
    path
}

/// The shared mesh `name`, read and cleaned as the library does (bit-exact weld, degenerate
/// triangles dropped).
pub fn load_shared(name: &str) -> Mesh {
    let path = shared_mesh_path(name);
    match pgvol::io::read_mesh(&path) {
        Ok(read) => read.mesh,
        Err(e) => panic!("cannot read shared mesh {}: {e}", path.display()),
    }
}

/// The cube of side 1.1 x the longest extent around the mesh (the grid convention), as
/// `(lo, hi)`.
pub fn margin_cube(mesh: &Mesh) -> (Vec3, Vec3) {
    let (lo, hi) = mesh.bounds().expect("mesh has triangles");
    let half = 0.5 * pgvol::core::GRID_MARGIN * (hi - lo).max_element();
    let centre = 0.5 * (lo + hi);
    (centre - Vec3::splat(half), centre + Vec3::splat(half))
}

/// `n` uniformly random points in `[lo, hi]`, reproducible from `seed`.
pub fn random_points(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..n)
        .map(|_| lo + (hi - lo) * Vec3::new(rng.gen(), rng.gen(), rng.gen()))
        .collect()
}

/// `mesh` encoded as `pgvol encode --res RES` does with every other option at its default.
pub fn encode(mesh: &Mesh, res: usize) -> pgvol::Encoded {
    let options = pgvol::EncodeOptions {
        grid: pgvol::GridSpec::Res(res),
        ..Default::default()
    };
    pgvol::encode(mesh, &options, &pgvol::Silent).expect("encode")
}

/// The zero level set of `volume`, contoured as `pgvol decode` does by default.
pub fn decode(volume: &CoefficientVolume) -> Mesh {
    pgvol::Field::from_volume((*volume).clone())
        .to_mesh(&pgvol::DecodeOptions::default(), &pgvol::Silent)
        .expect("decode")
}

/// Runs `f` in a fresh rayon pool of `threads` threads.
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[should_panic(expected = "refuse to pass without them")]
    fn a_missing_mesh_folder_fails_loudly() {
        existing_dir(PathBuf::from("/nonexistent/pgvol/meshes"), "a test");
    }

    #[test]
    fn the_default_folder_is_found() {
        assert!(shared_meshes_dir().join("stanford-bunny.obj").is_file());
    }
}
