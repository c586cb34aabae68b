//! Editing of coefficient volumes: new fields made from a field or from several.
//!
//! * [`offset`], [`shell`], [`hollow`]: new coefficient volumes from constructive operations on
//!   the field, with [`needs_wider_band`] telling when a narrow-band field cannot support them.
//! * [`lattice_part`], [`infill`]: triply periodic lattices ([`Lattice`], [`Tpms`]) cut to a part
//!   or filling a hollowed part's cavity, with drain holes through both.
//! * [`combine`], [`sample_bricks`]: sharp and rounded Booleans of fields, re-fitted brick by
//!   brick into one coefficient volume.
//! * [`liming`], [`functional_spline`], [`ipatch`]: algebraic blends between primaries, with
//!   [`renormalised`] making them distance-like again.
//! * [`repair`]: protrusion removal and denoising inside masks, re-fitting only the
//!   coefficients whose support meets a mask.
//!
//! Conventions are the workspace's: fields are negative inside, units are those of the mesh.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]
#![forbid(unsafe_code)]

mod blend;
mod booleans;
mod csg;
mod error;
mod lattice;
mod local_fit;
mod measure;
mod remap;
mod repair;

pub use blend::{
    check_ipatch, check_spline, edge_blend, fit_ipatch_weights, functional_spline, ipatch,
    ipatch_terms, liming, renormalised, weight_through_point, Continuity, MAX_CONTINUITY,
};
pub use booleans::{check_blend, combine, intersection, sample_bricks, union, Blend, BoolOp};
pub use csg::{
    hollow, needs_wider_band, offset, shell, stored_band, support_reach, Drain, ShellSide,
};
pub use error::OpsError;
pub use lattice::{
    infill, lattice_bricks, lattice_part, Grade, Lattice, LatticeSolid, LatticeStyle, Ramp, Tpms,
    TPMS_NAMES,
};
pub use local_fit::{node_value, refit_box, LocalFit, NodeBox};
pub use measure::{measure_field, FieldMeasure};
pub use repair::{
    coarse_lattice, mask_nodes, repair, Face, LaplaceSystem, Mask, MaskReport, Restore,
    MAX_MASK_NODES,
};
