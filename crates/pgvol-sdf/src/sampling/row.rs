//! One row of bricks along x, brick by brick: distances where the band (or the dense grid)
//! asks for them, signs everywhere. With the winding sign, one winding number is carried along
//! the whole row, through bricks with and without surface.

use glam::Vec3;

use super::{
    brick::{Brick, BrickSegment, LocalTriangle},
    candidates::LeafTable,
    carry::WindingCarry,
    flags::{Bits, RegionSigns},
    near::{BrickBox, REGION_SIGN_MARGIN},
};
use crate::bvh::{Bvh, Closest};
use crate::{grid::Grid, sdf::MeshSdf, SignMode};

/// What every row needs to know about the whole grid.
pub(super) struct Plan<'a> {
    pub(super) grid: &'a Grid,
    /// Nodes per brick edge.
    pub(super) brick: usize,
    /// Bricks per axis.
    pub(super) bricks: [usize; 3],
    pub(super) clamp: f32,
    /// The bricks the flags below cover, indexed by [`BrickBox::index`].
    pub(super) flags: BrickBox,
    /// Per brick, whether it is within the band of some triangle (`None`: dense, all are).
    pub(super) near: Option<Bits>,
    /// Per brick away from the surface, its sign when one winding number decides its region.
    pub(super) regions: Option<RegionSigns>,
}

/// The values of one row of bricks: nodes `(i, j, k)` of the row's `j` and `k` ranges, x
/// fastest, then j, then k.
pub(super) struct RowValues {
    /// The written values; the nodes of uniform bricks are left as they were.
    pub(super) values: Vec<f32>,
    pub(super) exact: usize,
    /// Per brick along x, its value when every node has it (and it was not written).
    pub(super) uniform: Vec<Option<f32>>,
    /// The value every brick of the row has, when they all have the same one: far from a small
    /// surface, most rows of a large grid.
    pub(super) single: Option<f32>,
}

impl RowValues {
    /// Writes the uniform bricks' values into `values`, for a row of `nx` nodes in bricks of
    /// `brick` nodes, `layers` node rows (`j` then `k`) thick.
    pub(super) fn fill_uniform(&mut self, nx: usize, brick: usize) {
        let layers = self.values.len() / nx;
        for (bi, value) in self.uniform.iter().enumerate() {
            let Some(v) = *value else { continue };
            let (i0, i1) = (bi * brick, (bi * brick + brick).min(nx));
            for line in self.values.chunks_exact_mut(nx).take(layers) {
                line[i0..i1].fill(v);
            }
        }
    }
}

/// Bricks along a row that share one gradient bound where it is small (one rim query per
/// brick took a tenth of the time of a band on the bunny).
const TILE: usize = 4;

/// A shared bound serves a brick when the drift over its half diagonal stays below this.
const TILE_DRIFT: f32 = 0.01;

/// Bricks at least this many grid spacings from the surface skip leaves by their oriented boxes.
const ORIENTED_FROM: f32 = 4.0;

/// The gradient bound of the last tile: rows `j`, `k` of the bricks and tile number.
#[derive(Default)]
pub(super) struct TileGradient {
    row_tile: Option<(usize, usize, usize)>,
    bound: f32,
}

/// Buffers reused from row to row.
#[derive(Default)]
pub(super) struct Scratch {
    leaves: Vec<(f32, u32)>,
    table: LeafTable,
    triangles: Vec<LocalTriangle>,
    tiles: TileGradient,
}

/// Where a brick's values go in its row.
struct RowOut<'a> {
    values: &'a mut [f32],
    nx: usize,
    ny: usize,
    j0: usize,
    k0: usize,
}

impl RowOut<'_> {
    fn put(&mut self, [i, j, k]: [usize; 3], value: f32) {
        self.values[i + self.nx * ((j - self.j0) + self.ny * (k - self.k0))] = value;
    }
}

/// How a brick of a row came out: one value at every node, recorded once instead of written
/// node by node (far from a small surface almost every brick of a large grid is one), or
/// values written into the row.
type Filled = Option<f32>;

