//! The payload's two brick maps: which file bricks are stored (those holding a coefficient the
//! band needs), and the side of each of the others, with the constant that stands for every
//! coefficient of an unstored brick.

use pgvol_field::CoefficientVolume;
use rayon::prelude::*;

use super::bricks::Bricks;
use super::coverage::{Coverage, INSIDE, MORE_INSIDE, MORE_OUTSIDE, OUTSIDE, STORED};
use super::stored_band::KeptBrick;

/// Bit `b` (byte `b/8`, LSB first) set for each kept brick `b`, as the payload stores it.
pub(crate) fn stored_map(total: usize, kept: &[KeptBrick]) -> Vec<u8> {
    let mut map = vec![0u8; total.div_ceil(8)];
    for k in kept {
        map[k.index / 8] |= 1 << (k.index % 8);
    }
    map
}

/// The value of the unstored bricks: `-clamp` inside, `clamp` outside.
pub(crate) struct Background {
    /// Bit `b` set for each unstored brick `b` that is inside; clear for stored bricks.
    pub(crate) inside: Vec<u8>,
    pub(crate) clamp: f32,
}

/// The side of each unstored file brick is the sign of its mean coefficient. The clamp is the
/// volume's background when its two sides are `±` one value, so a sparse volume keeps its
/// background exactly (its stored bricks may exceed it where no longer needed); otherwise (a
/// dense volume, or sides of different magnitudes) the largest magnitude of an unstored brick's
/// coefficient, so a banded distance field keeps its clamp value; with none other than 0,
/// `band` grid spacings (at least one).
///
/// Bricks holding no stored grid brick take their side from the grid's background sides
/// (`coverage`) without reading a node; the others are read.
pub(crate) fn background(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    coverage: &Coverage,
    stored: &[u8],
    band: f32,
) -> Background {
    let mut inside = vec![0u8; stored.len()];
    let largest = sides_of_layers(
        volume,
        bricks,
        coverage,
        stored,
        0..bricks.count[2],
        &mut inside,
    );
    let clamp = clamp_of(volume, volume.coeffs.is_full(), largest, band);
    Background { inside, clamp }
}

/// The sides of the unstored file bricks of the layers `layers` along z, set in `inside` (bit
/// per file brick, as the payload stores it); returns the largest magnitude of their
/// coefficients. Reads the coverage and the coefficients of those layers only.
pub(crate) fn sides_of_layers(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    coverage: &Coverage,
    stored: &[u8],
    layers: std::ops::Range<usize>,
    inside: &mut [u8],
) -> f32 {
    let bg = volume.coeffs.background();
    let symmetric = bg.outside.abs() == bg.inside.abs();
    let per_layer = bricks.count[0] * bricks.count[1];
    let sides: Vec<(usize, bool, f32)> = (layers.start * per_layer..layers.end * per_layer)
        .into_par_iter()
        .filter(|&b| stored[b / 8] >> (b % 8) & 1 == 0)
        .map_init(Vec::new, |values, b| {
            let flags = coverage.flags(b);
            let (inside, big) = if flags & STORED != 0
                || !symmetric && flags & OUTSIDE != 0 && flags & INSIDE != 0
            {
                mean_sign(volume, bricks, b, values)
            } else {
                background_side(bg.outside, bg.inside, flags)
            };
            (b, inside, big)
        })
        .collect();
    let mut largest = 0.0f32;
    for (b, side, big) in sides {
        inside[b / 8] |= (side as u8) << (b % 8);
        largest = largest.max(big);
    }
    largest
}

/// The clamp of a file of `volume` (see [`background`]) whose unstored bricks' largest
/// coefficient magnitude is `largest`; `full` tells whether every grid brick of the whole
/// volume is stored.
pub(crate) fn clamp_of(volume: &CoefficientVolume, full: bool, largest: f32, band: f32) -> f32 {
    let bg = volume.coeffs.background();
    let symmetric = bg.outside.abs() == bg.inside.abs();
    if !full && symmetric && bg.outside != 0.0 {
        bg.outside.abs()
    } else if largest == 0.0 {
        band.max(1.0) * volume.grid.spacing
    } else {
        largest
    }
}

