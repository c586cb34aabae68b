//! Operations for additive manufacturing on coefficient volumes.
//!
//! * [`slice`] / [`slice_volume`]: cut a field into planar layers of closed, simple, oriented
//!   contours (marching squares on the continuous field, then bounded-error simplification).
//! * [`write_svg`], [`write_cli`], [`write_slice_json`]: layer files for viewing, for build
//!   processors (Common Layer Interface, ASCII or binary with [`write_cli_with`]) and for
//!   scripts.
//! * [`offset`], [`shell`], [`hollow`]: new coefficient volumes from constructive operations on
//!   the field, with [`needs_wider_band`] telling when a narrow-band field cannot support them.
//!
//! Conventions are the workspace's: fields are negative inside, units are those of the mesh.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]
#![forbid(unsafe_code)]

mod cli_file;
mod cli_read;
mod csg;
mod error;
mod polygon;
mod simplify;
mod slice;
mod svg_read;
mod write;

pub use cli_file::{write_cli, write_cli_with, CliEncoding};
pub use cli_read::read_cli;
pub use csg::{
    hollow, needs_wider_band, offset, shell, stored_band, support_reach, Drain, ShellSide,
};
pub use error::OpsError;
pub use simplify::simplify_loops;
pub use slice::{
    layer_heights, slice, slice_volume, volume_bounds, Axis, Layer, Loop, SliceOptions, MAX_LAYERS,
    MAX_LAYER_NODES,
};
pub use svg_read::read_svg;
pub use write::{read_slice_json, write_slice_json, write_svg};
