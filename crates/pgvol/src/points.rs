//! Point clouds → coefficient volumes: the readers for point files, the options with their
//! defaults, the memory estimate and the call into `pgvol-points`.

use std::cmp::Ordering::Greater;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use glam::Vec3;
use std::time::Instant;

use pgvol_format::PgvFile;
use pgvol_points::sections::SectionPlanes;
use pgvol_points::{Method, PointCloud, PointsReport};
use pgvol_slice::{Axis, Layer, SliceError};

use crate::band::BAND_KEY;
use crate::encode::ENCODE_BAND;
use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::field_value::Field;
use crate::grid::GridSpec;
use crate::progress::{self, Progress};

pub use pgvol_points::{Method as PointsMethod, MAX_CUBIC_CENTRES};

/// How a point cloud becomes a coefficient volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointsOptions {
    /// The grid around the points' box (default 128 nodes per axis).
    pub grid: GridSpec,
    /// The field through the points (default `Spline`, see `docs/points.md` for the
    /// measurements behind it).
    pub method: Method,
    /// Node values kept within this many grid spacings of the points (default
    /// [`ENCODE_BAND`]), clamped beyond.
    pub band: f32,
    /// Wendland support radius in the cloud's units (default 3 point spacings, at least 2
    /// grid spacings).
    pub support: Option<f32>,
}

impl Default for PointsOptions {
    fn default() -> Self {
        Self {
            grid: GridSpec::default(),
            method: Method::Spline,
            band: ENCODE_BAND,
            support: None,
        }
    }
}

/// A reconstructed field ready to write, with what the reconstruction did.
#[derive(Clone, Debug)]
pub struct Reconstructed {
    /// Header and coefficients.
    pub file: PgvFile,
    /// Points, spacing, whether normals were estimated, the solve.
    pub report: PointsReport,
}

/// The point-cloud file name extensions read as text (one point per line).
pub const POINT_TEXT_EXTENSIONS: [&str; 4] = ["xyz", "csv", "txt", "pts"];

/// Reads a point cloud: PLY (the vertices, with nx, ny, nz when present; faces ignored) or
/// text (`.xyz`, `.csv`, `.txt`, `.pts`: see [`read_cloud_text`]).
pub fn read_point_cloud(path: impl AsRef<Path>) -> Result<PointCloud> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let is_text = POINT_TEXT_EXTENSIONS.contains(&ext.as_str());
    if ext != "ply" && !is_text {
        return Err(Error::file(
            ErrorKind::InputFile,
            path,
            format!(
                "cannot tell the point format from the extension '{ext}': use .ply or one of \
                 .{}",
                POINT_TEXT_EXTENSIONS.join(", .")
            ),
        ));
    }
    let bytes = pgvol_core::read_input(path).reading()?;
    if is_text {
        return read_cloud_text(bytes.as_slice(), path);
    }
    let (points, normals) = pgvol_mesh::read_ply_points(&bytes, path).reading()?;
    Ok(PointCloud { points, normals })
}

