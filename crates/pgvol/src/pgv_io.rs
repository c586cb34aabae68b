//! Reading `.pgv` files from paths, bytes or readers.

use std::io::Read;
use std::path::Path;

use pgvol_format::{PgvFile, PgvHeader, PgvInfo};
use pgvol_perturb::PerturbationField;

use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::progress::{Progress, Silent};

/// What a `.pgv` file holds: a coefficient volume, or a perturbation field's function list
/// (`docs/perturbation.md`).
#[derive(Clone, Debug)]
pub enum FieldSource {
    /// A coefficient volume (`dense-f32` or `sparse-bricks`).
    Volume(PgvFile),
    /// A function list (`perturbation-f64`).
    Perturbation {
        /// The list's header: `grid` and `basis` say where it is resampled.
        header: PgvHeader,
        /// The base quadric and its perturbations.
        field: PerturbationField,
    },
}

impl FieldSource {
    /// The file's header.
    pub fn header(&self) -> &PgvHeader {
        match self {
            FieldSource::Volume(f) => &f.header,
            FieldSource::Perturbation { header, .. } => header,
        }
    }

    /// A coefficient volume of the field: the volume itself, or the perturbation field
    /// resampled onto the sparse band of its header's grid ([`crate::resample_onto`]), which is
    /// how `decode`, `slice`, `eval` and `offset` contour and measure it. The returned header
    /// is the list's (encoding `perturbation-f64`), so reports say what the file holds.
    pub fn into_file(self, progress: &dyn Progress) -> Result<PgvFile> {
        match self {
            FieldSource::Volume(f) => Ok(f),
            FieldSource::Perturbation { header, field } => {
                let mut file = crate::perturb::resample_onto(&field, &header, progress)?;
                file.header = header;
                Ok(file)
            }
        }
    }
}

/// Reads and checks a `.pgv` file of either kind.
pub fn read_field_source(path: impl AsRef<Path>) -> Result<FieldSource> {
    let path = path.as_ref();
    let bytes = pgvol_core::read_input(path).reading()?;
    read_field_source_bytes(&bytes, path)
}

/// Decodes and checks the bytes of a `.pgv` file of either kind; `name` labels errors. The
/// grid the header declares is checked against the memory limit before any coefficient is
/// allocated.
pub fn read_field_source_bytes(bytes: &[u8], name: impl AsRef<Path>) -> Result<FieldSource> {
    let name = name.as_ref();
    let info = pgv_info(bytes, name)?;
    if pgvol_format::is_perturbation(&info.header) {
        crate::memory::check_grid("resampling the perturbation field", &info.header.grid, 4)
            .map_err(|e| e.at(name))?;
        let (header, field) = pgvol_format::decode_perturbation(bytes, name).reading()?;
        return Ok(FieldSource::Perturbation { header, field });
    }
    let [nx, ny, nz] = info.header.grid.dims;
    crate::memory::check_memory(
        &format!("reading its {nx} x {ny} x {nz} coefficients"),
        read_bytes(&info),
        "the file declares a larger grid than this machine can hold",
    )
    .map_err(|e| e.at(name))?;
    pgvol_format::decode_pgv(bytes, name)
        .reading()
        .map(FieldSource::Volume)
}

/// Reads and checks a `.pgv` file as a coefficient volume (a perturbation field resampled, see
/// [`FieldSource::into_file`]).
pub fn read_pgv(path: impl AsRef<Path>) -> Result<PgvFile> {
    let path = path.as_ref();
    let bytes = pgvol_core::read_input(path).reading()?;
    read_pgv_bytes(&bytes, path)
}

/// Decodes and checks the bytes of a `.pgv` file as a coefficient volume; `name` labels errors.
pub fn read_pgv_bytes(bytes: &[u8], name: impl AsRef<Path>) -> Result<PgvFile> {
    let name = name.as_ref();
    read_field_source_bytes(bytes, name)?
        .into_file(&Silent)
        .map_err(|e| match e.path() {
            Some(_) => e,
            None => e.at(name),
        })
}

/// Memory to hold a file's coefficients: its stored bricks (a sparse file in bricks the grid's
/// bricks tile) or every node twice (read whole, then cut into bricks).
fn read_bytes(info: &PgvInfo) -> u64 {
    let [nx, ny, nz] = info.header.grid.dims;
    let nodes = nx.saturating_mul(ny).saturating_mul(nz);
    match (&info.header.sparse, info.bricks_stored) {
        (Some(sp), Some(stored)) if sp.brick % pgvol_core::BRICK_EDGE == 0 => {
            (stored as u64).saturating_mul((sp.brick as u64).pow(3) * 4)
        }
        _ => crate::memory::grid_bytes(nodes, 8),
    }
}

/// Reads a `.pgv` file from any reader to its end; `name` labels errors.
pub fn read_pgv_from(r: &mut dyn Read, name: impl AsRef<Path>) -> Result<PgvFile> {
    let name = name.as_ref();
    let mut bytes = Vec::new();
    r.read_to_end(&mut bytes).map_err(|e| {
        Error::new(ErrorKind::InputFile, format!("cannot read: {e}"))
            .at(name)
            .caused_by(e)
    })?;
    read_pgv_bytes(&bytes, name)
}

/// What a file holds and how its bytes divide, without decoding the coefficients.
pub fn pgv_info(bytes: &[u8], name: impl AsRef<Path>) -> Result<PgvInfo> {
    let name = name.as_ref();
    pgvol_format::pgv_info(bytes, name).reading()
}
