//! Contouring a coefficient volume as a whole: sampling it on a grid, padding the grid so every
//! surface closes, and running the chosen method with the continuous field for placement.

use glam::Vec3;
use pgvol_field::{CoefficientVolume, Grid};

use crate::cell_set::CellSet;
use crate::crossings::with_normal;
use crate::dual::{CellKeep, DualMesh};
use crate::dual_methods::{dual_contour_with, surface_nets_with};
use crate::dual_options::{DualContourOptions, StoredVertices};
use crate::edge_cubic::crossing_on_grid_edge;
use crate::field::Field;
use crate::grids::padded;
use crate::marching::marching_cubes_samples;
use crate::place::onto_edge;
use crate::root::edge_root;
use crate::samples::{DenseNodes, Nodes, PaddedNodes, Samples};
use crate::volume_root::volume_refine;
use pgvol_core::progress::{Report, Span};

/// How the mesh is extracted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Marching cubes with vertices on the continuous field: watertight and manifold.
    #[default]
    MarchingCubes,
    /// Surface nets with vertices projected onto the field: watertight and manifold, smooth.
    SurfaceNets,
    /// Manifold dual contouring with the analytic gradients: keeps sharp features.
    DualContouring,
}

/// `mesh`, contoured in `grid`'s local coordinates, placed in the grid's world frame.
fn in_frame_of(grid: &Grid, mut mesh: pgvol_core::Mesh) -> pgvol_core::Mesh {
    mesh.offset = grid.offset;
    mesh
}

/// Contours the `iso` level set of `volume` sampled on `grid`. The samples are padded with one
/// layer of outside values (`iso + spacing`) so the surface is closed even where it reaches the
/// grid's border; edges into the padding place their vertex by linear interpolation, since the
/// padding values are artificial, and all other vertices lie on the continuous field.
///
/// The field is evaluated only in the bricks of nodes the level set may cross (see
/// `sparse_sample`), so time and memory follow the surface rather than the grid.
/// The fraction done goes to `report` (`pgvol_core::progress::QUIET` for none).
pub fn contour_volume(
    volume: &CoefficientVolume,
    grid: &Grid,
    iso: f32,
    method: Method,
    report: Report,
) -> pgvol_core::Mesh {
    contour_volume_placing(volume, grid, iso, method, report, None)
}

/// [`contour_volume`], with dual contouring and surface nets taking the vertices of the cells
/// `stored` gives (called with each singly crossed cell's lowest corner in `grid`'s local
/// coordinates; marching cubes ignores it). The guarantees of [`contour_volume`] hold whatever
/// it gives.
/// With `stored`, the other cells' vertices take no feature offset
/// ([`DualContourOptions::feature_offset`]): the stored cells are where the creases are, and
/// elsewhere the offset would bend curved surfaces into false creases.
pub fn contour_volume_placing(
    volume: &CoefficientVolume,
    grid: &Grid,
    iso: f32,
    method: Method,
    report: Report,
    stored: Option<&StoredVertices>,
) -> pgvol_core::Mesh {
    let options = dual_options(stored.is_some());
    let method = (method, &options);
    contour_volume_with(volume, grid, iso, method, report, stored, (false, None)).mesh
}

/// Dual contouring's options for a volume whose creases are (`true`) or are not given by
/// stored vertices.
fn dual_options(creases_stored: bool) -> DualContourOptions {
    let mut options = DualContourOptions::default();
    if creases_stored {
        options.feature_offset = 0.0;
    }
    options
}

/// Dual contouring of `volume` on `grid` for callers that keep only the vertices of the cells
/// a cell or more inside `grid`: those are [`contour_volume`]'s, while the field is not
/// evaluated outside `grid` to place vertices (the padding's cells keep their planes' point; a
/// border cell's offset planes reaching outside fall back to its crossings'). On a small grid
/// through a solid, where the padding closes whole faces, those cells are most of the work.
/// The vertices are those of [`contour_volume_placing`] with stored vertices, in the cells it
/// does not store: what an encoder compares with the exact ones to choose the cells to store.
pub fn dual_contour_interior(
    volume: &CoefficientVolume,
    grid: &Grid,
    iso: f32,
    report: Report,
) -> pgvol_core::Mesh {
    let method = (Method::DualContouring, &dual_options(true));
    contour_volume_with(volume, grid, iso, method, report, None, (true, None)).mesh
}

