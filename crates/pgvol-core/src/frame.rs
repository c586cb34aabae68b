//! Where a mesh or grid sits in the world: a translation kept in f64 beside the f32 local
//! coordinates, so precision follows an object's size and not its distance from the origin.
//!
//! World position = `offset + local`. Objects near the origin keep a zero offset (their local
//! coordinates are the file's own, bit for bit); an object whose centre lies more than
//! [`FAR_RATIO`] sizes away is recentred on a nearby round point.

use glam::{DVec3, Vec3};

/// A mesh whose bounding-box centre is farther from the origin than this many times its
/// longest extent is recentred. At this ratio f32 coordinates still resolve 1/130,000 of the
/// size (ulp 2^-23 at 64 sizes), below a thousandth of a grid spacing at 2048 nodes per axis.
pub const FAR_RATIO: f64 = 64.0;

/// The offset to subtract from world coordinates spanning `[lo, hi]`, axis by axis: zero on an
/// axis where the box's centre is near the origin (and for an empty box), so those coordinates
/// stay exactly as given; on a far axis the centre rounded to a multiple of a power of two no
/// larger than the box's longest extent, so local coordinates stay within about one size of
/// zero and the offset has short decimal and binary forms.
pub fn recentring_offset(lo: DVec3, hi: DVec3) -> DVec3 {
    let size = (hi - lo).max_element();
    let centre = (lo + hi) * 0.5;
    if !(size > 0.0 && size.is_finite() && centre.is_finite()) {
        return DVec3::ZERO;
    }
    let step = 2f64.powi(size.log2().floor() as i32);
    DVec3::from_array(centre.to_array().map(|c| {
        if c.abs() <= FAR_RATIO * size {
            0.0
        } else {
            (c / step).round() * step
        }
    }))
}

/// Bounds of `points`, `None` when there are none.
pub fn world_bounds(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

/// `world − offset`, rounded once to f32.
#[inline]
pub fn to_local(world: DVec3, offset: DVec3) -> Vec3 {
    (world - offset).as_vec3()
}

/// `offset + local`, exact in f64.
#[inline]
pub fn to_world(local: Vec3, offset: DVec3) -> DVec3 {
    offset + local.as_dvec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_meshes_keep_a_zero_offset() {
        let lo = DVec3::new(-1.0, 0.5, 2.0);
        assert_eq!(recentring_offset(lo, lo + DVec3::ONE), DVec3::ZERO);
        assert_eq!(
            recentring_offset(DVec3::splat(60.0), DVec3::splat(61.0)),
            DVec3::ZERO
        );
    }

    #[test]
    fn far_meshes_are_recentred_on_a_round_point_near_their_centre() {
        let lo = DVec3::new(1e6, 1e6, 1e6);
        let off = recentring_offset(lo, lo + DVec3::ONE);
        assert!((off - (lo + 0.5)).abs().max_element() <= 0.5);
        assert_eq!(off.as_vec3().as_dvec3(), off);
        let lo = DVec3::new(-3e7, 0.0, 0.0);
        let off = recentring_offset(lo, lo + DVec3::splat(1e-3));
        assert!((off.x + 3e7 - 5e-4).abs() <= 1e-3, "{off}");
        // Only the far axis moves: the others keep their coordinates exactly.
        assert_eq!((off.y, off.z), (0.0, 0.0));
    }
}
