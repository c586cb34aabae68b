//! 3MF package with a level-set object of the Volumetric extension: the field sampled on a grid,
//! stored as a stack of one-channel 16-bit PNG sheets and read through a `functionfromimage3d`;
//! optionally the level set is an implicit function (`crate::implicit`) that reads that stack
//! through a function call. Element and attribute names follow the published Volumetric &
//! Implicit 1.0 schema (see `docs/format.md` and `docs/interop.md`).

use std::io::Write;
use std::path::Path;

use pgvol_field::Grid;
use zip::write::SimpleFileOptions;

use crate::error::{err, FormatError};
use crate::implicit::{Binary, ImplicitFunction, Port};

pub const NS_CORE: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";
pub const NS_VOLUMETRIC: &str = "http://schemas.3mf.io/3dmanufacturing/volumetric/2022/01";
pub const NS_IMPLICIT: &str = "http://schemas.3mf.io/3dmanufacturing/implicit/2023/12";
const REL_MODEL: &str = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel";
const REL_TEXTURE: &str = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dtexture";
/// Where the sheets go: `/3D/volumetric/<image name>/`, as the extension recommends.
const SHEET_DIR: &str = "3D/volumetric/sdf";
/// Resource ids: the evaluation box, the image stack and the function reading it; then the
/// implicit function when there is one, and the level-set object last.
const BOX_ID: u32 = 1;
const IMAGE_ID: u32 = 2;
const IMAGE_FUNCTION_ID: u32 = 3;
/// The output of `functionfromimage3d` the sampled field is read from.
const IMAGE_CHANNEL: &str = "red";

/// How field values map to 16-bit pixels: `value = pixel / 65535 · scale + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantisation {
    pub offset: f64,
    pub scale: f64,
}

impl Quantisation {
    /// Spans `[min, max]` of `values` exactly, so the error is at most half a step.
    pub fn spanning(values: &[f32]) -> Quantisation {
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v as f64), hi.max(v as f64))
            });
        if !(lo.is_finite() && hi.is_finite()) {
            return Quantisation {
                offset: 0.0,
                scale: 1.0,
            };
        }
        // A constant field still needs a non-zero scale for the mapping to be invertible.
        let scale = if hi > lo { hi - lo } else { 1.0 };
        Quantisation { offset: lo, scale }
    }

    /// Pixels `step` apart from the minimum of `values`, when their span fits in 16 bits; else
    /// [`Quantisation::spanning`]. A coarser step than the span needs leaves smooth sheets
    /// with small differences between neighbours, which PNG's filters and deflate compress.
    pub fn stepped(values: &[f32], step: f64) -> Quantisation {
        let full = Quantisation::spanning(values);
        let scale = step * 65535.0;
        if step > 0.0 && scale >= full.scale {
            Quantisation {
                offset: full.offset,
                scale,
            }
        } else {
            full
        }
    }

    pub fn pixel(&self, v: f32) -> u16 {
        ((v as f64 - self.offset) / self.scale * 65535.0)
            .round()
            .clamp(0.0, 65535.0) as u16
    }

    pub fn value(&self, pixel: u16) -> f64 {
        pixel as f64 / 65535.0 * self.scale + self.offset
    }
}

/// The object-to-UVW transform of the level set, as the 12 numbers of a 3MF `ST_Matrix3D`
/// (row-vector convention: `[x y z 1] · M`, translation last). Voxel centres sit at
/// `(i + ½) / n` in UVW, so the unit cube covers the grid box grown by half a spacing and each
/// pixel centre lands on its grid node.
pub fn object_to_uvw(grid: &Grid) -> [f64; 12] {
    let h = grid.spacing as f64;
    // World coordinates: the frame offset added in f64.
    let o = pgvol_core::frame::to_world(grid.origin, grid.offset)
        .to_array()
        .map(|c| c - 0.5 * h);
    let s = grid.dims.map(|n| 1.0 / (n as f64 * h));
    [
        s[0],
        0.0,
        0.0,
        0.0,
        s[1],
        0.0,
        0.0,
        0.0,
        s[2],
        -o[0] * s[0],
        -o[1] * s[1],
        -o[2] * s[2],
    ]
}

