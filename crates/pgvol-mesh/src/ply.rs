//! PLY (ascii, binary_little_endian, binary_big_endian). Only `vertex` x/y/z and the `face`
//! index list are kept; every other element and property is parsed past and dropped. The body
//! must be exactly what the header declares: a binary header over text, or data after the last
//! element, is refused.

use std::io::{self, Write};
use std::path::Path;

use glam::{DVec3, Vec3};

use crate::chunks::write_records;
use crate::{Mesh, MeshError};

#[derive(Clone, Copy, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    body_start: usize,
}

/// A reader of the body's values in the file's encoding.
fn body_values(encoding: Encoding, body: &[u8]) -> Box<dyn Values + '_> {
    match encoding {
        Encoding::Ascii => Box::new(AsciiValues { body, pos: 0 }),
        enc => Box::new(BinaryValues {
            body,
            pos: 0,
            big_endian: enc == Encoding::BigEndian,
        }),
    }
}

/// The header and the body after it, checked to be in the encoding the header states.
fn split(bytes: &[u8]) -> Result<(Header, &[u8]), String> {
    let header = parse_header(bytes)?;
    let body = &bytes[header.body_start..];
    if header.encoding != Encoding::Ascii && looks_like_text(body) {
        // Read as binary, the digits' bytes would make a few tiny numbers and no error.
        let format = match header.encoding {
            Encoding::BigEndian => "binary_big_endian",
            _ => "binary_little_endian",
        };
        return Err(format!(
            "the header says 'format {format}' but the data after 'end_header' is ASCII \
             text; for text data the format line must be 'format ascii 1.0'"
        ));
    }
    Ok((header, body))
}

/// Only digits, signs, points, exponents and whitespace, with at least one digit and one
/// separator: numbers written as text. Binary coordinates almost always hold other bytes.
fn looks_like_text(body: &[u8]) -> bool {
    body.iter().any(u8::is_ascii_digit)
        && body.iter().any(u8::is_ascii_whitespace)
        && body
            .iter()
            .all(|&b| b.is_ascii_digit() || b.is_ascii_whitespace() || b"+-.eE".contains(&b))
}

/// Refuses data after the last declared element: the header's counts or types do not match
/// the body, so what was read is not what the file holds.
fn check_end(values: &dyn Values, elements: &[Element]) -> Result<(), String> {
    let Some(left) = values.leftover() else {
        return Ok(());
    };
    let declared: Vec<String> = elements
        .iter()
        .map(|e| format!("{} {}", e.count, e.name))
        .collect();
    Err(format!(
        "{left} after the last element the header declares ({}); the header's element counts \
         and property types must describe the data exactly",
        declared.join(", ")
    ))
}

pub(crate) fn read(bytes: &[u8], name: &Path) -> Result<Mesh, MeshError> {
    let err = |problem: String| MeshError::new(name, problem);
    let (header, body) = split(bytes).map_err(err)?;
    let mut values = body_values(header.encoding, body);

    let (mut world, mut triangles) = (Vec::new(), Vec::new());
    let mut saw_vertices = false;
    for element in &header.elements {
        let result = match element.name.as_str() {
            "vertex" if !saw_vertices => {
                saw_vertices = true;
                read_vertices(element, values.as_mut(), body.len(), &mut world, None)
            }
            "face" => read_faces(element, values.as_mut(), &mut triangles),
            _ => skip(element, values.as_mut()),
        };
        result.map_err(err)?;
    }
    if !saw_vertices {
        return Err(err("PLY header declares no 'vertex' element".into()));
    }
    check_end(values.as_ref(), &header.elements).map_err(err)?;
    Ok(Mesh::from_world(&world, triangles))
}

/// The `vertex` element of a PLY file as points, with their normals when it has nx, ny, nz;
/// faces and other elements are skipped.
pub(crate) fn read_points(
    bytes: &[u8],
    name: &Path,
) -> Result<(Vec<Vec3>, Option<Vec<Vec3>>), MeshError> {
    let err = |problem: String| MeshError::new(name, problem);
    let (header, body) = split(bytes).map_err(err)?;
    let mut values = body_values(header.encoding, body);
    let (mut points, mut normals) = (Vec::new(), Vec::new());
    let mut saw_vertices = false;
    for element in &header.elements {
        let result = if element.name == "vertex" && !saw_vertices {
            saw_vertices = true;
            let normals = Some(&mut normals);
            read_vertices(element, values.as_mut(), body.len(), &mut points, normals)
        } else {
            // Faces and other elements are not needed, but are parsed past to check the end.
            skip(element, values.as_mut())
        };
        result.map_err(err)?;
    }
    check_end(values.as_ref(), &header.elements).map_err(err)?;
    if points.is_empty() {
        return Err(err("PLY file has no vertices to read as points".into()));
    }
    let points: Vec<Vec3> = points.iter().map(|p: &DVec3| p.as_vec3()).collect();
    let normals = (normals.len() == points.len()).then_some(normals);
    Ok((points, normals))
}

fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut first = true;
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(if first {
                "not a PLY file (first line is not 'ply')".into()
            } else {
                "PLY header has no 'end_header' line".into()
            });
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let line = std::str::from_utf8(raw)
            .map_err(|_| "PLY header contains non-text bytes".to_string())?
            .trim();
        if first {
            if line != "ply" {
                return Err("not a PLY file (first line is not 'ply')".into());
            }
            first = false;
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["end_header"] => break,
            ["format", fmt, _version] => {
                encoding = Some(match *fmt {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    other => return Err(format!("unknown PLY format '{other}'")),
                });
            }
            ["element", elem, count] => {
                let count = count
                    .parse()
                    .map_err(|_| format!("element '{elem}' has a bad count '{count}'"))?;
                elements.push(Element {
                    name: elem.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", count, item, prop] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| format!("property '{prop}' comes before any element"))?;
                let count = scalar_type(count)?;
                if !count.is_integer() {
                    return Err(format!("list '{prop}' has a non-integer count type"));
                }
                let item = scalar_type(item)?;
                element.props.push(Property {
                    name: prop.to_string(),
                    kind: Kind::List { count, item },
                });
            }
            ["property", ty, prop] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| format!("property '{prop}' comes before any element"))?;
                element.props.push(Property {
                    name: prop.to_string(),
                    kind: Kind::Scalar(scalar_type(ty)?),
                });
            }
            _ => return Err(format!("unrecognised PLY header line '{line}'")),
        }
    }
    let encoding = encoding.ok_or("PLY header has no 'format' line")?;
    Ok(Header {
        encoding,
        elements,
        body_start: pos,
    })
}

fn scalar_type(word: &str) -> Result<Scalar, String> {
    Scalar::parse(word).ok_or_else(|| format!("unknown PLY property type '{word}'"))
}

/// Sequential access to the body's numbers, independent of encoding.
trait Values {
    fn next(&mut self, ty: Scalar) -> Result<f64, String>;
    /// What is left after the values read so far, described, if anything.
    fn leftover(&self) -> Option<String>;
}

struct AsciiValues<'a> {
    body: &'a [u8],
    pos: usize,
}

impl Values for AsciiValues<'_> {
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        let rest = &self.body[self.pos..];
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or("file ends early")?;
        let len = rest[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len() - start);
        self.pos += start + len;
        let word = std::str::from_utf8(&rest[start..start + len]).unwrap_or("?");
        let bad = || format!("'{word}' is not a valid {ty:?} value");
        if ty.is_integer() {
            word.parse::<i64>().map(|v| v as f64).map_err(|_| bad())
        } else {
            word.parse::<f64>().map_err(|_| bad())
        }
    }

    fn leftover(&self) -> Option<String> {
        let rest = self.body[self.pos..].trim_ascii();
        let word = rest.split(u8::is_ascii_whitespace).next().unwrap_or(rest);
        (!rest.is_empty()).then(|| {
            let word = String::from_utf8_lossy(&word[..word.len().min(20)]).into_owned();
            format!("text ('{word}' ...)")
        })
    }
}

struct BinaryValues<'a> {
    body: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Values for BinaryValues<'_> {
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        let n = ty.size();
        let raw = self
            .body
            .get(self.pos..self.pos + n)
            .ok_or("file ends early")?;
        self.pos += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.big_endian {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    fn leftover(&self) -> Option<String> {
        let n = self.body.len() - self.pos;
        (n > 0).then(|| format!("{n} more bytes"))
    }
}

fn list_len(v: f64) -> Result<u64, String> {
    if v >= 0.0 && v.fract() == 0.0 {
        Ok(v as u64)
    } else {
        Err(format!("negative list length {v}"))
    }
}

/// Reads (and drops) one property value, whatever its kind.
fn skip_property(kind: &Kind, values: &mut dyn Values) -> Result<(), String> {
    match *kind {
        Kind::Scalar(ty) => values.next(ty).map(drop),
        Kind::List { count, item } => {
            for _ in 0..list_len(values.next(count)?)? {
                values.next(item)?;
            }
            Ok(())
        }
    }
}

fn skip(element: &Element, values: &mut dyn Values) -> Result<(), String> {
    if element.props.is_empty() {
        // Nothing to consume; do not spin through a hostile count.
        return Ok(());
    }
    for i in 0..element.count {
        for p in &element.props {
            skip_property(&p.kind, values).map_err(|e| at(element, i, e))?;
        }
    }
    Ok(())
}

fn at(element: &Element, i: u64, problem: String) -> String {
    format!("{} {i} (of {}): {problem}", element.name, element.count)
}

