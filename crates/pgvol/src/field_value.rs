//! [`Field`], the value the library's users hold: read from a `.pgv` file, encoded from a mesh
//! (on the fly with distances as far out as an operation needs), saved again; and the
//! operations that move its surface (offset, shell, hollow) with the checks that the field
//! reaches far enough.

use std::io::{Read, Write};
use std::path::Path;
use std::sync::Arc;

use glam::{DVec3, Vec3};
use pgvol_core::{Grid, Mesh};
use pgvol_field::{Basis, CoefficientVolume, FitMethod};
use pgvol_format::{PgvFile, PgvHeader};
use pgvol_ops::{Drain, ShellSide};
use pgvol_sdf::SignMode;

use crate::band::{recorded_band, BAND_KEY};
use crate::encode::{fit_exact, is_pgv, EncodeOptions, StorageOptions, StorageReport, ENCODE_BAND};
use crate::error::{Error, ErrorKind, Result};
use crate::exact_distance::ExactDistance;
use crate::grid::GridSpec;
use crate::memory;
use crate::mesh_io;
use crate::pgv_io::read_pgv;
use crate::progress::{self, Progress, Silent};
use crate::resolution::{check_pieces, check_wall, figure};
use crate::sharp::store::{attach_with, SharpOptions};
use crate::timings::Timings;

/// Grid nodes per axis when a mesh is encoded on the fly for an offset or a shell.
pub const SHAPE_RES: usize = 128;

/// Grid nodes per axis when a mesh is encoded on the fly for slicing.
pub const SLICE_RES: usize = 256;

/// A field: the coefficient volume with its file header, the box of the shape it came from and
/// the band within which it is an exact distance. Every operation returns a new `Field`, so
/// operations chain, and any `Field` saves as a `.pgv` file.
#[derive(Clone, Debug)]
pub struct Field {
    /// The header and the coefficients, as a `.pgv` file holds them.
    pub(crate) file: PgvFile,
    pub(crate) bounds: (Vec3, Vec3),
    /// The source mesh, when the field was encoded from one in this process.
    pub(crate) mesh: Option<Arc<Mesh>>,
    pub(crate) band: Option<f32>,
}

/// How [`Field::open`] makes a field of a mesh file (a `.pgv` file is read as it is).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpenOptions {
    /// Grid nodes per axis (default [`SHAPE_RES`]).
    pub res: usize,
    /// The mesh's box is grown by this much on every side before the grid is laid over it, so
    /// that a result reaching outside the mesh stays on the grid (default 0).
    pub grow: f32,
    /// Distances are exact this far beyond the usual encoding band, for an operation reading
    /// the field that far from the surface (default 0).
    pub reach: f32,
    /// A grid that cannot hold walls this thin (see [`check_wall`]) is refused before the mesh
    /// is encoded, and so is such a `.pgv` file (default none). With walls, the memory estimate
    /// made before the encode includes the shell that follows it.
    pub wall: Option<f32>,
    /// How inside is told from outside in a mesh (default [`SignMode::Auto`]); a `.pgv` file
    /// stores its signs, and any other mode is refused for one.
    pub sign: SignMode,
    /// Whether a mesh's sharp-feature vertices are stored with its field, as
    /// [`EncodeOptions::sharp`] (default not); a `.pgv` file keeps the ones it has, and asking
    /// for them is refused for one.
    pub sharp: SharpOptions,
}

impl Default for OpenOptions {
    fn default() -> Self {
        OpenOptions {
            res: SHAPE_RES,
            grow: 0.0,
            reach: 0.0,
            wall: None,
            sign: SignMode::Auto,
            sharp: SharpOptions::default(),
        }
    }
}

impl Field {
    /// The field of a decoded `.pgv` file.
    pub fn from_file(file: PgvFile) -> Field {
        let band = recorded_band(&file);
        let bounds = match file.header.source_bounds {
            Some([lo, hi]) => (Vec3::from(lo), Vec3::from(hi)),
            None => pgvol_slice::volume_bounds(&file.volume),
        };
        Field {
            file,
            bounds,
            mesh: None,
            band,
        }
    }

