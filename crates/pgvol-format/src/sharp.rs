//! The optional `sharp` header section: dual-contouring vertices of the source mesh's exact
//! distance, stored in the cells next to its creases and corners, where the smooth fit rounds
//! them (`docs/format.md`, "The `sharp` section").
//!
//! A cell is named by its key `i + (nx − 1) · (j + (ny − 1) · k)` on the file's grid. The
//! section's `data` is base64 of one zstd frame holding, for `cells` = N cells in ascending key
//! order: N LEB128 varints, the first key then each key less the one before (≥ 1); then N bytes
//! of x, N of y and N of z, each the vertex's position in its cell as `q / 255` of the spacing.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{err, FormatError};

/// Bits per axis of a stored position in its cell; the only value this version writes or reads.
pub const SHARP_BITS: u8 = 8;

/// The most cells a section may hold: bounds the buffer its data decompresses into.
pub const MAX_SHARP_CELLS: u64 = 1 << 22;

/// The largest quantised coordinate.
const TOP: f32 = 255.0;

/// Longest LEB128 varint of a u64.
const MAX_VARINT: usize = 10;

/// zstd level of the data: the section is small, so the best ratio costs nothing.
const ZSTD_LEVEL: i32 = 19;

/// The section as the header holds it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SharpSection {
    /// Number of cells.
    pub cells: u64,
    /// Bits per axis of a position in its cell (8).
    pub bits: u8,
    /// Base64 of the zstd frame described in the module documentation.
    pub data: String,
}

/// Decoded cells: ascending keys and each one's position in its cell, per axis in `[0, 1]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SharpCells {
    pub keys: Vec<u64>,
    pub positions: Vec<[u8; 3]>,
}

impl SharpCells {
    /// The stored position of cell `index` in cell units, in `[0, 1]` per axis.
    pub fn position(&self, index: usize) -> [f32; 3] {
        self.positions[index].map(|q| f32::from(q) / TOP)
    }

    /// The nearest stored word of a position in cell units (clamped to the cell).
    pub fn quantise(x: [f32; 3]) -> [u8; 3] {
        x.map(|v| (v.clamp(0.0, 1.0) * TOP).round() as u8)
    }
}

/// Number of cells of a grid of `dims` nodes, `None` when it overflows.
pub fn cell_count(dims: [usize; 3]) -> Option<u64> {
    dims.iter()
        .try_fold(1u64, |acc, &n| acc.checked_mul((n as u64).checked_sub(1)?))
}

/// The section of `cells` (keys strictly ascending, at most [`MAX_SHARP_CELLS`]).
pub fn encode_sharp(cells: &SharpCells) -> SharpSection {
    assert_eq!(cells.keys.len(), cells.positions.len());
    assert!(cells.keys.windows(2).all(|w| w[0] < w[1]), "keys ascend");
    let n = cells.keys.len();
    let mut raw = Vec::with_capacity(n * 5);
    let mut last = 0;
    for &key in &cells.keys {
        put_varint(&mut raw, key - last);
        last = key;
    }
    for axis in 0..3 {
        raw.extend(cells.positions.iter().map(|p| p[axis]));
    }
    let packed = zstd::bulk::compress(&raw, ZSTD_LEVEL).expect("compressing to memory");
    SharpSection {
        cells: n as u64,
        bits: SHARP_BITS,
        data: pgvol_core::base64::encode(&packed),
    }
}

