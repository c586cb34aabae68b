//! STL, ASCII and binary. Every facet gets its own three vertices, as in the file; welding is
//! left to [`crate::read_clean`] so that `read` stays a faithful image of the file.

use std::io::{self, Write};
use std::path::Path;

use glam::{DVec3, Vec3};

use crate::chunks::write_records;
use crate::{face_normal, Mesh, MeshError};

const HEADER: usize = 80;
const PREAMBLE: usize = HEADER + 4;
const FACET: usize = 50;

pub(crate) fn read(bytes: &[u8], name: &Path) -> Result<Mesh, MeshError> {
    let declared = (bytes.len() >= PREAMBLE)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let expected_len = declared.map(|n| PREAMBLE as u64 + FACET as u64 * n);
    // The size test comes first: binary files often start with "solid" too.
    if expected_len == Some(bytes.len() as u64) {
        return read_binary(bytes, name);
    }
    if looks_ascii(bytes) {
        let ascii = read_ascii(bytes, name);
        // A binary file whose header happens to read as text: the binary checks below report
        // on it if its size could be binary.
        let fits_binary = expected_len.is_some_and(|e| e <= bytes.len() as u64);
        match ascii {
            Ok(m) if !m.triangles.is_empty() || !fits_binary => return Ok(m),
            Err(e) if !fits_binary => return Err(e),
            _ => {}
        }
    }
    let (Some(n), Some(expected)) = (declared, expected_len) else {
        return Err(MeshError::new(
            name,
            format!(
                "not an STL file: {} bytes is too short for binary STL (at least 84) and the \
                 text does not start with 'solid'",
                bytes.len()
            ),
        ));
    };
    if expected > bytes.len() as u64 && is_text(bytes) {
        // A binary count read from text is meaningless: say what the file does look like.
        return Err(MeshError::new(
            name,
            format!(
                "not an STL file: it is text, but ASCII STL starts with 'solid' and this starts \
                 with '{}'; as binary STL its size ({} bytes) does not match",
                String::from_utf8_lossy(&bytes[..bytes.len().min(12)])
                    .lines()
                    .next()
                    .unwrap_or("")
                    .trim(),
                bytes.len()
            ),
        ));
    }
    if expected > bytes.len() as u64 {
        let holds = (bytes.len() - PREAMBLE) / FACET;
        return Err(MeshError::new(
            name,
            format!("truncated binary STL: header says {n} triangles, file holds {holds}"),
        ));
    }
    // Bytes after the declared facets: the count or the file is wrong, so what the facets
    // would give is not known to be the whole mesh.
    let extra = bytes.len() as u64 - expected;
    Err(MeshError::new(
        name,
        format!(
            "binary STL with {extra} bytes after its last facet: the header says {n} \
             triangles, which take {expected} bytes, but the file has {}; a binary STL file \
             is exactly 84 + 50 × (triangle count) bytes",
            bytes.len()
        ),
    ))
}

/// Whether the beginning of `bytes` is text: no control characters but whitespace.
fn is_text(bytes: &[u8]) -> bool {
    bytes[..bytes.len().min(512)]
        .iter()
        .all(|&b| !b.is_ascii_control() || b.is_ascii_whitespace())
}

/// ASCII if it starts with "solid" and the beginning has no control characters (binary headers
/// that start with "solid" are usually followed by NULs or other control bytes). Bytes above
/// 0x7F are allowed for UTF-8 solid names.
fn looks_ascii(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let text = &bytes[start..];
    let probe = &text[..text.len().min(512)];
    text.len() >= 5 && text[..5].eq_ignore_ascii_case(b"solid") && is_text(probe)
}

