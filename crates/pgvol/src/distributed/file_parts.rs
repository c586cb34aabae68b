//! Slicing a `.pgv` file in parts without decoding it whole: the plan comes from the file's
//! header, and each part's bricks from the slabs of file bricks its layers reach, so the caller
//! holds one part's bricks at a time rather than the whole volume.

use std::ops::Range;
use std::path::Path;

use glam::Vec3;
use pgvol_core::SparseGrid;
use pgvol_field::CoefficientVolume;
use pgvol_format::{PgvHeader, SlabReader, SlabSource};
use pgvol_slice::Layer;

use super::decode_parts::{part_brick_layers, slab_of};
use super::split::split;
use crate::error::{Error, FileResult, Result};
use crate::slice::{header_bounds, options_for, SliceOptions as SliceSettings};

/// The layer numbers of each part of a slicing, and the box the shape lies in.
pub type FileSlicePlan = (Vec<Range<usize>>, (Vec3, Vec3));

/// A slicing of the file at `path` in at most `parts` parts: each part's layer numbers and the
/// shape's bounds (what [`super::slice_part`] takes), or `None` when the file is not read slab
/// by slab (a version 1 or dense file, or a basis that is not separable), whose parts come from
/// the loaded field ([`super::plan_slice`]).
pub fn plan_slice_file(
    path: &Path,
    settings: &SliceSettings,
    parts: usize,
) -> Result<Option<FileSlicePlan>> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Ok(None);
        };
        let header = reader.header();
        crate::frame::require_near(header.grid.offset, "slicing in parts")?;
        let options = options_for(header.grid.spacing, header.grid.offset, settings)?;
        let bounds = header_bounds(header);
        let heights = pgvol_slice::layer_heights(bounds, &options)?;
        Ok(Some((split(heights.len(), parts)?, bounds)))
    })
}

/// The bricks of the layers `layers` of slicing the file at `path`, the bytes
/// [`super::slice_part_bricks`] gives for the loaded field, from only the slabs of file bricks
/// they reach. The file must be one [`plan_slice_file`] plans.
pub fn slice_file_part_bricks(
    path: &Path,
    settings: &SliceSettings,
    layers: Range<usize>,
) -> Result<Vec<u8>> {
    with_reader(path, |reader| {
        let Some(reader) = reader else {
            return Err(Error::parameter(
                "the file is not read slab by slab (a version 1 or dense file, or a basis \
                 that is not separable); slice the loaded field in parts instead",
            ));
        };
        let header = reader.header();
        let grid = header.grid;
        let options = options_for(grid.spacing, grid.offset, settings)?;
        let (axis, bricks) = part_brick_layers(&grid, header_bounds(header), &options, layers)?;
        let mut coeffs = SparseGrid::new(grid.dims, reader.background());
        let per = reader.grid_bricks_per_slab().max(1);
        let mut stored = Vec::new();
        for slab in bricks.start / per..bricks.end.div_ceil(per) {
            let decoded = reader.slab(axis, slab).reading()?;
            for b in decoded.inside {
                coeffs.set_inside(b, true);
            }
            stored.extend(decoded.stored);
        }
        // In the loaded field's order (file bricks x fastest, then each one's grid bricks), so
        // the part's bytes are the same.
        let file_order = |m: &[usize; 3]| {
            let f = m.map(|c| c / per);
            ([f[2], f[1], f[0]], [m[2], m[1], m[0]])
        };
        stored.sort_unstable_by_key(|(m, _)| file_order(m));
        for (b, values) in stored {
            coeffs.insert(b, values);
        }
        let volume = CoefficientVolume {
            grid,
            basis: header.basis,
            coeffs,
        };
        Ok(slab_of(&volume, axis, bricks).to_bytes())
    })
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
        let header: &PgvHeader = match reader {
            Some(reader) => reader.header(),
            None => {
                return Err(Error::parameter(
                    "the file is not read slab by slab; sharpen the layers of the loaded field",
                ))
            }
        };
        crate::sharp::sharpen_sliced(layers, header, settings.axis)
    })
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
