//! Format dispatch for reading and writing whole files.

use std::path::Path;

use crate::validate::problem;
use crate::{
    gltf_io, obj, output_normals, ply, stl, threemf, DeclaredUnit, Mesh, MeshError, MeshFormat,
    UnitChoice,
};
use pgvol_core::write_atomic;

/// Reads the mesh in `path`, choosing the format by extension, and validates it.
pub fn read(path: &Path) -> Result<Mesh, MeshError> {
    read_with_unit(path, UnitChoice::default()).map(|(mesh, _)| mesh)
}

/// [`read`], with the length unit the file declared (3MF only), the coordinates converted to
/// millimetres or kept as `choice` says.
pub(crate) fn read_with_unit(
    path: &Path,
    choice: UnitChoice,
) -> Result<(Mesh, Option<DeclaredUnit>), MeshError> {
    let format = MeshFormat::from_path(path)?;
    let bytes = pgvol_core::read_input(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    parse(&bytes, format, path, Some(dir), choice)
}

/// Parses a mesh held in memory. `name` is only used in error messages. A `.gltf` whose buffers
/// live in separate files cannot be read this way and yields an error saying so.
pub fn read_bytes(bytes: &[u8], format: MeshFormat, name: &Path) -> Result<Mesh, MeshError> {
    parse(bytes, format, name, None, UnitChoice::default()).map(|(mesh, _)| mesh)
}

/// [`read_bytes`], with the length unit the file declared (3MF only), as `choice` says.
pub(crate) fn read_bytes_with_unit(
    bytes: &[u8],
    format: MeshFormat,
    name: &Path,
    choice: UnitChoice,
) -> Result<(Mesh, Option<DeclaredUnit>), MeshError> {
    parse(bytes, format, name, None, choice)
}

fn parse(
    bytes: &[u8],
    format: MeshFormat,
    name: &Path,
    dir: Option<&Path>,
    choice: UnitChoice,
) -> Result<(Mesh, Option<DeclaredUnit>), MeshError> {
    if bytes.is_empty() {
        return Err(MeshError::new(name, "empty file"));
    }
    let mut unit = None;
    let mesh = match format {
        MeshFormat::Obj => obj::read(bytes, name)?,
        MeshFormat::Gltf => gltf_io::read(bytes, name, false, dir)?,
        MeshFormat::Glb => gltf_io::read(bytes, name, true, dir)?,
        MeshFormat::Stl => stl::read(bytes, name)?,
        MeshFormat::Ply => ply::read(bytes, name)?,
        MeshFormat::ThreeMf => {
            let (mesh, declared) = threemf::read(bytes, name, choice)?;
            unit = Some(declared);
            mesh
        }
    };
    match problem(&mesh, "file") {
        Some(p) => Err(MeshError::new(name, p)),
        None => Ok((mesh, unit)),
    }
}

/// Writes `mesh` to `path` in the format named by its extension, atomically, with unit
/// per-vertex normals (facet normals for STL).
pub fn write(path: &Path, mesh: &Mesh) -> Result<(), MeshError> {
    let format = MeshFormat::for_output(path)?;
    check_writable(mesh, format, path)?;
    write_atomic(path, |w| encode(w, mesh, format))
}

/// Writes `mesh` in `format` to any writer (a buffer, a socket); `name` labels errors. The same
/// checks as [`write`] come first, so nothing is written for a mesh that would be refused.
pub fn write_to(
    w: &mut dyn std::io::Write,
    mesh: &Mesh,
    format: MeshFormat,
    name: &Path,
) -> Result<(), MeshError> {
    check_writable(mesh, format, name)?;
    encode(w, mesh, format).map_err(|e| MeshError::new(name, format!("write failed: {e}")))
}

fn check_writable(mesh: &Mesh, format: MeshFormat, name: &Path) -> Result<(), MeshError> {
    if !format.writable() {
        return Err(MeshError::new(
            name,
            format!("meshes are not written as .{}", format.extension()),
        ));
    }
    if let Some(p) = problem(mesh, "mesh") {
        return Err(MeshError::new(name, format!("refusing to write: {p}")));
    }
    check_precision(mesh, format, name)
}

/// Refuses `format` for `mesh` when it cannot hold the mesh's positions: STL's f32 world
/// coordinates far from the origin. Every other writer keeps the frame offset in f64 (text,
/// doubles or a node translation). A mesh of the same frame and size (the input of a remesh,
/// say) gives the answer before any work.
pub fn check_precision(mesh: &Mesh, format: MeshFormat, name: &Path) -> Result<(), MeshError> {
    if format == MeshFormat::Stl {
        if let Some((step, relative)) = crate::f32_rounding_loss(mesh) {
            return Err(MeshError::new(
                name,
                format!(
                    "refusing to write: STL stores single-precision coordinates, which this \
                     far from the origin are rounded by up to {step:e} ({:.2} % of the mesh's \
                     size); write OBJ, GLB/glTF or PLY instead, which keep full precision",
                    relative * 100.0
                ),
            ));
        }
    }
    Ok(())
}

fn encode(w: &mut dyn std::io::Write, mesh: &Mesh, format: MeshFormat) -> std::io::Result<()> {
    let normals = match format {
        MeshFormat::Stl => std::borrow::Cow::Borrowed(&[][..]),
        _ => output_normals(mesh),
    };
    match format {
        MeshFormat::Obj => obj::write(w, mesh, &normals),
        MeshFormat::Gltf => gltf_io::write(w, mesh, &normals, false),
        MeshFormat::Glb => gltf_io::write(w, mesh, &normals, true),
        MeshFormat::Stl => stl::write(w, mesh),
        MeshFormat::Ply => ply::write(w, mesh, &normals),
        // Refused by `check_writable` before any byte is written.
        MeshFormat::ThreeMf => Err(std::io::Error::other("3MF meshes are not written")),
    }
}

/// Reads the vertices of a PLY file as a point cloud (faces, if any, are ignored), with their
/// normals when the vertices carry nx, ny and nz. Coordinates must be finite and below
/// [`MAX_COORDINATE`](crate::MAX_COORDINATE), normals finite.
pub fn read_ply_points(
    bytes: &[u8],
    name: &Path,
) -> Result<(Vec<glam::Vec3>, Option<Vec<glam::Vec3>>), MeshError> {
    if bytes.is_empty() {
        return Err(MeshError::new(name, "empty file"));
    }
    let (points, normals) = ply::read_points(bytes, name)?;
    if let Some(i) = points
        .iter()
        .position(|p| !(p.is_finite() && p.abs().max_element() < crate::MAX_COORDINATE))
    {
        return Err(MeshError::new(
            name,
            format!(
                "vertex {i}: coordinates must be finite and below {:e} in magnitude, got {}",
                crate::MAX_COORDINATE,
                points[i]
            ),
        ));
    }
    if let Some(i) = normals
        .as_ref()
        .and_then(|n| n.iter().position(|v| !v.is_finite()))
    {
        return Err(MeshError::new(
            name,
            format!("vertex {i}: the normal is not finite"),
        ));
    }
    Ok((points, normals))
}
