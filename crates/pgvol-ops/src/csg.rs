//! New coefficient volumes from constructive operations on a field: offsets, shells, hollowing
//! with drain holes.
//!
//! Apart from the constant offset of partition-of-unity bases, every operation evaluates the
//! field at the nodes, combines the node values and interpolates them again in the same basis
//! on the same grid. The results are signed distances only where the input is one: a field
//! encoded from a mesh in a narrow band of width `W` (values clamped to `±W`) represents
//! surfaces only up to about `W` minus the basis support from the original one; see
//! [`needs_wider_band`]. Operations creating creases (the min/max of CSG, the absolute value of
//! a shell) are smoothed over about one grid spacing by the re-interpolation; surfaces away from
//! the crease are unaffected.

use glam::Vec3;
use pgvol_core::progress::{Report, QUIET};
use pgvol_field::fit::node_values_sparse;
use pgvol_field::{Basis, CoefficientVolume};

use crate::error::OpsError;
use crate::remap::remap;

/// Where a shell's wall lies relative to the original surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShellSide {
    /// Between the surface and `thickness` inside it: the outside stays where it was.
    #[default]
    Inner,
    /// Between the surface and `thickness` outside it.
    Outer,
    /// `thickness / 2` on either side.
    Centred,
}

/// A drain hole: the solid ray-capped cylinder starting at `point` and running along
/// `direction`, removed from the part. Put `point` in the cavity and aim `direction` out through
/// the wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drain {
    pub point: Vec3,
    pub direction: Vec3,
    pub diameter: f32,
}

impl Drain {
    /// Exact signed distance to the half-infinite cylinder (flat cap at `point`), given a unit
    /// direction.
    pub(crate) fn distance(&self, unit: Vec3, p: Vec3) -> f32 {
        let d = p - self.point;
        let along = d.dot(unit);
        let radial = (d - unit * along).length() - 0.5 * self.diameter;
        let cap = -along;
        radial.max(cap).min(0.0) + Vec3::new(radial.max(0.0), cap.max(0.0), 0.0).length()
    }
}

pub(crate) fn check(name: &str, x: f32, positive: bool) -> Result<(), OpsError> {
    if !x.is_finite() || (positive && x <= 0.0) {
        let want = if positive {
            "positive and finite"
        } else {
            "finite"
        };
        return Err(OpsError::BadParameter(format!(
            "{name} must be {want}, got {x}"
        )));
    }
    Ok(())
}

/// The largest magnitude of the field's node values. For a narrow-band encoding this is the
/// clamp `W`: beyond it the field is not a distance.
pub fn stored_band(volume: &CoefficientVolume) -> f32 {
    let [lo, hi] = node_values_sparse(volume).value_range();
    lo.abs().max(hi.abs())
}

/// Whether moving the surface by `distance` (an offset, shell thickness or wall) leaves the band
/// where the field is a distance: `|distance|` plus the basis support (2 spacings for the cubic
/// B-spline, which is the widest separable one; the pseudo-Gaussian radius otherwise) reaches
/// [`stored_band`]. Then the result would follow the clamp rather than the shape; re-encode with
/// a wider band first.
pub fn needs_wider_band(volume: &CoefficientVolume, distance: f32) -> bool {
    distance.abs() + support_reach(volume) >= stored_band(volume)
}

/// How far from a level set, in model units, the coefficients that shape it reach: 2 spacings
/// for the B-splines and trilinear (the cubic B-spline's support, the widest separable one),
/// the radius for the pseudo-Gaussian when larger.
pub fn support_reach(volume: &CoefficientVolume) -> f32 {
    let spacings = match volume.basis {
        Basis::Pg { r, .. } => r.max(2.0),
        _ => 2.0,
    };
    spacings * volume.grid.spacing
}

/// The surface moved by `distance` along its normals (outward when positive): the field minus
/// `distance`. B-spline and trilinear bases sum to one at every point (the mirrored border
/// nodes included), so subtracting the constant from every coefficient subtracts it from the
/// field exactly; the pseudo-Gaussian does not, so its node values are shifted and interpolated
/// again.
pub fn offset(volume: &CoefficientVolume, distance: f32) -> Result<CoefficientVolume, OpsError> {
    check("offset distance", distance, false)?;
    match volume.basis {
        Basis::Trilinear | Basis::Bspline2 | Basis::Bspline3 => {
            let mut coeffs = volume.coeffs.clone();
            coeffs.map_values(|c| c - distance);
            Ok(CoefficientVolume::from_sparse(
                volume.grid,
                volume.basis,
                coeffs,
            )?)
        }
        Basis::Pg { .. } => remap(volume, |_, v| v - distance, |_, _, _| false, QUIET),
    }
}

