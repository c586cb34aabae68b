//! Layer files: SVG to look at and JSON for scripts, written atomically. The Common Layer
//! Interface files for build processors are in `cli_file`.

use std::path::Path;

use pgvol_core::{write_atomic, FileError};
use serde::{Deserialize, Serialize};

use crate::layer_frame::{world_text, LayerFrame};
use crate::slice::{Layer, Loop};

/// Bounding box `[min_u, min_v, max_u, max_v]` of every loop point, if any.
pub(crate) fn extent(layers: &[Layer]) -> Option<[f32; 4]> {
    let mut pts = layers
        .iter()
        .flat_map(|l| &l.loops)
        .flat_map(|l| &l.points)
        .peekable();
    pts.peek()?;
    Some(pts.fold(
        [
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ]
        },
    ))
}

/// An SVG of the layers side by side in a near-square grid of equal tiles, bottom layer first,
/// left to right then top to bottom. Each layer is one `<g id="layer-i" data-height="z">` with a
/// `<title>` and one even-odd filled path, so holes show as holes. The v axis points up, as in
/// the layer coordinates, so counter-clockwise loops look counter-clockwise. The root carries
/// `data-u-offset` and `data-v-offset`: a point (x, y) of a layer's path is at
/// u = x + u-offset, v = v-offset − y in layer coordinates ([`read_svg`](crate::read_svg)).
pub fn write_svg(path: &Path, layers: &[Layer]) -> Result<(), FileError> {
    write_svg_in(path, layers, &LayerFrame::default())
}

/// [`write_svg`] for layers in `frame`: the heights and the root's offsets are world
/// coordinates (the frame added in f64); the paths, relative to the offsets, are unchanged.
pub fn write_svg_in(path: &Path, layers: &[Layer], frame: &LayerFrame) -> Result<(), FileError> {
    let [u0, v0, u1, v1] = extent(layers).unwrap_or([0.0, 0.0, 1.0, 1.0]);
    let size = (u1 - u0).max(v1 - v0).max(f32::MIN_POSITIVE);
    let pad = 0.05 * size;
    let (tw, th) = (u1 - u0 + 2.0 * pad, v1 - v0 + 2.0 * pad);
    let columns = (layers.len() as f64).sqrt().ceil().max(1.0) as usize;
    let rows = layers.len().div_ceil(columns).max(1);
    let stroke = size / 500.0;
    write_atomic(path, |w| {
        writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
        writeln!(
            w,
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {} {}" width="{}" height="{}" data-u-offset="{}" data-v-offset="{}">"#,
            tw * columns as f32,
            th * rows as f32,
            (1024 * columns / columns.max(rows)).max(64),
            (1024 * rows / columns.max(rows)).max(64),
            world_text(u0 - pad, frame.u),
            world_text(v1 + pad, frame.v),
        )?;
        for (i, layer) in layers.iter().enumerate() {
            let (c, r) = (i % columns, i / columns);
            writeln!(
                w,
                r#"<g id="layer-{i}" data-height="{}" transform="translate({} {})">"#,
                world_text(layer.height, frame.height),
                tw * c as f32,
                th * r as f32
            )?;
            writeln!(
                w,
                "<title>layer {i} at {}</title>",
                world_text(layer.height, frame.height)
            )?;
            write!(
                w,
                r##"<rect width="{tw}" height="{th}" fill="none" stroke="#ccc" stroke-width="{stroke}"/>"##
            )?;
            if !layer.loops.is_empty() {
                write!(w, r#"<path d=""#)?;
                for lp in &layer.loops {
                    for (k, p) in lp.points.iter().enumerate() {
                        let cmd = if k == 0 { 'M' } else { 'L' };
                        write!(w, "{cmd}{} {} ", p[0] - u0 + pad, v1 - p[1] + pad)?;
                    }
                    write!(w, "Z ")?;
                }
                write!(
                    w,
                    r##"" fill="#4a7" fill-rule="evenodd" stroke="#000" stroke-width="{stroke}"/>"##
                )?;
            }
            writeln!(w, "\n</g>")?;
        }
        writeln!(w, "</svg>")
    })
}

/// A layer as the JSON file holds it: its loops, then its area and perimeter for readers that
/// plan without tracing the loops (readers of the loops ignore them).
#[derive(Serialize)]
struct LayerRecord<'a> {
    height: f32,
    loops: &'a [Loop],
    area: f64,
    perimeter: f64,
}

#[derive(Serialize)]
struct SliceFileRef<'a> {
    layers: Vec<LayerRecord<'a>>,
}

#[derive(Deserialize)]
struct SliceFile {
    layers: Vec<Layer>,
}

/// The layers as JSON: `{"layers": [{"height": z, "loops": [{"points": [[u, v], …], "hole":
/// false}, …], "area": a, "perimeter": p}, …]}`, numbers written so they read back to the same
/// f32; `area` is the solid's (holes subtracted) and `perimeter` the loops' total length, in f64.
pub fn write_slice_json(path: &Path, layers: &[Layer]) -> Result<(), FileError> {
    write_slice_json_in(path, layers, &LayerFrame::default())
}

/// [`write_slice_json`] for layers in `frame`: heights and points are world coordinates, the
/// frame added in f64 and written as f64.
pub fn write_slice_json_in(
    path: &Path,
    layers: &[Layer],
    frame: &LayerFrame,
) -> Result<(), FileError> {
    if frame.is_zero() {
        let layers = layers
            .iter()
            .map(|l| LayerRecord {
                height: l.height,
                loops: &l.loops,
                area: l.area(),
                perimeter: l.perimeter(),
            })
            .collect();
        return write_atomic(path, |w| {
            serde_json::to_writer(&mut *w, &SliceFileRef { layers })?;
            writeln!(w)
        });
    }
    let world: Vec<serde_json::Value> = layers
        .iter()
        .map(|layer| {
            let loops: Vec<serde_json::Value> = layer
                .loops
                .iter()
                .map(|lp| {
                    let points: Vec<[f64; 2]> = lp
                        .points
                        .iter()
                        .map(|p| [frame.u + f64::from(p[0]), frame.v + f64::from(p[1])])
                        .collect();
                    serde_json::json!({ "points": points, "hole": lp.hole })
                })
                .collect();
            serde_json::json!({
                "height": frame.height + f64::from(layer.height),
                "loops": loops,
                "area": layer.area(),
                "perimeter": layer.perimeter(),
            })
        })
        .collect();
    write_atomic(path, |w| {
        serde_json::to_writer(&mut *w, &serde_json::json!({ "layers": world }))?;
        writeln!(w)
    })
}

/// Reads what [`write_slice_json`] wrote.
pub fn read_slice_json(path: &Path) -> Result<Vec<Layer>, FileError> {
    let text = std::fs::read_to_string(path).map_err(|e| FileError::new(path, e.to_string()))?;
    serde_json::from_str::<SliceFile>(&text)
        .map(|f| f.layers)
        .map_err(|e| FileError::new(path, format!("not a slice file: {e}")))
}
