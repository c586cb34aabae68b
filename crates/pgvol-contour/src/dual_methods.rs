//! Dual contouring and surface nets on a grid of samples: the two placements of the vertices of
//! the dual mesh that `dual` builds.

use glam::Vec3;
use pgvol_core::Mesh;

use crate::cell_set::edge_touches;
use crate::crossings::{all_crossings, with_normal, Place, PlaceWithNormal, Refine};
use crate::dual::{self, CellKeep, DualMesh, Placement};
use crate::dual_options::{DualContourOptions, StoredVertices};
use crate::extract::EXTRA_FLAG;
use crate::field::Field;
use crate::place::lerp_crossing;
use crate::root::cubic_edge_root;
use crate::samples::{DenseNodes, Samples};

/// Extracts the surface `value == iso` by dual contouring: one vertex per surface component of
/// each cell, placed by the tangent planes of the continuous `field`, so sharp edges and corners
/// are reproduced rather than chamfered.
///
/// `values` are the samples of `field` at the grid nodes, laid out as for [`marching_cubes`];
/// they decide the topology (inside is `< iso`, NaN outside, ambiguous faces by the asymptotic
/// decider), and `field` only places vertices: edge crossings as in
/// [`marching_cubes_on_field`], their normals from `field.value_gradient`, and each component's
/// vertex by a truncated least-squares fit (QEF) about the crossings' mass point, refined as
/// described at [`DualContourOptions`].
///
/// Guarantees, for every input, wherever the inside region stays away from the grid border:
///
/// * **Watertight, manifold and oriented**: the mesh is the dual of the [`marching_cubes`]
///   surface (same loops, same decider), so every edge has exactly two triangles, traversed
///   once in each direction, the triangles around every vertex form one disk, and normals point
///   towards increasing values. The rare doubled dual edge (a tunnel through one face) gets a
///   midpoint vertex so this holds for the indexed triangle mesh too.
/// * **Non-degenerate** with `clamp_to_cell`: every triangle has positive area.
/// * **Deterministic**: identical output for any number of threads.
///
/// Without `clamp_to_cell` the topology is the same but vertices may leave their cells, so
/// triangles can fold over or degenerate.
///
/// # Panics
///
/// As [`marching_cubes`].
///
/// [`marching_cubes`]: crate::marching_cubes
/// [`marching_cubes_on_field`]: crate::marching_cubes_on_field
pub fn dual_contour(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
    options: &DualContourOptions,
) -> Mesh {
    let place = |a, va, b, vb, axis| {
        let p = cubic_edge_root(field, a, va, b, vb, iso);
        with_normal(a, b, axis, p, |p| field.value_gradient(p).1)
    };
    let nodes = DenseNodes::new(values, dims);
    match Samples::checked(&nodes, origin, spacing, iso) {
        Some(samples) => {
            dual_contour_with(&samples, field, options, &place, None, false, None).mesh
        }
        None => Mesh::default(),
    }
}

/// [`dual_contour`] on any source of samples, with the edge crossings and their normals from
/// `place`, and the vertices of the cells `stored` gives taken from it; each vertex's cell too
/// when `with_homes`. With `only` (cells named by their lowest sample), just those cells'
/// vertices come out, with their cells and no triangles: the other edges get no crossing
/// placed, the other cells no vertex.
pub(crate) fn dual_contour_with(
    samples: &Samples,
    field: &dyn Field,
    options: &DualContourOptions,
    place: &PlaceWithNormal,
    stored: Option<&StoredVertices>,
    with_homes: bool,
    only: Option<&CellKeep>,
) -> DualMesh {
    let Some(keep) = only else {
        let crossings = all_crossings(samples, Place::WithNormal(place), EXTRA_FLAG);
        let placement = Placement::Planes(options, stored);
        return dual::dual_contour(samples, &crossings, field, placement, with_homes, None);
    };
    // An edge none of whose cells is kept is only counted: its ends' linear crossing, no
    // normal, and no call of `place`, which is where the field is read.
    let inv_h = 1.0 / samples.spacing;
    let place_kept = |a: Vec3, va: f32, b: Vec3, vb: f32, axis: usize| {
        let n = ((a - samples.origin) * inv_h)
            .round()
            .to_array()
            .map(|x| x as usize);
        if edge_touches(keep, n, axis) {
            place(a, va, b, vb, axis)
        } else {
            (lerp_crossing(a, va, b, vb, samples.iso), Vec3::ZERO)
        }
    };
    let crossings = all_crossings(samples, Place::WithNormal(&place_kept), EXTRA_FLAG);
    let placement = Placement::Planes(options, stored);
    dual::dual_contour(samples, &crossings, field, placement, true, Some(keep))
}

/// Extracts the surface `value == iso` by surface nets: one vertex per surface component of
/// each cell, at the mean of the component's edge crossings, moved onto the zero set of `field`
/// by Newton steps along its gradient that stay inside the cell.
///
/// Inputs are as for [`dual_contour`], and so is the topology: the mesh is the dual of the
/// [`marching_cubes`] surface, with the same guarantees (watertight, manifold, oriented,
/// non-degenerate, deterministic, sparse). Crossings are the roots of the field along each edge
/// as in [`marching_cubes_on_field`]; no normals are needed, so this is cheaper than
/// [`dual_contour`] and rounds sharp features off where dual contouring keeps them.
///
/// Classic surface nets (and the `fast-surface-nets` crate) make one vertex per cell, which
/// joins two sheets passing through one cell into a vertex that is not a manifold; the tests
/// compare this function with that crate wherever every cell holds one component.
///
/// # Panics
///
/// As [`marching_cubes`].
///
/// [`marching_cubes`]: crate::marching_cubes
/// [`marching_cubes_on_field`]: crate::marching_cubes_on_field
pub fn surface_nets(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
) -> Mesh {
    let refine = |a, va, b, vb| cubic_edge_root(field, a, va, b, vb, iso);
    let nodes = DenseNodes::new(values, dims);
    match Samples::checked(&nodes, origin, spacing, iso) {
        Some(samples) => surface_nets_with(&samples, field, &refine, None),
        None => Mesh::default(),
    }
}

/// [`surface_nets`] on any source of samples, with the edge crossings placed by `refine`, as in
/// [`marching_cubes_with`].
///
/// [`marching_cubes_with`]: crate::marching_cubes_with
pub(crate) fn surface_nets_with(
    samples: &Samples,
    field: &dyn Field,
    refine: &Refine,
    stored: Option<&StoredVertices>,
) -> Mesh {
    let crossings = all_crossings(samples, Place::Position(refine), EXTRA_FLAG);
    dual::dual_contour(
        samples,
        &crossings,
        field,
        Placement::Mean(stored),
        false,
        None,
    )
    .mesh
}
