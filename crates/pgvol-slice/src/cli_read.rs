//! Reading Common Layer Interface files, ASCII or binary, as written by `cli_file` and by
//! build processors: the layers (`$$LAYER` / command 127 or 128) and their polylines
//! (`$$POLYLINE` / command 129 or 130); hatches and other commands are skipped. Coordinates are
//! returned in file units (`$$UNITS` is not applied), as `pgvol slice` wrote them.

use std::path::Path;

use pgvol_core::FileError;

use crate::slice::{Layer, Loop};

/// The layers of a CLI file held in `bytes`; `name` labels errors.
pub fn read_cli(bytes: &[u8], name: &Path) -> Result<Vec<Layer>, FileError> {
    let fail = |problem: String| FileError::new(name, problem);
    let end =
        find(bytes, b"$$HEADEREND").ok_or_else(|| fail("not a CLI file: no $$HEADEREND".into()))?;
    let header = String::from_utf8_lossy(&bytes[..end]);
    let body = &bytes[end + b"$$HEADEREND".len()..];
    let layers = if header.contains("$$BINARY") {
        read_binary(body).map_err(fail)?
    } else {
        // ASCII geometry ends with this command; without it the file was cut short, and the
        // layers read would be only its first ones.
        if find(body, b"$$GEOMETRYEND").is_none() {
            return Err(fail(
                "the ASCII geometry has no $$GEOMETRYEND: the file was cut short, and its last \
                 layers would be missing"
                    .into(),
            ));
        }
        read_ascii(&String::from_utf8_lossy(body)).map_err(fail)?
    };
    if layers.iter().all(|l| l.loops.is_empty()) {
        return Err(fail("the file has no closed polylines".into()));
    }
    if let Some(problem) = crate::layer_frame::layer_coordinate_problem(&layers) {
        return Err(fail(problem));
    }
    Ok(layers)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A polyline's points as a loop: closed by repeating its first point, which is dropped;
/// direction 0 (clockwise) marks a hole.
fn to_loop(mut points: Vec<[f32; 2]>, direction: i64) -> Result<Option<Loop>, String> {
    if points.iter().flatten().any(|c| !c.is_finite()) {
        return Err("a polyline has a coordinate that is not finite".into());
    }
    if points.len() > 1 && points.first() == points.last() {
        points.pop();
    }
    Ok((points.len() >= 3).then_some(Loop {
        points,
        hole: direction == 0,
    }))
}

fn read_ascii(text: &str) -> Result<Vec<Layer>, String> {
    let mut layers: Vec<Layer> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        let at = |e: String| format!("line {} of the geometry: {e}", n + 1);
        if let Some(h) = line.strip_prefix("$$LAYER/") {
            let height: f32 = h
                .trim()
                .parse()
                .map_err(|_| at(format!("'{h}' is not a layer height")))?;
            if !height.is_finite() {
                return Err(at("the layer height is not finite".into()));
            }
            layers.push(Layer {
                height,
                loops: Vec::new(),
            });
        } else if let Some(rest) = line.strip_prefix("$$POLYLINE/") {
            let fields: Vec<f64> = rest
                .split(',')
                .map(|f| f.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| at(format!("'{rest}' is not a list of numbers")))?;
            if fields.len() < 3 {
                return Err(at("a polyline needs id, direction and count".into()));
            }
            let count = fields[2];
            if count < 0.0 || fields.len() != 3 + 2 * count as usize {
                return Err(at(format!(
                    "the polyline declares {count} points but gives {} numbers",
                    fields.len() - 3
                )));
            }
            let points = fields[3..]
                .chunks_exact(2)
                .map(|c| [c[0] as f32, c[1] as f32])
                .collect();
            let layer = layers
                .last_mut()
                .ok_or_else(|| at("a polyline before any $$LAYER".into()))?;
            if let Some(lp) = to_loop(points, fields[1] as i64).map_err(at)? {
                layer.loops.push(lp);
            }
        }
    }
    Ok(layers)
}

