//! Coefficient volumes: one coefficient per grid node of a compactly supported basis, the field
//! being their weighted sum. Smooth, O(1) to evaluate, with exact analytic gradients and
//! Hessians; coefficients from node samples or fitted to a signed distance function.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

pub mod analytic;
pub mod basis;
mod distance;
pub mod fit;
pub mod kernel;
pub mod prefilter;
mod stencil;
pub mod volume;

pub use basis::Basis;
pub use fit::{
    fit, interp_sparse_groups, sparse_reach, wls_band, ClosestFn, ClosestPoint, FitMethod,
    FitOptions, FitReport, LayerBricks, SignedDistance, MAX_Z_STEP, SPARSE_GROUP,
};
pub use kernel::{Jet, Kernel};
pub use pgvol_core::grid::{Grid, MAX_GRID_NODES};
pub use stencil::mirror;
pub use volume::{CoefficientVolume, FieldError};
