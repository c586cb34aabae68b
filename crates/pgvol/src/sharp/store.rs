//! What encoding stores: the creases of the mesh, the cells around them, and the exact
//! vertices of those whose smooth vertex is off, put in the file's `sharp` section.

use std::sync::atomic::{AtomicUsize, Ordering};

use pgvol_core::Mesh;
use pgvol_core::BRICK_EDGE;
use pgvol_format::sharp::{encode_sharp, SharpCells, SharpSection, MAX_SHARP_CELLS};
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
    /// Store them (default `false`: the default decoding, marching cubes, does not read them,
    /// and finding them costs time in proportion to the cells near creases); smooth shapes
    /// store nothing either way and cost nothing.
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
    attach_with(file, mesh, sign, None, options, progress)
}

/// [`attach`] with the exact distance of `mesh` already built (the one an encoding sampled),
/// or `None` to build it only if the mesh has creases.
pub(crate) fn attach_with(
    file: &mut PgvFile,
    mesh: &Mesh,
    sign: SignMode,
    exact: Option<&ExactDistance<'_>>,
    options: &SharpOptions,
    progress: &dyn Progress,
) -> Result<SharpReport> {
    file.header.sharp = None;
    let plan = SharpPlan::new(mesh, sign, exact, &file.volume.grid, options, progress)?;
    let (section, report) = plan.section(&file.volume, progress)?;
    file.header.sharp = section;
    Ok(report)
}

/// Where a mesh's sharp-feature vertices may be stored on a grid, found from the mesh alone
/// before any coefficient exists, so that a file written as its coefficients arrive can keep
/// just the coefficient bricks the vertices are chosen against ([`SharpPlan::needs_brick`]).
pub(crate) struct SharpPlan<'a> {
    feature_cells: usize,
    /// Boxes of cells near creases, each contoured on its own; empty when nothing is stored.
    boxes: Vec<boxes::CellBox>,
    /// Coefficient bricks the boxes read.
    bricks: std::collections::HashSet<[usize; 3]>,
    /// The mesh's exact distance, given or built here once the mesh is known to have creases.
    given: Option<&'a ExactDistance<'a>>,
    built: Option<ExactDistance<'a>>,
}

