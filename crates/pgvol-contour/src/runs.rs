//! Marching cubes of a coefficient volume run by run of node layers along z, so that what is
//! held at any time is one run's samples, crossings and coefficients, not the whole band.
//!
//! The padded sampling grid (see `grids`) is cut into runs of [`RUN_LAYERS`] cell layers. A run
//! is contoured as a grid of its own, its nodes placed as the whole grid places them, and reads
//! only the coefficient layers its nodes' supports reach, which a [`CoefficientWindows`] source
//! provides (the whole volume in memory, or a window decoded from a file). Two runs share the
//! node plane between them: its crossings (on edges along x and y) come out identical in both,
//! since their values come from the same bricks and their positions from the same nodes, so the
//! upper run takes the lower run's vertices for them and the mesh is welded across runs.
//!
//! Vertices are numbered run by run: a run's new edge vertices in the order of its blocks, then
//! its loop centre vertices; triangles follow their cells' order. The result does not depend on
//! the number of threads, nor on where the coefficients come from.

use std::borrow::Cow;
use std::collections::HashMap;
use std::ops::Range;

use glam::Vec3;
use pgvol_core::progress::{stopped, tick, Report, Span};
use pgvol_field::{CoefficientVolume, Grid};
use rayon::prelude::*;

use crate::blocks::{coords, BoxValues, BLOCK};
use crate::crossings::{all_crossings, Crossings, Place};
use crate::extract::{block_triangles, Part, EXTRA_FLAG};
use crate::samples::{Nodes, Samples, CROSSINGS_PART};
use crate::sparse_sample::{coefficient_layers, VolumeNodes};

/// Cell layers per run: 4 contour blocks. A run sorts again the brick layer it shares with the
/// run below (a quarter more sorting), and a shorter run holds fewer slabs of the file: decoding
/// fandisk at 2048³ peaks at 1.28 GB with runs of 32 layers against 1.53 GB with 64, for 6 % more
/// CPU time (`docs/algorithms.md`).
pub const RUN_LAYERS: usize = 4 * BLOCK;

/// Where a contoured volume's coefficients come from, a window of node layers at a time.
pub trait CoefficientWindows {
    type Error;

    /// The grid of the coefficients.
    fn grid(&self) -> Grid;

    /// A volume on the same grid and basis whose coefficients equal the whole volume's at every
    /// node with a z index in `layers[0]..=layers[1]` (the others are never read). Windows are
    /// asked for in ascending order.
    fn window(&mut self, layers: [usize; 2]) -> Result<Cow<'_, CoefficientVolume>, Self::Error>;

    /// Where the coefficients may differ from the outside background, if known and the basis
    /// is separable (values are weighted means of the coefficients within 2 nodes): then the
    /// contouring of the volume's own grid visits only the box around them.
    fn occupied(&self) -> Option<Occupied> {
        None
    }
}

/// A box of coefficient bricks outside which every coefficient is the outside background.
#[derive(Clone, Debug, PartialEq)]
pub struct Occupied {
    /// Per axis, the range of brick indices; an empty range when no brick is stored or inside.
    pub bricks: [Range<usize>; 3],
    /// The outside background's value.
    pub outside: f32,
}

/// A volume held whole is its own window.
impl CoefficientWindows for &CoefficientVolume {
    type Error = std::convert::Infallible;

    fn grid(&self) -> Grid {
        self.grid
    }

    fn window(&mut self, _: [usize; 2]) -> Result<Cow<'_, CoefficientVolume>, Self::Error> {
        Ok(Cow::Borrowed(*self))
    }

    fn occupied(&self) -> Option<Occupied> {
        self.basis.is_separable().then(|| Occupied {
            bricks: self.coeffs.occupied_bricks(),
            outside: self.coeffs.background().outside,
        })
    }
}

/// What one run adds to the mesh.
#[derive(Debug, Default)]
pub struct RunPart {
    /// The run's new vertices, in the grid's local frame; they follow those of earlier runs.
    pub positions: Vec<Vec3>,
    /// The run's triangles, indexing all vertices so far.
    pub triangles: Vec<[u32; 3]>,
    /// The unit normals of `positions`: the field's gradient direction, zero where it has
    /// none (see `volume_place_with_normal`).
    pub normals: Vec<Vec3>,
}

