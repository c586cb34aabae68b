//! A shape as a field for the manufacturing operations: read from a `.pgv` file, or encoded from
//! a mesh on the fly with distances as far out as the operation needs; and the operations
//! themselves (offset, shell, hollow) with the checks that the field reaches far enough.

use std::path::Path;

use glam::{DVec3, Vec3};
use pgvol_core::{Grid, Mesh};
use pgvol_field::{Basis, CoefficientVolume, FitMethod};
use pgvol_format::PgvFile;
use pgvol_ops::{Drain, ShellSide};
use pgvol_sdf::SignMode;

use crate::encode::{fit_volume, is_pgv, EncodeOptions, BAND_KEY, ENCODE_BAND};
use crate::error::{Error, ErrorKind, Result};
use crate::grid::GridSpec;
use crate::pgv_io::{read_pgv, recorded_band};
use crate::progress::Progress;
use crate::resolution::{check_pieces, check_wall};
use crate::{mesh_io, Timings};

/// Grid nodes per axis when a mesh is encoded on the fly for an offset or a shell.
pub const SHAPE_RES: usize = 128;

/// Grid nodes per axis when a mesh is encoded on the fly for slicing.
pub const SLICE_RES: usize = 256;

/// A field and what is known of the shape it came from.
#[derive(Clone, Debug)]
pub struct Shape {
    /// The field.
    pub volume: CoefficientVolume,
    /// The box of the source shape (the grid's box when the file does not record it).
    pub bounds: (Vec3, Vec3),
    /// The source mesh, when the shape was encoded from one.
    pub mesh: Option<Mesh>,
    /// Distance from the surface within which the field is exact, when known.
    pub band: Option<f32>,
}

impl Shape {
    /// The shape of a `.pgv` file.
    pub fn from_file(file: PgvFile) -> Shape {
        let band = recorded_band(&file);
        let bounds = match file.header.source_bounds {
            Some([lo, hi]) => (Vec3::from(lo), Vec3::from(hi)),
            None => pgvol_slice::volume_bounds(&file.volume),
        };
        Shape {
            volume: file.volume,
            bounds,
            mesh: None,
            band,
        }
    }

    /// `mesh` encoded on `res` nodes per axis over its box grown by `grow` on every side, with
    /// exact distances `reach` beyond the usual encoding band, so that an operation reaching
    /// `reach` from the surface reads exact distances; inside told from outside by `sign`.
    pub fn from_mesh(
        mesh: Mesh,
        res: usize,
        grow: f32,
        reach: f32,
        sign: SignMode,
        progress: &dyn Progress,
    ) -> Result<Shape> {
        Shape::encode_mesh(mesh, res, grow, reach, None, sign, progress)
    }

    /// [`Shape::from_mesh`], refusing a grid that cannot hold walls as thin as `wall` (see
    /// [`check_wall`]) before the mesh is encoded.
    fn encode_mesh(
        mesh: Mesh,
        res: usize,
        grow: f32,
        reach: f32,
        wall: Option<f32>,
        sign: SignMode,
        progress: &dyn Progress,
    ) -> Result<Shape> {
        let (lo, hi) = mesh
            .bounds()
            .ok_or_else(|| Error::new(ErrorKind::InputFile, "the mesh has no triangles"))?;
        let pad = Vec3::splat(grow.max(0.0));
        let grid = Grid::cube_res(lo - pad, hi + pad, res)?.with_offset(mesh.offset);
        if let Some(wall) = wall {
            check_wall("the wall thickness", wall, &grid)?;
        }
        let options = EncodeOptions {
            grid: GridSpec::Res(res),
            basis: Basis::Bspline3,
            fit: FitMethod::Interp,
            band: ENCODE_BAND + reach.abs() / grid.spacing,
            sign,
        };
        crate::memory::check_sparse_encode("encoding the mesh", &mesh, &grid, options.band)?;
        let volume = fit_volume(&mesh, grid, &options, &mut Timings::default(), progress)?.volume;
        Ok(Shape {
            volume,
            bounds: (lo, hi),
            band: Some(options.band * grid.spacing),
            mesh: Some(mesh),
        })
    }

