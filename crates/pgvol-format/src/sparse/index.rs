//! The brick maps and the index at the start of a `sparse-bricks` payload: written by the
//! encoder, parsed and checked against the header and the payload by every reader.

use std::path::Path;

use super::bricks::Bricks;
use crate::container::crc_ok;
use crate::error::{err, FormatError};
use crate::header::PgvHeader;
use crate::sparse_params::{Precision, SparseParams, BRICK_RANGE};

/// Bytes of one index entry: offset u64, length u32, CRC-32 u32.
const ENTRY: usize = 16;

/// A checked sparse payload: its parameters, bitmaps and index, and where the data starts.
pub(crate) struct Layout<'a> {
    pub(crate) sp: SparseParams,
    pub(crate) bricks: Bricks,
    pub(crate) stored: &'a [u8],
    pub(crate) inside: &'a [u8],
    /// (offset, length, crc) per stored brick, in brick order.
    pub(crate) entries: Vec<(u64, u32, u32)>,
    pub(crate) data: &'a [u8],
    pub(crate) index_bytes: usize,
}

pub(crate) fn bit(map: &[u8], b: usize) -> bool {
    map[b / 8] >> (b % 8) & 1 == 1
}

/// Checks the sparse parameters against the grid and the payload, and reads the index.
pub(crate) fn layout<'a>(
    header: &PgvHeader,
    payload: &'a [u8],
    path: &Path,
) -> Result<Layout<'a>, FormatError> {
    let Some(sp) = header.sparse.clone() else {
        return Err(err(
            path,
            "the header has no 'sparse' parameters for the sparse-bricks encoding",
        ));
    };
    if !BRICK_RANGE.contains(&sp.brick) {
        return Err(err(
            path,
            format!("brick edge {} is outside {:?}", sp.brick, BRICK_RANGE),
        ));
    }
    let bricks = Bricks::new(header.grid.dims, sp.brick);
    if sp.bricks != bricks.count {
        return Err(err(
            path,
            format!(
                "the header counts {:?} bricks but a {:?} grid in bricks of {} has {:?}",
                sp.bricks, header.grid.dims, sp.brick, bricks.count
            ),
        ));
    }
    let nb = bricks.total();
    if sp.stored > nb {
        return Err(err(
            path,
            format!(
                "{} stored bricks claimed, but there are only {nb}",
                sp.stored
            ),
        ));
    }
    let scale_ok = match sp.fixed {
        None => sp.precision != Precision::Fixed,
        Some(f) => sp.precision == Precision::Fixed && f.is_valid(),
    };
    if !scale_ok {
        return Err(err(
            path,
            format!(
                "fixed scale {:?} with precision {}: 'fixed' needs a valid scale, others none",
                sp.fixed,
                sp.precision.name()
            ),
        ));
    }
    if !(sp.clamp.is_finite() && sp.clamp >= 0.0) {
        return Err(err(
            path,
            format!("clamp {} is not finite and >= 0", sp.clamp),
        ));
    }
    let map = nb.div_ceil(8);
    let meta = (2 * map as u64) + (sp.stored as u64) * ENTRY as u64;
    if meta + 4 > payload.len() as u64 {
        return Err(err(
            path,
            format!(
                "truncated payload: the brick maps and index need {} bytes, the payload has {}",
                meta + 4,
                payload.len()
            ),
        ));
    }
    let meta = meta as usize;
    let icrc = u32::from_le_bytes(payload[meta..meta + 4].try_into().expect("4 bytes"));
    if !crc_ok(icrc, crc32fast::hash(&payload[..meta])) {
        return Err(err(
            path,
            "brick index checksum mismatch: the file is corrupt",
        ));
    }
    let (stored, inside) = (&payload[..map], &payload[map..2 * map]);
    let set: usize = stored.iter().map(|b| b.count_ones() as usize).sum();
    let stray = (nb..map * 8).any(|b| bit(stored, b) || bit(inside, b));
    if set != sp.stored || stray {
        return Err(err(
            path,
            format!(
                "the brick map marks {set} bricks stored (or bits past the last brick), the header {}",
                sp.stored
            ),
        ));
    }
    let data = &payload[meta + 4..];
    let mut entries = Vec::with_capacity(sp.stored);
    let mut next = 0u64;
    for e in payload[2 * map..meta].chunks_exact(ENTRY) {
        let offset = u64::from_le_bytes(e[0..8].try_into().expect("8 bytes"));
        let len = u32::from_le_bytes(e[8..12].try_into().expect("4 bytes"));
        let crc = u32::from_le_bytes(e[12..16].try_into().expect("4 bytes"));
        if offset != next || offset + len as u64 > data.len() as u64 {
            return Err(err(
                path,
                format!(
                    "brick index entry {} (offset {offset}, length {len}) does not follow the \
                     previous one inside the {} bytes of brick data",
                    entries.len(),
                    data.len()
                ),
            ));
        }
        next = offset + len as u64;
        entries.push((offset, len, crc));
    }
    if next != data.len() as u64 {
        return Err(err(
            path,
            format!(
                "the index covers {next} bytes of brick data but the payload holds {}",
                data.len()
            ),
        ));
    }
    Ok(Layout {
        sp,
        bricks,
        stored,
        inside,
        entries,
        data,
        index_bytes: meta + 4,
    })
}

/// The brick maps (`stored`, and `inside` for the others, as the payload holds them), the index
/// of `blobs` (the stored bricks in brick order) and its CRC: the payload before the brick data.
pub(crate) fn brick_index(stored: &[u8], inside: &[u8], blobs: &[Vec<u8>]) -> Vec<u8> {
    let mut meta = Vec::with_capacity(stored.len() + inside.len() + ENTRY * blobs.len() + 4);
    meta.extend_from_slice(stored);
    meta.extend_from_slice(inside);
    let mut offset = 0u64;
    for blob in blobs {
        meta.extend_from_slice(&offset.to_le_bytes());
        meta.extend_from_slice(&(blob.len() as u32).to_le_bytes());
        meta.extend_from_slice(&crc32fast::hash(blob).to_le_bytes());
        offset += blob.len() as u64;
    }
    let icrc = crc32fast::hash(&meta);
    meta.extend_from_slice(&icrc.to_le_bytes());
    meta
}