/// Parses a text point cloud: per line `x y z` or `x y z nx ny nz` (commas, semicolons,
/// spaces or tabs between), every line alike. Blank lines and lines starting with `#` are
/// skipped, and so is a first line in which no field is a number (a header); a UTF-8
/// byte-order mark is ignored. Coordinates must be finite and below
/// [`MAX_COORDINATE`](pgvol_mesh::MAX_COORDINATE) in magnitude, normals finite; `name` labels
/// errors.
pub fn read_cloud_text(r: impl Read, name: impl AsRef<Path>) -> Result<PointCloud> {
    let name = name.as_ref();
    let fail = |message: String| Error::new(ErrorKind::InputFile, message).at(name);
    let mut cloud = PointCloud::default();
    let mut normals = Vec::new();
    let mut columns = None;
    let mut seen_data = false;
    for (n, line) in BufReader::new(r).lines().enumerate() {
        let line = line.map_err(|e| fail(format!("line {} is not text: {e}", n + 1)))?;
        let line = line.trim_start_matches('\u{feff}').trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let numbers: Vec<Option<f32>> = line
            .split([',', ';', ' ', '\t'])
            .filter(|f| !f.is_empty())
            .map(|f| f.parse::<f32>().ok())
            .collect();
        let first = !seen_data;
        seen_data = true;
        if first && numbers.iter().all(Option::is_none) {
            continue;
        }
        let values: Option<Vec<f32>> = numbers.iter().copied().collect();
        let values = match values {
            Some(v) if (v.len() == 3 || v.len() == 6) && columns.is_none_or(|c| c == v.len()) => v,
            _ => {
                let want = match columns {
                    Some(3) => "three numbers x y z",
                    Some(_) => "six numbers x y z nx ny nz",
                    None => "three numbers x y z or six x y z nx ny nz",
                };
                return Err(fail(format!(
                    "line {}: expected {want} like the lines before, got '{line}'",
                    n + 1
                )));
            }
        };
        columns = Some(values.len());
        let p = Vec3::new(values[0], values[1], values[2]);
        if !p.is_finite() || p.abs().max_element() >= pgvol_mesh::MAX_COORDINATE {
            return Err(fail(format!(
                "line {}: coordinates must be finite and below {:e} in magnitude, got '{line}'",
                n + 1,
                pgvol_mesh::MAX_COORDINATE
            )));
        }
        cloud.points.push(p);
        if values.len() == 6 {
            let normal = Vec3::new(values[3], values[4], values[5]);
            if !normal.is_finite() {
                return Err(fail(format!(
                    "line {}: the normal is not finite: '{line}'",
                    n + 1
                )));
            }
            normals.push(normal);
        }
    }
    if let Some((lo, hi)) = cloud
        .points
        .iter()
        .fold(None, |b: Option<(Vec3, Vec3)>, &p| {
            Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
        })
    {
        crate::frame::require_near_box(lo, hi, "reconstruction from points")?;
    }
    if cloud.points.is_empty() {
        return Err(fail("no points".into()));
    }
    cloud.normals = (columns == Some(6)).then_some(normals);
    Ok(cloud)
}

/// Bytes per stored node brick while sampling and fitting: the samples, the coefficients and
/// the local prefilter's halo, as for a sparse encode.
const BYTES_PER_BRICK: u64 = crate::memory::BYTES_PER_BAND_BRICK;

/// Bytes per point: the point, normal, index, neighbour lists and constraints.
const BYTES_PER_POINT: u64 = 200;

/// Bytes per stored brick held beside the least-squares fit's vectors: the starting
/// coefficients and the result's copy of them (8³ f32 each).
const BYTES_PER_COPY: u64 = 2 * 2048;

/// Estimated peak bytes of reconstructing `points` (mean spacing `spacing`) on `grid`, from the
/// bricks the band around them will really store (counted here, a byte per brick of the grid).
pub fn points_bytes(
    points: &[Vec3],
    spacing: f32,
    grid: &pgvol_core::Grid,
    options: &PointsOptions,
) -> u64 {
    let n = points.len() as u64;
    let bricks =
        pgvol_points::band::band_bricks(grid, points, options.band * grid.spacing).len() as u64;
    let flags = grid
        .dims
        .iter()
        .map(|&d| d.div_ceil(8) as u64)
        .product::<u64>();
    let mut bytes = bricks
        .saturating_mul(BYTES_PER_BRICK)
        .saturating_add(n.saturating_mul(BYTES_PER_POINT))
        .saturating_add(flags);
    match options.method {
        Method::Tangent => {}
        // The least-squares fit over the band's bricks, two constraints per point, beside the
        // starting volume and its copy for the result.
        Method::Spline => {
            bytes += pgvol_points::spline_fit::fit_bytes(bricks, 2 * n)
                + bricks.saturating_mul(BYTES_PER_COPY);
        }
        Method::RbfWendland => {
            let support = options
                .support
                .unwrap_or_else(|| pgvol_points::default_support(spacing, grid));
            // Clouds denser than a third of the support are thinned to one point per cell of
            // that size; two centres per kept point, each row seeing both layers of a sheet
            // within the support.
            let area = n as f64 * f64::from(spacing).powi(2);
            let kept_spacing = f64::from(spacing.max(support / pgvol_points::SUPPORT_SPACINGS));
            let kept = (area / (kept_spacing * kept_spacing)).min(n as f64);
            let per_row = 2.0 * std::f64::consts::PI * (f64::from(support) / kept_spacing).powi(2);
            let entries = 2.0 * kept * per_row;
            let matrix = (entries * pgvol_points::wendland::BYTES_PER_ENTRY as f64) as u64;
            // The spline fit it corrects comes first, and its memory is freed before.
            bytes += matrix.max(
                pgvol_points::spline_fit::fit_bytes(bricks, 2 * n)
                    + bricks.saturating_mul(BYTES_PER_COPY),
            );
        }
        Method::RbfCubic => bytes += pgvol_points::cubic::cubic_bytes(2 * n as usize),
    }
    bytes
}