    /// A field of coefficients made elsewhere, with a header that records no source.
    pub fn from_volume(volume: CoefficientVolume) -> Field {
        let header = pgvol_format::header_for(&volume, "interp", None);
        Field::from_file(PgvFile { header, volume })
    }

    /// Reads a `.pgv` file of a coefficient volume (a perturbation field's file is resampled
    /// onto its grid, as [`crate::perturb`] describes).
    pub fn load(path: impl AsRef<Path>) -> Result<Field> {
        let path = path.as_ref();
        let source = crate::pgv_io::read_field_source(path)?;
        Ok(Field::from_file(
            source.into_file(&Silent).map_err(|e| e.at(path))?,
        ))
    }

    /// [`Field::load`] from the bytes of a file; `name` labels errors.
    pub fn from_bytes(bytes: &[u8], name: impl AsRef<Path>) -> Result<Field> {
        let name = name.as_ref();
        let source = crate::pgv_io::read_field_source_bytes(bytes, name)?;
        Ok(Field::from_file(
            source.into_file(&Silent).map_err(|e| e.at(name))?,
        ))
    }

    /// [`Field::load`] from a reader; `name` labels errors.
    pub fn from_reader(r: &mut dyn Read, name: impl AsRef<Path>) -> Result<Field> {
        let mut bytes = Vec::new();
        r.read_to_end(&mut bytes).map_err(|e| {
            Error::new(ErrorKind::InputFile, format!("read failed: {e}"))
                .caused_by(e)
                .at(name.as_ref())
        })?;
        Field::from_bytes(&bytes, name)
    }

    /// `mesh` encoded as `options` ask (see [`crate::encode`]), warnings sent to `progress`.
    pub fn from_mesh(
        mesh: &Mesh,
        options: &EncodeOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        Ok(Field::from_file(
            crate::encode::encode(mesh, options, progress)?.file,
        ))
    }

    /// A `.pgv` file, an OpenVDB `.vdb` level set (its first float level set, fitted on its
    /// own voxel grid: see [`crate::io::encode_vdb`]), or a mesh file by extension encoded as
    /// `options` say: on `options.res`
    /// nodes per axis over its box grown by `options.grow`, with exact distances
    /// `options.reach` beyond the usual band, so that an operation reaching that far from the
    /// surface reads exact distances.
    pub fn open(
        path: impl AsRef<Path>,
        options: &OpenOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        let path = path.as_ref();
        let at_path = |e: Error| match e.path() {
            Some(_) => e,
            None => e.at(path),
        };
        let from_mesh = !(is_pgv(path) || crate::vdb_in::is_vdb(path));
        if options.sharp.enabled && !from_mesh {
            return Err(Error::new(
                ErrorKind::BadParameter,
                "sharp-feature vertices are found from a mesh; a .pgv file keeps those it was \
                 encoded with, and a .vdb level set has none (pass the mesh to store them)",
            )
            .at(path));
        }
        if is_pgv(path) {
            if options.sign != SignMode::Auto {
                return Err(Error::new(
                    ErrorKind::BadParameter,
                    "a sign method applies to mesh inputs; a .pgv file stores its field's signs \
                     (pass the mesh to choose how they are found)",
                )
                .at(path));
            }
            let field = Field::from_file(read_pgv(path)?);
            if let Some(wall) = options.wall {
                check_wall("the wall thickness", wall, &field.file.volume.grid).map_err(at_path)?;
            }
            return Ok(field);
        }
        if crate::vdb_in::is_vdb(path) {
            if options.sign != SignMode::Auto {
                return Err(Error::new(
                    ErrorKind::BadParameter,
                    "a sign method applies to mesh inputs; a .vdb level set stores its signs",
                )
                .at(path));
            }
            let vdb_options = crate::vdb_in::VdbEncodeOptions::default();
            let file = crate::vdb_in::encode_vdb(path, &vdb_options, progress)?.file;
            let field = Field::from_file(file);
            if let Some(wall) = options.wall {
                check_wall("the wall thickness", wall, &field.file.volume.grid).map_err(at_path)?;
            }
            return Ok(field);
        }
        let mesh = mesh_io::read_mesh(path)?.mesh;
        Field::for_operations(mesh, options, progress).map_err(at_path)
    }

