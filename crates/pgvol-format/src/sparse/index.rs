//! The brick maps and the index at the start of a `sparse-bricks` payload: written by the
//! encoder, parsed and checked against the header and the payload by every reader.

use std::borrow::Cow;
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
    pub(crate) data: BrickData<'a>,
    pub(crate) index_bytes: usize,
}

/// Where the brick data is: in memory, or in a file read a blob at a time.
#[derive(Clone, Copy)]
pub(crate) enum BrickData<'a> {
    Bytes(&'a [u8]),
    File {
        file: &'a std::fs::File,
        /// The data's first byte in the file.
        start: u64,
        len: u64,
    },
}

impl<'a> BrickData<'a> {
    pub(crate) fn len(&self) -> u64 {
        match self {
            BrickData::Bytes(b) => b.len() as u64,
            BrickData::File { len, .. } => *len,
        }
    }

    /// The `len` bytes from `offset` (within the data, which the layout check guarantees).
    pub(crate) fn read(&self, offset: u64, len: u32) -> std::io::Result<Cow<'a, [u8]>> {
        match self {
            BrickData::Bytes(b) => Ok(Cow::Borrowed(
                &b[offset as usize..offset as usize + len as usize],
            )),
            BrickData::File { file, start, .. } => {
                let mut blob = vec![0u8; len as usize];
                read_exact_at(file, &mut blob, start + offset)?;
                Ok(Cow::Owned(blob))
            }
        }
    }
}

/// Fills `buf` from the file's bytes at `at`, without moving a shared cursor, so threads may
/// read bricks of one file at once.
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], at: u64) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_exact_at(file, buf, at)
    }
    #[cfg(windows)]
    {
        let mut done = 0;
        while done < buf.len() {
            let n =
                std::os::windows::fs::FileExt::seek_read(file, &mut buf[done..], at + done as u64)?;
            if n == 0 {
                return Err(std::io::ErrorKind::UnexpectedEof.into());
            }
            done += n;
        }
        Ok(())
    }
}

pub(crate) fn bit(map: &[u8], b: usize) -> bool {
    map[b / 8] >> (b % 8) & 1 == 1
}

/// Checks the sparse parameters against the grid and the payload, and reads the index: from
/// the start of `payload` (version 1), or from `index` with `payload` the brick data alone
/// (version 2, which writes the index after the data).
pub(crate) fn layout<'a>(
    header: &PgvHeader,
    index: Option<&'a [u8]>,
    payload: &'a [u8],
    path: &Path,
) -> Result<Layout<'a>, FormatError> {
    layout_of(header, index, BrickData::Bytes(payload), path)
}

/// [`layout`] of a version 2 file whose brick data stays in the file: `index` is read, the
/// blobs are read as they are asked for.
pub(crate) fn layout_in_file<'a>(
    header: &PgvHeader,
    index: &'a [u8],
    data: BrickData<'a>,
    path: &Path,
) -> Result<Layout<'a>, FormatError> {
    layout_of(header, Some(index), data, path)
}