/// Why [`contour_runs`] stopped.
#[derive(Debug)]
pub enum RunsError<E> {
    /// The coefficient source or the receiver of the parts failed.
    Source(E),
    /// The mesh would need more vertices than 32-bit indices address.
    TooManyVertices,
}

/// Marching cubes of the `iso` level set of the volume `windows` provides, sampled on `grid`
/// and padded with outside values so the surface closes, handed to `part` run by run along z.
/// Progress goes to `report`; an error from `part` or `windows` stops the work.
pub fn contour_runs<W: CoefficientWindows>(
    windows: &mut W,
    grid: &Grid,
    iso: f32,
    report: Report,
    part: &mut dyn FnMut(RunPart) -> Result<(), W::Error>,
) -> Result<(), RunsError<W::Error>> {
    contour_runs_of(windows, grid, iso, RUN_LAYERS, report, part)
}

/// [`contour_runs`] with runs of `run_layers` cell layers, a multiple of [`BLOCK`].
fn contour_runs_of<W: CoefficientWindows>(
    windows: &mut W,
    grid: &Grid,
    iso: f32,
    run_layers: usize,
    report: Report,
    part: &mut dyn FnMut(RunPart) -> Result<(), W::Error>,
) -> Result<(), RunsError<W::Error>> {
    let volume_grid = windows.grid();
    // Node positions are the whole grid's, whatever part of it is contoured.
    let origin = crate::grids::padded(grid).origin;
    let (first, grid) = match windows.occupied() {
        Some(occupied) if grid == &volume_grid => {
            match cropped(&occupied, grid, iso, [BLOCK, BLOCK, run_layers]) {
                Some(crop) => crop,
                // Every coefficient is outside: no surface.
                None => return Ok(()),
            }
        }
        _ => ([0; 3], *grid),
    };
    let grid = &grid;
    let padded = crate::grids::padded(grid);
    let cells = padded.dims[2] - 1;
    let runs = cells.div_ceil(run_layers);
    let span = Span::whole(report);
    let mut stitch = Stitch::default();
    for run in 0..runs {
        // A stop asked for: the runs not yet begun are not read; the caller drops the mesh.
        if span.cancelled() {
            return Ok(());
        }
        let layers = [run * run_layers, ((run + 1) * run_layers).min(cells)];
        let needed = coefficient_layers(&volume_grid, grid, layers);
        let window = windows.window(needed).map_err(RunsError::Source)?;
        let span = span.part(run as f64 / runs as f64, (run + 1) as f64 / runs as f64);
        let at = [first[0], first[1], first[2] + layers[0]];
        let (crossings, parts) = run_mesh(&window, grid, iso, layers, (origin, at), span);
        let last = run + 1 == runs;
        let out = stitch.add(&crossings, parts, layers, last)?;
        // Freed before the part is handed on, which may copy it.
        drop(crossings);
        drop(window);
        part(out).map_err(RunsError::Source)?;
    }
    Ok(())
}

/// Nodes past the occupied coefficients whose values can still differ from the outside
/// background: the supports of the separable bases reach at most 2 nodes.
const SUPPORT_REACH: usize = 2;

