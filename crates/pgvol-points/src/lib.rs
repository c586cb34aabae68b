//! Implicit surfaces through oriented points, as coefficient volumes.
//!
//! Every method turns the points into constraints (value 0 at each point, ±ε at points moved
//! ε along its normal), evaluates a field at the grid nodes within a band of the points and
//! fits the cubic B-spline coefficients to those nodes brick by brick; the rest of the grid
//! is background by side. The methods differ in the field near the points:
//! - [`Method::Spline`]: the coefficients of the band's bricks fitted to the constraints by
//!   weighted least squares with a smoothness term ([`spline_fit`]), starting from and weakly
//!   pulled towards the tangent-plane field.
//! - [`Method::Tangent`]: the blended tangent-plane distance of the nearest points
//!   ([`tangent`]) at the nodes, interpolated by the B-spline volume; no system to solve.
//! - [`Method::RbfWendland`]: compactly supported RBFs ([`wendland`]), a sparse positive
//!   definite system solved by conjugate gradients, correcting the `spline` field so that the
//!   result interpolates the constraints.
//! - [`Method::RbfCubic`]: the global r³ RBF with a linear term ([`cubic`]), dense, for small
//!   clouds only.
//!
//! The Wendland RBFs interpolate the correction to a base field rather than the constraint
//! values themselves (a base field plus compactly supported corrections, as in Ohtake et al.
//! 2003): alone, their sum fades to zero a support away from the points, where zero says
//! nothing of the side, and spurious surfaces appear.

pub mod band;
pub mod bridge;
mod cloud;
pub mod contours;
pub mod cubic;
pub mod index;
pub mod normals;
pub mod orientation;
pub mod plane_distance;
pub mod plane_fit;
pub mod sections;
pub mod spline_fit;
pub mod stack;
pub mod tangent;
#[cfg(test)]
mod test_points;
pub mod wendland;

use std::time::Instant;

use glam::Vec3;
use pgvol_core::Grid;
use pgvol_field::{Basis, CoefficientVolume, FieldError};

pub use cloud::PointCloud;
pub use cubic::MAX_CUBIC_CENTRES;
pub use index::{mean_spacing, sampling_radius};
pub use normals::estimate_normals;

/// How the field through the points is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// B-spline coefficients fitted to the constraints by weighted least squares.
    #[default]
    Spline,
    /// Tangent-plane distance at the nodes, interpolated by the B-spline volume.
    Tangent,
    /// Wendland compactly supported RBFs, sparse system.
    RbfWendland,
    /// Cubic RBFs with a linear term, dense system.
    RbfCubic,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Spline => "spline",
            Method::Tangent => "tangent",
            Method::RbfWendland => "rbf-wendland",
            Method::RbfCubic => "rbf-cubic",
        }
    }
}

/// Distinct points a surface fit needs at least.
pub const MIN_POINTS: usize = 10;

/// Off-surface constraints lie this many point spacings along the normal: less than half the
/// spacing keeps them nearer their own point than a neighbouring sheet a spacing away.
pub const OFFSET_SPACINGS: f32 = 0.5;

/// Wendland support radius, in point spacings: about 28 points of a flat sheet (and as many
/// off-surface centres) fall in a support, enough to bridge uneven sampling.
pub const SUPPORT_SPACINGS: f32 = 3.0;

/// The support radius is at least this many grid spacings, so every grid cell at the surface
/// has nodes the RBF reaches.
pub const SUPPORT_GRID_SPACINGS: f32 = 2.0;

/// Sampling radius ([`sampling_radius`]), in grid spacings, beyond which a cloud is too sparse
/// for its grid. The band of nodes sampled around the points then leaves holes between them
/// through which the outside floods in, and the least-squares fit, with few constraints per
/// unknown, stops at its iteration cap. 3 000 random points on a unit sphere (radius 0.0875):
/// exact at 128³ (5.1 spacings, 140 iterations) and 192³ (7.6, 297 iterations), volume 1.13 of
/// 4.19 and Euler −20 at 256³ (10.1, stopped at 400).
pub const MAX_RADIUS_SPACINGS: f32 = 8.0;

/// Parameters of a reconstruction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointsOptions {
    pub method: Method,
    /// Node values are kept within this distance (mesh units) of the points and clamped to it
    /// beyond.
    pub band: f32,
    /// Wendland support radius in mesh units (default from the point spacing and the grid).
    pub support: Option<f32>,
}

