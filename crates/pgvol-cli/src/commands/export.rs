//! `pgvol export`: a .pgv file as NRRD (coefficients or sampled field) or as a 3MF level set.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};

use super::{OutputArgs, PathArg};

#[derive(Args)]
pub struct ExportArgs {
    /// Input .pgv file.
    pub input: PathArg,
    /// Output file: .nrrd or .3mf.
    #[arg(short, long)]
    pub output: PathArg,
    /// What a NRRD holds: the coefficient grid itself (readable by `pgvol encode --from`) or
    /// the field sampled on a grid. A .3mf always holds the sampled field.
    #[arg(long, value_enum, default_value_t)]
    pub what: WhatArg,
    /// Sample on N nodes along the longest side over the same box (default: the stored grid).
    #[arg(long, value_parser = clap::value_parser!(u32).range(4..=2048))]
    pub res: Option<u32>,
    #[command(flatten)]
    pub out: OutputArgs,
}

/// What a NRRD export holds.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WhatArg {
    /// The coefficients, with the basis in key/value fields; round-trips bit-exactly.
    Coefficients,
    /// The signed distance sampled at the grid nodes.
    #[default]
    Sdf,
}

enum Kind {
    Nrrd,
    ThreeMf,
}

pub fn run(a: ExportArgs) -> Result<()> {
    let kind = match a.output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("nrrd") => Kind::Nrrd,
        Some(e) if e.eq_ignore_ascii_case("3mf") => Kind::ThreeMf,
        _ => bail!("{}: expected a .nrrd or .3mf file name", a.output.display()),
    };
    let coefficients = a.what == WhatArg::Coefficients;
    if coefficients && matches!(kind, Kind::ThreeMf) {
        bail!("--what coefficients applies to .nrrd only; a .3mf holds the sampled field");
    }
    if coefficients && a.res.is_some() {
        bail!("--res resamples the field; it does not apply to --what coefficients");
    }
    let file = pgvol_format::read_pgv(&a.input)?;
    let volume = &file.volume;
    let grid = match a.res {
        None => volume.grid,
        Some(n) => pgvol_contour::resampled_grid(volume, n as usize)
            .with_context(|| format!("--res {n} gives a grid larger than the limit"))?,
    };
    let what = if coefficients {
        pgvol_format::nrrd::write_coefficients_nrrd(&a.output, &file)?;
        "coefficients"
    } else {
        let values = volume.sample(&grid);
        match kind {
            Kind::Nrrd => {
                pgvol_format::nrrd::write_field_nrrd(&a.output, &grid, &values, volume.basis)?
            }
            // 3MF units are named; pgvol's are the source mesh's, taken to be millimetres.
            Kind::ThreeMf => {
                pgvol_format::threemf::write_3mf(&a.output, &grid, &values, "millimeter")?
            }
        }
        "sdf"
    };
    let bytes = std::fs::metadata(&a.output)?.len();
    if a.out.json {
        let v = serde_json::json!({
            "output": a.output, "what": what, "grid": grid, "bytes": bytes,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else if !a.out.quiet {
        let [nx, ny, nz] = grid.dims;
        println!(
            "{}: {what} on {nx} x {ny} x {nz} nodes, {bytes} bytes",
            a.output.display()
        );
    }
    Ok(())
}
