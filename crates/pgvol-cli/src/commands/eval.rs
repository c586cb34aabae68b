//! `pgvol eval`: the field's value and gradient at given points.

use std::io::{BufRead, Write};

use anyhow::{bail, Context, Result};
use clap::Args;
use glam::Vec3;

use super::{OutputArgs, PathArg};

#[derive(Args)]
pub struct EvalArgs {
    /// A .pgv file.
    pub input: PathArg,
    /// Points, one `x,y,z` per line (commas, semicolons or spaces; a header line and lines
    /// starting with # are skipped).
    pub points: PathArg,
    /// Write `x,y,z,value,gx,gy,gz` lines here instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathArg>,
    #[command(flatten)]
    pub out: OutputArgs,
}

/// Parses the points file; a line that is not three numbers is an error naming the line, except
/// a first line without digits-only fields (a header).
fn read_points(path: &std::path::Path) -> Result<Vec<Vec3>> {
    let file =
        std::fs::File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
    let mut points = Vec::new();
    for (n, line) in std::io::BufReader::new(file).lines().enumerate() {
        let line =
            line.with_context(|| format!("{}: line {} is not text", path.display(), n + 1))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split([',', ';', ' ', '\t'])
            .filter(|f| !f.is_empty())
            .collect();
        let numbers: Option<Vec<f32>> = fields.iter().map(|f| f.parse::<f32>().ok()).collect();
        match numbers {
            Some(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => {
                points.push(Vec3::new(v[0], v[1], v[2]))
            }
            None if n == 0 => continue,
            _ => bail!(
                "{}: line {}: expected three finite numbers x,y,z, got '{line}'",
                path.display(),
                n + 1
            ),
        }
    }
    if points.is_empty() {
        bail!("{}: no points", path.display());
    }
    Ok(points)
}

pub fn run(a: EvalArgs) -> Result<()> {
    let file = pgvol_format::read_pgv(&a.input)?;
    let points = read_points(&a.points)?;
    let results = file.volume.eval_many(&points);
    if a.out.json {
        let rows: Vec<_> = points
            .iter()
            .zip(&results)
            .map(|(p, (v, g))| serde_json::json!({ "point": p.to_array(), "value": v, "gradient": g.to_array() }))
            .collect();
        println!("{}", serde_json::to_string(&rows)?);
        return Ok(());
    }
    let mut text = String::from("x,y,z,value,gx,gy,gz\n");
    for (p, (v, g)) in points.iter().zip(&results) {
        text.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            p.x, p.y, p.z, v, g.x, g.y, g.z
        ));
    }
    match &a.output {
        Some(path) => pgvol_mesh::write_atomic(path, |w| w.write_all(text.as_bytes()))?,
        None => std::io::stdout().write_all(text.as_bytes())?,
    }
    Ok(())
}
