//! `pgvol perturb`.

use std::time::Instant;

use anyhow::Result;
use clap::Args;
use serde::Serialize;

use super::args::{at_input, load_mesh, non_negative, MeshInputArgs, OutputArgs, PathArg};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::Seconds;

#[derive(Args)]
#[command(
    after_help = "Examples:\n  pgvol perturb cow.obj -o cow.pgv --max-functions 2038   (the function list)\n  \
                  pgvol perturb cow.obj -o cow-128.pgv --resample 128   (a coefficient volume)\n  \
                  pgvol perturb cow.obj -o cow-perturb.obj   (the contoured zero set)"
)]
pub struct PerturbArgs {
    /// Input mesh (.obj, .gltf, .glb, .stl, .ply, .3mf; 3MF read in millimetres).
    pub input: PathArg,
    #[command(flatten)]
    pub read: MeshInputArgs,
    /// Output: a .pgv file (the function list, encoding perturbation-f64, or with --resample a
    /// cubic B-spline coefficient volume; decode, slice, eval, offset, shell and info read
    /// either) or a mesh (.glb, .gltf, .obj, .stl, .ply: the contoured zero set, every piece
    /// kept).
    #[arg(short, long)]
    pub output: PathArg,
    /// Most perturbation functions the fitting loop adds (`loop_functions` in --json); the
    /// passes after it that remove stray pieces add more, so the `functions` total can exceed
    /// it.
    #[arg(long, default_value_t = pgvol::perturbation::PerturbOptions::default().max_functions as u64,
          value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    pub max_functions: u64,
    /// Stop once every vertex is within this fraction of the bounding-box diagonal of the zero
    /// set (first-order estimate |M| / |∇M|).
    #[arg(long, default_value_t = pgvol::perturbation::PerturbOptions::default().tolerance as f32, value_parser = non_negative)]
    pub tolerance: f32,
    /// Most descent steps on each perturbation's coefficients after its ten-point solve (the
    /// paper's optimisation step); 0 keeps the solved quadric.
    #[arg(long, default_value_t = pgvol::perturbation::PerturbOptions::default().descent_steps as u32)]
    pub descent_steps: u32,
    /// Write a coefficient volume resampled on RES nodes per axis (a cube 1.1 × the mesh's
    /// longest extent) instead of the function list; for a mesh output, the grid it is
    /// contoured on. Without it the list records, and a mesh output uses, 128.
    #[arg(long, value_name = "RES",
          value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
    pub resample: Option<u32>,
    /// With --resample and a .pgv output: write every coefficient as f32 instead of the sparse,
    /// compressed bricks around the surface.
    #[arg(long, requires = "resample")]
    pub dense_file: bool,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Serialize)]
struct Report<'a> {
    input: &'a std::path::Path,
    output: &'a std::path::Path,
    input_triangles: usize,
    input_components: usize,
    perturbation: &'a pgvol::perturbation::PerturbReport,
    /// The pass clearing wrong nodes of the check grid away from the surface.
    cleanup: pgvol::perturbation::Cleanup,
    /// The passes removing the stray pieces left on the check grid.
    strays: pgvol::perturbation::Strays,
    grid: pgvol::Grid,
    /// Bytes of the .pgv file, or triangles, vertices and components of the mesh written.
    #[serde(skip_serializing_if = "Option::is_none")]
    bytes: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    triangles: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    components: Option<usize>,
}

pub fn run(a: PerturbArgs) -> Result<()> {
    let to_pgv = pgvol::io::is_pgv(&a.output);
    if !to_pgv {
        // Refuse an unwritable output format before doing the work.
        pgvol::io::mesh_format(&a.output)?;
    }
    super::args::check_dense_file(a.dense_file, &a.output)?;
    let start = Instant::now();
    let quiet = a.out.silent();
    let mesh = load_mesh(&a.input, a.read, quiet)?;
    let read = start.elapsed().as_secs_f64();
    let options = pgvol::perturbation::PerturbOptions {
        max_functions: a.max_functions as usize,
        tolerance: a.tolerance as f64,
        descent_steps: a.descent_steps as usize,
    };
    let bars = Bars::new(quiet);
    let res = a.resample.unwrap_or(pgvol::limits::DEFAULT_RES as u32);
    let spec = pgvol::GridSpec::Res(res as usize);
    // Checked on the grid the output is contoured or resampled on (the list records it).
    let perturbed = pgvol::perturbation::perturb_on(&mesh, &options, spec, &bars)
        .map_err(|e| at_input(e, &a.input))?;
    let built = start.elapsed().as_secs_f64() - read;
    let t = Instant::now();
    let header = pgvol::perturbation::perturbation_header(&perturbed.field, &mesh, spec)
        .map_err(|e| at_input(e, &a.input))?;
    let list = to_pgv && a.resample.is_none();
    let file = if list {
        None
    } else {
        Some(
            pgvol::perturbation::resample(&perturbed.field, &mesh, spec, &bars)
                .map_err(|e| at_input(e, &a.input))?,
        )
    };
    let resampled = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (mut bytes, mut triangles, mut components) = (None, None, None);
    let mut contour = 0.0;
    match &file {
        None => pgvol::perturbation::write_perturbation(&a.output, &header, &perturbed.field)?,
        Some(file) if to_pgv => {
            let storage = if a.dense_file {
                super::args::file_storage(true)
            } else {
                pgvol::perturbation::resampled_storage()
            };
            pgvol::io::write_pgv(&a.output, file, &storage)?;
        }
        Some(file) => {
            let out = pgvol::perturbation::perturbation_mesh(file, &bars)?;
            contour = t.elapsed().as_secs_f64();
            pgvol::io::write_mesh(&a.output, &out)?;
            triangles = Some(out.triangles.len());
            components = Some(out.stats().components);
        }
    }
    if to_pgv {
        bytes = Some(std::fs::metadata(&a.output)?.len());
    }
    let write = t.elapsed().as_secs_f64() - contour;
    let r = &perturbed.report;
    let report = Report {
        input: &a.input,
        output: &a.output,
        input_triangles: mesh.triangles.len(),
        input_components: mesh.stats().components,
        perturbation: r,
        cleanup: perturbed.cleanup,
        strays: perturbed.strays,
        grid: header.grid,
        bytes,
        triangles,
        components,
    };
    if a.out.json {
        let seconds = Seconds::since(start).stages([
            ("read", read),
            ("perturb", built),
            ("resample", resampled),
            ("contour", contour),
            ("write", write),
        ]);
        return crate::report::print(&report, &seconds);
    }
    if !a.out.quiet {
        outln!(
            "{} -> {}: {} functions in {:.2} s (stopped: {:?})",
            a.input.display(),
            a.output.display(),
            perturbed.field.terms().len(),
            r.seconds,
            r.stop
        );
        outln!(
            "vertex deviation estimate: base quadric mean {:.4} %, max {:.4} %; final mean {:.4} %, max {:.4} % of the diagonal",
            100.0 * r.base_mean / r.diagonal,
            100.0 * r.base_max / r.diagonal,
            100.0 * r.mean / r.diagonal,
            100.0 * r.max / r.diagonal
        );
        match (bytes, triangles) {
            (Some(b), _) if list => {
                outln!("function list: {b} bytes (resampled at {res}^3 when read)")
            }
            (Some(b), _) => outln!("resampled at {res}^3: {b} bytes"),
            (_, Some(t)) => outln!(
                "contoured at {}^3: {} triangles, {} components (input {})",
                res,
                t,
                components.unwrap_or(0),
                report.input_components
            ),
            _ => {}
        }
    }
    Ok(())
}
