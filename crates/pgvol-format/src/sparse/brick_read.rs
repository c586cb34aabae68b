//! Reading one stored brick: its blob checked against its CRC, decompressed into a buffer sized
//! from the brick, and decoded; and the value of an unstored brick.

use std::borrow::Cow;
use std::cell::RefCell;
use std::path::Path;

use rayon::prelude::*;
use zstd::bulk::Decompressor;

use super::brick_decoder::{decode_values, decode_words16, raw_len, WordScratch};
use super::index::{bit, Layout};
use crate::container::crc_ok;
use crate::error::{err, FormatError};
use crate::sparse_params::Compression;

thread_local! {
    /// One zstd context per thread, created on first use and kept from brick to brick and file
    /// to file: creating one costs more than decompressing a brick.
    static DCTX: RefCell<Option<Decompressor<'static>>> = const { RefCell::new(None) };
}

/// Buffers for decoding bricks, reused from brick to brick.
#[derive(Default)]
pub(crate) struct BrickReader {
    raw: Vec<u8>,
    scratch: WordScratch,
}

impl BrickReader {
    /// Verifies and decodes stored brick `b` (index entry `e`) into `out`, one value per node.
    pub(crate) fn decode(
        &mut self,
        l: &Layout,
        b: usize,
        e: usize,
        path: &Path,
        out: &mut [f32],
    ) -> Result<(), FormatError> {
        let blob = checked_blob(l, b, e, path)?;
        let BrickReader { raw, scratch } = self;
        // Nothing in here runs other rayon tasks, so the borrow cannot be taken twice.
        DCTX.with_borrow_mut(|dctx| {
            let raw = inflate(l, b, &blob, dctx, raw, path)?;
            let (_, n) = l.bricks.extent(b);
            decode_values(raw, n, &l.sp, scratch, out).map_err(|_| non_finite(l, b, path))
        })
    }
}

impl BrickReader {
    /// Verifies and decodes stored brick `b` (index entry `e`) into its 16-bit words
    /// (`brick_decoder::decode_words16`); `Ok(false)` where the brick's words do not fit.
    pub(crate) fn decode_words16(
        &mut self,
        l: &Layout,
        b: usize,
        e: usize,
        path: &Path,
        out: &mut [i16],
    ) -> Result<bool, FormatError> {
        let blob = checked_blob(l, b, e, path)?;
        let BrickReader { raw, scratch } = self;
        DCTX.with_borrow_mut(|dctx| {
            let raw = inflate(l, b, &blob, dctx, raw, path)?;
            let (_, n) = l.bricks.extent(b);
            Ok(decode_words16(raw, n, &l.sp, scratch, out))
        })
    }
}

/// The error for a brick holding an infinite or NaN coefficient.
pub(crate) fn non_finite(l: &Layout, b: usize, path: &Path) -> FormatError {
    err(
        path,
        format!(
            "brick {:?} decodes to a non-finite coefficient",
            l.bricks.coords(b)
        ),
    )
}

/// The blob of stored brick `b` (index entry `e`), after checking its CRC.
pub(crate) fn checked_blob<'a>(
    l: &Layout<'a>,
    b: usize,
    e: usize,
    path: &Path,
) -> Result<Cow<'a, [u8]>, FormatError> {
    let (offset, len, crc) = l.entries[e];
    // The layout check put every entry inside the data.
    let blob = l.data.read(offset, len).map_err(|e| {
        err(
            path,
            format!("cannot read brick {:?}: {e}", l.bricks.coords(b)),
        )
    })?;
    if !crc_ok(crc, crc32fast::hash(&blob)) {
        return Err(err(
            path,
            format!(
                "brick {:?} checksum mismatch: the file is corrupt",
                l.bricks.coords(b)
            ),
        ));
    }
    Ok(blob)
}

/// The brick's bytes before compression: the blob itself, or its zstd frame decompressed into
/// `buf` sized from the brick's node count (never from a number read in the file).
pub(crate) fn inflate<'a>(
    l: &Layout,
    b: usize,
    blob: &'a [u8],
    dctx: &mut Option<Decompressor<'static>>,
    buf: &'a mut Vec<u8>,
    path: &Path,
) -> Result<&'a [u8], FormatError> {
    let coords = l.bricks.coords(b);
    let (_, n) = l.bricks.extent(b);
    let want = raw_len(n, &l.sp);
    let raw = match l.sp.compression {
        Compression::None => blob,
        Compression::Zstd => {
            if dctx.is_none() {
                *dctx = Some(
                    Decompressor::new()
                        .map_err(|e| err(path, format!("cannot start zstd decompression: {e}")))?,
                );
            }
            let dctx = dctx.as_mut().expect("created above");
            buf.resize(want, 0);
            // Fails if the output would be larger than the brick.
            let got = dctx.decompress_to_buffer(blob, &mut buf[..]).map_err(|e| {
                err(
                    path,
                    format!("brick {coords:?} does not decompress to {want} bytes: {e}"),
                )
            })?;
            &buf[..got]
        }
    };
    if raw.len() != want {
        return Err(err(
            path,
            format!(
                "brick {coords:?} holds {} bytes, a brick of {n:?} nodes needs {want}",
                raw.len()
            ),
        ));
    }
    Ok(raw)
}

/// The value of every node of background brick `b`.
pub(crate) fn background(l: &Layout, b: usize) -> f32 {
    if bit(l.inside, b) {
        -l.sp.clamp
    } else {
        l.sp.clamp
    }
}

/// Checks every stored brick's CRC: what a version 1 payload's own CRC checks at once, for a
/// version 2 file, whose bricks carry only theirs.
pub(crate) fn check_all_bricks(l: &Layout, path: &Path) -> Result<(), FormatError> {
    let stored: Vec<usize> = (0..l.bricks.total())
        .filter(|&b| bit(l.stored, b))
        .collect();
    stored
        .par_iter()
        .enumerate()
        .try_for_each(|(e, &b)| checked_blob(l, b, e, path).map(|_| ()))
}
