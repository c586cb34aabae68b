//! `pgvol remesh`.

use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};
use serde::Serialize;

use super::args::{
    at_input, load_mesh_with_unit, non_negative, BasisArgs, GridArgs, MeshInputArgs, MethodArg,
    OutputArgs, PathArg, SignArg,
};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::Seconds;

/// Which field the vertices are placed on.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FieldArg {
    /// The exact signed distance of the input mesh: sharp edges stay sharp (no fit, --basis
    /// unused).
    #[default]
    Exact,
    /// The decoded coefficient volume of --basis, as `encode` then `decode` would give.
    Decoded,
}

#[derive(Args)]
#[command(after_help = "Example: pgvol remesh scan.stl -o clean.glb --res 256 --method dc")]
pub struct RemeshArgs {
    /// Input mesh (.obj, .gltf, .glb, .stl, .ply, .3mf; 3MF read in millimetres).
    pub input: PathArg,
    #[command(flatten)]
    pub read: MeshInputArgs,
    /// Output mesh; the format follows the extension (.glb, .gltf, .obj, .stl, .ply).
    #[arg(short, long)]
    pub output: PathArg,
    #[command(flatten)]
    pub grid: GridArgs,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Contouring method.
    #[arg(long, value_enum, default_value_t)]
    pub method: MethodArg,
    /// Field that places the vertices (node signs always come from the mesh's distance).
    #[arg(long, value_enum, default_value_t)]
    pub field: FieldArg,
    /// Remove pieces of the output enclosing less than this volume (model units cubed); by
    /// default specks under 2 grid cells go, with a warning; 0 keeps every piece.
    #[arg(long, value_name = "VOLUME", value_parser = non_negative)]
    pub min_component: Option<f32>,
    /// How inside is told from outside.
    #[arg(long, value_enum, default_value_t)]
    pub sign: SignArg,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Serialize)]
struct Report<'a> {
    input: &'a std::path::Path,
    output: &'a std::path::Path,
    grid: pgvol::Grid,
    basis: &'static str,
    input_triangles: usize,
    /// How the input's declared length unit was converted (3MF), `null` for other formats.
    unit: Option<String>,
    triangles: usize,
    vertices: usize,
}

pub fn run(a: RemeshArgs) -> Result<()> {
    // Refuse an unwritable output format before doing the work.
    pgvol::io::mesh_format(&a.output)?;
    if a.field == FieldArg::Exact && !a.basis.is_default() {
        anyhow::bail!("--basis applies to --field decoded; the exact field has no basis");
    }
    let start = Instant::now();
    let quiet = a.out.silent();
    let (mesh, unit) = load_mesh_with_unit(&a.input, a.read, quiet)?;
    pgvol::io::check_mesh_output(&a.output, &mesh)?;
    let read = start.elapsed().as_secs_f64();
    let options = pgvol::RemeshOptions {
        grid: a.grid.spec(),
        method: a.method.into(),
        field: match a.field {
            FieldArg::Exact => pgvol::RemeshField::Exact,
            FieldArg::Decoded => pgvol::RemeshField::Decoded(a.basis.basis()?),
        },
        min_component: a.min_component,
        sign: a.sign.into(),
    };
    let remeshed =
        pgvol::remesh(&mesh, &options, &Bars::new(quiet)).map_err(|e| at_input(e, &a.input))?;
    let w = Instant::now();
    pgvol::io::write_mesh(&a.output, &remeshed.mesh)?;
    let mut seconds = remeshed.timings;
    seconds.read = read;
    seconds.write = w.elapsed().as_secs_f64();
    let basis = match options.field {
        pgvol::RemeshField::Exact => "exact",
        pgvol::RemeshField::Decoded(b) => b.name(),
    };
    let grid = remeshed.grid;
    let total = start.elapsed().as_secs_f64();
    let report = Report {
        input: &a.input,
        output: &a.output,
        grid,
        basis,
        input_triangles: mesh.triangles.len(),
        unit,
        triangles: remeshed.mesh.triangles.len(),
        vertices: remeshed.mesh.positions.len(),
    };
    if a.out.json {
        let seconds = Seconds::since(start).stages([
            ("read", seconds.read),
            ("sdf", seconds.sdf),
            ("fit", seconds.fit),
            ("contour", seconds.contour),
            ("write", seconds.write),
        ]);
        return crate::report::print(&report, &seconds);
    }
    if !a.out.quiet {
        outln!(
            "{} -> {}: {} triangles at {}^3 ({} field), {:.2} s",
            a.input.display(),
            a.output.display(),
            report.triangles,
            grid.dims[0],
            report.basis,
            total
        );
    }
    Ok(())
}
