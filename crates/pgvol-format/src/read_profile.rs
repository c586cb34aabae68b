//! Where the time of reading a `sparse-bricks` file goes: the reader's own steps run one stage
//! at a time over all bricks, on one thread, each timed. The real reader
//! ([`crate::decode_pgv`]) interleaves the stages per brick and runs brick rows in parallel;
//! this split shows what each stage costs. Between stages the bricks' bytes and values are kept
//! in flat buffers, which the real reader never builds.

use std::path::Path;
use std::time::{Duration, Instant};

use crate::brick_codec::{decode_values, raw_len, WordScratch};
use crate::pgv::{err, parse_container, FormatError};
use crate::sparse::{bit, layout, ENCODING_SPARSE};
use crate::sparse_read::{
    checked_blob, fill_brick_row, inflate, layer_first_entries, layer_rows, non_finite, RowScratch,
};

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
    let l = layout(&c.header, c.payload, path)?;
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
    for (&(b, blob), span) in blobs.iter().zip(&raw_spans) {
        let raw = inflate(&l, b, blob, &mut dctx, &mut buf, path)?;
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
    let mut coeffs = crate::dense_alloc::zeroed(nx * ny * nz);
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
