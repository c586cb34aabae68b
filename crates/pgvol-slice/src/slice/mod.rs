//! Planar slices of a field: marching squares on a fine 2D grid per layer, vertices on the
//! continuous field, loops traced with the inside on their left.
//!
//! `plane` contours one layer's grid, visiting only the blocks of cells a contour can cross;
//! `collapsed` gives it a separable coefficient volume restricted to the layer's plane, built
//! from the bricks in reach of the plane; `bricks` says where those come from (a grid in memory
//! or slabs decoded from a file on demand) and `window` holds the slabs a run of layers needs.

mod bricks;
mod collapsed;
mod cubic;
mod edge_table;
mod plane;
mod window;

use glam::Vec3;
use pgvol_core::progress::{Counter, Report, Span};
use pgvol_core::{Background, BRICK_EDGE};
use pgvol_field::kernel::Profile;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::SliceError;
use crate::polygon::{perimeter, signed_area};
use crate::simplify::simplify_loops;
use collapsed::{tap_layers, CollapsedPlane, NodeWindows};
use plane::{LayerField, Plane};
use window::Window;

pub use bricks::{
    brick_counts, plane_axes, BrickLayer, BrickRef, BrickSource, LayerRanges, INSIDE, OUTSIDE,
};
pub use plane::{LayerCost, MAX_LAYER_NODES};

/// Most layers one call produces: far beyond any printer, small enough to refuse typos.
pub const MAX_LAYERS: usize = 1_000_000;

/// The build direction. Layer coordinates `(u, v)` are the next two axes in cyclic order
/// (X: `(y, z)`, Y: `(z, x)`, Z: `(x, y)`), so `u × v` points along the axis and
/// counter-clockwise means counter-clockwise seen from the positive side of the axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    X,
    Y,
    #[default]
    Z,
}

impl Axis {
    /// Indices of (axis, u, v) in a `Vec3`.
    pub fn indices(self) -> [usize; 3] {
        match self {
            Axis::X => [0, 1, 2],
            Axis::Y => [1, 2, 0],
            Axis::Z => [2, 0, 1],
        }
    }

    /// The 3D point at height `h` and layer coordinates `(u, v)`.
    fn point(self, h: f32, u: f32, v: f32) -> Vec3 {
        let [a, b, c] = self.indices();
        let mut p = [0.0f32; 3];
        p[a] = h;
        p[b] = u;
        p[c] = v;
        Vec3::from_array(p)
    }
}

/// How to slice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceOptions {
    pub axis: Axis,
    /// Distance between layer planes, > 0.
    pub layer_height: f32,
    /// Height of the first plane; `None` for half a layer above the bottom of the bounds, so
    /// each plane sits in the middle of the slab it stands for.
    pub first: Option<f32>,
    /// Spacing of the 2D grid the contours are extracted on, > 0. Features thinner than about
    /// one spacing may be missed; the field's own grid spacing is a sensible start.
    pub resolution: f32,
    /// Largest distance a simplified loop may move away from any vertex of the extracted one;
    /// 0 keeps every vertex.
    pub tolerance: f32,
}

impl SliceOptions {
    /// Slicing along `axis` with the first plane half a layer above the bottom and a
    /// simplification tolerance of a tenth of `resolution`.
    pub fn new(axis: Axis, layer_height: f32, resolution: f32) -> Self {
        SliceOptions {
            axis,
            layer_height,
            first: None,
            resolution,
            tolerance: resolution / 10.0,
        }
    }
}

/// One closed contour. The last point is not repeated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Loop {
    /// Layer coordinates `(u, v)` (see [`Axis`]).
    pub points: Vec<[f32; 2]>,
    /// A hole: clockwise, with the solid on its outside. Outer boundaries (including islands
    /// inside holes) are counter-clockwise.
    pub hole: bool,
}

/// The contours of one plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// Position of the plane along the axis.
    pub height: f32,
    pub loops: Vec<Loop>,
}

impl Layer {
    /// The solid's area in the plane: outer loops' areas less the holes'.
    pub fn area(&self) -> f64 {
        self.loops.iter().map(|l| signed_area(&l.points)).sum()
    }

    /// The loops' total length.
    pub fn perimeter(&self) -> f64 {
        self.loops.iter().map(|l| perimeter(&l.points)).sum()
    }
}

