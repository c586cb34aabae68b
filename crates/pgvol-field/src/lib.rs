//! Coefficient volumes: one coefficient per grid node of a compactly supported basis, the field
//! being their weighted sum. Smooth, O(1) to evaluate, with exact analytic gradients.

pub mod basis;
pub mod prefilter;
pub mod volume;

pub use basis::Basis;
pub use pgvol_sdf::grid::{Grid, MAX_GRID_NODES};
pub use volume::{CoefficientVolume, FieldError};
