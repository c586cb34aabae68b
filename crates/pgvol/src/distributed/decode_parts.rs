//! Contouring and slicing in parts: each part gets the coefficient bricks around its slab of
//! the grid, contours or slices its share, and the pieces are welded or concatenated.

use std::ops::Range;

use glam::Vec3;
use pgvol_contour::Method;
use pgvol_core::{Mesh, BRICK_EDGE};
use pgvol_field::CoefficientVolume;
use pgvol_slice::{Layer, SliceOptions};

use super::slab::Slab;
use super::split::split;
use crate::decode::{finish_mesh, DecodeOptions};
use crate::error::{Error, Result};
use crate::field_value::Field;
use crate::progress::Progress;
use crate::slice::SliceOptions as SliceSettings;
use pgvol_format::PgvFile;

/// Grid bricks of coefficients sent around a part's slab. A cell's contour reads coefficients
/// up to 2 nodes from its corners (the cubic B-spline's support), and the cut edge of the sent
/// bricks makes a false surface within 2 nodes of it: two bricks keep both 12 nodes or more
/// from every kept cell.
pub const PART_HALO_BRICKS: usize = 2;

/// Cells along z of `volume`'s grid as a part owns them: the padding cells the contour adds
/// below node 0 and above the last node belong to the first and last cell.
fn z_cells(volume: &CoefficientVolume) -> usize {
    volume.grid.dims[2] - 1
}

/// Cuts the contouring of `volume` into at most `parts` slabs of cells along z.
pub fn plan_decode(volume: &CoefficientVolume, parts: usize) -> Result<Vec<Range<usize>>> {
    crate::frame::require_near(volume.grid.offset, "a decode in parts")?;
    split(z_cells(volume), parts)
}

/// The coefficient bricks a part needs to contour its cells `cells` (z), as [`Slab`] bytes.
pub fn decode_part_bricks(volume: &CoefficientVolume, cells: Range<usize>) -> Vec<u8> {
    slab_of(volume, 2, decode_part_reach(cells)).to_bytes()
}

/// The brick layers along z a part contouring cells `cells` (z) needs.
pub(crate) fn decode_part_reach(cells: Range<usize>) -> Range<usize> {
    let lo = (cells.start / BRICK_EDGE).saturating_sub(PART_HALO_BRICKS);
    let hi = cells.end / BRICK_EDGE + 1 + PART_HALO_BRICKS;
    lo..hi
}

/// The bricks of `volume` whose index along `axis` lies in `range`, all of the other axes.
fn slab_of(volume: &CoefficientVolume, axis: usize, range: Range<usize>) -> Slab {
    let counts = volume.coeffs.brick_counts();
    let mut bricks = [0..counts[0], 0..counts[1], 0..counts[2]];
    bricks[axis] = range.start.min(counts[axis])..range.end.min(counts[axis]);
    Slab::cut(volume.grid, volume.basis, &volume.coeffs, bricks)
}

/// The triangles of the `options.iso` level set in the z cells `cells`, contoured from the
/// bricks of [`decode_part_bricks`] by marching cubes on the volume's own grid: each the same
/// triangle, with the same vertex positions, as the whole contour holds. A triangle belongs to
/// the cell holding its centroid.
pub fn decode_part(bricks: &[u8], cells: Range<usize>, options: &DecodeOptions) -> Result<Mesh> {
    // Before the bricks are read: a wrong option fails at once.
    check_part_options(options)?;
    let volume = Slab::from_bytes(bricks)?.volume()?;
    contour_part(&volume, cells, options)
}

/// The triangles of [`decode_part`] from `volume`, which holds at least the bricks it sends;
/// `options` checked by [`check_part_options`].
pub(crate) fn contour_part(
    volume: &CoefficientVolume,
    cells: Range<usize>,
    options: &DecodeOptions,
) -> Result<Mesh> {
    let grid = volume.grid;
    let mut mesh = pgvol_contour::contour_volume(
        volume,
        &grid,
        options.iso,
        Method::MarchingCubes,
        pgvol_core::progress::QUIET,
    );
    let last = z_cells(volume) - 1;
    let (z0, h) = (grid.origin.z, grid.spacing);
    let owner = |t: &[u32; 3]| {
        let c: Vec3 = t.iter().map(|&i| mesh.positions[i as usize]).sum::<Vec3>() / 3.0;
        let cell = ((c.z - z0) / h).floor();
        cell.clamp(0.0, last as f32) as usize
    };
    let kept: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .filter(|t| cells.contains(&owner(t)))
        .copied()
        .collect();
    mesh.triangles = kept;
    mesh.drop_unused_vertices();
    Ok(mesh)
}

