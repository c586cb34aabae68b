//! No input bytes may panic a reader: random bytes, format-shaped noise, truncations and
//! mutations of valid files all have to come back as `Ok` or `Err`. Set PROPTEST_CASES for a
//! longer run than the default 256 cases per property.

mod common;

use std::path::Path;
use std::sync::OnceLock;

use pgvol_mesh::{read_bytes, write, MeshFormat};
use proptest::prelude::*;

const FORMATS: [MeshFormat; 5] = [
    MeshFormat::Obj,
    MeshFormat::Gltf,
    MeshFormat::Glb,
    MeshFormat::Stl,
    MeshFormat::Ply,
];

/// A valid file of every format, plus a few hand-written variants that reach other code paths.
fn samples() -> &'static Vec<(MeshFormat, Vec<u8>)> {
    static SAMPLES: OnceLock<Vec<(MeshFormat, Vec<u8>)>> = OnceLock::new();
    SAMPLES.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let mut out = Vec::new();
        for f in FORMATS {
            let path = dir.path().join(format!("s.{}", f.extension()));
            write(&path, &common::odd_cube()).unwrap();
            out.push((f, std::fs::read(&path).unwrap()));
        }
        out.push((
            MeshFormat::Stl,
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
              vertex 0 1 0\nendloop\nendfacet\nendsolid x\n"
                .to_vec(),
        ));
        out.push((
            MeshFormat::Ply,
            b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
              end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"
                .to_vec(),
        ));
        out.push((
            MeshFormat::Obj,
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4/1/1 -3 -2 -1\nf 1 2 3\n".to_vec(),
        ));
        out
    })
}

fn check(bytes: &[u8], format: MeshFormat) {
    let name = Path::new("fuzz.bin");
    if let Err(e) = read_bytes(bytes, format, name) {
        assert!(e.to_string().starts_with("fuzz.bin: "), "{e}");
        assert!(!e.problem.is_empty());
    }
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
        let (format, bytes) = which.get(samples());
        let cut = cut.index(bytes.len() + 1);
        check(&bytes[..cut], *format);
    }

    #[test]
    fn mutated_valid_files(
        which in any::<prop::sample::Index>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
    ) {
        let (format, bytes) = which.get(samples());
        let mut bytes = bytes.clone();
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        check(&bytes, *format);
    }

    #[test]
    fn mutated_digits_in_text_files(
        which in any::<prop::sample::Index>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), prop::sample::select(b"-0123456789.e+ /\n".to_vec())), 1..6),
    ) {
        // Textual edits keep text formats parseable far enough to reach index and number checks.
        let (format, bytes) = which.get(samples());
        let mut bytes = bytes.clone();
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        check(&bytes, *format);
    }
}

#[test]
fn every_truncation_of_small_samples() {
    for (format, bytes) in samples() {
        if bytes.len() <= 4096 {
            for cut in 0..bytes.len() {
                check(&bytes[..cut], *format);
            }
        }
    }
}

#[test]
fn samples_are_valid() {
    for (format, bytes) in samples() {
        let m = read_bytes(bytes, *format, Path::new("sample")).unwrap();
        assert!(!m.triangles.is_empty());
    }
}