/// Cross-sections of the field through a point cloud in planes normal to an axis, cut from the
/// field itself (see [`points_with_sections`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SectionOptions {
    /// The axis the planes are normal to.
    pub axis: Axis,
    /// Plane positions along the axis, in the cloud's units, within the grid's box.
    pub heights: Vec<f32>,
    /// Spacing of each plane's sampling grid; `None` (the default) for the grid spacing.
    pub resolution: Option<f32>,
}

impl SectionOptions {
    /// Planes at `heights` along `axis`, sampled at the grid spacing.
    pub fn new(axis: Axis, heights: Vec<f32>) -> Self {
        Self {
            axis,
            heights,
            resolution: None,
        }
    }
}

/// The cross-sections [`points_with_sections`] cut.
#[derive(Clone, Debug, PartialEq)]
pub struct Sections {
    /// One layer per distinct height, bottom first, in the planes' coordinates (see [`Axis`]).
    pub layers: Vec<Layer>,
    /// The heights whose plane misses the surface (their layers hold no loop); each was also
    /// warned of through the progress.
    pub empty: Vec<f32>,
    /// Spacing of the planes' sampling grids.
    pub resolution: f32,
    /// Seconds spent cutting them.
    pub seconds: f64,
}

impl Field {
    /// A field whose zero set passes through `cloud`; see [`points`], which gives the report
    /// too.
    pub fn from_points(
        cloud: &PointCloud,
        options: &PointsOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        Ok(Field::from_file(points(cloud, options, progress)?.file))
    }

    /// A closed solid through a stack of planar contours along `axis`; see [`contours`].
    pub fn from_contours(
        layers: &[Layer],
        axis: Axis,
        options: &PointsOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        Ok(Field::from_file(
            contours(layers, axis, options, progress)?.file,
        ))
    }
}

/// Fits a coefficient volume whose zero set passes through `cloud` (normals estimated and
/// oriented when it has none; see `report.normals_estimated`).
pub fn points(
    cloud: &PointCloud,
    options: &PointsOptions,
    progress: &dyn Progress,
) -> Result<Reconstructed> {
    Ok(reconstruct_points(cloud, options, None, progress)?.0)
}

/// [`points`], and cross-sections of the field through the points in the planes of `sections`,
/// cut from the field the method builds before it is sampled on the grid (as the RBF method's
/// output is): for `RbfWendland` the least-squares spline plus the Wendland RBFs, for `RbfCubic`
/// the cubic RBF, for `Tangent` the blended tangent-plane distance, for `Spline` the fitted
/// B-spline (the result itself). Each plane is contoured on a 2D grid over the grid box's
/// cross-section, every vertex on the field's zero set, and simplified to a tenth of the
/// resolution. The heights are checked against the grid's box before the fit; a height whose
/// plane misses the surface gives an empty layer, listed in `empty` and warned of.
pub fn points_with_sections(
    cloud: &PointCloud,
    options: &PointsOptions,
    sections: &SectionOptions,
    progress: &dyn Progress,
) -> Result<(Reconstructed, Sections)> {
    let (fitted, sections) = reconstruct_points(cloud, options, Some(sections), progress)?;
    let sections =
        sections.ok_or_else(|| Error::new(ErrorKind::Internal, "the sections were not cut"))?;
    Ok((fitted, sections))
}

