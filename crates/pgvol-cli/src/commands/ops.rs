//! `pgvol slice`, `pgvol offset` and `pgvol shell`: additive-manufacturing operations on a field,
//! read from a .pgv file or encoded on the fly from a mesh.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::{
    at_input, grid_error, parse_angle, OutputArgs, PathArg, ShapeOutputArgs, SharpArg, SignArg,
};
use super::lattice::{build_lattice, write_solid, GradeArgs, StyleArg};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::{self, Seconds};

/// Writes an operation's result as .pgv, or contours it into a mesh file, by the output's
/// extension; returns the triangles written (0 for a .pgv).
fn write_result(
    output: &Path,
    result: &pgvol::Field,
    operation: &str,
    args: &ShapeOutputArgs,
    progress: &Bars,
) -> Result<usize> {
    if pgvol::io::is_pgv(output) {
        result.save(output, &args.storage())?;
        return Ok(0);
    }
    let mesh = result
        .to_mesh(&args.decode_options(), progress)
        .map_err(|e| match e.kind() {
            pgvol::ErrorKind::EmptyResult => anyhow::anyhow!(
                "{operation}: the result is empty: {e}; either the operation removes the whole \
                 shape, or what it leaves is thinner than the grid's spacing {} holds, which a \
                 finer grid (--res) would show",
                result.grid().spacing
            ),
            _ => e.into(),
        })?;
    pgvol::io::write_mesh(output, &mesh)?;
    Ok(mesh.triangles.len())
}

#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum AxisArg {
    X,
    Y,
    #[default]
    Z,
}

