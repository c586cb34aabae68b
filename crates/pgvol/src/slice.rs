//! Layers of closed contours for additive manufacturing, and their files.

use std::path::Path;

use glam::Vec3;
use pgvol_core::WordScale;
use pgvol_format::{CompactBrick, SlabReader, SlabSource};
use rayon::prelude::*;

use crate::decode_file::whole_file;
use pgvol_slice::{
    brick_counts, plane_axes, Axis, BrickLayer, BrickRef, BrickSource, CliEncoding, Layer,
    LayerFrame, LayerRanges, SliceOptions as StageOptions,
};

use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::field_value::Field;
use crate::progress::{self, Progress};

/// How to slice a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceOptions {
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

impl SliceOptions {
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

impl Field {
    /// The layers of the shape, and where they sit in the world.
    pub fn slice(&self, options: &SliceOptions, progress: &dyn Progress) -> Result<Sliced> {
        let stage = slice_options(self, options)?;
        let mut layers = progress::stage(progress, "slice", |update| {
            pgvol_slice::slice_volume(&self.file.volume, self.bounds, &stage, update)
        })??;
        crate::sharp::sharpen_sliced(&mut layers, &self.file.header, options.axis)?;
        let frame = layer_frame(self, options.axis);
        Ok(Sliced { layers, frame })
    }
}

/// The layers of a `.pgv` file and where they sit in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Sliced {
    /// The layers, bottom first.
    pub layers: Vec<Layer>,
    /// The world translation [`write_layers`] adds to the layers.
    pub frame: LayerFrame,
}

/// The layers of the `.pgv` file at `path`, as [`slice`] of the file's shape gives them. A
/// sparse file is decoded one slab of bricks at a time, only the slabs within reach of the
/// layers being sliced held, so memory is a window of the volume (and the file's bytes for a
/// version 1 file, which is read whole).
pub fn slice_file(
    path: impl AsRef<Path>,
    settings: &SliceOptions,
    progress: &dyn Progress,
) -> Result<Sliced> {
    let path = path.as_ref();
    let source = SlabSource::open(path).reading()?;
    let at = |e: Error| match e.path() {
        Some(_) => e,
        None => e.at(path),
    };
    let Some(reader) = SlabReader::from_source(&source, path).reading()? else {
        let shape = Field::from_file(whole_file(&source, path)?);
        return shape.slice(settings, progress).map_err(at);
    };
    let header = reader.header().clone();
    if !header.basis.is_separable() {
        let shape = Field::from_file(whole_file(&source, path)?);
        return shape.slice(settings, progress).map_err(at);
    }
    let mut layers = slice_reader(&reader, settings, 0..usize::MAX, progress).map_err(at)?;
    crate::sharp::sharpen_sliced(&mut layers, &header, settings.axis).map_err(at)?;
    Ok(Sliced {
        layers,
        frame: LayerFrame::new(settings.axis, header.grid.offset),
    })
}

/// The layers numbered `range` of slicing the file `reader` reads (a separable basis), slab by
/// slab, without the sharp section's corners.
pub(crate) fn slice_reader(
    reader: &SlabReader,
    settings: &SliceOptions,
    range: std::ops::Range<usize>,
    progress: &dyn Progress,
) -> Result<Vec<Layer>> {
    let header = reader.header();
    let grid = header.grid;
    let bounds = header_bounds(header);
    let options = options_for(grid.spacing, grid.offset, settings)?;
    let heights = pgvol_slice::layer_heights(bounds, &options)?.len();
    let total = heights.min(range.end).saturating_sub(range.start);
    let source = FileBricks {
        reader,
        grid_counts: brick_counts(grid.dims),
        word_scale: reader.word_scale(),
    };
    let mut layers = Vec::with_capacity(total);
    progress::check(progress)?;
    progress.stage("slice");
    pgvol_slice::slice_bricks(
        &source,
        &grid,
        header.basis,
        reader.background(),
        bounds,
        &options,
        range,
        &mut |layer| {
            layers.push(layer);
            progress.update(layers.len() as f64 / total.max(1) as f64);
            progress::check(progress)
        },
    )?;
    progress.finish();
    Ok(layers)
}

/// A sparse `.pgv` file's bricks, decoded slab by slab, kept as the file's 16-bit words where
/// it can (half the memory of the values: a layer lying in a large flat face holds two brick
/// layers of it).
struct FileBricks<'r, 'b> {
    reader: &'r SlabReader<'b>,
    /// The sparse grid's bricks per axis.
    grid_counts: [usize; 3],
    /// How words map to values ([`SlabReader::word_scale`]).
    word_scale: Option<WordScale>,
}

impl BrickSource for FileBricks<'_, '_> {
    type Error = Error;

    fn slab_bricks(&self) -> usize {
        self.reader.grid_bricks_per_slab()
    }

