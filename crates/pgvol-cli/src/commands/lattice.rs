//! `pgvol lattice` and the lattice options of `pgvol shell --infill`: triply periodic lattices cut
//! to a part or filling its cavity, with the solid's volume fraction and area reported.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::{at_input, OutputArgs, PathArg, ShapeOutputArgs};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::Seconds;

#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum StyleArg {
    /// A wall of --thickness centred on the surface.
    #[default]
    Sheet,
    /// One of the two labyrinths, bounded at the level --thickness (negative thins the struts).
    Strut,
}

/// Grading of the cell size and thickness from their values at the ramp's start to far values.
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct GradeArgs {
    /// Grade with depth: the thickness goes from its value at the skin to --thickness-far at
    /// this depth inside the part (model units) and stays there.
    #[arg(long, value_name = "DEPTH", conflicts_with = "grade_linear")]
    pub grade_depth: Option<f32>,
    /// Grade along a segment `x0,y0,z0,x1,y1,z1`: cell and thickness go from their values at the
    /// first point to --cell-far and --thickness-far at the second, constant beyond.
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", value_parser = parse_segment, allow_hyphen_values = true)]
    pub grade_linear: Option<[f32; 6]>,
    /// The cell size at the ramp's end (default: the cell size; linear ramps only).
    #[arg(long, value_name = "SIZE")]
    pub cell_far: Option<f32>,
    /// The thickness at the ramp's end (default: the thickness).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub thickness_far: Option<f32>,
}

fn parse_segment(text: &str) -> Result<[f32; 6], String> {
    let numbers: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{text}' is not six comma-separated numbers"))?;
    <[f32; 6]>::try_from(numbers).map_err(|_| format!("'{text}': expected six numbers"))
}

fn parse_surface(text: &str) -> Result<pgvol::lattices::Tpms, String> {
    text.parse()
}

/// The lattice of the command line.
pub fn build_lattice(
    surface: pgvol::lattices::Tpms,
    style: StyleArg,
    cell: f32,
    thickness: f32,
    grade: &GradeArgs,
) -> Result<pgvol::Lattice> {
    let ramp = match (grade.grade_depth, grade.grade_linear) {
        (Some(depth), _) => Some(pgvol::lattices::Ramp::Depth { depth }),
        (None, Some(s)) => Some(pgvol::lattices::Ramp::Linear {
            from: pgvol::glam::Vec3::new(s[0], s[1], s[2]),
            to: pgvol::glam::Vec3::new(s[3], s[4], s[5]),
        }),
        (None, None) => None,
    };
    let style = match style {
        StyleArg::Sheet => pgvol::lattices::LatticeStyle::Sheet,
        StyleArg::Strut => pgvol::lattices::LatticeStyle::Strut,
    };
    Ok(pgvol::lattices::make_lattice(
        surface,
        style,
        cell,
        thickness,
        ramp,
        grade.cell_far,
        grade.thickness_far,
    )?)
}

#[derive(Args)]
#[command(
    after_help = "Defaults: sheet style, 128 nodes per axis for a mesh input.\n\n\
    Example: pgvol lattice part.stl -o lattice.stl --surface gyroid --cell 5 --thickness 0.6 \
    --res 256\n\n\
    As an implicit 3MF: pgvol lattice part.stl -o lattice.3mf --surface gyroid --cell 5 \
    --thickness 0.6 --grade-linear 0,0,0,0,0,40 --cell-far 8"
)]
pub struct LatticeArgs {
    /// A .pgv file, or a mesh (encoded on the fly at --res).
    pub input: PathArg,
    /// Output: .pgv, a mesh (.glb, .gltf, .obj, .stl, .ply), or .3mf (the part as a level-set
    /// image stack and the lattice as an implicit function of it).
    #[arg(short, long)]
    pub output: PathArg,
    /// The periodic surface: gyroid, schwarz-p, diamond or neovius.
    #[arg(long, value_parser = parse_surface)]
    pub surface: pgvol::lattices::Tpms,
    /// Sheet (a wall on the surface) or strut (a labyrinth).
    #[arg(long, value_enum, default_value_t)]
    pub style: StyleArg,
    /// The cell size (the surface's period along each axis), model units.
    #[arg(long)]
    pub cell: f32,
    /// Sheet: the wall thickness. Strut: the level bounding the struts (0 fills half of each
    /// cell, negative thins them). Model units.
    #[arg(long, allow_negative_numbers = true)]
    pub thickness: f32,
    #[command(flatten)]
    pub grade: GradeArgs,
    /// With a .3mf output: the unit it names for the model's coordinates (micron, millimeter,
    /// centimeter, inch, foot or meter).
    #[arg(long, default_value = pgvol::limits::THREEMF_UNIT)]
    pub unit: String,
    #[command(flatten)]
    pub shape: ShapeOutputArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn lattice(a: LatticeArgs) -> Result<()> {
    let start = Instant::now();
    let implicit = is_3mf(&a.output);
    if implicit {
        check_unit(&a.output, &a.unit)?;
    } else {
        a.shape.check_output(&a.output)?;
    }
    let lattice = build_lattice(a.surface, a.style, a.cell, a.thickness, &a.grade)?;
    let bars = Bars::new(a.out.silent());
    let reach = pgvol::checks::lattice_reach(&lattice, 0.0);
    let shape = a.shape.load(&a.input, 0.0, reach, &bars)?;
    let loaded = start.elapsed().as_secs_f64();
    if implicit {
        let cut = pgvol::lattices::LatticeCut::Part;
        return write_implicit(
            (&a.input, &a.output, &a.unit),
            &shape,
            &lattice,
            cut,
            &[],
            &a.out,
            (start, loaded),
        );
    }
    let solid = shape
        .lattice(&lattice, &bars)
        .map_err(|e| at_input(e, &a.input))?;
    let stages = [
        ("load", loaded),
        ("lattice", start.elapsed().as_secs_f64() - loaded),
    ];
    write_solid(
        &a.output,
        solid,
        "the lattice",
        &a.shape,
        &a.out,
        &bars,
        (start, stages),
    )
}

/// Whether `output` names a 3MF package, where a lattice goes as an implicit function.
pub fn is_3mf(output: &Path) -> bool {
    output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("3mf"))
}

