//! Sharp edges that survive the file: at encoding, the dual-contouring vertices of the mesh's
//! exact distance are stored in the cells next to its creases and corners where the smooth fit
//! rounds them (the `sharp` section of the header, `pgvol_format::sharp`); decoding by dual
//! contouring or surface nets on the file's own grid puts those cells' vertices there.
//! Everything else about the field (values, gradients, other methods and grids) is the smooth
//! fit's. `docs/algorithms.md`, "Sharp edges through the file", has the measurements.

mod boxes;
mod cells;
mod corners;
mod place;
mod select;
pub(crate) mod store;

use pgvol_format::sharp::{decode_sharp, SharpCells};
use pgvol_format::PgvFile;

use crate::decode::DecodeOptions;
use crate::error::{Error, ErrorKind, Result};
use pgvol_contour::Method;

pub(crate) use place::stored_vertex;
pub use store::{
    attach, SharpOptions, SharpReport, DEFAULT_SHARP_ANGLE, SHARP_FLAT_BELOW, SHARP_FLAT_REACH,
    SHARP_FLAT_TURN, SHARP_MIN_LENGTH, SHARP_RING, SHARP_TOLERANCE,
};

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
    use super::select::{feature_cells, sharp_edges, stored_cells, within_ring, FlatSides};
    use super::*;
    use crate::exact_distance::ExactDistance;
    use crate::progress::Silent;
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
            .contour_from_faces(&grid, pgvol_contour::MAX_OUTSIDE_REACH, None, &Silent)
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
