//! The commands that build in their input's own frame and do not yet carry a frame offset
//! refuse a far input with advice, rather than write a result in the wrong place.

use glam::{DVec3, Vec3};

use crate::error::{Error, Result};

/// Refuses `offset` (of a mesh or a field) for `operation` unless it is zero: for the
/// operations that work in their input's own frame only.
pub fn require_near(offset: DVec3, operation: &str) -> Result<()> {
    if offset == DVec3::ZERO {
        return Ok(());
    }
    Err(Error::parameter(format!(
        "{operation} works only near the origin, and this input lies far from it (about \
         ({}, {}, {}), more than {} times its size away); translate it near the origin first \
         and the result back afterwards, or use remesh, encode, decode, offset, shell, slice \
         or eval, which keep positions far from the origin exact",
        offset.x,
        offset.y,
        offset.z,
        pgvol_core::frame::FAR_RATIO
    )))
}

/// Refuses points read in single precision spanning `[lo, hi]` when they lie far from the
/// origin relative to their extent, where f32 has already rounded them.
pub(crate) fn require_near_box(lo: Vec3, hi: Vec3, operation: &str) -> Result<()> {
    require_near(
        pgvol_core::frame::recentring_offset(lo.as_dvec3(), hi.as_dvec3()),
        operation,
    )
}