fn read_binary(bytes: &[u8], name: &Path) -> Result<Mesh, MeshError> {
    let body = &bytes[PREAMBLE..];
    let n = body.len() / FACET;
    if u32::try_from(3 * n as u64).is_err() {
        return Err(MeshError::new(name, "more than 2^32 vertices"));
    }
    let mut positions = Vec::with_capacity(3 * n);
    for facet in body.chunks_exact(FACET) {
        // Skip the stored normal (bytes 0..12); it is recomputed from the corners when needed.
        for k in 0..3 {
            let o = 12 + 12 * k;
            let f = |i: usize| {
                let s = o + 4 * i;
                f32::from_le_bytes([facet[s], facet[s + 1], facet[s + 2], facet[s + 3]])
            };
            positions.push(Vec3::new(f(0), f(1), f(2)).as_dvec3());
        }
    }
    let triangles = (0..n as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    Ok(Mesh::from_world(&positions, triangles))
}

fn read_ascii(bytes: &[u8], name: &Path) -> Result<Mesh, MeshError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| MeshError::new(name, format!("ASCII STL is not valid text: {e}")))?;
    // World positions in f64 (text keeps what f32 would round away far from the origin).
    let mut mesh = (Vec::<DVec3>::new(), Vec::<[u32; 3]>::new());
    let mut loop_start: Option<usize> = None;
    let mut facets = 0usize;
    for (line_no, line) in text.lines().enumerate() {
        let line_no = line_no + 1;
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword.to_ascii_lowercase().as_str() {
            "vertex" => {
                let mut xyz = [0f64; 3];
                for c in &mut xyz {
                    let word = words.next().ok_or_else(|| {
                        MeshError::new(name, format!("line {line_no}: vertex needs 3 numbers"))
                    })?;
                    *c = word.parse().map_err(|_| {
                        MeshError::new(name, format!("line {line_no}: '{word}' is not a number"))
                    })?;
                }
                if loop_start.is_none() {
                    // Tolerate a missing "outer loop" line: the vertex starts a loop.
                    loop_start = Some(mesh.0.len());
                }
                mesh.0.push(DVec3::from_array(xyz));
            }
            "outer" => loop_start = Some(mesh.0.len()),
            "endloop" | "endfacet" => {
                let Some(start) = loop_start.take() else {
                    continue;
                };
                let count = mesh.0.len() - start;
                if count < 3 {
                    return Err(MeshError::new(
                        name,
                        format!("line {line_no}: facet {facets} has only {count} vertices"),
                    ));
                }
                facets += 1;
                // Polygon loops (rare) are fanned from their first corner.
                let base = index(start, name)?;
                for k in 1..count - 1 {
                    let k = index(k, name)?;
                    mesh.1.push([base, base + k, base + k + 1]);
                }
            }
            _ => {}
        }
    }
    if loop_start.is_some_and(|s| mesh.0.len() > s) {
        return Err(MeshError::new(
            name,
            "ASCII STL ends in the middle of a facet (missing 'endloop')",
        ));
    }
    Ok(Mesh::from_world(&mesh.0, mesh.1))
}

fn index(i: usize, name: &Path) -> Result<u32, MeshError> {
    u32::try_from(i).map_err(|_| MeshError::new(name, "more than 2^32 vertices"))
}

/// Binary STL with facet normals. The header must not start with "solid", or some readers
/// would take the file for ASCII.
pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let count = u32::try_from(mesh.triangles.len())
        .map_err(|_| io::Error::other("more than 2^32 triangles do not fit binary STL"))?;
    let mut header = [b' '; HEADER];
    let label = b"pgvol binary STL";
    header[..label.len()].copy_from_slice(label);
    w.write_all(&header)?;
    w.write_all(&count.to_le_bytes())?;
    write_records(w, mesh.triangles.len(), |range, out| {
        for t in range {
            let tri = mesh.triangle(t);
            // Degenerate facets get the zero normal, which STL readers take as "compute it".
            let n = face_normal(tri);
            for v in [n, tri[0], tri[1], tri[2]] {
                for c in v.to_array() {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            // The attribute byte count.
            out.extend_from_slice(&[0, 0]);
        }
    })?;
    Ok(())
}
