//! OpenVDB `.vdb` files: the facts a reader and a writer share. The layout is described in
//! `docs/format.md` ("OpenVDB .vdb files").

pub mod blosc;
pub mod read;

/// The magic number every `.vdb` file starts with, as a little-endian 64-bit integer.
pub const MAGIC: u64 = 0x5644_4220;

/// The file version OpenVDB 10 writes (`OPENVDB_FILE_VERSION_MULTIPASS_IO`).
pub const FILE_VERSION: u32 = 224;

/// The first file version with per-grid compression flags and per-node mask metadata
/// (`OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION`).
pub const FILE_VERSION_NODE_MASK_COMPRESSION: u32 = 222;

/// Log2 of the edge, in voxels, of a leaf node, of an internal node's child and of a root
/// child: the standard `Tree_float_5_4_3` configuration.
pub const LEAF_LOG2: u32 = 3;
/// Log2 of the edge, in children, of the lower internal node (16³ leaves).
pub const INTERNAL1_LOG2: u32 = 4;
/// Log2 of the edge, in children, of the upper internal node (32³ lower nodes).
pub const INTERNAL2_LOG2: u32 = 5;

/// Grid type name of a float tree of this configuration.
pub const FLOAT_TREE: &str = "Tree_float_5_4_3";
/// Suffix a grid type name carries when its values are stored as 16-bit floats.
pub const HALF_FLOAT_SUFFIX: &str = "_HalfFloat";
/// The `class` metadata value of a level set.
pub const LEVEL_SET_CLASS: &str = "level set";

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