/// Whether the mean of unstored file brick `b`'s coefficients is negative, and their largest
/// magnitude, reading them.
fn mean_sign(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    b: usize,
    values: &mut Vec<f32>,
) -> (bool, f32) {
    let (lo, n) = bricks.extent(b);
    values.resize(n[0] * n[1] * n[2], 0.0);
    volume.coeffs.gather(lo, n, values);
    // Eight running sums, not one: a single chain of dependent additions took a tenth of a
    // 2048³ encode. Only a sum within rounding of zero can take another sign.
    const LANES: usize = 8;
    let (mut sums, mut largest) = ([0.0f64; LANES], [0.0f32; LANES]);
    for chunk in values.chunks(LANES) {
        for (i, &c) in chunk.iter().enumerate() {
            sums[i] += c as f64;
            largest[i] = largest[i].max(c.abs());
        }
    }
    let sum: f64 = sums.iter().sum();
    (sum < 0.0, largest.into_iter().fold(0.0, f32::max))
}

/// As [`mean_sign`] for a file brick of background only (`flags` from [`Coverage`]), whose
/// values are `outside` and `inside`, equal in magnitude if both occur: the sum is exact in
/// f64 either way, so its sign is that of the majority side's value.
fn background_side(outside: f32, inside: f32, flags: u8) -> (bool, f32) {
    match (flags & OUTSIDE != 0, flags & INSIDE != 0) {
        (true, false) => (outside < 0.0, outside.abs()),
        (false, true) => (inside < 0.0, inside.abs()),
        _ => {
            let negative = if flags & MORE_INSIDE != 0 {
                inside < 0.0
            } else if flags & MORE_OUTSIDE != 0 {
                outside < 0.0
            } else {
                // As many nodes each side: the two values cancel.
                outside < 0.0 && inside < 0.0
            };
            (negative, outside.abs().max(inside.abs()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::stored_band::stored_band;
    use crate::sparse::test_volumes::{dense, sparse, BASES};
    use pgvol_core::Background as Sides;

    /// The sign of each unstored brick's mean coefficient and their largest magnitude, node by
    /// node.
    fn by_every_node(volume: &CoefficientVolume, bricks: &Bricks, stored: &[u8]) -> (Vec<u8>, f32) {
        let mut inside = vec![0u8; stored.len()];
        let mut largest = 0.0f32;
        for b in (0..bricks.total()).filter(|b| stored[b / 8] >> (b % 8) & 1 == 0) {
            let (lo, n) = bricks.extent(b);
            let mut sum = 0.0f64;
            for k in lo[2]..lo[2] + n[2] {
                for j in lo[1]..lo[1] + n[1] {
                    for i in lo[0]..lo[0] + n[0] {
                        let c = volume.coeffs.get([i, j, k]);
                        sum += c as f64;
                        largest = largest.max(c.abs());
                    }
                }
            }
            inside[b / 8] |= ((sum < 0.0) as u8) << (b % 8);
        }
        (inside, largest)
    }

    #[test]
    fn sides_are_the_mean_signs_and_the_clamp_the_sparse_background() {
        let asymmetric = Sides {
            outside: 0.25,
            inside: -0.5,
        };
        for basis in BASES {
            for (volume, clamp) in [
                (dense([13, 7, 9], basis, 3, 0.5), None),
                (sparse(basis, Sides::clamp(0.3), 7), Some(0.3)),
                (sparse(basis, asymmetric, 9), None),
            ] {
                for edge in [2, 5, 8, 16] {
                    for band in [0.0, 1.0, 2.0] {
                        let bricks = Bricks::new(volume.grid.dims, edge);
                        let coverage = Coverage::new(&volume.coeffs, &bricks);
                        let kept = stored_band(&volume, &bricks, &coverage, band);
                        let stored = stored_map(bricks.total(), &kept);
                        let got = background(&volume, &bricks, &coverage, &stored, band);
                        let (inside, largest) = by_every_node(&volume, &bricks, &stored);
                        let what = format!("{basis} edge {edge} band {band}");
                        assert_eq!(got.inside, inside, "{what}");
                        let want = clamp.unwrap_or(if largest == 0.0 {
                            band.max(1.0) * volume.grid.spacing
                        } else {
                            largest
                        });
                        assert_eq!(got.clamp, want, "{what}");
                    }
                }
            }
        }
    }
}
