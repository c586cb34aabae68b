//! Lattices for additive manufacturing: triply periodic minimal surfaces ([`Tpms`]) as sheet or
//! strut solids ([`Lattice`]), cut to a part ([`lattice_part`]) or filling the cavity of a
//! hollowed part ([`infill`]).
//!
//! Both operations map the part's node values with the lattice's value at each node and
//! interpolate them again, like the other constructive operations. Every brick inside the part
//! holds lattice surface, so it is stored; bricks outside stay background: the cost follows the
//! lattice's surface, which fills the part's inside.

mod field;
mod tpms;

pub use field::{Grade, Lattice, LatticeStyle, Ramp};
pub use tpms::{Tpms, TPMS_NAMES};

use pgvol_field::CoefficientVolume;

use crate::csg::{check, cut_drains, drain_reaches, drain_units, remap, Drain};
use crate::error::OpsError;

/// The part intersected with the lattice: `max(f, lattice)`.
pub fn lattice_part(
    volume: &CoefficientVolume,
    lattice: &Lattice,
) -> Result<CoefficientVolume, OpsError> {
    lattice.check()?;
    remap(volume, |p, v| v.max(lattice.value(p, v)), |_, _, v| v < 0.0)
}

/// The part hollowed to walls of `wall` thickness with the cavity filled by the lattice,
/// `max(f, min(−(f + wall), lattice))`, and the drains cut through wall and lattice alike so
/// that powder or resin can leave.
pub fn infill(
    volume: &CoefficientVolume,
    wall: f32,
    lattice: &Lattice,
    drains: &[Drain],
) -> Result<CoefficientVolume, OpsError> {
    check("wall thickness", wall, true)?;
    lattice.check()?;
    let units = drain_units(drains)?;
    remap(
        volume,
        |p, v| {
            let filled = v.max((-(v + wall)).min(lattice.value(p, v)));
            cut_drains(drains, &units, p, filled)
        },
        |lo, hi, v| v < 0.0 || drain_reaches(drains, &units, lo, hi, v),
    )
}

/// Bricks of 8³ nodes a lattice operation on `volume` stores: those stored already and every
/// brick inside the part.
pub fn lattice_bricks(volume: &CoefficientVolume) -> usize {
    let coeffs = &volume.coeffs;
    coeffs
        .all_bricks()
        .filter(|&b| coeffs.is_stored(b) || coeffs.is_inside(b))
        .count()
}
