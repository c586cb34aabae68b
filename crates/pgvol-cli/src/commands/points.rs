//! `pgvol points`: a surface through a point cloud, written as a .pgv file or a mesh.

use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::{at_input, GridArgs, MethodArg, OutputArgs, PathArg};
use super::ops::{check_dense_file, check_output_name, file_storage};
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

impl From<PointsMethodArg> for pgvol::PointsMethod {
    fn from(m: PointsMethodArg) -> Self {
        match m {
            PointsMethodArg::Spline => pgvol::PointsMethod::Spline,
            PointsMethodArg::Tangent => pgvol::PointsMethod::Tangent,
            PointsMethodArg::RbfWendland => pgvol::PointsMethod::RbfWendland,
            PointsMethodArg::RbfCubic => pgvol::PointsMethod::RbfCubic,
        }
    }
}

#[derive(Args)]
#[command(
    after_help = "Example: pgvol points scan.ply -o scan.glb --res 192 --method rbf-wendland"
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
    #[arg(long, value_name = "W", default_value_t = pgvol::ENCODE_BAND)]
    pub band: f32,
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

pub fn run(a: PointsArgs) -> Result<()> {
    let start = Instant::now();
    check_output_name(&a.output)?;
    check_dense_file(a.dense_file, &a.output)?;
    let quiet = a.out.silent();
    let bars = Bars::new(quiet);
    let cloud = pgvol::read_point_cloud(&a.input)?;
    let read_seconds = start.elapsed().as_secs_f64();
    let options = pgvol::PointsOptions {
        grid: a.grid.spec(),
        method: a.method.into(),
        band: a.band,
        support: a.support,
    };
    let t = Instant::now();
    let fitted = pgvol::points(&cloud, &options, &bars).map_err(|e| at_input(e, &a.input))?;
    let fit_seconds = t.elapsed().as_secs_f64();
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
    let write_seconds = t.elapsed().as_secs_f64();
    let grid = fitted.file.volume.grid;
    if a.out.json {
        return report::print(
            &serde_json::json!({
                "output": a.output, "grid": grid, "method": r.method, "points": r.points,
                "normals_estimated": r.normals_estimated, "spacing": r.spacing,
                "offset": r.offset, "centres": r.centres, "support": r.support,
                "iterations": r.iterations, "residual": r.residual, "converged": r.converged,
                "normals_reoriented": r.orientation.reoriented,
                "normals_flipped": r.orientation.flipped,
                "matrix_entries": r.matrix_entries, "bricks": r.bricks, "triangles": triangles,
            }),
            &Seconds::since(start).stages([
                ("read", read_seconds),
                ("normals", r.seconds_normals),
                ("solve", r.seconds_solve),
                ("fit", fit_seconds),
                ("write", write_seconds),
            ]),
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
    }
    Ok(())
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
    let layers = pgvol::read_layers(&a.input)?;
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
    let fitted =
        pgvol::contours(&layers, axis, &options, &bars).map_err(|e| at_input(e, &a.input))?;
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
    if pgvol::is_pgv(output) {
        pgvol::write_pgv(output, &fitted.file, &file_storage(dense_file))?;
        return Ok(0);
    }
    let decode = pgvol::DecodeOptions {
        method: contour.into(),
        ..Default::default()
    };
    let mesh = pgvol::decode(&fitted.file.volume, &decode, bars)?;
    pgvol::write_mesh(output, &mesh)?;
    Ok(mesh.triangles.len())
}