    fn slab(&self, axis: usize, slab: usize) -> Result<Vec<BrickLayer<'_>>> {
        let decoded = self.reader.compact_slab(axis, slab).reading()?;
        let per = self.slab_bricks();
        let [p, q] = plane_axes(axis);
        let first = slab * per;
        let count = per.min(self.grid_counts[axis].saturating_sub(first));
        let plane = [self.grid_counts[p], self.grid_counts[q]];
        let mut layers: Vec<BrickLayer> = (0..count).map(|_| BrickLayer::outside(plane)).collect();
        let at = |m: [usize; 3]| (m[axis] - first, m[p] + self.grid_counts[p] * m[q]);
        for m in decoded.inside {
            let (n, k) = at(m);
            layers[n].set_inside(k);
        }
        let mut stored = Vec::with_capacity(decoded.stored.len());
        for (m, brick) in decoded.stored {
            let brick = match (brick, self.word_scale) {
                (CompactBrick::Values(values), _) => BrickRef::Owned(values),
                (CompactBrick::Words(words), Some(scale)) => BrickRef::Words(words, scale),
                // `compact_slab` gives words only where the scale exists.
                (CompactBrick::Words(_), None) => {
                    return Err(Error::new(
                        ErrorKind::Internal,
                        "a slab came as words without their values",
                    ))
                }
            };
            stored.push((at(m), brick));
        }
        // Each brick's ranges read all its values: on the threads, not between the runs of
        // layers that keep them busy.
        let ranges: Vec<LayerRanges> = stored
            .par_iter()
            .map(|(_, brick)| brick.layer_ranges(axis))
            .collect();
        for (((n, k), brick), ranges) in stored.into_iter().zip(ranges) {
            layers[n].insert_ranged(k, brick, ranges);
        }
        Ok(layers.into_iter().map(BrickLayer::finish).collect())
    }
}

/// The stage's options for slicing `shape` by `settings`.
pub(crate) fn slice_options(shape: &Field, settings: &SliceOptions) -> Result<StageOptions> {
    let grid = &shape.file.volume.grid;
    options_for(grid.spacing, grid.offset, settings)
}

/// The box a file's shape lies in: the source's bounds where the header has them, else the
/// grid's.
pub(crate) fn header_bounds(header: &pgvol_format::PgvHeader) -> (Vec3, Vec3) {
    match header.source_bounds {
        Some([lo, hi]) => (Vec3::from(lo), Vec3::from(hi)),
        None => (header.grid.origin, header.grid.max_corner()),
    }
}

/// The stage's options for slicing a field of grid `spacing` and frame `offset` by `settings`.
pub(crate) fn options_for(
    spacing: f32,
    offset: glam::DVec3,
    settings: &SliceOptions,
) -> Result<StageOptions> {
    if !(settings.layer_height.is_finite() && settings.layer_height > 0.0) {
        return Err(Error::parameter(format!(
            "the layer height must be a positive number, got {}",
            settings.layer_height
        )));
    }
    let resolution = settings.resolution.unwrap_or(spacing);
    let mut options = StageOptions::new(settings.axis, settings.layer_height, resolution);
    // The stage slices in the field's local frame.
    let shift = LayerFrame::new(settings.axis, offset).height;
    options.first = settings.first.map(|f| (f - shift) as f32);
    if let Some(t) = settings.tolerance {
        options.tolerance = t;
    }
    Ok(options)
}

/// Where layers of `shape` stacked along `axis` sit in the world: the field's frame offset, which
/// [`write_layers`] adds (in f64) to the local layer coordinates.
fn layer_frame(shape: &Field, axis: Axis) -> LayerFrame {
    LayerFrame::new(axis, shape.file.volume.grid.offset)
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
    pub fn from_path(path: impl AsRef<Path>, binary: bool) -> Result<LayerFormat> {
        let path = path.as_ref();
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

/// Writes `layers` to `path` atomically in world coordinates (`frame`, from [`Sliced::frame`],
/// added in f64); `units_mm` is millimetres per model unit (CLI header). Binary CLI, which
/// holds f32, is refused for layers so far from the origin that it would round them visibly.
pub fn write_layers(
    path: impl AsRef<Path>,
    layers: &[Layer],
    format: LayerFormat,
    units_mm: f32,
    frame: &LayerFrame,
) -> Result<()> {
    let path = path.as_ref();
    if !(units_mm.is_finite() && units_mm > 0.0) {
        return Err(Error::parameter(format!(
            "millimetres per unit must be a positive number, got {units_mm}"
        )));
    }
    match format {
        LayerFormat::Svg => pgvol_slice::write_svg_in(path, layers, frame),
        LayerFormat::Cli(encoding) => {
            pgvol_slice::write_cli_in(path, layers, units_mm, encoding, frame)
        }
        LayerFormat::Json => pgvol_slice::write_slice_json_in(path, layers, frame),
    }
    .writing()
}