/// Only what the parts reproduce exactly: marching cubes on the stored grid.
pub(crate) fn check_part_options(options: &DecodeOptions) -> Result<()> {
    if !options.iso.is_finite() {
        return Err(Error::parameter("the level must be a finite number"));
    }
    if options.method != Method::MarchingCubes || options.res.is_some() {
        return Err(Error::parameter(
            "contouring in parts supports marching cubes on the file's own grid only (no \
             method or resolution options)",
        ));
    }
    Ok(())
}

/// The mesh of the pieces of [`decode_part`]: vertices on the seams, computed alike by both
/// neighbours, merged by position, then the small pieces removed as
/// [`decode`](crate::decode()) does. `spacing` is the grid's.
pub fn weld_parts(
    pieces: Vec<Mesh>,
    spacing: f32,
    options: &DecodeOptions,
    progress: &dyn Progress,
) -> Result<Mesh> {
    let mut mesh = Mesh::default();
    // Normals are kept only when every piece has one per vertex.
    let with_normals = pieces.iter().all(|p| p.normals.len() == p.positions.len());
    for piece in pieces {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(piece.positions);
        if with_normals {
            mesh.normals.extend(piece.normals);
        }
        mesh.triangles
            .extend(piece.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    mesh.weld(0.0);
    finish_mesh(mesh, options, spacing, progress)
}

/// Layer numbers of the slicing of `shape` by `settings`, cut into at most `parts` ranges.
pub fn plan_slice(
    shape: &Field,
    settings: &SliceSettings,
    parts: usize,
) -> Result<Vec<Range<usize>>> {
    crate::frame::require_near(shape.file.volume.grid.offset, "slicing in parts")?;
    let options = crate::slice::slice_options(shape, settings)?;
    let heights = pgvol_slice::layer_heights(shape.bounds, &options)?;
    split(heights.len(), parts)
}

/// The coefficient bricks the layers `layers` of the slicing read: those within the basis
/// support of their planes, plus one brick.
pub fn slice_part_bricks(
    shape: &Field,
    settings: &SliceSettings,
    layers: Range<usize>,
) -> Result<Vec<u8>> {
    let options = crate::slice::slice_options(shape, settings)?;
    let volume = &shape.file.volume;
    let (axis, bricks) = part_brick_layers(&volume.grid, shape.bounds, &options, layers)?;
    Ok(slab_of(volume, axis, bricks).to_bytes())
}

/// The grid axis the layers `layers` of slicing a field on `grid` (its shape within `bounds`)
/// stack along, and the brick layers along it that [`slice_part_bricks`] sends them.
pub(crate) fn part_brick_layers(
    grid: &pgvol_field::Grid,
    bounds: (Vec3, Vec3),
    options: &SliceOptions,
    layers: Range<usize>,
) -> Result<(usize, Range<usize>)> {
    let heights = pgvol_slice::layer_heights(bounds, options)?;
    let axis = options.axis.indices()[0];
    let node = |h: f32| ((h - grid.origin[axis]) / grid.spacing).clamp(0.0, grid.dims[axis] as f32);
    let (Some(first), Some(last)) = (
        heights.get(layers.start),
        heights.get(layers.end.saturating_sub(1)),
    ) else {
        return Err(Error::parameter(format!(
            "layers {}..{} are not among the {} layers",
            layers.start,
            layers.end,
            heights.len()
        )));
    };
    let lo = (node(*first) as usize).saturating_sub(3) / BRICK_EDGE;
    let hi = (node(*last) as usize + 3) / BRICK_EDGE + 2;
    Ok((axis, lo.saturating_sub(1)..hi))
}

/// The layers `layers` of the slicing, from the bricks of [`slice_part_bricks`]: each the
/// same layer the whole slicing gives. `bounds` is the shape's.
pub fn slice_part(
    bricks: &[u8],
    bounds: (Vec3, Vec3),
    settings: &SliceSettings,
    layers: Range<usize>,
) -> Result<Vec<Layer>> {
    let volume = Slab::from_bytes(bricks)?.volume()?;
    let mut shape = Field::from_file(PgvFile {
        header: pgvol_format::header_for(&volume, "interp", None),
        volume,
    });
    shape.bounds = bounds;
    let options: SliceOptions = crate::slice::slice_options(&shape, settings)?;
    Ok(pgvol_slice::slice_volume_range(
        &shape.file.volume,
        bounds,
        &options,
        layers,
        pgvol_core::progress::QUIET,
    )?)
}

/// Puts back into `layers`, the parts' layers of slicing `field` by `settings` concatenated in
/// plan order, the corners the field's sharp section marks, as [`Field::slice`] does after
/// slicing; the layers of a field without the section are left as they are.
pub fn sharpen_layers(field: &Field, settings: &SliceSettings, layers: &mut [Layer]) -> Result<()> {
    crate::sharp::sharpen_sliced(layers, &field.file.header, settings.axis)
}