fn reconstruct_points(
    cloud: &PointCloud,
    options: &PointsOptions,
    sections: Option<&SectionOptions>,
    progress: &dyn Progress,
) -> Result<(Reconstructed, Option<Sections>)> {
    if !(options.band.is_finite() && options.band >= crate::encode::MIN_BAND) {
        return Err(Error::parameter(format!(
            "the band must be at least {} grid spacings, got {}",
            crate::encode::MIN_BAND,
            options.band
        )));
    }
    if let Some(r) = options.support {
        if !(r.is_finite() && r > 0.0) {
            return Err(Error::parameter(format!(
                "the support radius must be a positive length, got {r}"
            )));
        }
    }
    if cloud.points.is_empty() {
        return Err(Error::new(ErrorKind::InputFile, "the cloud has no points"));
    }
    // Clouds given directly, not read from a file, are checked here.
    let max = pgvol_mesh::MAX_COORDINATE;
    if let Some(i) =
        (cloud.points.iter()).position(|p| !(p.is_finite() && p.abs().max_element() < max))
    {
        return Err(Error::parameter(format!(
            "point {i}: coordinates must be finite and below {max:e} in magnitude, got {}",
            cloud.points[i]
        )));
    }
    check_distinct(&cloud.points)?;
    let (lo, hi) = pgvol_points::index::bounds(&cloud.points);
    crate::frame::require_near_box(lo, hi, "reconstruction from points")?;
    let grid = options.grid.grid_for_box(lo, hi)?;
    let planes = sections.map(|s| section_planes(s, &grid)).transpose()?;
    fit_on_grid(cloud, grid, options, (lo, hi), planes.as_ref(), progress)
}

/// The planes of `settings` on `grid`, checked before any work.
fn section_planes(settings: &SectionOptions, grid: &pgvol_core::Grid) -> Result<SectionPlanes> {
    let resolution = settings.resolution.unwrap_or(grid.spacing);
    let planes = SectionPlanes::new(settings.axis, settings.heights.clone(), resolution);
    pgvol_points::sections::check(grid, &planes).map_err(|e| match e {
        SliceError::BadParameter(message) => Error::parameter(message),
        stopped @ SliceError::Stopped => stopped.into(),
    })?;
    Ok(planes)
}

/// Refuses a cloud of fewer distinct points than a fit needs, saying so (its box, a point, would
/// otherwise be refused as an empty box).
fn check_distinct(points: &[Vec3]) -> Result<()> {
    let min = pgvol_points::MIN_POINTS;
    let mut distinct: Vec<[u32; 3]> = Vec::with_capacity(min);
    for p in points {
        let key = p.to_array().map(f32::to_bits);
        if !distinct.contains(&key) {
            distinct.push(key);
            if distinct.len() >= min {
                return Ok(());
            }
        }
    }
    let n = points.len();
    let problem = match (n, distinct.len()) {
        (1, _) => format!("the cloud has a single point, {}", points[0]),
        (_, 1) => format!("all {n} points coincide, at {}", points[0]),
        (_, d) if d == n => format!("the cloud has only {n} points"),
        (_, d) => format!("the cloud's {n} points hold only {d} distinct ones"),
    };
    Err(Error::new(
        ErrorKind::InputFile,
        format!("{problem}; fitting a surface needs at least {min} distinct points"),
    ))
}