/// One 16-bit greyscale PNG of `columns × rows` pixels (row-major, the top row first).
fn png_sheet(pixels: &[u16], columns: usize, rows: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, columns as u32, rows as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    // PNG stores 16-bit samples big-endian.
    let data: Vec<u8> = pixels.iter().flat_map(|p| p.to_be_bytes()).collect();
    w.write_image_data(&data).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())?;
    Ok(out)
}

fn num(v: f64) -> String {
    // Shortest text that reads back to the same f64.
    format!("{v}")
}

/// A level set given by an implicit function of the object's coordinates (no transform), with
/// the value it falls back to where the function is undefined.
pub struct ImplicitLevelSet<'a> {
    pub function: &'a ImplicitFunction,
    pub fallback: f64,
    /// The image stack's value step ([`Quantisation::stepped`]); `None` spans the values.
    pub value_step: Option<f64>,
}

/// The sampled field inside an implicit function: the image stack's function called at the
/// UVW coordinates of `pos` (object coordinates), [`object_to_uvw`] made of nodes.
pub fn image_value(f: &mut ImplicitFunction, grid: &Grid, pos: &Port) -> Port {
    let m = object_to_uvw(grid);
    let scale = f.constvec([m[0], m[4], m[8]]);
    let shift = f.constvec([m[9], m[10], m[11]]);
    let scaled = f.binary(Binary::Mul, pos, &scale);
    let uvw = f.binary(Binary::Add, &scaled, &shift);
    let id = f.resource(IMAGE_FUNCTION_ID);
    f.call(&id, &uvw, IMAGE_CHANNEL)
}

