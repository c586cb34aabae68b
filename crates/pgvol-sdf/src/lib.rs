//! Signed distance from triangle meshes.
//!
//! Distances are exact (closest point on the nearest triangle, found through a BVH); the sign
//! comes from the generalized winding number, which stays meaningful on open, flipped or
//! self-intersecting meshes. Negative inside, positive outside, in the mesh's units.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

mod bvh;
mod bvh_build;
#[cfg(test)]
mod consistency;
mod lanes;
mod leaf_bounds;
mod pseudonormal;
mod rims;
pub mod sampling;
mod sdf;
pub mod triangle;
mod wide;
pub mod winding;

pub use bvh::{Bvh, Closest, SegmentHit};
pub use grid::{Grid, GridError};
pub use pgvol_core::grid;
pub use sdf::{MeshSdf, SdfError, SignMode};
pub use winding::WindingTree;
