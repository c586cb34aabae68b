//! The field's value and analytic gradient at given points, and the point files that carry them.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use glam::DVec3;
use pgvol_core::Grid;
use pgvol_field::CoefficientVolume;

use serde::Serialize;

use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::field_value::Field;

/// Parses points, one `x,y,z` per line (commas, semicolons, spaces or tabs between). Blank lines
/// and lines starting with `#` are skipped, and so is a first line in which no field is a number
/// (a header such as `x,y,z`); a UTF-8 byte-order mark is ignored. Any other line that is not
/// three finite numbers below [`MAX_COORDINATE`](pgvol_mesh::MAX_COORDINATE) in magnitude is an
/// error naming the line; `name` labels errors.
///
/// The points are world coordinates, parsed in f64 so that points far from the origin keep
/// their precision until [`eval`] takes them into the field's frame.
pub fn read_points(r: impl Read, name: impl AsRef<Path>) -> Result<Vec<DVec3>> {
    let name = name.as_ref();
    let fail = |message: String| Error::new(ErrorKind::InputFile, message).at(name);
    let mut points = Vec::new();
    let mut seen_data = false;
    for (n, line) in BufReader::new(r).lines().enumerate() {
        let line = line.map_err(|e| fail(format!("line {} is not text: {e}", n + 1)))?;
        let line = line.trim_start_matches('\u{feff}').trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split([',', ';', ' ', '\t'])
            .filter(|f| !f.is_empty())
            .collect();
        let numbers: Vec<Option<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        let first = !seen_data;
        seen_data = true;
        if first && numbers.iter().all(Option::is_none) {
            continue;
        }
        let point = match numbers.as_slice() {
            [Some(x), Some(y), Some(z)] => DVec3::new(*x, *y, *z),
            _ => {
                return Err(fail(format!(
                    "line {}: expected three numbers x,y,z, got '{line}'",
                    n + 1
                )))
            }
        };
        if !point.is_finite() || point.abs().max_element() >= f64::from(pgvol_mesh::MAX_COORDINATE)
        {
            return Err(fail(format!(
                "line {}: coordinates must be finite and below {:e} in magnitude, got '{line}'",
                n + 1,
                pgvol_mesh::MAX_COORDINATE
            )));
        }
        points.push(point);
    }
    if points.is_empty() {
        return Err(fail("no points".into()));
    }
    Ok(points)
}

/// Reads the points of a file; see [`read_points`].
pub fn read_points_file(path: impl AsRef<Path>) -> Result<Vec<DVec3>> {
    let path = path.as_ref();
    let bytes = pgvol_core::read_input(path).reading()?;
    read_points(bytes.as_slice(), path)
}

/// The field at one point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// The field's value: the signed distance where `exact`.
    pub value: f32,
    /// Its analytic gradient.
    pub gradient: [f32; 3],
    /// Whether the value is a distance: the point lies inside the grid box and within the band
    /// where the field is exact. Elsewhere the value has the right sign but is a clamp (beyond
    /// the band) or an extrapolation (outside the box), and its magnitude is not a distance.
    pub exact: bool,
}

impl Field {
    /// Refuses query points that are not finite or not below
    /// [`MAX_COORDINATE`](pgvol_mesh::MAX_COORDINATE) in magnitude, naming the first (counted
    /// from 0): where [`Field::eval`] would clamp them into the grid and give a value that
    /// belongs to another point.
    pub fn check_query_points(points: &[DVec3]) -> Result<()> {
        let limit = f64::from(pgvol_mesh::MAX_COORDINATE);
        match points
            .iter()
            .position(|p| !p.is_finite() || p.abs().max_element() >= limit)
        {
            None => Ok(()),
            Some(i) => Err(Error::parameter(format!(
                "point {i} is ({}, {}, {}): coordinates must be finite and below {limit:e} in \
                 magnitude",
                points[i].x, points[i].y, points[i].z
            ))),
        }
    }

    /// Value and gradient of the field at each point (world coordinates, taken into the
    /// field's frame in f64), in parallel, each flagged by whether it is an exact distance.
    pub fn eval(&self, points: &[DVec3]) -> Vec<Evaluation> {
        let volume: &CoefficientVolume = &self.file.volume;
        let band = self.exact_band();
        let (lo, hi) = (volume.grid.origin, volume.grid.max_corner());
        let points = self.to_local(points);
        volume
            .eval_many(&points)
            .into_iter()
            .zip(&points)
            .map(|((value, gradient), p)| Evaluation {
                value,
                gradient: gradient.to_array(),
                exact: value.abs() < band && p.cmpge(lo).all() && p.cmple(hi).all(),
            })
            .collect()
    }

    /// The field sampled at every node of `grid` (in the field's local frame), x fastest
    /// (flat index `i + nx · (j + ny · k)`). Refuses a grid that is not finite, positive and
    /// within the node limit, or that would not fit in memory.
    pub fn sample_grid(&self, grid: &Grid) -> Result<Vec<f32>> {
        sample(&self.file.volume, grid)
    }
}

/// See [`Field::sample_grid`].
pub(crate) fn sample(volume: &CoefficientVolume, grid: &Grid) -> Result<Vec<f32>> {
    if !(grid.spacing.is_finite() && grid.spacing > 0.0) {
        return Err(Error::parameter(format!(
            "the grid spacing must be a positive number, got {}",
            grid.spacing
        )));
    }
    // The node count first: the far corner of a grid without nodes is not defined.
    if grid.dims.contains(&0) {
        return Err(Error::parameter(format!(
            "the grid needs at least one node per axis, got {:?}",
            grid.dims
        )));
    }
    if !grid.origin.is_finite() || !grid.max_corner().is_finite() {
        return Err(Error::parameter("the grid's corners must be finite"));
    }
    let nodes = grid.dims.iter().map(|&n| n as u128).product::<u128>();
    if nodes > pgvol_core::MAX_GRID_NODES {
        return Err(Error::new(
            ErrorKind::ResourceLimit,
            format!(
                "a grid of {nodes} nodes exceeds the limit of {}",
                pgvol_core::MAX_GRID_NODES
            ),
        ));
    }
    crate::memory::check_grid("sampling", grid, crate::memory::BYTES_PER_SDF_NODE)?;
    Ok(volume.sample(grid))
}
