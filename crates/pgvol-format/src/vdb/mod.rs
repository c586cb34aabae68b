//! OpenVDB `.vdb` files: the facts of the format shared by its writer and reader.
//!
//! Values from OpenVDB's file format (`openvdb/io`, `openvdb/tree`): a file header, grid
//! descriptors, then per grid its metadata, transform and a 5-4-3 tree (a root table of
//! 32³-child internal nodes, each holding 16³-child internal nodes, each holding 8³-voxel
//! leaves), topology first and leaf buffers after. Everything is little-endian.

pub mod write;

/// The first 8 bytes of every `.vdb` file (`OPENVDB_MAGIC`, as an i64).
pub const MAGIC: i64 = 0x5644_4220;

/// The file format version OpenVDB 6 to 12 write (`OPENVDB_FILE_VERSION`).
pub const FILE_VERSION: u32 = 224;

/// The library version written in the header: the OpenVDB release whose files these match.
pub const LIBRARY_VERSION: (u32, u32) = (10, 0);

/// log2 of the edge, in children, of a leaf (voxels), a lower and an upper internal node.
pub const LEAF_LOG2: u32 = 3;
pub const LOWER_LOG2: u32 = 4;
pub const UPPER_LOG2: u32 = 5;

/// Voxels along a leaf's edge and in a leaf.
pub const LEAF_EDGE: usize = 1 << LEAF_LOG2;
pub const LEAF_VOXELS: usize = 1 << (3 * LEAF_LOG2);

/// The tree type of a float grid with this configuration, and the suffix a grid type takes
/// when its values are stored as half floats.
pub const TREE_FLOAT_543: &str = "Tree_float_5_4_3";
pub const HALF_FLOAT_SUFFIX: &str = "_HalfFloat";

/// Grid compression flags (`io::COMPRESS_*`).
pub const COMPRESS_ZIP: u32 = 0x1;
pub const COMPRESS_ACTIVE_MASK: u32 = 0x2;
pub const COMPRESS_BLOSC: u32 = 0x4;

/// Per-node tags saying which inactive values a mask-compressed chunk leaves out
/// (`io::NO_MASK_OR_INACTIVE_VALS` ...).
pub const NO_MASK_OR_INACTIVE_VALS: u8 = 0;
pub const NO_MASK_AND_MINUS_BG: u8 = 1;
pub const NO_MASK_AND_ONE_INACTIVE_VAL: u8 = 2;
pub const MASK_AND_NO_INACTIVE_VALS: u8 = 3;
pub const MASK_AND_ONE_INACTIVE_VAL: u8 = 4;
pub const MASK_AND_TWO_INACTIVE_VALS: u8 = 5;
pub const NO_MASK_AND_ALL_VALS: u8 = 6;

/// The transform type written, and the grid class metadata value of level sets.
pub const UNIFORM_SCALE_TRANSLATE_MAP: &str = "UniformScaleTranslateMap";
pub const UNIFORM_SCALE_MAP: &str = "UniformScaleMap";
pub const CLASS_LEVEL_SET: &str = "level set";

/// Offset of voxel (or child) `(x, y, z)`, each below `1 << log2`, in a node's value array: z
/// varies fastest.
pub fn node_offset(log2: u32, [x, y, z]: [usize; 3]) -> usize {
    (x << (2 * log2)) | (y << log2) | z
}

/// An index-to-world map that scales by `voxel_size` on every axis then translates: voxel
/// `(i, j, k)` is centred at `translation + voxel_size · (i, j, k)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformScaleTranslate {
    pub voxel_size: f64,
    pub translation: [f64; 3],
}