    /// `mesh` encoded for the operations that read its field away from the surface (offsets,
    /// shells, lattices): see [`OpenOptions`].
    pub fn for_operations(
        mesh: Mesh,
        options: &OpenOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        let (lo, hi) = mesh
            .bounds()
            .ok_or_else(|| Error::new(ErrorKind::InputFile, "the mesh has no triangles"))?;
        let pad = Vec3::splat(options.grow.max(0.0));
        let grid = Grid::cube_res(lo - pad, hi + pad, options.res)?.with_offset(mesh.offset);
        if let Some(wall) = options.wall {
            check_wall("the wall thickness", wall, &grid)?;
        }
        let encode = EncodeOptions {
            grid: GridSpec::Res(options.res),
            basis: Basis::Bspline3,
            fit: FitMethod::Interp,
            band: ENCODE_BAND + options.reach.abs() / grid.spacing,
            sign: options.sign,
            sharp: SharpOptions::default(),
        };
        let walls = match options.wall {
            // The walls' operation maps the field and fits it again (see `Field::shell`).
            Some(_) => memory::band_bricks(memory::mesh_area(&mesh), grid.spacing, encode.band)
                .saturating_mul(memory::BYTES_PER_REMAP_BRICK),
            None => 0,
        };
        let job = match walls {
            0 => "encoding the mesh",
            _ => "encoding the mesh and making its walls",
        };
        let then = walls.saturating_add(memory::crease_bytes(&mesh, options.sharp.enabled));
        memory::check_sparse_encode_then(job, &mesh, &grid, encode.band, then)?;
        // Built once: the sharp-feature stage queries the same distance.
        let start = std::time::Instant::now();
        let exact = ExactDistance::new(&mesh, options.sign)?;
        let timings = (&mut Timings::default(), start);
        let keep = options.sharp.enabled;
        let (fitted, exact) = fit_exact(exact, keep, grid, &encode, timings, progress)?;
        let volume = fitted.volume;
        let band = encode.band * grid.spacing;
        let mut header = pgvol_format::header_for(&volume, "interp", Some(&mesh));
        header.metadata.insert(BAND_KEY.into(), format!("{band}"));
        let mut file = PgvFile { header, volume };
        let sign = options.sign;
        attach_with(
            &mut file,
            &mesh,
            sign,
            exact.as_ref(),
            &options.sharp,
            progress,
        )?;
        drop(exact);
        Ok(Field {
            file,
            bounds: (lo, hi),
            band: Some(band),
            mesh: Some(Arc::new(mesh)),
        })
    }

    /// The coefficient volume.
    pub fn volume(&self) -> &CoefficientVolume {
        &self.file.volume
    }

    /// The header a `.pgv` file of this field carries.
    pub fn header(&self) -> &PgvHeader {
        &self.file.header
    }

    /// The grid the coefficients sit on.
    pub fn grid(&self) -> &Grid {
        &self.file.volume.grid
    }

    /// The box of the source shape (the grid's box when the file does not record it), in the
    /// field's local frame.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// This field with `bounds` as the box of its source shape (local frame), which slicing
    /// centres its in-plane lattice on.
    pub fn with_bounds(mut self, bounds: (Vec3, Vec3)) -> Field {
        self.bounds = bounds;
        self
    }

