//! Writing a float level set as an OpenVDB file.
//!
//! Each leaf is encoded as soon as its values are given (leaves in parallel), so memory holds
//! only the encoded band; the small tree above the leaves is built afterwards. Inactive values are `+background`
//! outside and `-background` inside, and every chunk is written with OpenVDB's active-mask
//! compression: the active values only, plus a mask choosing the sign of the inactive ones
//! where both occur.

use std::collections::BTreeMap;
use std::hash::{BuildHasher, Hasher};
use std::io::{self, Write};
use std::path::Path;

use rayon::prelude::*;

use super::mask_metadata::*;
use super::*;
use crate::error::{err, FormatError};

/// How value chunks are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VdbCompression {
    /// Raw values.
    None,
    /// Each chunk zlib-compressed (OpenVDB's "zip"), or raw when that would not be smaller.
    #[default]
    Zip,
}

/// What a level-set grid's header says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelSetGrid<'a> {
    /// The grid's name (what Blender's Volume to Mesh and other tools ask for).
    pub name: &'a str,
    pub transform: UniformScaleTranslate,
    /// The value of inactive voxels and tiles, positive, in world units: `+background` outside,
    /// `-background` inside; voxels with `|value| < background` are active.
    pub background: f32,
    /// Store values as 16-bit floats.
    pub half: bool,
    pub compression: VdbCompression,
}

/// What one leaf (an 8³ block of voxels at a multiple of 8) holds.
#[derive(Clone, Debug, PartialEq)]
pub enum VdbLeafValues {
    /// Entirely outside: nothing is written (the background).
    Outside,
    /// Entirely inside: an inactive tile of `-background`.
    Inside,
    /// Sampled values in OpenVDB's order ([`node_offset`]: z fastest); values at or beyond
    /// the background become inactive with the background of their sign.
    Sampled(Box<[f32; LEAF_VOXELS]>),
}

/// A leaf's place: the index of its first voxel, a multiple of [`LEAF_EDGE`] on every axis.
pub type VdbLeaf = [i32; 3];

/// An encoded leaf.
enum Encoded {
    Outside,
    Inside,
    Leaf {
        active: [u64; 8],
        /// Value mask then the value chunk, as the leaf's buffer is written.
        buffer: Vec<u8>,
        bounds: [[i32; 3]; 2],
    },
}

/// A lower internal node (16³ leaves): its leaves and inside tiles by offset.
#[derive(Default)]
struct Lower {
    slots: BTreeMap<usize, LowerSlot>,
}

enum LowerSlot {
    Inside,
    Leaf(usize),
}

/// An upper internal node (32³ lower nodes).
#[derive(Default)]
struct Upper {
    children: BTreeMap<usize, Lower>,
    inside: Vec<usize>,
}

/// Writes a float level set at `path` atomically: `leaf(origin)` gives the values of each
/// leaf in `origins` (each listed once; called in parallel); leaves not listed are outside.
pub fn write_level_set(
    path: &Path,
    grid: &LevelSetGrid,
    origins: &[VdbLeaf],
    leaf: impl Fn(VdbLeaf) -> VdbLeafValues + Sync,
) -> Result<(), FormatError> {
    check_grid(grid).map_err(|e| err(path, e))?;
    if let Some(o) = origins
        .iter()
        .find(|o| o.iter().any(|c| c.rem_euclid(LEAF_EDGE as i32) != 0))
    {
        return Err(err(
            path,
            format!("leaf origin {o:?} is not a multiple of 8"),
        ));
    }
    let background = stored_background(grid);
    let encoded: Vec<Encoded> = origins
        .par_iter()
        .map(|&o| encode_leaf(o, leaf(o), background, grid))
        .collect();
    let uppers = build_tree(origins, &encoded).map_err(|e| err(path, e))?;
    pgvol_core::write_atomic(path, |w| write_file(w, grid, background, &uppers, &encoded))
        .map_err(|e| err(path, e.problem))
}

