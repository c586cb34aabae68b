//! A `.pgv` file → mesh, decoding the file a window of brick slabs at a time.

use std::borrow::Cow;
use std::ops::Range;
use std::path::Path;

use pgvol_contour::{CoefficientWindows, Method, Occupied, RunPart, RunsError};
use pgvol_core::{Grid, Mesh, SparseGrid, BRICK_EDGE};
use pgvol_field::CoefficientVolume;
use pgvol_format::{SlabReader, SlabSource};

use crate::band::header_band;
use crate::decode::{finish_mesh, target_grid_of, DecodeOptions};
use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::field_value::{check_reach_within, Field};
use crate::pgv_io::read_pgv_bytes;
use crate::progress::{self, Progress};

/// Contours the `options.iso` level set of the `.pgv` file at `path` (or of an OpenVDB `.vdb`
/// level set, fitted first as [`crate::io::encode_vdb`] does), as [`crate::decode_shape`]
/// of the file's shape does. Marching cubes of a sparse file reads the file one window of brick
/// slabs at a time and contours it run by run along z, so memory is the mesh and one window
/// (and the file's bytes for a version 1 file, which is read whole); other methods and
/// encodings read the whole volume first.
pub fn decode_file(
    path: impl AsRef<Path>,
    options: &DecodeOptions,
    progress: &dyn Progress,
) -> Result<Mesh> {
    let path = path.as_ref();
    let at = |e: Error| match e.path() {
        Some(_) => e,
        None => e.at(path),
    };
    if crate::vdb_in::is_vdb(path) {
        // An OpenVDB level set is fitted in memory first, then contoured as a whole.
        let options_vdb = crate::vdb_in::VdbEncodeOptions::default();
        let file = crate::vdb_in::encode_vdb(path, &options_vdb, progress)?.file;
        return Field::from_file(file)
            .to_mesh(options, progress)
            .map_err(at);
    }
    let source = SlabSource::open(path).reading()?;
    let reader = match options.method {
        Method::MarchingCubes => SlabReader::from_source(&source, path).reading()?,
        _ => None,
    };
    let streamed = reader.filter(|r| {
        let header = r.header();
        // Without a recorded band, a level's reach is measured from the whole volume.
        header.basis.is_separable() && (options.iso == 0.0 || header_band(header).is_some())
    });
    let Some(reader) = streamed else {
        let shape = Field::from_file(whole_file(&source, path)?);
        return shape.to_mesh(options, progress).map_err(at);
    };
    decode_slabs(&reader, options, progress).map_err(at)
}

/// [`decode_file`] of a sparse file with a separable basis, by windows of slabs.
fn decode_slabs(
    reader: &SlabReader,
    options: &DecodeOptions,
    progress: &dyn Progress,
) -> Result<Mesh> {
    let header = reader.header();
    let volume_grid = header.grid;
    if !options.iso.is_finite() {
        return Err(Error::parameter("the level must be a finite number"));
    }
    if options.iso != 0.0 {
        // A separable basis reaches 2 spacings (`pgvol_ops::support_reach`).
        let support = 2.0 * volume_grid.spacing;
        let band = header_band(header).unwrap_or(0.0) - support;
        check_reach_within(band, support, &volume_grid, options.iso)?;
    }
    let grid = target_grid_of(&volume_grid, options.res)?;
    let per_slab = reader.grid_bricks_per_slab().pow(3);
    let stored = header.sparse.as_ref().map_or(0, |s| s.stored) * per_slab;
    crate::memory::check_contour_of(stored, volume_grid.spacing, &grid)?;
    let mut windows = FileWindows {
        reader,
        volume: CoefficientVolume {
            grid: volume_grid,
            basis: header.basis,
            coeffs: SparseGrid::new(volume_grid.dims, reader.background()),
        },
        held: 0..0,
    };
    let mut mesh = Mesh::default();
    let report = |f: f64| progress.update(f);
    progress::check(progress)?;
    progress.stage("contour");
    let runs = pgvol_contour::contour_runs(
        &mut windows,
        &grid,
        options.iso,
        &report,
        &mut |part: RunPart| {
            append(&mut mesh, &part);
            progress::check(progress)
        },
    );
    match runs {
        Ok(()) => {}
        Err(RunsError::Source(e)) => return Err(e),
        Err(RunsError::TooManyVertices) => {
            return Err(Error::new(
                ErrorKind::ResourceLimit,
                "the mesh would have more vertices than 32-bit indices address; contour a \
                 coarser grid",
            ))
        }
    }
    progress.finish();
    drop(windows);
    mesh.offset = grid.offset;
    finish_mesh(mesh, options, grid.spacing, progress)
}

/// Adds a run's part to `mesh`. The arrays grow by exactly the part: large blocks are moved by
/// remapping pages rather than copied, and none ends up with twice the room it needs.
pub(crate) fn append(mesh: &mut Mesh, part: &RunPart) {
    mesh.positions.reserve_exact(part.positions.len());
    mesh.positions.extend_from_slice(&part.positions);
    mesh.triangles.reserve_exact(part.triangles.len());
    mesh.triangles.extend_from_slice(&part.triangles);
    mesh.normals.reserve_exact(part.normals.len());
    mesh.normals.extend_from_slice(&part.normals);
}

/// A sparse `.pgv` file's coefficients, held a window of slabs along z at a time.
struct FileWindows<'r, 'b> {
    reader: &'r SlabReader<'b>,
    /// The volume with the bricks of the slabs held.
    volume: CoefficientVolume,
    /// The file's slabs along z held in `volume`.
    held: Range<usize>,
}

impl CoefficientWindows for FileWindows<'_, '_> {
    type Error = Error;

    fn grid(&self) -> Grid {
        self.volume.grid
    }

    fn window(&mut self, layers: [usize; 2]) -> Result<Cow<'_, CoefficientVolume>> {
        let per = self.reader.grid_bricks_per_slab();
        let edge = per * BRICK_EDGE;
        let wanted = layers[0] / edge..layers[1] / edge + 1;
        if wanted.start < self.held.start || wanted.start >= self.held.end {
            self.volume.coeffs = SparseGrid::new(self.volume.grid.dims, self.reader.background());
            self.held = wanted.start..wanted.start;
        } else if wanted.start > self.held.start {
            // Windows move up: the bricks below the new window are not read again.
            let first = wanted.start * per;
            self.volume.coeffs.retain(|b, _| b[2] >= first);
            self.held.start = wanted.start;
        }
        for slab in self.held.end..wanted.end {
            let decoded = self.reader.slab(2, slab).reading()?;
            for b in decoded.inside {
                self.volume.coeffs.set_inside(b, true);
            }
            for (b, values) in decoded.stored {
                self.volume.coeffs.insert(b, values);
            }
        }
        self.held.end = self.held.end.max(wanted.end);
        Ok(Cow::Borrowed(&self.volume))
    }

    fn occupied(&self) -> Option<Occupied> {
        self.volume.basis.is_separable().then(|| Occupied {
            bricks: self.reader.occupied_bricks(),
            outside: self.reader.background().outside,
        })
    }
}

/// The file `source` was opened from, decoded whole (read again when `source` left its bricks
/// on disk).
pub(crate) fn whole_file(source: &SlabSource, path: &Path) -> Result<pgvol_format::PgvFile> {
    match source.bytes() {
        Some(bytes) => read_pgv_bytes(bytes, path),
        None => read_pgv_bytes(&pgvol_core::read_input(path).reading()?, path),
    }
}