/// Decodes and checks `section` of a file whose grid has `dims` nodes: every key must name a
/// cell of that grid. The error says what is wrong, for the caller to name the file.
pub fn decode_sharp(section: &SharpSection, dims: [usize; 3]) -> Result<SharpCells, String> {
    let bad = |problem: String| {
        format!(
            "the sharp-feature section {problem}: the file is corrupt; encode the mesh again, \
             or contour by another method than dual contouring"
        )
    };
    if section.bits != SHARP_BITS {
        return Err(bad(format!(
            "stores {} bits per axis, this reader knows {SHARP_BITS}",
            section.bits
        )));
    }
    let n = section.cells;
    if n > MAX_SHARP_CELLS {
        return Err(bad(format!(
            "holds {n} cells, more than the limit of {MAX_SHARP_CELLS}"
        )));
    }
    let grid_cells = cell_count(dims).unwrap_or(u64::MAX);
    if n > grid_cells {
        return Err(bad(format!(
            "holds {n} cells, more than the grid's {grid_cells}"
        )));
    }
    let n = n as usize;
    let packed = pgvol_core::base64::decode(&section.data)
        .map_err(|e| bad(format!("is not base64: {e}")))?;
    let raw = zstd::bulk::decompress(&packed, n * (MAX_VARINT + 3))
        .map_err(|e| bad(format!("does not decompress: {e}")))?;
    let mut at = 0;
    let mut keys = Vec::with_capacity(n);
    let mut last: Option<u64> = None;
    for i in 0..n {
        let delta = take_varint(&raw, &mut at).ok_or_else(|| bad(format!("ends in key {i}")))?;
        let key = match last {
            None => delta,
            Some(_) if delta == 0 => return Err(bad(format!("repeats key {i}"))),
            Some(prev) => prev
                .checked_add(delta)
                .ok_or_else(|| bad(format!("overflows at key {i}")))?,
        };
        if key >= grid_cells {
            return Err(bad(format!(
                "names cell {key}, beyond the grid's {grid_cells} cells"
            )));
        }
        keys.push(key);
        last = Some(key);
    }
    if raw.len() - at != 3 * n {
        return Err(bad(format!(
            "holds {} bytes of positions for {n} cells, which need {}",
            raw.len() - at,
            3 * n
        )));
    }
    let axes = &raw[at..];
    let positions = (0..n)
        .map(|i| [axes[i], axes[n + i], axes[2 * n + i]])
        .collect();
    Ok(SharpCells { keys, positions })
}

/// The sharp cells of the `section` of a file read from `path` whose grid has `dims` nodes,
/// `None` without a section; errors name the file.
pub fn read_sharp(
    section: Option<&SharpSection>,
    dims: [usize; 3],
    path: &Path,
) -> Result<Option<SharpCells>, FormatError> {
    section
        .map(|section| decode_sharp(section, dims))
        .transpose()
        .map_err(|problem| err(path, problem))
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// The varint at `*at`, `None` when the bytes end first or it does not fit in 64 bits.
fn take_varint(bytes: &[u8], at: &mut usize) -> Option<u64> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let b = *bytes.get(*at)?;
        *at += 1;
        let part = u64::from(b & 0x7f);
        if shift == 63 && part > 1 {
            return None;
        }
        v |= part << shift;
        if b & 0x80 == 0 {
            return Some(v);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> SharpCells {
        SharpCells {
            keys: vec![0, 5, 300, 70_000],
            positions: vec![[0, 1, 2], [255, 128, 3], [9, 9, 9], [1, 2, 255]],
        }
    }

    #[test]
    fn round_trips() {
        let cells = sample();
        let section = encode_sharp(&cells);
        let back = decode_sharp(&section, [100, 100, 100]).unwrap();
        assert_eq!(back, cells);
        assert_eq!(back.position(1)[0], 1.0);
    }

    #[test]
    fn refuses_keys_beyond_the_grid_and_bad_counts() {
        let section = encode_sharp(&sample());
        let small = decode_sharp(&section, [10, 10, 10]).unwrap_err();
        assert!(small.contains("beyond the grid"), "{small}");
        let mut more = section.clone();
        more.cells = 5;
        assert!(decode_sharp(&more, [100, 100, 100]).is_err());
        let mut bits = section;
        bits.bits = 10;
        assert!(decode_sharp(&bits, [100, 100, 100]).is_err());
    }

    #[test]
    fn varints_refuse_overflow() {
        let mut at = 0;
        assert_eq!(take_varint(&[0xff; 10], &mut at), None);
        let mut out = Vec::new();
        put_varint(&mut out, u64::MAX);
        let mut at = 0;
        assert_eq!(take_varint(&out, &mut at), Some(u64::MAX));
    }
}
