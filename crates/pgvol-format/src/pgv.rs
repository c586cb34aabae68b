//! The `.pgv` coefficient-volume file: a checked header and the coefficients.
//!
//! Layout (all integers little-endian):
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
//! Every size is checked against the file and the grid before anything is allocated from it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pgvol_field::{Basis, CoefficientVolume, Grid};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub const MAGIC: &[u8; 8] = b"PGVOL\0\r\n";
pub const VERSION: u32 = 1;
const MAX_HEADER: usize = 1 << 20;
/// The only payload encoding of version 1: every coefficient as f32, x fastest.
pub const ENCODING_DENSE_F32: &str = "dense-f32";

/// What a `.pgv` header holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PgvHeader {
    pub basis: Basis,
    /// How the coefficients were found (e.g. "interp").
    pub fit: String,
    pub grid: Grid,
    /// Units of positions and values: those of the source mesh.
    pub units: String,
    pub encoding: String,
    /// Bounding box of the source mesh, `[min, max]`.
    pub source_bounds: Option<[[f32; 3]; 2]>,
    /// 64-bit FNV-1a hash of the source mesh's positions and triangles, hex.
    pub source_hash: Option<String>,
    #[serde(default)]
    pub metadata: BTreeMap<String, String>,
    /// Parameters of the `sparse-bricks` encoding; absent for `dense-f32`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sparse: Option<crate::sparse::SparseParams>,
}

/// A decoded file.
#[derive(Clone, Debug, PartialEq)]
pub struct PgvFile {
    pub header: PgvHeader,
    pub volume: CoefficientVolume,
}

/// Why a `.pgv` file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {problem}")]
pub struct FormatError {
    pub path: PathBuf,
    pub problem: String,
}

pub(crate) fn err(path: &Path, problem: impl Into<String>) -> FormatError {
    FormatError {
        path: path.to_path_buf(),
        problem: problem.into(),
    }
}

/// Serialises `file` to bytes in the `dense-f32` encoding, whatever its header says.
pub fn encode_pgv(file: &PgvFile) -> Vec<u8> {
    let mut header = file.header.clone();
    header.encoding = ENCODING_DENSE_F32.to_string();
    header.sparse = None;
    let payload: Vec<u8> = file
        .volume
        .coeffs
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    container(&header, &payload)
}

/// Frames a header and a payload: magic, version, header with its CRC, payload with its CRC.
pub(crate) fn container(header: &PgvHeader, payload: &[u8]) -> Vec<u8> {
    let header = serde_json::to_vec(header).expect("header serialises");
    let mut out = Vec::with_capacity(32 + header.len() + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&crc32fast::hash(&header).to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(payload);
    out.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    out
}

/// Writes `file` to `path` atomically.
pub fn write_pgv(path: &Path, file: &PgvFile) -> Result<(), FormatError> {
    let bytes = encode_pgv(file);
    pgvol_core::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| err(path, e.problem))
}

/// Reads and verifies a `.pgv` file.
pub fn read_pgv(path: &Path) -> Result<PgvFile, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
    decode_pgv(&bytes, path)
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
    pub payload: &'a [u8],
    /// The stored CRC-32 of the payload.
    pub payload_crc: u32,
}