/// The vertices [`dual_contour_interior`] gives the cells of `grid` in `cells`, each with its
/// cell, and no triangles: the other cells' crossings and vertices are not worked out.
pub fn dual_vertices_interior(
    volume: &CoefficientVolume,
    grid: &Grid,
    iso: f32,
    cells: &CellSet,
    report: Report,
) -> DualMesh {
    let method = (Method::DualContouring, &dual_options(true));
    contour_volume_with(volume, grid, iso, method, report, None, (true, Some(cells)))
}

/// [`contour_volume_placing`], the padding's cells refined on the field or (`interior_only`)
/// not; with `only`, dual contouring's vertices of those cells alone, with their cells.
fn contour_volume_with(
    volume: &CoefficientVolume,
    grid: &Grid,
    iso: f32,
    (method, options): (Method, &DualContourOptions),
    report: Report,
    stored: Option<&StoredVertices>,
    (interior_only, only): (bool, Option<&CellSet>),
) -> DualMesh {
    if method == Method::MarchingCubes {
        let mut mesh = pgvol_core::Mesh::default();
        let collect = &mut |part: crate::runs::RunPart| {
            mesh.positions.extend_from_slice(&part.positions);
            mesh.triangles.extend_from_slice(&part.triangles);
            mesh.normals.extend_from_slice(&part.normals);
            Ok(())
        };
        return match crate::runs::contour_runs(&mut { volume }, grid, iso, report, collect) {
            Ok(()) => DualMesh {
                mesh: in_frame_of(grid, mesh),
                homes: Vec::new(),
            },
            Err(crate::runs::RunsError::TooManyVertices) => panic!("too many vertices"),
        };
    }
    let span = Span::whole(report);
    let sampling = Some(span.part(0.0, SAMPLING_PART));
    let nodes = crate::sparse_sample::VolumeNodes::new(volume, grid, iso, sampling);
    let rest = Some(span.part(SAMPLING_PART, 1.0));
    let interior = interior_only.then(|| (grid.origin, grid.max_corner()));
    let keep = only.map(|cells| move |c: [usize; 3]| cells.contains_padded(c, 1));
    let out = contour_nodes(
        volume,
        &padded(grid),
        &nodes,
        iso,
        (method, interior),
        rest,
        (options, stored, keep.as_ref().map(|k| k as &CellKeep)),
    );
    DualMesh {
        mesh: in_frame_of(grid, out.mesh),
        homes: out.homes,
    }
}

/// The part of [`contour_volume`]'s progress spent evaluating the field at nodes.
const SAMPLING_PART: f64 = 0.4;

/// [`contour_volume`] from given samples of `volume` on `grid`.
#[cfg(test)]
pub(crate) fn contour_samples(
    volume: &CoefficientVolume,
    grid: &Grid,
    inner: &[f32],
    iso: f32,
    method: Method,
) -> pgvol_core::Mesh {
    let nodes = PaddedNodes::new(inner, grid.dims, iso + grid.spacing);
    contour_nodes(
        volume,
        &padded(grid),
        &nodes,
        iso,
        (method, None),
        None,
        (&DualContourOptions::default(), None, None),
    )
    .mesh
}

/// Why [`contour_field`] cannot contour the samples it is given.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SamplesError {
    /// The samples are not one per node of the grid.
    #[error(
        "{given} samples given for a grid of {} × {} × {} nodes: one sample per node is needed",
        dims[0], dims[1], dims[2]
    )]
    Count { given: usize, dims: [usize; 3] },
    /// The grid spacing is zero, negative or not finite.
    #[error("the grid spacing is {0}: it must be positive and finite")]
    Spacing(f32),
}

