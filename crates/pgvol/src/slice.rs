//! Layers of closed contours for additive manufacturing, and their files.

use std::path::Path;

use pgvol_ops::{Axis, CliEncoding, Layer, LayerFrame, SliceOptions};

use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::progress::{self, Progress};
use crate::shape::Shape;

/// How to slice a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceSettings {
    /// Axis the layers stack along (default z).
    pub axis: Axis,
    /// Distance between layer planes, in model units (> 0).
    pub layer_height: f32,
    /// Height of the first plane in world coordinates; `None` (the default) for half a layer
    /// above the bottom.
    pub first: Option<f64>,
    /// Spacing of each layer's sampling grid; `None` (the default) for the field's spacing.
    pub resolution: Option<f32>,
    /// Simplification tolerance; `None` (the default) for a tenth of the resolution.
    pub tolerance: Option<f32>,
}

impl SliceSettings {
    /// Layers of `layer_height` along z with every other setting at its default.
    pub fn new(layer_height: f32) -> Self {
        Self {
            axis: Axis::Z,
            layer_height,
            first: None,
            resolution: None,
            tolerance: None,
        }
    }
}

/// The layers of `shape`.
pub fn slice(
    shape: &Shape,
    settings: &SliceSettings,
    progress: &dyn Progress,
) -> Result<Vec<Layer>> {
    let options = slice_options(shape, settings)?;
    let layers = progress::stage(progress, "slice", |_| {
        pgvol_ops::slice_volume(&shape.volume, shape.bounds, &options)
    })?;
    Ok(layers?)
}

/// The stage's options for slicing `shape` by `settings`.
pub(crate) fn slice_options(shape: &Shape, settings: &SliceSettings) -> Result<SliceOptions> {
    if !(settings.layer_height.is_finite() && settings.layer_height > 0.0) {
        return Err(Error::parameter(format!(
            "the layer height must be a positive number, got {}",
            settings.layer_height
        )));
    }
    let resolution = settings.resolution.unwrap_or(shape.volume.grid.spacing);
    let mut options = SliceOptions::new(settings.axis, settings.layer_height, resolution);
    // The stage slices in the field's local frame.
    let shift = layer_frame(shape, settings.axis).height;
    options.first = settings.first.map(|f| (f - shift) as f32);
    if let Some(t) = settings.tolerance {
        options.tolerance = t;
    }
    Ok(options)
}

/// Where layers of `shape` stacked along `axis` sit in the world: the field's frame offset, which
/// [`write_layers`] adds (in f64) to the local layer coordinates.
pub fn layer_frame(shape: &Shape, axis: Axis) -> LayerFrame {
    LayerFrame::new(axis, shape.volume.grid.offset)
}

/// Layer file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerFormat {
    /// SVG, one group per layer, viewable in a browser.
    Svg,
    /// Common Layer Interface, ASCII or binary geometry.
    Cli(CliEncoding),
    /// JSON: the layers as pgvol's own structures.
    Json,
}

impl LayerFormat {
    /// The format of `path`'s extension (`.svg`, `.cli`, `.json`); `binary` asks for the
    /// binary form of `.cli` and is refused for the others.
    pub fn from_path(path: &Path, binary: bool) -> Result<LayerFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let format = match ext.as_deref() {
            Some("svg") => LayerFormat::Svg,
            Some("json") => LayerFormat::Json,
            Some("cli") if binary => LayerFormat::Cli(CliEncoding::Binary),
            Some("cli") => LayerFormat::Cli(CliEncoding::Ascii),
            _ => {
                return Err(Error::new(
                    ErrorKind::OutputFile,
                    "unknown layer file extension (expected .svg, .cli or .json)",
                )
                .at(path))
            }
        };
        if binary && !matches!(format, LayerFormat::Cli(_)) {
            return Err(Error::parameter("binary output applies only to .cli files").at(path));
        }
        Ok(format)
    }
}

/// Millimetres per model unit written to Common Layer Interface headers unless told otherwise.
pub const DEFAULT_UNITS_MM: f32 = 1.0;

/// Writes `layers` to `path` atomically in world coordinates (`frame`, from [`layer_frame`],
/// added in f64); `units_mm` is millimetres per model unit (CLI header). Binary CLI, which
/// holds f32, is refused for layers so far from the origin that it would round them visibly.
pub fn write_layers(
    path: &Path,
    layers: &[Layer],
    format: LayerFormat,
    units_mm: f32,
    frame: &LayerFrame,
) -> Result<()> {
    if !(units_mm.is_finite() && units_mm > 0.0) {
        return Err(Error::parameter(format!(
            "millimetres per unit must be a positive number, got {units_mm}"
        )));
    }
    match format {
        LayerFormat::Svg => pgvol_ops::write_svg_in(path, layers, frame),
        LayerFormat::Cli(encoding) => {
            pgvol_ops::write_cli_in(path, layers, units_mm, encoding, frame)
        }
        LayerFormat::Json => pgvol_ops::write_slice_json_in(path, layers, frame),
    }
    .writing()
}
