//! `pgvol points`: a surface through a point cloud, written as a .pgv file or a mesh.

use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::{at_input, GridArgs, MethodArg, OutputArgs, PathArg};
use super::args::{check_dense_file, check_output_name, file_storage};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::{self, Seconds};

/// The field through the points.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum PointsMethodArg {
    /// Cubic B-spline coefficients fitted directly to the points and their off-surface
    /// constraints by weighted least squares, with a smoothness term (sparse, conjugate
    /// gradients).
    #[default]
    Spline,
    /// Blended tangent-plane distance of the nearest points at the grid nodes, interpolated
    /// by the cubic B-spline volume: no system to solve.
    Tangent,
    /// Compactly supported Wendland RBFs (sparse system, conjugate gradients) correcting the
    /// spline fit so the field interpolates the points exactly.
    RbfWendland,
    /// Global cubic RBFs r³ with a linear term (dense solve): at most
    /// 2000 points.
    RbfCubic,
}

impl From<PointsMethodArg> for pgvol::reconstruct::PointsMethod {
    fn from(m: PointsMethodArg) -> Self {
        match m {
            PointsMethodArg::Spline => pgvol::reconstruct::PointsMethod::Spline,
            PointsMethodArg::Tangent => pgvol::reconstruct::PointsMethod::Tangent,
            PointsMethodArg::RbfWendland => pgvol::reconstruct::PointsMethod::RbfWendland,
            PointsMethodArg::RbfCubic => pgvol::reconstruct::PointsMethod::RbfCubic,
        }
    }
}

/// The planes of `--sections`: an axis and the heights along it.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionsArg {
    pub axis: pgvol::Axis,
    pub heights: Vec<f32>,
}

/// Parses `AXIS:H1,H2,...` (axis x, y or z; heights finite and below 1e8 in magnitude).
fn parse_sections(s: &str) -> Result<SectionsArg, String> {
    let (name, list) = s
        .split_once(':')
        .ok_or_else(|| format!("expected AXIS:H1,H2,... (e.g. z:0,0.5), got '{s}'"))?;
    let name = name.trim().to_ascii_lowercase();
    let axis = match name.as_str() {
        "x" => pgvol::Axis::X,
        "y" => pgvol::Axis::Y,
        "z" => pgvol::Axis::Z,
        other => return Err(format!("the axis must be x, y or z, got '{other}'")),
    };
    if list.trim().is_empty() {
        return Err(format!("no heights after '{name}:' (e.g. {name}:0,0.5)"));
    }
    let heights = list
        .split(',')
        .map(|h| {
            let h = h.trim();
            match h.parse::<f32>() {
                Ok(v) if v.is_finite() && v.abs() < pgvol::slicing::MAX_LAYER_COORDINATE => Ok(v),
                _ => Err(format!(
                    "the height '{h}' is not a finite number below 1e8 in magnitude"
                )),
            }
        })
        .collect::<Result<Vec<f32>, String>>()?;
    Ok(SectionsArg { axis, heights })
}

/// Where the sections go when --sections-out is not given: the output's name with
/// `.sections.json` in place of its extension.
pub fn default_sections_path(output: &std::path::Path) -> std::path::PathBuf {
    output.with_extension("sections.json")
}

