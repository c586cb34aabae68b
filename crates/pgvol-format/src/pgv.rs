//! The `.pgv` coefficient-volume file: encoding in `dense-f32`, and reading and writing in either
//! encoding (the container is described in `container`, `sparse-bricks` in `sparse`).

use std::path::Path;

use pgvol_core::{Background, SparseGrid};
use pgvol_field::CoefficientVolume;
use rayon::prelude::*;

use crate::container::{container, parse_container};
use crate::dense_alloc::zeroed;
use crate::error::err;
use crate::perturbation::is_perturbation;
use crate::sparse::payload_read::decode_payload;

pub use crate::container::{MAGIC, VERSION};
pub use crate::error::FormatError;
pub use crate::header::{header_for, mesh_hash, PgvFile, PgvHeader, ENCODING_DENSE_F32};

/// Serialises `file` to bytes in the `dense-f32` encoding, whatever its header says.
pub fn encode_pgv(file: &PgvFile) -> Vec<u8> {
    let mut header = file.header.clone();
    header.encoding = ENCODING_DENSE_F32.to_string();
    header.sparse = None;
    let payload: Vec<u8> = file
        .volume
        .dense_coeffs()
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    container(&header, &payload)
}

/// Writes `file` to `path` atomically.
pub fn write_pgv(path: &Path, file: &PgvFile) -> Result<(), FormatError> {
    let bytes = encode_pgv(file);
    pgvol_core::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| err(path, e.problem))
}

/// Reads and verifies a `.pgv` file.
pub fn read_pgv(path: &Path) -> Result<PgvFile, FormatError> {
    let bytes = pgvol_core::read_input(path).map_err(|e| err(path, e.problem))?;
    decode_pgv(&bytes, path)
}

/// Decodes a `.pgv` file from bytes, in either encoding; `path` names the file in errors.
pub fn decode_pgv(bytes: &[u8], path: &Path) -> Result<PgvFile, FormatError> {
    let c = parse_container(bytes, path, true)?;
    if is_perturbation(&c.header) {
        return Err(err(
            path,
            "holds a perturbation field (its function list), not a coefficient volume; \
             read it with pgvol's field reader, which resamples it",
        ));
    }
    let coeffs = if c.header.encoding == ENCODING_DENSE_F32 {
        let dense = dense_coeffs(c.payload, path)?;
        SparseGrid::from_dense(c.header.grid.dims, &dense, Background::clamp(0.0))
    } else {
        decode_payload(&c.header, c.index, c.payload, path)?
    };
    // Built directly rather than by `CoefficientVolume::from_sparse`, whose checks would cost
    // one more pass over every coefficient: the container check validated the basis and the
    // grid (at least 2 nodes per axis), and decoding gave finite coefficients.
    debug_assert_eq!(coeffs.dims(), c.header.grid.dims);
    let volume = CoefficientVolume {
        grid: c.header.grid,
        basis: c.header.basis,
        coeffs,
    };
    Ok(PgvFile {
        header: c.header,
        volume,
    })
}

