//! The error of slicing and of the layer files.

/// Why a slice could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SliceError {
    #[error("invalid parameter: {0}")]
    BadParameter(String),
    /// The caller's interrupt asked the slicing to stop.
    #[error("stopped on request")]
    Stopped,
}