fn check_grid(grid: &LevelSetGrid) -> Result<(), String> {
    let t = grid.transform;
    if !(t.voxel_size.is_finite() && t.voxel_size > 0.0) {
        return Err(format!(
            "voxel size {} is not a positive number",
            t.voxel_size
        ));
    }
    if t.translation.iter().any(|c| !c.is_finite()) {
        return Err(format!("translation {:?} is not finite", t.translation));
    }
    if !(grid.background.is_finite() && grid.background > 0.0) {
        return Err(format!(
            "background {} is not a positive number",
            grid.background
        ));
    }
    if grid.half && half::f16::from_f32(grid.background).to_f32() <= 0.0 {
        return Err(format!(
            "background {} is too small for half floats",
            grid.background
        ));
    }
    if grid.name.is_empty() || grid.name.len() > 256 {
        return Err("a grid name needs 1 to 256 bytes".to_string());
    }
    Ok(())
}

/// The background as stored: rounded to a half float when values are, so that inactive values
/// read back equal to it whatever the precision.
fn stored_background(grid: &LevelSetGrid) -> f32 {
    if grid.half {
        half::f16::from_f32(grid.background).to_f32()
    } else {
        grid.background
    }
}

fn encode_leaf(
    origin: VdbLeaf,
    values: VdbLeafValues,
    background: f32,
    grid: &LevelSetGrid,
) -> Encoded {
    let values = match values {
        VdbLeafValues::Outside => return Encoded::Outside,
        VdbLeafValues::Inside => return Encoded::Inside,
        VdbLeafValues::Sampled(v) => v,
    };
    let mut active = [0u64; 8];
    let mut clamped = [0f32; LEAF_VOXELS];
    let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
    let (mut any_inside, mut any_outside) = (false, false);
    for (n, (&v, c)) in values.iter().zip(clamped.iter_mut()).enumerate() {
        // NaN counts as outside, like a missing value.
        if v.abs() < background {
            active[n >> 6] |= 1 << (n & 63);
            *c = v;
            let xyz = [n >> 6, (n >> 3) & 7, n & 7];
            for a in 0..3 {
                lo[a] = lo[a].min(origin[a] + xyz[a] as i32);
                hi[a] = hi[a].max(origin[a] + xyz[a] as i32);
            }
        } else if v < 0.0 {
            *c = -background;
            any_inside = true;
        } else {
            *c = background;
            any_outside = true;
        }
    }
    if active.iter().all(|&w| w == 0) && !(any_inside && any_outside) {
        return if any_inside {
            Encoded::Inside
        } else {
            Encoded::Outside
        };
    }
    let mut buffer = Vec::with_capacity(64 + 1 + 64 + 4 * LEAF_VOXELS);
    put_mask(&mut buffer, &active);
    value_chunk(&mut buffer, &clamped, &active, &[], background, grid);
    Encoded::Leaf {
        active,
        buffer,
        bounds: [lo, hi],
    }
}

fn put_mask(out: &mut Vec<u8>, words: &[u64]) {
    for w in words {
        out.extend_from_slice(&w.to_le_bytes());
    }
}

fn bit(words: &[u64], n: usize) -> bool {
    words.get(n >> 6).is_some_and(|w| w >> (n & 63) & 1 == 1)
}

