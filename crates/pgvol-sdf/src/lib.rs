//! Signed distance from triangle meshes.
//!
//! Distances are exact (closest point on the nearest triangle, found through a BVH); the sign
//! comes from the generalized winding number, which stays meaningful on open, flipped or
//! self-intersecting meshes. Negative inside, positive outside, in the mesh's units.

pub mod bvh;
pub mod consistency;
pub use pgvol_core::grid;
pub mod lanes;
pub mod leaf_bounds;
pub mod pseudonormal;
pub mod rims;
pub mod sampling;
pub mod triangle;
mod wide;
pub mod winding;

pub use bvh::{Bvh, Closest};
pub use grid::{Grid, GridError};
pub use winding::WindingTree;
pub mod sdf;
pub use sdf::{MeshSdf, SdfError, SignMode};
