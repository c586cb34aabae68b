//! The error of every operation.

/// Why an operation could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OpsError {
    #[error("invalid parameter: {0}")]
    BadParameter(String),
    #[error(transparent)]
    Field(#[from] pgvol_field::FieldError),
}
