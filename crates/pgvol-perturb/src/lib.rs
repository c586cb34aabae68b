//! Implicit surfaces from meshes by quadric perturbations (Vyatkin, Romanyuk and Velichko):
//! `M(x) = F(x) + Σ fᵢ Qᵢ(x)³` over `Qᵢ ≥ 0`, a base quadric plus local bumps added until the
//! mesh's vertices lie on the zero set. See `docs/perturbation.md`.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

mod box_tree;
mod build;
mod cleanup;
mod descent;
mod field;
mod point_grid;
pub mod quadric;
mod resample;
mod strays;
mod trial;

pub use box_tree::BoxTree;
pub use build::{
    build, PerturbError, PerturbOptions, PerturbReport, Refusals, StopReason, DESCENT_STEPS,
    MAX_PEAK_RATIO, MAX_REACH, POINTS_PER_TERM, PROBE_EDGES, RADIUS_EDGES, TRIAL_RADII,
};
pub use cleanup::{clear_points, Cleanup};
pub use field::{Perturbation, PerturbationError, PerturbationField};
pub use quadric::Quadric;
pub use resample::sample_band;
pub use strays::{
    clear_strays, stray_nodes, Strays, STRAY_AGAINST_RADIUS, STRAY_MIN_MARGIN, STRAY_MIN_RADIUS,
};