    /// The source mesh, when this field was encoded from one in this process.
    pub fn mesh(&self) -> Option<&Mesh> {
        self.mesh.as_deref()
    }

    /// The distance from the surface within which the node values are exact distances, when
    /// recorded.
    pub fn band(&self) -> Option<f32> {
        self.band
    }

    /// The field as a `.pgv` file's contents.
    pub fn file(&self) -> &PgvFile {
        &self.file
    }

    /// The field as a `.pgv` file's contents, without copying the coefficients.
    pub fn into_file(self) -> PgvFile {
        self.file
    }

    /// Refuses an operation reaching `reach` from the surface when the field is not an exact
    /// distance that far out: the recorded band less the basis support, or, for files without
    /// a record, the band measured from the coefficients.
    pub fn check_reach(&self, reach: f32) -> Result<()> {
        let support = pgvol_ops::support_reach(&self.file.volume);
        check_reach_within(self.exact_band(), support, &self.file.volume.grid, reach)
    }

    /// Points given in world coordinates, in the field's local frame (the offset subtracted in
    /// f64, then rounded once).
    pub fn to_local(&self, points: &[DVec3]) -> Vec<Vec3> {
        let offset = self.file.volume.grid.offset;
        points
            .iter()
            .map(|&p| pgvol_core::frame::to_local(p, offset))
            .collect()
    }

    /// The distance from the surface within which level sets of the field are exact: the
    /// recorded band (or, for files without a record, the largest node value) less the reach of
    /// the basis support, which blends in the clamped values beyond it.
    pub fn exact_band(&self) -> f32 {
        reach_within(self.band, &self.file.volume)
    }

    /// The field of `volume` derived from this one by `operation`, which moved the surface by
    /// up to `shift` from this field's (see [`operation_shift`]). Its header records the band
    /// within which its node values are exact distances: this field's (or, without a record,
    /// its largest node value) less `shift`, since the operation reads this field that much
    /// farther out. A sparse write keeps the bricks that band needs.
    pub(crate) fn derived(&self, volume: CoefficientVolume, operation: &str, shift: f32) -> Field {
        let mut header = pgvol_format::header_for(&volume, "interp", self.mesh.as_deref());
        header
            .metadata
            .insert("operation".into(), operation.to_string());
        let band = self
            .band
            .unwrap_or_else(|| pgvol_ops::stored_band(&self.file.volume))
            - shift.abs();
        if band.is_finite() && band > 0.0 {
            header.metadata.insert(BAND_KEY.into(), format!("{band}"));
        }
        let mut field = Field::from_file(PgvFile { header, volume });
        field.mesh = self.mesh.clone();
        field
    }

    /// The field of `volume` made by an edit (a Boolean, a repair) over its own grid, recording
    /// `operation` and the `band` within which its values are distances.
    pub(crate) fn edited(volume: CoefficientVolume, operation: &str, band: f32) -> Field {
        let mut header = pgvol_format::header_for(&volume, "interp", None);
        header
            .metadata
            .insert("operation".into(), operation.to_string());
        header.metadata.insert(BAND_KEY.into(), format!("{band}"));
        Field::from_file(PgvFile { header, volume })
    }
}

impl Field {
    /// Writes the field to `path` as a `.pgv` file, atomically (the replaced file's mode
    /// kept): sparse compressed bricks around the surface, or dense as `storage` asks.
    pub fn save(&self, path: impl AsRef<Path>, storage: &StorageOptions) -> Result<StorageReport> {
        crate::encode::write_pgv(path.as_ref(), &self.file, storage)
    }

    /// The bytes of the field's `.pgv` file; see [`Field::save`].
    pub fn to_bytes(&self, storage: &StorageOptions) -> Result<Vec<u8>> {
        Ok(crate::encode::pgv_bytes(&self.file, storage)?.bytes)
    }