/// The reconstruction of `cloud` on `grid`, with the sections of its field by `planes` when
/// given; `bounds` is the box recorded as the source's.
fn fit_on_grid(
    cloud: &PointCloud,
    grid: pgvol_core::Grid,
    options: &PointsOptions,
    (lo, hi): (Vec3, Vec3),
    planes: Option<&SectionPlanes>,
    progress: &dyn Progress,
) -> Result<(Reconstructed, Option<Sections>)> {
    crate::points_warnings::warn_about_outliers(&cloud.points, progress);
    let spacing = pgvol_points::mean_spacing(&cloud.points);
    pgvol_points::check_spacing(&cloud.points, spacing, &grid)
        .map_err(|e| Error::new(ErrorKind::BadParameter, e.to_string()).caused_by(e))?;
    let [nx, ny, nz] = grid.dims;
    crate::memory::check_memory(
        &format!(
            "fitting {} points by {} on a {nx} x {ny} x {nz} grid",
            cloud.points.len(),
            options.method.name()
        ),
        points_bytes(&cloud.points, spacing, &grid, options),
        if options.method == Method::Tangent {
            "lower the resolution or thin the cloud"
        } else {
            "lower the resolution, thin the cloud, or use the tangent method (no system to solve)"
        },
    )?;
    let fit_options = pgvol_points::PointsOptions {
        method: options.method,
        band: options.band * grid.spacing,
        support: options.support,
    };
    // The sections are cut from the method's field while the fit holds it.
    let mut cut: Option<(std::result::Result<Vec<Layer>, SliceError>, f64)> = None;
    let (volume, report) = progress::stage(progress, "fit", |_| {
        pgvol_points::reconstruct_with(cloud, grid, &fit_options, &mut |field| {
            if let Some(planes) = planes {
                let t = Instant::now();
                let layers = pgvol_points::sections::sections(field, &grid, planes);
                cut = Some((layers, t.elapsed().as_secs_f64()));
            }
        })
    })?
    .map_err(|e| {
        let kind = match e {
            pgvol_points::PointsError::TooManyForCubic { .. } => ErrorKind::ResourceLimit,
            pgvol_points::PointsError::TooSparse { .. } => ErrorKind::BadParameter,
            pgvol_points::PointsError::Field(_) => ErrorKind::Internal,
            _ => ErrorKind::InputFile,
        };
        Error::new(kind, e.to_string()).caused_by(e)
    })?;
    crate::points_warnings::warn_about(&report, grid.spacing, progress);
    let sections = match (planes, cut) {
        (None, _) => None,
        (Some(_), None) => {
            return Err(Error::new(
                ErrorKind::Internal,
                "the fit did not hand over its field",
            ))
        }
        (Some(planes), Some((layers, seconds))) => {
            let layers = layers?;
            let empty: Vec<f32> = layers
                .iter()
                .filter(|l| l.loops.is_empty())
                .map(|l| l.height)
                .collect();
            let axis = pgvol_points::sections::axis_name(planes.axis);
            for h in &empty {
                progress.warn(&format!(
                    "the section at {axis} = {h} is empty: the plane misses the surface"
                ));
            }
            Some(Sections {
                layers,
                empty,
                resolution: planes.resolution,
                seconds,
            })
        }
    };
    let mut header = pgvol_format::header_for(&volume, options.method.name(), None);
    header.source_bounds = Some([lo.to_array(), hi.to_array()]);
    header
        .metadata
        .insert(BAND_KEY.into(), format!("{}", fit_options.band));
    header
        .metadata
        .insert("points".into(), report.points.to_string());
    header.metadata.insert(
        "normals".into(),
        if report.normals_estimated {
            "estimated"
        } else {
            "given"
        }
        .into(),
    );
    Ok((
        Reconstructed {
            file: PgvFile { header, volume },
            report,
        },
        sections,
    ))
}

/// Reads a stack of planar contours: the JSON, Common Layer Interface (ASCII or binary) or SVG
/// layer files `pgvol slice` writes, by extension.
pub fn read_layers(path: impl AsRef<Path>) -> Result<Vec<Layer>> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let layers = match ext.as_str() {
        "json" => pgvol_slice::read_slice_json(path).reading()?,
        "cli" => {
            let bytes = pgvol_core::read_input(path).reading()?;
            pgvol_slice::read_cli(&bytes, path).reading()?
        }
        "svg" => {
            let bytes = pgvol_core::read_input(path).reading()?;
            let text = String::from_utf8(bytes).map_err(|_| {
                Error::file(ErrorKind::InputFile, path, "the SVG file is not UTF-8 text")
            })?;
            pgvol_slice::read_svg(&text, path).reading()?
        }
        _ => {
            return Err(Error::file(
                ErrorKind::InputFile,
                path,
                format!(
                    "cannot tell the contour format from the extension '{ext}': use .json, .cli or \
                     .svg, as `pgvol slice` writes them"
                ),
            ))
        }
    };
    if layers.iter().all(|l| l.loops.is_empty()) {
        return Err(Error::file(
            ErrorKind::InputFile,
            path,
            "no closed contours",
        ));
    }
    // The CLI and SVG readers check this themselves; the JSON one does not.
    if let Some(problem) = pgvol_slice::layer_coordinate_problem(&layers) {
        return Err(Error::file(ErrorKind::InputFile, path, problem));
    }
    Ok(layers)
}

