//! Integration tests of the marching cubes contouring.

mod ambiguous;
mod determinism;
mod grids;
mod random_fields;
mod shapes;
mod single_cell;
mod topology;
