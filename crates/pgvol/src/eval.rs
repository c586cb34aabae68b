//! The field's value and analytic gradient at given points, and the point files that carry them.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use glam::Vec3;
use pgvol_field::CoefficientVolume;

use crate::error::{Error, ErrorKind, Result};

/// Parses points, one `x,y,z` per line (commas, semicolons, spaces or tabs between); blank lines
/// and lines starting with `#` are skipped, and so is a first line without numbers (a header).
/// Any other line that is not three finite numbers is an error naming the line; `name` labels
/// errors.
pub fn read_points(r: impl Read, name: &Path) -> Result<Vec<Vec3>> {
    let fail = |message: String| Error::new(ErrorKind::InputFile, message).at(name);
    let mut points = Vec::new();
    for (n, line) in BufReader::new(r).lines().enumerate() {
        let line = line.map_err(|e| fail(format!("line {} is not text: {e}", n + 1)))?;
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
            _ => {
                return Err(fail(format!(
                    "line {}: expected three finite numbers x,y,z, got '{line}'",
                    n + 1
                )))
            }
        }
    }
    if points.is_empty() {
        return Err(fail("no points".into()));
    }
    Ok(points)
}

/// Reads the points of a file; see [`read_points`].
pub fn read_points_file(path: &Path) -> Result<Vec<Vec3>> {
    let file = std::fs::File::open(path).map_err(|e| {
        Error::new(ErrorKind::InputFile, format!("cannot open: {e}"))
            .at(path)
            .caused_by(e)
    })?;
    read_points(file, path)
}

/// Value and gradient of `volume` at each point, in parallel.
pub fn eval(volume: &CoefficientVolume, points: &[Vec3]) -> Vec<(f32, Vec3)> {
    volume.eval_many(points)
}

/// The rows `x,y,z,value,gx,gy,gz` of [`eval`]'s results, with a header line.
pub fn eval_csv(points: &[Vec3], results: &[(f32, Vec3)]) -> String {
    let mut text = String::from("x,y,z,value,gx,gy,gz\n");
    for (p, (v, g)) in points.iter().zip(results) {
        text.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            p.x, p.y, p.z, v, g.x, g.y, g.z
        ));
    }
    text
}
