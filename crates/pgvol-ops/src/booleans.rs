//! Booleans of distance fields, sharp or rounded, and the brick-by-brick sampling that turns any
//! combination of fields into one coefficient volume.
//!
//! Sharp operations are `min`/`max`. The rounded union of distances `a`, `b` with radius `r` is
//! the circular blend `max(r, min(a, b)) − ‖(max(r − a, 0), max(r − b, 0))‖`, floored at
//! `min(a, b) − r`:
//! * it equals `min(a, b)` wherever `max(a, b) ≥ r`, so the two differ only within `r` of both
//!   surfaces, and `min(a, b) − r ≤ blend ≤ min(a, b)` everywhere;
//! * between two planes at right angles its zero set is a quarter circle of radius `r` tangent
//!   to both: a fillet of exactly the radius asked for;
//! * its gradient is `((r − a)∇a + (r − b)∇b) / ‖·‖` in the blend, so it is Lipschitz with
//!   constant √2 (1 when the operands' gradients are orthogonal), and 1 elsewhere: offsets by
//!   `d` of the result move its surface by between `d/√2` and `d` in the blend.
//!
//! Intersection is the union's mirror, `−union(−a, −b)`, and difference `A − B` the
//! intersection of `a` and `−b`.

use glam::Vec3;
use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, SparseGrid, BRICK_EDGE};
use pgvol_field::{Basis, CoefficientVolume, Grid};
use rayon::prelude::*;

use crate::error::OpsError;

/// Which Boolean operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoolOp {
    Union,
    Intersection,
    /// The first operand less every other one.
    Difference,
}

/// How the operands meet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Blend {
    /// `min` / `max`: creases where the surfaces cross.
    Sharp,
    /// Circular fillets of this radius where the surfaces cross.
    Round(f32),
}

impl Blend {
    /// The Lipschitz constant of the combined field, given operands of constant 1.
    pub fn lipschitz(self) -> f32 {
        match self {
            Blend::Sharp => 1.0,
            Blend::Round(_) => std::f32::consts::SQRT_2,
        }
    }
}

/// The union of two distances (see the module's documentation for the rounded form's bounds).
pub fn union(a: f32, b: f32, blend: Blend) -> f32 {
    match blend {
        Blend::Sharp => a.min(b),
        // Outside the blend the formula reduces to min(a, b); returned exactly.
        Blend::Round(r) if a.max(b) >= r => a.min(b),
        Blend::Round(r) => {
            let (u, v) = (r - a, r - b);
            (r - (u * u + v * v).sqrt()).max(a.min(b) - r)
        }
    }
}

/// The intersection of two distances: the union of the complements, complemented.
pub fn intersection(a: f32, b: f32, blend: Blend) -> f32 {
    -union(-a, -b, blend)
}

/// The operation folded over `values` from the first one.
pub fn combine(op: BoolOp, blend: Blend, values: &[f32]) -> f32 {
    let Some((&first, rest)) = values.split_first() else {
        return f32::NAN;
    };
    rest.iter().fold(first, |acc, &v| match op {
        BoolOp::Union => union(acc, v, blend),
        BoolOp::Intersection => intersection(acc, v, blend),
        BoolOp::Difference => intersection(acc, -v, blend),
    })
}

/// Refuses a blend radius that is not positive and finite.
pub fn check_blend(blend: Blend) -> Result<(), OpsError> {
    match blend {
        Blend::Round(r) if !(r.is_finite() && r > 0.0) => Err(OpsError::BadParameter(format!(
            "the blend radius must be positive and finite, got {r}"
        ))),
        _ => Ok(()),
    }
}

/// One brick of [`sample_bricks`]: its node values, or the side it lies on.
enum Sampled {
    Stored(Box<BrickValues>),
    Absent { inside: bool },
}

