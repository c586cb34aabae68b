//! Reading one float level set from an OpenVDB file: the header, the grid descriptors, then
//! the chosen grid's metadata, transform, tree topology and leaf buffers. Every count and
//! size is checked against the bytes that remain before anything is allocated for it.

use std::io::Read;
use std::path::Path;

use super::mask_metadata as mm;
use super::{
    blosc, COMPRESS_ACTIVE_MASK, COMPRESS_BLOSC, COMPRESS_ZIP, FILE_VERSION,
    FILE_VERSION_NODE_MASK_COMPRESSION, FLOAT_TREE, HALF_FLOAT_SUFFIX, LEAF_LOG2, LEAF_VOXELS,
    LEVEL_SET_CLASS, LOWER_LOG2, MAGIC, UPPER_LOG2,
};
use crate::error::{err, FormatError};

/// Bytes of a leaf's value mask.
const LEAF_MASK_BYTES: usize = LEAF_VOXELS / 8;
/// Longest string (grid name, type or metadata name) read.
const MAX_STRING: usize = 1 << 16;
/// Most leaves read: as many voxels as pgvol's largest grid has nodes.
pub const MAX_LEAVES: usize = (pgvol_core::MAX_GRID_NODES >> (3 * LEAF_LOG2)) as usize;
/// Separator OpenVDB puts between a grid's name and the number that makes it unique.
const UNIQUE_SUFFIX: char = '\u{1e}';

/// A leaf node: 8³ voxels from `origin`, z fastest (OpenVDB's order), with its active mask.
#[derive(Clone, Debug, PartialEq)]
pub struct VdbLeaf {
    pub origin: [i32; 3],
    /// Bit `n` set when voxel `n` is active.
    pub active: [u64; LEAF_VOXELS / 64],
    pub values: Box<[f32; LEAF_VOXELS]>,
}

/// A constant region: a cube of `1 << log2_edge` voxels from `origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VdbTile {
    pub origin: [i32; 3],
    pub log2_edge: u32,
    pub value: f32,
    pub active: bool,
}

/// One float level set as stored: index space, its transform to world space, the leaves and
/// the tiles whose value differs from the background or that are active.
#[derive(Clone, Debug)]
pub struct VdbLevelSet {
    pub name: String,
    pub file_version: u32,
    /// World size of a voxel (the uniform scale).
    pub voxel_size: f64,
    /// World position of voxel (0, 0, 0).
    pub translation: [f64; 3],
    /// Value outside the narrow band (positive: the band's half-width in world units).
    pub background: f32,
    /// Whether values were stored as 16-bit floats.
    pub half: bool,
    /// The grid's compression flags (`COMPRESS_*`).
    pub compression: u32,
    /// The transform's type name.
    pub map: String,
    pub leaves: Vec<VdbLeaf>,
    pub tiles: Vec<VdbTile>,
}

/// One entry of the file's grid table.
#[derive(Clone, Debug)]
struct Descriptor {
    name: String,
    grid_type: String,
    half: bool,
    instance_of: String,
    grid_pos: usize,
    end_pos: usize,
}

/// Reads the level set `name` (or the first float level set) of the `.vdb` file at `path`.
pub fn read_vdb(path: &Path, name: Option<&str>) -> Result<VdbLevelSet, FormatError> {
    let bytes = pgvol_core::read_input(path).map_err(|e| err(path, e.problem))?;
    decode_vdb(&bytes, path, name)
}

/// [`read_vdb`] from bytes; `path` names the file in errors.
pub fn decode_vdb(
    bytes: &[u8],
    path: &Path,
    name: Option<&str>,
) -> Result<VdbLevelSet, FormatError> {
    decode(bytes, name).map_err(|problem| err(path, problem))
}

