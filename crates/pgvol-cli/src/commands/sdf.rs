//! `pgvol sdf`.

use anyhow::Result;
use clap::{Args, ValueEnum};
use serde::Serialize;

use super::args::{at_input, load_mesh, GridArgs, MeshInputArgs, OutputArgs, PathArg, SignArg};
use crate::output::outln;
use crate::progress::Bars;
use crate::report::Seconds;

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum GridFormat {
    /// NRRD, raw float32 with the grid's origin and spacing in the header.
    Nrrd,
    /// NumPy .npy, float32 of shape (nz, ny, nx).
    Npy,
}

#[derive(Args)]
#[command(after_help = "Example: pgvol sdf part.obj -o part.npy --res 256 --band 3")]
pub struct SdfArgs {
    /// Input mesh.
    pub mesh: PathArg,
    #[command(flatten)]
    pub read: MeshInputArgs,
    /// Output grid file.
    #[arg(short, long)]
    pub output: PathArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Exact distances at every node (the default).
    #[arg(long, conflicts_with = "band")]
    pub dense: bool,
    /// Exact distances only within W grid spacings of the surface; elsewhere only the sign, with
    /// magnitude W × spacing.
    #[arg(long, value_name = "W")]
    pub band: Option<f32>,
    /// How inside and outside are told apart.
    #[arg(long, value_enum, default_value_t)]
    pub sign: SignArg,
    /// File format; by default from the output's extension (.npy, otherwise NRRD).
    #[arg(long, value_enum)]
    pub format: Option<GridFormat>,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn run(a: SdfArgs) -> Result<()> {
    let start = std::time::Instant::now();
    let format = match a.format {
        Some(GridFormat::Nrrd) => pgvol::io::GridFormat::Nrrd,
        Some(GridFormat::Npy) => pgvol::io::GridFormat::Npy,
        None => pgvol::io::GridFormat::from_path(&a.output)
            .map_err(|e| anyhow::anyhow!("{e}, or give --format"))?,
    };
    let quiet = a.out.silent();
    let mesh = load_mesh(&a.mesh, a.read, quiet)?;
    let options = pgvol::SdfOptions {
        grid: a.grid.spec(),
        band: a.band,
        sign: a.sign.into(),
    };
    let sampled = pgvol::distances::signed_distance(&mesh, &options, &Bars::new(quiet))
        .map_err(|e| at_input(e, &a.mesh))?;
    pgvol::io::write_grid(&a.output, &sampled.grid, &sampled.values, format)?;
    let values = &sampled.values;
    let report = Report {
        grid: sampled.grid,
        sign: sampled.sign,
        band: a.band,
        exact_nodes: sampled.exact_nodes,
        samples: values.len(),
        samples_per_second: values.len() as f64 / sampled.seconds.max(1e-9),
        inside: values.iter().filter(|v| **v < 0.0).count(),
    };
    if a.out.json {
        return crate::report::print(
            &report,
            &Seconds::since(start).stage("sdf", sampled.seconds),
        );
    }
    if !a.out.quiet {
        outln!(
            "{}: {}^3 signed distances ({} sign, {} exact) in {:.2} s ({:.0} samples/s), {} inside",
            a.output.display(),
            report.grid.dims[0],
            report.sign,
            report.exact_nodes,
            sampled.seconds,
            report.samples_per_second,
            report.inside
        );
    }
    Ok(())
}

#[derive(Serialize)]
struct Report {
    grid: pgvol::Grid,
    sign: &'static str,
    band: Option<f32>,
    exact_nodes: usize,
    samples: usize,
    samples_per_second: f64,
    inside: usize,
}