/// The box of a volume's grid, the natural bounds for [`slice_volume`].
pub fn volume_bounds(volume: &CoefficientVolume) -> (Vec3, Vec3) {
    (volume.grid.origin, volume.grid.max_corner())
}

/// The plane heights for `bounds` and `options`: `first + i · layer_height` (computed in f64,
/// rounded once) for `i = 0, 1, …` while not above the top of the bounds.
pub fn layer_heights(bounds: (Vec3, Vec3), options: &SliceOptions) -> Result<Vec<f32>, SliceError> {
    let a = options.axis.indices()[0];
    let (lo, hi) = (bounds.0[a] as f64, bounds.1[a] as f64);
    let step = options.layer_height as f64;
    if !(step.is_finite() && step > 0.0) {
        return Err(SliceError::BadParameter(format!(
            "layer height must be positive, got {}",
            options.layer_height
        )));
    }
    let first = options.first.map_or(lo + step / 2.0, |f| f as f64);
    if !first.is_finite() {
        return Err(SliceError::BadParameter(
            "first layer height is not finite".into(),
        ));
    }
    let mut count = if first > hi {
        0.0
    } else {
        ((hi - first) / step).floor() + 1.0
    };
    if count > MAX_LAYERS as f64 {
        return Err(SliceError::BadParameter(format!(
            "{count} layers, more than the limit of {MAX_LAYERS}"
        )));
    }
    // The division may round either way; settle the count on the products themselves.
    while count > 0.0 && first + (count - 1.0) * step > hi {
        count -= 1.0;
    }
    while first + count * step <= hi {
        count += 1.0;
    }
    let heights: Vec<f32> = (0..count as usize)
        .map(|i| (first + i as f64 * step) as f32)
        .collect();
    Ok(heights)
}

/// Layers computed together before they are handed on: enough to keep every core busy, few
/// enough that the bricks in their reach stay a thin slab of the volume.
const LAYER_RUN: usize = 16;

/// Slices a coefficient volume held in memory; see [`slice`]. For the separable bases each
/// layer collapses the coefficients along the axis into a 2D spline (4 nodes per column for the
/// cubic B-spline), so a layer node costs 16 terms instead of 64, and evaluates only the blocks
/// of its grid a contour can cross; values are those of [`CoefficientVolume::value`] up to
/// float rounding, outside the grid box included.
pub fn slice_volume(
    volume: &CoefficientVolume,
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    report: Report,
) -> Result<Vec<Layer>, SliceError> {
    slice_volume_range(volume, bounds, options, 0..usize::MAX, report)
}

/// The layers of [`slice_volume`] numbered `range` (from 0 at the first plane), each the same
/// as in the whole slicing: every layer is computed alone from its own plane, so layers can be
/// sliced in parts and concatenated. A layer needs only the coefficients within the basis
/// support of its plane.
///
/// Finished layers are reported to `report`, which is polled for a stop as they finish: a
/// stopped slicing returns [`SliceError::Stopped`].
pub fn slice_volume_range(
    volume: &CoefficientVolume,
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    range: std::ops::Range<usize>,
    report: Report,
) -> Result<Vec<Layer>, SliceError> {
    let all = layer_heights(bounds, options)?.len();
    let count = range.end.min(all).saturating_sub(range.start);
    let counter = Span::whole(report).counter(count);
    if !volume.basis.is_separable() {
        let field = &|p| volume.value(p);
        return slice_points(field, bounds, options, range, Some(&counter));
    }
    let mut layers = Vec::new();
    slice_bricks(
        &volume.coeffs,
        &volume.grid,
        volume.basis,
        volume.coeffs.background(),
        bounds,
        options,
        range,
        &mut |layer| {
            layers.push(layer);
            counter.tick();
            if counter.stopped() {
                return Err(SliceError::Stopped);
            }
            Ok(())
        },
    )?;
    Ok(layers)
}

