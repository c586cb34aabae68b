//! Conformance: one suite per trait of the pipeline, run against every implementor, so that a
//! new basis or a new field is held to the same contract as the others.
//!
//! - `field`: `pgvol_contour::Field` (coefficient volumes in five bases, the facade's exact
//!   mesh field, closures);
//! - `signed_distance`: `pgvol_field::fit::SignedDistance` (the facade's mesh distance, the
//!   analytic solids, closures), with the mesh distance's grid sampling;
//! - `closest_point`: `pgvol_field::fit::ClosestPoint`;
//! - `kernel`: `pgvol_field::Kernel`, the basis functions;
//! - `volume`: the coefficient volume in every basis: its kernels, evaluation paths and batch
//!   calls.
//!
//! The field properties are written once (`properties`); each trait's suite runs them through
//! that trait's methods. Shapes and bounds are in `subjects`.

mod closest_point;
mod field;
mod kernel;
mod properties;
mod signed_distance;
mod subjects;
mod support;
mod volume;