/// The coefficient volume interpolating `field`, clamped to `±band`, on `grid`, built brick by
/// brick: a brick is sampled node by node only where `field` at its centre, with Lipschitz
/// constant `lipschitz`, could come within `band` of zero inside it; every other brick is
/// left absent on its side. Cost follows the surface, plus one evaluation per brick.
pub fn sample_bricks(
    grid: Grid,
    basis: Basis,
    band: f32,
    lipschitz: f32,
    field: impl Fn(Vec3) -> f32 + Sync,
) -> Result<CoefficientVolume, OpsError> {
    if !(band.is_finite() && band > 0.0) {
        return Err(OpsError::BadParameter(format!(
            "the band must be positive, got {band}"
        )));
    }
    let mut values = SparseGrid::new(grid.dims, Background::clamp(band));
    let bricks: Vec<[usize; 3]> = values.all_bricks().collect();
    let half_diagonal = 0.5 * 3f32.sqrt() * (BRICK_EDGE - 1) as f32 * grid.spacing;
    let sampled: Vec<([usize; 3], Sampled)> = bricks
        .into_par_iter()
        .map(|b| {
            let lo = b.map(|c| c * BRICK_EDGE);
            let mid = grid.point(lo[0], lo[1], lo[2])
                + Vec3::splat(0.5 * (BRICK_EDGE - 1) as f32 * grid.spacing);
            let v = field(mid);
            // NaN counts as outside and never as far: sampled.
            if v.abs() > lipschitz * half_diagonal + band {
                return (b, Sampled::Absent { inside: v < 0.0 });
            }
            let mut brick = Box::new([0.0f32; BRICK_EDGE * BRICK_EDGE * BRICK_EDGE]);
            for (at, x) in brick.iter_mut().enumerate() {
                let n = [
                    lo[0] + at % BRICK_EDGE,
                    lo[1] + (at / BRICK_EDGE) % BRICK_EDGE,
                    lo[2] + at / (BRICK_EDGE * BRICK_EDGE),
                ];
                let f = field(grid.point(n[0], n[1], n[2]));
                *x = if f.is_nan() {
                    band
                } else {
                    f.clamp(-band, band)
                };
            }
            (b, Sampled::Stored(brick))
        })
        .collect();
    for (b, s) in sampled {
        match s {
            Sampled::Stored(brick) => values.insert(b, brick),
            Sampled::Absent { inside } => values.set_inside(b, inside),
        }
    }
    values.compact_tiles();
    let (volume, _) =
        pgvol_field::fit::interp_sparse(grid, basis, &values, pgvol_core::progress::QUIET)?;
    Ok(volume)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_union_bounds_hold() {
        let r = 0.3;
        let blend = Blend::Round(r);
        for i in 0..60 {
            for j in 0..60 {
                let (a, b) = (-2.0 + i as f32 * 0.07, -2.0 + j as f32 * 0.07);
                let u = union(a, b, blend);
                let m = a.min(b);
                assert!(u <= m + 1e-6 && u >= m - r - 1e-6, "{a} {b} {u}");
                if a.max(b) >= r {
                    assert_eq!(u, m);
                }
            }
        }
        // Two orthogonal planes x = 0, y = 0: the fillet's zero set is the circle of radius r
        // about (r, r).
        for k in 0..=8 {
            let t = k as f32 / 8.0 * std::f32::consts::FRAC_PI_2;
            let p = (r - r * t.cos(), r - r * t.sin());
            assert!(union(p.0, p.1, blend).abs() < 1e-5);
        }
    }

    #[test]
    fn difference_removes_the_later_operands() {
        assert_eq!(
            combine(BoolOp::Difference, Blend::Sharp, &[-1.0, -0.5]),
            0.5
        );
        assert_eq!(
            combine(BoolOp::Union, Blend::Sharp, &[1.0, -0.5, 2.0]),
            -0.5
        );
        assert_eq!(
            combine(BoolOp::Intersection, Blend::Sharp, &[1.0, -0.5]),
            1.0
        );
    }
}
