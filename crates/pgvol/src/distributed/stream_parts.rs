//! Writing an encode's file while its parts arrive: each z slab of parts is applied to a window
//! of coefficient bricks, the file brick layers it completes are written (`StreamedPgv`), and
//! the bricks no later layer reads are dropped, so the process writing the file holds a window
//! of slabs, not the whole volume. The file is bit for bit that of
//! [`assemble_encode`](super::assemble_encode) written by [`write_pgv`](crate::write_pgv).

use std::io::Write;
use std::path::Path;

use pgvol_core::{Mesh, SparseGrid, BRICK_EDGE};
use pgvol_field::CoefficientVolume;
use pgvol_format::{EncodeReport, StreamError, StreamedPgv};

use super::encode_parts::{assembled_fit, check_parts_options, check_slab, EncodedPart};
use super::slab::Slab;
use super::tiling::Tiling;
use crate::encode::{encoded_header, sparse_options, EncodeOptions, StorageOptions};
use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::progress::Silent;
use crate::sharp::store::SharpPlan;

/// How writing an encode's parts ended.
#[derive(Clone, Debug, PartialEq)]
pub enum PartsWritten {
    /// The file is written; what it stores.
    Written(EncodeReport),
    /// The automatic precision cannot be chosen a slab at a time (a coefficient lies beyond the
    /// `fixed` precision's tolerance): nothing was written; assemble the parts in memory with
    /// [`assemble_encode`](super::assemble_encode) and write that.
    NeedsWholeVolume,
}

/// Writes the file of the encode of `mesh` by `options` to `path` atomically from `parts`, the
/// plan's parts in plan order, each taken as it comes and dropped once applied. See
/// [`PartsWritten`] for the case that leaves nothing written.
pub fn write_encode_parts(
    path: impl AsRef<Path>,
    mesh: &Mesh,
    options: &EncodeOptions,
    parts: &mut dyn Iterator<Item = Result<EncodedPart>>,
) -> Result<PartsWritten> {
    let path = path.as_ref();
    let mut outcome = None;
    let written = pgvol_core::write_atomic(path, |w| {
        let result = write_encode_parts_to(w, mesh, options, parts);
        let keep = matches!(result, Ok(PartsWritten::Written(_)));
        outcome = Some(result);
        if keep {
            Ok(())
        } else {
            // Any other outcome leaves the file as it was.
            Err(std::io::Error::other("stopped"))
        }
    });
    match outcome {
        Some(Ok(PartsWritten::Written(report))) => {
            written.writing().map(|_| PartsWritten::Written(report))
        }
        Some(Ok(other)) => Ok(other),
        Some(Err(e)) => Err(e.at(path)),
        None => written.writing().map(|_| PartsWritten::NeedsWholeVolume),
    }
}

/// [`write_encode_parts`] to any writer; after `NeedsWholeVolume` what was written is not a
/// file.
pub fn write_encode_parts_to(
    w: &mut dyn Write,
    mesh: &Mesh,
    options: &EncodeOptions,
    parts: &mut dyn Iterator<Item = Result<EncodedPart>>,
) -> Result<PartsWritten> {
    check_parts_options(options)?;
    let grid = options.grid.grid_for(mesh)?;
    let counts = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
    let grid_bricks: usize = counts.iter().product();
    let mut tiling = Tiling::new(counts);
    // Sharp-feature vertices are chosen against the coefficient bricks near creases, kept
    // aside as they pass through the window.
    let sharp = SharpPlan::new(mesh, options.sign, None, &grid, &options.sharp, &Silent)?;
    let mut near_creases: Option<SparseGrid> = None;
    let mut window: Option<CoefficientVolume> = None;
    let mut writer: Option<StreamedPgv> = None;
    // The output, until the first part gives the header that starts the file.
    let mut out = Some(w);
    let mut stored = 0usize;
    for part in parts {
        let part = part?;
        let slab = Slab::from_bytes(&part.bricks)?;
        drop(part);
        check_slab(&slab, &grid, options)?;
        let slab_done = tiling.accept(&slab.bricks)?;
        let complete = (slab.bricks[2].end * BRICK_EDGE).min(grid.dims[2]);
        stored += slab.stored.len();
        let volume = window.get_or_insert_with(|| CoefficientVolume {
            grid,
            basis: options.basis,
            coeffs: SparseGrid::new(grid.dims, slab.background),
        });
        if sharp.has_boxes() {
            let kept =
                near_creases.get_or_insert_with(|| SparseGrid::new(grid.dims, slab.background));
            slab.apply_some(kept, |b| sharp.needs_brick(b));
        }
        slab.apply(&mut volume.coeffs);
        let w = match writer.as_mut() {
            Some(w) => w,
            None => {
                let fit = assembled_fit(&grid, options, volume.coeffs.background())?;
                let header = encoded_header(mesh, volume, &fit, Some(options.band));
                let storage = sparse_options(&header, &StorageOptions::default());
                let out = out.take().expect("the file starts once");
                writer.insert(StreamedPgv::start(out, header, &storage).map_err(stream_error)?)
            }
        };
        if !slab_done {
            continue;
        }
        match w.write_ready(volume, complete) {
            Err(StreamError::WholeVolume) => return Ok(PartsWritten::NeedsWholeVolume),
            other => other.map_err(stream_error)?,
        }
        let keep = w.first_node_needed();
        volume.coeffs.retain(|b, _| (b[2] + 1) * BRICK_EDGE > keep);
    }
    tiling.finish()?;
    let (Some(mut w), Some(volume)) = (writer, window) else {
        return Err(Error::parameter("no parts to write"));
    };
    if let Some(coeffs) = near_creases {
        let kept = CoefficientVolume {
            grid,
            basis: options.basis,
            coeffs,
        };
        let (section, _) = sharp.section(&kept, &Silent)?;
        w.set_sharp(section);
    }
    match w.finish(&volume, stored == grid_bricks) {
        Ok(report) => Ok(PartsWritten::Written(report)),
        Err(StreamError::WholeVolume) => Ok(PartsWritten::NeedsWholeVolume),
        Err(e) => Err(stream_error(e)),
    }
}

fn stream_error(e: StreamError) -> Error {
    match e {
        StreamError::Write(io) => {
            Error::new(ErrorKind::OutputFile, format!("write failed: {io}")).caused_by(io)
        }
        other => Error::new(
            ErrorKind::Internal,
            format!("cannot write the parts' file: {other}"),
        ),
    }
}
