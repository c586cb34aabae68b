//! `pgvol remesh`.

use std::time::Instant;

use anyhow::Result;
use clap::{Args, ValueEnum};
use serde::Serialize;

use super::{BasisArgs, GridArgs, MethodArg, OutputArgs, PathArg};
use crate::exact_field;
use crate::pipeline::{self, Timings};

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
pub struct RemeshArgs {
    /// Input mesh (.obj, .gltf, .glb, .stl, .ply).
    pub input: PathArg,
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
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Serialize)]
struct Report<'a> {
    input: &'a std::path::Path,
    output: &'a std::path::Path,
    grid: pgvol_field::Grid,
    basis: &'static str,
    input_triangles: usize,
    triangles: usize,
    vertices: usize,
    seconds: Timings,
    total_seconds: f64,
}

pub fn run(a: RemeshArgs) -> Result<()> {
    // Refuse an unwritable output format before doing the work.
    pgvol_mesh::MeshFormat::from_path(&a.output)?;
    let start = Instant::now();
    let mut t = Timings::default();
    let quiet = a.out.silent();
    let mesh = pipeline::load_mesh(&a.input, quiet)?;
    t.read = start.elapsed().as_secs_f64();
    let grid = a.grid.spec(128).grid_for(&mesh)?;
    if a.field == FieldArg::Exact && a.basis.basis()? != pgvol_field::Basis::Bspline3 {
        anyhow::bail!("--basis applies to --field decoded; the exact field has no basis");
    }
    let (out, basis) = match a.field {
        FieldArg::Exact => {
            let method = match a.method {
                MethodArg::Mc => pgvol_contour::Method::MarchingCubes,
                MethodArg::Sn => pgvol_contour::Method::SurfaceNets,
                MethodArg::Dc => pgvol_contour::Method::DualContouring,
            };
            let (out, sdf) = exact_field::contour_exact(&mesh, &grid, method, quiet)?;
            t.sdf = sdf;
            t.contour = start.elapsed().as_secs_f64() - t.read - sdf;
            (out, "exact")
        }
        FieldArg::Decoded => {
            let (volume, sdf, fit) = pipeline::encode(&mesh, grid, a.basis.basis()?, quiet)?;
            t.sdf = sdf;
            t.fit = fit;
            let c = Instant::now();
            let out = pipeline::decode(&volume, 0.0, a.method, None)?;
            t.contour = c.elapsed().as_secs_f64();
            (out, volume.basis.name())
        }
    };
    if out.triangles.is_empty() {
        anyhow::bail!(
            "{}: the surface vanished at this resolution (no inside region found); try a larger --res",
            a.input.display()
        );
    }
    let w = Instant::now();
    pgvol_mesh::write(&a.output, &out)?;
    t.write = w.elapsed().as_secs_f64();
    let report = Report {
        input: &a.input,
        output: &a.output,
        grid,
        basis,
        input_triangles: mesh.triangles.len(),
        triangles: out.triangles.len(),
        vertices: out.positions.len(),
        seconds: t,
        total_seconds: start.elapsed().as_secs_f64(),
    };
    if a.out.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !a.out.quiet {
        println!(
            "{} -> {}: {} triangles at {}^3 ({} field), {:.2} s",
            a.input.display(),
            a.output.display(),
            report.triangles,
            grid.dims[0],
            report.basis,
            report.total_seconds
        );
    }
    Ok(())
}
