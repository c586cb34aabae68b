//! Slicing and contouring a `.pgv` file in parts without decoding it: the plan comes from the
//! file's header, and each part gets the file's own compressed bricks of the slabs it reaches,
//! as a `.pgv` file of their own, so the caller holds one part's bytes at a time rather than
//! the volume, and each part decodes only its slabs.

use std::ops::Range;
use std::path::Path;

use pgvol_core::Mesh;
use pgvol_format::{SlabReader, SlabSource};
use pgvol_slice::Layer;

use super::decode_parts::{check_part_options, contour_part, decode_part_reach, part_brick_layers};
use super::split::split;
use crate::decode::DecodeOptions;
use crate::error::{Error, FileResult, Result};
use crate::progress::Silent;
use crate::slice::{header_bounds, options_for, SliceOptions as SliceSettings};

/// A slicing of the file at `path` in at most `parts` parts, each part's layer numbers; `None`
/// when the file is not read slab by slab (a version 1 or dense file, or a basis that is not
/// separable), whose parts come from the loaded field ([`super::plan_slice`]).
pub fn plan_slice_file(
    path: &Path,
    settings: &SliceSettings,
    parts: usize,
) -> Result<Option<Vec<Range<usize>>>> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Ok(None);
        };
        let header = reader.header();
        crate::frame::require_near(header.grid.offset, "slicing in parts")?;
        let options = options_for(header.grid.spacing, header.grid.offset, settings)?;
        let heights = pgvol_slice::layer_heights(header_bounds(header), &options)?;
        Ok(Some(split(heights.len(), parts)?))
    })
}

/// What the layers `layers` of slicing the file at `path` read: a version 2 `.pgv` file holding
/// the file's own compressed bricks of the slabs those layers reach
/// ([`SlabReader::part_file`]), for [`slice_file_part`]. The file must be one
/// [`plan_slice_file`] plans.
pub fn slice_file_part_bricks(
    path: &Path,
    settings: &SliceSettings,
    layers: Range<usize>,
) -> Result<Vec<u8>> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Err(not_by_slabs());
        };
        let header = reader.header();
        let grid = header.grid;
        let options = options_for(grid.spacing, grid.offset, settings)?;
        let (axis, bricks) = part_brick_layers(&grid, header_bounds(header), &options, layers)?;
        let per = reader.grid_bricks_per_slab().max(1);
        reader
            .part_file(axis, bricks.start / per..bricks.end.div_ceil(per))
            .reading()
    })
}

/// The layers `layers` of slicing, from the bytes [`slice_file_part_bricks`] gave for them:
/// each the layer slicing the whole file gives, before [`sharpen_file_layers`].
pub fn slice_file_part(
    part: &[u8],
    settings: &SliceSettings,
    layers: Range<usize>,
) -> Result<Vec<Layer>> {
    let name = Path::new("<part of a .pgv file>");
    let reader = SlabReader::open(part, name).reading()?;
    let Some(reader) = reader.filter(|r| r.header().basis.is_separable()) else {
        return Err(Error::parameter(
            "the bytes are not a part of a sparse .pgv file with a separable basis",
        ));
    };
    crate::slice::slice_reader(&reader, settings, layers, &Silent)
}

/// Puts back into `layers`, the parts' layers of slicing the file at `path` concatenated in
/// plan order, the corners its sharp section marks, as [`super::sharpen_layers`] does for the
/// loaded field.
pub fn sharpen_file_layers(
    path: &Path,
    settings: &SliceSettings,
    layers: &mut [Layer],
) -> Result<()> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Err(not_by_slabs());
        };
        crate::sharp::sharpen_sliced(layers, reader.header(), settings.axis)
    })
}

/// A contouring of the file at `path` in at most `parts` slabs of cells along z, and the grid
/// spacing [`super::weld_parts`] takes; `None` when the file is not read slab by slab, whose
/// parts come from the loaded field ([`super::plan_decode`]).
pub fn plan_decode_file(path: &Path, parts: usize) -> Result<Option<(Vec<Range<usize>>, f32)>> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Ok(None);
        };
        let grid = reader.header().grid;
        crate::frame::require_near(grid.offset, "a decode in parts")?;
        // The cells along z, as the loaded field's plan counts them.
        Ok(Some((split(grid.dims[2] - 1, parts)?, grid.spacing)))
    })
}

/// What contouring the z cells `cells` of the file at `path` reads: a `.pgv` file of the file's
/// own bricks in the slabs along z the part reaches, for [`decode_file_part`].
pub fn decode_file_part_bricks(path: &Path, cells: Range<usize>) -> Result<Vec<u8>> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Err(not_by_slabs());
        };
        let bricks = decode_part_reach(cells);
        let per = reader.grid_bricks_per_slab().max(1);
        reader
            .part_file(2, bricks.start / per..bricks.end.div_ceil(per))
            .reading()
    })
}

/// The triangles of the z cells `cells`, from the bytes [`decode_file_part_bricks`] gave for
/// them: those [`super::decode_part`] gives from the loaded field's bricks.
pub fn decode_file_part(part: &[u8], cells: Range<usize>, options: &DecodeOptions) -> Result<Mesh> {
    check_part_options(options)?;
    let file = crate::io::read_pgv_bytes(part, Path::new("<part of a .pgv file>"))?;
    contour_part(&file.volume, cells, options)
}

fn not_by_slabs() -> Error {
    Error::parameter(
        "the file is not read slab by slab (a version 1 or dense file, or a basis that is not \
         separable); work on the loaded field in parts instead",
    )
}

/// `work` on the slab reader of the file at `path` (`None` for a file not read slab by slab),
/// its errors naming the file.
fn with_reader<T>(path: &Path, work: impl FnOnce(Option<&SlabReader>) -> Result<T>) -> Result<T> {
    let at = |e: Error| match e.path() {
        Some(_) => e,
        None => e.at(path),
    };
    let source = SlabSource::open(path).reading()?;
    let reader = SlabReader::from_source(&source, path).reading()?;
    let separable = reader.as_ref().filter(|r| r.header().basis.is_separable());
    work(separable).map_err(at)
}
