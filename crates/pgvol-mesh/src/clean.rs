//! Reading with the repairs that make soup-like input (STL, per-face vertices) usable: bit-exact
//! welding and dropping zero-area triangles (the repairs themselves are `Mesh` methods).

use std::path::Path;

use crate::io::{read_bytes_with_unit, read_with_unit};
use crate::{DeclaredUnit, Mesh, MeshError, MeshFormat, UnitChoice};

/// What [`read_clean`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CleanReport {
    pub vertices_merged: usize,
    pub degenerate_dropped: usize,
    /// Triangles repeating an earlier one's vertices.
    pub duplicates_dropped: usize,
    /// The length unit the file declared and whether its coordinates were converted to
    /// millimetres (3MF; other formats declare none and are read as they are).
    pub unit: Option<DeclaredUnit>,
}

/// Reads `path`, welds bit-identical vertices and drops degenerate and repeated triangles.
pub fn read_clean(path: &Path) -> Result<(Mesh, CleanReport), MeshError> {
    read_clean_in(path, UnitChoice::default())
}

/// [`read_clean`] with the coordinates of a file that declares a length unit (3MF) converted to
/// millimetres or kept as declared, as `choice` says.
pub fn read_clean_in(path: &Path, choice: UnitChoice) -> Result<(Mesh, CleanReport), MeshError> {
    let (mut mesh, unit) = read_with_unit(path, choice)?;
    let report = clean(&mut mesh, path)?;
    Ok((mesh, CleanReport { unit, ..report }))
}

/// [`read_clean`] on bytes already in memory, in `format`; `name` labels errors.
pub fn read_bytes_clean(
    bytes: &[u8],
    format: MeshFormat,
    name: &Path,
) -> Result<(Mesh, CleanReport), MeshError> {
    let (mut mesh, unit) = read_bytes_with_unit(bytes, format, name, UnitChoice::default())?;
    let report = clean(&mut mesh, name)?;
    Ok((mesh, CleanReport { unit, ..report }))
}

/// Welds bit-identical vertices of `mesh` and drops its degenerate and repeated triangles,
/// refusing a mesh with none left; `name` labels the error.
pub fn clean(mesh: &mut Mesh, name: &Path) -> Result<CleanReport, MeshError> {
    let vertices_merged = mesh.weld(0.0);
    let degenerate_dropped = mesh.drop_degenerate();
    let duplicates_dropped = mesh.drop_duplicate_triangles();
    if mesh.triangles.is_empty() {
        return Err(MeshError::new(
            name,
            format!("no triangles left after dropping {degenerate_dropped} degenerate triangles"),
        ));
    }
    Ok(CleanReport {
        vertices_merged,
        degenerate_dropped,
        duplicates_dropped,
        unit: None,
    })
}
