//! Writing a `.pgv` file in the `sparse-bricks` encoding: which bricks to store, their encoding
//! at the chosen precision, the index, and the container around them.

use std::path::Path;

use pgvol_field::CoefficientVolume;

use super::brick_encoder::StoredBricks;
use super::bricks::Bricks;
use super::free_words::FreeNodes;
use super::index::brick_index;
use super::kept_bricks::{background, kept_bricks, Background};
use super::options::{EncodeOptions, EncodeReport};
use super::precision_choice::{basis_weight_bound, encode_smallest, fixed_scale};
use super::stored_band::needed_nodes;
use crate::container::container;
use crate::error::{err, FormatError};
use crate::header::PgvFile;
use crate::sparse_params::{Precision, SparseParams, BRICK_RANGE, ENCODING_SPARSE};

/// Encodes `file` in the `sparse-bricks` encoding.
pub fn encode_pgv_with(
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<(Vec<u8>, EncodeReport), FormatError> {
    let fail = |m: String| err(Path::new("<encode>"), m);
    let volume = &file.volume;
    let g = volume.grid;
    if !BRICK_RANGE.contains(&opts.brick) {
        return Err(fail(format!(
            "brick edge {} is outside {:?}",
            opts.brick, BRICK_RANGE
        )));
    }
    if !(opts.band.is_finite() && opts.band >= 0.0) {
        return Err(fail(format!("band {} must be finite and >= 0", opts.band)));
    }
    CoefficientVolume::from_sparse(g, volume.basis, volume.coeffs.clone())
        .map_err(|e| fail(format!("invalid volume: {e}")))?;
    // Steps in units of field error: a coefficient error δ moves the field by at most W·δ.
    let weight = basis_weight_bound(volume.basis);
    let scale = fixed_scale(opts, g.spacing, weight).map_err(fail)?;
    let bricks = Bricks::new(g.dims, opts.brick);
    let needed = needed_nodes(volume, opts.band);
    let keep = kept_bricks(&bricks, &needed);
    let free = FreeNodes::new(&needed, opts, weight);
    let Background { inside, clamp } = background(volume, &bricks, &keep, opts.band);

    let mut sp = SparseParams {
        brick: opts.brick,
        bricks: bricks.count,
        stored: keep.iter().filter(|&&k| k).count(),
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
        keep: &keep,
        free: &free,
    };
    let (blobs, worst) = encode_smallest(&stored, &mut sp, scale, opts, weight).map_err(fail)?;

    let meta = brick_index(&keep, &inside, &blobs);
    let bytes_index = meta.len();
    let mut payload = meta;
    for blob in &blobs {
        payload.extend_from_slice(blob);
    }
    let mut header = file.header.clone();
    header.grid = g;
    header.basis = volume.basis;
    header.encoding = ENCODING_SPARSE.to_string();
    header.sparse = Some(sp.clone());
    let bytes = container(&header, &payload);
    let report = EncodeReport {
        bricks_total: bricks.total(),
        bricks_stored: sp.stored,
        bytes_header: bytes.len() - payload.len(),
        bytes_index,
        bytes_payload: payload.len() - bytes_index,
        precision: sp.precision,
        max_quantisation_error: worst,
        clamp,
    };
    Ok((bytes, report))
}

/// Writes `file` to `path` atomically in the `sparse-bricks` encoding.
pub fn write_pgv_with(
    path: &Path,
    file: &PgvFile,
    opts: &EncodeOptions,
) -> Result<EncodeReport, FormatError> {
    let (bytes, report) = encode_pgv_with(file, opts).map_err(|e| err(path, e.problem))?;
    pgvol_core::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| err(path, e.problem))?;
    Ok(report)
}