/// One node's values as `io::writeCompressedValues` writes them with active-mask compression:
/// a tag, the mask choosing `+background` (bit on) or `-background` where both occur, then
/// the active values. `values` off `active` and off `children` must be ±`background`.
fn value_chunk(
    out: &mut Vec<u8>,
    values: &[f32],
    active: &[u64],
    children: &[u64],
    background: f32,
    grid: &LevelSetGrid,
) {
    let inactive = |n: &usize| !bit(active, *n) && !bit(children, *n);
    let inside = (0..values.len()).filter(inactive).any(|n| values[n] < 0.0);
    let outside = (0..values.len()).filter(inactive).any(|n| values[n] > 0.0);
    let tag = match (inside, outside) {
        (true, true) => MASK_AND_NO_INACTIVE_VALS,
        (true, false) => NO_MASK_AND_MINUS_BG,
        _ => NO_MASK_OR_INACTIVE_VALS,
    };
    out.push(tag);
    if tag == MASK_AND_NO_INACTIVE_VALS {
        let mut selection = vec![0u64; values.len().div_ceil(64)];
        for n in (0..values.len()).filter(inactive) {
            if values[n] == background {
                selection[n >> 6] |= 1 << (n & 63);
            }
        }
        put_mask(out, &selection);
    }
    let mut raw = Vec::new();
    let mut count = 0usize;
    for (n, &v) in values.iter().enumerate() {
        if bit(active, n) {
            count += 1;
            if grid.half {
                raw.extend_from_slice(&half::f16::from_f32(v).to_le_bytes());
            } else {
                raw.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    // Half chunks of no values are left out entirely; float ones still carry their length
    // when zipped (as OpenVDB writes them).
    if count == 0 && grid.half {
        return;
    }
    match grid.compression {
        VdbCompression::None => out.extend_from_slice(&raw),
        VdbCompression::Zip => zip_chunk(out, &raw),
    }
}

/// A zipped chunk: its zlib length then the zlib stream, or the negated raw length then the
/// raw bytes when zlib would not be smaller.
fn zip_chunk(out: &mut Vec<u8>, raw: &[u8]) {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    let zipped = z.write_all(raw).and_then(|_| z.finish());
    match zipped {
        Ok(zipped) if zipped.len() < raw.len() => {
            out.extend_from_slice(&(zipped.len() as i64).to_le_bytes());
            out.extend_from_slice(&zipped);
        }
        _ => {
            out.extend_from_slice(&(-(raw.len() as i64)).to_le_bytes());
            out.extend_from_slice(raw);
        }
    }
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_str(out: &mut Vec<u8>, s: &str) {
    put_u32(out, s.len() as u32);
    out.extend_from_slice(s.as_bytes());
}

fn put_coord(out: &mut Vec<u8>, c: [i32; 3]) {
    for v in c {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// One metadata entry: name, type name, byte size, value.
fn put_meta(out: &mut Vec<u8>, name: &str, type_name: &str, value: &[u8]) {
    put_str(out, name);
    put_str(out, type_name);
    put_u32(out, value.len() as u32);
    out.extend_from_slice(value);
}

fn coord_bytes(c: [i32; 3]) -> Vec<u8> {
    let mut v = Vec::new();
    put_coord(&mut v, c);
    v
}

/// The leaves sorted into lower and upper internal nodes, inside lower nodes made tiles.
fn build_tree(
    origins: &[VdbLeaf],
    encoded: &[Encoded],
) -> Result<BTreeMap<[i32; 3], Upper>, String> {
    const LOWER_SPAN: i32 = 1 << (LEAF_LOG2 + LOWER_LOG2);
    const UPPER_SPAN: i32 = 1 << (LEAF_LOG2 + LOWER_LOG2 + UPPER_LOG2);
    let mut uppers: BTreeMap<[i32; 3], Upper> = BTreeMap::new();
    for (index, (o, e)) in origins.iter().zip(encoded).enumerate() {
        let slot = match e {
            Encoded::Outside => continue,
            Encoded::Inside => LowerSlot::Inside,
            Encoded::Leaf { .. } => LowerSlot::Leaf(index),
        };
        let upper = o.map(|c| c.div_euclid(UPPER_SPAN) * UPPER_SPAN);
        let lower_at = std::array::from_fn(|a| ((o[a] - upper[a]) / LOWER_SPAN) as usize);
        let leaf_at =
            std::array::from_fn(|a| ((o[a].rem_euclid(LOWER_SPAN)) >> LEAF_LOG2) as usize);
        let before = uppers
            .entry(upper)
            .or_default()
            .children
            .entry(node_offset(UPPER_LOG2, lower_at))
            .or_default()
            .slots
            .insert(node_offset(LOWER_LOG2, leaf_at), slot);
        if before.is_some() {
            return Err(format!("leaf origin {o:?} is listed twice"));
        }
    }
    for upper in uppers.values_mut() {
        let full = 1usize << (3 * LOWER_LOG2);
        let inside: Vec<usize> = upper
            .children
            .iter()
            .filter(|(_, l)| {
                l.slots.len() == full && l.slots.values().all(|s| matches!(s, LowerSlot::Inside))
            })
            .map(|(&at, _)| at)
            .collect();
        for at in &inside {
            upper.children.remove(at);
        }
        upper.inside = inside;
    }
    uppers.retain(|_, u| !u.children.is_empty() || !u.inside.is_empty());
    Ok(uppers)
}

/// The tree's topology (`Tree::writeTopology`): buffer count, root, then each internal node
/// with its masks and tile values, each leaf's value mask. Returns the leaves in write order.
fn topology(
    out: &mut Vec<u8>,
    uppers: &BTreeMap<[i32; 3], Upper>,
    encoded: &[Encoded],
    background: f32,
    grid: &LevelSetGrid,
) -> Vec<usize> {
    let mut order = Vec::new();
    out.extend_from_slice(&1i32.to_le_bytes());
    out.extend_from_slice(&background.to_le_bytes());
    put_u32(out, 0);
    put_u32(out, uppers.len() as u32);
    let upper_slots = 1usize << (3 * UPPER_LOG2);
    let lower_slots = 1usize << (3 * LOWER_LOG2);
    for (&origin, upper) in uppers {
        put_coord(out, origin);
        let mut children = vec![0u64; upper_slots / 64];
        let mut values = vec![background; upper_slots];
        for &at in upper.children.keys() {
            children[at >> 6] |= 1 << (at & 63);
            values[at] = 0.0;
        }
        for &at in &upper.inside {
            values[at] = -background;
        }
        put_mask(out, &children);
        put_mask(out, &vec![0u64; upper_slots / 64]);
        value_chunk(out, &values, &[], &children, background, grid);
        for lower in upper.children.values() {
            let mut children = vec![0u64; lower_slots / 64];
            let mut values = vec![background; lower_slots];
            for (&at, slot) in &lower.slots {
                match slot {
                    LowerSlot::Inside => values[at] = -background,
                    LowerSlot::Leaf(_) => {
                        children[at >> 6] |= 1 << (at & 63);
                        values[at] = 0.0;
                    }
                }
            }
            put_mask(out, &children);
            put_mask(out, &vec![0u64; lower_slots / 64]);
            value_chunk(out, &values, &[], &children, background, grid);
            for slot in lower.slots.values() {
                if let LowerSlot::Leaf(index) = *slot {
                    if let Encoded::Leaf { active, .. } = &encoded[index] {
                        put_mask(out, active);
                    }
                    order.push(index);
                }
            }
        }
    }
    order
}

/// A random version-4 UUID in its 36-character text form, as OpenVDB tags each file.
fn uuid_text() -> String {
    let state = std::collections::hash_map::RandomState::new();
    let word = |salt: u64| {
        let mut h = state.build_hasher();
        h.write_u64(salt);
        if let Ok(t) = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH) {
            h.write_u128(t.as_nanos());
        }
        h.write_u32(std::process::id());
        h.finish()
    };
    let (a, b) = (word(1), word(2));
    let a = (a & !0xf000) | 0x4000; // version 4
    let b = (b & !(0xc << 60)) | (0x8 << 60); // RFC 4122 variant
    format!(
        "{:08x}-{:04x}-{:04x}-{:04x}-{:012x}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// The grid's metadata (sorted by name, as OpenVDB writes its map).
fn grid_metadata(out: &mut Vec<u8>, grid: &LevelSetGrid, encoded: &[Encoded]) {
    let (mut lo, mut hi, mut count) = ([i32::MAX; 3], [i32::MIN; 3], 0i64);
    for e in encoded {
        if let Encoded::Leaf { active, bounds, .. } = e {
            count += active.iter().map(|w| w.count_ones() as i64).sum::<i64>();
            for a in 0..3 {
                lo[a] = lo[a].min(bounds[0][a]);
                hi[a] = hi[a].max(bounds[1][a]);
            }
        }
    }
    let mut entries: Vec<(&str, &str, Vec<u8>)> = vec![
        ("class", "string", LEVEL_SET_CLASS.as_bytes().to_vec()),
        ("name", "string", grid.name.as_bytes().to_vec()),
        ("file_voxel_count", "int64", count.to_le_bytes().to_vec()),
    ];
    if count > 0 {
        entries.push(("file_bbox_min", "vec3i", coord_bytes(lo)));
        entries.push(("file_bbox_max", "vec3i", coord_bytes(hi)));
    }
    if grid.half {
        entries.push(("is_saved_as_half_float", "bool", vec![1]));
    }
    entries.sort_by(|a, b| a.0.cmp(b.0));
    out.extend_from_slice(&(entries.len() as i32).to_le_bytes());
    for (name, type_name, value) in &entries {
        put_meta(out, name, type_name, value);
    }
}

/// `UniformScaleTranslateMap::write`: translation, scale, voxel size, inverse scale, inverse
/// squared scale and inverse doubled scale, each three f64.
fn transform(out: &mut Vec<u8>, t: UniformScaleTranslate) {
    put_str(out, UNIFORM_SCALE_TRANSLATE_MAP);
    let s = t.voxel_size;
    let rows = [
        t.translation,
        [s; 3],
        [s; 3],
        [1.0 / s; 3],
        [1.0 / (s * s); 3],
        [0.5 / s; 3],
    ];
    for v in rows.iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// The whole file into `out`: header, one grid descriptor with its offsets, the grid.
fn write_file(
    w: &mut dyn Write,
    grid: &LevelSetGrid,
    background: f32,
    uppers: &BTreeMap<[i32; 3], Upper>,
    encoded: &[Encoded],
) -> io::Result<()> {
    // The grid up to its buffers, so the descriptor can give the offsets before it.
    let mut body = Vec::new();
    let mut compression = COMPRESS_ACTIVE_MASK;
    if grid.compression == VdbCompression::Zip {
        compression |= COMPRESS_ZIP;
    }
    put_u32(&mut body, compression);
    grid_metadata(&mut body, grid, encoded);
    transform(&mut body, grid.transform);
    let order = topology(&mut body, uppers, encoded, background, grid);
    let buffers: usize = order
        .iter()
        .map(|&i| match &encoded[i] {
            Encoded::Leaf { buffer, .. } => buffer.len(),
            _ => 0,
        })
        .sum();

    let mut head = Vec::new();
    let out = &mut head;
    out.extend_from_slice(&MAGIC.to_le_bytes());
    put_u32(out, FILE_VERSION);
    put_u32(out, LIBRARY_VERSION.0);
    put_u32(out, LIBRARY_VERSION.1);
    out.push(1); // the grid offsets below are present
    out.extend_from_slice(uuid_text().as_bytes());
    out.extend_from_slice(&0i32.to_le_bytes()); // no file metadata
    out.extend_from_slice(&1i32.to_le_bytes()); // one grid
    put_str(out, grid.name);
    let type_name = if grid.half {
        format!("{FLOAT_TREE}{HALF_FLOAT_SUFFIX}")
    } else {
        FLOAT_TREE.to_string()
    };
    put_str(out, &type_name);
    put_str(out, ""); // not an instance of another grid
    let grid_pos = out.len() + 24;
    let block_pos = grid_pos + body.len();
    let end_pos = block_pos + buffers;
    for p in [grid_pos, block_pos, end_pos] {
        out.extend_from_slice(&(p as i64).to_le_bytes());
    }
    w.write_all(&head)?;
    w.write_all(&body)?;
    for &i in &order {
        if let Encoded::Leaf { buffer, .. } = &encoded[i] {
            w.write_all(buffer)?;
        }
    }
    Ok(())
}
