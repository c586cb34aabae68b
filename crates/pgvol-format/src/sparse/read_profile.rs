//! Where the time of reading a `sparse-bricks` file goes: the reader's own steps run one stage
//! at a time over all bricks, on one thread, each timed. The real reader
//! ([`crate::decode_pgv`]) interleaves the stages per brick and runs brick rows in parallel;
//! this split shows what each stage costs. Between stages the bricks' bytes and values are kept
//! in flat buffers, which the real reader never builds.
//!
//! Built for the tests only: an independent sequential reader that the parallel one must agree
//! with, on valid and on damaged files.

use std::path::Path;
use std::time::{Duration, Instant};

use super::brick_decoder::{decode_values, raw_len, WordScratch};
use super::brick_read::{checked_blob, inflate, non_finite};
use super::index::{bit, layout};
use super::payload_read::{fill_brick_row, layer_first_entries, layer_rows, RowScratch};
use crate::container::parse_container;
use crate::dense_alloc::zeroed;
use crate::error::{err, FormatError};
use crate::sparse_params::ENCODING_SPARSE;

/// Time per stage of reading one sparse file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadStages {
    /// Container and JSON header, sizes, brick maps and index with its CRC.
    pub parse: Duration,
    /// The payload CRC and every brick's CRC.
    pub checksums: Duration,
    /// zstd decompression of every stored brick.
    pub decompress: Duration,
    /// Byte un-shuffle, un-zig-zag, undoing the prediction, dequantisation, finiteness.
    pub decode: Duration,
    /// Allocating the dense array and writing every coefficient: stored and background.
    pub fill: Duration,
}

impl ReadStages {
    pub fn total(&self) -> Duration {
        self.parse + self.checksums + self.decompress + self.decode + self.fill
    }
}

