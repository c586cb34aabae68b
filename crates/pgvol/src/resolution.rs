//! What a grid resolves: walls are compared with its spacing before an operation, and the
//! operation's result is checked for breaking into far more pieces than its input, the sign of
//! walls the grid could not hold. Both refusals name a grid that would work.

use pgvol_core::Grid;
use pgvol_field::CoefficientVolume;

use crate::error::{Error, ErrorKind, Result};
use crate::pieces::count_pieces;

/// Grid spacings a wall needs to stay whole: a wall of one spacing comes out perforated
/// (a 100-unit rocker arm's 0.86-unit inner wall at spacing 0.86 has Euler characteristic
/// −100 instead of 0); lattice sheets need the same.
pub const MIN_WALL_SPACINGS: f32 = 2.0;

/// A result may hold this many times its input's pieces (plus [`EXTRA_PIECES`]) before it is
/// taken as broken: shrinking legitimately cuts a few narrow necks, a wall the grid cannot
/// hold falls into hundreds of pieces.
pub const PIECES_FACTOR: usize = 4;

/// Pieces a result may gain beyond [`PIECES_FACTOR`] times its input's.
pub const EXTRA_PIECES: usize = 4;

/// `x` to four significant digits, for a person reading the message.
pub(crate) fn figure(x: f32) -> String {
    let digits = 3 - x.abs().log10().floor() as i32;
    if !x.is_normal() || !(-6..=9).contains(&digits) {
        return format!("{x:.3e}");
    }
    format!("{:.*}", digits.max(0) as usize, x)
}

/// Nodes per axis of a grid over `grid`'s box with spacing at most `spacing`.
fn nodes_for(grid: &Grid, spacing: f32) -> usize {
    let cells = grid
        .dims
        .iter()
        .max()
        .copied()
        .unwrap_or(2)
        .saturating_sub(1);
    let side = grid.spacing * cells as f32;
    ((side / spacing).ceil() as usize).saturating_add(1)
}

/// How a grid of `nodes` per axis is named: its count, or past the largest grid, that.
fn grid_size(nodes: usize) -> String {
    let max = crate::grid::MAX_RES as usize;
    if nodes > max {
        format!("more than the {max} nodes per axis a grid may have")
    } else {
        format!("{nodes} nodes per axis over the same box")
    }
}

/// Refuses `what` (a sentence subject, "the wall") of `thickness` on `grid` when it is thinner
/// than [`MIN_WALL_SPACINGS`] spacings, with the grid that would resolve it.
pub fn check_wall(what: &str, thickness: f32, grid: &Grid) -> Result<()> {
    check_width(what, ("a wall", "thinner"), thickness, grid)
}

/// Refuses a hole (`what`, a sentence subject, "drain 1's diameter") of `diameter` on `grid`
/// narrower than [`MIN_WALL_SPACINGS`] spacings: the grid closes it, and a cavity it was to
/// open stays sealed.
pub fn check_hole(what: &str, diameter: f32, grid: &Grid) -> Result<()> {
    check_width(what, ("a hole", "narrower"), diameter, grid)
}

/// [`check_wall`] for a feature named by `noun` ("a wall") and measured by `adjective`
/// ("thinner").
fn check_width(
    what: &str,
    (noun, adjective): (&str, &str),
    thickness: f32,
    grid: &Grid,
) -> Result<()> {
    let least = MIN_WALL_SPACINGS * grid.spacing;
    if thickness >= least {
        return Ok(());
    }
    let needed = thickness / MIN_WALL_SPACINGS;
    let nodes = nodes_for(grid, needed);
    Err(Error::new(
        ErrorKind::Unresolved,
        format!(
            "{what} {} is {adjective} than the grid resolves: {noun} needs \
             {MIN_WALL_SPACINGS} grid spacings ({}, the spacing being {}) or the grid loses it; \
             a grid of spacing {} or finer ({}) would resolve it, as would {noun} of {} or more",
            figure(thickness),
            figure(least),
            figure(grid.spacing),
            figure(needed),
            grid_size(nodes),
            figure(least),
        ),
    )
    .needing_resolution(nodes))
}

/// Refuses the result of `operation` when it has far more pieces (6-connected sets of inside
/// nodes) than `input`: parts of it are thinner than the grid holds. Names a grid twice as fine.
pub fn check_pieces(
    operation: &str,
    input: &CoefficientVolume,
    result: &CoefficientVolume,
) -> Result<()> {
    let before = count_pieces(input);
    let after = count_pieces(result);
    if after <= PIECES_FACTOR * before.max(1) + EXTRA_PIECES {
        return Ok(());
    }
    let grid = &result.grid;
    let nodes = nodes_for(grid, 0.5 * grid.spacing);
    Err(Error::new(
        ErrorKind::Unresolved,
        format!(
            "{operation}: the result breaks into {after} pieces where the shape has {before}, \
             more than parts the operation separates would give: parts of it are likely thinner \
             than the grid resolves ({MIN_WALL_SPACINGS} spacings of {}); a grid twice as fine \
             ({}) would hold parts half as thin and keep only the pieces that are real",
            figure(grid.spacing),
            grid_size(nodes)
        ),
    )
    .needing_resolution(nodes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_under_two_spacings_is_refused_with_the_grid_that_holds_it() {
        let grid = Grid::cube_res(glam::Vec3::ZERO, glam::Vec3::splat(100.0), 128).unwrap();
        check_wall("the wall", 2.0 * grid.spacing, &grid).unwrap();
        let e = check_wall("the wall", 0.5, &grid).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Unresolved);
        // Spacing 0.25 over the same 110-unit cube.
        let nodes = e.resolution().unwrap();
        assert_eq!(nodes, 441, "{e}");
        let finer = Grid::cube_res(glam::Vec3::ZERO, glam::Vec3::splat(100.0), nodes).unwrap();
        check_wall("the wall", 0.5, &finer).unwrap();
        assert!(e.message().contains("0.25"), "{e}");
        // A wall no grid holds is named so, without overflowing.
        let e = check_wall("the wall", 1e-30, &grid).unwrap_err();
        let most = crate::grid::MAX_RES as usize;
        assert!(
            e.message().contains(&format!("more than the {most} nodes")),
            "{e}"
        );
        assert!(e.resolution().unwrap() > most);
    }
}
