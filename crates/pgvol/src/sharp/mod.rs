//! Sharp edges that survive the file: at encoding, the dual-contouring vertices of the mesh's
//! exact distance are stored in the cells next to its creases and corners where the smooth fit
//! rounds them (the `sharp` section of the header, `pgvol_format::sharp`); decoding by dual
//! contouring on the file's own grid puts those cells' vertices there. Everything else about
//! the field (values, gradients, other methods and grids) is the smooth fit's.
//! `docs/algorithms.md`, "Sharp edges through the file", has the measurements.

mod boxes;
mod cells;
mod corners;
mod place;
mod select;

use std::sync::atomic::{AtomicUsize, Ordering};

use pgvol_core::Mesh;
use pgvol_format::sharp::{decode_sharp, encode_sharp, SharpCells, MAX_SHARP_CELLS};
use pgvol_format::PgvFile;
use pgvol_sdf::SignMode;

use crate::decode::DecodeOptions;
use crate::error::{Error, ErrorKind, Result};
use crate::progress::{Progress, Silent};
use crate::remesh::ExactDistance;
use pgvol_contour::Method;
use rayon::prelude::*;

pub(crate) use place::stored_vertex;
use select::{feature_cells, sharp_edges, stored_cells, within_ring, FlatSides};

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

/// The stored cells of `file` that a decoding by `options` uses: dual contouring or surface
/// nets of the surface on the file's own grid; `None` otherwise or when the file has none.
pub(crate) fn cells_for(file: &PgvFile, options: &DecodeOptions) -> Result<Option<SharpCells>> {
    let dual = matches!(options.method, Method::DualContouring | Method::SurfaceNets);
    let uses = dual && options.res.is_none() && options.iso == 0.0;
    match &file.header.sharp {
        Some(section) if uses => decode_sharp(section, file.volume.grid.dims)
            .map(Some)
            .map_err(|problem| Error::new(ErrorKind::InputFile, problem)),
        _ => Ok(None),
    }
}

/// Puts back into `layers`, sliced along `axis` from the field of a file with `header`, the
/// corners its sharp-feature vertices mark (see `corners.rs`); a file without any is left as
/// sliced.
pub(crate) fn sharpen_sliced(
    layers: &mut [pgvol_slice::Layer],
    header: &pgvol_format::PgvHeader,
    axis: pgvol_slice::Axis,
) -> Result<()> {
    let Some(section) = &header.sharp else {
        return Ok(());
    };
    let cells = decode_sharp(section, header.grid.dims)
        .map_err(|problem| Error::new(ErrorKind::InputFile, problem))?;
    corners::sharpen_layers(layers, &header.grid, &cells, axis);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat3, Vec3};

    /// The boxes give the cells and vertices that contouring the whole grid gives: a wrong
    /// margin or origin would change whole rows of cells, while node positions computed from
    /// another origin move only a few vertices, by rounding.
    #[test]
    fn boxes_store_what_the_whole_grid_stores() {
        let mut cube = pgvol_mesh::shapes::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5));
        let turn = Mat3::from_rotation_y(0.5) * Mat3::from_rotation_x(0.5);
        for p in &mut cube.positions {
            *p = turn * *p;
        }
        let options = crate::EncodeOptions {
            grid: crate::grid::GridSpec::Res(48),
            ..Default::default()
        };
        let mut file = crate::encode(&cube, &options, &Silent).unwrap().file;
        let sign = options.sign;
        let sharp = SharpOptions {
            enabled: true,
            ..Default::default()
        };
        let report = attach(&mut file, &cube, sign, &sharp, &Silent).unwrap();
        let section = file.header.sharp.as_ref().expect("a cube stores cells");
        let boxed = decode_sharp(section, file.volume.grid.dims).unwrap();
        assert!(report.stored_cells > 100, "{report:?}");

        let grid = file.volume.grid;
        let angle = sharp.angle.to_radians();
        let bvh = pgvol_sdf::Bvh::build(&cube);
        let triangle = |p| bvh.closest(p, f32::INFINITY).map(|c| c.triangle);
        let edges = sharp_edges(&cube, angle);
        let flat = FlatSides::new(SHARP_FLAT_BELOW, SHARP_FLAT_REACH, SHARP_FLAT_TURN);
        let features = feature_cells(&cube, &edges, &grid, SHARP_MIN_LENGTH, &flat, &triangle);
        let near = within_ring(&features, &grid, SHARP_RING);
        let dc = Method::DualContouring;
        let exact = ExactDistance::new(&cube, sign)
            .unwrap()
            .contour_from_faces(&grid, pgvol_contour::MAX_OUTSIDE_REACH, &Silent)
            .unwrap();
        let decode = DecodeOptions {
            method: dc,
            min_component: Some(0.0),
            ..DecodeOptions::default()
        };
        let smooth = crate::decode::decode(&file.volume, &decode, &Silent).unwrap();
        let closest = |p| bvh.closest(p, f32::INFINITY).map(|c| c.point);
        let whole = stored_cells(&near, &exact, &smooth, &grid, SHARP_TOLERANCE, &closest);

        let same_cell = whole
            .iter()
            .filter(|(key, target)| {
                let Ok(i) = boxed.keys.binary_search(key) else {
                    return false;
                };
                let q = SharpCells::quantise(target.to_array());
                (0..3).all(|a| (q[a] - boxed.positions[i][a]).abs() <= 1.01 / 128.0)
            })
            .count();
        assert!(
            same_cell * 100 >= whole.len() * 99 && boxed.keys.len() * 100 <= whole.len() * 101,
            "{same_cell} of {} whole-grid cells stored alike by the {} boxed cells",
            whole.len(),
            boxed.keys.len()
        );
    }
}