impl MeshSdf {
    /// The values go into `values`, whatever it held before: every node a non-uniform brick
    /// holds is written, and a uniform brick's are not read (a reused buffer is not cleared).
    pub(super) fn sample_row(
        &self,
        plan: &Plan,
        row: usize,
        scratch: &mut Scratch,
        mut values: Vec<f32>,
    ) -> RowValues {
        let grid = plan.grid;
        let [nx, ny, nz] = grid.dims;
        let size = plan.brick;
        let (bj, bk) = (row % plan.bricks[1], row / plan.bricks[1]);
        let (j0, j1) = (bj * size, (bj * size + size).min(ny));
        let (k0, k1) = (bk * size, (bk * size + size).min(nz));
        values.resize(nx * (j1 - j0) * (k1 - k0), 0.0);
        // A row far from every triangle whose bricks' regions share one sign is that sign
        // throughout, as the loop below finds brick by brick: most rows of a large grid.
        let first = plan.flags.index([0, bj, bk]);
        let bricks = first..first + plan.bricks[0];
        if let (Some(near), Some(regions)) = (&plan.near, &plan.regions) {
            if !near.any_in(bricks.clone()) {
                if let Some(inside) = regions.same_in(bricks) {
                    let v = if inside { -plan.clamp } else { plan.clamp };
                    return RowValues {
                        values,
                        exact: 0,
                        uniform: vec![Some(v); plan.bricks[0]],
                        single: Some(v),
                    };
                }
            }
        }
        let mut out = RowOut {
            values: &mut values,
            nx,
            ny: j1 - j0,
            j0,
            k0,
        };
        let mut exact = 0;
        let mut uniform = vec![None; plan.bricks[0]];
        let mut carry = WindingCarry::default();
        // The triangle closest to the last near brick's centre: it bounds the next centre's
        // search. Kept within the row, so each row is sampled the same whatever came before.
        let mut seed_hint = None;
        let mut previous_far = false;
        let whole = self.winding_is_whole();
        for (bi, filled) in uniform.iter_mut().enumerate() {
            let b = plan.flags.index([bi, bj, bk]);
            let brick = || {
                Brick::new(
                    grid,
                    [bi * size, j0, k0],
                    [(bi * size + size).min(nx), j1, k1],
                )
            };
            let far = plan.near.as_ref().is_some_and(|near| !near.get(b));
            *filled = if far {
                match plan.regions.as_ref().and_then(|r| r.get(b)) {
                    Some(inside) => {
                        // A whole winding number carries across any distance without drift
                        // (only crossings change it); otherwise the next brick starts afresh.
                        if !whole {
                            carry.forget();
                        }
                        Some(if inside { -plan.clamp } else { plan.clamp })
                    }
                    // Two neighbouring far bricks: no triangle meets either, so nothing is
                    // crossed between them.
                    None => {
                        self.signs_only(&brick(), plan, &mut carry, previous_far, scratch, &mut out)
                    }
                }
            } else {
                let (filled, n) = self.near_brick(
                    &brick(),
                    plan,
                    &mut carry,
                    &mut seed_hint,
                    scratch,
                    &mut out,
                );
                exact += n;
                filled
            };
            previous_far = far;
        }
        let single = uniform
            .first()
            .copied()
            .flatten()
            .filter(|&v| uniform.iter().all(|&u| u == Some(v)));
        RowValues {
            values,
            exact,
            uniform,
            single,
        }
    }

    /// A brick with no surface in it and every node farther than the clamp: only signs.
    /// `entry_is_clear` says the segment from the last carried point crosses no triangle.
    fn signs_only(
        &self,
        brick: &Brick,
        plan: &Plan,
        carry: &mut WindingCarry,
        entry_is_clear: bool,
        scratch: &mut Scratch,
        out: &mut RowOut,
    ) -> Filled {
        let grid = plan.grid;
        let clamp = plan.clamp;
        let signed = |inside: bool| if inside { -clamp } else { clamp };
        if self.sign_mode() != SignMode::Winding {
            // A closed mesh whose region's winding number was unclear (see `near.rs`): the
            // winding number decides, per brick when clear, else per node.
            let w = self.winding_number(Vec3::from(brick.centre()));
            if (w - 0.5).abs() >= REGION_SIGN_MARGIN {
                return Some(signed(w > 0.5));
            }
            brick.for_each_node(grid, |at, p| {
                out.put(at, signed(self.winding_number(Vec3::from(p)) > 0.5))
            });
            return None;
        }
        let gradient = self.gradient_towards(plan, brick, carry, &mut scratch.tiles);
        let segment = BrickSegment {
            sdf: self,
            brick,
            triangles: &[],
            entry_is_clear,
            gradient,
        };
        // No triangle crosses the brick: the winding number moves away from the centre's value
        // by at most the gradient bound times the distance.
        let drift = segment.gradient * brick.half_diagonal();
        let centre = carry.winding_at(self, brick.centre(), &segment, drift);
        if (centre.value - 0.5).abs() > centre.error + drift {
            return Some(signed(centre.value > 0.5));
        }
        brick.for_each_node(grid, |at, p| {
            out.put(
                at,
                signed(carry.winding_near(self, p, &segment).value > 0.5),
            );
        });
        None
    }

