//! File formats and their recognition from a path's extension.

use std::path::Path;

use crate::MeshError;

/// The mesh file formats this crate reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    Obj,
    Gltf,
    Glb,
    Stl,
    Ply,
    /// 3MF packages: read only (the build as one mesh, in millimetres unless asked otherwise).
    ThreeMf,
}

impl MeshFormat {
    /// The format named by the extension of `path`, ignoring case.
    pub fn from_path(path: &Path) -> Result<MeshFormat, MeshError> {
        Self::named(path, "(expected .obj, .gltf, .glb, .stl, .ply, .3mf)")
    }

    /// [`MeshFormat::from_path`], naming the `expected` extensions when there is none.
    fn named(path: &Path, expected: &str) -> Result<MeshFormat, MeshError> {
        let Some(ext) = path.extension() else {
            return Err(MeshError::new(
                path,
                format!("no file extension {expected}"),
            ));
        };
        let ext = ext.to_string_lossy();
        match ext.to_ascii_lowercase().as_str() {
            "obj" => Ok(MeshFormat::Obj),
            "gltf" => Ok(MeshFormat::Gltf),
            "glb" => Ok(MeshFormat::Glb),
            "stl" => Ok(MeshFormat::Stl),
            "ply" => Ok(MeshFormat::Ply),
            "3mf" => Ok(MeshFormat::ThreeMf),
            _ => Err(MeshError::new(
                path,
                format!("unknown extension '.{ext}' {expected}"),
            )),
        }
    }

    /// Conventional lower-case extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Gltf => "gltf",
            MeshFormat::Glb => "glb",
            MeshFormat::Stl => "stl",
            MeshFormat::Ply => "ply",
            MeshFormat::ThreeMf => "3mf",
        }
    }

    /// Whether meshes can be written in this format (3MF is read only).
    pub fn writable(self) -> bool {
        self != MeshFormat::ThreeMf
    }

    /// The format of an output file named `path`: as [`MeshFormat::from_path`], refusing the
    /// formats that are only read.
    pub fn for_output(path: &Path) -> Result<MeshFormat, MeshError> {
        let format = MeshFormat::named(path, "(expected .obj, .gltf, .glb, .stl, .ply)")?;
        if !format.writable() {
            return Err(MeshError::new(
                path,
                "3MF meshes are read but not written (write .obj, .gltf, .glb, .stl or .ply; \
                 a field is exported to 3MF as a level set instead)",
            ));
        }
        Ok(format)
    }
}
