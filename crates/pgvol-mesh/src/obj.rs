//! Wavefront OBJ via `tobj`: all objects and groups merged into one mesh; polygons fanned, or
//! split in halves when large.

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
        triangulate: false,
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
        let mut corners = Vec::new();
        let mut at = 0usize;
        let arities = (!m.face_arities.is_empty())
            .then_some(&m.face_arities)
            .into_iter()
            .flatten()
            .map(|&k| k as usize);
        let all_triangles = std::iter::repeat_n(3, m.indices.len() / 3);
        let faces: Box<dyn Iterator<Item = usize>> = if m.face_arities.is_empty() {
            Box::new(all_triangles)
        } else {
            Box::new(arities)
        };
        for k in faces {
            let Some(face) = m.indices.get(at..at + k) else {
                return Err(MeshError::new(name, "malformed face list"));
            };
            at += k;
            corners.clear();
            for &i in face {
                corners.push(
                    i.checked_add(base)
                        .ok_or_else(|| MeshError::new(name, "more than 2^32 vertices"))?,
                );
            }
            triangulate(&corners, &mut mesh.triangles);
        }
    }
    Ok(mesh)
}

/// Polygons up to this many corners are fanned from their first corner, as OBJ readers do.
const FAN_LIMIT: usize = 32;

/// Triangles of one polygon, in its order (so its orientation). A fan of a large polygon is a
/// sheaf of needles, each spanning the polygon, which every distance query near it must visit
/// (a 50,000-sided cap took minutes); split in halves instead, the triangles shrink by half at
/// each level and a point meets a few dozen. Both are exact for convex polygons.
fn triangulate(corners: &[u32], out: &mut Vec<[u32; 3]>) {
    let k = corners.len();
    if k < 3 {
        return;
    }
    if k <= FAN_LIMIT {
        for i in 1..k - 1 {
            out.push([corners[0], corners[i], corners[i + 1]]);
        }
        return;
    }
    // Ranges of corners closed by the chord from their last back to their first.
    let mut ranges = vec![(0usize, k - 1)];
    while let Some((lo, hi)) = ranges.pop() {
        if hi - lo < 2 {
            continue;
        }
        let mid = (lo + hi) / 2;
        out.push([corners[lo], corners[mid], corners[hi]]);
        ranges.push((mid, hi));
        ranges.push((lo, mid));
    }
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