/// Fits a coefficient volume through a stack of closed planar contours stacked along `axis`.
/// `Method::Spline` (the default): each plane's exact 2D signed distance, corrected so the
/// plane's spline passes through its loops, fitted across the planes by a cubic B-spline along
/// the axis (evenly spaced planes are put on nodes, see [`SNAP_SPACING`]), leaning regions
/// bridged, the solid closed half a layer (at least 2 grid spacings) beyond the outermost
/// planes; the RBF methods fit points along the loops and caps over the parts of a layer its
/// neighbour does not cover. Holes and several loops per plane are allowed (even-odd). See
/// `docs/points.md` for the measurements and the limits.
pub fn contours(
    layers: &[Layer],
    axis: Axis,
    options: &PointsOptions,
    progress: &dyn Progress,
) -> Result<Reconstructed> {
    let a = match axis {
        Axis::X => 0,
        Axis::Y => 1,
        Axis::Z => 2,
    };
    let mut planes: Vec<pgvol_points::contours::ContourPlane> = layers
        .iter()
        .filter(|l| !l.loops.is_empty())
        .map(|l| pgvol_points::contours::ContourPlane {
            height: l.height,
            loops: l.loops.iter().map(|lp| lp.points.clone()).collect(),
        })
        .collect();
    if planes.is_empty() {
        return Err(Error::new(ErrorKind::InputFile, "no closed contours"));
    }
    // Layers given directly, not read from a file, are checked here.
    if let Some(problem) = pgvol_slice::layer_coordinate_problem(layers) {
        return Err(Error::parameter(problem));
    }
    planes.sort_by(|x, y| x.height.total_cmp(&y.height));
    // The field across the planes takes one value per plane and height.
    let rising = |w: &[pgvol_points::contours::ContourPlane]| {
        w[1].height.partial_cmp(&w[0].height) == Some(Greater)
    };
    if let Some(w) = planes.windows(2).find(|w| !rising(w)) {
        return Err(Error::new(
            ErrorKind::InputFile,
            format!(
                "two layers lie at height {}: a stack needs one layer per height (put both \
                 layers' loops in one layer)",
                w[0].height
            ),
        ));
    }
    // The box of the loops, grown by the caps half the outermost layer distances out.
    let outline = pgvol_points::contours::contour_points(&planes, a, f32::INFINITY);
    let (mut lo, mut hi) = pgvol_points::index::bounds(&outline.points);
    if let [first, second, .., before_last, last] = planes.as_slice() {
        lo[a] -= 0.5 * (second.height - first.height);
        hi[a] += 0.5 * (last.height - before_last.height);
    }
    crate::frame::require_near_box(lo, hi, "reconstruction from contours")?;
    let grid = options.grid.grid_for_box(lo, hi)?;
    if options.method != Method::Spline {
        // Samples at half the grid spacing: every cell the surface crosses holds several.
        let cloud = pgvol_points::contours::contour_points(&planes, a, 0.5 * grid.spacing);
        return Ok(fit_on_grid(&cloud, grid, options, (lo, hi), None, progress)?.0);
    }
    let heights: Vec<f32> = planes.iter().map(|p| p.height).collect();
    let grid = planes_on_nodes(grid, &heights, a, (lo, hi))?;
    let [nx, ny, nz] = grid.dims;
    crate::memory::check_memory(
        &format!(
            "fitting {} contour planes on a {nx} x {ny} x {nz} grid",
            planes.len()
        ),
        stack_bytes(planes.len(), &grid),
        "lower the resolution",
    )?;
    let band = options.band * grid.spacing;
    let (volume, report) = progress::stage(progress, "fit", |_| {
        pgvol_points::reconstruct_stack(&planes, a, grid, band)
    })?
    .map_err(|e| {
        let kind = match e {
            pgvol_points::PointsError::Field(_) => ErrorKind::Internal,
            _ => ErrorKind::InputFile,
        };
        Error::new(kind, e.to_string()).caused_by(e)
    })?;
    let mut header = pgvol_format::header_for(&volume, "contours", None);
    header.source_bounds = Some([lo.to_array(), hi.to_array()]);
    header.metadata.insert(BAND_KEY.into(), format!("{band}"));
    header
        .metadata
        .insert("contour planes".into(), planes.len().to_string());
    Ok(Reconstructed {
        file: PgvFile { header, volume },
        report,
    })
}

