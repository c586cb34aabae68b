//! Meshes in and out: files by extension, or bytes and writers with the format given.

use std::io::Write;
use std::path::Path;

use pgvol_core::Mesh;
use pgvol_mesh::{CleanReport, MeshFormat};

use crate::error::{Error, FileResult, Result};

/// A mesh read and cleaned, with what the cleaning did.
#[derive(Clone, Debug)]
pub struct ReadMesh {
    /// The cleaned mesh.
    pub mesh: Mesh,
    /// Vertices welded and triangles dropped, and the length unit a 3MF file declared.
    pub cleaned: CleanReport,
}

impl From<(Mesh, CleanReport)> for ReadMesh {
    fn from((mesh, cleaned): (Mesh, CleanReport)) -> Self {
        ReadMesh { mesh, cleaned }
    }
}

/// Reads a mesh file (OBJ, glTF/GLB, STL, PLY, 3MF by extension), welds bit-identical vertices
/// and drops degenerate triangles; the report says how many of each, and the length unit a 3MF
/// file declared (its mesh comes in millimetres).
pub fn read_mesh(path: impl AsRef<Path>) -> Result<ReadMesh> {
    let path = path.as_ref();
    Ok(pgvol_mesh::read_clean(path).reading()?.into())
}

/// [`read_mesh`], with a 3MF file's coordinates converted to millimetres or kept in the unit
/// it declares, as `choice` says.
pub fn read_mesh_in(path: impl AsRef<Path>, choice: pgvol_mesh::UnitChoice) -> Result<ReadMesh> {
    let path = path.as_ref();
    Ok(pgvol_mesh::read_clean_in(path, choice).reading()?.into())
}

/// [`read_mesh`] on bytes already in memory; `name` labels errors.
pub fn read_mesh_bytes(
    bytes: &[u8],
    format: MeshFormat,
    name: impl AsRef<Path>,
) -> Result<ReadMesh> {
    let name = name.as_ref();
    Ok(pgvol_mesh::read_bytes_clean(bytes, format, name)
        .reading()?
        .into())
}

/// A mesh given as vertex positions and triangles in memory (by a binding, say), checked as a
/// mesh read from a file is (finite coordinates below 1e8, indices in range, an extent of at
/// least 1e-6) and cleaned as [`read_mesh`] cleans it. Problems are bad parameters.
pub fn mesh_from_parts(positions: Vec<glam::Vec3>, triangles: Vec<[u32; 3]>) -> Result<ReadMesh> {
    let world: Vec<glam::DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    mesh_from_world(&world, triangles)
}

/// [`mesh_from_parts`] from f64 world positions: a mesh far from the origin (more than
/// [`FAR_RATIO`](pgvol_core::frame::FAR_RATIO) times its size away) is recentred with its
/// offset kept in f64, so its precision follows its size.
pub fn mesh_from_world(positions: &[glam::DVec3], triangles: Vec<[u32; 3]>) -> Result<ReadMesh> {
    let mut mesh = Mesh::from_world(positions, triangles);
    if let Some(problem) = pgvol_mesh::mesh_problem(&mesh) {
        return Err(Error::parameter(format!("the mesh is unusable: {problem}")));
    }
    let report = pgvol_mesh::clean(&mut mesh, Path::new(""))
        .map_err(|e| Error::parameter(format!("the mesh is unusable: {}", e.problem)))?;
    Ok(ReadMesh {
        mesh,
        cleaned: report,
    })
}

/// The mesh format an output file name asks for, refused (as an output error) when there is
/// none or it is only read (3MF).
pub fn mesh_format(path: impl AsRef<Path>) -> Result<MeshFormat> {
    let path = path.as_ref();
    MeshFormat::for_output(path).writing()
}

/// Refuses, before the work, an output `path` whose format cannot hold a mesh in `like`'s frame
/// and of its size (STL far from the origin), as writing the result would.
pub fn check_mesh_output(path: impl AsRef<Path>, like: &Mesh) -> Result<()> {
    let path = path.as_ref();
    let format = mesh_format(path)?;
    pgvol_mesh::check_precision(like, format, path).writing()
}

/// Writes `mesh` to `path` atomically in the format of its extension.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &Mesh) -> Result<()> {
    let path = path.as_ref();
    pgvol_mesh::write(path, mesh).writing()
}

/// Writes `mesh` in `format` to `w`; `name` labels errors.
pub fn write_mesh_to(
    w: &mut dyn Write,
    mesh: &Mesh,
    format: MeshFormat,
    name: impl AsRef<Path>,
) -> Result<()> {
    let name = name.as_ref();
    pgvol_mesh::write_to(w, mesh, format, name).writing()
}