    /// A `.pgv` file or a mesh file by extension; see [`Shape::from_mesh`] for `res`, `grow`,
    /// `reach` and `sign`. A `.pgv` file holds its signs already: a `sign` other than
    /// [`SignMode::Auto`] is refused for one rather than ignored.
    pub fn load(
        path: &Path,
        res: usize,
        grow: f32,
        reach: f32,
        sign: SignMode,
        progress: &dyn Progress,
    ) -> Result<Shape> {
        Shape::load_inner(path, res, grow, reach, None, sign, progress)
    }

    /// [`Shape::load`] for an operation making walls as thin as `wall`: a grid that cannot
    /// hold them (see [`check_wall`]) is refused before a mesh is encoded on it.
    pub fn load_walled(
        path: &Path,
        res: usize,
        grow: f32,
        reach: f32,
        wall: f32,
        sign: SignMode,
        progress: &dyn Progress,
    ) -> Result<Shape> {
        Shape::load_inner(path, res, grow, reach, Some(wall), sign, progress)
    }

    fn load_inner(
        path: &Path,
        res: usize,
        grow: f32,
        reach: f32,
        wall: Option<f32>,
        sign: SignMode,
        progress: &dyn Progress,
    ) -> Result<Shape> {
        let at_path = |e: Error| match e.path() {
            Some(_) => e,
            None => e.at(path),
        };
        if is_pgv(path) {
            if sign != SignMode::Auto {
                return Err(Error::new(
                    ErrorKind::BadParameter,
                    "a sign method applies to mesh inputs; a .pgv file stores its field's signs \
                     (pass the mesh to choose how they are found)",
                )
                .at(path));
            }
            let shape = Shape::from_file(read_pgv(path)?);
            if let Some(wall) = wall {
                check_wall("the wall thickness", wall, &shape.volume.grid).map_err(at_path)?;
            }
            return Ok(shape);
        }
        let (mesh, _) = mesh_io::read_mesh(path)?;
        Shape::encode_mesh(mesh, res, grow, reach, wall, sign, progress).map_err(at_path)
    }

    /// Refuses an operation reaching `reach` from the surface when the field is not an exact
    /// distance that far out: the recorded band less the basis support, or, for files without
    /// a record, the band measured from the coefficients.
    pub fn check_reach(&self, reach: f32) -> Result<()> {
        let support = pgvol_ops::support_reach(&self.volume);
        check_reach_within(self.exact_band(), support, self.volume.grid.spacing, reach)
    }

    /// Points given in world coordinates, in the field's local frame (the offset subtracted in
    /// f64, then rounded once).
    pub fn to_local(&self, points: &[DVec3]) -> Vec<Vec3> {
        let offset = self.volume.grid.offset;
        points
            .iter()
            .map(|&p| pgvol_core::frame::to_local(p, offset))
            .collect()
    }

    /// The distance from the surface within which level sets of the field are exact: the
    /// recorded band (or, for files without a record, the largest node value) less the reach of
    /// the basis support, which blends in the clamped values beyond it.
    pub fn exact_band(&self) -> f32 {
        reach_within(self.band, &self.volume)
    }

    /// The `.pgv` file of a field derived from this shape by `operation`, which moved the
    /// surface by up to `shift` from this shape's (see [`operation_shift`]). Its header records
    /// the band within which its node values are exact distances: this shape's (or, without a
    /// record, its largest node value) less `shift`, since the operation reads this field that
    /// much farther out. A sparse write keeps the bricks that band needs.
    pub fn derived_file(&self, volume: CoefficientVolume, operation: &str, shift: f32) -> PgvFile {
        let mut header = pgvol_format::header_for(&volume, "interp", self.mesh.as_ref());
        header
            .metadata
            .insert("operation".into(), operation.to_string());
        let band = self
            .band
            .unwrap_or_else(|| pgvol_ops::stored_band(&self.volume))
            - shift.abs();
        if band.is_finite() && band > 0.0 {
            header.metadata.insert(BAND_KEY.into(), format!("{band}"));
        }
        PgvFile { header, volume }
    }
}

