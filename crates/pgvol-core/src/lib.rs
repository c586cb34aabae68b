//! The types every pgvol stage shares, with no file formats, no BVH and no solver behind them:
//! the sampling [`Grid`], the triangle [`Mesh`], atomic file replacement and the error that names
//! a file and what is wrong with it. Reading a `.pgv` file needs nothing more than this.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]
// Unsafe code only where a kernel's AVX2 build is entered, after the CPU check, and in the
// one call that hands freed memory back to the system.
#![deny(unsafe_code)]

pub mod atomic;
pub mod base64;
#[allow(unsafe_code)]
pub mod cpu;
pub mod file_error;
pub mod frame;
pub mod grid;
#[allow(unsafe_code)]
pub mod heap;
pub mod input;
pub mod mesh;
pub mod per_thread;
pub mod progress;
pub mod sparse;
pub mod word_scale;

pub use atomic::write_atomic;
pub use file_error::FileError;
pub use grid::{Grid, GridError, GRID_MARGIN, MAX_GRID_NODES};
pub use input::read_input;
pub use mesh::stats::MeshStats;
pub use mesh::Mesh;
pub use per_thread::PerThread;
pub use sparse::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};
pub use word_scale::WordScale;