/// The part of the volume's own `grid` that can hold the `iso` level when only the `occupied`
/// bricks differ from an outside background above it: its first node in `grid` and the grid
/// of its nodes, `None` when no node can. The box starts at a multiple of `align` (contour
/// blocks along x and y, runs along z), so its blocks and runs are the whole grid's, and
/// reaches past the support of the occupied coefficients, so the padding around it stands for
/// nodes that are outside in the whole grid too: the mesh is the whole grid's, bit for bit.
/// The whole grid when the background is not clearly above the level.
fn cropped(
    occupied: &Occupied,
    grid: &Grid,
    iso: f32,
    align: [usize; 3],
) -> Option<([usize; 3], Grid)> {
    // Values of background-only supports are the background up to rounding of the weights;
    // a NaN level or background keeps the whole grid too.
    let clearly_above = occupied.outside - iso > 1e-5 * occupied.outside.abs();
    if !clearly_above {
        return Some(([0; 3], *grid));
    }
    if occupied.bricks.iter().any(|r| r.is_empty()) {
        return None;
    }
    let mut first = [0; 3];
    let mut dims = grid.dims;
    for a in 0..3 {
        let r = &occupied.bricks[a];
        let lo = r.start * pgvol_core::BRICK_EDGE;
        let hi = (r.end * pgvol_core::BRICK_EDGE).min(grid.dims[a]);
        // Node `first - 1`, which the padding stands for, lies beyond the support's reach.
        first[a] = lo.saturating_sub(SUPPORT_REACH) / align[a] * align[a];
        let end = (hi - 1 + SUPPORT_REACH + 1).min(grid.dims[a]);
        dims[a] = end - first[a];
    }
    let origin =
        grid.origin + grid.spacing * Vec3::new(first[0] as f32, first[1] as f32, first[2] as f32);
    Some((
        first,
        Grid {
            origin,
            spacing: grid.spacing,
            dims,
            offset: grid.offset,
        },
    ))
}

/// The crossings and the blocks' triangles of the padded node layers `layers` of `grid`, its
/// nodes placed at `origin + spacing · (node + at)` (`place`).
fn run_mesh(
    volume: &CoefficientVolume,
    grid: &Grid,
    iso: f32,
    layers: [usize; 2],
    place: (Vec3, [usize; 3]),
    span: Span,
) -> (Crossings, Vec<Part>) {
    let sampling = Some(span.part(0.0, SAMPLING_PART));
    let nodes = VolumeNodes::layers(volume, grid, iso, layers, sampling);
    let padded = crate::grids::padded(grid);
    let run = RunNodes {
        inner: &nodes,
        first: layers[0],
        dims: [padded.dims[0], padded.dims[1], layers[1] - layers[0] + 1],
        block_plane: padded.dims[0].div_ceil(BLOCK) * padded.dims[1].div_ceil(BLOCK),
    };
    let samples = Samples::checked(&run, place.0, padded.spacing, iso)
        .expect("a run holds at least one cell layer")
        .shifted(place.1)
        .reporting(Some(span.part(SAMPLING_PART, 1.0)));
    // Normals are taken with the crossings, from the stencil each root reads anyway: writers
    // then need no pass over the faces (angle-weighted normals cost more than the roots).
    let place = crate::volume_root::volume_place_with_normal(volume, iso);
    let crossings = all_crossings(&samples, Place::WithNormal(&place), EXTRA_FLAG);
    let blocks = crossings.blocks.active.len();
    let counter = samples.counter(CROSSINGS_PART, 1.0, blocks);
    let parts = (0..blocks)
        .into_par_iter()
        .map(|slot| {
            if stopped(counter.as_ref()) {
                return Part::default();
            }
            tick(counter.as_ref());
            block_triangles(&crossings, iso, slot)
        })
        .collect();
    (crossings, parts)
}

/// The part of a run's progress spent evaluating the field at nodes.
const SAMPLING_PART: f64 = 0.4;

/// The padded node layers `first..first + dims[2]` of a [`VolumeNodes`], as a grid of their own.
struct RunNodes<'a> {
    inner: &'a VolumeNodes,
    first: usize,
    dims: [usize; 3],
    /// Contour blocks per layer of blocks.
    block_plane: usize,
}

impl Nodes for RunNodes<'_> {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    fn candidates(&self, iso: f32) -> Vec<u32> {
        // Runs start on block layers, so ids shift by whole layers of blocks.
        let shift = (self.first / BLOCK * self.block_plane) as u32;
        let ids = self.inner.candidates(iso);
        ids.into_iter().map(|id| id - shift).collect()
    }

    fn read_box(&self, lo: [usize; 3], n: [usize; 3], out: &mut BoxValues) {
        self.inner
            .read_box([lo[0], lo[1], lo[2] + self.first], n, out);
    }
}

/// Numbers the vertices of successive runs, welding each run to the one below.
#[derive(Default)]
struct Stitch {
    /// Vertices handed out so far.
    count: u64,
    /// The global index of each crossing on the top plane of the last run, by its edge's lower
    /// node `(i, j)` and axis.
    top: HashMap<(u32, u32, u8), u32>,
}

