//! The `.pgv` container: the framing of a header and a payload, each with its CRC, written and
//! checked.
//!
//! Version 1 (all integers little-endian):
//! ```text
//! magic    8 bytes  "PGVOL\0\r\n" (the CR/LF catch text-mode mangling)
//! version  u32      1
//! hlen     u32      length of the header, at most 1 MiB
//! header   hlen     UTF-8 JSON (PgvHeader)
//! hcrc     u32      CRC-32 of the header bytes
//! plen     u64      payload length
//! payload  plen     the coefficients as described by header.encoding
//! pcrc     u32      CRC-32 of the payload
//! ```
//! Version 2 (`sparse-bricks` only) puts everything whose size is known only at the end after
//! the bricks, so a writer can stream them:
//! ```text
//! magic    8 bytes  as above
//! version  u32      2
//! data     dlen     the stored bricks' blobs
//! index    ilen     the brick maps, the index and its CRC
//! header   hlen     UTF-8 JSON
//! dlen     u64
//! ilen     u64
//! hlen     u32      at most 1 MiB
//! hcrc     u32      CRC-32 of the header bytes
//! magic    8 bytes  again, so a truncated file is told apart from a damaged one
//! ```
//! Every size is checked against the file and the grid before anything is allocated from it.

use std::path::Path;

use glam::Vec3;

/// The largest frame offset a header may declare: the coordinate range meshes are accepted in.
pub(crate) const MAX_OFFSET: f64 = 1e8;
/// Largest magnitude of a grid corner's coordinates in its local frame: ten times the largest
/// mesh coordinate the readers accept.
const MAX_GRID_COORDINATE: f32 = 1e9;
/// Least grid spacing relative to the grid's largest coordinate: 16 steps of single precision
/// per spacing.
const MIN_RELATIVE_SPACING: f32 = 1.0 / (1 << 19) as f32;

use crate::error::{err, FormatError};
use crate::header::{PgvHeader, ENCODING_DENSE_F32, ENCODING_PERTURBATION};
use crate::sparse_params::ENCODING_SPARSE;

pub const MAGIC: &[u8; 8] = b"PGVOL\0\r\n";
/// The version of the layout with the header first (every encoding).
pub const VERSION: u32 = 1;
/// The version of the layout with the header and the index last (`sparse-bricks`).
pub const VERSION_STREAMED: u32 = 2;
/// Bytes after the header of a version 2 file: dlen, ilen, hlen, hcrc and the magic.
pub(crate) const TRAILER: usize = 8 + 8 + 4 + 4 + 8;
const MAX_HEADER: usize = 1 << 20;

/// Frames a header and a payload: magic, version, header with its CRC, payload with its CRC.
pub(crate) fn container(header: &PgvHeader, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + payload.len() + 1024);
    write_container(&mut out, header, &[payload]).expect("writing to memory does not fail");
    out
}

/// Bytes of the version 2 container around a header of `header_len` bytes, without the brick
/// data and the index.
pub(crate) const fn streamed_framing_bytes(header_len: usize) -> usize {
    MAGIC.len() + 4 + header_len + TRAILER
}

/// The start of a version 2 file, before its brick data.
pub(crate) fn write_streamed_start(w: &mut dyn std::io::Write) -> std::io::Result<()> {
    w.write_all(MAGIC)?;
    w.write_all(&VERSION_STREAMED.to_le_bytes())
}

/// The end of a version 2 file after `data_len` bytes of brick data: the index, the header and
/// the trailer.
pub(crate) fn write_streamed_end(
    w: &mut dyn std::io::Write,
    data_len: u64,
    index: &[u8],
    header: &PgvHeader,
) -> std::io::Result<()> {
    let header = serde_json::to_vec(header).expect("header serialises");
    w.write_all(index)?;
    w.write_all(&header)?;
    w.write_all(&data_len.to_le_bytes())?;
    w.write_all(&(index.len() as u64).to_le_bytes())?;
    w.write_all(&(header.len() as u32).to_le_bytes())?;
    w.write_all(&crc32fast::hash(&header).to_le_bytes())?;
    w.write_all(MAGIC)
}