    /// A bound on the winding number's gradient over the brick and the segment entering it.
    /// The bound over the run of [`TILE`] bricks holding `brick` and the brick before them
    /// serves when it is small enough; otherwise the brick's own box is bounded.
    fn gradient_towards(
        &self,
        plan: &Plan,
        brick: &Brick,
        carry: &WindingCarry,
        tiles: &mut TileGradient,
    ) -> f32 {
        let size = plan.brick;
        let tile = brick.lo[0] / (size * TILE);
        if tiles.row_tile != Some((brick.lo[1], brick.lo[2], tile)) {
            let first = (tile * TILE * size).saturating_sub(size);
            let last = ((tile + 1) * TILE * size).min(plan.grid.dims[0]) - 1;
            let lo = plan.grid.point(first, brick.lo[1], brick.lo[2]).into();
            let hi = plan
                .grid
                .point(last, brick.hi[1] - 1, brick.hi[2] - 1)
                .into();
            tiles.bound = self.rims().gradient_bound(lo, hi);
            tiles.row_tile = Some((brick.lo[1], brick.lo[2], tile));
        }
        if tiles.bound * brick.half_diagonal() < TILE_DRIFT {
            return tiles.bound;
        }
        let (lo, hi) = match carry.last_point() {
            Some(q) => (brick.pmin.min(q), brick.pmax.max(q)),
            None => (brick.pmin, brick.pmax),
        };
        self.rims().gradient_bound(lo, hi)
    }

    /// A brick within the band of some triangle (or of a dense grid): exact distances where
    /// they are within the clamp. Returns how the brick was filled and how many nodes are.
    fn near_brick(
        &self,
        brick: &Brick,
        plan: &Plan,
        carry: &mut WindingCarry,
        seed_hint: &mut Option<u32>,
        scratch: &mut Scratch,
        out: &mut RowOut,
    ) -> (Filled, usize) {
        let bvh = self.bvh();
        let grid = plan.grid;
        let clamp = plan.clamp;
        let centre = brick.centre();
        let seed = centre_closest(bvh, Vec3::from(centre), *seed_hint, grid.spacing);
        *seed_hint = Some(seed.slot);
        let centre_distance = seed.distance_squared.sqrt();
        let half_diagonal = brick.half_diagonal();
        // The ball around the centre up to the closest point holds the brick and no triangle.
        let surface_free = centre_distance > half_diagonal;
        let winding = self.sign_mode() == SignMode::Winding;
        // Without the winding number, a surface-free brick takes the sign of its centre.
        let brick_sign =
            (surface_free && !winding).then(|| self.is_inside_near(centre.into(), &seed));
        if centre_distance - half_diagonal > clamp {
            let filled = match brick_sign {
                Some(inside) => Some(if inside { -clamp } else { clamp }),
                None => self.signs_only(brick, plan, carry, false, scratch, out),
            };
            return (filled, 0);
        }
        // With the winding sign, nodes beyond the band need no closest point: triangles farther
        // than the clamp are not looked for. The slack keeps every distance whose square root
        // rounds to at most `clamp` within the limit, so band values stay exact.
        let limit = if winding {
            clamp * clamp * (1.0 + 1e-5)
        } else {
            f32::INFINITY
        };
        self.brick_leaves(brick, &seed, limit, &mut scratch.leaves);
        // Near the surface a node's ball touches few leaves beyond its closest one, and copying
        // the oriented boxes costs more than they save (band runs were 10-15 % slower).
        let far = centre_distance - half_diagonal > ORIENTED_FROM * grid.spacing;
        scratch.table.fill(
            bvh,
            brick.centre(),
            &scratch.leaves,
            self.avx2(),
            far && self.skips_by_oriented_boxes(),
        );
        scratch.triangles.clear();
        if winding && !surface_free {
            self.brick_triangles(brick, &scratch.leaves, &mut scratch.triangles);
        }
        let gradient = if winding {
            self.gradient_towards(plan, brick, carry, &mut scratch.tiles)
        } else {
            0.0
        };
        let segment = BrickSegment {
            sdf: self,
            brick,
            triangles: &scratch.triangles,
            entry_is_clear: false,
            gradient,
        };
        if winding {
            let drift = segment.gradient * half_diagonal;
            carry.winding_at(self, centre, &segment, drift);
        }
        let mut slot = seed.slot;
        let mut exact = 0;
        brick.for_each_node(grid, |at, p| {
            let best = scratch.table.closest(bvh, p, slot, limit);
            slot = best.slot;
            let d = best.distance_squared.sqrt();
            let inside = match brick_sign {
                Some(s) => s,
                None if winding => carry.winding_near(self, p, &segment).value > 0.5,
                None => self.is_inside_near(Vec3::from(p), &best.closest(bvh, p)),
            };
            if d <= clamp {
                exact += 1;
            }
            let d = d.min(clamp);
            out.put(at, if inside { -d } else { d });
        });
        (None, exact)
    }
}