fn decode(bytes: &[u8], wanted: Option<&str>) -> Result<VdbLevelSet, String> {
    let mut c = Cursor::new(bytes);
    let magic = c
        .u64()
        .map_err(|_| "too short for an OpenVDB file".to_string())?;
    if magic != MAGIC {
        return Err("not an OpenVDB file (its first bytes are not the .vdb magic number)".into());
    }
    let version = c.u32()?;
    if !(FILE_VERSION_NODE_MASK_COMPRESSION..=FILE_VERSION).contains(&version) {
        return Err(format!(
            "OpenVDB file version {version} is not read: versions \
             {FILE_VERSION_NODE_MASK_COMPRESSION} to {FILE_VERSION} are ({FILE_VERSION} is what \
             OpenVDB 10 writes); resave the file with a current OpenVDB"
        ));
    }
    let _library = (c.u32()?, c.u32()?);
    if c.u8()? == 0 {
        return Err(
            "the file has no grid offsets (written as a stream); resave it as a file".into(),
        );
    }
    c.take(36, "the file's UUID")?;
    skip_metadata(&mut c, "file")?;
    let count = c.u32()? as usize;
    // A descriptor holds at least three string lengths and three offsets.
    c.check_count(count, 36, "grids")?;
    let mut descriptors = Vec::with_capacity(count);
    for _ in 0..count {
        let unique = c.string("a grid name")?;
        let name = unique
            .split(UNIQUE_SUFFIX)
            .next()
            .unwrap_or_default()
            .to_string();
        let mut grid_type = c.string("a grid type")?;
        let half = grid_type.ends_with(HALF_FLOAT_SUFFIX);
        if half {
            grid_type.truncate(grid_type.len() - HALF_FLOAT_SUFFIX.len());
        }
        let instance_of = c.string("a grid's instance parent")?;
        let grid_pos = c.offset("grid")?;
        let _block_pos = c.offset("block")?;
        let end_pos = c.offset("end")?;
        if grid_pos != c.pos || end_pos < grid_pos {
            return Err(format!(
                "grid '{name}' has data from byte {grid_pos} to {end_pos}, not after its \
                 descriptor at byte {}",
                c.pos
            ));
        }
        descriptors.push(Descriptor {
            name,
            grid_type,
            half,
            instance_of,
            grid_pos,
            end_pos,
        });
        c.pos = end_pos;
    }
    let chosen = choose(bytes, &descriptors, wanted)?;
    let d = &descriptors[chosen];
    if !d.instance_of.is_empty() {
        return Err(format!(
            "grid '{}' is an instance of grid '{}' (shared trees are not read)",
            d.name, d.instance_of
        ));
    }
    let mut g = Cursor::new(&bytes[..d.end_pos]);
    g.pos = d.grid_pos;
    read_grid(&mut g, d, version).map_err(|e| format!("grid '{}': {e}", d.name))
}