#[derive(Args)]
#[command(after_help = "Example: pgvol slice part.pgv -o part.cli --layer-height 0.05 --binary")]
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
    /// Height of the first plane, in the model's own coordinates however far from the origin
    /// (default: half a layer above the bottom of the shape).
    #[arg(long, allow_negative_numbers = true)]
    pub first: Option<f64>,
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
    #[arg(long, default_value_t = pgvol::limits::DEFAULT_UNITS_MM)]
    pub units_mm: f32,
    /// Write the .cli file's geometry in the binary form (little-endian long commands).
    #[arg(long)]
    pub binary: bool,
    /// Grid nodes per axis when the input is a mesh: finer than the 128 of the other commands,
    /// since layers are traced at the field's spacing and walls thinner than about one spacing
    /// drop out of them.
    #[arg(long, default_value_t = pgvol::limits::SLICE_RES as u32, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
    pub res: u32,
    /// How inside is told from outside when the input is a mesh.
    #[arg(long, value_enum, default_value_t)]
    pub sign: SignArg,
    /// When the input is a mesh: `auto` stores the exact vertices of the cells at its creases
    /// and corners with the field, as `encode --sharp auto` does, so that the layers keep the
    /// corners of its sections; `off` stores none. A .pgv file's layers keep the corners its
    /// own section marks [default: off].
    #[arg(long, value_enum)]
    pub sharp: Option<SharpArg>,
    /// Crease angle in degrees for `--sharp auto` (see `encode --help`).
    #[arg(long, value_name = "DEG", default_value_t = pgvol::sharp::DEFAULT_SHARP_ANGLE, value_parser = parse_angle)]
    pub sharp_angle: f32,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn slice(a: SliceArgs) -> Result<()> {
    let format =
        pgvol::io::LayerFormat::from_path(&a.output, a.binary).map_err(|e| match e.kind() {
            pgvol::ErrorKind::BadParameter => anyhow::anyhow!("--binary: {e}"),
            _ => e.into(),
        })?;
    let quiet = a.out.silent();
    let bars = Bars::new(quiet);
    let start = Instant::now();
    let settings = pgvol::SliceOptions {
        axis: match a.axis {
            AxisArg::X => pgvol::Axis::X,
            AxisArg::Y => pgvol::Axis::Y,
            AxisArg::Z => pgvol::Axis::Z,
        },
        layer_height: a.layer_height,
        first: a.first,
        resolution: a.resolution,
        tolerance: a.tolerance,
    };
    let sign: pgvol::SignMode = a.sign.into();
    let t = Instant::now();
    // A .pgv file is sliced as it is read, a window of its bricks at a time.
    let is_pgv = pgvol::io::is_pgv(&a.input);
    if is_pgv && a.sharp.is_some() {
        anyhow::bail!(
            "{}: --sharp applies to mesh inputs; a .pgv file's layers keep the corners its own \
             sharp section marks (encode the mesh with --sharp auto to store one)",
            a.input.display()
        );
    }
    let sliced = if is_pgv && sign == pgvol::SignMode::Auto {
        pgvol::stream::slice_file(&a.input, &settings, &bars).map_err(|e| at_input(e, &a.input))?
    } else {
        let open = pgvol::OpenOptions {
            res: a.res as usize,
            sign,
            sharp: a.sharp.unwrap_or_default().options(a.sharp_angle),
            ..Default::default()
        };
        let shape = pgvol::Field::open(&a.input, &open, &bars)?;
        shape
            .slice(&settings, &bars)
            .map_err(|e| at_input(e, &a.input))?
    };
    let slice_seconds = t.elapsed().as_secs_f64();
    let layers = sliced.layers;
    let loops: usize = layers.iter().map(|l| l.loops.len()).sum();
    if loops == 0 {
        // Nothing to build: refuse rather than write a file of empty layers.
        let heights = match (layers.first(), layers.last()) {
            (Some(f), Some(l)) if layers.len() > 1 => {
                format!("{} layers from {} to {}", layers.len(), f.height, l.height)
            }
            (Some(f), _) => format!("one layer, at {}", f.height),
            _ => {
                anyhow::bail!(
                    "{}: no layer holds a contour: a layer height of {} puts no layer within \
                     the shape's extent along its axis, so the part is thinner than one layer \
                     (a mesh without thickness, a flat or open sheet, has none); a smaller \
                     --layer-height, or --first at a height within the part, would",
                    a.input.display(),
                    a.layer_height
                )
            }
        };
        anyhow::bail!(
            "{}: no layer holds a contour ({heights}): the shape has no inside at the layer \
             heights; a mesh without thickness (a flat or open sheet) encloses none, and \
             --first and --layer-height must put layers through the solid",
            a.input.display()
        );
    }
    pgvol::io::write_layers(&a.output, &layers, format, a.units_mm, &sliced.frame)?;
    let points: usize = layers
        .iter()
        .flat_map(|l| &l.loops)
        .map(|l| l.points.len())
        .sum();
    if a.out.json {
        return report::print(
            &serde_json::json!({
                "output": a.output, "layers": layers.len(), "loops": loops, "points": points,
            }),
            &Seconds::since(start).stage("slice", slice_seconds),
        );
    }
    if !a.out.quiet {
        outln!(
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

#[derive(Args)]
#[command(after_help = "Example: pgvol offset part.stl -o grown.glb --distance 0.5")]
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
    let start = Instant::now();
    a.shape.check_output(&a.output)?;
    let bars = Bars::new(a.out.silent());
    pgvol::checks::check_offset(a.distance).map_err(|e| anyhow::anyhow!("--distance: {e}"))?;
    let shape = a
        .shape
        .load(&a.input, a.distance.max(0.0), a.distance.abs(), &bars)?;
    let grown = shape
        .offset(a.distance)
        .map_err(|e| grid_error(e, &a.input))?;
    let triangles = write_result(&a.output, &grown, "the offset", &a.shape, &bars)?;
    report(&a.out, &a.output, triangles, start)
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
#[command(
    after_help = "Example: pgvol shell part.stl -o hollow.glb --thickness 1.2 --hollow --drain 0,0,-5,0,0,-1,2\n\n\
    With an infill: pgvol shell part.stl -o infill.stl --thickness 1.2 --infill gyroid --cell 5 \
    --infill-thickness 0.6 --drain 0,0,-5,0,0,-1,2\n\n\
    As an implicit 3MF (the part as an image stack, the infill as a formula of it): \
    pgvol shell part.stl -o infill.3mf --thickness 1.2 --infill gyroid --cell 5 \
    --infill-thickness 0.6 --grade-depth 10 --thickness-far 0.4"
)]
pub struct ShellArgs {
    /// A .pgv file, or a mesh.
    pub input: PathArg,
    /// Output: .pgv, a mesh (.glb, .gltf, .obj, .stl, .ply), or with --infill .3mf (the part as
    /// a level-set image stack, the infill as an implicit function of it).
    #[arg(short, long)]
    pub output: PathArg,
    /// Wall thickness in model units: at least two grid spacings (a thinner wall is refused,
    /// naming the --res that holds it).
    #[arg(long)]
    pub thickness: f32,
    /// Where the wall lies relative to the surface (ignored with --hollow, which keeps the
    /// outer surface and cuts a cavity inside).
    #[arg(long, value_enum, default_value_t)]
    pub side: SideArg,
    /// Hollow for printing: keep the outer surface and add an inner cavity at --thickness.
    #[arg(long)]
    pub hollow: bool,
    /// A drain hole through the wall (and the infill), with --hollow or --infill:
    /// `x,y,z,dx,dy,dz,diameter` (a point inside the cavity, the direction out through the wall,
    /// the hole's diameter). Repeat for more holes.
    #[arg(long, value_parser = parse_drain, allow_hyphen_values = true)]
    pub drain: Vec<pgvol::edit::Drain>,
    /// Hollow and fill the cavity with this lattice: gyroid, schwarz-p, diamond or neovius
    /// (see `pgvol lattice`).
    #[arg(long, value_name = "SURFACE", value_parser = parse_surface, requires = "cell")]
    pub infill: Option<pgvol::lattices::Tpms>,
    /// With --infill: the lattice's cell size, model units.
    #[arg(long, requires = "infill")]
    pub cell: Option<f32>,
    /// With --infill: the lattice's sheet thickness or strut level (default: --thickness).
    #[arg(long, allow_negative_numbers = true, requires = "infill")]
    pub infill_thickness: Option<f32>,
    /// With --infill: sheet or strut.
    #[arg(long, value_enum, default_value_t, requires = "infill")]
    pub infill_style: StyleArg,
    #[command(flatten)]
    pub grade: GradeArgs,
    /// With --infill and a .3mf output: the unit it names for the model's coordinates (micron,
    /// millimeter, centimeter, inch, foot or meter).
    #[arg(long, default_value = pgvol::limits::THREEMF_UNIT)]
    pub unit: String,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

fn parse_drain(s: &str) -> Result<pgvol::edit::Drain, String> {
    crate::parse::parse_drain(s).map_err(|e| e.to_string())
}

fn parse_surface(s: &str) -> Result<pgvol::lattices::Tpms, String> {
    s.parse()
}

/// `shell --infill`: the hollowed part with its cavity filled by a lattice.
fn shell_infill(a: ShellArgs, surface: pgvol::lattices::Tpms, start: Instant) -> Result<()> {
    let cell = a.cell.unwrap_or_default();
    let thickness = a.infill_thickness.unwrap_or(a.thickness);
    let lattice = build_lattice(surface, a.infill_style, cell, thickness, &a.grade)
        .map_err(|e| anyhow::anyhow!("--infill: {e}"))?;
    let bars = Bars::new(a.out.silent());
    let reach = pgvol::checks::lattice_reach(&lattice, a.thickness);
    let shape = a
        .shape
        .load_walled(&a.input, 0.0, reach, a.thickness, &bars)?;
    let loaded = start.elapsed().as_secs_f64();
    if super::lattice::is_3mf(&a.output) {
        let cut = pgvol::lattices::LatticeCut::Infill { wall: a.thickness };
        return super::lattice::write_implicit(
            (&a.input, &a.output, &a.unit),
            &shape,
            &lattice,
            cut,
            &a.drain,
            &a.out,
            (start, loaded),
        );
    }
    let solid = shape
        .infill(a.thickness, &lattice, &a.drain, &bars)
        .map_err(|e| grid_error(e, &a.input))?;
    let stages = [
        ("load", loaded),
        ("infill", start.elapsed().as_secs_f64() - loaded),
    ];
    write_solid(
        &a.output,
        solid,
        "the infill",
        &a.shape,
        &a.out,
        &bars,
        (start, stages),
    )
}

pub fn shell(a: ShellArgs) -> Result<()> {
    let start = Instant::now();
    if super::lattice::is_3mf(&a.output) {
        if a.infill.is_none() {
            anyhow::bail!(
                "a .3mf output holds an --infill lattice as an implicit function; for a plain \
                 shell write a mesh or .pgv"
            );
        }
        super::lattice::check_unit(&a.output, &a.unit)?;
    } else {
        a.shape.check_output(&a.output)?;
    }
    pgvol::checks::check_thickness(a.thickness).map_err(|e| anyhow::anyhow!("--thickness: {e}"))?;
    if let Some(surface) = a.infill {
        return shell_infill(a, surface, start);
    }
    if a.grade.grade_depth.is_some() || a.grade.grade_linear.is_some() {
        anyhow::bail!("--grade-depth and --grade-linear apply to an --infill lattice");
    }
    if !a.drain.is_empty() && !a.hollow {
        anyhow::bail!("--drain needs --hollow or --infill");
    }
    let bars = Bars::new(a.out.silent());
    let kind = if a.hollow {
        pgvol::ShellKind::Hollow
    } else {
        pgvol::ShellKind::Wall(match a.side {
            SideArg::Inner => pgvol::edit::ShellSide::Inner,
            SideArg::Outer => pgvol::edit::ShellSide::Outer,
            SideArg::Centred => pgvol::edit::ShellSide::Centred,
        })
    };
    let options = pgvol::ShellOptions {
        thickness: a.thickness,
        kind,
        drains: a.drain.clone(),
    };
    let shape = a
        .shape
        .load_walled(&a.input, options.growth(), a.thickness, a.thickness, &bars)?;
    let walled = shape
        .shell(&options, &bars)
        .map_err(|e| grid_error(e, &a.input))?;
    let operation = if a.hollow {
        "the hollowing"
    } else {
        "the shell"
    };
    let triangles = write_result(&a.output, &walled, operation, &a.shape, &bars)?;
    report(&a.out, &a.output, triangles, start)
}

pub(super) fn report(
    out: &OutputArgs,
    output: &Path,
    triangles: usize,
    start: Instant,
) -> Result<()> {
    if out.json {
        report::print(
            &serde_json::json!({ "output": output, "triangles": triangles }),
            &Seconds::since(start),
        )?;
    } else if !out.quiet {
        if triangles > 0 {
            outln!("{}: {} triangles", output.display(), triangles);
        } else {
            outln!("{}: written", output.display());
        }
    }
    Ok(())
}
