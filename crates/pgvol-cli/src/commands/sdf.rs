//! `pgvol sdf`.

use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use serde::Serialize;

use super::{GridArgs, OutputArgs, PathArg};
use crate::pipeline;

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum GridFormat {
    /// NRRD, raw float32 with the grid's origin and spacing in the header.
    Nrrd,
    /// NumPy .npy, float32 of shape (nz, ny, nx).
    Npy,
}

#[derive(Args)]
pub struct SdfArgs {
    /// Input mesh.
    pub mesh: PathArg,
    /// Output grid file.
    #[arg(short, long)]
    pub output: PathArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Exact distances at every node (the only mode so far; kept for scripts that say so).
    #[arg(long)]
    pub dense: bool,
    /// File format; by default from the output's extension (.npy, otherwise NRRD).
    #[arg(long, value_enum)]
    pub format: Option<GridFormat>,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Serialize)]
struct Report {
    grid: pgvol_field::Grid,
    samples: usize,
    seconds: f64,
    samples_per_second: f64,
    inside: usize,
}

pub fn run(a: SdfArgs) -> Result<()> {
    let format = match a.format {
        Some(f) => f,
        None => match a
            .output
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
        {
            Some(e) if e == "npy" => GridFormat::Npy,
            Some(e) if e == "nrrd" => GridFormat::Nrrd,
            _ => bail!(
                "{}: unknown grid file extension (expected .nrrd or .npy, or give --format)",
                a.output.display()
            ),
        },
    };
    let quiet = a.out.silent();
    let mesh = pipeline::load_mesh(&a.mesh, quiet)?;
    let grid = a.grid.spec(128).grid_for(&mesh)?;
    let t = Instant::now();
    let values = pipeline::signed_distance_grid(&mesh, &grid, quiet)?;
    let seconds = t.elapsed().as_secs_f64();
    match format {
        GridFormat::Nrrd => pgvol_format::grid_files::write_nrrd(&a.output, &grid, &values, &[])?,
        GridFormat::Npy => pgvol_format::grid_files::write_npy(&a.output, &grid, &values)?,
    }
    let report = Report {
        grid,
        samples: values.len(),
        seconds,
        samples_per_second: values.len() as f64 / seconds.max(1e-9),
        inside: values.iter().filter(|v| **v < 0.0).count(),
    };
    if a.out.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !a.out.quiet {
        println!(
            "{}: {}^3 signed distances in {:.2} s ({:.0} samples/s), {} inside",
            a.output.display(),
            grid.dims[0],
            seconds,
            report.samples_per_second,
            report.inside
        );
    }
    Ok(())
}
