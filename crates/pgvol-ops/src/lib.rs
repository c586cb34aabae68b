//! Operations for additive manufacturing on coefficient volumes.
//!
//! * [`slice`] / [`slice_volume`]: cut a field into planar layers of closed, simple, oriented
//!   contours (marching squares on the continuous field, then bounded-error simplification).
//! * [`write_svg`], [`write_cli`], [`write_slice_json`]: layer files for viewing, for build
//!   processors (Common Layer Interface, ASCII or binary with [`write_cli_with`]) and for
//!   scripts.
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
mod cli_file;
mod cli_read;
mod csg;
mod error;
mod lattice;
mod layer_frame;
mod local_fit;
mod measure;
mod polygon;
mod repair;
mod simplify;
mod slice;
mod svg_read;
mod write;

pub use blend::{
    check_ipatch, check_spline, edge_blend, fit_ipatch_weights, functional_spline, ipatch,
    ipatch_terms, liming, renormalised, weight_through_point, Continuity, MAX_CONTINUITY,
};
pub use booleans::{check_blend, combine, intersection, sample_bricks, union, Blend, BoolOp};
pub use cli_file::{write_cli, write_cli_in, write_cli_with, CliEncoding, MAX_BINARY_ROUNDING};
pub use cli_read::read_cli;
pub use csg::{
    hollow, needs_wider_band, offset, shell, stored_band, support_reach, Drain, ShellSide,
};
pub use error::OpsError;
pub use lattice::{
    infill, lattice_bricks, lattice_part, Grade, Lattice, LatticeSolid, LatticeStyle, Ramp, Tpms,
    TPMS_NAMES,
};
pub use layer_frame::{layer_coordinate_problem, LayerFrame, MAX_LAYER_COORDINATE};
pub use local_fit::{node_value, refit_box, LocalFit, NodeBox};
pub use measure::{measure_field, FieldMeasure};
pub use repair::{
    coarse_lattice, mask_nodes, repair, Face, LaplaceSystem, Mask, MaskReport, Restore,
    MAX_MASK_NODES,
};
pub use simplify::simplify_loops;
pub use slice::{
    brick_counts, layer_heights, plane_axes, slice, slice_bricks, slice_volume, slice_volume_range,
    volume_bounds, Axis, BrickLayer, BrickRef, BrickSource, Layer, LayerCost, Loop, SliceOptions,
    INSIDE, MAX_LAYERS, MAX_LAYER_NODES, OUTSIDE,
};
pub use svg_read::read_svg;
pub use write::{read_slice_json, write_slice_json, write_slice_json_in, write_svg, write_svg_in};