/// Contours the `iso` level set of any continuous `field` given its samples `inner` on `grid`
/// (x fastest; only their side of iso matters beyond the crossed edges, so clamped band values
/// do), padded like [`contour_volume`] so the surface closes. Crossings are found by regula
/// falsi on the field itself, not a cubic through the edge, so a field that is not smooth
/// along an edge (an exact signed distance near a sharp edge) gets its true crossing; edges into
/// the padding are interpolated linearly. `options` applies to dual contouring.
///
/// # Errors
///
/// [`SamplesError`] when `inner` does not hold one sample per node of `grid`, or the grid
/// spacing is not positive and finite.
/// The fraction done goes to `report` (`pgvol_core::progress::QUIET` for none).
pub fn contour_field(
    field: &dyn Field,
    grid: &Grid,
    inner: &[f32],
    iso: f32,
    method: Method,
    options: &DualContourOptions,
    report: Report,
) -> Result<pgvol_core::Mesh, SamplesError> {
    let hermite = (None, None);
    contour_field_placing(field, grid, inner, iso, method, options, hermite, report).map(|d| d.mesh)
}

/// [`contour_field`], with dual contouring's Hermite data from `hermite` where it answers, and
/// (`only`) the vertices of those cells alone.
#[allow(clippy::too_many_arguments)]
fn contour_field_placing(
    field: &dyn Field,
    grid: &Grid,
    inner: &[f32],
    iso: f32,
    method: Method,
    options: &DualContourOptions,
    (hermite, only): (Option<&EdgeHermite>, Option<&CellSet>),
    report: Report,
) -> Result<DualMesh, SamplesError> {
    let nodes = grid.dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    if nodes != Some(inner.len()) {
        return Err(SamplesError::Count {
            given: inner.len(),
            dims: grid.dims,
        });
    }
    if !(grid.spacing.is_finite() && grid.spacing > 0.0) {
        return Err(SamplesError::Spacing(grid.spacing));
    }
    // The padding is read through the source, not copied around the caller's samples.
    let nodes = PaddedNodes::new(inner, grid.dims, iso + grid.spacing);
    let padded = padded(grid);
    let Some(samples) = Samples::checked(&nodes, padded.origin, padded.spacing, iso) else {
        return Ok(DualMesh::default());
    };
    let samples = samples.reporting(Some(Span::whole(report)));
    let (lo, hi) = (grid.origin, grid.max_corner());
    let in_box = |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
    let refine = |a: Vec3, va: f32, b: Vec3, vb: f32| -> Vec3 {
        if in_box(a) && in_box(b) {
            edge_root(field, a, va, b, vb, iso)
        } else {
            crate::place::lerp_crossing(a, va, b, vb, iso)
        }
    };
    let mut out = match method {
        Method::MarchingCubes => DualMesh {
            mesh: marching_cubes_samples(&samples, &refine),
            homes: Vec::new(),
        },
        Method::DualContouring => {
            let place = |a: Vec3, va, b: Vec3, vb, axis| {
                if let Some(h) = hermite {
                    if !(in_box(a) && in_box(b)) {
                        // Into the padding: only the cells outside the grid use it, and those
                        // are artificial; the edge itself is the normal (as for a missing
                        // gradient), which costs no query of the field.
                        let p = crate::place::lerp_crossing(a, va, b, vb, iso);
                        let mut n = Vec3::ZERO;
                        n[axis] = if va < iso { 1.0 } else { -1.0 };
                        return (onto_edge(a, b, axis, p), n);
                    }
                    if let Some((p, n)) = h(a, b, axis, va < iso) {
                        return (onto_edge(a, b, axis, p), n.normalize_or_zero());
                    }
                }
                let p = refine(a, va, b, vb);
                with_normal(a, b, axis, p, |p| field.value_gradient(p).1)
            };
            // With Hermite data given, the padding's cells are not projected onto the field
            // either: a vanishing gradient leaves their vertices where the planes put them.
            let inside_only = |p: Vec3| match in_box(p) {
                true => field.value_gradient(p),
                false => (f32::NAN, Vec3::ZERO),
            };
            let placing: &dyn Field = if hermite.is_some() {
                &inside_only
            } else {
                field
            };
            let keep = only.map(|cells| move |c: [usize; 3]| cells.contains_padded(c, 1));
            let keep = keep.as_ref().map(|k| k as &CellKeep);
            dual_contour_with(
                &samples,
                placing,
                options,
                &place,
                None,
                hermite.is_some(),
                keep,
            )
        }
        Method::SurfaceNets => DualMesh {
            mesh: surface_nets_with(&samples, field, &refine, None),
            homes: Vec::new(),
        },
    };
    out.mesh = in_frame_of(grid, out.mesh);
    Ok(out)
}

