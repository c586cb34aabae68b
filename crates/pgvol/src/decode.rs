//! Coefficient volume → mesh.

use pgvol_contour::Method;
use pgvol_core::{Grid, Mesh};
use pgvol_field::CoefficientVolume;

use crate::error::{Error, ErrorKind, Result};
use crate::progress::{self, Progress};

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
    /// Pieces enclosing less than this volume (mesh units cubed) are removed; `None` (the
    /// default) removes those under [`SPECK_VOXELS`] cells of the contouring grid, `Some(0.0)`
    /// keeps every piece.
    pub min_component: Option<f32>,
}

/// Pieces of a contour smaller than this many grid cells are specks (noise, features thinner
/// than the grid), not parts: removed by default, with a warning.
pub const SPECK_VOXELS: f32 = 2.0;

/// Removes the pieces of `mesh` under `min_component`, or under [`SPECK_VOXELS`] cells of
/// spacing `h` by default, and says how many went.
pub(crate) fn remove_specks(
    mesh: &mut Mesh,
    min_component: Option<f32>,
    h: f32,
    progress: &dyn Progress,
) -> (usize, f32) {
    let limit = min_component.unwrap_or(SPECK_VOXELS * h * h * h);
    if limit.is_nan() || limit <= 0.0 {
        return (0, limit);
    }
    let removed = mesh.remove_small_components(limit as f64);
    if removed > 0 {
        progress.warn(&format!(
            "removed {removed} piece{} enclosing less than {limit:.3e} (the smallest piece \
             volume kept; 0 keeps every piece)",
            if removed == 1 { "" } else { "s" }
        ));
    }
    (removed, limit)
}

impl Default for DecodeOptions {
    fn default() -> Self {
        Self {
            iso: 0.0,
            method: Method::MarchingCubes,
            res: None,
            min_component: None,
        }
    }
}

/// `volume`'s own grid, or one of `res` nodes along its longest side over the same box.
pub(crate) fn target_grid(volume: &CoefficientVolume, res: Option<usize>) -> Result<Grid> {
    target_grid_of(&volume.grid, res)
}

/// [`target_grid`] of a volume on `grid`.
pub(crate) fn target_grid_of(grid: &Grid, res: Option<usize>) -> Result<Grid> {
    let min = crate::grid::MIN_RES as usize;
    match res {
        None => Ok(*grid),
        // A grid this coarse holds no surface; it would only be reported as an empty level set.
        Some(n) if n < min => Err(Error::parameter(format!(
            "the resampling resolution must be at least {min} nodes along the longest side, \
             got {n}"
        ))),
        Some(n) => pgvol_contour::resampled_grid_of(grid, n).ok_or_else(|| {
            Error::new(
                ErrorKind::ResourceLimit,
                format!("a resampling at {n} nodes gives a grid larger than the limit"),
            )
        }),
    }
}

/// Contours the `options.iso` level set of `volume`. An empty level set is an error: it is
/// never a useful mesh.
pub(crate) fn decode(
    volume: &CoefficientVolume,
    options: &DecodeOptions,
    progress: &dyn Progress,
) -> Result<Mesh> {
    decode_placing(volume, options, None, progress)
}

/// [`decode`], with the vertices of the cells `sharp` stores put where it stores them (a dual
/// contour on the volume's own grid, see [`crate::sharp`]).
pub(crate) fn decode_placing(
    volume: &CoefficientVolume,
    options: &DecodeOptions,
    sharp: Option<&pgvol_format::sharp::SharpCells>,
    progress: &dyn Progress,
) -> Result<Mesh> {
    if !options.iso.is_finite() {
        return Err(Error::parameter("the level must be a finite number"));
    }
    let grid = target_grid(volume, options.res)?;
    crate::memory::check_contour(volume, &grid)?;
    let stored = |corner| crate::sharp::stored_vertex(&grid, sharp?, corner);
    let mesh = progress::stage(progress, "contour", |update| {
        let (iso, method) = (options.iso, options.method);
        let stored: Option<&pgvol_contour::StoredVertices> = match sharp {
            Some(_) => Some(&stored),
            None => None,
        };
        pgvol_contour::contour_volume_placing(volume, &grid, iso, method, update, stored)
    })?;
    finish_mesh(mesh, options, grid.spacing, progress)
}

/// A contour as decoding returns it: its specks removed (on a grid of `spacing`), and an empty
/// level set refused, since it is never a useful mesh.
pub(crate) fn finish_mesh(
    mut mesh: Mesh,
    options: &DecodeOptions,
    spacing: f32,
    progress: &dyn Progress,
) -> Result<Mesh> {
    let (removed, limit) = remove_specks(&mut mesh, options.min_component, spacing, progress);
    if mesh.triangles.is_empty() && removed > 0 {
        return Err(Error::new(
            ErrorKind::EmptyResult,
            format!(
                "every piece of the level set {} ({removed}) encloses less than {limit:.3e}, the \
                 smallest piece volume kept; a smaller limit (0 keeps every piece) or a finer \
                 grid would keep them",
                options.iso
            ),
        ));
    }
    if mesh.triangles.is_empty() {
        // A grid coarser than the field's may step over a thin shape.
        let coarse = match options.res {
            Some(res) => format!(
                " at {res} nodes per axis, which may step over a thin shape; a finer grid may \
                 find it"
            ),
            None => String::new(),
        };
        return Err(Error::new(
            ErrorKind::EmptyResult,
            format!(
                "the level set {} is empty in this field{coarse}",
                options.iso
            ),
        ));
    }
    Ok(mesh)
}