#[derive(Args)]
#[command(
    after_help = "Examples:\n  pgvol points scan.ply -o scan.glb --res 192 --method rbf-wendland\n  \
                  pgvol points scan.ply -o scan.pgv --method rbf-wendland --sections z:0,0.5,1   \
                  (also writes scan.sections.json)\n  \
                  pgvol points scan.xyz -o scan.pgv --method rbf-cubic --sections x:-2,2 \
                  --sections-out cuts.svg"
)]
pub struct PointsArgs {
    /// Point cloud: PLY (vertices, with nx ny nz if present) or text .xyz/.csv/.txt/.pts
    /// (x y z or x y z nx ny nz per line). Without normals they are estimated and oriented.
    pub input: PathArg,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// How the field through the points is built.
    #[arg(long, value_enum, default_value_t)]
    pub method: PointsMethodArg,
    /// Wendland support radius in model units [default: 3 point spacings, at least 2 grid
    /// spacings].
    #[arg(long)]
    pub support: Option<f32>,
    /// Node values kept within W grid spacings of the points, clamped beyond. Offsets, shells
    /// and levels read from the file are exact within W − 2 spacings (the cubic B-spline's
    /// support blends in the clamp), as `pgvol info` shows.
    #[arg(long, value_name = "W", default_value_t = pgvol::limits::ENCODE_BAND)]
    pub band: f32,
    /// Contouring method for mesh outputs.
    #[arg(long = "contour", value_enum, default_value_t)]
    pub contour: MethodArg,
    /// Also write cross-sections in planes normal to AXIS (x, y or z) at heights H1, H2, ...
    /// (the cloud's units, within the grid's box), cut from the method's own field before it
    /// is resampled on the grid: the spline fit plus the Wendland RBFs for rbf-wendland, the
    /// cubic RBF for rbf-cubic, the tangent-plane field for tangent, the fitted B-spline for
    /// spline. A height whose plane misses the surface is warned of and written empty.
    #[arg(long, value_name = "AXIS:H1,H2,...", value_parser = parse_sections, allow_hyphen_values = true)]
    pub sections: Option<SectionsArg>,
    /// Layer file for --sections: .json, .svg or .cli (ASCII), as `pgvol slice` writes them
    /// [default: the output's name with .sections.json for its extension].
    #[arg(long, value_name = "FILE", requires = "sections")]
    pub sections_out: Option<PathArg>,
    /// Spacing of each section plane's 2D sampling grid, in the cloud's units [default: the
    /// grid spacing]; contours are simplified to a tenth of it.
    #[arg(long, value_name = "H", requires = "sections")]
    pub sections_resolution: Option<f32>,
    /// Write a .pgv output with every coefficient as f32 instead of the sparse, compressed
    /// bricks around the surface.
    #[arg(long)]
    pub dense_file: bool,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn run(a: PointsArgs) -> Result<()> {
    let start = Instant::now();
    check_output_name(&a.output)?;
    check_dense_file(a.dense_file, &a.output)?;
    let sections_out = a.sections.as_ref().map(|_| {
        a.sections_out
            .clone()
            .unwrap_or_else(|| default_sections_path(&a.output))
    });
    let sections_format = match &sections_out {
        Some(path) => {
            let format = pgvol::io::LayerFormat::from_path(path, false)
                .map_err(|e| anyhow::anyhow!("--sections-out: {e}"))?;
            a.out.check(path)?;
            Some(format)
        }
        None => None,
    };
    let quiet = a.out.silent();
    let bars = Bars::new(quiet);
    let cloud = pgvol::io::read_point_cloud(&a.input)?;
    let read_seconds = start.elapsed().as_secs_f64();
    let options = pgvol::PointsOptions {
        grid: a.grid.spec(),
        method: a.method.into(),
        band: a.band,
        support: a.support,
    };
    let t = Instant::now();
    let (fitted, sections) = match &a.sections {
        Some(s) => {
            let settings = pgvol::reconstruct::SectionOptions {
                axis: s.axis,
                heights: s.heights.clone(),
                resolution: a.sections_resolution,
            };
            let (fitted, sections) =
                pgvol::reconstruct::points_with_sections(&cloud, &options, &settings, &bars)
                    .map_err(|e| sections_error(e, &a.input))?;
            (fitted, Some(sections))
        }
        None => (
            pgvol::reconstruct::points(&cloud, &options, &bars)
                .map_err(|e| at_input(e, &a.input))?,
            None,
        ),
    };
    let fit_seconds = t.elapsed().as_secs_f64() - sections.as_ref().map_or(0.0, |s| s.seconds);
    let r = &fitted.report;
    if r.normals_estimated && !quiet {
        eprintln!(
            "note: {} has no normals; they were estimated (PCA of 12 neighbours) and oriented \
             along a minimum spanning tree",
            a.input.display()
        );
    }
    let t = Instant::now();
    let triangles = write_output(&a.output, &fitted, a.contour, a.dense_file, &bars)?;
    let grid = fitted.file.volume.grid;
    if let (Some(s), Some(path), Some(format), Some(arg)) =
        (&sections, &sections_out, sections_format, &a.sections)
    {
        let frame = pgvol::reconstruct::LayerFrame::new(arg.axis, grid.offset);
        pgvol::io::write_layers(
            path,
            &s.layers,
            format,
            pgvol::limits::DEFAULT_UNITS_MM,
            &frame,
        )?;
    }
    let write_seconds = t.elapsed().as_secs_f64();
    let sections_json = match (&sections, &sections_out, &a.sections) {
        (Some(s), Some(path), Some(arg)) => {
            let heights: Vec<f32> = s.layers.iter().map(|l| l.height).collect();
            let loops: Vec<usize> = s.layers.iter().map(|l| l.loops.len()).collect();
            serde_json::json!({
                "output": path, "axis": arg.axis, "heights": heights, "loops": loops,
                "empty": s.empty, "resolution": s.resolution,
            })
        }
        _ => serde_json::Value::Null,
    };
    if a.out.json {
        let mut seconds = Seconds::since(start).stages([
            ("read", read_seconds),
            ("normals", r.seconds_normals),
            ("solve", r.seconds_solve),
            ("fit", fit_seconds),
        ]);
        if let Some(s) = &sections {
            seconds = seconds.stage("sections", s.seconds);
        }
        return report::print(
            &serde_json::json!({
                "output": a.output, "grid": grid, "method": r.method, "points": r.points,
                "normals_estimated": r.normals_estimated, "spacing": r.spacing,
                "offset": r.offset, "centres": r.centres, "support": r.support,
                "iterations": r.iterations, "residual": r.residual, "converged": r.converged,
                "normals_reoriented": r.orientation.reoriented,
                "normals_flipped": r.orientation.flipped,
                "matrix_entries": r.matrix_entries, "bricks": r.bricks, "triangles": triangles,
                "sections": sections_json,
            }),
            &seconds.stage("write", write_seconds),
        );
    }
    if !a.out.quiet {
        let solve = if r.centres > 0 {
            let unit = if r.method == "spline" {
                "constraints"
            } else {
                "centres"
            };
            format!(
                ", {} {unit}, {} iterations, residual {:.1e}",
                r.centres, r.iterations, r.residual
            )
        } else {
            String::new()
        };
        let what = if triangles > 0 {
            format!("{triangles} triangles")
        } else {
            "written".to_string()
        };
        outln!(
            "{}: {what}; {} points by {}{solve}, {}^3 grid, {:.2} s",
            a.output.display(),
            r.points,
            r.method,
            grid.dims[0],
            start.elapsed().as_secs_f64()
        );
        if let (Some(s), Some(path)) = (&sections, &sections_out) {
            let loops: usize = s.layers.iter().map(|l| l.loops.len()).sum();
            let n = s.layers.len();
            outln!(
                "{}: {n} section{}, {loops} loops, cut from the {} field in {:.2} s",
                path.display(),
                if n == 1 { "" } else { "s" },
                r.method,
                s.seconds
            );
        }
    }
    Ok(())
}

/// A library error of a fit with sections: problems with the planes name the option, the others
/// the input.
fn sections_error(e: pgvol::Error, input: &std::path::Path) -> anyhow::Error {
    let about =
        |what: &str| e.kind() == pgvol::ErrorKind::BadParameter && e.message().contains(what);
    if about("sections' resolution") || about("nodes per plane") {
        anyhow::anyhow!("--sections-resolution: {e}")
    } else if about("section height") {
        anyhow::anyhow!("--sections: {e}")
    } else {
        at_input(e, input).into()
    }
}

#[derive(Args)]
#[command(after_help = "Example: pgvol contours scan.json -o scan.glb --res 192")]
pub struct ContoursArgs {
    /// A stack of closed planar contours: the .json, .cli (ASCII or binary) or .svg layer
    /// files `pgvol slice` writes.
    pub input: PathArg,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// Axis the planes are stacked along (as given to `pgvol slice`).
    #[arg(long, value_enum, default_value_t)]
    pub axis: super::ops::AxisArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// How the field between the planes is built: spline (default) interpolates each plane's
    /// 2D signed distance across the planes by a cubic spline along the axis; the RBF methods
    /// fit points along the loops and over the caps.
    #[arg(long, value_enum, default_value_t)]
    pub method: PointsMethodArg,
    /// Contouring method for mesh outputs.
    #[arg(long = "contour", value_enum, default_value_t)]
    pub contour: MethodArg,
    /// Write a .pgv output with every coefficient as f32 instead of the sparse, compressed
    /// bricks around the surface.
    #[arg(long)]
    pub dense_file: bool,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn contours(a: ContoursArgs) -> Result<()> {
    let start = Instant::now();
    check_output_name(&a.output)?;
    check_dense_file(a.dense_file, &a.output)?;
    let bars = Bars::new(a.out.silent());
    let layers = pgvol::io::read_layers(&a.input)?;
    let options = pgvol::PointsOptions {
        grid: a.grid.spec(),
        method: a.method.into(),
        ..Default::default()
    };
    let axis = match a.axis {
        super::ops::AxisArg::X => pgvol::Axis::X,
        super::ops::AxisArg::Y => pgvol::Axis::Y,
        super::ops::AxisArg::Z => pgvol::Axis::Z,
    };
    let t = Instant::now();
    let fitted = pgvol::reconstruct::contours(&layers, axis, &options, &bars)
        .map_err(|e| at_input(e, &a.input))?;
    let fit_seconds = t.elapsed().as_secs_f64();
    let triangles = write_output(&a.output, &fitted, a.contour, a.dense_file, &bars)?;
    let loops: usize = layers.iter().map(|l| l.loops.len()).sum();
    if a.out.json {
        return report::print(
            &serde_json::json!({
                "output": a.output, "grid": fitted.file.volume.grid, "layers": layers.len(),
                "loops": loops, "points": fitted.report.points, "method": fitted.report.method,
                "triangles": triangles,
            }),
            &Seconds::since(start).stage("fit", fit_seconds),
        );
    }
    if !a.out.quiet {
        outln!(
            "{}: {} layers, {loops} loops; {} constraint points by {}, {:.2} s",
            a.output.display(),
            layers.len(),
            fitted.report.points,
            fitted.report.method,
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Writes a fitted volume as .pgv (dense with `dense_file`) or contours it into a mesh; returns
/// the triangles written.
fn write_output(
    output: &std::path::Path,
    fitted: &pgvol::Reconstructed,
    contour: MethodArg,
    dense_file: bool,
    bars: &Bars,
) -> Result<usize> {
    if pgvol::io::is_pgv(output) {
        pgvol::io::write_pgv(output, &fitted.file, &file_storage(dense_file))?;
        return Ok(0);
    }
    let decode = pgvol::DecodeOptions {
        method: contour.into(),
        ..Default::default()
    };
    let mesh = pgvol::Field::from_file(fitted.file.clone()).to_mesh(&decode, bars)?;
    pgvol::io::write_mesh(output, &mesh)?;
    Ok(mesh.triangles.len())
}
