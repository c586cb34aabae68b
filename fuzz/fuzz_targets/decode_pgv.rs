#![no_main]
//! Any bytes: decoding, info, single-brick and (compact) slab reads return errors, never panic; and
//! whatever decodes, info, single-brick and slab reads agree with and re-encodes to the same file. The seed
//! files are checked to decode first, so a decoder that refuses everything fails at once.

use std::path::Path;
use std::sync::Once;

use libfuzzer_sys::fuzz_target;
use pgvol_format::PgvFile;

/// The valid files of the seed corpus.
const SEEDS: [&[u8]; 9] = [
    include_bytes!("../corpus/decode_pgv/dense.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-f16.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-f32.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-fixed.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-q16.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-f16-v1.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-f32-v1.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-fixed-v1.pgv"),
    include_bytes!("../corpus/decode_pgv/sparse-q16-v1.pgv"),
];

/// Checks that a file that decoded to `file` reads the same through the other entry points, and
/// that its `dense-f32` encoding decodes back bit for bit.
fn check_agreement(data: &[u8], path: &Path, file: &PgvFile) {
    let info = pgvol_format::pgv_info(data, path).expect("info of a file that decodes");
    assert_eq!(info.header, file.header);
    if file.header.sparse.is_some() {
        let brick = pgvol_format::read_brick(data, path, [0, 0, 0])
            .expect("the first brick of a file that decodes");
        let mut at = 0;
        for k in 0..brick.dims[2] {
            for j in 0..brick.dims[1] {
                for i in 0..brick.dims[0] {
                    let whole = file.volume.coeffs.get([i, j, k]);
                    assert_eq!(brick.coeffs[at].to_bits(), whole.to_bits());
                    at += 1;
                }
            }
        }
    }
    if let Some(reader) =
        pgvol_format::SlabReader::open(data, path).expect("a file that decodes opens")
    {
        let counts = reader.brick_counts();
        for axis in 0..3 {
            for s in 0..counts[axis] {
                let slab = reader.slab(axis, s).expect("a slab of a file that decodes");
                for (m, values) in &slab.stored {
                    assert_eq!(file.volume.coeffs.brick(*m), Some(&**values));
                }
                for m in &slab.inside {
                    assert!(
                        file.volume.coeffs.brick(*m).is_none() && file.volume.coeffs.is_inside(*m)
                    );
                }
                // The compact slab holds the same coefficients, words mapped to their values.
                let compact = reader.compact_slab(axis, s).expect("a compact slab too");
                assert_eq!(compact.inside, slab.inside);
                let words = reader.word_scale();
                for (m, brick) in &compact.stored {
                    let values: Vec<f32> = match brick {
                        pgvol_format::CompactBrick::Words(w) => {
                            let scale = words.expect("words come with their values");
                            w.iter().map(|&w| scale.value(w as i32)).collect()
                        }
                        pgvol_format::CompactBrick::Values(v) => v.to_vec(),
                    };
                    let want = file.volume.coeffs.brick(*m).expect("a stored brick");
                    assert!(values
                        .iter()
                        .zip(want.iter())
                        .all(|(a, b)| a.to_bits() == b.to_bits()));
                }
            }
        }
    }
    let dense = pgvol_format::encode_pgv(file);
    let back = pgvol_format::decode_pgv(&dense, path).expect("the dense encoding decodes");
    assert_eq!(back.volume, file.volume);
}

static SEEDS_DECODE: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    SEEDS_DECODE.call_once(|| {
        for seed in SEEDS {
            let path = Path::new("seed.pgv");
            let file = pgvol_format::decode_pgv(seed, path).expect("a seed file decodes");
            check_agreement(seed, path, &file);
        }
    });
    let path = Path::new("fuzz.pgv");
    if let Ok(file) = pgvol_format::decode_pgv(data, path) {
        check_agreement(data, path, &file);
    }
    let _ = pgvol_format::pgv_info(data, path);
    let _ = pgvol_format::read_brick(data, path, [0, 0, 0]);
    if let Ok(Some(reader)) = pgvol_format::SlabReader::open(data, path) {
        for axis in 0..3 {
            let _ = reader.slab(axis, 0);
            let _ = reader.compact_slab(axis, 0);
        }
    }
});