/// What a reconstruction did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointsReport {
    pub method: &'static str,
    pub points: usize,
    /// Whether the normals were estimated (the cloud had none).
    pub normals_estimated: bool,
    /// Mean distance to the nearest neighbour.
    pub spacing: f32,
    /// Off-surface offset ε.
    pub offset: f32,
    /// RBF centres, or the constraints of the least-squares fit (`spline`; 0 for `tangent`).
    pub centres: usize,
    /// Wendland support radius (0 otherwise).
    pub support: f32,
    /// Conjugate-gradient iterations and final relative residual (Wendland, or the
    /// least-squares fit).
    pub iterations: usize,
    pub residual: f64,
    /// Whether every solve reached its tolerance before its iteration cap (true when there
    /// is no solve).
    pub converged: bool,
    /// What the check of given normals found and changed (nothing for estimated ones).
    pub orientation: orientation::Orientation,
    /// Stored matrix entries (Wendland).
    pub matrix_entries: usize,
    /// Stored bricks of node samples.
    pub bricks: usize,
    pub seconds_normals: f64,
    pub seconds_solve: f64,
    pub seconds_fit: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum PointsError {
    #[error("{0} points given; at least {MIN_POINTS} are needed to fit a surface")]
    TooFew(usize),
    #[error("{normals} normals for {points} points")]
    NormalCount { points: usize, normals: usize },
    #[error(
        "normal {0} is zero or not finite: give unit normals, or none (leave out nx, ny, nz) to \
         have them estimated"
    )]
    BadNormal(usize),
    #[error(
        "rbf-cubic solves a dense system of 2 centres per point and takes at most {max} centres \
         ({} points); this cloud has {points} points: use the rbf-wendland or spline method, \
         which are sparse",
        max / 2
    )]
    TooManyForCubic { points: usize, max: usize },
    #[error("the cubic RBF system is singular (repeated points, or all points on one plane)")]
    Singular,
    #[error("all points coincide")]
    NoSpread,
    #[error(
        "the points are too sparse for the grid: the 6 nearest neighbours of a point lie within \
         {radius:.4} on average (the nearest {spacing:.4}), {:.1} grid spacings of \
         {grid_spacing:.4}, and a fit needs them within {MAX_RADIUS_SPACINGS} (farther, the band \
         around the points has holes and the solid comes out hollow): use a grid spacing of at \
         least {:.4} (about {nodes} nodes along the longest side) or a denser cloud",
        radius / grid_spacing,
        radius / MAX_RADIUS_SPACINGS
    )]
    TooSparse {
        radius: f32,
        spacing: f32,
        grid_spacing: f32,
        /// Nodes along the grid's longest side at the finest grid that would work.
        nodes: usize,
    },
    #[error(transparent)]
    Field(#[from] FieldError),
}

/// Centres and values: each point at 0, and one off-surface centre per point at ±ε along its
/// normal, alternating sides so inside and outside are held alike with 2 centres per point.
pub fn constraints(points: &[Vec3], normals: &[Vec3], offset: f32) -> (Vec<Vec3>, Vec<f32>) {
    let mut centres = points.to_vec();
    let mut values = vec![0.0; points.len()];
    for (i, (p, n)) in points.iter().zip(normals).enumerate() {
        let side = if i % 2 == 0 { 1.0 } else { -1.0 };
        centres.push(*p + *n * (side * offset));
        values.push(side * offset);
    }
    (centres, values)
}

/// One point per cell of side `cell` when the cloud is denser than that (with its normal),
/// and the spacing of what is kept. The RBF correction cannot show detail finer than the grid,
/// and a support holding hundreds of centres makes the system large and slow to converge.
fn thin(points: &[Vec3], normals: &[Vec3], spacing: f32, cell: f32) -> (Vec<Vec3>, Vec<Vec3>, f32) {
    if cell <= spacing {
        return (points.to_vec(), normals.to_vec(), spacing);
    }
    let key = |p: Vec3| (p / cell).floor().as_ivec3().to_array();
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| (key(points[i]), i));
    order.dedup_by_key(|i| key(points[*i]));
    let kept: Vec<Vec3> = order.iter().map(|&i| points[i]).collect();
    let kept_spacing = mean_spacing(&kept).max(spacing);
    (
        kept,
        order.iter().map(|&i| normals[i]).collect(),
        kept_spacing,
    )
}

