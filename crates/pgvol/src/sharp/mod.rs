//! Sharp edges that survive the file: at encoding, the dual-contouring vertices of the mesh's
//! exact distance are stored in the cells next to its creases and corners where the smooth fit
//! rounds them (the `sharp` section of the header, `pgvol_format::sharp`); decoding by dual
//! contouring on the file's own grid puts those cells' vertices there. Everything else about
//! the field (values, gradients, other methods and grids) is the smooth fit's.
//! `docs/algorithms.md`, "Sharp edges through the file", has the measurements.

mod cells;
mod place;
mod select;

use pgvol_core::Mesh;
use pgvol_format::sharp::{decode_sharp, encode_sharp, SharpCells, MAX_SHARP_CELLS};
use pgvol_format::PgvFile;
use pgvol_sdf::SignMode;

use crate::decode::DecodeOptions;
use crate::error::{Error, ErrorKind, Result};
use crate::progress::Progress;
use crate::timings::Timings;
use pgvol_contour::Method;

pub(crate) use place::stored_vertex;
use select::{stored_cells, Selection};

/// Default angle (degrees) between the normals of two triangles around a vertex of the exact
/// contour above which the vertex is on a crease or corner.
pub const DEFAULT_SHARP_ANGLE: f32 = 50.0;

/// Creases shorter than this many cells store nothing.
pub const SHARP_MIN_LENGTH: f32 = 4.0;

/// Cells within this many cells of a crease may be stored: the B-spline rounds an edge over
/// about two cells.
pub const SHARP_RING: u64 = 3;

/// A cell is stored only where the smooth fit's vertex is at least this far (in cells) from the
/// exact one.
pub const SHARP_TOLERANCE: f32 = 0.005;

/// The largest grid (nodes) on which encoding looks for sharp features (a 320³ grid): the
/// exact-distance contour holds about 13 bytes per node, 430 MB here.
pub const MAX_SHARP_NODES: u64 = 1 << 25;

/// Whether and how encoding stores sharp-feature vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SharpOptions {
    /// Store them (default `true`); smooth shapes store nothing either way.
    pub enabled: bool,
    /// Crease angle in degrees (default [`DEFAULT_SHARP_ANGLE`]).
    pub angle: f32,
}

impl Default for SharpOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            angle: DEFAULT_SHARP_ANGLE,
        }
    }
}

/// What [`attach`] stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SharpReport {
    /// Cells a crease or corner of the mesh passes through.
    pub feature_cells: usize,
    /// Cells with a stored vertex.
    pub stored_cells: usize,
    /// Bytes of the section's data in the header.
    pub bytes: usize,
}

/// Stores in `file` (fitted to `mesh`, whose inside `sign` tells) the exact dual-contouring
/// vertices of the cells near creases and corners whose smooth vertex is off; a shape without
/// any gets no section.
pub fn attach(
    file: &mut PgvFile,
    mesh: &Mesh,
    sign: SignMode,
    options: &SharpOptions,
    progress: &dyn Progress,
) -> Result<SharpReport> {
    file.header.sharp = None;
    if !options.enabled {
        return Ok(SharpReport::default());
    }
    if !(options.angle.is_finite() && options.angle > 0.0 && options.angle < 180.0) {
        return Err(Error::parameter(format!(
            "the crease angle must be between 0 and 180 degrees, got {}",
            options.angle
        )));
    }
    let grid = file.volume.grid;
    // The exact contour holds a value per grid node.
    let bytes = crate::memory::BYTES_PER_NODE;
    let fits = crate::memory::check_grid("finding sharp features", &grid, bytes);
    if grid.len() as u64 > MAX_SHARP_NODES || fits.is_err() {
        let [nx, ny, nz] = grid.dims;
        progress.warn(&format!(
            "no sharp-feature vertices stored: finding them contours the exact distance over \
             every node, done on grids of up to {MAX_SHARP_NODES} nodes and within the memory \
             limit, and this grid is {nx} x {ny} x {nz}"
        ));
        return Ok(SharpReport::default());
    }
    let mut timings = Timings::default();
    let exact = crate::remesh::contour_exact(
        mesh,
        &grid,
        Method::DualContouring,
        sign,
        &mut timings,
        progress,
    )?;
    let decode = DecodeOptions {
        method: Method::DualContouring,
        min_component: Some(0.0),
        ..DecodeOptions::default()
    };
    let smooth = crate::decode::decode(&file.volume, &decode, progress)?;
    let selection = Selection {
        angle: options.angle.to_radians(),
        min_length: SHARP_MIN_LENGTH,
        ring: SHARP_RING,
        tolerance: SHARP_TOLERANCE,
    };
    let bvh = pgvol_sdf::Bvh::build(mesh);
    let closest = |p| bvh.closest(p, f32::INFINITY).map(|c| c.point);
    let triangle = |p| bvh.closest(p, f32::INFINITY).map(|c| c.triangle);
    let (stored, feature_cells) = stored_cells(
        mesh, &exact, &smooth, &grid, &selection, &closest, &triangle,
    );
    if stored.is_empty() {
        return Ok(SharpReport {
            feature_cells,
            ..SharpReport::default()
        });
    }
    if stored.len() as u64 > MAX_SHARP_CELLS {
        progress.warn(&format!(
            "{} cells hold sharp-feature vertices, more than a file stores ({MAX_SHARP_CELLS}); \
             the file keeps the smooth field only",
            stored.len()
        ));
        return Ok(SharpReport {
            feature_cells,
            ..SharpReport::default()
        });
    }
    let cells = SharpCells {
        keys: stored.iter().map(|s| s.0).collect(),
        positions: stored
            .iter()
            .map(|s| SharpCells::quantise(s.1.to_array()))
            .collect(),
    };
    let section = encode_sharp(&cells);
    let report = SharpReport {
        feature_cells,
        stored_cells: cells.keys.len(),
        bytes: section.data.len(),
    };
    file.header.sharp = Some(section);
    Ok(report)
}

/// The stored cells of `file` that a decoding by `options` uses: dual contouring of the
/// surface on the file's own grid; `None` otherwise or when the file has none.
pub(crate) fn cells_for(file: &PgvFile, options: &DecodeOptions) -> Result<Option<SharpCells>> {
    let uses =
        options.method == Method::DualContouring && options.res.is_none() && options.iso == 0.0;
    match &file.header.sharp {
        Some(section) if uses => decode_sharp(section, file.volume.grid.dims)
            .map(Some)
            .map_err(|problem| Error::new(ErrorKind::InputFile, problem)),
        _ => Ok(None),
    }
}