/// Writes the container of `header` and the payload made of `parts` back to back, so a
/// payload held in pieces (an index and the bricks' blobs) is written without being copied
/// into one buffer.
pub(crate) fn write_container(
    w: &mut dyn std::io::Write,
    header: &PgvHeader,
    parts: &[&[u8]],
) -> std::io::Result<()> {
    let header = serde_json::to_vec(header).expect("header serialises");
    w.write_all(MAGIC)?;
    w.write_all(&VERSION.to_le_bytes())?;
    w.write_all(&(header.len() as u32).to_le_bytes())?;
    w.write_all(&header)?;
    w.write_all(&crc32fast::hash(&header).to_le_bytes())?;
    let len: u64 = parts.iter().map(|p| p.len() as u64).sum();
    w.write_all(&len.to_le_bytes())?;
    let mut crc = crc32fast::Hasher::new();
    for part in parts {
        crc.update(part);
        w.write_all(part)?;
    }
    w.write_all(&crc.finalize().to_le_bytes())
}

/// Whether a stored CRC-32 matches the computed one. Fuzz builds (`--cfg fuzzing`, set by
/// cargo-fuzz) accept every checksum, so that mutated inputs reach the parsing behind the checks
/// rather than stopping at them; every other build compares.
pub(crate) fn crc_ok(stored: u32, computed: u32) -> bool {
    cfg!(fuzzing) || stored == computed
}

/// A cursor that refuses to read past the end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str, path: &Path) -> Result<&'a [u8], FormatError> {
        let left = self.bytes.len() - self.at;
        if n > left {
            return Err(err(
                path,
                format!("truncated file: {what} needs {n} bytes, {left} left"),
            ));
        }
        let s = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }

    fn u32(&mut self, what: &str, path: &Path) -> Result<u32, FormatError> {
        Ok(u32::from_le_bytes(
            self.take(4, what, path)?.try_into().expect("4 bytes"),
        ))
    }

    fn u64(&mut self, what: &str, path: &Path) -> Result<u64, FormatError> {
        Ok(u64::from_le_bytes(
            self.take(8, what, path)?.try_into().expect("8 bytes"),
        ))
    }
}

/// A checked container: the header and the payload.
pub(crate) struct Container<'a> {
    pub header: PgvHeader,
    /// Version 1: the whole payload. Version 2: the brick data.
    pub payload: &'a [u8],
    /// Version 2: the brick maps and index, which follow the data.
    pub index: Option<&'a [u8]>,
    /// The stored CRC-32 of a version 1 payload (version 2 has a CRC per brick and one for
    /// the index instead).
    pub payload_crc: Option<u32>,
}

impl Container<'_> {
    /// The file's format version.
    pub(crate) fn version(&self) -> u32 {
        if self.index.is_some() {
            VERSION_STREAMED
        } else {
            VERSION
        }
    }

    /// Hashes a version 1 payload and compares it with its stored CRC.
    pub(crate) fn check_payload(&self, path: &Path) -> Result<(), FormatError> {
        let Some(stored) = self.payload_crc else {
            return Ok(());
        };
        if !crc_ok(stored, crc32fast::hash(self.payload)) {
            return Err(err(
                path,
                "coefficient checksum mismatch: the file is corrupt",
            ));
        }
        Ok(())
    }
}

/// Parses and checks everything but the payload's contents. The payload CRC is verified only
/// when `check_payload` is set, so single bricks can be read without hashing the whole payload.
pub(crate) fn parse_container<'a>(
    bytes: &'a [u8],
    path: &Path,
    check_payload: bool,
) -> Result<Container<'a>, FormatError> {
    let mut r = Reader { bytes, at: 0 };
    if bytes.is_empty() {
        return Err(err(path, "empty file"));
    }
    let magic = r.take(MAGIC.len(), "the magic number", path)?;
    if magic != MAGIC {
        return Err(err(path, "not a .pgv file (wrong magic number)"));
    }
    let version = r.u32("the version", path)?;
    let c = match version {
        VERSION => parse_v1(r, path)?,
        VERSION_STREAMED => parse_v2(bytes, path)?,
        _ => {
            return Err(err(
                path,
                format!(
                    "format version {version} is not supported (this reader knows versions \
                     {VERSION} and {VERSION_STREAMED})"
                ),
            ))
        }
    };
    if check_payload {
        c.check_payload(path)?;
    }
    Ok(c)
}