    /// Writes the field's `.pgv` file to any writer; see [`Field::save`].
    pub fn write_to(&self, w: &mut dyn Write, storage: &StorageOptions) -> Result<StorageReport> {
        crate::encode::write_pgv_to(w, &self.file, storage)
    }
}

impl Field {
    /// Contours the `options.iso` level set into a mesh, refusing a level beyond the band where
    /// the field is an exact distance (there the level set would follow the clamp, not the
    /// shape). An empty level set is an error: it is never a useful mesh.
    pub fn to_mesh(
        &self,
        options: &crate::decode::DecodeOptions,
        progress: &dyn Progress,
    ) -> Result<Mesh> {
        if options.iso != 0.0 && options.iso.is_finite() {
            self.check_reach(options.iso)?;
        }
        let sharp = crate::sharp::cells_for(&self.file, options)?;
        crate::decode::decode_placing(&self.file.volume, options, sharp.as_ref(), progress)
    }
}

/// Refuses reaching `reach` from the surface of a field that is an exact distance only within
/// `band`, whose basis support reaches `support`, on `grid`. A reach beyond the grid's box
/// needs another grid, not a wider band.
pub(crate) fn check_reach_within(band: f32, support: f32, grid: &Grid, reach: f32) -> Result<()> {
    let across = grid.spacing * (grid.dims.iter().max().copied().unwrap_or(2) - 1) as f32;
    if reach.abs() >= band && reach.abs() >= across {
        return Err(Error::parameter(format!(
            "{} reaches beyond the field's grid, {} across: no band of this grid holds \
             distances that far; encode the mesh on a grid with that much room, or ask for less",
            figure(reach),
            figure(across)
        )));
    }
    if reach.abs() >= band {
        let needed = ((reach.abs() + support) / grid.spacing).ceil() + 1.0;
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

/// Where a shell's wall lies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShellKind {
    /// A wall of the given side.
    Wall(ShellSide),
    /// Keep the outer surface and cut a cavity inside (hollowing for printing).
    #[default]
    Hollow,
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

/// What [`Field::shell`] makes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShellOptions {
    /// The wall's thickness in model units (> 0).
    pub thickness: f32,
    /// Where the wall lies (default: hollowing).
    pub kind: ShellKind,
    /// Drain holes through the wall of a hollowed part, in world coordinates.
    pub drains: Vec<Drain>,
}

impl ShellOptions {
    /// How far outside the shape the result reaches, so that a grid laid over a mesh's box
    /// grown by it covers the result ([`OpenOptions::grow`]).
    pub fn growth(&self) -> f32 {
        match self.kind {
            ShellKind::Wall(ShellSide::Outer) => self.thickness,
            ShellKind::Wall(ShellSide::Centred) => self.thickness / 2.0,
            _ => 0.0,
        }
    }
}

impl Field {
    /// The shape grown (`distance` > 0) or shrunk by `distance`; refused when the field is not
    /// an exact distance that far out, or when the result breaks into far more pieces than the
    /// shape (see [`check_pieces`]).
    pub fn offset(&self, distance: f32) -> Result<Field> {
        check_offset(distance)?;
        self.check_reach(distance)?;
        let volume = pgvol_ops::offset(&self.file.volume, distance)?;
        check_pieces("the offset", &self.file.volume, &volume)?;
        let operation = operation_name(None, distance);
        Ok(self.derived(volume, &operation, operation_shift(None, distance)))
    }

    /// A wall of `options.thickness` around the surface, or the shape hollowed with drain
    /// holes. A wall thinner than the grid resolves is refused before the work (see
    /// [`check_wall`]), a result broken into far more pieces than the shape after it.
    pub fn shell(&self, options: &ShellOptions, progress: &dyn Progress) -> Result<Field> {
        let (thickness, kind) = (options.thickness, options.kind);
        check_thickness(thickness)?;
        if !options.drains.is_empty() && kind != ShellKind::Hollow {
            return Err(Error::parameter("drain holes apply to hollowing only"));
        }
        check_wall("the wall thickness", thickness, &self.file.volume.grid)?;
        self.check_reach(thickness)?;
        // Drain points are world coordinates; the field's are local.
        let drains: Vec<Drain> = options
            .drains
            .iter()
            .map(|d| Drain {
                point: self.to_local(&[d.point.as_dvec3()])[0],
                ..*d
            })
            .collect();
        if kind == ShellKind::Hollow {
            check_drains(self, thickness, &drains, progress)?;
        }
        let stored = self.file.volume.coeffs.stored_count() as u64;
        memory::check_memory(
            "the shell",
            stored.saturating_mul(memory::BYTES_PER_REMAP_BRICK),
            "lower the resolution",
        )?;
        let volume = &self.file.volume;
        let (volume, operation) = match kind {
            ShellKind::Hollow => (
                progress::stage(progress, "hollow", |update| {
                    pgvol_ops::hollow(volume, thickness, &drains, update)
                })??,
                "the hollowing",
            ),
            ShellKind::Wall(side) => (
                progress::stage(progress, "shell", |update| {
                    pgvol_ops::shell(volume, thickness, side, update)
                })??,
                "the shell",
            ),
        };
        check_pieces(operation, &self.file.volume, &volume)?;
        let name = operation_name(Some(kind), thickness);
        Ok(self.derived(volume, &name, operation_shift(Some(kind), thickness)))
    }

    /// The shape hollowed to walls of `thickness`, with `drains` cut through them: see
    /// [`Field::shell`].
    pub fn hollow(
        &self,
        thickness: f32,
        drains: &[Drain],
        progress: &dyn Progress,
    ) -> Result<Field> {
        let options = ShellOptions {
            thickness,
            kind: ShellKind::Hollow,
            drains: drains.to_vec(),
        };
        self.shell(&options, progress)
    }
}

/// Warns when hollowing an open mesh; refuses walls of `thickness` that leave no cavity, a
/// drain narrower than the grid resolves, and a drain whose point is not in the cavity (it
/// would open nothing).
pub(crate) fn check_drains(
    shape: &Field,
    thickness: f32,
    drains: &[Drain],
    progress: &dyn Progress,
) -> Result<()> {
    // The field is a convex combination of its coefficients, so none below −thickness means
    // no point deeper than the walls: the "hollowed" shape would be the solid unchanged.
    let [least, _] = shape.file.volume.coeffs.value_range();
    if least >= -thickness {
        return Err(Error::new(
            ErrorKind::EmptyResult,
            format!(
                "walls of {thickness} leave no cavity: the shape is nowhere more than {} inside \
                 its surface; a thinner wall would",
                figure(-least.min(0.0))
            ),
        ));
    }
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
        crate::resolution::check_hole(
            &format!("drain {}'s diameter", n + 1),
            drain.diameter,
            &shape.file.volume.grid,
        )?;
        // The hole runs from its point outward: a point outside the cavity opens nothing.
        let value = shape.file.volume.value(drain.point);
        if value >= -thickness {
            let p = pgvol_core::frame::to_world(drain.point, shape.file.volume.grid.offset);
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
fn operation_name(kind: Option<ShellKind>, amount: f32) -> String {
    match kind {
        None => format!("offset {amount}"),
        Some(ShellKind::Hollow) => format!("hollow {amount}"),
        Some(ShellKind::Wall(_)) => format!("shell {amount}"),
    }
}

/// How far from the shape's surface an offset (`kind` `None`, `amount` the distance), a shell
/// or a hollowing (`amount` the thickness) puts the result's surfaces, for
/// [`Field::derived`]: the distance, the thickness, half of it for a centred wall.
fn operation_shift(kind: Option<ShellKind>, amount: f32) -> f32 {
    match kind {
        Some(ShellKind::Wall(ShellSide::Centred)) => amount.abs() / 2.0,
        _ => amount.abs(),
    }
}
