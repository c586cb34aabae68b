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

use glam::Vec3;
use pgvol_field::fit::{interp_sparse, node_values_sparse};
use pgvol_field::CoefficientVolume;

use crate::csg::{check, cut_drains, drain_reaches, drain_units, Drain};
use crate::error::OpsError;
use crate::measure::{measure_field, FieldMeasure};
use crate::remap::map_nodes;

/// A lattice solid with the measures of its field and of the part's, taken from the node values
/// both pass through anyway.
#[derive(Clone, Debug)]
pub struct LatticeSolid {
    pub volume: CoefficientVolume,
    pub solid: FieldMeasure,
    pub part: FieldMeasure,
}

/// The part's node values mapped by `f` and interpolated again, measured before and after.
fn solid_of(
    volume: &CoefficientVolume,
    f: impl Fn(Vec3, f32) -> f32 + Sync,
    varies: impl Fn(Vec3, Vec3, f32) -> bool + Sync,
) -> Result<LatticeSolid, OpsError> {
    let mut values = node_values_sparse(volume);
    let part = measure_field(&values, &volume.grid);
    map_nodes(&mut values, volume.grid, f, varies);
    let solid = measure_field(&values, &volume.grid);
    let (volume, _) = interp_sparse(
        volume.grid,
        volume.basis,
        &values,
        pgvol_core::progress::QUIET,
    )?;
    Ok(LatticeSolid {
        volume,
        solid,
        part,
    })
}

/// The part intersected with the lattice: `max(f, lattice)`.
pub fn lattice_part(
    volume: &CoefficientVolume,
    lattice: &Lattice,
) -> Result<LatticeSolid, OpsError> {
    lattice.check()?;
    // Nodes whose part value exceeds every lattice value keep it: no lattice to evaluate.
    let above = lattice.max_value();
    let cut = |p, v: f32| {
        if v >= above {
            v
        } else {
            v.max(lattice.value(p, v))
        }
    };
    solid_of(volume, cut, |_, _, v| v < 0.0)
}

/// The part hollowed to walls of `wall` thickness with the cavity filled by the lattice,
/// `max(f, min(−(f + wall), lattice))`, and the drains cut through wall and lattice alike so
/// that powder or resin can leave.
pub fn infill(
    volume: &CoefficientVolume,
    wall: f32,
    lattice: &Lattice,
    drains: &[Drain],
) -> Result<LatticeSolid, OpsError> {
    check("wall thickness", wall, true)?;
    lattice.check()?;
    let units = drain_units(drains)?;
    solid_of(
        volume,
        |p, v| {
            // Outside the part, −(v + w) < v already: the lattice cannot win the max.
            let filled = if v >= 0.0 {
                v
            } else {
                v.max((-(v + wall)).min(lattice.value(p, v)))
            };
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