/// A wall of `thickness` following the surface, on the given side: `|f − c| − t/2` with the
/// wall's mid-surface `c` at `−t/2`, `t/2` or 0.
/// Layers of the remap are reported to `report`, which may stop it (see [`hollow`]).
pub fn shell(
    volume: &CoefficientVolume,
    thickness: f32,
    side: ShellSide,
    report: Report,
) -> Result<CoefficientVolume, OpsError> {
    check("shell thickness", thickness, true)?;
    let half = 0.5 * thickness;
    let centre = match side {
        ShellSide::Inner => -half,
        ShellSide::Outer => half,
        ShellSide::Centred => 0.0,
    };
    remap(
        volume,
        |_, v| (v - centre).abs() - half,
        |_, _, _| false,
        report,
    )
}

/// The part with a cavity leaving walls of `wall` thickness, `max(f, −(f + wall))`, and the
/// drains cut out of it, `max(·, −drain)`. The work goes a layer of brick groups at a time,
/// each reported to `report`, which is polled for a stop between layers; a stopped hollowing
/// returns an incomplete volume, which the caller who asked for the stop discards.
pub fn hollow(
    volume: &CoefficientVolume,
    wall: f32,
    drains: &[Drain],
    report: Report,
) -> Result<CoefficientVolume, OpsError> {
    check("wall thickness", wall, true)?;
    let units = drain_units(drains)?;
    let wall_only = |v: f32| v.max(-(v + wall));
    remap(
        volume,
        |p, v| cut_drains(drains, &units, p, wall_only(v)),
        |lo, hi, v| drain_reaches(drains, &units, lo, hi, wall_only(v)),
        report,
    )
}

/// The unit directions of valid drains, or why one is not.
pub(crate) fn drain_units(drains: &[Drain]) -> Result<Vec<Vec3>, OpsError> {
    let mut units = Vec::with_capacity(drains.len());
    for d in drains {
        check("drain diameter", d.diameter, true)?;
        let u = d.direction.normalize_or_zero();
        if u == Vec3::ZERO || !d.point.is_finite() {
            return Err(OpsError::BadParameter(
                "a drain needs a finite point and a non-zero direction".into(),
            ));
        }
        units.push(u);
    }
    Ok(units)
}

/// The field `value` at `p` with the drains removed from it.
pub(crate) fn cut_drains(drains: &[Drain], units: &[Vec3], p: Vec3, value: f32) -> f32 {
    drains
        .iter()
        .zip(units)
        .fold(value, |g, (d, &u)| g.max(-d.distance(u, p)))
}

/// Whether a drain can change the field over the box `[lo, hi]` whose value without drains is
/// `value`: over a box, a drain's distance varies by at most the box's half diagonal from its
/// value at the centre, and it matters where its negative can exceed `value`.
pub(crate) fn drain_reaches(
    drains: &[Drain],
    units: &[Vec3],
    lo: Vec3,
    hi: Vec3,
    value: f32,
) -> bool {
    let (centre, reach) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    drains
        .iter()
        .zip(units)
        .any(|(d, &u)| -(d.distance(u, centre) - reach) >= value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drain_distance_is_exact_on_simple_points() {
        let d = Drain {
            point: Vec3::ZERO,
            direction: Vec3::Z * 3.0,
            diameter: 1.0,
        };
        let u = Vec3::Z;
        // Radially outside, beside the body.
        assert!((d.distance(u, Vec3::new(2.0, 0.0, 5.0)) - 1.5).abs() < 1e-6);
        // Below the cap, on the axis.
        assert!((d.distance(u, Vec3::new(0.0, 0.0, -2.0)) - 2.0).abs() < 1e-6);
        // Beyond the cap's rim: distance to the circle.
        let p = Vec3::new(3.5, 0.0, -4.0);
        assert!((d.distance(u, p) - 5.0).abs() < 1e-6);
        // Inside: nearest is the wall (0.3 away) rather than the cap (1 away).
        assert!((d.distance(u, Vec3::new(0.2, 0.0, 1.0)) + 0.3).abs() < 1e-6);
    }
}