/// The Wendland correction interpolating what `base` leaves of the constraints, on the points
/// thinned to one per cell of a third of the support (the correction cannot show detail finer
/// than the grid, and a support holding hundreds of centres makes the system large and slow
/// to converge).
fn wendland_correction(
    points: &[Vec3],
    normals: &[Vec3],
    spacing: f32,
    support: f32,
    base: &(dyn Fn(Vec3) -> f32 + Sync),
) -> (wendland::WendlandFit<'static>, f32) {
    use rayon::prelude::*;
    let (kept, kept_normals, kept_spacing) =
        thin(points, normals, spacing, support / SUPPORT_SPACINGS);
    let offset = OFFSET_SPACINGS * kept_spacing;
    let (centres, values) = constraints(&kept, &kept_normals, offset);
    let values: Vec<f32> = centres
        .par_iter()
        .zip(&values)
        .map(|(&c, &v)| v - base(c))
        .collect();
    (wendland::fit_owned(centres, &values, support), offset)
}

/// The Wendland support radius for a cloud of `spacing` on `grid`.
pub fn default_support(spacing: f32, grid: &Grid) -> f32 {
    (SUPPORT_SPACINGS * spacing).max(SUPPORT_GRID_SPACINGS * grid.spacing)
}

/// Removes exact duplicates (they make the RBF systems singular), keeping the first normal.
pub fn dedup(cloud: &PointCloud) -> PointCloud {
    let mut order: Vec<usize> = (0..cloud.points.len()).collect();
    let key = |i: usize| cloud.points[i].to_array().map(f32::to_bits);
    order.sort_by_key(|&i| (key(i), i));
    order.dedup_by_key(|i| key(*i));
    order.sort_unstable();
    PointCloud {
        points: order.iter().map(|&i| cloud.points[i]).collect(),
        normals: cloud
            .normals
            .as_ref()
            .map(|n| order.iter().map(|&i| n[i]).collect()),
    }
}

/// Refuses `points` (mean spacing `spacing`) too sparse for `grid` ([`MAX_RADIUS_SPACINGS`]),
/// with the grid spacing that would work.
pub fn check_spacing(points: &[Vec3], spacing: f32, grid: &Grid) -> Result<(), PointsError> {
    let radius = sampling_radius(points);
    if radius <= MAX_RADIUS_SPACINGS * grid.spacing {
        return Ok(());
    }
    let needed = radius / MAX_RADIUS_SPACINGS;
    let longest = grid.dims.iter().copied().max().unwrap_or(1);
    let extent = longest.saturating_sub(1) as f32 * grid.spacing;
    Err(PointsError::TooSparse {
        radius,
        spacing,
        grid_spacing: grid.spacing,
        nodes: (extent / needed).floor() as usize + 1,
    })
}

/// Fits a cubic B-spline coefficient volume on `grid` whose zero set passes through `cloud`.
pub fn reconstruct(
    cloud: &PointCloud,
    grid: Grid,
    options: &PointsOptions,
) -> Result<(CoefficientVolume, PointsReport), PointsError> {
    reconstruct_with(cloud, grid, options, &mut |_| {})
}

/// A continuous field through the points, as [`reconstruct_with`] hands it over.
pub type PointField<'a> = dyn Fn(Vec3) -> f32 + Sync + 'a;

