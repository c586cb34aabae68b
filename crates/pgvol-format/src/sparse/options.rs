//! What the encoder is asked for, and what it reports.

use crate::fixed_step::{FIXED_KNEE, FIXED_RATIO, FIXED_STEP, FREE_TOLERANCE};
use crate::sparse_params::{Compression, Precision, Predictor};

/// Choices for [`encode_pgv_with`](super::encode_pgv_with).
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeOptions {
    /// `None`: the smallest of q16, f16 and fixed within
    /// [`AUTO_TOLERANCE`](super::AUTO_TOLERANCE), else f32.
    pub precision: Option<Precision>,
    /// A brick is stored if the field at any node within the basis support of its nodes is
    /// within `band` grid spacings of zero.
    pub band: f32,
    /// Brick edge in nodes (in [`BRICK_RANGE`](super::BRICK_RANGE)).
    pub brick: usize,
    pub predictor: Predictor,
    pub shuffle: bool,
    pub compression: Compression,
    pub zstd_level: i32,
    /// The `fixed` precision's fine step, in grid spacings (divided by the basis weight bound).
    pub fixed_step: f32,
    /// The magnitude, in grid spacings, up to which `fixed` uses the fine step.
    pub fixed_knee: f32,
    /// The coarse step beyond the knee, in fine steps.
    pub fixed_ratio: u32,
    /// With `fixed`: how far (grid spacings) a stored coefficient that no point within the band
    /// reaches may move towards its prediction; 0 keeps every coefficient within half a step.
    pub free_tolerance: f32,
}

impl Default for EncodeOptions {
    /// The best measured settings (`docs/format.md`, "Measurements").
    fn default() -> Self {
        EncodeOptions {
            precision: None,
            band: 3.0,
            brick: 16,
            predictor: Predictor::DeltaX,
            shuffle: true,
            compression: Compression::Zstd,
            zstd_level: 6,
            fixed_step: FIXED_STEP,
            fixed_knee: FIXED_KNEE,
            fixed_ratio: FIXED_RATIO,
            free_tolerance: FREE_TOLERANCE,
        }
    }
}

/// What an encode produced. The four byte counts add up to the file size.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodeReport {
    pub bricks_total: usize,
    pub bricks_stored: usize,
    /// Container framing and JSON header: magic, version, lengths, header, both CRCs.
    pub bytes_header: usize,
    /// Bitmaps, index and index CRC.
    pub bytes_index: usize,
    /// Brick blobs.
    pub bytes_payload: usize,
    pub precision: Precision,
    /// Largest |decoded − original| over stored coefficients (field units).
    pub max_quantisation_error: f32,
    /// Magnitude given to unstored bricks.
    pub clamp: f32,
}

impl EncodeOptions {
    /// An error naming the first option a writer cannot use.
    pub(crate) fn check(&self) -> Result<(), String> {
        if !crate::sparse_params::BRICK_RANGE.contains(&self.brick) {
            return Err(format!(
                "brick edge {} is outside {:?}",
                self.brick,
                crate::sparse_params::BRICK_RANGE
            ));
        }
        if !(self.band.is_finite() && self.band >= 0.0) {
            return Err(format!("band {} must be finite and >= 0", self.band));
        }
        Ok(())
    }
}