/// Reads a `sparse-bricks` file stage by stage on the calling thread, with every check of
/// [`crate::decode_pgv`]; returns the stage times and the coefficients (x fastest), which are
/// those `decode_pgv` gives.
pub fn profile_sparse_read(
    bytes: &[u8],
    path: &Path,
) -> Result<(ReadStages, Vec<f32>), FormatError> {
    let mut times = ReadStages::default();

    let t = Instant::now();
    let c = parse_container(bytes, path, false)?;
    if c.header.encoding != ENCODING_SPARSE {
        return Err(err(
            path,
            format!("the stages are those of the {ENCODING_SPARSE} encoding"),
        ));
    }
    let l = layout(&c.header, c.index, c.payload, path)?;
    times.parse = t.elapsed();

    let t = Instant::now();
    c.check_payload(path)?;
    let mut blobs = Vec::with_capacity(l.sp.stored);
    for b in (0..l.bricks.total()).filter(|&b| bit(l.stored, b)) {
        blobs.push((b, checked_blob(&l, b, blobs.len(), path)?));
    }
    times.checksums = t.elapsed();

    // The flat buffers between stages are allocated and touched before the timers start, so
    // that their page faults count in no stage.
    let (mut raw_spans, mut value_spans) = (Vec::with_capacity(blobs.len()), Vec::new());
    let (mut raw_total, mut value_total) = (0, 0);
    for &(b, _) in &blobs {
        let (_, n) = l.bricks.extent(b);
        let (raw, count) = (raw_len(n, &l.sp), n[0] * n[1] * n[2]);
        raw_spans.push(raw_total..raw_total + raw);
        value_spans.push(value_total..value_total + count);
        raw_total += raw;
        value_total += count;
    }
    let mut raws = vec![u8::MAX; raw_total];
    let mut values = vec![f32::MAX; value_total];

    let t = Instant::now();
    let (mut dctx, mut buf) = (None, Vec::new());
    for ((b, blob), span) in blobs.iter().zip(&raw_spans) {
        let raw = inflate(&l, *b, blob, &mut dctx, &mut buf, path)?;
        raws[span.clone()].copy_from_slice(raw);
    }
    times.decompress = t.elapsed();

    let t = Instant::now();
    let mut scratch = WordScratch::default();
    for ((&(b, _), raw), out) in blobs.iter().zip(&raw_spans).zip(&value_spans) {
        let (_, n) = l.bricks.extent(b);
        decode_values(
            &raws[raw.clone()],
            n,
            &l.sp,
            &mut scratch,
            &mut values[out.clone()],
        )
        .map_err(|_| non_finite(&l, b, path))?;
    }
    times.decode = t.elapsed();

    let t = Instant::now();
    let [nx, ny, nz] = l.bricks.dims;
    let mut coeffs = zeroed(nx * ny * nz);
    let mut row_scratch = RowScratch::default();
    let firsts = layer_first_entries(&l);
    for (bk, slab) in coeffs.chunks_mut(nx * ny * l.bricks.edge).enumerate() {
        for mut r in layer_rows(&l, bk, firsts[bk], slab) {
            fill_brick_row(&l, &mut r, &mut row_scratch, |_, e, out| {
                out.copy_from_slice(&values[value_spans[e].clone()]);
                Ok(())
            })?;
        }
    }
    times.fill = t.elapsed();
    Ok((times, coeffs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::header::{header_for, PgvFile};
    use crate::pgv::decode_pgv;
    use crate::sparse::{encode_pgv_with, EncodeOptions};
    use crate::sparse_params::{Compression, Precision, Predictor};
    use glam::Vec3;
    use pgvol_field::{Basis, CoefficientVolume, Grid};
    use proptest::prelude::*;

    fn p() -> &'static Path {
        Path::new("r.pgv")
    }

    /// Two banded spheres on a grid whose sides are not multiples of the brick edges.
    fn two_spheres(dims: [usize; 3]) -> PgvFile {
        let grid = Grid {
            origin: Vec3::new(-1.0, -0.8, -1.2),
            spacing: 2.4 / dims[2] as f32,
            dims,
            offset: Default::default(),
        };
        let clamp = 4.0 * grid.spacing;
        let mut samples = Vec::with_capacity(grid.len());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let q = grid.point(i, j, k);
                    let a = (q - Vec3::new(-0.3, 0.0, -0.4)).length() - 0.4;
                    let b = (q - Vec3::new(0.4, 0.1, 0.5)).length() - 0.3;
                    samples.push(a.min(b).clamp(-clamp, clamp));
                }
            }
        }
        let volume = CoefficientVolume::new(grid, Basis::Trilinear, samples).unwrap();
        PgvFile {
            header: header_for(&volume, "interp", None),
            volume,
        }
    }

    fn encoded(
        f: &PgvFile,
        brick: usize,
        precision: Precision,
        predictor: Predictor,
        compression: Compression,
    ) -> Vec<u8> {
        let o = EncodeOptions {
            precision: Some(precision),
            brick,
            predictor,
            compression,
            band: 2.0,
            zstd_level: 3,
            ..EncodeOptions::default()
        };
        encode_pgv_with(f, &o).unwrap().0
    }

    fn bits(v: &[f32]) -> Vec<u32> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn stage_by_stage_read_gives_the_decoded_volume() {
        let f = two_spheres([41, 33, 50]);
        for (brick, precision, predictor, compression) in [
            (8, Precision::Q16, Predictor::DeltaX, Compression::Zstd),
            (5, Precision::F32, Predictor::Lorenzo, Compression::None),
            (3, Precision::F16, Predictor::None, Compression::None),
            (8, Precision::Fixed, Predictor::DeltaX, Compression::Zstd),
            (7, Precision::Fixed, Predictor::Lorenzo, Compression::Zstd),
        ] {
            let bytes = encoded(&f, brick, precision, predictor, compression);
            let (stages, staged) = profile_sparse_read(&bytes, p()).unwrap();
            let decoded = decode_pgv(&bytes, p()).unwrap().volume.dense_coeffs();
            assert_eq!(bits(&staged), bits(&decoded), "{brick} {precision:?}");
            assert!(stages.total() >= stages.decompress + stages.decode);
        }
    }

    #[test]
    fn stage_by_stage_read_names_the_first_damaged_brick() {
        let f = two_spheres([41, 33, 50]);
        let good = encoded(&f, 8, Precision::Q16, Predictor::DeltaX, Compression::Zstd);
        // Two bytes of brick data near its end (version 2: the data ends where the trailer's
        // first field says, 12 bytes in).
        let n = good.len();
        let dlen = u64::from_le_bytes(good[n - 32..n - 24].try_into().unwrap()) as usize;
        let end = 12 + dlen;
        let mut bad = good.clone();
        for at in [end - 9, end - 400] {
            bad[at] ^= 0x5a;
        }
        let want = decode_pgv(&bad, p()).unwrap_err().to_string();
        assert!(want.contains("checksum mismatch"), "{want}");
        let got = profile_sparse_read(&bad, p()).unwrap_err().to_string();
        assert_eq!(got, want);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// On any edit of a valid file the two readers both fail, or both give the same volume.
        #[test]
        fn both_readers_accept_the_same_files(
            edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..3),
            cut in any::<usize>(),
            which in 0usize..4,
        ) {
            let f = two_spheres([9, 10, 12]);
            let mut bytes = encoded(
                &f,
                4,
                Precision::ALL[which],
                Predictor::DeltaX,
                Compression::Zstd,
            );
            // The valid file reads, the same both ways.
            let (_, clean) = profile_sparse_read(&bytes, p()).unwrap();
            prop_assert_eq!(bits(&clean), bits(&decode_pgv(&bytes, p()).unwrap().volume.dense_coeffs()));
            let n = bytes.len();
            for (pos, val) in edits {
                bytes[pos % n] = val;
            }
            bytes.truncate(n - cut % 3);
            let staged = profile_sparse_read(&bytes, p());
            let decoded = decode_pgv(&bytes, p());
            prop_assert_eq!(staged.is_ok(), decoded.is_ok());
            if let (Ok((_, staged)), Ok(decoded)) = (staged, decoded) {
                prop_assert_eq!(bits(&staged), bits(&decoded.volume.dense_coeffs()));
            }
        }
    }
}
