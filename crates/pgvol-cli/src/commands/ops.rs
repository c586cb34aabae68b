//! `pgvol slice`, `pgvol offset` and `pgvol shell`: additive-manufacturing operations on a field,
//! read from a .pgv file or encoded on the fly from a mesh.

use std::path::Path;

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use glam::Vec3;
use pgvol_field::{CoefficientVolume, Grid};

use super::{MethodArg, OutputArgs, PathArg};
use crate::pipeline;

/// A field and the box of the shape it came from.
struct Source {
    volume: CoefficientVolume,
    bounds: (Vec3, Vec3),
    mesh: Option<pgvol_mesh::Mesh>,
    /// Distance from the surface within which the field is exact, when the file records it.
    band: Option<f32>,
}

fn is_pgv(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("pgv"))
}

/// Reads a .pgv file, or encodes a mesh on a grid of `res` nodes whose box is the mesh's box grown
/// by `grow` on every side, with exact distances `band` spacings beyond `grow`.
fn load(input: &Path, res: usize, grow: f32, extra_band: f32, quiet: bool) -> Result<Source> {
    if is_pgv(input) {
        let file = pgvol_format::read_pgv(input)?;
        let bounds = match file.header.source_bounds {
            Some([lo, hi]) => (Vec3::from(lo), Vec3::from(hi)),
            None => pgvol_ops::volume_bounds(&file.volume),
        };
        let band = file
            .header
            .metadata
            .get(super::files::BAND_KEY)
            .and_then(|b| b.parse::<f32>().ok())
            .filter(|b| b.is_finite() && *b > 0.0);
        return Ok(Source {
            volume: file.volume,
            bounds,
            mesh: None,
            band,
        });
    }
    let mesh = pipeline::load_mesh(input, quiet)?;
    let (lo, hi) = mesh.bounds().context("the mesh has no triangles")?;
    let pad = Vec3::splat(grow.max(0.0));
    let grid = Grid::cube_res(lo - pad, hi + pad, res).context("cannot make the sampling grid")?;
    let band = pipeline::ENCODE_BAND + extra_band / grid.spacing;
    let (volume, _, _) =
        pipeline::encode_banded(&mesh, grid, pgvol_field::Basis::Bspline3, band, quiet)?;
    Ok(Source {
        volume,
        bounds: (lo, hi),
        mesh: Some(mesh),
        band: None,
    })
}

/// Writes a volume as .pgv, or contours it into a mesh file, by the output's extension.
fn write_result(
    output: &Path,
    volume: &CoefficientVolume,
    source: &Source,
    op: &str,
    method: MethodArg,
) -> Result<usize> {
    if is_pgv(output) {
        let mut header = pgvol_format::pgv::header_for(volume, "interp", source.mesh.as_ref());
        header.metadata.insert("operation".into(), op.to_string());
        pgvol_format::write_pgv(
            output,
            &pgvol_format::PgvFile {
                header,
                volume: volume.clone(),
            },
        )?;
        return Ok(0);
    }
    pgvol_mesh::MeshFormat::from_path(output)?;
    let mesh = pipeline::decode(volume, 0.0, method, None)?;
    if mesh.triangles.is_empty() {
        bail!("{op}: the result is empty (the operation removed the whole shape)");
    }
    pgvol_mesh::write(output, &mesh)?;
    Ok(mesh.triangles.len())
}

fn check_output_name(output: &Path) -> Result<()> {
    if !is_pgv(output) {
        pgvol_mesh::MeshFormat::from_path(output)?;
    }
    Ok(())
}

fn finite_nonzero(name: &str, v: f32) -> Result<()> {
    if !v.is_finite() || v == 0.0 {
        bail!("{name} must be a finite non-zero number, got {v}");
    }
    Ok(())
}

fn refuse_narrow_band(source: &Source, input: &Path, reach: f32) -> Result<()> {
    if source.mesh.is_some() {
        return Ok(());
    }
    // The band recorded at encoding is exact and free; older files are measured instead.
    let (band, too_narrow) = match source.band {
        Some(band) => (band, reach.abs() + 2.0 * source.volume.grid.spacing >= band),
        None => (
            pgvol_ops::stored_band(&source.volume),
            pgvol_ops::needs_wider_band(&source.volume, reach),
        ),
    };
    if too_narrow {
        bail!(
            "{}: the file stores distances only within {band:.4} of the surface, too narrow for {reach}; \
             encode it again with a wider --band, or pass the mesh instead",
            input.display(),
        );
    }
    Ok(())
}

#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum AxisArg {
    X,
    Y,
    #[default]
    Z,
}