/// The rest of a version 1 file after its version.
fn parse_v1<'a>(mut r: Reader<'a>, path: &Path) -> Result<Container<'a>, FormatError> {
    let hlen = r.u32("the header length", path)? as usize;
    check_header_len(hlen, path)?;
    let header_bytes = r.take(hlen, "the header", path)?;
    let hcrc = r.u32("the header checksum", path)?;
    let (header, nodes) = checked_header(header_bytes, hcrc, path)?;
    let plen = r.u64("the payload length", path)?;
    if header.encoding == ENCODING_DENSE_F32 && plen != nodes * 4 {
        return Err(err(
            path,
            format!(
                "payload holds {plen} bytes but a {:?} grid of f32 needs {}",
                header.grid.dims,
                nodes * 4
            ),
        ));
    }
    let left = (r.bytes.len() - r.at) as u64;
    if plen > left {
        return Err(err(
            path,
            format!("truncated file: the payload needs {plen} bytes, {left} left"),
        ));
    }
    let payload = r.take(plen as usize, "the payload", path)?;
    let payload_crc = r.u32("the payload checksum", path)?;
    if r.at != r.bytes.len() {
        return Err(err(
            path,
            format!(
                "{} unexpected bytes after the end of the data",
                r.bytes.len() - r.at
            ),
        ));
    }
    Ok(Container {
        header,
        payload,
        index: None,
        payload_crc: Some(payload_crc),
    })
}

/// A version 2 file, read from its trailer back.
fn parse_v2<'a>(bytes: &'a [u8], path: &Path) -> Result<Container<'a>, FormatError> {
    let start = MAGIC.len() + 4;
    let len = bytes.len() as u64;
    let trailer = &bytes[bytes.len().saturating_sub(TRAILER)..];
    let sizes = v2_sizes(len, trailer, path)?;
    let (dlen, ilen) = (sizes.dlen as usize, sizes.ilen as usize);
    let header_at = start + dlen + ilen;
    let header = v2_header(&bytes[header_at..header_at + sizes.hlen], sizes.hcrc, path)?;
    Ok(Container {
        header,
        payload: &bytes[start..start + dlen],
        index: Some(&bytes[start + dlen..header_at]),
        payload_crc: None,
    })
}

/// The section sizes a version 2 file's trailer gives.
pub(crate) struct V2Sizes {
    pub(crate) dlen: u64,
    pub(crate) ilen: u64,
    pub(crate) hlen: usize,
    pub(crate) hcrc: u32,
}

/// The sizes in `trailer`, the last [`TRAILER`] bytes of a version 2 file of `len` bytes (fewer
/// when the file is shorter), checked to add up to the file.
pub(crate) fn v2_sizes(len: u64, trailer: &[u8], path: &Path) -> Result<V2Sizes, FormatError> {
    let start = (MAGIC.len() + 4) as u64;
    if len < start + TRAILER as u64 || trailer.len() != TRAILER || &trailer[TRAILER - 8..] != MAGIC
    {
        return Err(err(
            path,
            "truncated file: a version 2 .pgv ends with its index, header and the magic number \
             again, and this one does not (an interrupted copy or write?)",
        ));
    }
    let t = trailer;
    let dlen = u64::from_le_bytes(t[0..8].try_into().expect("8 bytes"));
    let ilen = u64::from_le_bytes(t[8..16].try_into().expect("8 bytes"));
    let hlen = u32::from_le_bytes(t[16..20].try_into().expect("4 bytes")) as usize;
    let hcrc = u32::from_le_bytes(t[20..24].try_into().expect("4 bytes"));
    check_header_len(hlen, path)?;
    let sized = start
        .checked_add(dlen)
        .and_then(|n| n.checked_add(ilen))
        .and_then(|n| n.checked_add((hlen + TRAILER) as u64));
    if sized != Some(len) {
        return Err(err(
            path,
            format!(
                "the trailer gives {dlen} bytes of bricks, {ilen} of index and {hlen} of header, \
                 which do not add up to the file's {len} bytes"
            ),
        ));
    }
    Ok(V2Sizes {
        dlen,
        ilen,
        hlen,
        hcrc,
    })
}

