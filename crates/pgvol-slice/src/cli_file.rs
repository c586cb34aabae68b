//! Common Layer Interface (CLI) files, version 2.0, ASCII or binary, written atomically.
//!
//! Both forms share the ASCII header. `$$UNITS` is the length of one coordinate unit in
//! millimetres (1 for a mesh in mm). Each layer is a start-layer command at its height followed
//! by one polyline per loop, closed by repeating its first point; the direction is 1 for
//! counter-clockwise (outer) loops and 0 for clockwise (hole) loops. All polylines belong to
//! part 1.

use std::io::{self, Write};
use std::path::Path;

use pgvol_core::{write_atomic, FileError};

use crate::layer_frame::{f32_loss, world_text, LayerFrame};
use crate::slice::Layer;
use crate::write::extent;

/// Binary command indices of the CLI 2.0 specification ("long" forms: 32-bit integers and
/// IEEE floats, little-endian).
const START_LAYER_LONG: u16 = 127;
const START_POLYLINE_LONG: u16 = 130;

/// Which of the two encodings of the geometry section to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CliEncoding {
    Ascii,
    Binary,
}

/// Writes `layers` as a CLI file in `encoding`.
pub fn write_cli_with(
    path: &Path,
    layers: &[Layer],
    units_mm: f32,
    encoding: CliEncoding,
) -> Result<(), FileError> {
    write_cli_in(path, layers, units_mm, encoding, &LayerFrame::default())
}

/// The largest rounding, relative to the layers' extent, that binary CLI's f32 coordinates may
/// add to layers in a frame away from the origin; beyond it the write is refused.
pub const MAX_BINARY_ROUNDING: f64 = 1e-5;

/// [`write_cli_with`] for layers in `frame`: world coordinates, the frame added in f64 (ASCII
/// text keeps them whole; binary f32 is refused when it would round them by more than
/// [`MAX_BINARY_ROUNDING`] of the layers' extent).
pub fn write_cli_in(
    path: &Path,
    layers: &[Layer],
    units_mm: f32,
    encoding: CliEncoding,
    frame: &LayerFrame,
) -> Result<(), FileError> {
    if !(units_mm.is_finite() && units_mm > 0.0) {
        return Err(FileError::new(
            path,
            format!("units must be a positive length in mm, got {units_mm}"),
        ));
    }
    if let (CliEncoding::Binary, Some(extent), Some(first), Some(last)) =
        (encoding, extent(layers), layers.first(), layers.last())
    {
        let loss = f32_loss(frame, extent, (first.height, last.height));
        if let Some(relative) = loss.filter(|&r| r > MAX_BINARY_ROUNDING) {
            return Err(FileError::new(
                path,
                format!(
                    "refusing to write: binary CLI stores single-precision coordinates, which \
                     this far from the origin are rounded by up to {:.3} % of the part's size; \
                     write ASCII CLI (without --binary), SVG or JSON instead",
                    relative * 100.0
                ),
            ));
        }
    }
    write_atomic(path, |w| {
        write_header(w, layers, units_mm, encoding, frame)?;
        match encoding {
            CliEncoding::Ascii => write_ascii_geometry(w, layers, frame),
            CliEncoding::Binary => write_binary_geometry(w, layers, frame),
        }
    })
}

/// Writes `layers` as an ASCII CLI file.
pub fn write_cli(path: &Path, layers: &[Layer], units_mm: f32) -> Result<(), FileError> {
    write_cli_with(path, layers, units_mm, CliEncoding::Ascii)
}

fn write_header(
    w: &mut dyn Write,
    layers: &[Layer],
    units_mm: f32,
    encoding: CliEncoding,
    frame: &LayerFrame,
) -> io::Result<()> {
    writeln!(w, "$$HEADERSTART")?;
    match encoding {
        CliEncoding::Ascii => writeln!(w, "$$ASCII")?,
        CliEncoding::Binary => writeln!(w, "$$BINARY")?,
    }
    writeln!(w, "$$UNITS/{units_mm}")?;
    writeln!(w, "$$VERSION/200")?;
    writeln!(w, "$$LABEL/1,part1")?;
    if let (Some([u0, v0, u1, v1]), Some(first), Some(last)) =
        (extent(layers), layers.first(), layers.last())
    {
        let (u, v, h) = (frame.u, frame.v, frame.height);
        writeln!(
            w,
            "$$DIMENSION/{},{},{},{},{},{}",
            world_text(u0, u),
            world_text(v0, v),
            world_text(first.height, h),
            world_text(u1, u),
            world_text(v1, v),
            world_text(last.height, h)
        )?;
    }
    writeln!(w, "$$LAYERS/{}", layers.len())?;
    // The binary geometry starts right after this keyword, with no line break in between.
    match encoding {
        CliEncoding::Ascii => writeln!(w, "$$HEADEREND"),
        CliEncoding::Binary => write!(w, "$$HEADEREND"),
    }
}

fn write_ascii_geometry(w: &mut dyn Write, layers: &[Layer], frame: &LayerFrame) -> io::Result<()> {
    writeln!(w, "$$GEOMETRYSTART")?;
    for layer in layers {
        writeln!(w, "$$LAYER/{}", world_text(layer.height, frame.height))?;
        for lp in &layer.loops {
            let Some(start) = lp.points.first() else {
                continue;
            };
            write!(
                w,
                "$$POLYLINE/1,{},{}",
                direction(lp.hole),
                lp.points.len() + 1
            )?;
            for p in lp.points.iter().chain(std::iter::once(start)) {
                write!(
                    w,
                    ",{},{}",
                    world_text(p[0], frame.u),
                    world_text(p[1], frame.v)
                )?;
            }
            writeln!(w)?;
        }
    }
    writeln!(w, "$$GEOMETRYEND")
}