/// Slices a separable coefficient volume whose bricks come from `source` (`grid`, `basis` and
/// `background` are the volume's), handing each layer to `sink` in order. Layers are computed
/// in parallel runs, each holding only the slabs of bricks within its planes' support, so memory
/// follows a window of the volume and layers leave as they are done. Returns what the
/// contouring visited, summed over the layers.
#[allow(clippy::too_many_arguments)]
pub fn slice_bricks<S: BrickSource + ?Sized>(
    source: &S,
    grid: &Grid,
    basis: Basis,
    background: Background,
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    range: std::ops::Range<usize>,
    sink: &mut dyn FnMut(Layer) -> Result<(), S::Error>,
) -> Result<LayerCost, S::Error> {
    let profile = match basis {
        Basis::Trilinear => Profile::Linear,
        Basis::Bspline2 => Profile::Quadratic,
        Basis::Bspline3 => Profile::Cubic,
        Basis::Pg { .. } => {
            return Err(SliceError::BadParameter(
                "slicing brick by brick needs a separable basis".into(),
            )
            .into())
        }
    };
    let job = Job::new(bounds, options, range)?;
    let axis = options.axis.indices()[0];
    let mut window = Window::new(source, axis);
    let mut total = LayerCost::default();
    let node_windows = NodeWindows::new(grid, profile, axis, job.plane.node_coordinates());
    let wanted = |run: &[f32]| -> Vec<usize> {
        run.iter()
            .flat_map(|&h| tap_layers(grid, profile, axis, h))
            .map(|n| n / BRICK_EDGE)
            .collect()
    };
    let runs: Vec<&[f32]> = job.heights.chunks(LAYER_RUN).collect();
    if let Some(first) = runs.first() {
        window.hold(&wanted(first), Vec::new())?;
    }
    for (i, run) in runs.iter().enumerate() {
        let next = runs.get(i + 1).map(|r| wanted(r));
        let ahead = next.as_deref().map_or(Vec::new(), |n| window.missing(n));
        let held = &window;
        // The next run's new slabs load while this run's layers are contoured, rather than
        // between the runs, when the threads that finished their layers would wait.
        let (layers, loaded) = rayon::join(
            || {
                run.par_iter()
                    .map(|&h| {
                        let layer = |n| held.layer(n);
                        let plane = CollapsedPlane::new(
                            grid,
                            background,
                            profile,
                            axis,
                            h,
                            &layer,
                            Some(&node_windows),
                        );
                        job.layer(&plane, h)
                    })
                    .collect::<Vec<(Layer, LayerCost)>>()
            },
            || held.load(&ahead),
        );
        for (layer, cost) in layers {
            total.nodes += cost.nodes;
            total.blocks += cost.blocks;
            total.crossings += cost.crossings;
            sink(layer)?;
        }
        if let Some(next) = next {
            window.hold(&next, loaded?)?;
        }
    }
    Ok(total)
}

/// Cuts the solid `field < 0` by the planes of [`layer_heights`] within `bounds`.
///
/// Per layer the field is sampled on a 2D grid of spacing `options.resolution` covering the
/// bounds (centred on them), surrounded by one ring of nodes counted as outside so every loop
/// closes (a solid cut by the bounds is closed less than one spacing outside them). Each crossed
/// grid edge gets one vertex, placed at the zero of the field along the edge (regula falsi,
/// Illinois) and kept a little away from the nodes; ambiguous cells are split by the asymptotic
/// decider (the sign of the bilinear interpolant at its saddle). Hence, before simplification,
/// the loops of a layer are closed, simple and pairwise disjoint. They are traced with the
/// inside on their left: outer boundaries counter-clockwise, holes clockwise.
/// [`simplify_loops`] then reduces them to `options.tolerance` keeping these properties.
///
/// Non-finite field values count as outside. Layers run in parallel; the output does not depend
/// on the number of threads.
pub fn slice(
    field: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
) -> Result<Vec<Layer>, SliceError> {
    slice_points(field, bounds, options, 0..usize::MAX, None)
}

/// [`slice`] of the layers numbered `range`, every node of every layer evaluated.
fn slice_points(
    field: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    range: std::ops::Range<usize>,
    counter: Option<&Counter>,
) -> Result<Vec<Layer>, SliceError> {
    let job = Job::new(bounds, options, range)?;
    let axis = options.axis;
    job.heights
        .par_iter()
        .map(|&h| {
            if pgvol_core::progress::stopped(counter) {
                return Err(SliceError::Stopped);
            }
            let layer = job.layer(&PointField { field, axis, h }, h).0;
            pgvol_core::progress::tick(counter);
            Ok(layer)
        })
        .collect()
}

struct PointField<'a> {
    field: &'a (dyn Fn(Vec3) -> f32 + Sync),
    axis: Axis,
    h: f32,
}

impl LayerField for PointField<'_> {
    type Block = ();

    fn value(&self, u: f32, v: f32) -> f32 {
        (self.field)(self.axis.point(self.h, u, v))
    }
}