/// Refuses a unit 3MF does not name before any work.
pub fn check_unit(output: &Path, unit: &str) -> Result<()> {
    if !pgvol::limits::THREEMF_UNITS.contains(&unit) {
        anyhow::bail!(
            "{}: --unit {unit}: 3MF knows {}",
            output.display(),
            pgvol::limits::THREEMF_UNITS.join(", ")
        );
    }
    Ok(())
}

/// Writes `lattice` cut to `shape` (read from `input`) as an implicit 3MF package and reports
/// its size.
pub fn write_implicit(
    (input, output, unit): (&Path, &Path, &str),
    shape: &pgvol::Field,
    lattice: &pgvol::Lattice,
    cut: pgvol::lattices::LatticeCut,
    drains: &[pgvol::edit::Drain],
    out: &OutputArgs,
    (start, loaded): (Instant, f64),
) -> Result<()> {
    let t = Instant::now();
    // Errors without a file are about the part (its band, its frame): name the input.
    let written = shape
        .write_lattice_3mf(output, lattice, cut, drains, unit)
        .map_err(|e| at_input(e, input))?;
    let (grid, nodes) = (written.grid, written.nodes);
    let bytes = std::fs::metadata(output).map(|m| m.len()).unwrap_or(0);
    let write = t.elapsed().as_secs_f64();
    let [nx, ny, nz] = grid.dims;
    if out.json {
        let seconds = Seconds::since(start).stages([("load", loaded), ("write", write)]);
        return crate::report::print(
            &serde_json::json!({
                "output": output, "bytes": bytes, "nodes": nodes, "image_dims": grid.dims
            }),
            &seconds,
        );
    }
    if !out.quiet {
        outln!(
            "{}: implicit lattice of {nodes} nodes over the part's {nx} x {ny} x {nz} image \
             stack, {bytes} bytes",
            output.display()
        );
    }
    Ok(())
}

/// Writes a lattice solid as .pgv or as a mesh by the output's extension, and reports its
/// volume fraction and area.
pub fn write_solid(
    output: &Path,
    solid: pgvol::Latticed,
    operation: &str,
    args: &ShapeOutputArgs,
    out: &OutputArgs,
    progress: &Bars,
    (start, stages): (Instant, [(&str, f64); 2]),
) -> Result<()> {
    // A mesh output is contoured anyway and measured exactly; a .pgv is measured on the field.
    let t = Instant::now();
    let mesh = if pgvol::io::is_pgv(output) {
        None
    } else {
        Some(
            solid
                .field
                .to_mesh(&args.decode_options(), progress)
                .map_err(|e| {
                    anyhow::anyhow!(
                        "{operation}: the result is empty (no lattice inside the part): {e}"
                    )
                })?,
        )
    };
    let contour = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let report = solid.report(mesh.as_ref(), progress);
    let measure = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let triangles = match mesh {
        Some(mesh) => {
            pgvol::io::write_mesh(output, &mesh)?;
            mesh.triangles.len()
        }
        None => {
            solid.field.save(output, &args.storage())?;
            0
        }
    };
    let write = t.elapsed().as_secs_f64();
    if out.json {
        let seconds = Seconds::since(start).stages(stages).stages([
            ("contour", contour),
            ("measure", measure),
            ("write", write),
        ]);
        return crate::report::print(
            &serde_json::json!({ "output": output, "triangles": triangles, "solid": report }),
            &seconds,
        );
    }
    if !out.quiet {
        outln!(
            "{}: {}volume {:.6} ({:.2} % of the part's {:.6}), area {:.6}",
            output.display(),
            if triangles > 0 {
                format!("{triangles} triangles, ")
            } else {
                String::new()
            },
            report.volume,
            100.0 * report.fraction,
            report.part_volume,
            report.area
        );
    }
    Ok(())
}
