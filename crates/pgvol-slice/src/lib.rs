//! Slicing for additive manufacturing: a field cut into planar layers, and the layer files.
//!
//! * [`slice`] / [`slice_volume`]: cut a field into planar layers of closed, simple, oriented
//!   contours (marching squares on the continuous field, then bounded-error simplification);
//!   [`slice_bricks`] slices a volume whose bricks come a slab at a time from a [`BrickSource`].
//! * [`write_svg`], [`write_cli`], [`write_slice_json`]: layer files for viewing, for build
//!   processors (Common Layer Interface, ASCII or binary with [`write_cli_with`]) and for
//!   scripts; [`read_svg`], [`read_cli`] and [`read_slice_json`] read them back.
//! * [`LayerFrame`]: the world translation of layers cut in a far shape's local frame, applied
//!   when their files are written.
//!
//! Conventions are the workspace's: fields are negative inside, units are those of the mesh.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]
#![forbid(unsafe_code)]

mod cli_file;
mod cli_read;
mod error;
mod layer_frame;
mod polygon;
mod simplify;
mod slice;
mod svg_read;
mod write;

pub use cli_file::{write_cli, write_cli_in, write_cli_with, CliEncoding, MAX_BINARY_ROUNDING};
pub use cli_read::read_cli;
pub use error::SliceError;
pub use layer_frame::{layer_coordinate_problem, LayerFrame, MAX_LAYER_COORDINATE};
pub use simplify::simplify_loops;
pub use slice::{
    brick_counts, layer_heights, plane_axes, slice, slice_bricks, slice_volume, slice_volume_range,
    volume_bounds, Axis, BrickLayer, BrickRef, BrickSource, Layer, LayerCost, LayerRanges, Loop,
    SliceOptions, INSIDE, MAX_LAYERS, MAX_LAYER_NODES, OUTSIDE,
};
pub use svg_read::read_svg;
pub use write::{read_slice_json, write_slice_json, write_slice_json_in, write_svg, write_svg_in};
