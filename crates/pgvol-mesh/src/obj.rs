//! Wavefront OBJ via `tobj`: all objects and groups merged into one mesh, polygons fanned.

use std::io::{self, Write};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use glam::Vec3;

use crate::{Mesh, MeshError};

pub(crate) fn read(bytes: &[u8], name: &Path) -> Result<Mesh, MeshError> {
    if let Some(line) = short_face(bytes) {
        return Err(MeshError::new(
            name,
            format!("line {line}: a face ('f') with fewer than three vertices (a truncated file?)"),
        ));
    }
    // tobj's optional features add fields; the update keeps this compiling if one is enabled.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Materials are irrelevant to geometry, so every mtllib is answered with "not found".
    let load = || {
        tobj::load_obj_buf(&mut io::Cursor::new(bytes), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
    };
    // A third-party parser must not be able to take the process down on hostile input.
    let (models, _materials) = match catch_unwind(AssertUnwindSafe(load)) {
        Ok(Ok(loaded)) => loaded,
        Ok(Err(e)) => return Err(MeshError::new(name, describe(&e))),
        Err(_) => return Err(MeshError::new(name, "malformed OBJ (the parser gave up)")),
    };

    let mut mesh = Mesh::default();
    for model in &models {
        let m = &model.mesh;
        let base = u32::try_from(mesh.positions.len())
            .map_err(|_| MeshError::new(name, "more than 2^32 vertices"))?;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2])),
        );
        for t in m.indices.chunks_exact(3) {
            let tri = [t[0], t[1], t[2]].map(|i| i.checked_add(base));
            match tri {
                [Some(a), Some(b), Some(c)] => mesh.triangles.push([a, b, c]),
                _ => return Err(MeshError::new(name, "more than 2^32 vertices")),
            }
        }
    }
    Ok(mesh)
}

/// The number of the first `f` line naming fewer than three vertices, which the parser would
/// drop without a word.
fn short_face(bytes: &[u8]) -> Option<usize> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .find_map(|(i, line)| {
            let mut words = line
                .split(|b| b.is_ascii_whitespace())
                .filter(|w| !w.is_empty());
            (words.next() == Some(&b"f"[..]) && words.take_while(|w| w[0] != b'#').count() < 3)
                .then_some(i + 1)
        })
}

fn describe(e: &tobj::LoadError) -> String {
    use tobj::LoadError as E;
    match e {
        E::ReadError => "cannot read OBJ text (not UTF-8 or I/O failure)".into(),
        E::PositionParseError => "malformed vertex position ('v' line)".into(),
        E::NormalParseError => "malformed vertex normal ('vn' line)".into(),
        E::TexcoordParseError => "malformed texture coordinate ('vt' line)".into(),
        E::ColorParseError => "malformed vertex colour on a 'v' line".into(),
        E::FaceParseError => "malformed face ('f' line) or face index out of range".into(),
        E::InvalidPolygon => "face with fewer than three vertices".into(),
        E::FaceVertexOutOfBounds => "a face refers to a vertex the file does not have".into(),
        E::FaceTexCoordOutOfBounds => {
            "a face refers to a texture coordinate the file does not have".into()
        }
        E::FaceNormalOutOfBounds => "a face refers to a normal the file does not have".into(),
        E::FaceColorOutOfBounds => "a face refers to a vertex colour the file does not have".into(),
        E::ScalingByZeroError => "vertex with w = 0".into(),
        other => format!("invalid OBJ: {other}"),
    }
}

/// `v` and `vn` per vertex and `f a//a b//b c//c`; f32 `Display` is the shortest text that
/// parses back to the same value, so positions survive a round trip bit for bit.
pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, normals: &[Vec3]) -> io::Result<()> {
    writeln!(w, "# pgvol mesh")?;
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for n in normals {
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
    }
    Ok(())
}
