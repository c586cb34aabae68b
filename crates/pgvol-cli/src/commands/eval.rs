//! `pgvol eval`: the field's value and gradient at given points.

use std::io::Write;

use anyhow::Result;
use clap::Args;

use super::args::{OutputArgs, PathArg};
use crate::report::{self, Seconds};

#[derive(Args)]
#[command(after_help = "Example: pgvol eval part.pgv points.csv -o values.csv")]
pub struct EvalArgs {
    /// A .pgv file.
    pub input: PathArg,
    /// Points, one `x,y,z` per line (commas, semicolons or spaces; a first line without numbers
    /// and lines starting with # are skipped). Coordinates must be below 1e8 in magnitude.
    pub points: PathArg,
    /// Write `x,y,z,value,gx,gy,gz,exact` lines here instead of standard output. `exact` is 1
    /// where the value is the signed distance: inside the grid box and within the band the file
    /// stores. Elsewhere (0) the value has the right sign but its magnitude is a clamp (beyond
    /// the band) or an extrapolation (outside the box).
    #[arg(short, long)]
    pub output: Option<PathArg>,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn run(a: EvalArgs) -> Result<()> {
    let start = std::time::Instant::now();
    let shape = pgvol::Field::from_file(pgvol::io::read_pgv(&a.input)?);
    let points = pgvol::io::read_points_file(&a.points)?;
    let results = shape.eval(&points);
    if a.out.json {
        let rows: Vec<_> = points
            .iter()
            .zip(&results)
            .map(|(p, e)| serde_json::json!({ "point": crate::field_text::point_json(&shape, *p), "value": e.value, "gradient": e.gradient, "exact": e.exact }))
            .collect();
        return report::print(
            &serde_json::json!({ "points": rows }),
            &Seconds::since(start),
        );
    }
    let text = crate::field_text::eval_csv(&shape, &points, &results);
    match &a.output {
        Some(path) => pgvol::core::write_atomic(path, |w| w.write_all(text.as_bytes()))?,
        None => std::io::stdout().write_all(text.as_bytes())?,
    }
    Ok(())
}