/// The `3D/3dmodel.model` part for `grid` and the sheet paths; the level set reads the image
/// stack directly, or through `implicit`.
pub fn model_xml(
    grid: &Grid,
    q: Quantisation,
    sheets: &[String],
    unit: &str,
    implicit: Option<&ImplicitLevelSet>,
) -> String {
    let [nx, ny, nz] = grid.dims;
    // World coordinates: f32 text near the origin, the offset added in f64 otherwise.
    let corner = |p: glam::Vec3| -> [String; 3] {
        if grid.offset == glam::DVec3::ZERO {
            p.to_array().map(|c| c.to_string())
        } else {
            pgvol_core::frame::to_world(p, grid.offset)
                .to_array()
                .map(num)
        }
    };
    let lo = corner(grid.origin);
    let hi = corner(grid.max_corner());
    let t = object_to_uvw(grid).map(num).join(" ");
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    // The level set is geometry: a consumer that does not know an extension in it must refuse.
    let required = if implicit.is_some() { "v i" } else { "v" };
    s.push_str(&format!(
        "<model unit=\"{unit}\" xml:lang=\"en-US\" xmlns=\"{NS_CORE}\" xmlns:v=\"{NS_VOLUMETRIC}\" xmlns:i=\"{NS_IMPLICIT}\" requiredextensions=\"{required}\">\n"
    ));
    s.push_str(" <metadata name=\"Application\">pgvol</metadata>\n <resources>\n");
    // 1: the grid box as a closed mesh, the level set's evaluation domain.
    s.push_str(&format!(
        "  <object id=\"{BOX_ID}\" type=\"model\" name=\"evaluation box\">\n   <mesh>\n    <vertices>\n",
    ));
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
                let p = |c: usize, a: usize| if c == 0 { &lo[a] } else { &hi[a] };
                s.push_str(&format!(
                    "     <vertex x=\"{}\" y=\"{}\" z=\"{}\"/>\n",
                    p(i, 0),
                    p(j, 1),
                    p(k, 2)
                ));
            }
        }
    }
    s.push_str("    </vertices>\n    <triangles>\n");
    for [a, b, c] in BOX_TRIANGLES {
        s.push_str(&format!(
            "     <triangle v1=\"{a}\" v2=\"{b}\" v3=\"{c}\"/>\n"
        ));
    }
    s.push_str("    </triangles>\n   </mesh>\n  </object>\n");
    // The image stack; columns run along x (U), rows along −y (V), sheets along z (W).
    s.push_str(&format!(
        "  <v:image3d id=\"{IMAGE_ID}\" name=\"sdf\">\n   <v:imagestack rowcount=\"{ny}\" columncount=\"{nx}\" sheetcount=\"{nz}\">\n"
    ));
    for p in sheets {
        s.push_str(&format!("    <v:imagesheet path=\"/{p}\"/>\n"));
    }
    s.push_str("   </v:imagestack>\n  </v:image3d>\n");
    // 3: the function reading it; clamp so the border values continue outside the box.
    s.push_str(&format!(
        "  <v:functionfromimage3d id=\"{IMAGE_FUNCTION_ID}\" displayname=\"signed distance\" image3did=\"{IMAGE_ID}\" valueoffset=\"{}\" valuescale=\"{}\" filter=\"linear\" tilestyleu=\"clamp\" tilestylev=\"clamp\" tilestylew=\"clamp\"/>\n",
        num(q.offset),
        num(q.scale)
    ));
    // The object, negative inside: the field itself, or the implicit function of it.
    let object_id = match implicit {
        None => {
            let id = IMAGE_FUNCTION_ID + 1;
            s.push_str(&format!(
                "  <object id=\"{id}\" type=\"model\" name=\"pgvol level set\">\n   <v:levelset functionid=\"{IMAGE_FUNCTION_ID}\" channel=\"{IMAGE_CHANNEL}\" transform=\"{t}\" minfeaturesize=\"{}\" meshid=\"{BOX_ID}\" meshbboxonly=\"true\" fallbackvalue=\"{}\"/>\n  </object>\n",
                grid.spacing,
                num(q.offset + q.scale)
            ));
            id
        }
        Some(level_set) => {
            let function_id = IMAGE_FUNCTION_ID + 1;
            let channel = level_set.function.output_name().unwrap_or("shape");
            s.push_str(&level_set.function.xml(function_id, "pgvol lattice", 2));
            let id = function_id + 1;
            s.push_str(&format!(
                "  <object id=\"{id}\" type=\"model\" name=\"pgvol level set\">\n   <v:levelset functionid=\"{function_id}\" channel=\"{channel}\" minfeaturesize=\"{}\" meshid=\"{BOX_ID}\" meshbboxonly=\"true\" fallbackvalue=\"{}\"/>\n  </object>\n",
                grid.spacing,
                num(level_set.fallback)
            ));
            id
        }
    };
    s.push_str(&format!(
        " </resources>\n <build>\n  <item objectid=\"{object_id}\"/>\n </build>\n</model>\n"
    ));
    s
}

/// Corners numbered `i + 2j + 4k`; counter-clockwise seen from outside.
const BOX_TRIANGLES: [[u32; 3]; 12] = [
    [0, 2, 3],
    [0, 3, 1], // z = lo
    [4, 5, 7],
    [4, 7, 6], // z = hi
    [0, 1, 5],
    [0, 5, 4], // y = lo
    [2, 6, 7],
    [2, 7, 3], // y = hi
    [0, 4, 6],
    [0, 6, 2], // x = lo
    [1, 3, 7],
    [1, 7, 5], // x = hi
];

/// Writes `values` (sampled on `grid`, x fastest) as a 3MF package at `path`, atomically.
pub fn write_3mf(path: &Path, grid: &Grid, values: &[f32], unit: &str) -> Result<(), FormatError> {
    write_package(path, grid, values, unit, None)
}

/// Writes a 3MF package whose level set is `level_set`, an implicit function that may read
/// `values` (sampled on `grid`) through [`image_value`]; atomically.
pub fn write_3mf_implicit(
    path: &Path,
    grid: &Grid,
    values: &[f32],
    unit: &str,
    level_set: &ImplicitLevelSet,
) -> Result<(), FormatError> {
    if level_set.function.output_name().is_none() {
        return Err(err(path, "the implicit function has no output"));
    }
    write_package(path, grid, values, unit, Some(level_set))
}