/// Reads the `vertex` element's x, y, z into `out`, and its nx, ny, nz into `normals` when
/// given and the element has all three (`normals` is left empty otherwise).
fn read_vertices(
    element: &Element,
    values: &mut dyn Values,
    body_len: usize,
    out: &mut Vec<DVec3>,
    mut normals: Option<&mut Vec<Vec3>>,
) -> Result<(), String> {
    let find = |axis: &str| {
        element
            .props
            .iter()
            .position(|p| p.name == axis)
            .ok_or_else(|| format!("PLY 'vertex' element has no '{axis}' property"))
    };
    let slots = [find("x")?, find("y")?, find("z")?];
    let normal_slots = match (find("nx"), find("ny"), find("nz")) {
        (Ok(a), Ok(b), Ok(c)) if normals.is_some() => Some([a, b, c]),
        _ => None,
    };
    if normal_slots.is_none() {
        normals = None;
    }
    for &s in slots.iter().chain(normal_slots.iter().flatten()) {
        if let Kind::List { .. } = element.props[s].kind {
            return Err(format!(
                "vertex property '{}' is a list, expected a number",
                element.props[s].name
            ));
        }
    }
    if element.count > u64::from(u32::MAX) {
        return Err(format!("{} vertices is more than 2^32", element.count));
    }
    // The declared count is untrusted; never reserve more than the body could hold.
    out.reserve((element.count as usize).min(body_len / 3));
    let normal_slots = normal_slots.unwrap_or([usize::MAX; 3]);
    for i in 0..element.count {
        let mut xyz = [0f64; 3];
        let mut nxyz = [0f32; 3];
        for (k, p) in element.props.iter().enumerate() {
            let axis = slots.iter().position(|&s| s == k);
            let normal_axis = normal_slots.iter().position(|&s| s == k);
            match (p.kind_scalar(), axis, normal_axis) {
                (Some(ty), Some(a), _) => {
                    xyz[a] = values.next(ty).map_err(|e| at(element, i, e))?;
                }
                (Some(ty), None, Some(a)) => {
                    nxyz[a] = values.next(ty).map_err(|e| at(element, i, e))? as f32;
                }
                _ => skip_property(&p.kind, values).map_err(|e| at(element, i, e))?,
            }
        }
        out.push(DVec3::from_array(xyz));
        if let Some(n) = normals.as_deref_mut() {
            n.push(Vec3::from_array(nxyz));
        }
    }
    Ok(())
}

impl Property {
    fn kind_scalar(&self) -> Option<Scalar> {
        match self.kind {
            Kind::Scalar(ty) => Some(ty),
            Kind::List { .. } => None,
        }
    }
}

fn read_faces(
    element: &Element,
    values: &mut dyn Values,
    out: &mut Vec<[u32; 3]>,
) -> Result<(), String> {
    let slot = element
        .props
        .iter()
        .position(|p| {
            matches!(p.kind, Kind::List { .. })
                && (p.name == "vertex_indices" || p.name == "vertex_index")
        })
        .ok_or("PLY 'face' element has no 'vertex_indices' list")?;
    for i in 0..element.count {
        for (k, p) in element.props.iter().enumerate() {
            match p.kind {
                Kind::List { count, item } if k == slot => {
                    let n = list_len(values.next(count).map_err(|e| at(element, i, e))?)
                        .map_err(|e| at(element, i, e))?;
                    // Fan from the first corner, streaming so a hostile count costs nothing.
                    let mut first = 0;
                    let mut prev = 0;
                    for j in 0..n {
                        let v = values.next(item).map_err(|e| at(element, i, e))?;
                        let v = vertex_index(v).map_err(|e| at(element, i, e))?;
                        match j {
                            0 => first = v,
                            1 => {}
                            _ => out.push([first, prev, v]),
                        }
                        prev = v;
                    }
                }
                _ => skip_property(&p.kind, values).map_err(|e| at(element, i, e))?,
            }
        }
    }
    Ok(())
}

fn vertex_index(v: f64) -> Result<u32, String> {
    if v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0 {
        Ok(v as u32)
    } else {
        Err(format!("invalid vertex index {v}"))
    }
}

/// Binary little-endian PLY with per-vertex normals. Positions are floats, or for a mesh with a
/// frame offset doubles holding the world positions (offset added in f64).
pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, normals: &[Vec3]) -> io::Result<()> {
    let far = mesh.offset != DVec3::ZERO;
    let position_type = if far { "double" } else { "float" };
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment pgvol\n\
         element vertex {}\n\
         property {position_type} x\nproperty {position_type} y\nproperty {position_type} z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )?;
    write_records(w, mesh.positions.len(), |range, out| {
        for i in range {
            if far {
                for c in mesh.world(i).to_array() {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            } else {
                for c in mesh.positions[i].to_array() {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            for c in normals[i].to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    })?;
    write_records(w, mesh.triangles.len(), |range, out| {
        for t in &mesh.triangles[range] {
            out.push(3);
            for i in t {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
    })?;
    Ok(())
}