/// The index of the grid to read: the one named `wanted` or the first float level set.
fn choose(bytes: &[u8], grids: &[Descriptor], wanted: Option<&str>) -> Result<usize, String> {
    let listing = || {
        grids
            .iter()
            .map(|d| format!("'{}' ({})", d.name, d.grid_type))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if grids.is_empty() {
        return Err("the file holds no grid".into());
    }
    if let Some(name) = wanted {
        let i = grids
            .iter()
            .position(|d| d.name == name)
            .ok_or_else(|| format!("has no grid named '{name}'; its grids are {}", listing()))?;
        if grids[i].grid_type != FLOAT_TREE {
            return Err(format!(
                "grid '{name}' is a {}, not a float level set ({FLOAT_TREE})",
                grids[i].grid_type
            ));
        }
        return Ok(i);
    }
    for (i, d) in grids.iter().enumerate() {
        if d.grid_type == FLOAT_TREE && grid_class(bytes, d)? == LEVEL_SET_CLASS {
            return Ok(i);
        }
    }
    Err(format!(
        "holds no float level set (a {FLOAT_TREE} grid of class '{LEVEL_SET_CLASS}'); its \
         grids are {}",
        listing()
    ))
}

/// The `class` metadata of a grid, empty when it has none.
fn grid_class(bytes: &[u8], d: &Descriptor) -> Result<String, String> {
    let mut c = Cursor::new(&bytes[..d.end_pos]);
    c.pos = d.grid_pos;
    c.u32()?;
    let meta = read_metadata(&mut c, "grid")?;
    Ok(meta.class)
}

/// What the reader uses of a grid's metadata.
#[derive(Default)]
struct GridMeta {
    class: String,
}

fn read_metadata(c: &mut Cursor, whose: &str) -> Result<GridMeta, String> {
    let mut meta = GridMeta::default();
    let count = c.u32()? as usize;
    // Each entry holds two string lengths and a value length.
    c.check_count(count, 12, &format!("{whose} metadata entries"))?;
    for _ in 0..count {
        let name = c.string("a metadata name")?;
        let _type = c.string("a metadata type")?;
        let size = c.u32()? as usize;
        let value = c.take(size, &format!("metadata '{name}'"))?;
        if name == "class" {
            meta.class = String::from_utf8_lossy(value).into_owned();
        }
    }
    Ok(meta)
}

fn skip_metadata(c: &mut Cursor, whose: &str) -> Result<(), String> {
    read_metadata(c, whose).map(|_| ())
}

fn read_grid(c: &mut Cursor, d: &Descriptor, version: u32) -> Result<VdbLevelSet, String> {
    let compression = c.u32()?;
    if compression & !(COMPRESS_ZIP | COMPRESS_ACTIVE_MASK | COMPRESS_BLOSC) != 0 {
        return Err(format!("unknown compression flags {compression:#x}"));
    }
    let meta = read_metadata(c, "grid")?;
    if meta.class != LEVEL_SET_CLASS {
        return Err(format!(
            "its class is '{}', not '{LEVEL_SET_CLASS}': only level sets (signed distances) \
             are read",
            meta.class
        ));
    }
    let (map, voxel_size, translation) = read_transform(c)?;
    let buffers = c.i32()?;
    if buffers != 1 {
        return Err(format!("the tree has {buffers} buffers per leaf, not 1"));
    }
    let background = c.f32()?;
    if !(background.is_finite() && background > 0.0) {
        return Err(format!(
            "its background {background} is not a positive finite distance, as a level \
             set's must be"
        ));
    }
    let mut tree = Tree {
        chunks: Chunks {
            compression,
            half: d.half,
            background,
            version,
        },
        leaves: Vec::new(),
        tiles: Vec::new(),
    };
    let tiles = c.u32()? as usize;
    let children = c.u32()? as usize;
    c.check_count(tiles, 17, "root tiles")?;
    for _ in 0..tiles {
        let origin = c.coord()?;
        let value = c.f32()?;
        let active = c.u8()? != 0;
        tree.tile(origin, UPPER_LOG2 + LOWER_LOG2 + LEAF_LOG2, value, active)?;
    }
    let top_mask_bytes = 2 * (1usize << (3 * UPPER_LOG2)) / 8;
    c.check_count(children, 12 + top_mask_bytes, "root children")?;
    for _ in 0..children {
        let origin = c.coord()?;
        tree.internal(c, origin, UPPER_LOG2)?;
    }
    for leaf in &mut tree.leaves {
        let mask = c.mask(LEAF_VOXELS)?;
        let values = tree.chunks.values(c, LEAF_VOXELS, &mask)?;
        leaf.active.copy_from_slice(&mask);
        leaf.values.copy_from_slice(&values);
    }
    Ok(VdbLevelSet {
        name: d.name.clone(),
        file_version: version,
        voxel_size,
        translation,
        background,
        half: d.half,
        compression,
        map,
        leaves: tree.leaves,
        tiles: tree.tiles,
    })
}

/// The map type, the uniform voxel size and the translation of voxel (0, 0, 0).
fn read_transform(c: &mut Cursor) -> Result<(String, f64, [f64; 3]), String> {
    let map = c.string("the transform's map type")?;
    let translation = match map.as_str() {
        "UniformScaleMap" => [0.0; 3],
        "UniformScaleTranslateMap" => c.vec3d()?,
        other => {
            return Err(format!(
                "its transform is a {other}; only UniformScaleMap and \
                 UniformScaleTranslateMap (a uniform voxel size, no rotation) are read"
            ))
        }
    };
    let scale = c.vec3d()?;
    // Voxel size, inverse scale, inverse square and inverse twice the scale follow: derived.
    c.take(4 * 24, "the transform")?;
    let s = scale[0];
    let finite = translation.iter().all(|t| t.is_finite() && t.abs() < 1e12);
    if !(s.is_finite() && s > 0.0 && scale.iter().all(|&v| v == s) && finite) {
        return Err(format!(
            "its {map} has scale {scale:?} and translation {translation:?}: not a positive \
             uniform voxel size with a finite translation"
        ));
    }
    Ok((map, s, translation))
}

/// How a grid's value chunks are stored.
struct Chunks {
    compression: u32,
    half: bool,
    background: f32,
    version: u32,
}

impl Chunks {
    /// `count` values of a node with active mask `mask`, inactive ones restored.
    fn values(&self, c: &mut Cursor, count: usize, mask: &[u64]) -> Result<Vec<f32>, String> {
        let bg = self.background;
        let mut metadata = mm::NO_MASK_AND_ALL_VALS;
        if self.version >= FILE_VERSION_NODE_MASK_COMPRESSION {
            metadata = c.u8()?;
        }
        if metadata > mm::NO_MASK_AND_ALL_VALS {
            return Err(format!("unknown node mask metadata {metadata}"));
        }
        let mut inactive = [
            if metadata == mm::NO_MASK_OR_INACTIVE_VALS {
                bg
            } else {
                -bg
            },
            bg,
        ];
        if matches!(
            metadata,
            mm::NO_MASK_AND_ONE_INACTIVE_VAL
                | mm::MASK_AND_ONE_INACTIVE_VAL
                | mm::MASK_AND_TWO_INACTIVE_VALS
        ) {
            inactive[0] = c.f32()?;
            if metadata == mm::MASK_AND_TWO_INACTIVE_VALS {
                inactive[1] = c.f32()?;
            }
        }
        let selection = if matches!(
            metadata,
            mm::MASK_AND_NO_INACTIVE_VALS
                | mm::MASK_AND_ONE_INACTIVE_VAL
                | mm::MASK_AND_TWO_INACTIVE_VALS
        ) {
            c.mask(count)?
        } else {
            vec![0; count / 64]
        };
        let active = mask.iter().map(|w| w.count_ones() as usize).sum::<usize>();
        let stored = if self.compression & COMPRESS_ACTIVE_MASK != 0
            && metadata != mm::NO_MASK_AND_ALL_VALS
        {
            active
        } else {
            count
        };
        let read = self.chunk(c, stored)?;
        if stored == count {
            return Ok(read);
        }
        let mut next = read.into_iter();
        Ok((0..count)
            .map(|i| {
                if bit(mask, i) {
                    next.next().unwrap_or(bg)
                } else {
                    inactive[usize::from(bit(&selection, i))]
                }
            })
            .collect())
    }

    /// One chunk of `count` values, compressed as the grid says.
    fn chunk(&self, c: &mut Cursor, count: usize) -> Result<Vec<f32>, String> {
        let width = if self.half { 2 } else { 4 };
        if self.half && count == 0 {
            // OpenVDB's half reader returns before the chunk's size when there is nothing.
            return Ok(Vec::new());
        }
        let bytes = count * width;
        let raw: Vec<u8> = if self.compression & (COMPRESS_BLOSC | COMPRESS_ZIP) != 0 {
            let n = c.i64()?;
            if n <= 0 {
                let n = n.unsigned_abs() as usize;
                if n != bytes {
                    return Err(format!(
                        "a node's uncompressed chunk holds {n} bytes where {bytes} were expected"
                    ));
                }
                c.take(n, "a node's values")?.to_vec()
            } else {
                let packed = c.take(n as usize, "a node's compressed values")?;
                if self.compression & COMPRESS_BLOSC != 0 {
                    blosc::decompress(packed, bytes)?
                } else {
                    inflate(packed, bytes)?
                }
            }
        } else {
            c.take(bytes, "a node's values")?.to_vec()
        };
        let values: Vec<f32> = if self.half {
            raw.chunks_exact(2)
                .map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32())
                .collect()
        } else {
            raw.chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect()
        };
        if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
            return Err(format!(
                "a node holds the value {bad}; distances must be finite"
            ));
        }
        Ok(values)
    }
}

