//! Which bricks need exact distances in a narrow band, and the signs of the others where one
//! winding number decides a whole region.

use glam::Vec3A;

use super::flags::{Bits, RegionSigns};
use super::BRICK;
use crate::{grid::Grid, sdf::MeshSdf};

/// A surface-free region or brick whose winding number is at least this far from 1/2 takes
/// that sign.
pub(super) const REGION_SIGN_MARGIN: f32 = 0.3;

impl MeshSdf {
    /// Which bricks lie within `reach` of some triangle's bounding box: the only ones that can
    /// hold band nodes (the way OpenVDB finds its narrow band). A brick's cell runs up to the
    /// next brick, so no triangle meets the cells of the others, nor a segment between two
    /// neighbouring ones.
    pub(super) fn bricks_near_triangles(
        &self,
        grid: &Grid,
        bricks: [usize; 3],
        reach: f32,
    ) -> Bits {
        // A little more than `reach`, so rounding in the cell arithmetic cannot miss a cell.
        let reach = reach + 0.01 * grid.spacing;
        let mut near = Bits::new(bricks[0] * bricks[1] * bricks[2]);
        let span = grid.spacing * BRICK as f32;
        let cell = |x: f32, axis: usize| -> usize {
            ((x - grid.origin[axis]) / span)
                .floor()
                .clamp(0.0, (bricks[axis] - 1) as f32) as usize
        };
        for t in &self.bvh().tris {
            let lo = t[0].min(t[1]).min(t[2]) - Vec3A::splat(reach);
            let hi = t[0].max(t[1]).max(t[2]) + Vec3A::splat(reach);
            // Brick b spans nodes b·BRICK ..= b·BRICK + BRICK − 1, i.e. up to the next brick.
            let (i0, i1) = (cell(lo.x, 0), cell(hi.x, 0));
            let (j0, j1) = (cell(lo.y, 1), cell(hi.y, 1));
            let (k0, k1) = (cell(lo.z, 2), cell(hi.z, 2));
            for k in k0..=k1 {
                for j in j0..=j1 {
                    let row = bricks[0] * (j + bricks[1] * k);
                    near.set_range(row + i0..=row + i1);
                }
            }
        }
        near
    }

    /// For meshes without rim edges (closed and consistently oriented) the winding number is an
    /// integer away from the surface, so the sign is constant over each connected region of
    /// bricks away from the surface (6-connected; the near bricks cover the whole surface, so a
    /// path between such bricks never crosses it): one winding number per region. `None` per
    /// brick for near bricks and regions whose winding number is unclear; `None` overall for
    /// meshes with rims.
    pub(super) fn region_signs(
        &self,
        grid: &Grid,
        bricks: [usize; 3],
        near: &Bits,
    ) -> Option<RegionSigns> {
        if !self.rims().is_empty() {
            return None;
        }
        let len = bricks[0] * bricks[1] * bricks[2];
        let mut sign = RegionSigns::new(len);
        let mut seen = Bits::new(len);
        let mut queue = std::collections::VecDeque::new();
        let span = grid.spacing * BRICK as f32;
        for start in 0..len {
            if near.get(start) || seen.get(start) {
                continue;
            }
            let at = [
                start % bricks[0],
                (start / bricks[0]) % bricks[1],
                start / (bricks[0] * bricks[1]),
            ];
            let centre = grid.origin
                + (glam::Vec3::new(at[0] as f32, at[1] as f32, at[2] as f32) + 0.5) * span;
            let w = self.winding_number(centre);
            let region_sign = ((w - 0.5).abs() >= REGION_SIGN_MARGIN).then_some(w > 0.5);
            seen.set(start);
            queue.push_back(start);
            while let Some(b) = queue.pop_front() {
                sign.set(b, region_sign);
                let (i, j, k) = (
                    b % bricks[0],
                    (b / bricks[0]) % bricks[1],
                    b / (bricks[0] * bricks[1]),
                );
                let mut visit = |n: usize| {
                    if !near.get(n) && !seen.get(n) {
                        seen.set(n);
                        queue.push_back(n);
                    }
                };
                if i > 0 {
                    visit(b - 1);
                }
                if i + 1 < bricks[0] {
                    visit(b + 1);
                }
                if j > 0 {
                    visit(b - bricks[0]);
                }
                if j + 1 < bricks[1] {
                    visit(b + bricks[0]);
                }
                if k > 0 {
                    visit(b - bricks[0] * bricks[1]);
                }
                if k + 1 < bricks[2] {
                    visit(b + bricks[0] * bricks[1]);
                }
            }
        }
        Some(sign)
    }
}
