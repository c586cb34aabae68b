//! Which bricks need exact distances in a narrow band, and the signs of the others where one
//! winding number decides a whole region, over a box of the grid's sampling bricks: the whole
//! grid, or the rows one part of a distributed encode samples.

use glam::Vec3A;
use rayon::prelude::*;

use super::flags::{Bits, RegionSigns};
use crate::{grid::Grid, sdf::MeshSdf};

/// Nodes per brick edge in a narrow band, where exact bricks hug the surface: on the bunny's
/// ±3 band at 256³, bricks of 8 took 8–25 % longer than bricks of 4 (more nodes per brick are
/// beyond the band but still scanned).
pub const BRICK: usize = 4;

/// A surface-free region or brick whose winding number is at least this far from 1/2 takes
/// that sign.
pub(super) const REGION_SIGN_MARGIN: f32 = 0.3;

/// Sampling bricks per edge of the tiles the far regions are flooded in (64 nodes, one fitting
/// group). Regions stop at tile faces so that a tile's signs depend on the tile alone: a box
/// made of whole tiles gets the flags the whole grid gets, whichever box it is. A tile costs
/// one winding number per region of it (about one per tile away from the surface).
pub const REGION_TILE: usize = 16;

/// A box of sampling bricks: every brick along x, and ranges along y and z.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct BrickBox {
    pub(super) lo: [usize; 3],
    pub(super) size: [usize; 3],
}

impl BrickBox {
    /// The whole grid of `bricks` bricks.
    pub(super) fn all(bricks: [usize; 3]) -> Self {
        Self {
            lo: [0; 3],
            size: bricks,
        }
    }

    /// The bricks of rows `js`, `ks` (sampling bricks) widened to whole region tiles, within
    /// the grid's `bricks`.
    pub(super) fn tiles_around(
        bricks: [usize; 3],
        js: std::ops::Range<usize>,
        ks: std::ops::Range<usize>,
    ) -> Self {
        let widen = |r: std::ops::Range<usize>, n: usize| {
            if r.start >= r.end.min(n) {
                return (0, 0);
            }
            let lo = r.start / REGION_TILE * REGION_TILE;
            (lo, (r.end.div_ceil(REGION_TILE) * REGION_TILE).min(n) - lo)
        };
        let (j0, nj) = widen(js, bricks[1]);
        let (k0, nk) = widen(ks, bricks[2]);
        Self {
            lo: [0, j0, k0],
            size: [bricks[0], nj, nk],
        }
    }

    pub(super) fn len(&self) -> usize {
        self.size.iter().product()
    }

    /// Flat index (x fastest) of grid brick `b`, which must lie in the box.
    #[inline]
    pub(super) fn index(&self, b: [usize; 3]) -> usize {
        let [i, j, k] = [0, 1, 2].map(|a| b[a] - self.lo[a]);
        i + self.size[0] * (j + self.size[1] * k)
    }
}

/// The region signs of one tile.
enum TileSigns {
    /// Every brick has this sign (or every brick's is unknown).
    Same(Option<bool>),
    /// Per brick of the tile, indexed in it.
    Each(RegionSigns),
}

impl MeshSdf {
    /// Which bricks of `area` lie within `reach` of some triangle's bounding box: the only ones
    /// that can hold band nodes (the way OpenVDB finds its narrow band). A brick's cell runs up
    /// to the next brick, so no triangle meets the cells of the others, nor a segment between
    /// two neighbouring ones. Each brick's flag depends on the triangles alone, so any box gets
    /// the whole grid's flags; only the triangles of the tree's leaves near the box are tested,
    /// so a small box of a large mesh (a sharp-feature box, a distributed part) costs its own
    /// share of the triangles.
    pub(super) fn bricks_near_triangles(&self, grid: &Grid, reach: f32, area: &BrickBox) -> Bits {
        // A little more than `reach`, so rounding in the cell arithmetic cannot miss a cell.
        let reach = reach + 0.01 * grid.spacing;
        let mut near = Bits::new(area.len());
        if area.len() == 0 {
            return near;
        }
        let span = grid.spacing * BRICK as f32;
        // The brick whose cell holds coordinate `x` along `axis`, unclamped: a brick's cell
        // runs up to the next brick, so a triangle whose inflated bounds end before brick 0 or
        // start past the last brick's cell is beyond `reach` of every node.
        let cell = |x: f32, axis: usize| -> i64 { ((x - grid.origin[axis]) / span).floor() as i64 };
        let hi_of = |a: usize| (area.lo[a] + area.size[a] - 1) as i64;
        let mut mark = |t: &[Vec3A; 3]| {
            let lo = t[0].min(t[1]).min(t[2]) - Vec3A::splat(reach);
            let hi = t[0].max(t[1]).max(t[2]) + Vec3A::splat(reach);
            let range = |a: usize| {
                (
                    cell(lo[a], a).max(area.lo[a] as i64),
                    cell(hi[a], a).min(hi_of(a)),
                )
            };
            let [(i0, i1), (j0, j1), (k0, k1)] = [0, 1, 2].map(range);
            if i0 > i1 || j0 > j1 || k0 > k1 {
                return;
            }
            let [i0, i1] = [i0, i1].map(|i| i as usize);
            for k in k0 as usize..=k1 as usize {
                for j in j0 as usize..=j1 as usize {
                    near.set_range(area.index([i0, j, k])..=area.index([i1, j, k]));
                }
            }
        };
        // Only the leaves near the box can mark it: the box grown by a brick on each side (for
        // rounding at cell borders), and the reach along a diagonal.
        let bvh = self.bvh();
        let corner =
            |b: [usize; 3]| Vec3A::from(grid.origin) + Vec3A::from(b.map(|x| x as f32)) * span;
        let lo = corner(area.lo) - Vec3A::splat(span);
        let hi = corner([0, 1, 2].map(|a| area.lo[a] + area.size[a])) + Vec3A::splat(span);
        let mut leaves = Vec::new();
        bvh.leaves_near_box(lo, hi, 3.0 * reach * reach, &mut leaves);
        for &(_, id) in &leaves {
            let node = &bvh.nodes[id as usize];
            bvh.leaf(node).iter().for_each(&mut mark);
        }
        near
    }

