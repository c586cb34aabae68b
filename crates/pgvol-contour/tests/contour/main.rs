//! Integration tests of the contouring methods.

mod ambiguous;
mod dc_features;
mod dc_topology;
mod determinism;
mod fields;
mod grids;
mod nets;
mod random_fields;
mod shapes;
mod single_cell;
mod topology;
