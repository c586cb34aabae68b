//! The band a file records: how far from the surface its field is an exact distance.

use pgvol_format::{PgvFile, PgvHeader};

/// Header metadata key holding the distance from the surface, in mesh units, within which the
/// stored field is an exact distance; beyond it the field is a clamp.
pub const BAND_KEY: &str = "band";

/// The distance from the surface within which `file`'s field is exact, when its header records
/// one that makes sense (finite, positive, at most the grid's extent).
pub fn recorded_band(file: &PgvFile) -> Option<f32> {
    header_band(&file.header)
}

/// [`recorded_band`] from the header alone.
pub(crate) fn header_band(header: &PgvHeader) -> Option<f32> {
    let g = header.grid;
    let extent = g.spacing * g.dims.iter().copied().max().unwrap_or(0) as f32;
    header
        .metadata
        .get(BAND_KEY)
        .and_then(|b| b.parse::<f32>().ok())
        .filter(|b| b.is_finite() && *b > 0.0 && *b <= extent)
}