    /// For meshes without rim edges (closed and consistently oriented) the winding number is an
    /// integer away from the surface, so the sign is constant over each connected region of
    /// bricks away from the surface (6-connected; the near bricks cover the whole surface, so a
    /// path between such bricks never crosses it): one winding number per region, the regions
    /// cut at the faces of [`REGION_TILE`] tiles (in parallel, and alike in any box of whole
    /// tiles). `None` per brick for near bricks and regions whose winding number is unclear;
    /// `None` overall for meshes with rims. `area` must be made of whole tiles.
    pub(super) fn region_signs(
        &self,
        grid: &Grid,
        near: &Bits,
        area: &BrickBox,
    ) -> Option<RegionSigns> {
        if !self.rims().is_empty() {
            return None;
        }
        let tiles = area.size.map(|n| n.div_ceil(REGION_TILE));
        let tile_signs: Vec<(BrickBox, TileSigns)> = (0..tiles.iter().product::<usize>())
            .into_par_iter()
            .map(|t| {
                let at = [
                    t % tiles[0],
                    (t / tiles[0]) % tiles[1],
                    t / (tiles[0] * tiles[1]),
                ];
                let tile = BrickBox {
                    lo: [0, 1, 2].map(|a| area.lo[a] + at[a] * REGION_TILE),
                    size: [0, 1, 2].map(|a| REGION_TILE.min(area.size[a] - at[a] * REGION_TILE)),
                };
                let signs = self.tile_region_signs(grid, near, area, &tile);
                (tile, signs)
            })
            .collect();
        let mut sign = RegionSigns::new(area.len());
        for (tile, signs) in &tile_signs {
            for k in 0..tile.size[2] {
                for j in 0..tile.size[1] {
                    let row = [tile.lo[0], tile.lo[1] + j, tile.lo[2] + k];
                    let first = area.index(row);
                    match signs {
                        // A run of bricks along x a word at a time.
                        TileSigns::Same(region) => {
                            sign.set_run(first..first + tile.size[0], *region)
                        }
                        TileSigns::Each(each) => {
                            let from = tile.index(row);
                            for i in 0..tile.size[0] {
                                sign.set(first + i, each.get(from + i));
                            }
                        }
                    }
                }
            }
        }
        Some(sign)
    }

    /// The signs of the far regions of one tile, flooded within it, indexed in the tile.
    fn tile_region_signs(
        &self,
        grid: &Grid,
        near: &Bits,
        area: &BrickBox,
        tile: &BrickBox,
    ) -> TileSigns {
        let len = tile.len();
        let [sx, sy, sz] = tile.size;
        let span = grid.spacing * BRICK as f32;
        let region_sign = |start: usize| {
            let at = [
                tile.lo[0] + start % sx,
                tile.lo[1] + (start / sx) % sy,
                tile.lo[2] + start / (sx * sy),
            ];
            let centre = grid.origin
                + (glam::Vec3::new(at[0] as f32, at[1] as f32, at[2] as f32) + 0.5) * span;
            let w = self.winding_number(centre);
            ((w - 0.5).abs() >= REGION_SIGN_MARGIN).then_some(w > 0.5)
        };
        // A tile with no near brick is one region, flooded from its first brick: far from a
        // small surface, most tiles of a large grid.
        let rows = (0..sz)
            .flat_map(|k| (0..sy).map(move |j| [tile.lo[0], tile.lo[1] + j, tile.lo[2] + k]));
        if rows.clone().all(|row| {
            let first = area.index(row);
            !near.any_in(first..first + sx)
        }) {
            return TileSigns::Same(region_sign(0));
        }
        let mut sign = RegionSigns::new(len);
        let mut seen = Bits::new(len);
        let mut queue = std::collections::VecDeque::new();
        let is_near = |b: usize| {
            let [i, j, k] = [b % sx, (b / sx) % sy, b / (sx * sy)];
            near.get(area.index([tile.lo[0] + i, tile.lo[1] + j, tile.lo[2] + k]))
        };
        for start in 0..len {
            if seen.get(start) || is_near(start) {
                continue;
            }
            let region_sign = region_sign(start);
            seen.set(start);
            queue.push_back(start);
            while let Some(b) = queue.pop_front() {
                sign.set(b, region_sign);
                let (i, j, k) = (b % sx, (b / sx) % sy, b / (sx * sy));
                let mut visit = |n: usize| {
                    if !seen.get(n) && !is_near(n) {
                        seen.set(n);
                        queue.push_back(n);
                    }
                };
                if i > 0 {
                    visit(b - 1);
                }
                if i + 1 < sx {
                    visit(b + 1);
                }
                if j > 0 {
                    visit(b - sx);
                }
                if j + 1 < sy {
                    visit(b + sx);
                }
                if k > 0 {
                    visit(b - sx * sy);
                }
                if k + 1 < sz {
                    visit(b + sx * sy);
                }
            }
        }
        TileSigns::Each(sign)
    }
}
