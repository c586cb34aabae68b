//! Bounds of a coefficient volume over a box of points, from the coefficients that can weigh on
//! it.
//!
//! For the B-spline and trilinear bases every field value is a convex combination of the
//! coefficients in its support (non-negative weights summing to one), so where those of a box
//! all lie above (below) the iso value the field does too, and their minimum (maximum) bounds
//! it. An absent coefficient brick holds its side's background, so a box whose supporting
//! bricks are all absent is decided from their sides alone, without reading a coefficient.
//!
//! Which bricks a box reaches depends on each axis separately, so the kinds reached by every
//! brick of a sampling grid are found by three one-axis passes over one byte per coefficient
//! brick, whatever the size of the supports.

use std::ops::Range;

use glam::Vec3;
use pgvol_core::{Background, SparseGrid, BRICK_EDGE};
use pgvol_field::{CoefficientVolume, Grid};
use rayon::prelude::*;

use crate::window_or::or_over_boxes;

/// Kinds of coefficient brick, as bits so that a set of bricks is their OR.
pub(crate) const OUTSIDE_BACKGROUND: u8 = 1;
pub(crate) const INSIDE_BACKGROUND: u8 = 2;
/// Every stored brick has this bit, and one of the next three.
pub(crate) const STORED: u8 = 4;
/// A stored brick whose coefficients all lie clearly above the iso value ([`clearly_above`]).
const STORED_ABOVE: u8 = 8;
/// A stored brick whose coefficients all lie clearly below the iso value.
const STORED_BELOW: u8 = 16;
/// A stored brick with coefficients on both sides of the iso value, or near it.
const STORED_MIXED: u8 = 32;

/// Whether a field value that is a convex combination of coefficients of at least `min` lies
/// above `iso` whatever the rounding of the combination: by a margin far beyond f32 rounding.
fn clearly_above(min: f32, iso: f32) -> bool {
    min - iso > 1e-5 * (min.abs() + iso.abs())
}

/// First and last coefficient node per axis of a volume on grid `g` that can weigh on a point
/// of the box `[lo, hi]`.
pub(crate) fn coefficient_ranges(g: &Grid, lo: Vec3, hi: Vec3) -> [[usize; 2]; 3] {
    let (ulo, uhi) = (g.to_grid(lo), g.to_grid(hi));
    // Every basis here reaches at most 2 nodes from the cell holding the point; mirrored indices
    // beyond the border repeat coefficients inside it, so the clamped range covers them.
    [0, 1, 2].map(|a| {
        let n = g.dims[a] as i64;
        [
            (ulo[a].floor() as i64 - 2).clamp(0, n - 1) as usize,
            (uhi[a].ceil() as i64 + 2).clamp(0, n - 1) as usize,
        ]
    })
}

/// The kind of every coefficient brick in the box of bricks `span` (per axis), x fastest, one
/// byte each; stored bricks are told apart by the sides of their coefficients against `iso`.
fn brick_kinds(coeffs: &SparseGrid, span: [Range<usize>; 3], iso: f32) -> Vec<u8> {
    let [sx, sy, _] = span.clone().map(|r| r.len());
    let mut kinds = vec![0u8; sx * sy * span[2].len()];
    if sx * sy == 0 {
        return kinds;
    }
    kinds
        .par_chunks_mut(sx * sy)
        .enumerate()
        .for_each(|(k, layer)| {
            for (at, kind) in layer.iter_mut().enumerate() {
                let b = [
                    span[0].start + at % sx,
                    span[1].start + at / sx,
                    span[2].start + k,
                ];
                *kind = if let Some(values) = coeffs.brick(b) {
                    let (min, max) = values
                        .iter()
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &c| {
                            (lo.min(c), hi.max(c))
                        });
                    STORED
                        | if clearly_above(min, iso) {
                            STORED_ABOVE
                        } else if clearly_above(-max, -iso) {
                            STORED_BELOW
                        } else {
                            STORED_MIXED
                        }
                } else if coeffs.is_inside(b) {
                    INSIDE_BACKGROUND
                } else {
                    OUTSIDE_BACKGROUND
                };
            }
        });
    kinds
}

