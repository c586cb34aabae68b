//! Writing a `.pgv` file in the `sparse-bricks` encoding: which bricks to store, their encoding
//! at the chosen precision, the index, and the container around them.

use std::path::Path;

use super::brick_encoder::StoredBricks;
use super::bricks::Bricks;
use super::coverage::Coverage;
use super::free_words::tolerance_steps;
use super::index::brick_index;
use super::kept_bricks::{background, stored_map, Background};
use super::options::{EncodeOptions, EncodeReport};
use super::precision_choice::{basis_weight_bound, encode_smallest, fixed_scale};
use super::reencode::decoded_layout;
use super::stored_band::stored_band;
use crate::container::{
    streamed_framing_bytes, write_container, write_streamed_end, write_streamed_start,
};
use crate::error::{err, FormatError};
use crate::header::{PgvFile, PgvHeader};
use crate::sparse_params::{Precision, SparseParams, ENCODING_SPARSE};

/// A file in the `sparse-bricks` encoding, held as its header, its index and its bricks'
/// blobs: written out without being copied into one buffer first.
pub struct SparsePgv {
    header: PgvHeader,
    index: Vec<u8>,
    blobs: Vec<Vec<u8>>,
}

impl SparsePgv {
    /// Writes the file to `w` in the version 2 layout (brick data, then the index and the
    /// header), byte for byte what [`StreamedPgv`](super::StreamedPgv) writes of the same
    /// volume.
    pub fn write_to(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        write_streamed_start(w)?;
        for blob in &self.blobs {
            w.write_all(blob)?;
        }
        let data_len = self.blobs.iter().map(|b| b.len() as u64).sum();
        write_streamed_end(w, data_len, &self.index, &self.header)
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.len_hint());
        self.write_to(&mut out)
            .expect("writing to memory does not fail");
        out
    }

    /// The same file in the version 1 layout (header and index before the bricks), which every
    /// reader keeps reading: for tools and tests that need a file of that version.
    pub fn to_bytes_v1(&self) -> Vec<u8> {
        let parts: Vec<&[u8]> = std::iter::once(&self.index[..])
            .chain(self.blobs.iter().map(|b| &b[..]))
            .collect();
        let mut out = Vec::with_capacity(self.len_hint());
        write_container(&mut out, &self.header, &parts).expect("writing to memory does not fail");
        out
    }

    fn len_hint(&self) -> usize {
        self.index.len() + self.blobs.iter().map(Vec::len).sum::<usize>() + 1024
    }
}

/// Encodes `file` in the `sparse-bricks` encoding.
pub fn encode_pgv_with(
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<(Vec<u8>, EncodeReport), FormatError> {
    let (encoded, report) = sparse_pgv(file, opts)?;
    Ok((encoded.to_bytes(), report))
}

/// [`encode_pgv_with`], keeping the file in pieces for [`SparsePgv::write_to`].
pub fn sparse_pgv(
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<(SparsePgv, EncodeReport), FormatError> {
    let fail = |m: String| err(Path::new("<encode>"), m);
    let volume = &file.volume;
    let g = volume.grid;
    opts.check().map_err(fail)?;
    pgvol_field::volume::check_sparse(&volume.grid, volume.basis, &volume.coeffs)
        .map_err(|e| fail(format!("invalid volume: {e}")))?;
    // Steps in units of field error: a coefficient error δ moves the field by at most W·δ.
    let weight = basis_weight_bound(volume.basis);
    let scale = fixed_scale(opts, g.spacing, weight).map_err(fail)?;
    let bricks = Bricks::new(g.dims, opts.brick);
    let coverage = Coverage::new(&volume.coeffs, &bricks);
    // A decoded file keeps its layout (see `reencode`); anything else takes the band rule.
    let layout = decoded_layout(&file.header, volume, opts, &bricks, &coverage);
    let banded;
    let (kept, prefer) = match &layout {
        Some(l) => (&l.kept[..], Some(l.precision)),
        None => {
            banded = stored_band(volume, &bricks, &coverage, opts.band);
            (&banded[..], None)
        }
    };
    let stored_bits = stored_map(bricks.total(), kept);
    let Background { inside, clamp } =
        background(volume, &bricks, &coverage, &stored_bits, opts.band);
    let clamp = layout.as_ref().map_or(clamp, |l| l.clamp);

    let mut sp = SparseParams {
        brick: opts.brick,
        bricks: bricks.count,
        stored: kept.len(),
        precision: Precision::F32,
        predictor: opts.predictor,
        shuffle: opts.shuffle,
        compression: opts.compression,
        clamp,
        band: opts.band,
        fixed: None,
    };
    let stored = StoredBricks {
        volume,
        bricks: &bricks,
        kept,
        tolerance_steps: tolerance_steps(opts, weight),
    };
    let (blobs, worst) =
        encode_smallest(&stored, &mut sp, scale, opts, weight, prefer).map_err(fail)?;

    let index = brick_index(&stored_bits, &inside, &blobs);
    let mut header = file.header.clone();
    header.grid = g;
    header.basis = volume.basis;
    header.encoding = ENCODING_SPARSE.to_string();
    header.sparse = Some(sp.clone());
    let header_len = serde_json::to_vec(&header)
        .expect("header serialises")
        .len();
    let report = EncodeReport {
        bricks_total: bricks.total(),
        bricks_stored: sp.stored,
        bytes_header: streamed_framing_bytes(header_len),
        bytes_index: index.len(),
        bytes_payload: blobs.iter().map(Vec::len).sum(),
        precision: sp.precision,
        max_quantisation_error: worst,
        clamp,
    };
    Ok((
        SparsePgv {
            header,
            index,
            blobs,
        },
        report,
    ))
}

/// Writes `file` to `path` atomically in the `sparse-bricks` encoding.
pub fn write_pgv_with(
    path: &Path,
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<EncodeReport, FormatError> {
    let (encoded, report) = sparse_pgv(file, opts).map_err(|e| err(path, e.problem))?;
    pgvol_core::write_atomic(path, |w| encoded.write_to(w)).map_err(|e| err(path, e.problem))?;
    Ok(report)
}
