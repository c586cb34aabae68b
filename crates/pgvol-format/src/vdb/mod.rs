//! OpenVDB `.vdb` files: the facts of the format shared by its writer and reader. The layout is
//! described in `docs/format.md` ("OpenVDB .vdb files").
//!
//! Values from OpenVDB's file format (`openvdb/io`, `openvdb/tree`): a file header, grid
//! descriptors, then per grid its metadata, transform and a 5-4-3 tree (a root table of
//! 32³-child internal nodes, each holding 16³-child internal nodes, each holding 8³-voxel
//! leaves), topology first and leaf buffers after. Everything is little-endian.

pub mod blosc;
pub mod read;
pub mod write;

/// The magic number every `.vdb` file starts with, as a little-endian 64-bit integer
/// (`OPENVDB_MAGIC`).
pub const MAGIC: u64 = 0x5644_4220;

/// The file version OpenVDB 6 to 12 write (`OPENVDB_FILE_VERSION`, multipass I/O).
pub const FILE_VERSION: u32 = 224;

/// The first file version with per-grid compression flags and per-node mask metadata
/// (`OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION`).
pub const FILE_VERSION_NODE_MASK_COMPRESSION: u32 = 222;

/// The library version written in the header: the OpenVDB release whose files these match.
pub const LIBRARY_VERSION: (u32, u32) = (10, 0);

/// Log2 of the edge, in children, of a leaf (voxels), a lower internal node (16³ leaves) and
/// an upper internal node (32³ lower nodes): the standard `Tree_float_5_4_3` configuration.
pub const LEAF_LOG2: u32 = 3;
pub const LOWER_LOG2: u32 = 4;
pub const UPPER_LOG2: u32 = 5;

/// Voxels along a leaf's edge and in a leaf.
pub const LEAF_EDGE: usize = 1 << LEAF_LOG2;
pub const LEAF_VOXELS: usize = 1 << (3 * LEAF_LOG2);

/// Grid type name of a float tree of this configuration, and the suffix a grid type takes when
/// its values are stored as 16-bit floats.
pub const FLOAT_TREE: &str = "Tree_float_5_4_3";
pub const HALF_FLOAT_SUFFIX: &str = "_HalfFloat";

/// The `class` metadata value of a level set.
pub const LEVEL_SET_CLASS: &str = "level set";

/// Transform types: the one written, and the other one read.
pub const UNIFORM_SCALE_TRANSLATE_MAP: &str = "UniformScaleTranslateMap";
pub const UNIFORM_SCALE_MAP: &str = "UniformScaleMap";

/// Per-grid compression flags (`io::COMPRESS_*`).
pub const COMPRESS_ZIP: u32 = 0x1;
pub const COMPRESS_ACTIVE_MASK: u32 = 0x2;
pub const COMPRESS_BLOSC: u32 = 0x4;

/// The metadata byte before each node's values: which inactive values the node holds and
/// whether only its active values are stored (`io::NO_MASK_OR_INACTIVE_VALS`, ...).
pub mod mask_metadata {
    /// Inactive values are all +background.
    pub const NO_MASK_OR_INACTIVE_VALS: u8 = 0;
    /// Inactive values are all −background.
    pub const NO_MASK_AND_MINUS_BG: u8 = 1;
    /// Inactive values are all one stored value.
    pub const NO_MASK_AND_ONE_INACTIVE_VAL: u8 = 2;
    /// Inactive values are ±background, chosen by a selection mask.
    pub const MASK_AND_NO_INACTIVE_VALS: u8 = 3;
    /// Inactive values are background or one stored value, chosen by a selection mask.
    pub const MASK_AND_ONE_INACTIVE_VAL: u8 = 4;
    /// Inactive values are one of two stored values, chosen by a selection mask.
    pub const MASK_AND_TWO_INACTIVE_VALS: u8 = 5;
    /// Every value is stored, active or not.
    pub const NO_MASK_AND_ALL_VALS: u8 = 6;
}

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