/// A version 2 file's header, checked against its CRC and holding the one encoding the
/// version allows.
pub(crate) fn v2_header(
    header_bytes: &[u8],
    hcrc: u32,
    path: &Path,
) -> Result<PgvHeader, FormatError> {
    let (header, _) = checked_header(header_bytes, hcrc, path)?;
    if header.encoding != ENCODING_SPARSE {
        return Err(err(
            path,
            format!(
                "a version 2 file holds the '{ENCODING_SPARSE}' encoding, not '{}'",
                header.encoding
            ),
        ));
    }
    Ok(header)
}

fn check_header_len(hlen: usize, path: &Path) -> Result<(), FormatError> {
    if hlen > MAX_HEADER {
        return Err(err(
            path,
            format!("header length {hlen} exceeds the limit of {MAX_HEADER} bytes"),
        ));
    }
    Ok(())
}

/// The header of `header_bytes` checked against its CRC `hcrc`, and its grid's node count.
fn checked_header(
    header_bytes: &[u8],
    hcrc: u32,
    path: &Path,
) -> Result<(PgvHeader, u64), FormatError> {
    if !crc_ok(hcrc, crc32fast::hash(header_bytes)) {
        return Err(err(path, "header checksum mismatch: the file is corrupt"));
    }
    let header: PgvHeader = serde_json::from_slice(header_bytes)
        .map_err(|e| err(path, format!("header is not valid: {e}")))?;
    if ![ENCODING_DENSE_F32, ENCODING_SPARSE, ENCODING_PERTURBATION]
        .contains(&header.encoding.as_str())
    {
        return Err(err(
            path,
            format!("unknown coefficient encoding '{}'", header.encoding),
        ));
    }
    header
        .basis
        .validate()
        .map_err(|e| err(path, format!("invalid basis: {e}")))?;
    let g = header.grid;
    if !(g.origin.is_finite() && g.spacing.is_finite() && g.spacing > 0.0) {
        return Err(err(
            path,
            "grid origin or spacing is not a finite positive number",
        ));
    }
    if !(g.offset.is_finite() && g.offset.abs().max_element() < MAX_OFFSET) {
        return Err(err(
            path,
            format!(
                "grid offset {} is not finite or beyond {MAX_OFFSET:e} in magnitude",
                g.offset
            ),
        ));
    }
    if g.dims.iter().any(|&n| n < 2) {
        return Err(err(
            path,
            format!(
                "grid dimensions {:?}: every axis needs at least 2 nodes",
                g.dims
            ),
        ));
    }
    let nodes = g
        .dims
        .iter()
        .try_fold(1u64, |acc, &n| acc.checked_mul(n as u64));
    let nodes = match nodes {
        Some(n) if n as u128 <= pgvol_field::MAX_GRID_NODES => n,
        _ => {
            return Err(err(
                path,
                format!("grid dimensions {:?} are too large", g.dims),
            ))
        }
    };
    // Corners far beyond any mesh the readers accept, or nodes too close for single precision
    // to tell apart, make positions that no stage can index.
    let far = g
        .origin
        .abs()
        .max((g.origin + g.spacing * Vec3::from_array(g.dims.map(|n| (n - 1) as f32))).abs());
    if !(far.is_finite() && far.max_element() <= MAX_GRID_COORDINATE) {
        return Err(err(
            path,
            format!(
                "grid of spacing {:e} from origin {} reaches beyond {MAX_GRID_COORDINATE:e} in \
                 magnitude",
                g.spacing, g.origin
            ),
        ));
    }
    if g.spacing < far.max_element() * MIN_RELATIVE_SPACING {
        return Err(err(
            path,
            format!(
                "grid spacing {:e} is too small for single precision at coordinates up to {:e} \
                 (at least {:e} of them)",
                g.spacing,
                far.max_element(),
                MIN_RELATIVE_SPACING
            ),
        ));
    }
    Ok((header, nodes))
}