/// The coefficients of a `dense-f32` payload (its length checked against the grid), each
/// checked finite; converted in parallel chunks.
fn dense_coeffs(payload: &[u8], path: &Path) -> Result<Vec<f32>, FormatError> {
    const CHUNK: usize = 1 << 16;
    let mut coeffs = zeroed(payload.len() / 4);
    let first_bad = coeffs
        .par_chunks_mut(CHUNK)
        .zip(payload.par_chunks(4 * CHUNK))
        .enumerate()
        .filter_map(|(chunk, (out, bytes))| {
            for (o, b) in out.iter_mut().zip(bytes.chunks_exact(4)) {
                *o = f32::from_le_bytes(b.try_into().expect("4 bytes"));
            }
            let bad = out.iter().position(|v| !v.is_finite())?;
            Some(chunk * CHUNK + bad)
        })
        .min();
    match first_bad {
        Some(index) => Err(err(
            path,
            format!("invalid coefficients: value {index} is not finite"),
        )),
        None => Ok(coeffs),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use pgvol_field::{Basis, Grid};
    use proptest::prelude::*;

    fn sample_file() -> PgvFile {
        let grid = Grid {
            origin: Vec3::new(-1.0, 0.0, 2.0),
            spacing: 0.25,
            dims: [3, 4, 5],
            offset: Default::default(),
        };
        let coeffs = (0..60).map(|i| i as f32 * 0.5 - 3.0).collect();
        let volume = CoefficientVolume::new(grid, Basis::Bspline3, coeffs).unwrap();
        let mut header = header_for(&volume, "interp", None);
        header.metadata.insert("note".into(), "ünïcode ok".into());
        PgvFile { header, volume }
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pgv");
        let f = sample_file();
        write_pgv(&path, &f).unwrap();
        assert_eq!(read_pgv(&path).unwrap(), f);
    }

    #[test]
    fn damaged_files_give_clear_errors() {
        let good = encode_pgv(&sample_file());
        let p = Path::new("x.pgv");
        let msg = |b: &[u8]| decode_pgv(b, p).unwrap_err().to_string();
        assert!(msg(&[]).contains("empty"));
        assert!(msg(b"hello world, not a pgv").contains("magic"));
        let mut v = good.clone();
        v[8] = 9;
        assert!(msg(&v).contains("version 9"));
        assert!(msg(&good[..good.len() - 7]).contains("truncated"));
        let mut v = good.clone();
        let last = v.len() - 10;
        v[last] ^= 0x40;
        assert!(msg(&v).contains("checksum"));
        let mut v = good.clone();
        v[20] ^= 1;
        assert!(msg(&v).contains("checksum"));
        let mut v = good.clone();
        v.push(0);
        assert!(msg(&v).contains("unexpected bytes"));
        assert!(msg(&v).starts_with("x.pgv: "));
    }

    #[test]
    fn frame_offsets_round_trip_and_hostile_ones_are_refused() {
        // Near the origin no offset is written: the header is as it always was.
        let near = encode_pgv(&sample_file());
        assert!(!String::from_utf8_lossy(&near).contains("offset"));
        let mut f = sample_file();
        f.volume.grid.offset = glam::DVec3::new(1e6 + 0.125, -3e7, 0.0);
        f.header.grid = f.volume.grid;
        assert_eq!(decode_pgv(&encode_pgv(&f), Path::new("f.pgv")).unwrap(), f);
        for bad in [2e8, -1e300] {
            f.volume.grid.offset.x = bad;
            f.header.grid = f.volume.grid;
            let e = decode_pgv(&encode_pgv(&f), Path::new("h.pgv"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("offset"), "{e}");
        }
        // Non-finite values have no JSON form, and a number beyond f64 is not read as one.
        let grid = r#"{"origin":[0,0,0],"spacing":1,"dims":[2,2,2],"offset":[1e400,0,0]}"#;
        assert!(serde_json::from_str::<Grid>(grid).is_err());
    }

    #[test]
    fn absurd_sizes_are_refused_before_allocation() {
        let mut f = sample_file();
        f.header.grid.dims = [1 << 20, 1 << 20, 1 << 20];
        let mut bytes = encode_pgv(&f);
        // Rewrite the payload length to match the huge claim; the reader must refuse by size.
        let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let at = 16 + hlen + 4;
        bytes[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let e = decode_pgv(&bytes, Path::new("big.pgv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("too large"), "{e}");
    }

    /// Grids whose nodes no stage can index: a spacing that carries the corners past any mesh,
    /// one too small for single precision to tell nodes apart, an origin beyond any mesh.
    #[test]
    fn grids_beyond_single_precision_are_refused() {
        for (case, want) in [
            ("huge spacing", "reaches beyond"),
            ("tiny spacing", "too small for single precision"),
            ("far origin", "reaches beyond"),
        ] {
            let mut f = sample_file();
            let g = &mut f.header.grid;
            match case {
                "huge spacing" => g.spacing = 3e38,
                "tiny spacing" => g.spacing = 1e-45,
                _ => g.origin.x = 1e30,
            }
            let e = decode_pgv(&encode_pgv(&f), Path::new("g.pgv"))
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("g.pgv: ") && e.contains(want), "{e}");
        }
        // The sample grid itself reads back.
        let f = sample_file();
        assert_eq!(decode_pgv(&encode_pgv(&f), Path::new("g.pgv")).unwrap(), f);
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            // A decoder that refuses everything would pass on random bytes alone.
            let good = encode_pgv(&sample_file());
            prop_assert_eq!(decode_pgv(&good, Path::new("g.pgv")).unwrap(), sample_file());
            let _ = decode_pgv(&bytes, Path::new("r.pgv"));
        }

        #[test]
        fn corrupted_files_never_panic(pos in 0usize..10_000, val in any::<u8>(), cut in 0usize..10_000) {
            let good = encode_pgv(&sample_file());
            prop_assert_eq!(decode_pgv(&good, Path::new("g.pgv")).unwrap(), sample_file());
            let mut bytes = good.clone();
            let n = bytes.len();
            bytes[pos % n] = val;
            bytes.truncate(cut % (n + 1));
            // Every byte is checked or covered by a CRC: whatever still decodes is the file
            // written (the edit left it unchanged).
            if let Ok(back) = decode_pgv(&bytes, Path::new("c.pgv")) {
                prop_assert_eq!(back, sample_file());
                prop_assert_eq!(bytes, good);
            }
        }
    }
}
