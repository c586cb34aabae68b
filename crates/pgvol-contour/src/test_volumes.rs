//! Volumes shared by the unit tests.

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};

/// Two overlapping balls on a 40³ grid over [-1, 1]³, interpolated in `basis`.
pub(crate) fn two_balls(basis: Basis) -> CoefficientVolume {
    let grid = Grid {
        origin: Vec3::splat(-1.0),
        spacing: 2.0 / 39.0,
        dims: [40, 40, 40],
        offset: Default::default(),
    };
    let mut s = Vec::with_capacity(grid.len());
    for k in 0..40 {
        for j in 0..40 {
            for i in 0..40 {
                let p = grid.point(i, j, k);
                s.push(
                    (p - Vec3::new(0.2, 0.0, 0.1))
                        .length()
                        .min((p + Vec3::new(0.4, 0.3, 0.0)).length())
                        - 0.35,
                );
            }
        }
    }
    CoefficientVolume::interpolate(grid, basis, s).unwrap()
}