/// Binary geometry: 2-byte command indices, then their parameters. Only the long forms
/// (127 layer f32, 130 polyline i32 id, dir, n, then 2n f32) and the short forms (128 layer
/// u16, 129 polyline u16 id, dir, n, then 2n u16) are understood; anything else ends the read
/// with an error, since its length is unknown.
fn read_binary(body: &[u8]) -> Result<Vec<Layer>, String> {
    let mut layers: Vec<Layer> = Vec::new();
    let mut pos = 0;
    let take = |pos: &mut usize, n: usize| -> Result<&[u8], String> {
        let s = body
            .get(*pos..*pos + n)
            .ok_or_else(|| format!("the geometry ends inside a command at byte {}", *pos))?;
        *pos += n;
        Ok(s)
    };
    let word = |b: &[u8]| [b[0], b[1], b[2], b[3]];
    while pos < body.len() {
        let cmd = take(&mut pos, 2)?;
        let cmd = u16::from_le_bytes([cmd[0], cmd[1]]);
        match cmd {
            127 | 128 => {
                let height = if cmd == 127 {
                    f32::from_le_bytes(word(take(&mut pos, 4)?))
                } else {
                    let b = take(&mut pos, 2)?;
                    f32::from(u16::from_le_bytes([b[0], b[1]]))
                };
                if !height.is_finite() {
                    return Err("a layer height is not finite".into());
                }
                layers.push(Layer {
                    height,
                    loops: Vec::new(),
                });
            }
            129 | 130 => {
                let long = cmd == 130;
                let size = if long { 4 } else { 2 };
                let mut ints = [0i64; 3];
                for v in &mut ints {
                    let b = take(&mut pos, size)?;
                    *v = if long {
                        i64::from(i32::from_le_bytes(word(b)))
                    } else {
                        i64::from(u16::from_le_bytes([b[0], b[1]]))
                    };
                }
                let count = usize::try_from(ints[2])
                    .map_err(|_| format!("a polyline declares {} points", ints[2]))?;
                let raw = take(&mut pos, count.saturating_mul(2 * size))?;
                let points = raw
                    .chunks_exact(2 * size)
                    .map(|c| {
                        if long {
                            [
                                f32::from_le_bytes(word(c)),
                                f32::from_le_bytes(word(&c[4..])),
                            ]
                        } else {
                            [
                                f32::from(u16::from_le_bytes([c[0], c[1]])),
                                f32::from(u16::from_le_bytes([c[2], c[3]])),
                            ]
                        }
                    })
                    .collect();
                let layer = layers
                    .last_mut()
                    .ok_or("a polyline before any layer command")?;
                if let Some(lp) = to_loop(points, ints[1])? {
                    layer.loops.push(lp);
                }
            }
            other => {
                return Err(format!(
                    "unsupported binary command {other} at byte {}",
                    pos - 2
                ))
            }
        }
    }
    Ok(layers)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli_file::{write_cli_with, CliEncoding};

    #[test]
    fn both_encodings_read_back_what_was_written() {
        let layers = vec![
            Layer {
                height: 0.5,
                loops: vec![
                    Loop {
                        points: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]],
                        hole: false,
                    },
                    Loop {
                        points: vec![[0.5, 0.5], [0.5, 1.5], [1.5, 1.5], [1.5, 0.5]],
                        hole: true,
                    },
                ],
            },
            Layer {
                height: 1.25,
                loops: vec![Loop {
                    points: vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]],
                    hole: false,
                }],
            },
        ];
        let dir = tempfile::tempdir().unwrap();
        for encoding in [CliEncoding::Ascii, CliEncoding::Binary] {
            let path = dir.path().join("l.cli");
            write_cli_with(&path, &layers, 1.0, encoding).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            assert_eq!(read_cli(&bytes, &path).unwrap(), layers, "{encoding:?}");
            if encoding == CliEncoding::Ascii {
                // Cut after the first layer's lines, the rest would read as a shorter file.
                let cut = find(&bytes, b"$$LAYER/1.25").unwrap();
                let e = read_cli(&bytes[..cut], &path).unwrap_err().to_string();
                assert!(e.contains("cut short"), "{e}");
            }
        }
        let e = read_cli(b"$$HEADERSTART\n$$ASCII\n", Path::new("x.cli")).unwrap_err();
        assert!(e.to_string().starts_with("x.cli: "), "{e}");
    }

    #[test]
    fn coordinates_beyond_the_mesh_limit_are_refused() {
        let name = Path::new("far.cli");
        for (height, x) in [("1e20", "1"), ("0.5", "1e20"), ("0.5", "-3e8")] {
            let text = format!(
                "$$HEADERSTART\n$$ASCII\n$$HEADEREND\n$$GEOMETRYSTART\n$$LAYER/{height}\n\
                 $$POLYLINE/1,1,4,0,0,{x},0,0,1,0,0\n$$GEOMETRYEND\n"
            );
            let e = read_cli(text.as_bytes(), name).unwrap_err().to_string();
            assert!(
                e.starts_with("far.cli: ") && e.contains("out of range"),
                "{e}"
            );
        }
    }
}