/// [`reconstruct`], handing `visit` the method's own field through the points, continuous and
/// defined everywhere, before it is sampled at the grid nodes (once, after the solve): for
/// `rbf-wendland` the least-squares spline plus the Wendland RBFs, which interpolate the
/// constraints; for `rbf-cubic` the cubic RBF interpolant; for `tangent` the blended
/// tangent-plane distance (beyond its reach, the band with the side of the nearest point's
/// tangent plane); for `spline` the fitted B-spline, which is the result itself. Cross-sections
/// of this field ([`sections`]) are those of the interpolant, not of its B-spline resampling.
pub fn reconstruct_with(
    cloud: &PointCloud,
    grid: Grid,
    options: &PointsOptions,
    visit: &mut dyn FnMut(&PointField),
) -> Result<(CoefficientVolume, PointsReport), PointsError> {
    let cloud = dedup(cloud);
    let points = &cloud.points;
    if points.len() < MIN_POINTS {
        return Err(PointsError::TooFew(points.len()));
    }
    if let Some(normals) = &cloud.normals {
        if normals.len() != points.len() {
            return Err(PointsError::NormalCount {
                points: points.len(),
                normals: normals.len(),
            });
        }
        if let Some(i) = normals
            .iter()
            .position(|n| !(n.is_finite() && n.length_squared() > 1e-12))
        {
            return Err(PointsError::BadNormal(i));
        }
    }
    if options.method == Method::RbfCubic && 2 * points.len() > MAX_CUBIC_CENTRES {
        return Err(PointsError::TooManyForCubic {
            points: points.len(),
            max: MAX_CUBIC_CENTRES,
        });
    }
    let spacing = mean_spacing(points);
    if spacing.is_nan() || spacing <= 0.0 {
        return Err(PointsError::NoSpread);
    }
    check_spacing(points, spacing, &grid)?;
    let mut report = PointsReport {
        method: options.method.name(),
        points: points.len(),
        spacing,
        converged: true,
        ..Default::default()
    };
    let t = Instant::now();
    let normals: Vec<Vec3> = match &cloud.normals {
        Some(n) => {
            let mut normals: Vec<Vec3> = n.iter().map(|v| v.normalize()).collect();
            report.orientation = orientation::check_orientation(points, &mut normals, spacing);
            normals
        }
        None => {
            report.normals_estimated = true;
            estimate_normals(points, spacing)
        }
    };
    report.seconds_normals = t.elapsed().as_secs_f64();
    let tangent = tangent::TangentField::new(points, &normals, spacing, options.band);
    let offset = OFFSET_SPACINGS * spacing;
    report.offset = offset;
    let t = Instant::now();
    let samples = match options.method {
        Method::RbfCubic => {
            let (centres, values) = constraints(points, &normals, offset);
            let fit = cubic::fit(&centres, &values).ok_or(PointsError::Singular)?;
            report.centres = centres.len();
            report.seconds_solve = t.elapsed().as_secs_f64();
            visit(&|x| fit.value(x));
            band::sample_band(&grid, points, &tangent, options.band, &|x, _| fit.value(x))
        }
        Method::Tangent => {
            let band = options.band;
            visit(&|x| {
                tangent
                    .value(x, &mut Vec::new())
                    .unwrap_or_else(|| band.copysign(tangent.far_side(x)))
            });
            band::sample_band(&grid, points, &tangent, band, &|_, t| t)
        }
        Method::Spline | Method::RbfWendland => {
            band::sample_band(&grid, points, &tangent, options.band, &|_, t| t)
        }
    };
    report.bricks = samples.stored_count();
    let t = Instant::now();
    let (mut volume, _) = pgvol_field::fit::interp_sparse(
        grid,
        Basis::Bspline3,
        &samples,
        pgvol_core::progress::QUIET,
    )?;
    report.seconds_fit = t.elapsed().as_secs_f64();
    if matches!(options.method, Method::Spline | Method::RbfWendland) {
        let t = Instant::now();
        let (centres, values) = constraints(points, &normals, offset);
        let (coeffs, fit) = spline_fit::fit(
            &grid,
            &volume.coeffs,
            &centres,
            &values,
            spline_fit::SMOOTHNESS,
            spline_fit::pull_weight(grid.spacing, spacing),
        );
        report.centres = fit.constraints;
        report.iterations = fit.iterations;
        report.residual = fit.residual;
        report.converged = fit.converged;
        volume = CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs)?;
        report.seconds_solve = t.elapsed().as_secs_f64();
        if options.method == Method::Spline {
            visit(&|x| volume.value(x));
        }
    }
    if options.method == Method::RbfWendland {
        // The RBFs correct the least-squares spline, so that the field interpolates the
        // constraints; where they fade out, the spline holds the side.
        let t = Instant::now();
        let support = options
            .support
            .unwrap_or_else(|| default_support(spacing, &grid));
        let base = |x: Vec3| volume.value(x);
        let (fit, offset) = wendland_correction(points, &normals, spacing, support, &base);
        report.offset = offset;
        report.centres = fit.centres();
        report.iterations = fit.iterations;
        report.residual = fit.residual;
        report.converged &= fit.converged();
        report.matrix_entries = fit.entries;
        report.support = support;
        let field = |x: Vec3| base(x) + fit.value(x);
        let samples = band::resample(&grid, &samples, options.band, &field);
        report.seconds_solve += t.elapsed().as_secs_f64();
        visit(&field);
        let t = Instant::now();
        volume = pgvol_field::fit::interp_sparse(
            grid,
            Basis::Bspline3,
            &samples,
            pgvol_core::progress::QUIET,
        )?
        .0;
        report.seconds_fit += t.elapsed().as_secs_f64();
    }
    Ok((volume, report))
}

