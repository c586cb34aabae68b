//! No input bytes may panic a reader: random bytes, format-shaped noise, truncations and
//! mutations of valid files all have to come back as `Ok` or `Err`. Set PROPTEST_CASES for a
//! longer run than the default 256 cases per property.

mod common;

use std::path::Path;
use std::sync::OnceLock;

use pgvol_mesh::{read_bytes, write, Mesh, MeshFormat, MAX_COORDINATE};
use proptest::prelude::*;

const FORMATS: [MeshFormat; 5] = [
    MeshFormat::Obj,
    MeshFormat::Gltf,
    MeshFormat::Glb,
    MeshFormat::Stl,
    MeshFormat::Ply,
];

/// A valid file and the number of triangles reading it must give.
struct Sample {
    format: MeshFormat,
    bytes: Vec<u8>,
    triangles: usize,
}

/// A valid file of every format, plus a few hand-written variants that reach other code paths.
fn samples() -> &'static Vec<Sample> {
    static SAMPLES: OnceLock<Vec<Sample>> = OnceLock::new();
    SAMPLES.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let cube = common::odd_cube();
        let mut out = Vec::new();
        for format in FORMATS {
            let path = dir.path().join(format!("s.{}", format.extension()));
            write(&path, &cube).unwrap();
            out.push(Sample {
                format,
                bytes: std::fs::read(&path).unwrap(),
                triangles: cube.triangles.len(),
            });
        }
        out.push(Sample {
            format: MeshFormat::Stl,
            bytes: b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
              vertex 0 1 0\nendloop\nendfacet\nendsolid x\n"
                .to_vec(),
            triangles: 1,
        });
        // One quad: two triangles.
        out.push(Sample {
            format: MeshFormat::Ply,
            bytes: b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
              end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"
                .to_vec(),
            triangles: 2,
        });
        // A quad with negative indices and a triangle: three triangles.
        out.push(Sample {
            format: MeshFormat::Obj,
            bytes: b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4/1/1 -3 -2 -1\nf 1 2 3\n".to_vec(),
            triangles: 3,
        });
        out
    })
}

/// Reads `bytes` and holds the result to the readers' contract: an error names the file and a
/// problem; a mesh has triangles, only indices of its own vertices and only finite coordinates
/// within the accepted range. Returns the mesh read, if any.
fn check(bytes: &[u8], format: MeshFormat) -> Option<Mesh> {
    let name = Path::new("fuzz.bin");
    match read_bytes(bytes, format, name) {
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz.bin: "), "{e}");
            assert!(!e.problem.is_empty());
            None
        }
        Ok(mesh) => {
            assert!(
                !mesh.triangles.is_empty(),
                "{format:?}: a mesh without triangles"
            );
            let n = mesh.positions.len();
            for (t, tri) in mesh.triangles.iter().enumerate() {
                assert!(
                    tri.iter().all(|&i| (i as usize) < n),
                    "{format:?}: triangle {t} {tri:?} indexes past {n} vertices"
                );
            }
            for (i, p) in mesh.positions.iter().enumerate() {
                assert!(
                    p.is_finite() && p.abs().max_element() < MAX_COORDINATE,
                    "{format:?}: vertex {i} at {p}"
                );
            }
            Some(mesh)
        }
    }
}

/// A sample read whole: it must succeed with its own triangle count.
fn check_valid(sample: &Sample) -> Mesh {
    let mesh = check(&sample.bytes, sample.format)
        .unwrap_or_else(|| panic!("{:?}: a valid file was refused", sample.format));
    assert_eq!(
        mesh.triangles.len(),
        sample.triangles,
        "{:?}",
        sample.format
    );
    mesh
}

fn format_strategy() -> impl Strategy<Value = MeshFormat> {
    prop::sample::select(FORMATS.to_vec())
}

proptest! {
    #[test]
    fn random_bytes(bytes in prop::collection::vec(any::<u8>(), 0..600), format in format_strategy()) {
        check(&bytes, format);
    }

    #[test]
    fn format_prefix_then_noise(
        prefix in prop::sample::select(vec![
            &b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"[..],
            &b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 2\nproperty list uint int vertex_indices\nend_header\n"[..],
            &b"solid a\nfacet normal 0 0 0\nouter loop\nvertex "[..],
            &b"glTF\x02\x00\x00\x00"[..],
            &b"{\"asset\":{\"version\":\"2.0\"},"[..],
            &b"v 1 2 3\nv 4 5 6\nf "[..],
        ]),
        noise in prop::collection::vec(any::<u8>(), 0..300),
        format in format_strategy(),
    ) {
        let mut bytes = prefix.to_vec();
        bytes.extend_from_slice(&noise);
        check(&bytes, format);
    }

    #[test]
    fn truncated_valid_files(which in any::<prop::sample::Index>(), cut in any::<prop::sample::Index>()) {
        let sample = which.get(samples());
        let cut = cut.index(sample.bytes.len() + 1);
        if cut == sample.bytes.len() {
            check_valid(sample);
        } else {
            check(&sample.bytes[..cut], sample.format);
        }
    }

    #[test]
    fn mutated_valid_files(
        which in any::<prop::sample::Index>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
    ) {
        let sample = which.get(samples());
        let mut bytes = sample.bytes.clone();
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        if bytes == sample.bytes {
            check_valid(sample);
        } else {
            check(&bytes, sample.format);
        }
    }

    #[test]
    fn mutated_digits_in_text_files(
        which in any::<prop::sample::Index>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), prop::sample::select(b"-0123456789.e+ /\n".to_vec())), 1..6),
    ) {
        // Textual edits keep text formats parseable far enough to reach index and number checks.
        let sample = which.get(samples());
        let mut bytes = sample.bytes.clone();
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        if bytes == sample.bytes {
            check_valid(sample);
        } else {
            check(&bytes, sample.format);
        }
    }
}

#[test]
fn every_truncation_of_small_samples() {
    for sample in samples() {
        if sample.bytes.len() <= 4096 {
            for cut in 0..sample.bytes.len() {
                check(&sample.bytes[..cut], sample.format);
            }
        }
    }
}

/// Every sample reads with its triangle count, and the cube samples give back the cube's box,
/// so a reader that refuses everything, or returns a placeholder, fails here.
#[test]
fn samples_read_back_whole() {
    let (lo, hi) = common::odd_cube().bounds().unwrap();
    for sample in samples() {
        let mesh = check_valid(sample);
        if sample.triangles == 12 {
            // World bounds: a mesh far from the origin for its size is held recentred.
            let (got_lo, got_hi) = mesh.bounds().unwrap();
            let got_lo = (got_lo.as_dvec3() + mesh.offset).as_vec3();
            let got_hi = (got_hi.as_dvec3() + mesh.offset).as_vec3();
            let tol = 1e-6 * hi.abs().max(lo.abs()).max_element();
            assert!(
                (got_lo - lo).abs().max_element() <= tol
                    && (got_hi - hi).abs().max_element() <= tol,
                "{:?}: box {got_lo}..{got_hi}, want {lo}..{hi}",
                sample.format
            );
        }
    }
}