/// Refuses reaching `reach` from the surface of a field that is an exact distance only within
/// `band`, whose basis support reaches `support`, on a grid of `spacing`.
pub(crate) fn check_reach_within(band: f32, support: f32, spacing: f32, reach: f32) -> Result<()> {
    if reach.abs() >= band {
        let needed = ((reach.abs() + support) / spacing).ceil() + 1.0;
        return Err(Error::new(
            ErrorKind::BadParameter,
            format!(
                "the field is an exact distance only within {band:.4} of the surface, too \
                 narrow for {reach}; encode it again with a band of {needed} grid spacings \
                 or wider, or pass the mesh"
            ),
        )
        .with_remedy(crate::error::Remedy::Band(needed)));
    }
    Ok(())
}

/// The distance from the surface, in model units, within which the field of `file` is an exact
/// distance for offsets, shells, levels and evaluation: the band recorded in the file (or the
/// largest node value) less the reach of the basis support (2 spacings for the B-splines). A
/// band of W spacings thus serves offsets up to W − 2 spacings; 0 when nothing is exact.
pub fn exact_reach(file: &PgvFile) -> f32 {
    reach_within(recorded_band(file), &file.volume).max(0.0)
}

/// `band` (or the largest node value) less the basis support's reach.
fn reach_within(band: Option<f32>, volume: &CoefficientVolume) -> f32 {
    let band = band.unwrap_or_else(|| pgvol_ops::stored_band(volume));
    band - pgvol_ops::support_reach(volume)
}

/// A drain hole from `x,y,z,dx,dy,dz,diameter`: a point inside the cavity, the direction out
/// through the wall (normalised here) and the hole's diameter.
pub fn parse_drain(text: &str) -> Result<Drain> {
    let numbers: Vec<f32> = text
        .split(',')
        .map(|x| {
            x.trim()
                .parse::<f32>()
                .map_err(|_| Error::parameter(format!("drain: '{x}' is not a number")))
        })
        .collect::<Result<_>>()?;
    if numbers.len() != 7 || numbers.iter().any(|x| !x.is_finite()) {
        return Err(Error::parameter(
            "drain: expected seven finite numbers x,y,z,dx,dy,dz,diameter",
        ));
    }
    let direction = Vec3::new(numbers[3], numbers[4], numbers[5]);
    if direction.length() == 0.0 || numbers[6] <= 0.0 {
        return Err(Error::parameter(
            "drain: the direction must be non-zero and the diameter positive",
        ));
    }
    Ok(Drain {
        point: Vec3::new(numbers[0], numbers[1], numbers[2]),
        direction: direction.normalize(),
        diameter: numbers[6],
    })
}

/// Where a shell's wall lies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShellKind {
    /// A wall of the given side.
    Wall(ShellSide),
    /// Keep the outer surface and cut a cavity inside (hollowing for printing).
    #[default]
    Hollow,
}

/// How far outside the shape an operation's result reaches, so an encoded grid covers it.
pub fn growth(kind: ShellKind, thickness: f32) -> f32 {
    match kind {
        ShellKind::Wall(ShellSide::Outer) => thickness,
        ShellKind::Wall(ShellSide::Centred) => thickness / 2.0,
        _ => 0.0,
    }
}

/// Refuses an offset distance that is not finite and non-zero.
pub fn check_offset(distance: f32) -> Result<()> {
    if !distance.is_finite() || distance == 0.0 {
        return Err(Error::parameter(format!(
            "the offset distance must be a finite non-zero number, got {distance}"
        )));
    }
    Ok(())
}

/// Refuses a wall thickness that is not finite and positive.
pub fn check_thickness(thickness: f32) -> Result<()> {
    if !(thickness.is_finite() && thickness > 0.0) {
        return Err(Error::parameter(format!(
            "the thickness must be a positive number, got {thickness}"
        )));
    }
    Ok(())
}

