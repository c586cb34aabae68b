//! What encoding stores: the creases of the mesh, the cells around them, and the exact
//! vertices of those whose smooth vertex is off, put in the file's `sharp` section.

use std::sync::atomic::{AtomicUsize, Ordering};

use pgvol_core::Mesh;
use pgvol_format::sharp::{encode_sharp, SharpCells, MAX_SHARP_CELLS};
use pgvol_format::PgvFile;
use pgvol_sdf::SignMode;
use rayon::prelude::*;

use super::boxes;
use super::select::{feature_cells, sharp_edges, stored_cells, within_ring, FlatSides};
use crate::error::{Error, ErrorKind, Result};
use crate::exact_distance::ExactDistance;
use crate::progress::{Progress, Silent};

/// Default angle (degrees) between the normals of two triangles of the mesh above which their
/// edge may be a crease.
pub const DEFAULT_SHARP_ANGLE: f32 = 30.0;

/// Creases turning by less than this (degrees) are kept only where the surface beside them is
/// flat (`SHARP_FLAT_REACH`, `SHARP_FLAT_TURN`), which the facets of a coarse curved mesh are
/// not.
pub const SHARP_FLAT_BELOW: f32 = 50.0;

/// How far from such a crease (cells) the surface is compared with the surface a cell away.
pub const SHARP_FLAT_REACH: f32 = 8.0;

/// The largest turn (degrees) of the surface between one cell and `SHARP_FLAT_REACH` cells away
/// from a crease that still counts as flat.
pub const SHARP_FLAT_TURN: f32 = 3.0;

/// Creases shorter than this many cells store nothing.
pub const SHARP_MIN_LENGTH: f32 = 4.0;

/// Cells within this many cells of a crease may be stored: the B-spline rounds an edge over
/// about two cells.
pub const SHARP_RING: u64 = 3;

/// A cell is stored only where the smooth fit's vertex is at least this far (in cells) from the
/// exact one.
pub const SHARP_TOLERANCE: f32 = 0.005;

/// Whether and how encoding stores sharp-feature vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SharpOptions {
    /// Store them (default `false`: finding them costs time in proportion to the cells near
    /// creases, more than the encoding's own on crease-rich parts); smooth shapes store
    /// nothing either way and cost nothing.
    pub enabled: bool,
    /// Crease angle in degrees (default [`DEFAULT_SHARP_ANGLE`]).
    pub angle: f32,
}

impl Default for SharpOptions {
    fn default() -> Self {
        Self {
            enabled: false,
            angle: DEFAULT_SHARP_ANGLE,
        }
    }
}

impl SharpOptions {
    /// Refuses a crease angle that is not strictly between 0 and 180 degrees.
    pub fn validate(&self) -> Result<()> {
        if self.angle.is_finite() && self.angle > 0.0 && self.angle < 180.0 {
            return Ok(());
        }
        Err(Error::parameter(format!(
            "the crease angle must be between 0 and 180 degrees, got {}",
            self.angle
        )))
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
    options.validate()?;
    if !options.enabled {
        return Ok(SharpReport::default());
    }
    let grid = file.volume.grid;
    // Creases first: a smooth shape stops here, before any distance query or contour.
    let angle = options.angle.to_radians();
    let sharp = sharp_edges(mesh, angle);
    if sharp.edges.is_empty() {
        return Ok(SharpReport::default());
    }
    let bvh = pgvol_sdf::Bvh::build(mesh);
    let triangle = |p| bvh.closest(p, f32::INFINITY).map(|c| c.triangle);
    let flat = FlatSides::new(SHARP_FLAT_BELOW, SHARP_FLAT_REACH, SHARP_FLAT_TURN);
    let features = feature_cells(mesh, &sharp, &grid, SHARP_MIN_LENGTH, &flat, &triangle);
    let feature_cells = features.len();
    if features.is_empty() {
        return Ok(SharpReport::default());
    }
    // Memory follows the cells near creases: at most a cube of the ring's side around each
    // feature cell. Too many only costs the section, not the encoding.
    let ring_cells = (feature_cells as u64).saturating_mul((2 * SHARP_RING + 1).pow(3));
    let bytes = ring_cells.saturating_mul(crate::memory::BYTES_PER_SHARP_RING_CELL);
    if let Err(e) = crate::memory::check_memory(
        "finding sharp features",
        bytes,
        "a lower resolution stores the section",
    ) {
        progress.warn(&format!("no sharp-feature vertices stored: {e}"));
        return Ok(SharpReport {
            feature_cells,
            ..SharpReport::default()
        });
    }
    let near = within_ring(&features, &grid, SHARP_RING);
    let exact = ExactDistance::new(mesh, sign)?;
    let closest = |p| bvh.closest(p, f32::INFINITY).map(|c| c.point);
    // Each box is contoured on its own sub-grid, exact distance and smooth fit alike; a cell's
    // vertex depends only on its corners and edges, so an owned cell gets the vertex the whole
    // grid's contour would give it, to the rounding of the sub-grid's node positions.
    let boxes = boxes::boxes(&near, &grid);
    let done = AtomicUsize::new(0);
    let per_box = crate::progress::stage(progress, "sharp features", |update| {
        boxes
            .par_iter()
            .map(|cell_box| -> Result<Vec<(u64, glam::Vec3)>> {
                if update.cancelled() {
                    return Err(Error::new(ErrorKind::Cancelled, "cancelled"));
                }
                let sub = &cell_box.grid;
                let exact =
                    exact.contour_from_faces(sub, pgvol_contour::MAX_OUTSIDE_REACH, &Silent)?;
                let quiet = pgvol_core::progress::QUIET;
                let smooth = pgvol_contour::dual_contour_interior(&file.volume, sub, 0.0, quiet);
                let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                update.update(finished as f64 / boxes.len() as f64);
                Ok(stored_cells(
                    &cell_box.owned,
                    &exact,
                    &smooth,
                    &grid,
                    SHARP_TOLERANCE,
                    &closest,
                ))
            })
            .collect::<Result<Vec<_>>>()
    })?;
    let mut stored: Vec<(u64, glam::Vec3)> = per_box?.into_iter().flatten().collect();
    stored.sort_unstable_by_key(|s| s.0);
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
