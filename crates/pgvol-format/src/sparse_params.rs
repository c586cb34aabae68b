//! The `sparse-bricks` encoding's parameters as the header stores them: how values are quantised,
//! predicted and compressed, how the grid is cut into bricks, and the value of unstored bricks.

use serde::{Deserialize, Serialize};

use crate::fixed_step::FixedScale;

/// The header's `encoding` for this payload.
pub const ENCODING_SPARSE: &str = "sparse-bricks";

/// Brick edges accepted by the reader; 32³ nodes × 4 bytes bounds every decompression buffer.
pub const BRICK_RANGE: std::ops::RangeInclusive<usize> = 2..=32;

/// How stored coefficients are quantised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// IEEE binary32: bit-exact.
    F32,
    /// IEEE binary16 (round to nearest even).
    F16,
    /// 16-bit fixed point with a per-brick offset and scale.
    Q16,
    /// Signed 32-bit integer words on one scale for the whole file (`SparseParams::fixed`):
    /// steps tied to the grid spacing, fine near the surface and coarser far from it.
    Fixed,
}

impl Precision {
    pub const ALL: [Precision; 4] = [
        Precision::F32,
        Precision::F16,
        Precision::Q16,
        Precision::Fixed,
    ];

    /// Bytes per quantised value before compression.
    pub fn width(self) -> usize {
        match self {
            Precision::F32 | Precision::Fixed => 4,
            Precision::F16 | Precision::Q16 => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
            Precision::Q16 => "q16",
            Precision::Fixed => "fixed",
        }
    }
}

/// How each quantised value is predicted from its already decoded neighbours in the brick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Predictor {
    /// No prediction: the residual is the value.
    None,
    /// The previous value along x; a row's first value from the row before, a slice's first from
    /// the slice before.
    DeltaX,
    /// The 3-D Lorenzo predictor (parallelogram rule over the 7 lower neighbours; neighbours
    /// outside the brick count as 0).
    Lorenzo,
}

/// How each brick's bytes are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    None,
    /// One zstd frame per brick.
    Zstd,
}

/// The header's `sparse` object: everything needed to parse the payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseParams {
    /// Brick edge in nodes.
    pub brick: usize,
    /// Bricks per axis: `ceil(dims / brick)`.
    pub bricks: [usize; 3],
    /// Number of stored bricks.
    pub stored: usize,
    pub precision: Precision,
    pub predictor: Predictor,
    /// Whether residual bytes are grouped by significance (byte planes).
    pub shuffle: bool,
    pub compression: Compression,
    /// Magnitude of every coefficient of an unstored brick.
    pub clamp: f32,
    /// The band (grid spacings) the encoder kept; informative only.
    pub band: f32,
    /// With `fixed` precision (and only then): the scale of its words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed: Option<FixedScale>,
}