/// The closest point of the mesh to a brick's `centre`: what an unbounded search gives, found
/// within the distance of the triangle at leaf slot `hint` (widened well past rounding), which
/// prunes most of the tree. Only triangles farther than that are left out, never a closest one
/// nor one tied with it, and the tree is walked in the same order: the same triangle comes
/// back. The search from the root took a fifth of a 4096³ encode's sampling.
fn centre_closest(bvh: &Bvh, centre: Vec3, hint: Option<u32>, spacing: f32) -> Closest {
    if let Some(slot) = hint {
        let d = bvh.closest_on_slot(centre, slot).distance_squared.sqrt();
        let bound = d * (1.0 + 1e-4) + 1e-3 * spacing;
        if let Some(found) = bvh.closest(centre, bound * bound) {
            return found;
        }
    }
    bvh.closest(centre, f32::INFINITY)
        .expect("the mesh has triangles")
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_mesh::Mesh;
    use rand::{Rng, SeedableRng};

    /// A plane of `n` × `n` squares, each cut into two triangles: points above it on a lattice
    /// have their closest points on shared edges and corners, where triangles tie.
    fn tiled_plane(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                positions.push(Vec3::new(i as f32, j as f32, 0.0));
            }
        }
        let at = |i: u32, j: u32| i + (n + 1) * j;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        Mesh::new(positions, triangles)
    }

    /// Whatever the hint, the centre's closest point is the one a search from the root finds:
    /// the same triangle among tied ones, the same point and distance.
    #[test]
    fn a_hinted_centre_search_finds_what_the_whole_search_does() {
        let mesh = tiled_plane(12);
        let bvh = Bvh::build(&mesh);
        let slots = mesh.triangles.len() as u32;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let mut ties = 0;
        for _ in 0..3000 {
            // Half on the lattice of quarter units (ties), half anywhere.
            let p = if rng.gen() {
                Vec3::new(
                    rng.gen_range(-8..56) as f32 * 0.25,
                    rng.gen_range(-8..56) as f32 * 0.25,
                    rng.gen_range(-4..8) as f32 * 0.25,
                )
            } else {
                Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 16.0 - 2.0
            };
            let want = bvh.closest(p, f32::INFINITY).unwrap();
            let hint = rng.gen_range(0..slots);
            let got = centre_closest(&bvh, p, Some(hint), 0.25);
            assert_eq!(got, want, "{p} from slot {hint}");
            // The hint alone would often be a tie of another triangle.
            let hinted = bvh.closest_with_hint(p, f32::INFINITY, Some(hint)).unwrap();
            ties += usize::from(hinted.slot != want.slot);
        }
        assert!(ties > 0, "the points exercise ties");
    }
}