/// A zlib stream that must inflate to exactly `expected` bytes.
fn inflate(packed: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(expected);
    flate2::read::ZlibDecoder::new(packed)
        .take(expected as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("a node's zlib chunk does not inflate: {e}"))?;
    if out.len() != expected {
        return Err(format!(
            "a node's zlib chunk inflates to {} bytes where {expected} were expected",
            out.len()
        ));
    }
    Ok(out)
}

/// The tree as it is read: leaves in file order (the order of their buffers) and tiles.
struct Tree {
    chunks: Chunks,
    leaves: Vec<VdbLeaf>,
    tiles: Vec<VdbTile>,
}

impl Tree {
    /// Keeps a tile unless it is an inactive copy of the background.
    fn tile(
        &mut self,
        origin: [i32; 3],
        log2_edge: u32,
        value: f32,
        active: bool,
    ) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("a tile at {origin:?} holds the value {value}"));
        }
        if active || value != self.chunks.background {
            self.tiles.push(VdbTile {
                origin,
                log2_edge,
                value,
                active,
            });
        }
        Ok(())
    }

    /// An internal node of `log2` children per axis at `origin`, and its subtree.
    fn internal(&mut self, c: &mut Cursor, origin: [i32; 3], log2: u32) -> Result<(), String> {
        let child_log2 = if log2 == UPPER_LOG2 {
            LOWER_LOG2 + LEAF_LOG2
        } else {
            LEAF_LOG2
        };
        let span = 1i64 << (log2 + child_log2);
        if origin
            .iter()
            .any(|&o| i64::from(o) % span != 0 || i64::from(o) + span > i64::from(i32::MAX) + 1)
        {
            return Err(format!(
                "a node at {origin:?} is not aligned to its {span}-voxel size"
            ));
        }
        let slots = 1usize << (3 * log2);
        let children = c.mask(slots)?;
        let active = c.mask(slots)?;
        let values = self.chunks.values(c, slots, &active)?;
        let at = |n: usize| -> [i32; 3] {
            let m = (1usize << log2) - 1;
            let idx = [n >> (2 * log2), (n >> log2) & m, n & m];
            [0, 1, 2].map(|a| origin[a] + ((idx[a] as i32) << child_log2))
        };
        for (n, &value) in values.iter().enumerate() {
            if !bit(&children, n) {
                self.tile(at(n), child_log2, value, bit(&active, n))?;
            }
        }
        let count = children
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum::<usize>();
        if log2 == UPPER_LOG2 {
            let lower_masks = 2 * (1usize << (3 * LOWER_LOG2)) / 8;
            c.check_count(count, lower_masks, "internal node children")?;
        } else {
            // Each leaf's mask here, and its buffer later: the mask again and a metadata byte.
            c.check_count(count, 2 * LEAF_MASK_BYTES + 1, "leaf nodes")?;
            if self.leaves.len() + count > MAX_LEAVES {
                return Err(format!(
                    "more than {MAX_LEAVES} leaf nodes (the limit of {} voxels)",
                    pgvol_core::MAX_GRID_NODES
                ));
            }
        }
        for n in (0..slots).filter(|&n| bit(&children, n)) {
            if log2 == UPPER_LOG2 {
                self.internal(c, at(n), LOWER_LOG2)?;
            } else {
                let mask = c.mask(LEAF_VOXELS)?;
                let mut leaf = VdbLeaf {
                    origin: at(n),
                    active: [0; LEAF_VOXELS / 64],
                    values: Box::new([self.chunks.background; LEAF_VOXELS]),
                };
                leaf.active.copy_from_slice(&mask);
                self.leaves.push(leaf);
            }
        }
        Ok(())
    }
}