/// Fits a cubic B-spline coefficient volume on `grid` through a stack of contour planes
/// (sorted by height) along `axis` by distance interpolation ([`stack`]); `band` in mesh units.
pub fn reconstruct_stack(
    planes: &[contours::ContourPlane],
    axis: usize,
    grid: Grid,
    band: f32,
) -> Result<(CoefficientVolume, PointsReport), PointsError> {
    let points = planes.iter().flat_map(|p| &p.loops).map(Vec::len).sum();
    if points < 3 {
        return Err(PointsError::TooFew(points));
    }
    let t = Instant::now();
    let samples = stack::stack_samples(planes, axis % 3, &grid, band);
    let mut report = PointsReport {
        method: Method::Spline.name(),
        points,
        bricks: samples.stored_count(),
        seconds_solve: t.elapsed().as_secs_f64(),
        converged: true,
        ..Default::default()
    };
    let t = Instant::now();
    let (volume, _) = pgvol_field::fit::interp_sparse(
        grid,
        Basis::Bspline3,
        &samples,
        pgvol_core::progress::QUIET,
    )?;
    report.seconds_fit = t.elapsed().as_secs_f64();
    Ok((volume, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_points::sphere_points;

    /// Largest |distance from the origin − r| over the zero crossings along node rows.
    fn radius_error(volume: &CoefficientVolume, r: f32) -> f32 {
        let mut worst = 0.0f32;
        for k in 0..24 {
            let dir = sphere_points(24, 1.0)[k];
            // Bisection along the ray: inside at the centre, outside at 1.5 r.
            let (mut a, mut b) = (0.0f32, 1.5 * r);
            assert!(volume.value(Vec3::ZERO) < 0.0);
            assert!(volume.value(dir * b) > 0.0);
            for _ in 0..40 {
                let m = 0.5 * (a + b);
                if volume.value(dir * m) < 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            worst = worst.max((a - r).abs());
        }
        worst
    }

    fn sphere(n: usize, method: Method, with_normals: bool) -> (f32, PointsReport, f32) {
        let points = sphere_points(n, 1.0);
        let normals = with_normals.then(|| points.clone());
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 48).unwrap();
        let options = PointsOptions {
            method,
            band: 4.0 * grid.spacing,
            support: None,
        };
        let cloud = PointCloud { points, normals };
        let (volume, report) = reconstruct(&cloud, grid, &options).unwrap();
        (radius_error(&volume, 1.0), report, grid.spacing)
    }

    /// Bounds in grid spacings: about 3× the measured errors (docs/points.md), the tangent
    /// planes' blend and the B-spline interpolation of its samples being the loosest.
    #[test]
    fn every_method_finds_the_sphere() {
        for (method, n, bound) in [
            (Method::Spline, 4000, 0.01),
            (Method::Tangent, 4000, 0.1),
            (Method::RbfWendland, 4000, 0.02),
            (Method::RbfWendland, 16000, 0.02),
            (Method::RbfCubic, 1000, 0.02),
        ] {
            let (err, report, h) = sphere(n, method, true);
            eprintln!("{method:?}: {}", err / h);
            assert!(
                err < bound * h,
                "{method:?}: radius off by {err} (h = {h}), {report:?}"
            );
        }
    }

    /// Points about three grid spacings apart: the tangent planes alone leave facets, the
    /// least-squares fit (the `spline` method) bends between the points.
    #[test]
    fn the_fit_beats_the_tangent_field_on_a_sparse_sphere() {
        let (fitted, report, h) = sphere(600, Method::Spline, true);
        let (tangent, _, _) = sphere(600, Method::Tangent, true);
        eprintln!(
            "600 points: spline {} tangent {} (grid spacings)",
            fitted / h,
            tangent / h
        );
        assert!(report.iterations > 0, "{report:?}");
        assert!(fitted < 0.5 * tangent, "spline {fitted}, tangent {tangent}");
    }

    #[test]
    fn estimated_normals_give_the_same_sphere() {
        let (err, report, h) = sphere(4000, Method::Spline, false);
        assert!(report.normals_estimated);
        assert!(err < 0.1 * h, "radius off by {err} (h = {h})");
    }

    #[test]
    fn cubic_refuses_large_clouds() {
        let cloud = PointCloud {
            points: sphere_points(MAX_CUBIC_CENTRES, 1.0),
            normals: None,
        };
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 16).unwrap();
        let options = PointsOptions {
            method: Method::RbfCubic,
            band: 0.5,
            support: None,
        };
        let err = reconstruct(&cloud, grid, &options).unwrap_err();
        assert!(matches!(err, PointsError::TooManyForCubic { .. }), "{err}");
        assert!(
            !err.to_string().contains("--"),
            "the library names no flags: {err}"
        );
    }
}
