//! Reading back the SVG layer files `pgvol slice` writes: one `<g data-height="z">` per layer
//! holding one path of `M`, `L` and `Z` commands, in tile coordinates that the root's
//! `data-u-offset` and `data-v-offset` turn back into layer coordinates. Other SVG is refused
//! with what would work: these files are pictures first, and a general SVG (transforms, curves,
//! units) says nothing of heights.

use std::path::Path;

use pgvol_core::FileError;

use crate::slice::{Layer, Loop};

/// The layers of an SVG layer file held in `text`; `name` labels errors.
pub fn read_svg(text: &str, name: &Path) -> Result<Vec<Layer>, FileError> {
    read(text).map_err(|problem| FileError::new(name, problem))
}

fn read(text: &str) -> Result<Vec<Layer>, String> {
    let root = tags(text)
        .find(|t| t.starts_with("<svg"))
        .ok_or("not an SVG file: no <svg> element")?;
    let offset = |key: &str| -> Result<f32, String> {
        let value = attribute(root, key).ok_or_else(|| {
            format!(
                "the <svg> element has no {key}: only the SVG files `pgvol slice` writes carry \
                 layer coordinates; slice again, or give the .json or .cli layer file"
            )
        })?;
        number(value).ok_or_else(|| format!("{key}=\"{value}\" is not a finite number"))
    };
    if !text.trim_end().ends_with("</svg>") {
        return Err(
            "the file ends before its closing </svg>: it was cut short, and its last \
             layers would be missing; slice again to write it whole"
                .into(),
        );
    }
    let (u_offset, v_offset) = (offset("data-u-offset")?, offset("data-v-offset")?);
    let mut layers: Vec<Layer> = Vec::new();
    for tag in tags(text) {
        if tag.starts_with("<g ") {
            let Some(height) = attribute(tag, "data-height") else {
                continue;
            };
            let height = number(height).ok_or_else(|| {
                format!(
                    "data-height=\"{height}\" is not a finite number (layer {})",
                    layers.len()
                )
            })?;
            layers.push(Layer {
                height,
                loops: Vec::new(),
            });
        } else if tag.starts_with("<path") {
            let Some(layer) = layers.last_mut() else {
                return Err("a <path> before the first layer's <g data-height=...>".into());
            };
            let d = attribute(tag, "d").ok_or("a <path> without d")?;
            let loops = path_loops(d, u_offset, v_offset)
                .map_err(|e| format!("layer at {}: {e}", layer.height))?;
            layer.loops.extend(loops);
        }
    }
    if layers.iter().all(|l| l.loops.is_empty()) {
        return Err("no layer with closed contours (<g data-height=...> holding a <path>)".into());
    }
    if let Some(problem) = crate::layer_frame::layer_coordinate_problem(&layers) {
        return Err(problem);
    }
    Ok(layers)
}

/// The element tags `<...>` of `text`, in order (comments and declarations included).
fn tags(text: &str) -> impl Iterator<Item = &str> {
    text.match_indices('<').filter_map(move |(start, _)| {
        let end = text[start..].find('>')?;
        Some(&text[start..=start + end])
    })
}

/// The value of `key="..."` in a tag.
fn attribute<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let pattern = format!(" {key}=\"");
    let start = tag.find(&pattern)? + pattern.len();
    let end = tag[start..].find('"')?;
    Some(&tag[start..start + end])
}

fn number(s: &str) -> Option<f32> {
    s.trim().parse::<f32>().ok().filter(|v| v.is_finite())
}

