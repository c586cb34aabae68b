//! A field as NRRD (its coefficients, or the field sampled), as a 3MF level set or as an
//! OpenVDB level set.

use std::path::Path;

use pgvol_core::Grid;
use pgvol_format::PgvFile;

use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::field_value::Field;
pub use crate::vdb_export::VDB_BAND;
pub use pgvol_format::vdb::write::VdbCompression;

/// Export targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportKind {
    /// The coefficient grid with the basis in key/value fields; reads back bit-exactly.
    CoefficientsNrrd,
    /// The signed distance sampled on a grid, as NRRD.
    SdfNrrd,
    /// The signed distance sampled on a grid, as NumPy `.npy` (float32, shape (nz, ny, nx)).
    SdfNpy,
    /// The sampled field as a 3MF Volumetric level set (16-bit PNG image stack).
    ThreeMf,
    /// The narrow band of the sampled field as an OpenVDB FloatGrid level set (`.vdb`).
    Vdb,
}

impl ExportKind {
    /// The target of `path`'s extension; `coefficients` asks for the coefficients (NRRD only).
    pub fn from_path(path: impl AsRef<Path>, coefficients: bool) -> Result<ExportKind> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match (ext.as_deref(), coefficients) {
            (Some("nrrd"), true) => Ok(ExportKind::CoefficientsNrrd),
            (Some("nrrd"), false) => Ok(ExportKind::SdfNrrd),
            (Some("npy"), false) => Ok(ExportKind::SdfNpy),
            (Some("3mf"), false) => Ok(ExportKind::ThreeMf),
            (Some("vdb"), false) => Ok(ExportKind::Vdb),
            (Some("3mf" | "npy" | "vdb"), true) => Err(Error::parameter(
                "coefficients export to .nrrd only; .3mf, .npy and .vdb hold the sampled field",
            )
            .at(path)),
            _ => Err(Error::new(
                ErrorKind::OutputFile,
                "expected a .nrrd, .npy, .3mf or .vdb file name",
            )
            .at(path)),
        }
    }
}

/// The units a 3MF package may name (3MF core specification, `model@unit`).
pub const THREEMF_UNITS: [&str; 6] = [
    "micron",
    "millimeter",
    "centimeter",
    "inch",
    "foot",
    "meter",
];

/// The unit named in 3MF packages unless told otherwise: pgvol keeps the mesh's units, which
/// for printing are most often millimetres.
pub const THREEMF_UNIT: &str = "millimeter";

/// How [`Field::export`] writes a field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExportOptions<'a> {
    /// The target; `None` (the default) picks the sampled field in the format of the path's
    /// extension (.nrrd, .npy, .3mf or .vdb).
    pub kind: Option<ExportKind>,
    /// Sample on this many nodes along the longest side; `None` (the default) samples the
    /// stored grid. Not for coefficients.
    pub res: Option<usize>,
    /// The unit a 3MF package names, one of [`THREEMF_UNITS`] (default [`THREEMF_UNIT`]).
    pub unit: &'a str,
    /// A `.vdb`'s narrow band half-width in voxels: nodes nearer the surface are active, the
    /// others hold ±band·spacing (default [`VDB_BAND`]).
    pub band: f32,
    /// Store a `.vdb`'s values as 16-bit floats (default false).
    pub half: bool,
    /// How a `.vdb`'s value chunks are stored (default zlib).
    pub compression: VdbCompression,
}

impl Default for ExportOptions<'_> {
    fn default() -> Self {
        ExportOptions {
            kind: None,
            res: None,
            unit: THREEMF_UNIT,
            band: VDB_BAND,
            half: false,
            compression: VdbCompression::Zip,
        }
    }
}

impl Field {
    /// Writes the field to `path` for other tools as `options` say; returns the grid written.
    pub fn export(&self, path: impl AsRef<Path>, options: &ExportOptions) -> Result<Grid> {
        let path = path.as_ref();
        export(path, &self.file, options)
    }
}

/// Refuses a unit 3MF does not name.
pub(crate) fn check_unit(unit: &str) -> Result<()> {
    if !THREEMF_UNITS.contains(&unit) {
        return Err(Error::parameter(format!(
            "3MF has no unit '{unit}' (it knows {})",
            THREEMF_UNITS.join(", ")
        )));
    }
    Ok(())
}

/// Writes `file` to `path` as `options` say: `options.kind` (by default from the path's
/// extension), sampled on `options.res` nodes along the longest side (`None`: the stored grid;
/// not for coefficients); a 3MF package names `options.unit` (one of [`THREEMF_UNITS`]).
/// Returns the grid written.
pub fn export(path: impl AsRef<Path>, file: &PgvFile, options: &ExportOptions) -> Result<Grid> {
    let path = path.as_ref();
    let kind = match options.kind {
        Some(kind) => kind,
        None => ExportKind::from_path(path, false)?,
    };
    let (res, unit) = (options.res, options.unit);
    if kind == ExportKind::ThreeMf {
        check_unit(unit)?;
    }
    let volume = &file.volume;
    if kind == ExportKind::CoefficientsNrrd {
        if res.is_some() {
            return Err(Error::parameter(
                "resampling applies to the sampled field, not to the coefficients",
            ));
        }
        pgvol_format::nrrd::write_coefficients_nrrd(path, file).writing()?;
        return Ok(volume.grid);
    }
    let grid = crate::decode::target_grid(volume, res)?;
    if kind == ExportKind::Vdb {
        // Only the band is sampled, leaf by leaf: no dense array.
        let recorded = crate::band::recorded_band(file);
        crate::vdb_export::write_vdb(
            path,
            volume,
            &grid,
            options.band,
            recorded,
            options.half,
            options.compression,
        )?;
        return Ok(grid);
    }
    crate::memory::check_grid("sampling", &grid, crate::memory::BYTES_PER_SDF_NODE)?;
    let values = volume.sample(&grid);
    match kind {
        ExportKind::SdfNrrd => {
            pgvol_format::nrrd::write_field_nrrd(path, &grid, &values, volume.basis).writing()?
        }
        ExportKind::SdfNpy => {
            pgvol_format::grid_files::write_npy(path, &grid, &values).writing()?
        }
        _ => pgvol_format::threemf::write_3mf(path, &grid, &values, unit).writing()?,
    }
    Ok(grid)
}
