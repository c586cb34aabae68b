//! Points and evaluations as the command line writes them.

use pgvol::glam::DVec3;
use pgvol::{Evaluation, Field};
use serde::Serialize;

/// A query point as a report gives it: single precision near the origin, full f64 for a field
/// with a frame offset (as [`eval_csv`] writes it).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ReportPoint {
    /// A point of a field near the origin.
    Single([f32; 3]),
    /// A point of a field far from the origin.
    Double([f64; 3]),
}

/// `p` as [`ReportPoint`] for `shape`.
pub fn point_json(shape: &Field, p: DVec3) -> ReportPoint {
    if shape.grid().offset != DVec3::ZERO {
        ReportPoint::Double(p.to_array())
    } else {
        ReportPoint::Single(p.as_vec3().to_array())
    }
}

/// The rows `x,y,z,value,gx,gy,gz,exact` of [`Field::eval`]'s results (`exact` 1 or 0), with a header
/// line. Points are written as single precision for a field near the origin (as read), and in
/// full f64 for a field with a frame offset, so a far point is written as given.
pub fn eval_csv(shape: &Field, points: &[DVec3], results: &[Evaluation]) -> String {
    let far = shape.grid().offset != DVec3::ZERO;
    let mut text = String::from("x,y,z,value,gx,gy,gz,exact\n");
    for (p, e) in points.iter().zip(results) {
        let [gx, gy, gz] = e.gradient;
        let [x, y, z] = if far {
            p.to_array().map(|c| c.to_string())
        } else {
            p.as_vec3().to_array().map(|c| c.to_string())
        };
        text.push_str(&format!(
            "{x},{y},{z},{},{gx},{gy},{gz},{}\n",
            e.value,
            u8::from(e.exact)
        ));
    }
    text
}