/// Hermite data of a grid edge given from outside: called with the edge's ends `a` (lower) and
/// `b`, which lie on either side of iso, its axis and whether `a` is the inside end, it returns
/// the crossing and the unit normal there (pointing to the outside end), or `None` to find them
/// on the field as usual.
pub type EdgeHermite<'a> = dyn Fn(Vec3, Vec3, usize, bool) -> Option<(Vec3, Vec3)> + Sync + 'a;

/// Dual contouring as in [`contour_field`], with the crossings and normals of the edges that
/// `hermite` answers taken from it (a mesh's own faces, where they are known exactly); the
/// other edges, and the vertices' projection onto the zero set, use `field`, but for the cells
/// and edges of the padding, which take the edge's direction as normal and are not projected:
/// only cells outside the grid use them. A crossing is kept
/// on its edge as every crossing is, so the guarantees hold whatever `hermite` gives. The
/// mesh comes with the cell of each cell vertex, for callers that compare vertices cell by
/// cell. With `only`, just the vertices of those cells of `grid` come out, and no triangles:
/// the other edges and cells are not worked out.
///
/// # Errors
///
/// As [`contour_field`].
#[allow(clippy::too_many_arguments)]
pub fn contour_field_hermite(
    field: &dyn Field,
    grid: &Grid,
    inner: &[f32],
    iso: f32,
    options: &DualContourOptions,
    hermite: &EdgeHermite,
    only: Option<&CellSet>,
    report: Report,
) -> Result<DualMesh, SamplesError> {
    let dc = Method::DualContouring;
    contour_field_placing(
        field,
        grid,
        inner,
        iso,
        dc,
        options,
        (Some(hermite), only),
        report,
    )
}

/// Contours the `iso` level set of `volume` given its samples `values` on `grid` (x fastest),
/// without padding: surfaces reaching the grid's border stay open there. Vertices lie on the
/// continuous field wherever both ends of their grid edge are in the volume's box (from the
/// coefficients directly when `grid` is the volume's own cubic B-spline grid), and are
/// interpolated linearly outside it, where values are artificial.
///
/// # Panics
///
/// If `values.len()` does not match `grid.dims`, or `grid.spacing` is not positive and finite.
pub fn contour_sampled(
    volume: &CoefficientVolume,
    grid: &Grid,
    values: &[f32],
    iso: f32,
    method: Method,
) -> pgvol_core::Mesh {
    let nodes = DenseNodes::new(values, grid.dims);
    in_frame_of(
        grid,
        contour_nodes(
            volume,
            grid,
            &nodes,
            iso,
            (method, None),
            None,
            (&DualContourOptions::default(), None, None),
        )
        .mesh,
    )
}