#[derive(Args)]
pub struct SliceArgs {
    /// A .pgv file, or a mesh (encoded on the fly at --res).
    pub input: PathArg,
    /// Output layers: .svg (viewable), .cli (Common Layer Interface, ASCII unless --binary) or
    /// .json.
    #[arg(short, long)]
    pub output: PathArg,
    /// Distance between layer planes, in model units.
    #[arg(long)]
    pub layer_height: f32,
    /// Height of the first plane (default: half a layer above the bottom of the shape).
    #[arg(long, allow_negative_numbers = true)]
    pub first: Option<f32>,
    /// Axis the layers are stacked along.
    #[arg(long, value_enum, default_value_t)]
    pub axis: AxisArg,
    /// Spacing of the 2D sampling grid in each layer (default: the field's grid spacing).
    #[arg(long)]
    pub resolution: Option<f32>,
    /// Contour simplification tolerance (default: a tenth of the grid spacing).
    #[arg(long)]
    pub tolerance: Option<f32>,
    /// Millimetres per model unit, written to the CLI header.
    #[arg(long, default_value_t = 1.0)]
    pub units_mm: f32,
    /// Write the .cli file's geometry in the binary form (little-endian long commands).
    #[arg(long)]
    pub binary: bool,
    /// Grid nodes per axis when the input is a mesh.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(4..=2048))]
    pub res: u32,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn slice(a: SliceArgs) -> Result<()> {
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let ext = match ext.as_deref() {
        Some(e @ ("svg" | "cli" | "json")) => e.to_string(),
        _ => bail!(
            "{}: unknown layer file extension (expected .svg, .cli or .json)",
            a.output.display()
        ),
    };
    if a.binary && ext != "cli" {
        bail!(
            "{}: --binary applies only to .cli outputs",
            a.output.display()
        );
    }
    if !(a.layer_height.is_finite() && a.layer_height > 0.0) {
        bail!(
            "--layer-height must be a positive number, got {}",
            a.layer_height
        );
    }
    let quiet = a.out.silent();
    let start = std::time::Instant::now();
    let source = load(&a.input, a.res as usize, 0.0, 0.0, quiet)?;
    let spacing = source.volume.grid.spacing;
    let axis = match a.axis {
        AxisArg::X => pgvol_ops::Axis::X,
        AxisArg::Y => pgvol_ops::Axis::Y,
        AxisArg::Z => pgvol_ops::Axis::Z,
    };
    let mut options =
        pgvol_ops::SliceOptions::new(axis, a.layer_height, a.resolution.unwrap_or(spacing));
    options.first = a.first;
    options.tolerance = a.tolerance.unwrap_or(spacing / 10.0);
    let t = std::time::Instant::now();
    let layers = pgvol_ops::slice_volume(&source.volume, source.bounds, &options)?;
    let slice_seconds = t.elapsed().as_secs_f64();
    match ext.as_str() {
        "svg" => pgvol_ops::write_svg(&a.output, &layers)?,
        "cli" => {
            let encoding = if a.binary {
                pgvol_ops::CliEncoding::Binary
            } else {
                pgvol_ops::CliEncoding::Ascii
            };
            pgvol_ops::write_cli_with(&a.output, &layers, a.units_mm, encoding)?
        }
        _ => pgvol_ops::write_slice_json(&a.output, &layers)?,
    }
    let loops: usize = layers.iter().map(|l| l.loops.len()).sum();
    let points: usize = layers
        .iter()
        .flat_map(|l| &l.loops)
        .map(|l| l.points.len())
        .sum();
    if a.out.json {
        let v = serde_json::json!({
            "output": a.output, "layers": layers.len(), "loops": loops, "points": points,
            "seconds": { "slice": slice_seconds, "total": start.elapsed().as_secs_f64() },
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else if !a.out.quiet {
        println!(
            "{}: {} layers, {} loops, {} points; sliced in {:.2} s",
            a.output.display(),
            layers.len(),
            loops,
            points,
            slice_seconds
        );
    }
    Ok(())
}

/// Options shared by the commands that turn a shape into a new shape.
#[derive(Args, Clone, Copy)]
pub struct ShapeOutputArgs {
    /// Grid nodes per axis when the input is a mesh.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(4..=2048))]
    pub res: u32,
    /// Contouring method for mesh outputs.
    #[arg(long, value_enum, default_value_t)]
    pub method: MethodArg,
}

#[derive(Args)]
pub struct OffsetArgs {
    /// A .pgv file, or a mesh (distances are then computed as far out as the offset needs).
    pub input: PathArg,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// Offset distance in model units: positive grows the shape, negative shrinks it.
    #[arg(long, allow_negative_numbers = true)]
    pub distance: f32,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn offset(a: OffsetArgs) -> Result<()> {
    finite_nonzero("--distance", a.distance)?;
    check_output_name(&a.output)?;
    let quiet = a.out.silent();
    let source = load(
        &a.input,
        a.shape.res as usize,
        a.distance.max(0.0),
        a.distance.abs(),
        quiet,
    )?;
    refuse_narrow_band(&source, &a.input, a.distance.abs())?;
    let volume = pgvol_ops::offset(&source.volume, a.distance)?;
    let triangles = write_result(
        &a.output,
        &volume,
        &source,
        &format!("offset {}", a.distance),
        a.shape.method,
    )?;
    report(&a.out, &a.output, triangles)
}

#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum SideArg {
    /// The wall lies inside the original surface.
    #[default]
    Inner,
    /// The wall lies outside the original surface.
    Outer,
    /// The wall is centred on the original surface.
    Centred,
}

#[derive(Args)]
pub struct ShellArgs {
    /// A .pgv file, or a mesh.
    pub input: PathArg,
    /// Output: .pgv, or a mesh (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    /// Wall thickness in model units.
    #[arg(long)]
    pub thickness: f32,
    /// Where the wall lies relative to the surface (ignored with --hollow, which keeps the
    /// outer surface and cuts a cavity inside).
    #[arg(long, value_enum, default_value_t)]
    pub side: SideArg,
    /// Hollow for printing: keep the outer surface and add an inner cavity at --thickness.
    #[arg(long)]
    pub hollow: bool,
    /// A drain hole through the wall, with --hollow: `x,y,z,dx,dy,dz,diameter` (a point inside the
    /// cavity, the direction out through the wall, the hole's diameter). Repeat for more holes.
    #[arg(long, value_parser = parse_drain, requires = "hollow")]
    pub drain: Vec<pgvol_ops::Drain>,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

fn parse_drain(s: &str) -> Result<pgvol_ops::Drain, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| {
            x.trim()
                .parse::<f32>()
                .map_err(|_| format!("'{x}' is not a number"))
        })
        .collect::<Result<_, _>>()?;
    if v.len() != 7 || v.iter().any(|x| !x.is_finite()) {
        return Err("expected seven finite numbers x,y,z,dx,dy,dz,diameter".into());
    }
    let direction = Vec3::new(v[3], v[4], v[5]);
    if direction.length() == 0.0 || v[6] <= 0.0 {
        return Err("the direction must be non-zero and the diameter positive".into());
    }
    Ok(pgvol_ops::Drain {
        point: Vec3::new(v[0], v[1], v[2]),
        direction: direction.normalize(),
        diameter: v[6],
    })
}

pub fn shell(a: ShellArgs) -> Result<()> {
    if !(a.thickness.is_finite() && a.thickness > 0.0) {
        bail!("--thickness must be a positive number, got {}", a.thickness);
    }
    check_output_name(&a.output)?;
    let quiet = a.out.silent();
    let grow = match (a.hollow, a.side) {
        (false, SideArg::Outer) => a.thickness,
        (false, SideArg::Centred) => a.thickness / 2.0,
        _ => 0.0,
    };
    let source = load(&a.input, a.shape.res as usize, grow, a.thickness, quiet)?;
    refuse_narrow_band(&source, &a.input, a.thickness)?;
    let (volume, op) = if a.hollow {
        (
            pgvol_ops::hollow(&source.volume, a.thickness, &a.drain)?,
            format!("hollow {}", a.thickness),
        )
    } else {
        let side = match a.side {
            SideArg::Inner => pgvol_ops::ShellSide::Inner,
            SideArg::Outer => pgvol_ops::ShellSide::Outer,
            SideArg::Centred => pgvol_ops::ShellSide::Centred,
        };
        (
            pgvol_ops::shell(&source.volume, a.thickness, side)?,
            format!("shell {}", a.thickness),
        )
    };
    let triangles = write_result(&a.output, &volume, &source, &op, a.shape.method)?;
    report(&a.out, &a.output, triangles)
}

fn report(out: &OutputArgs, output: &Path, triangles: usize) -> Result<()> {
    if out.json {
        println!(
            "{}",
            serde_json::to_string_pretty(
                &serde_json::json!({ "output": output, "triangles": triangles })
            )?
        );
    } else if !out.quiet {
        if triangles > 0 {
            println!("{}: {} triangles", output.display(), triangles);
        } else {
            println!("{}: written", output.display());
        }
    }
    Ok(())
}
