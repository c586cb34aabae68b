//! `Field.view` and `Field._repr_html_`: the viewer page of `pgvol view`, written to a file or
//! shown in a notebook.

use std::collections::HashMap;

use pyo3::prelude::*;

use crate::errors;
use crate::names;

/// The viewer options from the keywords of `Field.view`.
pub(crate) fn options(
    py: Python<'_>,
    section: Option<(String, f64)>,
    iso: f32,
    colours: Option<HashMap<String, String>>,
    max_res: usize,
    title: Option<String>,
) -> PyResult<pgvol::view::ViewOptions> {
    let mut options = pgvol::view::ViewOptions {
        section: match section {
            Some((axis, height)) => Some((names::axis(py, &axis)?, height)),
            None => None,
        },
        iso,
        max_res,
        title,
        ..Default::default()
    };
    for (part, value) in colours.unwrap_or_default() {
        let slot = match part.as_str() {
            "surface" => &mut options.colours.surface,
            "section" => &mut options.colours.section,
            "background" => &mut options.colours.background,
            _ => {
                return Err(errors::parameter(
                    py,
                    format!(
                        "unknown colour {part:?}: the colours are surface, section and \
                         background"
                    ),
                ))
            }
        };
        *slot = value;
    }
    Ok(options)
}

/// The page inside an iframe's `srcdoc`, so a notebook runs its scripts apart from its own.
pub(crate) fn iframe(page: &str) -> String {
    let escaped = page
        .replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    format!(
        "<iframe srcdoc=\"{escaped}\" style=\"width:100%;height:480px;border:0\" \
         sandbox=\"allow-scripts\"></iframe>"
    )
}