fn write_package(
    path: &Path,
    grid: &Grid,
    values: &[f32],
    unit: &str,
    implicit: Option<&ImplicitLevelSet>,
) -> Result<(), FormatError> {
    let [nx, ny, nz] = grid.dims;
    if values.len() != grid.len() {
        return Err(err(
            path,
            format!("{} values for a {:?} grid", values.len(), grid.dims),
        ));
    }
    if nx > u32::MAX as usize || ny > u32::MAX as usize {
        return Err(err(path, "grid too large for PNG sheets"));
    }
    let q = match implicit.and_then(|l| l.value_step) {
        Some(step) => Quantisation::stepped(values, step),
        None => Quantisation::spanning(values),
    };
    let sheets: Vec<String> = (0..nz)
        .map(|k| format!("{SHEET_DIR}/sheet_{k:04}.png"))
        .collect();
    let model = model_xml(grid, q, &sheets, unit, implicit);

    let content_types = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">\n\
 <Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>\n\
 <Default Extension=\"model\" ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/>\n\
 <Default Extension=\"png\" ContentType=\"image/png\"/>\n\
</Types>\n";
    let root_rels = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">\n\
 <Relationship Id=\"rel0\" Target=\"/3D/3dmodel.model\" Type=\"{REL_MODEL}\"/>\n\
</Relationships>\n"
    );
    let mut model_rels = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">\n",
    );
    for (k, p) in sheets.iter().enumerate() {
        model_rels.push_str(&format!(
            " <Relationship Id=\"sheet{k}\" Target=\"/{p}\" Type=\"{REL_TEXTURE}\"/>\n"
        ));
    }
    model_rels.push_str("</Relationships>\n");

    let mut zip_bytes = Vec::new();
    let result = (|| -> Result<(), String> {
        let mut z = zip::ZipWriter::new(std::io::Cursor::new(&mut zip_bytes));
        let deflate =
            SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        // PNG data is already compressed.
        let stored =
            SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
        let mut put = |name: &str, data: &[u8], opts: SimpleFileOptions| -> Result<(), String> {
            z.start_file(name, opts).map_err(|e| e.to_string())?;
            z.write_all(data).map_err(|e| e.to_string())
        };
        put("[Content_Types].xml", content_types.as_bytes(), deflate)?;
        put("_rels/.rels", root_rels.as_bytes(), deflate)?;
        put("3D/3dmodel.model", model.as_bytes(), deflate)?;
        put(
            "3D/_rels/3dmodel.model.rels",
            model_rels.as_bytes(),
            deflate,
        )?;
        let plane = nx * ny;
        for (k, name) in sheets.iter().enumerate() {
            // Row index 0 lies at V near 1 (the extension's Figure 3-1: the front row, V = 0,
            // is the last), as PNG rows run top down: the first row written is y = ny − 1.
            let pixels: Vec<u16> = values[k * plane..(k + 1) * plane]
                .chunks_exact(nx)
                .rev()
                .flatten()
                .map(|&v| q.pixel(v))
                .collect();
            put(name, &png_sheet(&pixels, nx, ny)?, stored)?;
        }
        z.finish().map_err(|e| e.to_string())?;
        Ok(())
    })();
    result.map_err(|e| err(path, format!("cannot build the 3MF package: {e}")))?;
    pgvol_core::write_atomic(path, |w| w.write_all(&zip_bytes)).map_err(|e| err(path, e.problem))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn quantisation_error_is_half_a_step() {
        let values = [-2.5f32, -0.1, 0.0, 0.7, 1.25];
        let q = Quantisation::spanning(&values);
        assert_eq!((q.offset, q.scale), (-2.5, 3.75));
        assert_eq!(q.pixel(-2.5), 0);
        assert_eq!(q.pixel(1.25), 65535);
        for v in values {
            assert!((q.value(q.pixel(v)) - v as f64).abs() <= 0.5 * q.scale / 65535.0 + 1e-7);
        }
        assert_eq!(Quantisation::spanning(&[3.0, 3.0]).scale, 1.0);
    }

    #[test]
    fn a_stepped_quantisation_keeps_its_step_while_the_span_fits() {
        let values = [-1.0f32, 0.25, 2.0];
        let q = Quantisation::stepped(&values, 1e-3);
        assert_eq!((q.offset, q.scale), (-1.0, 65.535));
        assert_eq!(q.pixel(0.25), 1250);
        // A step too fine for 16 bits over the span falls back to spanning the values.
        assert_eq!(
            Quantisation::stepped(&values, 1e-6),
            Quantisation::spanning(&values)
        );
    }

    #[test]
    fn transform_puts_pixel_centres_on_nodes() {
        let grid = Grid {
            origin: Vec3::new(-1.0, 2.0, 0.5),
            spacing: 0.25,
            dims: [4, 5, 6],
            offset: Default::default(),
        };
        let m = object_to_uvw(&grid);
        let uvw = |p: Vec3| {
            let p = p.to_array().map(|c| c as f64);
            [0, 1, 2].map(|c| p[0] * m[c] + p[1] * m[3 + c] + p[2] * m[6 + c] + m[9 + c])
        };
        for (i, j, k) in [(0, 0, 0), (3, 4, 5), (1, 2, 3)] {
            let got = uvw(grid.point(i, j, k));
            let want = [
                (i as f64 + 0.5) / 4.0,
                (j as f64 + 0.5) / 5.0,
                (k as f64 + 0.5) / 6.0,
            ];
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() < 1e-6, "{got:?} {want:?}");
            }
        }
    }

    #[test]
    fn package_holds_model_rels_and_sheets() {
        let dir = tempfile::tempdir().unwrap();
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 0.5,
            dims: [3, 2, 4],
            offset: Default::default(),
        };
        let values: Vec<f32> = (0..24).map(|i| i as f32 - 10.0).collect();
        let path = dir.path().join("a.3mf");
        write_3mf(&path, &grid, &values, "millimeter").unwrap();
        let mut z = zip::ZipArchive::new(std::fs::File::open(&path).unwrap()).unwrap();
        let mut text = |name: &str| {
            let mut s = String::new();
            std::io::Read::read_to_string(&mut z.by_name(name).unwrap(), &mut s).unwrap();
            s
        };
        let model = text("3D/3dmodel.model");
        assert!(model.contains("sheetcount=\"4\"") && model.contains("columncount=\"3\""));
        assert_eq!(model.matches("<triangle ").count(), 12);
        assert!(text("3D/_rels/3dmodel.model.rels").contains("/3D/volumetric/sdf/sheet_0003.png"));
        assert!(text("_rels/.rels").contains("/3D/3dmodel.model"));
        let mut sheet = Vec::new();
        std::io::Read::read_to_end(
            &mut z.by_name("3D/volumetric/sdf/sheet_0001.png").unwrap(),
            &mut sheet,
        )
        .unwrap();
        let mut dec = png::Decoder::new(std::io::Cursor::new(sheet))
            .read_info()
            .unwrap();
        let mut buf = vec![0; dec.output_buffer_size().unwrap()];
        let info = dec.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(info.bit_depth, png::BitDepth::Sixteen);
        // Node (2, 1, 1) is value 2 + 3 + 6 - 10 = 1, i.e. 11/23 of the range; y = 1 is the
        // top row (row 0) of a sheet of two rows.
        let px = u16::from_be_bytes([buf[4], buf[5]]);
        assert_eq!(px, (11.0f64 / 23.0 * 65535.0).round() as u16);
    }

    #[test]
    fn box_is_closed_and_outward() {
        let corner = |v: u32| Vec3::new((v & 1) as f32, ((v >> 1) & 1) as f32, (v >> 2) as f32);
        let mut edges = std::collections::HashMap::new();
        for t in BOX_TRIANGLES {
            let [a, b, c] = t.map(corner);
            let n = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0 - Vec3::splat(0.5);
            assert!(n.dot(centre) > 0.0, "{t:?} faces inward");
            for e in 0..3 {
                *edges.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!((n, edges.get(&(b, a))), (1, Some(&1)), "edge {a}-{b}");
        }
    }
}
