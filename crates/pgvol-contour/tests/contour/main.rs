//! Integration tests of the contouring methods.

mod ambiguous;
mod dc_features;
mod determinism;
mod dual_topology;
mod fields;
mod grids;
mod nets;
mod random_fields;
mod reference_mc;
mod shapes;
mod single_cell;
mod sparse_volumes;
mod topology;