/// f32 world coordinate of a local one (the frame added in f64, rounded once).
fn world_f32(local: f32, shift: f64) -> f32 {
    if shift == 0.0 {
        local
    } else {
        (shift + f64::from(local)) as f32
    }
}

fn write_binary_geometry(
    w: &mut dyn Write,
    layers: &[Layer],
    frame: &LayerFrame,
) -> io::Result<()> {
    for layer in layers {
        w.write_all(&START_LAYER_LONG.to_le_bytes())?;
        w.write_all(&world_f32(layer.height, frame.height).to_le_bytes())?;
        for lp in &layer.loops {
            let Some(start) = lp.points.first() else {
                continue;
            };
            let count = i32::try_from(lp.points.len() + 1)
                .map_err(|_| io::Error::other("a loop has more than 2^31 points"))?;
            w.write_all(&START_POLYLINE_LONG.to_le_bytes())?;
            for v in [1, direction(lp.hole), count] {
                w.write_all(&v.to_le_bytes())?;
            }
            for p in lp.points.iter().chain(std::iter::once(start)) {
                w.write_all(&world_f32(p[0], frame.u).to_le_bytes())?;
                w.write_all(&world_f32(p[1], frame.v).to_le_bytes())?;
            }
        }
    }
    Ok(())
}

fn direction(hole: bool) -> i32 {
    if hole {
        0
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slice::Loop;

    fn sample_layers() -> Vec<Layer> {
        let square = Loop {
            points: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]],
            hole: false,
        };
        let hole = Loop {
            points: vec![[0.5, 0.5], [0.5, 1.5], [1.5, 1.5], [1.5, 0.5]],
            hole: true,
        };
        vec![
            Layer {
                height: 0.25,
                loops: vec![square.clone(), hole],
            },
            Layer {
                height: 0.75,
                loops: vec![square],
            },
        ]
    }

    /// (height, [(direction, points)]) per layer, read back from the binary geometry.
    type Parsed = Vec<(f32, Vec<(i32, Vec<[f32; 2]>)>)>;

    fn parse_binary(bytes: &[u8]) -> Parsed {
        let end = b"$$HEADEREND";
        let at = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
        let mut rest = &bytes[at..];
        let mut take = |n: usize| {
            let (head, tail) = rest.split_at(n);
            rest = tail;
            head.to_vec()
        };
        let mut layers: Parsed = Vec::new();
        let mut remaining = bytes.len() - at;
        while remaining > 0 {
            let cmd = u16::from_le_bytes(take(2).try_into().unwrap());
            remaining -= 2;
            match cmd {
                START_LAYER_LONG => {
                    layers.push((f32::from_le_bytes(take(4).try_into().unwrap()), vec![]));
                    remaining -= 4;
                }
                START_POLYLINE_LONG => {
                    let ints: Vec<i32> = (0..3)
                        .map(|_| i32::from_le_bytes(take(4).try_into().unwrap()))
                        .collect();
                    assert_eq!(ints[0], 1, "part id");
                    let pts = (0..ints[2])
                        .map(|_| {
                            let x = f32::from_le_bytes(take(4).try_into().unwrap());
                            let y = f32::from_le_bytes(take(4).try_into().unwrap());
                            [x, y]
                        })
                        .collect();
                    remaining -= 12 + 8 * ints[2] as usize;
                    layers.last_mut().unwrap().1.push((ints[1], pts));
                }
                other => panic!("unexpected command {other}"),
            }
        }
        layers
    }

    #[test]
    fn binary_geometry_reads_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("layers.cli");
        let layers = sample_layers();
        write_cli_with(&path, &layers, 0.5, CliEncoding::Binary).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let text_end = bytes.windows(11).position(|w| w == b"$$HEADEREND").unwrap();
        let header = std::str::from_utf8(&bytes[..text_end]).unwrap();
        assert!(header.contains("$$BINARY") && header.contains("$$UNITS/0.5"));
        assert!(header.contains("$$LAYERS/2"));
        let parsed = parse_binary(&bytes);
        assert_eq!(parsed.len(), layers.len());
        for (got, want) in parsed.iter().zip(&layers) {
            assert_eq!(got.0, want.height);
            assert_eq!(got.1.len(), want.loops.len());
            for ((dir, pts), lp) in got.1.iter().zip(&want.loops) {
                assert_eq!(*dir, if lp.hole { 0 } else { 1 });
                assert_eq!(&pts[..pts.len() - 1], &lp.points[..]);
                assert_eq!(pts.last(), lp.points.first(), "closed by its first point");
            }
        }
    }

    #[test]
    fn ascii_and_binary_share_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.cli"), dir.path().join("b.cli"));
        let layers = sample_layers();
        write_cli_with(&a, &layers, 1.0, CliEncoding::Ascii).unwrap();
        write_cli_with(&b, &layers, 1.0, CliEncoding::Binary).unwrap();
        let ascii = std::fs::read_to_string(&a).unwrap();
        let binary = std::fs::read(&b).unwrap();
        let head = |s: &str| s[..s.find("$$HEADEREND").unwrap()].replace("$$ASCII", "$$BINARY");
        assert_eq!(head(&ascii), head(&String::from_utf8_lossy(&binary)));
        assert_eq!(ascii.matches("$$POLYLINE/").count(), 3);
    }

    #[test]
    fn bad_units_are_refused_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.cli");
        for units in [0.0, -1.0, f32::NAN] {
            assert!(write_cli_with(&path, &sample_layers(), units, CliEncoding::Binary).is_err());
        }
        assert!(!path.exists());
    }
}
