//! The field every method falls back on away from its own reach: the signed distance to the
//! tangent planes of the nearest points, blended with Gaussian weights (an implicit moving
//! least-squares surface, Kolluri 2008). It has the right sign at any distance and is a
//! distance near the surface, so it closes the band and tells inside from outside.

use glam::Vec3;

use crate::index::PointIndex;

/// Points blended per query. One more is fetched, and every weight is lowered by that one's, so
/// a point enters or leaves the blend with weight zero and the field stays continuous.
pub const TANGENT_NEIGHBOURS: usize = 10;

/// Gaussian width of the blend, in point spacings: wide enough to average the noise of a few
/// neighbours, narrow enough to keep features a few spacings across.
pub const TANGENT_WIDTH: f32 = 2.0;

/// Signed distance to the blended tangent planes of an oriented cloud, within `reach` of it.
pub struct TangentField<'a> {
    index: PointIndex<'a>,
    normals: &'a [Vec3],
    width2: f32,
    reach: f32,
}

impl<'a> TangentField<'a> {
    /// The field of `points` (mean spacing `spacing`), defined within `reach` of them.
    pub fn new(points: &'a [Vec3], normals: &'a [Vec3], spacing: f32, reach: f32) -> Self {
        let width = TANGENT_WIDTH * spacing.max(f32::MIN_POSITIVE);
        // Half the reach: a query scans at most 5³ cells.
        let cell = (0.5 * reach).max(width);
        Self {
            index: PointIndex::new(points, cell),
            normals,
            width2: width * width,
            reach,
        }
    }

    /// The field at `x`, `None` farther than the reach from every point; `near` is scratch.
    pub fn value(&self, x: Vec3, near: &mut Vec<(f32, u32)>) -> Option<f32> {
        near.clear();
        self.index
            .for_each_within(x, self.reach, |j, d2| near.push((d2, j as u32)));
        if near.is_empty() {
            return None;
        }
        let k = TANGENT_NEIGHBOURS + 1;
        if near.len() > k {
            near.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            near.truncate(k);
        }
        near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let (d0, nearest) = near[0];
        let points = self.index.points();
        let plane = |j: u32| self.normals[j as usize].dot(x - points[j as usize]);
        // Relative to the nearest, so far queries do not underflow to 0/0.
        let gauss = |d2: f32| (-(d2 - d0) / self.width2).exp();
        let cut = if near.len() > TANGENT_NEIGHBOURS {
            near.pop().map_or(0.0, |(d2, _)| gauss(d2))
        } else {
            0.0
        };
        let (mut sum, mut weights) = (0.0f32, 0.0f32);
        for &(d2, j) in near.iter() {
            let w = gauss(d2) - cut;
            sum += w * plane(j);
            weights += w;
        }
        Some(if weights > 1e-12 {
            sum / weights
        } else {
            plane(nearest)
        })
    }

    /// The tangent plane of the nearest point at any distance: the side of a node that no
    /// point is within reach of.
    pub fn far_side(&self, x: Vec3) -> f32 {
        let mut near = Vec::new();
        self.index.nearest(x, 1, f32::MAX, &mut near);
        near.first().map_or(1.0, |&(_, j)| {
            self.normals[j as usize].dot(x - self.index.points()[j as usize])
        })
    }
}