/// Evenly spaced planes whose distance is within this fraction of a whole number of grid
/// spacings get a grid with that spacing, aligned so they fall on nodes.
pub const SNAP_SPACING: f32 = 0.1;

/// `grid` with its spacing moved by at most [`SNAP_SPACING`] and its origin along `axis`
/// shifted so that evenly spaced planes at `heights` lie on nodes (the node count follows, the
/// cube stays centred on `bounds` otherwise). A cubic B-spline along the axis can then take
/// every plane's value exactly even when the planes are less than two spacings apart, where
/// a least-squares fit between nodes would smooth single-plane features (the tips of horns)
/// away. Unevenly spaced planes keep `grid`.
fn planes_on_nodes(
    grid: pgvol_core::Grid,
    heights: &[f32],
    axis: usize,
    bounds: (Vec3, Vec3),
) -> Result<pgvol_core::Grid> {
    let gaps: Vec<f32> = heights.windows(2).map(|w| w[1] - w[0]).collect();
    let Some(&first) = gaps.first() else {
        return Ok(grid);
    };
    let mean = gaps.iter().sum::<f32>() / gaps.len() as f32;
    let uneven = gaps.iter().any(|g| (g - mean).abs() > 1e-3 * mean);
    if mean.is_nan() || mean <= 0.0 || first <= 0.0 || uneven {
        return Ok(grid);
    }
    let steps = (mean / grid.spacing).round().max(1.0);
    let spacing = mean / steps;
    if (spacing - grid.spacing).abs() > SNAP_SPACING * grid.spacing {
        return Ok(grid);
    }
    let mut snapped = pgvol_core::Grid::cube_voxel(bounds.0, bounds.1, spacing)?;
    // Down along the axis by less than a spacing onto the first plane, one node more on top.
    let offset = (heights[0] - snapped.origin[axis]) / spacing;
    let fraction = offset - offset.floor();
    if fraction > 0.0 {
        snapped.origin[axis] -= (1.0 - fraction) * spacing;
        snapped.dims[axis] += 1;
    }
    Ok(snapped)
}