/// [`contour_sampled`] with the samples from any source.
/// With `interior` (a box), dual contouring evaluates the field only inside it to place the
/// vertices of cells.
fn contour_nodes(
    volume: &CoefficientVolume,
    grid: &Grid,
    nodes: &dyn Nodes,
    iso: f32,
    (method, interior): (Method, Option<(Vec3, Vec3)>),
    span: Option<Span>,
    (options, stored, only): (
        &DualContourOptions,
        Option<&StoredVertices>,
        Option<&CellKeep>,
    ),
) -> DualMesh {
    let Some(samples) = Samples::checked(nodes, grid.origin, grid.spacing, iso) else {
        return DualMesh::default();
    };
    let samples = samples.reporting(span);
    let refine = volume_refine(volume, iso);
    let mesh_only = |mesh| DualMesh {
        mesh,
        homes: Vec::new(),
    };
    match method {
        Method::MarchingCubes => mesh_only(marching_cubes_samples(&samples, &refine)),
        Method::DualContouring => {
            // On the volume's own grid, crossing and normal come from one read of the edge's
            // coefficients; elsewhere as for marching cubes, then a general evaluation.
            let place = |a, va, b, vb, axis| {
                crossing_on_grid_edge(volume, a, va, b, vb, iso).unwrap_or_else(|| {
                    let p = refine(a, va, b, vb);
                    with_normal(a, b, axis, p, |p| volume.value_gradient(p).1)
                })
            };
            let inside_only = |p: Vec3| match interior {
                Some((lo, hi)) if !(p.cmpge(lo).all() && p.cmple(hi).all()) => {
                    (f32::NAN, Vec3::ZERO)
                }
                _ => volume.value_gradient(p),
            };
            let field: &dyn Field = match interior {
                Some(_) => &inside_only,
                None => volume,
            };
            dual_contour_with(&samples, field, options, &place, stored, false, only)
        }
        Method::SurfaceNets => mesh_only(surface_nets_with(&samples, volume, &refine, stored)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grids::resampled_grid;
    use crate::test_volumes::two_balls;
    use pgvol_field::Basis;

    fn sphere_volume(radius: f32) -> CoefficientVolume {
        let grid = Grid {
            origin: Vec3::splat(-1.0),
            spacing: 2.0 / 19.0,
            dims: [20, 20, 20],
            offset: Default::default(),
        };
        let mut samples = Vec::with_capacity(grid.len());
        for k in 0..20 {
            for j in 0..20 {
                for i in 0..20 {
                    samples.push(grid.point(i, j, k).length() - radius);
                }
            }
        }
        CoefficientVolume::interpolate(grid, Basis::Bspline3, samples).unwrap()
    }

    /// Sampling only near the level set gives the mesh of full sampling.
    #[test]
    fn sparse_sampling_contours_the_same_shape() {
        let v = two_balls(Basis::Bspline3);
        let method = Method::MarchingCubes;
        let full = contour_samples(&v, &v.grid, &v.sample(&v.grid), 0.0, method);
        let sparse = contour_volume(&v, &v.grid, 0.0, method, pgvol_core::progress::QUIET);
        assert_eq!(full.triangles, sparse.triangles);
        let worst = full
            .positions
            .iter()
            .zip(&sparse.positions)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        assert!(worst < 1e-3 * v.grid.spacing, "{worst}");
    }

    /// The two balls' volume and a sub-grid of its nodes from node `first`, `dims` nodes wide.
    fn two_balls_and_sub_grid(first: [usize; 3], dims: [usize; 3]) -> (CoefficientVolume, Grid) {
        let v = two_balls(Basis::Bspline3);
        let sub = Grid {
            origin: v.grid.point(first[0], first[1], first[2]),
            spacing: v.grid.spacing,
            dims,
            offset: Default::default(),
        };
        (v, sub)
    }

    /// On a sub-grid cutting through the shape, the cells a cell or more inside the sub-grid get
    /// the vertices [`contour_volume_placing`] gives the cells it stores none for, and the
    /// padding's own cells differ.
    #[test]
    fn interior_dual_contouring_keeps_the_inside_cells_vertices() {
        let (v, sub) = two_balls_and_sub_grid([8, 10, 12], [14, 12, 10]);
        let h = v.grid.spacing;
        let quiet = pgvol_core::progress::QUIET;
        let none = |_corner: Vec3| None;
        let dc = Method::DualContouring;
        let full = contour_volume_placing(&v, &sub, 0.0, dc, quiet, Some(&none));
        let interior = dual_contour_interior(&v, &sub, 0.0, quiet);
        // The same cells (quads next to the padding may split the other way).
        assert_eq!(full.positions.len(), interior.positions.len());
        assert_eq!(full.triangles.len(), interior.triangles.len());
        let inside = |p: Vec3| {
            let u = (p - sub.origin) / h;
            u.cmpgt(Vec3::ONE).all() && u.cmplt(Vec3::from(sub.dims.map(|n| n as f32 - 2.0))).all()
        };
        let (mut same, mut moved) = (0, 0);
        for (a, b) in full.positions.iter().zip(&interior.positions) {
            if inside(*a) {
                assert_eq!(a, b, "an inside vertex moved");
                same += 1;
            } else if a != b {
                moved += 1;
            }
        }
        assert!(
            same > 100 && moved > 10,
            "{same} inside, {moved} padding vertices moved"
        );
    }

    /// Asked for some cells only, interior dual contouring gives those cells exactly the
    /// vertices of the whole contour, with their cells, and nothing else.
    #[test]
    fn the_cells_asked_for_get_the_whole_contours_vertices() {
        let (v, sub) = two_balls_and_sub_grid([6, 8, 10], [16, 14, 12]);
        let h = v.grid.spacing;
        let quiet = pgvol_core::progress::QUIET;
        let whole = dual_contour_interior(&v, &sub, 0.0, quiet);
        // Each vertex of the whole contour by its cell (kept a margin inside it).
        let cell_of = |p: Vec3| ((p - sub.origin) / h).floor().to_array().map(|x| x as i64);
        let in_grid = |c: [i64; 3]| (0..3).all(|a| c[a] >= 0 && c[a] + 1 < sub.dims[a] as i64);
        let mut by_cell: Vec<([i64; 3], Vec3)> = whole
            .positions
            .iter()
            .map(|&p| (cell_of(p), p))
            .filter(|&(c, _)| in_grid(c))
            .collect();
        by_cell.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(a.1.to_array().partial_cmp(&b.1.to_array()).unwrap())
        });
        // Every other crossed cell, in a checkerboard.
        let picked = |c: [i64; 3]| (c[0] + c[1] + c[2]) % 2 == 0;
        let mut cells = CellSet::new(sub.dims);
        for &(c, _) in by_cell.iter().filter(|(c, _)| picked(*c)) {
            assert!(cells.insert(c.map(|x| x as usize)));
        }
        let some = dual_vertices_interior(&v, &sub, 0.0, &cells, quiet);
        assert!(some.mesh.triangles.is_empty());
        assert_eq!(some.homes.len(), some.mesh.positions.len());
        let mut got: Vec<([i64; 3], Vec3)> = some
            .homes
            .iter()
            .zip(&some.mesh.positions)
            .map(|(&home, &p)| (cell_of(home + Vec3::splat(0.5 * h)), p))
            .collect();
        got.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(a.1.to_array().partial_cmp(&b.1.to_array()).unwrap())
        });
        let expected: Vec<_> = by_cell.into_iter().filter(|(c, _)| picked(*c)).collect();
        assert!(expected.len() > 100, "{} vertices", expected.len());
        assert_eq!(got, expected);
    }

    #[test]
    fn surfaces_cut_by_the_border_are_closed_by_the_padding() {
        // A sphere of radius 1.2 pokes out of the [-1, 1]^3 grid on every face.
        let volume = sphere_volume(1.2);
        for method in [Method::MarchingCubes, Method::DualContouring] {
            let mesh = contour_volume(
                &volume,
                &volume.grid,
                0.0,
                method,
                pgvol_core::progress::QUIET,
            );
            let s = mesh.stats();
            assert!(s.watertight && s.winding_consistent, "{method:?}: {s:?}");
            assert!(s.volume > 0.0 && s.volume < 8.0 + 1e-3, "{method:?}: {s:?}");
        }
    }

    /// Given vertices are taken, kept inside their cells but past faces the surface does not
    /// cross, and the mesh stays closed, oriented and free of degenerate triangles even where
    /// they are far from the surface.
    #[test]
    fn dual_methods_take_given_vertices() {
        let volume = sphere_volume(0.6);
        let h = volume.grid.spacing;
        let origin = volume.grid.origin;
        let quiet = pgvol_core::progress::QUIET;
        for method in [Method::DualContouring, Method::SurfaceNets] {
            // Every cell's vertex 0.4 beyond its far corner: the margin moves it back inside
            // across crossed faces, and MAX_OUTSIDE_REACH allows it across the others.
            let given = |_corner: Vec3| Some(Vec3::splat(1.4));
            let mesh =
                contour_volume_placing(&volume, &volume.grid, 0.0, method, quiet, Some(&given));
            let s = mesh.stats();
            assert!(
                s.watertight && s.winding_consistent && s.volume > 0.0,
                "{method:?}: {s:?}"
            );
            let mut outside = 0;
            for p in &mesh.positions {
                let f = (*p - origin) / h;
                let f = f - f.floor();
                for a in 0..3 {
                    let beyond = (f[a] - 0.4).abs() < 1e-3;
                    assert!(f[a] > 0.99 || beyond, "{method:?}: {f}");
                    outside += usize::from(beyond);
                }
            }
            assert!(outside > mesh.positions.len() / 4, "{method:?}: {outside}");
            let smallest = mesh
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                    (b - a).cross(c - a).length()
                })
                .fold(f32::INFINITY, f32::min);
            assert!(smallest > 0.0, "{method:?}: {smallest}");
        }
        // With no vertex given, the same cells get a vertex as without stored vertices. Dual
        // contouring's vertices then take no feature offset, so on a sphere they lie nearer the
        // surface; surface nets place theirs as they always do.
        let none = |_corner: Vec3| None;
        let method = Method::DualContouring;
        let plain = contour_volume_placing(&volume, &volume.grid, 0.0, method, quiet, Some(&none));
        let offset = contour_volume(&volume, &volume.grid, 0.0, method, quiet);
        assert_eq!(plain.positions.len(), offset.positions.len());
        let off_sphere = |m: &pgvol_core::Mesh| {
            let total: f32 = m.positions.iter().map(|p| (p.length() - 0.6).abs()).sum();
            total / m.positions.len() as f32 / h
        };
        assert!(off_sphere(&plain) < off_sphere(&offset));
        let method = Method::SurfaceNets;
        let plain = contour_volume_placing(&volume, &volume.grid, 0.0, method, quiet, Some(&none));
        let nets = contour_volume(&volume, &volume.grid, 0.0, method, quiet);
        assert_eq!(plain.positions, nets.positions);
        assert_eq!(plain.triangles, nets.triangles);
    }

    #[test]
    fn resampling_keeps_the_box_and_refines_the_mesh() {
        let volume = sphere_volume(0.7);
        let fine = resampled_grid(&volume, 39).unwrap();
        assert_eq!(fine.dims, [39, 39, 39]);
        assert!((fine.max_corner() - volume.grid.max_corner()).length() < 1e-5);
        let coarse = contour_volume(
            &volume,
            &volume.grid,
            0.0,
            Method::MarchingCubes,
            pgvol_core::progress::QUIET,
        );
        let dense = contour_volume(
            &volume,
            &fine,
            0.0,
            Method::MarchingCubes,
            pgvol_core::progress::QUIET,
        );
        assert!(dense.triangles.len() > 3 * coarse.triangles.len());
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.7f64.powi(3);
        assert!((dense.stats().volume - exact).abs() / exact < 0.01);
        assert!(resampled_grid(&volume, 1 << 20).is_none());
    }

    /// Exact signed distance of a cube of half-side 0.55 rotated about x and y, with a central
    /// difference gradient.
    fn rotated_cube() -> (impl Fn(Vec3) -> (f32, Vec3) + Sync, Vec<Vec3>) {
        let r = glam::Mat3::from_rotation_y(0.5) * glam::Mat3::from_rotation_x(0.5);
        let half = 0.55f32;
        let sdf = move |p: Vec3| {
            let q = (r.transpose() * p).abs() - Vec3::splat(half);
            q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
        };
        let field = move |p: Vec3| {
            let e = 1e-4;
            let g = Vec3::new(
                sdf(p + Vec3::X * e) - sdf(p - Vec3::X * e),
                sdf(p + Vec3::Y * e) - sdf(p - Vec3::Y * e),
                sdf(p + Vec3::Z * e) - sdf(p - Vec3::Z * e),
            ) / (2.0 * e);
            (sdf(p), g)
        };
        let corners = (0..8u32)
            .map(|c| {
                let bit = |s: u32| if (c >> s) & 1 == 1 { half } else { -half };
                r * Vec3::new(bit(0), bit(1), bit(2))
            })
            .collect();
        (field, corners)
    }

    #[test]
    fn exact_field_keeps_the_corners_of_a_rotated_cube() {
        let (field, corners) = rotated_cube();
        let grid = Grid {
            origin: Vec3::splat(-1.0),
            spacing: 2.0 / 23.0,
            dims: [24, 24, 24],
            offset: Default::default(),
        };
        let mut samples = Vec::with_capacity(grid.len());
        for k in 0..24 {
            for j in 0..24 {
                for i in 0..24 {
                    samples.push(field(grid.point(i, j, k)).0);
                }
            }
        }
        let options = DualContourOptions {
            feature_offset: 0.0,
            ..DualContourOptions::default()
        };
        // Mean distance of a cube corner from its nearest vertex, in grid spacings.
        let corner_gap = |mesh: &pgvol_core::Mesh| {
            let nearest = |c: &Vec3| {
                let d = mesh.positions.iter().map(|p| p.distance(*c));
                d.fold(f32::INFINITY, f32::min) / grid.spacing
            };
            corners.iter().map(nearest).sum::<f32>() / corners.len() as f32
        };
        let mut gaps = Vec::new();
        for method in [Method::MarchingCubes, Method::DualContouring] {
            let mesh = contour_field(
                &field,
                &grid,
                &samples,
                0.0,
                method,
                &options,
                pgvol_core::progress::QUIET,
            )
            .unwrap();
            let s = mesh.stats();
            assert!(s.watertight && s.winding_consistent, "{method:?}: {s:?}");
            let exact = 1.1f64.powi(3);
            assert!((s.volume - exact).abs() < 0.02 * exact, "{method:?}: {s:?}");
            gaps.push(corner_gap(&mesh));
        }
        // Marching cubes cuts the corners off; dual contouring puts a vertex near each (0.11
        // against 0.38 cells when this was written; corners whose cell lacks one of the three
        // faces' crossings stay off).
        assert!(gaps[1] < 0.15, "{gaps:?}");
        assert!(gaps[0] > 2.5 * gaps[1], "{gaps:?}");
    }

    #[test]
    fn exact_field_refuses_mismatched_samples() {
        let (field, _) = rotated_cube();
        let mut grid = Grid {
            origin: Vec3::ZERO,
            spacing: 0.1,
            dims: [4, 4, 4],
            offset: Default::default(),
        };
        let options = DualContourOptions::default();
        let method = Method::DualContouring;
        let err = contour_field(
            &field,
            &grid,
            &[0.0; 10],
            0.0,
            method,
            &options,
            pgvol_core::progress::QUIET,
        )
        .unwrap_err();
        assert_eq!(
            err,
            SamplesError::Count {
                given: 10,
                dims: [4, 4, 4]
            }
        );
        assert_eq!(
            err.to_string(),
            "10 samples given for a grid of 4 × 4 × 4 nodes: one sample per node is needed"
        );
        grid.spacing = 0.0;
        let err = contour_field(
            &field,
            &grid,
            &[0.0; 64],
            0.0,
            method,
            &options,
            pgvol_core::progress::QUIET,
        )
        .unwrap_err();
        assert_eq!(err, SamplesError::Spacing(0.0));
    }
}