/// Closed loops of a path of absolute `M x y`, `L x y` and `Z` commands in layer coordinates.
fn path_loops(d: &str, u_offset: f32, v_offset: f32) -> Result<Vec<Loop>, String> {
    let mut loops = Vec::new();
    let mut current: Vec<[f32; 2]> = Vec::new();
    let mut tokens = d
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .peekable();
    while let Some(token) = tokens.next() {
        let (command, rest) = token.split_at(token.chars().next().map_or(0, char::len_utf8));
        match command {
            "M" | "L" => {
                if command == "M" && !current.is_empty() {
                    return Err("a subpath is not closed by Z".into());
                }
                let x = if rest.is_empty() {
                    tokens.next().unwrap_or_default()
                } else {
                    rest
                };
                let y = tokens.next().unwrap_or_default();
                let (Some(x), Some(y)) = (number(x), number(y)) else {
                    return Err(format!("'{token}' needs two finite coordinates"));
                };
                let (u, v) = (x + u_offset, v_offset - y);
                if !(u.is_finite() && v.is_finite()) {
                    return Err(format!(
                        "'{token}' is beyond single precision once the offsets are added"
                    ));
                }
                current.push([u, v]);
            }
            "Z" | "z" if rest.is_empty() => {
                if current.len() >= 3 {
                    loops.push(Loop {
                        points: std::mem::take(&mut current),
                        hole: false,
                    });
                } else {
                    current.clear();
                }
            }
            _ => {
                return Err(format!(
                    "path command '{token}' is not one pgvol writes (absolute M, L and Z only)"
                ))
            }
        }
    }
    if !current.is_empty() {
        return Err("the path's last subpath is not closed by Z".into());
    }
    Ok(loops)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write_svg;

    fn square(c: f32, r: f32) -> Loop {
        Loop {
            points: vec![
                [c - r, c - r],
                [c + r, c - r],
                [c + r, c + r],
                [c - r, c + r],
            ],
            hole: false,
        }
    }

    #[test]
    fn what_write_svg_writes_reads_back() {
        let layers = vec![
            Layer {
                height: 0.5,
                loops: vec![square(1.0, 2.0), square(1.0, 0.5)],
            },
            Layer {
                height: 1.5,
                loops: vec![],
            },
            Layer {
                height: 2.5,
                loops: vec![square(-3.0, 1.25)],
            },
        ];
        let dir = std::env::temp_dir().join(format!("pgvol-svg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("layers.svg");
        write_svg(&path, &layers).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let back = read_svg(&text, Path::new("layers.svg")).unwrap();
        assert_eq!(back.len(), 3);
        // Cut anywhere, the file is refused rather than read as its first layers.
        let whole = text.trim_end().len();
        for cut in (0..whole).step_by(7) {
            let e = read_svg(&text[..cut], Path::new("layers.svg")).unwrap_err();
            let e = e.to_string();
            assert!(
                e.contains("cut short") || e.contains("no <svg>"),
                "{cut}: {e}"
            );
        }
        for (a, b) in layers.iter().zip(&back) {
            assert_eq!(a.height, b.height);
            assert_eq!(a.loops.len(), b.loops.len());
            for (la, lb) in a.loops.iter().zip(&b.loops) {
                for (p, q) in la.points.iter().zip(&lb.points) {
                    assert!((p[0] - q[0]).abs() < 1e-5 && (p[1] - q[1]).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn other_svg_is_refused_by_name_with_what_would_work() {
        let name = Path::new("drawing.svg");
        for (bad, says) in [
            ("", "no <svg>"),
            ("<svg viewBox=\"0 0 1 1\"><path d=\"M0 0 L1 0 L1 1 Z\"/></svg>", ".json or .cli"),
            (
                "<svg data-u-offset=\"0\" data-v-offset=\"0\"><g data-height=\"1\"><path d=\"M0 0 C1 0 1 1 0 1 Z\"/></g></svg>",
                "absolute M, L and Z",
            ),
            (
                "<svg data-u-offset=\"0\" data-v-offset=\"0\"><g data-height=\"1\"><path d=\"M0 0 L1 0 L1 1\"/></g></svg>",
                "not closed",
            ),
            (
                "<svg data-u-offset=\"0\" data-v-offset=\"0\"><g data-height=\"x\"></g></svg>",
                "not a finite number",
            ),
            (
                "<svg data-u-offset=\"0\" data-v-offset=\"0\"><g data-height=\"1\"><path d=\"M0 0 L1 \"/></g></svg>",
                "two finite coordinates",
            ),
            (
                "<svg data-u-offset=\"3e38\" data-v-offset=\"0\"><g data-height=\"1\"><path d=\"M3e38 0 L1 0 L1 1 Z\"/></g></svg>",
                "beyond single precision",
            ),
            (
                "<svg data-u-offset=\"0\" data-v-offset=\"0\"><g data-height=\"1\"><path d=\"M1e20 0 L1 0 L1 1 Z\"/></g></svg>",
                "coordinate 1e20 in layer 0",
            ),
            (
                "<svg data-u-offset=\"0\" data-v-offset=\"0\"><g data-height=\"-1e21\"><path d=\"M0 0 L1 0 L1 1 Z\"/></g></svg>",
                "out of range",
            ),
        ] {
            let e = read_svg(bad, name).unwrap_err().to_string();
            assert!(e.starts_with("drawing.svg") && e.contains(says), "{bad}: {e}");
        }
    }
}