/// The shape grown (`distance` > 0) or shrunk by `distance`; refused when the result breaks
/// into far more pieces than the shape (see [`check_pieces`]).
pub fn offset(shape: &Shape, distance: f32) -> Result<CoefficientVolume> {
    check_offset(distance)?;
    shape.check_reach(distance)?;
    let volume = pgvol_ops::offset(&shape.volume, distance)?;
    check_pieces("the offset", &shape.volume, &volume)?;
    Ok(volume)
}

/// A wall of `thickness` around the surface, or the shape hollowed with drain holes. A wall
/// thinner than the grid resolves is refused before the work (see [`check_wall`]), a result
/// broken into far more pieces than the shape after it.
pub fn shell(
    shape: &Shape,
    thickness: f32,
    kind: ShellKind,
    drains: &[Drain],
    progress: &dyn Progress,
) -> Result<CoefficientVolume> {
    check_thickness(thickness)?;
    if !drains.is_empty() && kind != ShellKind::Hollow {
        return Err(Error::parameter("drain holes apply to hollowing only"));
    }
    check_wall("the wall thickness", thickness, &shape.volume.grid)?;
    shape.check_reach(thickness)?;
    // Drain points are world coordinates; the field's are local.
    let drains: Vec<Drain> = drains
        .iter()
        .map(|d| Drain {
            point: shape.to_local(&[d.point.as_dvec3()])[0],
            ..*d
        })
        .collect();
    if kind == ShellKind::Hollow {
        check_drains(shape, thickness, &drains, progress)?;
    }
    let (volume, operation) = match kind {
        ShellKind::Hollow => (
            pgvol_ops::hollow(&shape.volume, thickness, &drains)?,
            "the hollowing",
        ),
        ShellKind::Wall(side) => (
            pgvol_ops::shell(&shape.volume, thickness, side)?,
            "the shell",
        ),
    };
    check_pieces(operation, &shape.volume, &volume)?;
    Ok(volume)
}

/// Warns when hollowing an open mesh, and refuses a drain whose point is not in the cavity
/// left inside walls of `thickness` (it would open nothing).
pub(crate) fn check_drains(
    shape: &Shape,
    thickness: f32,
    drains: &[Drain],
    progress: &dyn Progress,
) -> Result<()> {
    if let Some(mesh) = &shape.mesh {
        let stats = mesh.stats();
        if stats.boundary_edges > 0 {
            progress.warn(&format!(
                "the mesh is open ({} boundary edges): its inside is a guess from the winding \
                 number, and the cavity may not be sealed",
                stats.boundary_edges
            ));
        }
    }
    for (n, drain) in drains.iter().enumerate() {
        // The hole runs from its point outward: a point outside the cavity opens nothing.
        let value = shape.volume.value(drain.point);
        if value >= -thickness {
            let p = pgvol_core::frame::to_world(drain.point, shape.volume.grid.offset);
            let place = if value >= 0.0 {
                "outside the shape".to_string()
            } else {
                format!("{:.4} inside the surface, in the wall", -value)
            };
            return Err(Error::parameter(format!(
                "drain {} at ({}, {}, {}) lies {place}; its point must be in the cavity, more \
                 than the thickness {thickness} inside the surface",
                n + 1,
                p.x,
                p.y,
                p.z
            )));
        }
    }
    Ok(())
}

/// The operation's name as recorded in a derived file.
pub fn operation_name(kind: Option<ShellKind>, amount: f32) -> String {
    match kind {
        None => format!("offset {amount}"),
        Some(ShellKind::Hollow) => format!("hollow {amount}"),
        Some(ShellKind::Wall(_)) => format!("shell {amount}"),
    }
}

/// How far from the shape's surface an offset (`kind` `None`, `amount` the distance), a shell
/// or a hollowing (`amount` the thickness) puts the result's surfaces, for
/// [`Shape::derived_file`]: the distance, the thickness, half of it for a centred wall.
pub fn operation_shift(kind: Option<ShellKind>, amount: f32) -> f32 {
    match kind {
        Some(ShellKind::Wall(ShellSide::Centred)) => amount.abs() / 2.0,
        _ => amount.abs(),
    }
}