/// Estimated peak bytes of the distance interpolation of `planes` contour planes on `grid`
/// (stacked along z; the grid is a cube): one 2D distance per node column and plane, the fitted
/// samples of every column along the axis, and every brick of samples and coefficients in the
/// worst case.
pub fn stack_bytes(planes: usize, grid: &pgvol_core::Grid) -> u64 {
    let [nx, ny, nz] = grid.dims.map(|d| d as u64);
    let columns = nx * ny;
    let per_column = (planes as u64 + 6) * 4 + nz * 4 + 64;
    let bricks = nx.div_ceil(8) * ny.div_ceil(8) * nz.div_ceil(8);
    columns * per_column + bricks * crate::memory::BYTES_PER_BAND_BRICK
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clouds_of_too_few_distinct_points_say_so() {
        let fit = |cloud: Vec<Vec3>| {
            let cloud = PointCloud {
                points: cloud,
                normals: None,
            };
            let e = points(&cloud, &PointsOptions::default(), &progress::Silent).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::InputFile);
            e.to_string()
        };
        let one = fit(vec![Vec3::ONE]);
        assert!(one.contains("a single point"), "{one}");
        let same = fit(vec![Vec3::splat(0.5); 1000]);
        assert!(same.contains("all 1000 points coincide"), "{same}");
        let few = fit((0..1000).map(|i| Vec3::X * (i % 4) as f32).collect());
        assert!(few.contains("only 4 distinct ones"), "{few}");
        for msg in [one, same, few] {
            assert!(msg.contains("at least 10 distinct points"), "{msg}");
            assert!(!msg.contains("bounding box"), "{msg}");
        }
    }

    #[test]
    fn text_clouds_with_and_without_normals() {
        let name = Path::new("c.xyz");
        let cloud = read_cloud_text("x y z\n0 0 0\n1,2,3\n".as_bytes(), name).unwrap();
        assert_eq!(cloud.points, vec![Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)]);
        assert!(cloud.normals.is_none());
        let cloud =
            read_cloud_text("\u{feff}0 0 0 0 0 1\n# c\n1 1 1 1 0 0\n".as_bytes(), name).unwrap();
        assert_eq!(cloud.normals.unwrap()[1], Vec3::X);
        for bad in [
            "0 0 0\n1 1 1 0 0 1\n",
            "0 0\n",
            "0 0 nan\n",
            "",
            "0 0 0 0 inf 0\n",
        ] {
            let e = read_cloud_text(bad.as_bytes(), name).unwrap_err();
            assert!(e.to_string().starts_with("c.xyz: "), "{e}");
        }
    }

    #[test]
    fn ply_points_with_normals_and_faces_ignored() {
        let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                   property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                   end_header\n0 0 0 0 0 1\n1 2 3 0 1 0\n";
        let (points, normals) =
            pgvol_mesh::read_ply_points(ply.as_bytes(), Path::new("p.ply")).unwrap();
        assert_eq!(points[1], Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(normals.unwrap()[1], Vec3::Y);
        let bare = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                    property float z\nend_header\n0 0 1e9\n";
        let e = pgvol_mesh::read_ply_points(bare.as_bytes(), Path::new("p.ply")).unwrap_err();
        assert!(e.to_string().starts_with("p.ply: "), "{e}");
    }

    #[test]
    fn evenly_spaced_planes_are_put_on_nodes() {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let grid = pgvol_core::Grid::cube_res(lo, hi, 64).unwrap();
        // 0.94 grid spacings apart: snapped, every plane on a node, the box still covered.
        let gap = 0.94 * grid.spacing;
        let heights: Vec<f32> = (0..30).map(|k| -0.8 + 0.013 + gap * k as f32).collect();
        let snapped = planes_on_nodes(grid, &heights, 2, (lo, hi)).unwrap();
        assert!((snapped.spacing - gap).abs() < 1e-6);
        for h in &heights {
            let k = (h - snapped.origin.z) / snapped.spacing;
            assert!((k - k.round()).abs() < 1e-3, "{h}: node {k}");
        }
        assert!(snapped.origin.cmple(grid.origin + Vec3::splat(1e-5)).all());
        assert!(snapped.max_corner().cmpge(hi).all());
        // 1.5 spacings apart (a third from a whole number) or uneven: left alone.
        let wide: Vec<f32> = (0..10).map(|k| 1.5 * grid.spacing * k as f32).collect();
        assert_eq!(planes_on_nodes(grid, &wide, 2, (lo, hi)).unwrap(), grid);
        let mut uneven = heights.clone();
        uneven[3] += 0.3 * gap;
        assert_eq!(planes_on_nodes(grid, &uneven, 2, (lo, hi)).unwrap(), grid);
    }

    #[test]
    fn layer_files_and_layers_beyond_the_mesh_limit_are_refused() {
        let far = Layer {
            height: 0.5,
            loops: vec![pgvol_slice::Loop {
                points: vec![[0.0, 0.0], [1e20, 0.0], [0.0, 1.0]],
                hole: false,
            }],
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("far.json");
        pgvol_slice::write_slice_json(&path, std::slice::from_ref(&far)).unwrap();
        let e = read_layers(&path).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InputFile, "{e}");
        assert_eq!(e.path(), Some(path.as_path()));
        assert!(e.message().contains("coordinate 1e20 in layer 0"), "{e}");
        let options = PointsOptions::default();
        let e = contours(&[far], Axis::Z, &options, &progress::Silent).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::BadParameter, "{e}");
        assert!(e.message().contains("out of range"), "{e}");
    }

    #[test]
    fn unknown_extension_is_refused_by_name() {
        let e = read_point_cloud(Path::new("cloud.bin")).unwrap_err();
        assert!(e.to_string().contains(".ply"), "{e}");
    }
}
