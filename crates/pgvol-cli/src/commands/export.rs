//! `pgvol export`: a .pgv file as NRRD (coefficients or sampled field), as a 3MF level set or
//! as an OpenVDB level set.

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::args::{OutputArgs, PathArg};
use crate::output::outln;
use crate::report::{self, Seconds};

#[derive(Args)]
#[command(
    after_help = "Examples:\n  pgvol export part.pgv -o part.3mf --res 256\n  pgvol export part.pgv -o part.vdb --band 3 --half"
)]
pub struct ExportArgs {
    /// Input .pgv file.
    pub input: PathArg,
    /// Output file: .nrrd, .npy (the sampled field, float32 of shape (nz, ny, nx)), .3mf or
    /// .vdb (an OpenVDB level-set FloatGrid named "surface", nodes as voxel centres).
    #[arg(short, long)]
    pub output: PathArg,
    /// What a NRRD holds: the coefficient grid itself (readable by `pgvol encode --from`) or
    /// the field sampled on a grid. A .3mf or .npy always holds the sampled field.
    #[arg(long, value_enum, default_value_t)]
    pub what: WhatArg,
    /// Sample on N nodes along the longest side over the same box (default: the stored grid).
    #[arg(long, value_parser = clap::value_parser!(u32).range(pgvol::limits::MIN_RES as i64..=pgvol::limits::MAX_RES as i64))]
    pub res: Option<u32>,
    /// The unit a .3mf names for the model's coordinates: micron, millimeter, centimeter,
    /// inch, foot or meter.
    #[arg(long, default_value = pgvol::limits::THREEMF_UNIT)]
    pub unit: String,
    /// A .vdb's narrow band half-width in voxels: nodes nearer the surface are active, the
    /// others hold ±W·spacing [default: 3].
    #[arg(long, value_name = "W")]
    pub band: Option<f32>,
    /// Store a .vdb's values as 16-bit half floats.
    #[arg(long)]
    pub half: bool,
    /// How a .vdb's value chunks are stored [default: zip].
    #[arg(long, value_enum)]
    pub vdb_compression: Option<VdbCompressionArg>,
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

/// How a .vdb's value chunks are stored.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VdbCompressionArg {
    /// zlib, as OpenVDB's "zip" compression: the smaller file.
    #[default]
    Zip,
    /// Raw values.
    None,
}

pub fn run(a: ExportArgs) -> Result<()> {
    let start = std::time::Instant::now();
    let kind = pgvol::ExportKind::from_path(&a.output, a.what == WhatArg::Coefficients)?;
    let vdb_options = a.band.is_some() || a.half || a.vdb_compression.is_some();
    if vdb_options && kind != pgvol::ExportKind::Vdb {
        anyhow::bail!("--band, --half and --vdb-compression apply to a .vdb output");
    }
    let file = pgvol::io::read_pgv(&a.input)?;
    let options = pgvol::ExportOptions {
        kind: Some(kind),
        res: a.res.map(|r| r as usize),
        unit: &a.unit,
        band: a.band.unwrap_or(pgvol::limits::VDB_BAND),
        half: a.half,
        compression: match a.vdb_compression.unwrap_or_default() {
            VdbCompressionArg::Zip => pgvol::io::VdbCompression::Zip,
            VdbCompressionArg::None => pgvol::io::VdbCompression::None,
        },
    };
    let grid = pgvol::io::export(&a.output, &file, &options)?;
    let what = match kind {
        pgvol::ExportKind::CoefficientsNrrd => "coefficients",
        pgvol::ExportKind::Vdb => "level set",
        _ => "sdf",
    };
    let bytes = std::fs::metadata(&a.output)?.len();
    let unit = (kind == pgvol::ExportKind::ThreeMf).then_some(a.unit.as_str());
    if a.out.json {
        return report::print(
            &serde_json::json!({
                "output": a.output, "what": what, "grid": grid, "bytes": bytes, "unit": unit,
            }),
            &Seconds::since(start),
        );
    }
    if !a.out.quiet {
        let [nx, ny, nz] = grid.dims;
        let unit = unit.map(|u| format!(", unit {u}")).unwrap_or_default();
        outln!(
            "{}: {what} on {nx} x {ny} x {nz} nodes, {bytes} bytes{unit}",
            a.output.display()
        );
    }
    Ok(())
}