impl Container<'_> {
    /// Hashes the payload and compares it with its stored CRC.
    pub(crate) fn check_payload(&self, path: &Path) -> Result<(), FormatError> {
        if crc32fast::hash(self.payload) != self.payload_crc {
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
    if version != VERSION {
        return Err(err(
            path,
            format!(
                "format version {version} is not supported (this reader knows version {VERSION})"
            ),
        ));
    }
    let hlen = r.u32("the header length", path)? as usize;
    if hlen > MAX_HEADER {
        return Err(err(
            path,
            format!("header length {hlen} exceeds the limit of {MAX_HEADER} bytes"),
        ));
    }
    let header_bytes = r.take(hlen, "the header", path)?;
    let hcrc = r.u32("the header checksum", path)?;
    if crc32fast::hash(header_bytes) != hcrc {
        return Err(err(path, "header checksum mismatch: the file is corrupt"));
    }
    let header: PgvHeader = serde_json::from_slice(header_bytes)
        .map_err(|e| err(path, format!("header is not valid: {e}")))?;
    if header.encoding != ENCODING_DENSE_F32 && header.encoding != crate::sparse::ENCODING_SPARSE {
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
    let plen = r.u64("the payload length", path)?;
    if header.encoding == ENCODING_DENSE_F32 && plen != nodes * 4 {
        return Err(err(
            path,
            format!(
                "payload holds {plen} bytes but a {:?} grid of f32 needs {}",
                g.dims,
                nodes * 4
            ),
        ));
    }
    let left = (bytes.len() - r.at) as u64;
    if plen > left {
        return Err(err(
            path,
            format!("truncated file: the payload needs {plen} bytes, {left} left"),
        ));
    }
    let payload = r.take(plen as usize, "the payload", path)?;
    let payload_crc = r.u32("the payload checksum", path)?;
    let c = Container {
        header,
        payload,
        payload_crc,
    };
    if check_payload {
        c.check_payload(path)?;
    }
    if r.at != bytes.len() {
        return Err(err(
            path,
            format!(
                "{} unexpected bytes after the end of the data",
                bytes.len() - r.at
            ),
        ));
    }
    Ok(c)
}

/// Decodes a `.pgv` file from bytes, in either encoding; `path` names the file in errors.
pub fn decode_pgv(bytes: &[u8], path: &Path) -> Result<PgvFile, FormatError> {
    let c = parse_container(bytes, path, true)?;
    let coeffs = if c.header.encoding == ENCODING_DENSE_F32 {
        dense_coeffs(c.payload, path)?
    } else {
        crate::sparse::decode_payload(&c.header, c.payload, path)?
    };
    // Built directly rather than by `CoefficientVolume::new`, whose checks would cost one more
    // pass over every coefficient: the container check validated the basis and the grid (at
    // least 2 nodes per axis), and decoding gave one finite coefficient per node.
    debug_assert!(coeffs.len() == c.header.grid.len() && coeffs.iter().all(|v| v.is_finite()));
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
    let mut coeffs = crate::dense_alloc::zeroed(payload.len() / 4);
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

/// FNV-1a (64-bit) over a mesh's positions and indices: a cheap content fingerprint.
pub fn mesh_hash(mesh: &pgvol_core::Mesh) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for p in &mesh.positions {
        for c in p.to_array() {
            eat(&c.to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        for i in t {
            eat(&i.to_le_bytes());
        }
    }
    format!("{h:016x}")
}

/// A header for a freshly fitted volume.
pub fn header_for(
    volume: &CoefficientVolume,
    fit: &str,
    source: Option<&pgvol_core::Mesh>,
) -> PgvHeader {
    let bounds = source
        .and_then(|m| m.bounds())
        .map(|(lo, hi)| [lo.to_array(), hi.to_array()]);
    PgvHeader {
        basis: volume.basis,
        fit: fit.to_string(),
        grid: volume.grid,
        units: "source mesh units".to_string(),
        encoding: ENCODING_DENSE_F32.to_string(),
        source_bounds: bounds,
        source_hash: source.map(mesh_hash),
        metadata: BTreeMap::new(),
        sparse: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use proptest::prelude::*;

    fn sample_file() -> PgvFile {
        let grid = Grid {
            origin: Vec3::new(-1.0, 0.0, 2.0),
            spacing: 0.25,
            dims: [3, 4, 5],
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

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = decode_pgv(&bytes, Path::new("r.pgv"));
        }

        #[test]
        fn corrupted_files_never_panic(pos in 0usize..10_000, val in any::<u8>(), cut in 0usize..10_000) {
            let mut bytes = encode_pgv(&sample_file());
            let n = bytes.len();
            bytes[pos % n] = val;
            bytes.truncate(cut % (n + 1));
            let _ = decode_pgv(&bytes, Path::new("c.pgv"));
        }
    }
}
