//! The grids a coefficient volume is contoured on: its box sampled at another resolution, and
//! a grid padded with one node layer on every side, whose outside values close every surface.

use glam::Vec3;
use pgvol_field::{CoefficientVolume, Grid};

/// The grid of `volume` resampled with `res` nodes along its longest side, same origin and box.
/// `None` when the grid would exceed [`pgvol_field::MAX_GRID_NODES`].
pub fn resampled_grid(volume: &CoefficientVolume, res: usize) -> Option<Grid> {
    resampled_grid_of(&volume.grid, res)
}

/// [`resampled_grid`] of a volume on `grid`.
pub fn resampled_grid_of(grid: &Grid, res: usize) -> Option<Grid> {
    let side = grid.max_corner() - grid.origin;
    let spacing = side.max_element() / (res.max(2) - 1) as f32;
    let dims = side
        .to_array()
        .map(|s| ((s / spacing).round() as usize + 1).max(2));
    let total = dims.iter().map(|&d| d as u128).product::<u128>();
    (total <= pgvol_field::MAX_GRID_NODES).then_some(Grid {
        origin: grid.origin,
        spacing,
        dims,
        offset: grid.offset,
    })
}

/// `grid` with one more node layer on every side: the grid of the padded samples.
pub(crate) fn padded(grid: &Grid) -> Grid {
    Grid {
        origin: grid.origin - Vec3::splat(grid.spacing),
        spacing: grid.spacing,
        dims: grid.dims.map(|n| n + 2),
        offset: grid.offset,
    }
}