/// A checked slicing: the layer grid, the heights and the simplification tolerance.
struct Job {
    plane: Plane,
    heights: Vec<f32>,
    tolerance: f32,
}

impl Job {
    fn new(
        bounds: (Vec3, Vec3),
        options: &SliceOptions,
        range: std::ops::Range<usize>,
    ) -> Result<Job, SliceError> {
        if !(bounds.0.is_finite() && bounds.1.is_finite() && bounds.0.cmple(bounds.1).all()) {
            return Err(SliceError::BadParameter(
                "slice bounds must be finite with min <= max".into(),
            ));
        }
        let res = options.resolution;
        if !(res.is_finite() && res > 0.0) {
            return Err(SliceError::BadParameter(format!(
                "slice resolution must be positive, got {res}"
            )));
        }
        if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
            return Err(SliceError::BadParameter(format!(
                "simplification tolerance must be >= 0, got {}",
                options.tolerance
            )));
        }
        let [_, iu, iv] = options.axis.indices();
        let plane = Plane::new(
            (bounds.0[iu], bounds.1[iu]),
            (bounds.0[iv], bounds.1[iv]),
            res,
        )?;
        let mut heights = layer_heights(bounds, options)?;
        heights.truncate(range.end);
        heights.drain(..range.start.min(heights.len()));
        Ok(Job {
            plane,
            heights,
            tolerance: options.tolerance,
        })
    }

    /// The layer at height `h` of `field`, simplified, with what its contouring visited.
    fn layer(&self, field: &impl LayerField, h: f32) -> (Layer, LayerCost) {
        let mut cost = LayerCost::default();
        let raw = self.plane.contours(field, &mut cost);
        let loops = simplify_loops(&raw, self.tolerance)
            .into_iter()
            .map(|points| {
                let hole = signed_area(&points) < 0.0;
                Loop { points, hole }
            })
            .collect();
        (Layer { height: h, loops }, cost)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collapsed_planes_match_the_volume() {
        let grid = Grid {
            origin: Vec3::new(-1.0, -0.8, -0.6),
            spacing: 0.1,
            dims: [21, 15, 13],
            offset: Default::default(),
        };
        let mut samples = Vec::with_capacity(grid.len());
        for k in 0..grid.dims[2] {
            for j in 0..grid.dims[1] {
                for i in 0..grid.dims[0] {
                    let p = grid.point(i, j, k);
                    samples.push((2.0 * p.x).sin() * p.y + p.z * p.z - 0.1);
                }
            }
        }
        for (basis, profile) in [
            (Basis::Trilinear, Profile::Linear),
            (Basis::Bspline2, Profile::Quadratic),
            (Basis::Bspline3, Profile::Cubic),
        ] {
            let vol = CoefficientVolume::interpolate(grid, basis, samples.clone()).unwrap();
            for axis in [Axis::X, Axis::Y, Axis::Z] {
                for h in [-1.3f32, -0.6, -0.137, 0.0, 0.42, 0.6, 1.7] {
                    let a = axis.indices()[0];
                    let mut window = Window::new(&vol.coeffs, a);
                    let taps: Vec<usize> = tap_layers(&grid, profile, a, h)
                        .iter()
                        .map(|n| n / BRICK_EDGE)
                        .collect();
                    // Loaded ahead, as slicing loads the next run's slabs.
                    let loaded = window.load(&window.missing(&taps)).unwrap();
                    window.hold(&taps, loaded).unwrap();
                    let background = vol.coeffs.background();
                    let layer = |n| window.layer(n);
                    // The nodes' windows worked out beforehand, here for nodes 1..6: sampled
                    // from node 2 on, they give the values sampling by place gives.
                    let (grid_us, grid_vs) = (
                        [-3.0f32, -2.0, -0.33, 0.0, 0.5, 1.9],
                        [-9.0f32, -0.2, 0.0, 0.5, 0.71, 2.0],
                    );
                    let windows = NodeWindows::new(&grid, profile, a, [&grid_us, &grid_vs]);
                    let plane = CollapsedPlane::new(&grid, background, profile, a, h, &layer, None);
                    let us = [-2.0, -0.33, 0.0, 0.5, 1.9];
                    let vs = [-0.2, 0.0, 0.5, 0.71, 2.0];
                    let mut batch = [0.0f32; 25];
                    plane.sample([0, 0], &us, &vs, &mut batch, &mut Default::default());
                    let known = CollapsedPlane::new(
                        &grid,
                        background,
                        profile,
                        a,
                        h,
                        &layer,
                        Some(&windows),
                    );
                    let mut by_index = [0.0f32; 16];
                    let (us4, vs4) = (&grid_us[2..], &grid_vs[2..]);
                    known.sample([2, 2], us4, vs4, &mut by_index, &mut Default::default());
                    let mut by_place = [0.0f32; 16];
                    plane.sample([0, 0], us4, vs4, &mut by_place, &mut Default::default());
                    assert_eq!(by_index.map(f32::to_bits), by_place.map(f32::to_bits));
                    for (j, &v) in vs.iter().enumerate() {
                        for (i, &u) in us.iter().enumerate() {
                            let want = vol.value(axis.point(h, u, v));
                            for got in [plane.value(u, v), batch[i + 5 * j]] {
                                assert!(
                                    (want - got).abs() < 1e-5,
                                    "{basis:?} {axis:?} h={h} ({u}, {v}): {got} vs {want}"
                                );
                            }
                        }
                    }
                    // Edges between the nodes of regular blocks, one inside and one at the
                    // box's low corner (whose windows read mirrored coefficients): the zero
                    // found from what sampling kept is the one found along the edge, bit for
                    // bit.
                    let [ou, ov] = plane_axes(a).map(|k| grid.origin[k]);
                    for (us, vs) in [
                        ([0.03f32, 0.13, 0.23, 0.33], [0.11f32, 0.21, 0.31]),
                        (
                            [0.0, 0.1, 0.2, 0.3].map(|d| ou + d),
                            [0.0, 0.1, 0.2].map(|d| ov + d),
                        ),
                    ] {
                        let mut nodes = [0.0f32; 12];
                        let mut block = Default::default();
                        plane.sample([0, 0], &us, &vs, &mut nodes, &mut block);
                        assert!(block.gathered, "{basis:?} {axis:?} h={h}: nothing kept");
                        for (j, &v) in vs.iter().enumerate() {
                            for (i, &u) in us.iter().enumerate() {
                                for step in [[0.1f32, 0.0], [0.0, 0.1]] {
                                    let p = [u, v];
                                    let a = plane.value(u, v);
                                    let b = plane.value(u + step[0], v + step[1]);
                                    // Root finding needs ends of opposite signs; other edges
                                    // are given some, which search the same points of the edge.
                                    let [a, b] = if (a < 0.0) != (b < 0.0) {
                                        [a, b]
                                    } else {
                                        [-1.0, 1.0]
                                    };
                                    let kept = plane.edge_zero(&block, [i, j], p, step, [a, b]);
                                    let along = plane::edge_root(&*plane.along(p, step), a, b);
                                    assert_eq!(
                                        kept.to_bits(),
                                        along.to_bits(),
                                        "{basis:?} {axis:?} h={h} ({u}, {v}) by {step:?}"
                                    );
                                }
                            }
                        }
                    }
                    // Segments of a spacing or less along either plane axis, across knots,
                    // between nodes a hair to either side of knots, inside the box and leaving
                    // it: the fraction-of-the-way function agrees with the point values.
                    for (p, step) in [
                        ([0.03f32, 0.11], [0.1f32, 0.0]),
                        ([0.03, 0.11], [0.0, 0.1]),
                        ([ou + 0.3 - 1e-6, 0.2], [0.1 + 2e-6, 0.0]),
                        ([0.2, ov + 0.4 + 1e-6], [0.0, 0.1 - 2e-6]),
                        ([-0.51, 0.2], [0.07, 0.0]),
                        ([0.25, -0.5], [0.0, 0.1]),
                        ([0.95, 0.3], [0.1, 0.0]),
                        ([-1.45, 0.3], [0.1, 0.0]),
                    ] {
                        let along = plane.along(p, step);
                        for t in [0.0f32, 0.13, 0.5, 0.77, 1.0] {
                            let (u, v) = (p[0] + step[0] * t, p[1] + step[1] * t);
                            let (want, got) = (plane.value(u, v), along(t));
                            assert!(
                                (want - got).abs() < 1e-5,
                                "{basis:?} {axis:?} h={h} along {p:?}+{t}·{step:?}: {got} vs {want}"
                            );
                        }
                    }
                }
            }
        }
    }
}
