//! The optional `sharp` header section: dual-contouring vertices of the source mesh's exact
//! distance, stored in the cells next to its creases and corners, where the smooth fit rounds
//! them (`docs/format.md`, "The `sharp` section").
//!
//! A cell is named by its key `i + (nx − 1) · (j + (ny − 1) · k)` on the file's grid. The
//! section's `data` is base64 of one zstd frame holding, for `cells` = N cells in ascending key
//! order: N LEB128 varints, the first key then each key less the one before (≥ 1); then N bytes
//! of x, N of y and N of z, each the vertex's position in its cell as `q / 255` of the spacing.
//! With `outside` = M, a byte 255 instead marks a coordinate outside the cell (or at its far
//! face), and M bytes follow, one per such mark in the order the marks come: `(r − 64) / 128`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{err, FormatError};

/// Bits per axis of a stored position in its cell; the only value this version writes or reads.
pub const SHARP_BITS: u8 = 8;

/// The most cells a section may hold: bounds the buffer its data decompresses into.
pub const MAX_SHARP_CELLS: u64 = 1 << 22;

/// The largest quantised coordinate in a cell.
const TOP: f32 = 255.0;

/// The byte that marks a coordinate stored among the outside ones, in a section with `outside`.
const MARK: u8 = 255;

/// An outside coordinate `r` is `(r − OUTSIDE_ZERO) / OUTSIDE_STEPS` cells: from −0.5 to
/// 1.49, with 0 and 1 exact.
const OUTSIDE_ZERO: f32 = 64.0;
const OUTSIDE_STEPS: f32 = 128.0;

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
    /// Number of coordinates stored outside their cell's span, when any is; absent, a byte 255
    /// is the cell's far face.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outside: Option<u64>,
    /// Base64 of the zstd frame described in the module documentation.
    pub data: String,
}

/// Decoded cells: ascending keys and each one's vertex in cell units about the cell's lowest
/// corner, per axis in `[-0.5, 1.5)`: in the cell, or up to half a cell beyond a face.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SharpCells {
    pub keys: Vec<u64>,
    pub positions: Vec<[f32; 3]>,
}

impl SharpCells {
    /// The stored position of cell `index` in cell units.
    pub fn position(&self, index: usize) -> [f32; 3] {
        self.positions[index]
    }

    /// The nearest position the section stores of `x` (cell units), clamped to the span
    /// `[-0.5, 1.49]`.
    pub fn quantise(x: [f32; 3]) -> [f32; 3] {
        x.map(|v| match word(v) {
            Word::In(q) => f32::from(q) / TOP,
            Word::Out(r) => outside_value(r),
        })
    }
}

/// How a coordinate is stored: a byte across the cell, or a marked byte among the outside ones.
enum Word {
    In(u8),
    Out(u8),
}

fn word(v: f32) -> Word {
    let q = (v * TOP).round();
    if (0.0..TOP).contains(&q) {
        Word::In(q as u8)
    } else {
        let r = (v * OUTSIDE_STEPS + OUTSIDE_ZERO).round().clamp(0.0, 255.0);
        Word::Out(r as u8)
    }
}

fn outside_value(r: u8) -> f32 {
    (f32::from(r) - OUTSIDE_ZERO) / OUTSIDE_STEPS
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
    let mut outside = Vec::new();
    for axis in 0..3 {
        raw.extend(cells.positions.iter().map(|p| match word(p[axis]) {
            Word::In(q) => q,
            Word::Out(r) => {
                outside.push(r);
                MARK
            }
        }));
    }
    let m = outside.len() as u64;
    raw.extend(outside);
    let packed = zstd::bulk::compress(&raw, ZSTD_LEVEL).expect("compressing to memory");
    SharpSection {
        cells: n as u64,
        bits: SHARP_BITS,
        outside: (m > 0).then_some(m),
        data: pgvol_core::base64::encode(&packed),
    }
}

