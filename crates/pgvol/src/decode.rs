//! Coefficient volume → mesh.

use pgvol_contour::Method;
use pgvol_core::{Grid, Mesh};
use pgvol_field::CoefficientVolume;

use crate::error::{Error, ErrorKind, Result};
use crate::progress::{self, Progress};
use crate::shape::Shape;

/// How a field is contoured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecodeOptions {
    /// The level set: 0 (the default) is the surface, positive values offset it outward.
    pub iso: f32,
    /// Contouring method (default marching cubes).
    pub method: Method,
    /// Resample on this many nodes along the longest side over the same box; `None` (the
    /// default) contours on the stored grid.
    pub res: Option<usize>,
}

impl Default for DecodeOptions {
    fn default() -> Self {
        Self {
            iso: 0.0,
            method: Method::MarchingCubes,
            res: None,
        }
    }
}

/// `volume`'s own grid, or one of `res` nodes along its longest side over the same box.
pub(crate) fn target_grid(volume: &CoefficientVolume, res: Option<usize>) -> Result<Grid> {
    match res {
        None => Ok(volume.grid),
        Some(n) => pgvol_contour::resampled_grid(volume, n).ok_or_else(|| {
            Error::new(
                ErrorKind::ResourceLimit,
                format!("a resampling at {n} nodes gives a grid larger than the limit"),
            )
        }),
    }
}

/// Contours the `options.iso` level set of `shape`, refusing a level beyond the band where its
/// field is an exact distance (there the level set would follow the clamp, not the shape).
pub fn decode_shape(
    shape: &Shape,
    options: &DecodeOptions,
    progress: &dyn Progress,
) -> Result<Mesh> {
    if options.iso != 0.0 && options.iso.is_finite() {
        shape.check_reach(options.iso)?;
    }
    decode(&shape.volume, options, progress)
}

/// Contours the `options.iso` level set of `volume`. An empty level set is an error: it is
/// never a useful mesh.
pub fn decode(
    volume: &CoefficientVolume,
    options: &DecodeOptions,
    progress: &dyn Progress,
) -> Result<Mesh> {
    if !options.iso.is_finite() {
        return Err(Error::parameter("the level must be a finite number"));
    }
    let grid = target_grid(volume, options.res)?;
    crate::memory::check_contour(volume, &grid)?;
    let mesh = progress::stage(progress, "contour", |_| {
        pgvol_contour::contour_volume(volume, &grid, options.iso, options.method)
    })?;
    if mesh.triangles.is_empty() {
        return Err(Error::new(
            ErrorKind::BadParameter,
            format!("the level set {} is empty in this field", options.iso),
        ));
    }
    Ok(mesh)
}