impl Stitch {
    /// The part a run adds: its crossings not on the plane it shares with the run below, its
    /// loop centres, and its triangles in global indices.
    fn add<E>(
        &mut self,
        crossings: &Crossings,
        parts: Vec<Part>,
        layers: [usize; 2],
        last: bool,
    ) -> Result<RunPart, RunsError<E>> {
        let n = crossings.positions.len();
        let mut ids = vec![u32::MAX; n];
        let counts = crossings.blocks.counts;
        let plane_edges = |z: usize| {
            let layer = z / BLOCK;
            crossings
                .blocks
                .active
                .iter()
                .enumerate()
                .filter(move |&(_, &id)| coords(counts, id)[2] == layer)
                .flat_map(|(slot, _)| crossings.block_vertices(slot))
                .filter_map(move |g| {
                    let (node, axis) = crossings.locate(g);
                    (node[2] == z && axis != 2)
                        .then_some((g, (node[0] as u32, node[1] as u32, axis as u8)))
                })
        };
        if layers[0] > 0 {
            for (g, key) in plane_edges(0) {
                if let Some(&id) = self.top.get(&key) {
                    ids[g as usize] = id;
                }
            }
        }
        let mut out = RunPart::default();
        for (g, id) in ids.iter_mut().enumerate() {
            if *id == u32::MAX {
                *id = self.count as u32;
                self.count += 1;
                out.positions.push(crossings.positions[g]);
                out.normals.push(crossings.normals[g]);
            }
        }
        let extras: u64 = parts.iter().map(|p| p.extra.len() as u64).sum();
        if self.count + extras > u64::from(u32::MAX) {
            return Err(RunsError::TooManyVertices);
        }
        for part in parts {
            let first = self.count as u32;
            let resolve = |v: u32| {
                if v & EXTRA_FLAG != 0 {
                    first + (v & !EXTRA_FLAG)
                } else {
                    ids[v as usize]
                }
            };
            out.triangles
                .extend(part.triangles.iter().map(|t| t.map(resolve)));
            self.count += part.extra.len() as u64;
            out.positions.extend_from_slice(&part.extra);
            out.normals.extend_from_slice(&part.extra_normals);
        }
        self.top.clear();
        if !last {
            let top = layers[1] - layers[0];
            for (g, key) in plane_edges(top) {
                self.top.insert(key, ids[g as usize]);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_volumes::two_balls;
    use pgvol_core::sparse::brick_offset;
    use pgvol_core::{Mesh, BRICK_EDGE};
    use pgvol_field::Basis;

    /// The mesh of [`contour_runs_of`] with runs of `run_layers`.
    fn mesh_of<W: CoefficientWindows>(windows: &mut W, grid: &Grid, run_layers: usize) -> Mesh
    where
        W::Error: std::fmt::Debug,
    {
        let mut mesh = Mesh::default();
        let collect = &mut |part: RunPart| {
            mesh.positions.extend_from_slice(&part.positions);
            mesh.triangles.extend_from_slice(&part.triangles);
            Ok(())
        };
        contour_runs_of(windows, grid, 0.0, run_layers, &|_| {}, collect).unwrap();
        mesh
    }

    /// The triangles as sorted triples of vertex positions: the mesh whatever its numbering.
    fn shape(mesh: &Mesh) -> Vec<[[u32; 3]; 3]> {
        let mut t: Vec<[[u32; 3]; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| mesh.positions[v as usize].to_array().map(f32::to_bits)))
            .collect();
        t.sort_unstable();
        t
    }

    /// The whole volume with every coefficient outside the asked layers made NaN, so a read
    /// outside a window shows in the mesh.
    struct Poisoned<'a>(&'a CoefficientVolume);

    impl CoefficientWindows for Poisoned<'_> {
        type Error = ();

        fn grid(&self) -> Grid {
            self.0.grid
        }

        fn window(&mut self, layers: [usize; 2]) -> Result<Cow<'_, CoefficientVolume>, ()> {
            let mut v = self.0.clone();
            for (b, values) in v.coeffs.stored_mut() {
                for k in 0..BRICK_EDGE {
                    let z = b[2] * BRICK_EDGE + k;
                    if z < layers[0] || z > layers[1] {
                        for j in 0..BRICK_EDGE {
                            for i in 0..BRICK_EDGE {
                                values[brick_offset([i, j, k])] = f32::NAN;
                            }
                        }
                    }
                }
            }
            Ok(Cow::Owned(v))
        }
    }

    /// A volume contoured on its whole grid: no box of occupied bricks is given.
    struct Uncropped<'a>(&'a CoefficientVolume);

    impl CoefficientWindows for Uncropped<'_> {
        type Error = ();

        fn grid(&self) -> Grid {
            self.0.grid
        }

        fn window(&mut self, _: [usize; 2]) -> Result<Cow<'_, CoefficientVolume>, ()> {
            Ok(Cow::Borrowed(self.0))
        }
    }

    #[test]
    fn the_box_of_occupied_bricks_gives_the_whole_grids_mesh_bit_for_bit() {
        // A small ball near a corner of a 96³ grid; the bricks away from it absent and outside.
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 1.0 / 95.0,
            dims: [96; 3],
            offset: Default::default(),
        };
        let centre = Vec3::new(0.8, 0.78, 0.82);
        let samples = (0..grid.len())
            .map(|n| {
                let [i, j, k] = [n % 96, n / 96 % 96, n / (96 * 96)];
                (grid.point(i, j, k) - centre).length() - 0.08
            })
            .collect();
        let mut v = CoefficientVolume::interpolate(grid, Basis::Bspline3, samples).unwrap();
        let clamp = 0.03;
        v.coeffs
            .retain(|_, values| values.iter().any(|&x| x < clamp));
        v.coeffs
            .set_background(pgvol_core::Background::clamp(clamp));
        v.coeffs.compact_tiles();
        let occupied = (&v).occupied().unwrap();
        assert!(
            occupied
                .bricks
                .iter()
                .all(|r| r.start >= 8 && !r.is_empty()),
            "{occupied:?}"
        );
        for run_layers in [BLOCK, 4 * BLOCK] {
            let cropped = mesh_of(&mut &v, &grid, run_layers);
            let whole = mesh_of(&mut Uncropped(&v), &grid, run_layers);
            assert!(cropped.triangles.len() > 500, "{}", cropped.triangles.len());
            assert_eq!(cropped.positions, whole.positions, "{run_layers}");
            assert_eq!(cropped.triangles, whole.triangles, "{run_layers}");
        }
        // Above the background, every node is inside: the whole grid is contoured.
        let level = cropped(&occupied, &grid, 0.05, [BLOCK, BLOCK, RUN_LAYERS]);
        assert_eq!(level, Some(([0; 3], grid)));
        // Nothing stored or inside: no surface.
        let empty = Occupied {
            bricks: [0..0, 0..4, 0..4],
            outside: clamp,
        };
        assert_eq!(
            cropped(&empty, &grid, 0.0, [BLOCK, BLOCK, RUN_LAYERS]),
            None
        );
    }

    #[test]
    fn runs_weld_into_the_mesh_of_one_run_and_read_only_their_windows() {
        for basis in [Basis::Bspline3, Basis::Trilinear] {
            let v = two_balls(basis);
            let fine = crate::grids::resampled_grid(&v, 61).unwrap();
            for grid in [v.grid, fine] {
                let whole = mesh_of(&mut &v, &grid, usize::MAX / 2);
                let s = whole.stats();
                assert!(s.watertight && s.winding_consistent, "{basis:?}: {s:?}");
                assert!(whole.triangles.len() > 1000);
                for run_layers in [BLOCK, 2 * BLOCK, 3 * BLOCK] {
                    let runs = mesh_of(&mut &v, &grid, run_layers);
                    assert_eq!(runs.positions.len(), whole.positions.len(), "{basis:?}");
                    assert_eq!(shape(&runs), shape(&whole), "{basis:?} {run_layers}");
                    let windowed = mesh_of(&mut Poisoned(&v), &grid, run_layers);
                    assert_eq!(windowed.positions, runs.positions, "{basis:?} {run_layers}");
                    assert_eq!(windowed.triangles, runs.triangles);
                }
            }
        }
    }
}