/// For boxes that are products of per-axis coefficient node ranges (`ranges[a][s]`, first and
/// last node), the OR of the kinds of the coefficient bricks each reaches (x fastest). Only
/// the bricks the boxes reach are read, so a small sampling grid on a large volume costs its
/// own share of the volume.
pub(crate) fn support_kinds(coeffs: &SparseGrid, ranges: [&[[usize; 2]]; 3], iso: f32) -> Vec<u8> {
    let mut bricks = ranges.map(|r| -> Vec<Range<usize>> {
        r.iter()
            .map(|&[first, last]| first / BRICK_EDGE..last / BRICK_EDGE + 1)
            .collect()
    });
    let span = bricks.each_mut().map(|axis| {
        let lo = axis.iter().map(|r| r.start).min().unwrap_or(0);
        let hi = axis.iter().map(|r| r.end).max().unwrap_or(lo);
        for r in axis.iter_mut() {
            *r = r.start - lo..r.end - lo;
        }
        lo..hi
    });
    let dims = span.clone().map(|r| r.len());
    let kinds = brick_kinds(coeffs, span, iso);
    or_over_boxes(&kinds, dims, [&bricks[0], &bricks[1], &bricks[2]])
}

/// The one-sided bound (see [`one_side`]) of a box whose supporting bricks are all absent, of
/// the kinds in `kinds`.
pub(crate) fn background_bound(background: Background, kinds: u8, iso: f32) -> Option<f32> {
    let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
    for (kind, value) in [
        (OUTSIDE_BACKGROUND, background.outside),
        (INSIDE_BACKGROUND, background.inside),
    ] {
        if kinds & kind != 0 {
            min = min.min(value);
            max = max.max(value);
        }
    }
    one_side(min, max, iso)
}

/// Whether every field value over a box whose supporting bricks are of the kinds in `kinds` lies
/// above iso (`Some(true)`) or below it (`Some(false)`), decided from the kinds alone: the
/// stored bricks' sides (read once per brick) and the backgrounds' values. `None` when they
/// differ or a stored brick holds both sides.
pub(crate) fn support_side(background: Background, kinds: u8, iso: f32) -> Option<bool> {
    if kinds & STORED_MIXED != 0 {
        return None;
    }
    let (mut above, mut below) = (kinds & STORED_ABOVE != 0, kinds & STORED_BELOW != 0);
    for (kind, value) in [
        (OUTSIDE_BACKGROUND, background.outside),
        (INSIDE_BACKGROUND, background.inside),
    ] {
        if kinds & kind != 0 {
            if clearly_above(value, iso) {
                above = true;
            } else if clearly_above(-value, -iso) {
                below = true;
            } else {
                return None;
            }
        }
    }
    (above != below).then_some(above)
}

/// The one-sided bound of the coefficients in the node `ranges`, read one by one.
pub(crate) fn gathered_bound(
    volume: &CoefficientVolume,
    ranges: [[usize; 2]; 3],
    iso: f32,
) -> Option<f32> {
    let [[i0, i1], [j0, j1], [k0, k1]] = ranges;
    let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut row = vec![0.0f32; i1 - i0 + 1];
    for k in k0..=k1 {
        for j in j0..=j1 {
            volume
                .coeffs
                .gather([i0, j, k], [row.len(), 1, 1], &mut row);
            for &c in &row {
                min = min.min(c);
                max = max.max(c);
            }
        }
        if min <= iso && max >= iso {
            return None;
        }
    }
    one_side(min, max, iso)
}

/// The bound of values in `[min, max]` when all are on one side of `iso`: `min` above it,
/// `max` below it. Points outside the volume's grid only add their (positive) distance to the
/// box, so a bound from the clamped box still holds there for values above iso.
fn one_side(min: f32, max: f32, iso: f32) -> Option<f32> {
    if min > iso {
        Some(min)
    } else if max < iso {
        // Outside the grid box values grow with distance, so a negative bound could be wrong
        // there; the sampling grids used here lie within the box.
        Some(max)
    } else {
        None
    }
}