fn bit(words: &[u64], i: usize) -> bool {
    words[i >> 6] >> (i & 63) & 1 == 1
}

/// Little-endian reads over the file's bytes; every read checks what remains.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, pos: 0 }
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if n > self.remaining() {
            return Err(format!(
                "truncated: {what} needs {n} bytes at byte {} but {} remain",
                self.pos,
                self.remaining()
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let s = self.take(N, "a number")?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.array::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        self.array().map(u32::from_le_bytes)
    }
    fn i32(&mut self) -> Result<i32, String> {
        self.array().map(i32::from_le_bytes)
    }
    fn u64(&mut self) -> Result<u64, String> {
        self.array().map(u64::from_le_bytes)
    }
    fn i64(&mut self) -> Result<i64, String> {
        self.array().map(i64::from_le_bytes)
    }
    fn f32(&mut self) -> Result<f32, String> {
        self.array().map(f32::from_le_bytes)
    }
    fn vec3d(&mut self) -> Result<[f64; 3], String> {
        let mut v = [0.0; 3];
        for x in &mut v {
            *x = f64::from_le_bytes(self.array()?);
        }
        Ok(v)
    }
    fn coord(&mut self) -> Result<[i32; 3], String> {
        Ok([self.i32()?, self.i32()?, self.i32()?])
    }

    /// A file offset, which must lie within the file.
    fn offset(&mut self, what: &str) -> Result<usize, String> {
        let o = self.i64()?;
        let len = self.bytes.len();
        usize::try_from(o)
            .ok()
            .filter(|&o| o <= len)
            .ok_or_else(|| {
                format!(
                    "truncated or corrupt: a {what} offset {o} lies beyond the file's {len} bytes"
                )
            })
    }

    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32()? as usize;
        if n > MAX_STRING {
            return Err(format!(
                "{what} of {n} bytes is longer than the {MAX_STRING} read"
            ));
        }
        Ok(String::from_utf8_lossy(self.take(n, what)?).into_owned())
    }

    /// A bit mask of `bits` bits as 64-bit words.
    fn mask(&mut self, bits: usize) -> Result<Vec<u64>, String> {
        let s = self.take(bits / 8, "a node mask")?;
        Ok(s.chunks_exact(8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap_or_default()))
            .collect())
    }

    /// Refuses `count` items of at least `each` bytes when fewer bytes remain.
    fn check_count(&self, count: usize, each: usize, what: &str) -> Result<(), String> {
        if count.saturating_mul(each) > self.remaining() {
            return Err(format!(
                "claims {count} {what} but only {} bytes remain for them",
                self.remaining()
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn chunks(compression: u32) -> Chunks {
        Chunks {
            compression,
            half: false,
            background: 3.0,
            version: FILE_VERSION,
        }
    }

    /// Zlib chunks (OpenVDB's "ZIP"), compressed here by the zlib reference encoder, and the
    /// raw chunks a negative size announces, with mask compression restoring ±background.
    #[test]
    fn zlib_and_raw_chunks_restore_inactive_values() {
        let values: Vec<f32> = (0..8).map(|i| i as f32 * 0.25 - 1.0).collect();
        let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        z.write_all(&raw).unwrap();
        let zipped = z.finish().unwrap();
        // 64 voxels: the first 8 active; the selection mask puts voxels 32.. at +background.
        let mask = [0xffu64];
        let mut file = vec![mm::MASK_AND_NO_INACTIVE_VALS];
        file.extend((1u64 << 40).to_le_bytes());
        file.extend((zipped.len() as i64).to_le_bytes());
        file.extend(&zipped);
        file.push(mm::NO_MASK_AND_ALL_VALS);
        let all: Vec<u8> = (0..64).flat_map(|i| (i as f32).to_le_bytes()).collect();
        file.extend((-(all.len() as i64)).to_le_bytes());
        file.extend(&all);
        let c_ = chunks(COMPRESS_ZIP | COMPRESS_ACTIVE_MASK);
        let mut c = Cursor::new(&file);
        let got = c_.values(&mut c, 64, &mask).unwrap();
        assert_eq!(&got[..8], &values[..]);
        assert!(got[8..40].iter().all(|&v| v == -3.0));
        assert!(got[40..41].iter().all(|&v| v == 3.0));
        let got = c_.values(&mut c, 64, &mask).unwrap();
        assert_eq!(got, (0..64).map(|i| i as f32).collect::<Vec<_>>());
        assert_eq!(c.remaining(), 0);
        // A chunk that inflates to the wrong size, and garbage, are errors.
        let mut bad = vec![mm::NO_MASK_AND_ALL_VALS];
        bad.extend((zipped.len() as i64).to_le_bytes());
        bad.extend(&zipped);
        let e = c_.values(&mut Cursor::new(&bad), 64, &mask).unwrap_err();
        assert!(e.contains("inflates to 32 bytes where 256"), "{e}");
        let mut bad = vec![mm::NO_MASK_OR_INACTIVE_VALS];
        bad.extend(8i64.to_le_bytes());
        bad.extend([0x78, 0x9c, 1, 2, 3, 4, 5, 6]);
        assert!(c_.values(&mut Cursor::new(&bad), 64, &mask).is_err());
    }
}
