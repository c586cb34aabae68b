//! Wavefront OBJ via `tobj`: all objects and groups merged into one mesh; polygons fanned, or
//! split in halves when large; polylines (`l`) and points ignored.

use std::borrow::Cow;
use std::io::{self, Write};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use glam::{DVec3, Vec3};

use crate::chunks::write_records;
use crate::{Mesh, MeshError};

pub(crate) fn read(bytes: &[u8], name: &Path) -> Result<Mesh, MeshError> {
    let bytes = check_lines(bytes).map_err(|problem| MeshError::new(name, problem))?;
    let bytes = &bytes[..];
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
        Ok(Err(e)) => {
            let line = match e {
                tobj::LoadError::PositionParseError => first_bad_line(bytes, "v", 3),
                tobj::LoadError::NormalParseError => first_bad_line(bytes, "vn", 3),
                tobj::LoadError::TexcoordParseError => first_bad_line(bytes, "vt", 1),
                _ => None,
            };
            let at = line.map_or(String::new(), |n| format!(" on line {n}"));
            return Err(MeshError::new(name, format!("{}{at}", describe(&e))));
        }
        Err(_) => return Err(MeshError::new(name, "malformed OBJ (the parser gave up)")),
    };

    let mut world = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let base = u32::try_from(world.len())
            .map_err(|_| MeshError::new(name, "more than 2^32 vertices"))?;
        world.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2])),
        );
        // Reserved, not grown by doubling: the list lives as long as the mesh, and its spare
        // capacity would too (10 MB of 25 for a mesh of 1.3 M triangles).
        let model_triangles = if m.face_arities.is_empty() {
            m.indices.len() / 3
        } else {
            m.face_arities
                .iter()
                .map(|&k| (k as usize).saturating_sub(2))
                .sum()
        };
        triangles.reserve_exact(model_triangles);
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
            triangulate(&corners, &mut triangles);
        }
    }
    Ok(Mesh::from_world(&world, triangles))
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

/// Checks the `f` lines before the parser sees them, split as it splits them (at Unicode
/// whitespace, up to the first line that is not UTF-8, where it stops), and hides the `l` lines
/// it would misread. Refused, with the number of the line:
/// - a face naming fewer than three vertices, which the parser would drop without a word;
/// - a corner index of 0, one counting back past the first element, or one too large for any
///   file this size: the parser scales texture-coordinate and normal indices without overflow
///   checks, so such an index could read another element or take it down.
///
/// A polyline (`l`) of three or more points would be read as a face, so those lines are turned
/// into comments in a copy (the bytes themselves when there is none).
fn check_lines(bytes: &[u8]) -> Result<Cow<'_, [u8]>, String> {
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let mut counts = [0usize; 3];
    let mut polylines = Vec::new();
    let mut start = 0;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let at = start;
        start += raw.len() + 1;
        let Ok(line) = std::str::from_utf8(raw) else {
            break;
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("l") if words.clone().count() >= 3 => {
                polylines.push(at + line.len() - line.trim_start().len());
            }
            Some("f") => {
                let corners = words.take_while(|w| !w.starts_with('#'));
                if corners.clone().count() < 3 {
                    return Err(format!(
                        "line {}: a face ('f') with fewer than three vertices (a truncated file?)",
                        i + 1
                    ));
                }
                for corner in corners {
                    for (k, part) in corner.split('/').enumerate().take(3) {
                        let Ok(index) = part.parse::<isize>() else {
                            continue;
                        };
                        let (kind, back) = (KINDS[k], index.unsigned_abs());
                        let problem = if index == 0 {
                            format!("{kind} index 0 (OBJ indices count from 1)")
                        } else if index < 0 && back > counts[k] {
                            format!("{kind} {index}, but only {} precede it", counts[k])
                        } else if index > 0 && back > bytes.len() {
                            format!("{kind} {index}, which the file does not have")
                        } else {
                            continue;
                        };
                        return Err(format!(
                            "line {}: face corner '{corner}' refers to {problem}",
                            i + 1
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    if polylines.is_empty() {
        return Ok(Cow::Borrowed(bytes));
    }
    let mut copy = bytes.to_vec();
    for at in polylines {
        copy[at] = b'#';
    }
    Ok(Cow::Owned(copy))
}

/// The first line (counted from 1) of `bytes` that starts with the keyword `key` and is not
/// followed by at least `least` numbers, for naming the line a parser refused.
fn first_bad_line(bytes: &[u8], key: &str, least: usize) -> Option<usize> {
    let text = String::from_utf8_lossy(bytes);
    text.lines().enumerate().find_map(|(n, line)| {
        let mut words = line.split_whitespace();
        if words.next() != Some(key) {
            return None;
        }
        let numbers: Vec<Option<f32>> = words.map(|w| w.parse().ok()).collect();
        (numbers.len() < least || numbers.iter().any(Option::is_none)).then_some(n + 1)
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
/// parses back to the same value, so positions survive a round trip bit for bit. A mesh with
/// a frame offset gets its world positions, offset added in f64 and written as f64.
pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, normals: &[Vec3]) -> io::Result<()> {
    writeln!(w, "# pgvol mesh")?;
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    )?;
    // Text formatting is most of the cost: lines are formatted in parallel chunks.
    let far = mesh.offset != DVec3::ZERO;
    write_records(w, mesh.positions.len(), |range, out| {
        for i in range {
            // Writing to a Vec cannot fail.
            let _ = if far {
                let p = mesh.world(i);
                writeln!(out, "v {} {} {}", p.x, p.y, p.z)
            } else {
                let p = mesh.positions[i];
                writeln!(out, "v {} {} {}", p.x, p.y, p.z)
            };
        }
    })?;
    write_records(w, normals.len(), |range, out| {
        for n in &normals[range] {
            let _ = writeln!(out, "vn {} {} {}", n.x, n.y, n.z);
        }
    })?;
    write_records(w, mesh.triangles.len(), |range, out| {
        for t in &mesh.triangles[range] {
            let [a, b, c] = t.map(|i| u64::from(i) + 1);
            let _ = writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}");
        }
    })?;
    Ok(())
}