fn layout_of<'a>(
    header: &PgvHeader,
    index: Option<&'a [u8]>,
    payload: BrickData<'a>,
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
            match sp.fixed {
                Some(f) => format!(
                    "the fixed scale (step {}, knee {}, ratio {}) with precision '{}': 'fixed' \
                     needs a step finite and above 0, a knee below 2^31 and a ratio from 1 to \
                     65536, and the other precisions no scale",
                    f.step,
                    f.knee,
                    f.ratio,
                    sp.precision.name()
                ),
                None => "precision 'fixed' without its fixed scale".to_string(),
            },
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
    let (index, data) = match index {
        None => {
            let BrickData::Bytes(payload) = payload else {
                return Err(err(path, "a version 1 payload is read from memory"));
            };
            if meta + 4 > payload.len() as u64 {
                return Err(err(
                    path,
                    format!(
                        "truncated payload: the brick maps and index need {} bytes, the payload \
                         has {}",
                        meta + 4,
                        payload.len()
                    ),
                ));
            }
            let (index, data) = payload.split_at(meta as usize + 4);
            (index, BrickData::Bytes(data))
        }
        Some(index) => {
            if meta + 4 != index.len() as u64 {
                return Err(err(
                    path,
                    format!(
                        "the brick maps and index of {} stored bricks take {} bytes, the file \
                         gives them {}",
                        sp.stored,
                        meta + 4,
                        index.len()
                    ),
                ));
            }
            (index, payload)
        }
    };
    let meta = meta as usize;
    let icrc = u32::from_le_bytes(index[meta..meta + 4].try_into().expect("4 bytes"));
    if !crc_ok(icrc, crc32fast::hash(&index[..meta])) {
        return Err(err(
            path,
            "brick index checksum mismatch: the file is corrupt",
        ));
    }
    let (stored, inside) = (&index[..map], &index[map..2 * map]);
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
    let mut entries = Vec::with_capacity(sp.stored);
    let mut next = 0u64;
    for e in index[2 * map..meta].chunks_exact(ENTRY) {
        let offset = u64::from_le_bytes(e[0..8].try_into().expect("8 bytes"));
        let len = u32::from_le_bytes(e[8..12].try_into().expect("4 bytes"));
        let crc = u32::from_le_bytes(e[12..16].try_into().expect("4 bytes"));
        if offset != next || offset + len as u64 > data.len() {
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
    if next != data.len() {
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

/// The brick maps and the index of a payload, built as the stored bricks' blobs are written
/// in brick order: the same bytes whether the blobs come all at once or a slab at a time.
pub(crate) struct IndexBuilder {
    /// Bit per file brick: stored.
    pub(crate) stored: Vec<u8>,
    /// Bit per file brick: unstored and inside.
    pub(crate) inside: Vec<u8>,
    entries: Vec<u8>,
    offset: u64,
}

impl IndexBuilder {
    /// Maps of `total` file bricks, none stored yet.
    pub(crate) fn new(total: usize) -> IndexBuilder {
        IndexBuilder {
            stored: vec![0; total.div_ceil(8)],
            inside: vec![0; total.div_ceil(8)],
            entries: Vec::new(),
            offset: 0,
        }
    }

    /// Records the next stored brick's blob (blobs come in brick order).
    pub(crate) fn push(&mut self, blob: &[u8]) {
        self.entries.extend_from_slice(&self.offset.to_le_bytes());
        self.entries
            .extend_from_slice(&(blob.len() as u32).to_le_bytes());
        self.entries
            .extend_from_slice(&crc32fast::hash(blob).to_le_bytes());
        self.offset += blob.len() as u64;
    }

    /// Bytes of brick data recorded so far.
    pub(crate) fn data_bytes(&self) -> u64 {
        self.offset
    }

    /// The maps, the entries and their CRC, as the payload holds them.
    pub(crate) fn finish(self) -> Vec<u8> {
        let mut meta = self.stored;
        meta.extend_from_slice(&self.inside);
        meta.extend_from_slice(&self.entries);
        let icrc = crc32fast::hash(&meta);
        meta.extend_from_slice(&icrc.to_le_bytes());
        meta
    }
}

/// The brick maps (`stored`, and `inside` for the others, as the payload holds them), the index
/// of `blobs` (the stored bricks in brick order) and its CRC.
pub(crate) fn brick_index(stored: &[u8], inside: &[u8], blobs: &[Vec<u8>]) -> Vec<u8> {
    let mut index = IndexBuilder {
        stored: stored.to_vec(),
        inside: inside.to_vec(),
        entries: Vec::with_capacity(ENTRY * blobs.len()),
        offset: 0,
    };
    for blob in blobs {
        index.push(blob);
    }
    index.finish()
}
