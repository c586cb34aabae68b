//! The contract every mesh reader is held to by the fuzz targets `read_obj`, `read_stl`,
//! `read_ply`, `read_gltf`, `read_glb` and `read_3mf`.

use std::path::Path;
use std::sync::Once;

use pgvol_mesh::{read_bytes, too_small, write_to, Mesh, MeshFormat, MAX_COORDINATE};

/// Reads `data` as `format` and checks the result: an error names the file and a problem; a mesh
/// has triangles, only indices of its own vertices, finite coordinates within the accepted range
/// and an extent large enough to process, and it writes in the same format and reads back with
/// the same triangle corners. The first call also checks that every seed file reads, so a reader
/// that refuses everything fails at once.
pub fn mesh_target(format: MeshFormat, seeds: &[&[u8]], data: &[u8]) {
    mesh_target_via(format, format, seeds, data);
}

/// [`mesh_target`] for a format that is read only (3MF): the mesh read is written as `written`
/// and must read back from it with the same triangle corners.
pub fn mesh_target_via(format: MeshFormat, written: MeshFormat, seeds: &[&[u8]], data: &[u8]) {
    static SEEDS_READ: Once = Once::new();
    SEEDS_READ.call_once(|| {
        for (i, seed) in seeds.iter().enumerate() {
            let name = format!("seed.{}", format.extension());
            if let Err(e) = read_bytes(seed, format, Path::new(&name)) {
                panic!("seed {i} does not read: {e}");
            }
        }
    });
    let name = format!("fuzz.{}", format.extension());
    let name = Path::new(&name);
    match read_bytes(data, format, name) {
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz."), "{e}");
            assert!(!e.problem.is_empty());
        }
        Ok(mesh) => {
            check_mesh(&mesh);
            let mut bytes = Vec::new();
            write_to(&mut bytes, &mesh, written, name).expect("a mesh that was read writes");
            let back = read_bytes(&bytes, written, name).expect("a written mesh reads back");
            assert_eq!(back.triangles.len(), mesh.triangles.len());
            if back.offset == mesh.offset {
                for t in 0..mesh.triangles.len() {
                    assert_eq!(back.triangle(t), mesh.triangle(t), "triangle {t}");
                }
            } else {
                // The frame of a mesh far from the origin is a rounding of its centre: the
                // composed write of the offset can land on the next step with the same world
                // positions, each local coordinate then rounded to f32 once more.
                let size = mesh_size(&mesh);
                let tolerance = 1e-6 * size + 1e-12 * mesh.offset.abs().max_element();
                for t in 0..mesh.triangles.len() {
                    for (a, b) in back.triangle(t).iter().zip(mesh.triangle(t)) {
                        let (a, b) = (back.offset + a.as_dvec3(), mesh.offset + b.as_dvec3());
                        assert!(
                            (a - b).abs().max_element() <= tolerance,
                            "triangle {t}: {a} read back, {b} written (frames {} and {})",
                            back.offset,
                            mesh.offset
                        );
                    }
                }
            }
        }
    }
}

/// The longest side of the mesh's bounding box.
fn mesh_size(mesh: &Mesh) -> f64 {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &mesh.positions {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (0..3).map(|a| f64::from(hi[a] - lo[a])).fold(0.0, f64::max)
}

/// The checks every mesh leaving a reader must pass.
fn check_mesh(mesh: &Mesh) {
    assert!(!mesh.triangles.is_empty(), "a mesh without triangles");
    let n = mesh.positions.len();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        assert!(
            tri.iter().all(|&i| (i as usize) < n),
            "triangle {t} {tri:?} indexes past {n} vertices"
        );
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        assert!(
            p.is_finite() && p.abs().max_element() < MAX_COORDINATE,
            "vertex {i} at {p}"
        );
    }
    assert_eq!(too_small(mesh), None, "a mesh too small to process");
}
