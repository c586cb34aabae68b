//! 3MF (3D Manufacturing Format) input: a zip package whose start part, found through
//! `_rels/.rels`, holds objects (meshes, or components placing other objects) and a build that
//! places objects. The build is read as one mesh in millimetres: every build item's object with
//! its component and item transforms applied, objects in other model parts followed through the
//! production extension's `p:path`. Objects of a type other than `model` (supports, surfaces,
//! other) are left out. See `docs/interop.md`, "3MF input".

mod assemble;
mod limits;
mod model;
mod package;
mod text;
mod transform;
mod unit;

use std::path::Path;

use crate::{Mesh, MeshError};
pub(crate) use limits::Limits;
use package::Package;
pub use unit::{DeclaredUnit, LengthUnit, UnitChoice};

/// Reads the 3MF package `bytes` (named `name` in errors) as one mesh, in millimetres or in the
/// unit its model declared, and that unit.
pub(crate) fn read(
    bytes: &[u8],
    name: &Path,
    choice: UnitChoice,
) -> Result<(Mesh, DeclaredUnit), MeshError> {
    read_with(bytes, name, choice, &Limits::DEFAULT)
}

pub(crate) fn read_with(
    bytes: &[u8],
    name: &Path,
    choice: UnitChoice,
    limits: &Limits,
) -> Result<(Mesh, DeclaredUnit), MeshError> {
    let fail = |problem: String| MeshError::new(name, problem);
    let mut package = Package::open(bytes, *limits).map_err(fail)?;
    let root = package.start_part().map_err(fail)?;
    let parts = load_parts(&mut package, &root, limits).map_err(fail)?;
    let declared = DeclaredUnit {
        unit: parts[&root].unit,
        converted: choice == UnitChoice::Millimetres,
    };
    let placed = assemble::place(&parts, &root, limits).map_err(fail)?;
    let scale = declared.scale();
    let world: Vec<_> = placed.positions.iter().map(|&p| p * scale).collect();
    Ok((Mesh::from_world(&world, placed.triangles), declared))
}

/// Parses the start part and every model part its references name (production extension
/// `p:path`), each once. Paths in the parsed references are made absolute part names.
fn load_parts(
    package: &mut Package,
    root: &str,
    limits: &Limits,
) -> Result<assemble::Parts, String> {
    let mut parts = assemble::Parts::new();
    let mut pending = vec![root.to_string()];
    while let Some(part) = pending.pop() {
        if parts.contains_key(&part) {
            continue;
        }
        let xml = package.read_part(&part)?;
        let mut model = model::parse(&xml, limits).map_err(|e| format!("part {part}: {e}"))?;
        let references = model.build.iter_mut().chain(
            model
                .objects
                .values_mut()
                .filter_map(|o| match &mut o.content {
                    model::Content::Components(list) => Some(list.iter_mut()),
                    _ => None,
                })
                .flatten(),
        );
        for r in references {
            if let Some(path) = &mut r.path {
                *path = package::resolve(&part, path);
                if !parts.contains_key(path.as_str()) && *path != part {
                    pending.push(path.clone());
                }
            }
        }
        parts.insert(part, model);
    }
    Ok(parts)
}

#[cfg(test)]
mod tests;
