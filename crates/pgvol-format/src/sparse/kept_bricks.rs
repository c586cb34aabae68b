//! Which bricks are stored (those holding a coefficient the band needs), and the constant that
//! stands for every coefficient of each of the others.

use pgvol_field::CoefficientVolume;

use super::bricks::Bricks;

/// Per brick: whether it holds a node the band needs (`needed`, per grid node).
pub(crate) fn kept_bricks(bricks: &Bricks, needed: &[bool]) -> Vec<bool> {
    (0..bricks.total())
        .map(|b| bricks.nodes(b).any(|i| needed[i]))
        .collect()
}

/// The value of the unstored bricks: `-clamp` inside, `clamp` outside.
pub(crate) struct Background {
    /// Per brick; false for stored bricks.
    pub(crate) inside: Vec<bool>,
    pub(crate) clamp: f32,
}

/// Sign by the brick's mean coefficient, magnitude the largest background one, so a banded
/// distance field keeps its clamp value exactly; with no background coefficient other than 0,
/// `band` grid spacings (at least one).
pub(crate) fn background(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    keep: &[bool],
    band: f32,
) -> Background {
    let mut inside = vec![false; bricks.total()];
    let mut clamp = 0.0f32;
    for b in (0..bricks.total()).filter(|&b| !keep[b]) {
        let mut sum = 0.0f64;
        for i in bricks.nodes(b) {
            let c = volume.coeffs.get(bricks.unflat(i));
            sum += c as f64;
            clamp = clamp.max(c.abs());
        }
        inside[b] = sum < 0.0;
    }
    if clamp == 0.0 {
        clamp = band.max(1.0) * volume.grid.spacing;
    }
    Background { inside, clamp }
}
