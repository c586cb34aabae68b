//! Marching cubes on a grid of samples: vertices on grid edges, placed linearly, by the caller,
//! or on the zero set of a continuous field.

use glam::Vec3;
use pgvol_core::Mesh;
use rayon::prelude::*;

use crate::crossings::{all_crossings, Place, Refine};
use crate::extract::{block_triangles, Part, EXTRA_FLAG};
use crate::field::Field;
use crate::place;
use crate::root::cubic_edge_root;
use crate::samples::CROSSINGS_PART;
use crate::samples::{DenseNodes, Samples};
use pgvol_core::progress::{stopped, tick};

/// Extracts the surface `value == iso` of a grid of samples, placing each vertex on its grid edge
/// by linear interpolation of the two node values.
///
/// `values` is indexed x fastest, `values[i + dims[0] * (j + dims[1] * k)]` being the sample at
/// `origin + spacing * (i, j, k)`. See the crate documentation for the guarantees on the result.
///
/// # Panics
///
/// If `values.len()` does not match `dims`, if `spacing` is not positive and finite, or if the
/// mesh would need more than 2^31 vertices.
pub fn marching_cubes(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
) -> Mesh {
    let linear = move |a, va, b, vb| place::lerp_crossing(a, va, b, vb, iso);
    marching_cubes_with(values, dims, origin, spacing, iso, &linear)
}

/// Like [`marching_cubes`], but places each vertex with `refine(a, va, b, vb)`, where `a` and `b`
/// are the lower and upper grid nodes of a crossed edge (differing along one axis) and `va`, `vb`
/// their values, which straddle iso (one `< iso`, the other `>= iso` or NaN). This lets a caller
/// with a continuous field find the crossing by root finding.
///
/// The returned point is projected onto the edge and kept a 1e-4 fraction of the edge away from
/// both nodes (a non-finite result falls back to the midpoint); that margin is what keeps the
/// triangles non-degenerate. `refine` runs once per crossed edge, from several threads.
///
/// # Panics
///
/// As [`marching_cubes`].
pub fn marching_cubes_with(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    refine: &(dyn Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync),
) -> Mesh {
    let nodes = DenseNodes::new(values, dims);
    match Samples::checked(&nodes, origin, spacing, iso) {
        Some(samples) => marching_cubes_samples(&samples, refine),
        None => Mesh::default(),
    }
}

/// [`marching_cubes_with`] on any source of samples.
pub(crate) fn marching_cubes_samples(samples: &Samples, refine: &Refine) -> Mesh {
    let crossings = all_crossings(samples, Place::Position(refine), EXTRA_FLAG);
    let blocks = crossings.blocks.active.len();
    let counter = samples.counter(CROSSINGS_PART, 1.0, blocks);
    let parts: Vec<Part> = (0..blocks)
        .into_par_iter()
        .map(|slot| {
            // A stopped stage's result is dropped by its caller: blocks after the stop are left
            // empty.
            if stopped(counter.as_ref()) {
                return Part::default();
            }
            tick(counter.as_ref());
            block_triangles(&crossings, samples.iso, slot)
        })
        .collect();
    assemble(crossings.positions, parts)
}

/// Like [`marching_cubes`], but places each vertex on the zero set of the continuous `field`
/// (whose node values `values` are) along its grid edge: the root of the cubic through the two
/// node values and the field at the edge's third points, two evaluations per vertex, exact for
/// a cubic B-spline field on its own grid. Non-finite samples fall back to regula falsi.
///
/// # Panics
///
/// As [`marching_cubes`].
pub fn marching_cubes_on_field(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
) -> Mesh {
    let refine = |a, va, b, vb| cubic_edge_root(field, a, va, b, vb, iso);
    marching_cubes_with(values, dims, origin, spacing, iso, &refine)
}

/// Concatenates the blocks' triangles in order, giving loop centre vertices their places after
/// the edge vertices.
fn assemble(mut positions: Vec<Vec3>, parts: Vec<Part>) -> Mesh {
    let n_triangles = parts.iter().map(|s| s.triangles.len()).sum();
    let mut triangles = Vec::with_capacity(n_triangles);
    for part in parts {
        let first = positions.len() as u32;
        assert!(
            first as usize + part.extra.len() < EXTRA_FLAG as usize,
            "too many vertices"
        );
        if part.extra.is_empty() {
            triangles.extend_from_slice(&part.triangles);
        } else {
            let resolve = |v: u32| {
                if v & EXTRA_FLAG != 0 {
                    first + (v & !EXTRA_FLAG)
                } else {
                    v
                }
            };
            triangles.extend(part.triangles.iter().map(|t| t.map(resolve)));
        }
        positions.extend_from_slice(&part.extra);
    }
    Mesh::new(positions, triangles)
}
