//! `pgvol sdf`.

use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use serde::Serialize;

use super::{GridArgs, OutputArgs, PathArg, SignArg};
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
    /// Exact distances at every node (the default).
    #[arg(long, conflicts_with = "band")]
    pub dense: bool,
    /// Exact distances only within W grid spacings of the surface; elsewhere only the sign, with
    /// magnitude W × spacing.
    #[arg(long, value_name = "W", value_parser = parse_band)]
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

fn parse_band(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(w) if w.is_finite() && w > 0.0 => Ok(w),
        _ => Err(format!("'{s}' is not a positive number of grid spacings")),
    }
}

#[derive(Serialize)]
struct Report {
    grid: pgvol_field::Grid,
    sign: &'static str,
    band: Option<f32>,
    exact_nodes: usize,
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
    let extent = match a.band {
        Some(w) => pgvol_sdf::sampling::Extent::Band(w),
        None => pgvol_sdf::sampling::Extent::Dense,
    };
    let t = Instant::now();
    let (sampled, sign) =
        pipeline::signed_distance_grid(&mesh, &grid, extent, a.sign.into(), quiet)?;
    let seconds = t.elapsed().as_secs_f64();
    let values = sampled.values;
    match format {
        GridFormat::Nrrd => pgvol_format::grid_files::write_nrrd(&a.output, &grid, &values, &[])?,
        GridFormat::Npy => pgvol_format::grid_files::write_npy(&a.output, &grid, &values)?,
    }
    let report = Report {
        grid,
        sign: sign.name(),
        band: a.band,
        exact_nodes: sampled.exact_nodes,
        samples: values.len(),
        seconds,
        samples_per_second: values.len() as f64 / seconds.max(1e-9),
        inside: values.iter().filter(|v| **v < 0.0).count(),
    };
    if a.out.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !a.out.quiet {
        println!(
            "{}: {}^3 signed distances ({} sign, {} exact) in {:.2} s ({:.0} samples/s), {} inside",
            a.output.display(),
            grid.dims[0],
            report.sign,
            report.exact_nodes,
            seconds,
            report.samples_per_second,
            report.inside
        );
    }
    Ok(())
}