impl<'a> SharpPlan<'a> {
    /// The plan for `mesh` (inside as `sign` tells, its exact distance `exact` when already
    /// built) on `grid` by `options`; a smooth shape, or options that store nothing, give a
    /// plan without boxes.
    pub(crate) fn new(
        mesh: &'a Mesh,
        sign: SignMode,
        exact: Option<&'a ExactDistance<'a>>,
        grid: &pgvol_core::Grid,
        options: &SharpOptions,
        progress: &dyn Progress,
    ) -> Result<SharpPlan<'a>> {
        options.validate()?;
        let mut plan = SharpPlan {
            feature_cells: 0,
            boxes: Vec::new(),
            bricks: Default::default(),
            given: exact,
            built: None,
        };
        if !options.enabled {
            return Ok(plan);
        }
        // Creases first: a smooth shape stops here, before any distance query or contour.
        let angle = options.angle.to_radians();
        let sharp = sharp_edges(mesh, angle);
        if sharp.edges.is_empty() {
            return Ok(plan);
        }
        if plan.given.is_none() {
            plan.built = Some(ExactDistance::new(mesh, sign)?);
        }
        let Some(bvh) = plan.exact().map(ExactDistance::bvh) else {
            return Ok(plan);
        };
        let triangle = |p| bvh.closest(p, f32::INFINITY).map(|c| c.triangle);
        let flat = FlatSides::new(SHARP_FLAT_BELOW, SHARP_FLAT_REACH, SHARP_FLAT_TURN);
        let features = feature_cells(mesh, &sharp, grid, SHARP_MIN_LENGTH, &flat, &triangle);
        plan.feature_cells = features.len();
        if features.is_empty() {
            return Ok(plan);
        }
        // Memory follows the cells near creases: at most a cube of the ring's side around each
        // feature cell. Too many only costs the section, not the encoding.
        let ring_cells = (features.len() as u64).saturating_mul((2 * SHARP_RING + 1).pow(3));
        let bytes = ring_cells.saturating_mul(crate::memory::BYTES_PER_SHARP_RING_CELL);
        if let Err(e) = crate::memory::check_memory(
            "finding sharp features",
            bytes,
            "a lower resolution stores the section",
        ) {
            progress.warn(&format!("no sharp-feature vertices stored: {e}"));
            return Ok(plan);
        }
        let near = within_ring(&features, grid, SHARP_RING);
        // Each box is contoured on its own sub-grid, exact distance and smooth fit alike; a
        // cell's vertex depends only on its corners and edges, so an owned cell gets the vertex
        // the whole grid's contour would give it, to the rounding of the sub-grid's node
        // positions.
        plan.boxes = boxes::boxes(&near, grid);
        for cell_box in &plan.boxes {
            let [x, y, z] = bricks_read(&cell_box.grid, grid);
            for k in z[0]..=z[1] {
                for j in y[0]..=y[1] {
                    plan.bricks.extend((x[0]..=x[1]).map(|i| [i, j, k]));
                }
            }
        }
        Ok(plan)
    }

    /// The mesh's exact distance, once the mesh is known to have creases.
    fn exact(&self) -> Option<&ExactDistance<'a>> {
        self.given.or(self.built.as_ref())
    }

    /// Whether any cell may get a vertex: else no coefficient is read.
    pub(crate) fn has_boxes(&self) -> bool {
        !self.boxes.is_empty()
    }

    /// Whether finding the vertices reads coefficient brick `b`.
    pub(crate) fn needs_brick(&self, b: [usize; 3]) -> bool {
        self.bricks.contains(&b)
    }

    /// The section of the vertices found against `volume` (which must hold every brick
    /// [`SharpPlan::needs_brick`] names as the whole fitted volume does), and what it holds.
    pub(crate) fn section(
        &self,
        volume: &pgvol_field::CoefficientVolume,
        progress: &dyn Progress,
    ) -> Result<(Option<SharpSection>, SharpReport)> {
        let nothing = SharpReport {
            feature_cells: self.feature_cells,
            ..SharpReport::default()
        };
        let Some(exact) = self.exact().filter(|_| !self.boxes.is_empty()) else {
            return Ok((None, nothing));
        };
        let grid = volume.grid;
        let boxes = &self.boxes;
        let bvh = exact.bvh();
        let closest = |p| bvh.closest(p, f32::INFINITY).map(|c| c.point);
        let done = AtomicUsize::new(0);
        let per_box = crate::progress::stage(progress, "sharp features", |update| {
            boxes
                .par_iter()
                .map(|cell_box| -> Result<Vec<(u64, glam::Vec3)>> {
                    if update.cancelled() {
                        return Err(Error::new(ErrorKind::Cancelled, "cancelled"));
                    }
                    let sub = &cell_box.grid;
                    // Only the owned cells' vertices are compared: the rest of the box, most of
                    // its crossed cells, is not contoured.
                    let owned = cell_box.owned_cells(&grid);
                    let reach = pgvol_contour::MAX_OUTSIDE_REACH;
                    let exact = exact.contour_from_faces(sub, reach, Some(&owned), &Silent)?;
                    let quiet = pgvol_core::progress::QUIET;
                    let smooth =
                        pgvol_contour::dual_vertices_interior(volume, sub, 0.0, &owned, quiet);
                    let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                    update.update(finished as f64 / boxes.len() as f64);
                    Ok(stored_cells(
                        &cell_box.owned,
                        &exact,
                        &smooth.mesh,
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
            return Ok((None, nothing));
        }
        if stored.len() as u64 > MAX_SHARP_CELLS {
            progress.warn(&format!(
                "{} cells hold sharp-feature vertices, more than a file stores \
                 ({MAX_SHARP_CELLS}); the file keeps the smooth field only",
                stored.len()
            ));
            return Ok((None, nothing));
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
            feature_cells: self.feature_cells,
            stored_cells: cells.keys.len(),
            bytes: section.data.len(),
        };
        Ok((Some(section), report))
    }
}

/// The coefficient bricks (inclusive index ranges per axis) that contouring the sub-grid `sub`
/// of `grid` reads: the cubic B-spline at a node reads coefficients one node either side, the
/// bricks' node values read their neighbours', so one brick of margin each way.
fn bricks_read(sub: &pgvol_core::Grid, grid: &pgvol_core::Grid) -> [[usize; 2]; 3] {
    let last = grid.dims.map(|n| n.saturating_sub(1) / BRICK_EDGE);
    [0, 1, 2].map(|a| {
        let first = ((sub.origin[a] - grid.origin[a]) / grid.spacing)
            .round()
            .max(0.0) as usize;
        let end = first + sub.dims[a].saturating_sub(1);
        [
            (first / BRICK_EDGE).saturating_sub(1),
            (end / BRICK_EDGE + 1).min(last[a]),
        ]
    })
}