/// Decodes and checks `section` of a file whose grid has `dims` nodes: every key must name a
/// cell of that grid. The error says what is wrong, for the caller to name the file.
pub fn decode_sharp(section: &SharpSection, dims: [usize; 3]) -> Result<SharpCells, String> {
    let bad = |problem: String| {
        format!(
            "the sharp-feature section {problem}: the file is corrupt; encode the mesh again \
             (decoding by marching cubes or surface nets does not read the section)"
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
    let outside = section.outside.unwrap_or(0);
    if outside > 3 * n as u64 {
        return Err(bad(format!(
            "marks {outside} coordinates outside their cells, more than its {n} cells have"
        )));
    }
    let raw = zstd::bulk::decompress(&packed, n * (MAX_VARINT + 6))
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
    let m = outside as usize;
    if raw.len() - at != 3 * n + m {
        return Err(bad(format!(
            "holds {} bytes of positions for {n} cells and {m} outside coordinates, which need {}",
            raw.len() - at,
            3 * n + m
        )));
    }
    let (axes, mut rest) = raw[at..].split_at(3 * n);
    let mut coordinate = |q: u8| -> Result<f32, String> {
        match (q, section.outside.is_some()) {
            (MARK, true) => {
                let (&r, tail) = rest
                    .split_first()
                    .ok_or_else(|| bad(format!("marks more than {m} outside coordinates")))?;
                rest = tail;
                Ok(outside_value(r))
            }
            _ => Ok(f32::from(q) / TOP),
        }
    };
    let mut positions = vec![[0.0; 3]; n];
    for (axis, bytes) in axes.chunks_exact(n.max(1)).enumerate().take(3) {
        for (p, &q) in positions.iter_mut().zip(bytes) {
            p[axis] = coordinate(q)?;
        }
    }
    if !rest.is_empty() {
        return Err(bad(format!("marks fewer outside coordinates than its {m}")));
    }
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
        let positions = [[0u8, 1, 2], [255, 128, 3], [9, 9, 9], [1, 2, 254]]
            .map(|p| p.map(|q| f32::from(q) / TOP))
            .to_vec();
        SharpCells {
            keys: vec![0, 5, 300, 70_000],
            positions,
        }
    }

    #[test]
    fn round_trips() {
        let cells = sample();
        let section = encode_sharp(&cells);
        let back = decode_sharp(&section, [100, 100, 100]).unwrap();
        assert_eq!(back, cells);
        assert_eq!(back.position(1)[0], 1.0);
        // Only the far face is stored outside the cell's bytes.
        assert_eq!(section.outside, Some(1));
    }

    #[test]
    fn positions_outside_the_cell_round_trip_to_a_128th() {
        let wanted = [[-0.3, 0.5, 1.2], [0.25, -0.5, 1.49], [0.999, 0.0, 1.0]];
        let cells = SharpCells {
            keys: vec![1, 2, 3],
            positions: wanted.map(SharpCells::quantise).to_vec(),
        };
        let section = encode_sharp(&cells);
        assert_eq!(section.outside, Some(6));
        let back = decode_sharp(&section, [10, 10, 10]).unwrap();
        assert_eq!(back, cells);
        for (p, w) in back.positions.iter().zip(wanted) {
            for a in 0..3 {
                assert!(
                    (p[a] - w[a]).abs() <= 0.5 / 128.0 + 1e-6,
                    "{p:?} against {w:?}"
                );
            }
        }
        // Inside the cell a coordinate keeps its 255th.
        assert_eq!(back.positions[0][1], 128.0 / TOP);
        // A count of marks that does not match the bytes is refused.
        let mut fewer = section.clone();
        fewer.outside = Some(5);
        assert!(decode_sharp(&fewer, [10, 10, 10]).is_err());
        let mut none = section;
        none.outside = None;
        assert!(decode_sharp(&none, [10, 10, 10]).is_err());
    }

    #[test]
    fn a_section_without_outside_reads_255_as_the_far_face() {
        // As written before outside coordinates: bytes only, 255 the far face.
        let mut raw = vec![4u8];
        raw.extend([255, 0, 7]);
        let section = SharpSection {
            cells: 1,
            bits: SHARP_BITS,
            outside: None,
            data: pgvol_core::base64::encode(&zstd::bulk::compress(&raw, 3).unwrap()),
        };
        let back = decode_sharp(&section, [10, 10, 10]).unwrap();
        assert_eq!(back.keys, vec![4]);
        assert_eq!(back.positions, vec![[1.0, 0.0, 7.0 / TOP]]);
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
