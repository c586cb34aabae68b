//! Signed distance on grids: dense (exact everywhere) or in a narrow band around the surface.
//!
//! The grid is cut into bricks of [`BRICK`]³ nodes ([`DENSE_BRICK`]³ on dense grids). Rows of
//! bricks along x are processed in parallel, each row brick by brick (`row.rs`), so that winding
//! numbers can be carried from node to node and from brick to brick (`carry.rs`). Per brick, one BVH query at the centre
//! bounds the distance of every node, and one BVH pass gathers the leaves that can hold any
//! node's closest triangle (`brick.rs`). In a narrow band, only bricks near triangles get
//! distances (`near.rs`).

mod brick;
mod candidates;
mod carry;
mod flags;
mod near;
mod row;

use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use pgvol_core::progress::Interrupt;
use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, PerThread, SparseGrid, BRICK_EDGE, BRICK_NODES};

use near::BrickBox;
pub use near::{BRICK, REGION_TILE};
use row::{Plan, RowValues};

use crate::{grid::Grid, sdf::MeshSdf};

/// Nodes per brick edge on a dense grid. Once the node scans became eight lanes wide with
/// oriented leaf bounds, the per-brick work (the centre query, collecting and sorting the
/// leaves near the brick) took a fifth of the time, and bricks of 8 beat 4 at 128³: fandisk
/// 0.53 s against 0.645 s, the bunny 1.34–1.39 s against 1.40–1.59 s, grids identical.
pub const DENSE_BRICK: usize = 8;

/// Sampling bricks (of [`BRICK`]³ nodes) the band's plan covers when
/// [`MeshSdf::sample_sparse_rows`] samples the rows of grid bricks `ys`, `zs` of `grid`: the
/// rows widened to whole [`REGION_TILE`] tiles. Its flags take about 3 bits per brick.
pub fn plan_bricks(grid: &Grid, ys: std::ops::Range<usize>, zs: std::ops::Range<usize>) -> usize {
    plan_box(grid, ys, zs).len()
}

/// The box of sampling bricks [`plan_bricks`] counts.
fn plan_box(grid: &Grid, ys: std::ops::Range<usize>, zs: std::ops::Range<usize>) -> BrickBox {
    let per = BRICK_EDGE / BRICK;
    let bricks = grid.dims.map(|n| n.div_ceil(BRICK));
    BrickBox::tiles_around(
        bricks,
        ys.start * per..ys.end * per,
        zs.start * per..zs.end * per,
    )
}

/// Where exact distances are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Extent {
    /// Every node.
    Dense,
    /// Nodes within this many grid spacings of the surface; the others get only their sign and
    /// the clamped magnitude `width · spacing`, and band values are clamped to it too.
    Band(f32),
}

/// A sampled grid and how much of it is exact.
#[derive(Clone, Debug)]
pub struct Sampled {
    pub values: Vec<f32>,
    /// Nodes whose distance was computed exactly.
    pub exact_nodes: usize,
    /// Magnitude of clamped values (infinite for dense grids).
    pub clamp: f32,
}

/// A banded signed distance as a sparse grid and how much of it is exact.
#[derive(Clone, Debug)]
pub struct SparseSampled {
    /// Bricks with a node within the band; the others hold `±clamp` by side.
    pub values: SparseGrid,
    /// Nodes whose distance was computed exactly.
    pub exact_nodes: usize,
    /// Magnitude of clamped values.
    pub clamp: f32,
}

/// One row of grid bricks: the stored ones and the unstored ones inside.
#[derive(Default)]
struct GridRow {
    stored: Vec<([usize; 3], Box<BrickValues>)>,
    inside: Vec<[usize; 3]>,
    exact: usize,
}

/// What a thread keeps from one row of grid bricks to the next.
#[derive(Default)]
struct RowScratch {
    row: row::Scratch,
    /// Row buffers to write values into.
    rows: Vec<Vec<f32>>,
}

/// Cuts the sampler's rows (`pieces`: their offsets in small bricks within the grid brick row
/// `[gj, gk]`, and their values) into grid bricks. A brick is stored when a node lies within
/// the band or its signs differ; otherwise it is all `+clamp` or all `−clamp` and only its side
/// is kept.
fn cut_row(
    grid: &Grid,
    [gj, gk]: [usize; 2],
    pieces: &[([usize; 2], RowValues)],
    clamp: f32,
) -> GridRow {
    let [nx, ny, nz] = grid.dims;
    let mut out = GridRow {
        stored: Vec::new(),
        inside: Vec::new(),
        exact: pieces.iter().map(|(_, r)| r.exact).sum(),
    };
    let mut brick = [0.0f32; BRICK_NODES];
    // Every small brick of the row holds one value: each grid brick is what the loop below
    // makes of one such value, without looking at the small bricks one by one.
    let single = pieces.first().and_then(|(_, row)| row.single);
    if let Some(v) = single.filter(|&v| pieces.iter().all(|(_, row)| row.single == Some(v))) {
        for gi in 0..nx.div_ceil(BRICK_EDGE) {
            let b = [gi, gj, gk];
            if v.abs() < clamp {
                brick.fill(v);
                out.stored.push((b, Box::new(brick)));
            } else if v < 0.0 {
                out.inside.push(b);
            }
        }
        return out;
    }
    for gi in 0..nx.div_ceil(BRICK_EDGE) {
        let i0 = gi * BRICK_EDGE;
        let ni = (i0 + BRICK_EDGE).min(nx) - i0;
        let small = i0 / BRICK..(i0 + ni).div_ceil(BRICK);
        let b = [gi, gj, gk];
        // A grid brick whose small bricks all hold one value keeps only its side.
        let first = pieces.first().and_then(|(_, row)| row.uniform[small.start]);
        let one_value = first.filter(|&v| {
            pieces
                .iter()
                .all(|(_, row)| row.uniform[small.clone()].iter().all(|&u| u == Some(v)))
        });
        if let Some(v) = one_value {
            if v.abs() < clamp {
                brick.fill(v);
                out.stored.push((b, Box::new(brick)));
            } else if v < 0.0 {
                out.inside.push(b);
            }
            continue;
        }
        brick.fill(clamp);
        let (mut near, mut inside, mut outside) = (false, false, false);
        for ([dj, dk], row) in pieces {
            let (j0, k0) = (
                (gj * BRICK_EDGE / BRICK + dj) * BRICK,
                (gk * BRICK_EDGE / BRICK + dk) * BRICK,
            );
            let (nj, nk) = ((j0 + BRICK).min(ny) - j0, (k0 + BRICK).min(nz) - k0);
            for k in 0..nk {
                for j in 0..nj {
                    let src = i0 + nx * (j + nj * k);
                    let dst = BRICK_EDGE * (dj * BRICK + j + BRICK_EDGE * (dk * BRICK + k));
                    for (x, (d, &v)) in brick[dst..dst + ni]
                        .iter_mut()
                        .zip(&row.values[src..src + ni])
                        .enumerate()
                    {
                        let v = row.uniform[(i0 + x) / BRICK].unwrap_or(v);
                        *d = v;
                        near |= v.abs() < clamp;
                        inside |= v < 0.0;
                        outside |= v >= 0.0;
                    }
                }
            }
        }
        if near || (inside && outside) {
            out.stored.push((b, Box::new(brick)));
        } else if inside {
            out.inside.push(b);
        }
    }
    out
}

impl MeshSdf {
    /// Exact signed distance at every node of `grid` (x fastest). The values do not depend on the
    /// number of threads.
    pub fn sample_grid(&self, grid: &Grid, progress: &dyn Interrupt) -> Vec<f32> {
        self.sample(grid, Extent::Dense, progress).values
    }

    /// Signed distance on `grid` within `width` spacings of the surface, as a sparse grid: the
    /// bricks holding a node within the band are stored, every other brick is the clamp of its
    /// side. Working memory is the stored bricks plus one row of bricks per thread.
    pub fn sample_sparse(
        &self,
        grid: &Grid,
        width: f32,
        progress: &dyn Interrupt,
    ) -> SparseSampled {
        let [_, by, bz] = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
        self.sample_sparse_rows(grid, width, 0..by, 0..bz, progress)
    }

    /// The band's plan over the bricks of `flags` (whole region tiles): bricks near triangles
    /// and the signs of far regions, the same for each brick whatever the box.
    fn band_plan<'g>(&self, grid: &'g Grid, width: f32, flags: BrickBox) -> Plan<'g> {
        let bricks = grid.dims.map(|n| n.div_ceil(BRICK));
        let clamp = width.max(0.0) * grid.spacing;
        let near = self.bricks_near_triangles(grid, clamp, &flags);
        let regions = self.region_signs(grid, &near, &flags);
        Plan {
            grid,
            brick: BRICK,
            bricks,
            flags,
            clamp,
            near: Some(near),
            regions,
        }
    }

    /// [`MeshSdf::sample_sparse`] restricted to the rows of grid bricks along x whose y and z
    /// brick indices lie in `ys` and `zs`, without the sign fallback: every brick it holds,
    /// stored or absent, is the one the whole grid's sampling gives, since each row of grid
    /// bricks is sampled alone from the mesh and the grid. Bricks of other rows are left
    /// absent and outside.
    /// The band's plan covers only these rows widened to whole [`REGION_TILE`] tiles, so its
    /// memory and time follow the rows, not the grid.
    pub fn sample_sparse_rows(
        &self,
        grid: &Grid,
        width: f32,
        ys: std::ops::Range<usize>,
        zs: std::ops::Range<usize>,
        progress: &dyn Interrupt,
    ) -> SparseSampled {
        let [_, by, bz] = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
        let ys = ys.start.min(by)..ys.end.min(by);
        let zs = zs.start.min(bz)..zs.end.min(bz);
        let plan = self.band_plan(grid, width, plan_box(grid, ys.clone(), zs.clone()));
        let clamp = plan.clamp;
        let done = AtomicUsize::new(0);
        // Set at a report that finds the caller wants to stop: rows not yet begun are skipped.
        let stop = AtomicBool::new(false);
        let total = ys.len() * zs.len();
        // One task per row of grid bricks (`grid_row`), handed out one at a time: rows cost what
        // their surface costs, and larger pieces left one thread running alone at the end.
        let scratches = PerThread::<RowScratch>::new();
        let rows: Vec<GridRow> = (0..total)
            .into_par_iter()
            .with_max_len(1)
            .map(|r| {
                if stop.load(Ordering::Relaxed) {
                    return GridRow::default();
                }
                let (gj, gk) = (ys.start + r % ys.len(), zs.start + r / ys.len());
                let out = scratches.with(|scratch| self.grid_row(grid, &plan, [gj, gk], scratch));
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                if n.is_multiple_of(16) || n == total {
                    progress.update(n as f64 / total as f64);
                    if progress.cancelled() {
                        stop.store(true, Ordering::Relaxed);
                    }
                }
                out
            })
            .collect();
        let mut values = SparseGrid::new(grid.dims, Background::clamp(clamp));
        let mut exact_nodes = 0;
        for row in rows {
            exact_nodes += row.exact;
            for b in row.inside {
                values.set_inside(b, true);
            }
            for (b, v) in row.stored {
                values.insert(b, v);
            }
        }
        values.compact_tiles();
        SparseSampled {
            values,
            exact_nodes,
            clamp,
        }
    }

    /// The grid bricks of the row `[gj, gk]`: the sampler's rows of small bricks it covers, one
    /// after another so each carries its winding number along x, then cut into grid bricks.
    fn grid_row(
        &self,
        grid: &Grid,
        plan: &Plan,
        [gj, gk]: [usize; 2],
        scratch: &mut RowScratch,
    ) -> GridRow {
        let per = BRICK_EDGE / BRICK;
        let mut pieces = Vec::new();
        for dk in 0..per {
            for dj in 0..per {
                let (sj, sk) = (gj * per + dj, gk * per + dk);
                if sj < plan.bricks[1] && sk < plan.bricks[2] {
                    let row = sj + plan.bricks[1] * sk;
                    let buffer = scratch.rows.pop().unwrap_or_default();
                    let values = self.sample_row(plan, row, &mut scratch.row, buffer);
                    pieces.push(([dj, dk], values));
                }
            }
        }
        let out = cut_row(grid, [gj, gk], &pieces, plan.clamp);
        // The row buffers serve the next rows: most of a large grid's rows write none of their
        // nodes, and clearing them would cost more than sampling them.
        scratch
            .rows
            .extend(pieces.into_iter().map(|(_, piece)| piece.values));
        out
    }

    /// Signed distance on `grid`, exact where `extent` asks. `progress` gets the fraction done.
    pub fn sample(&self, grid: &Grid, extent: Extent, progress: &dyn Interrupt) -> Sampled {
        let [nx, ny, _] = grid.dims;
        let plan = match extent {
            Extent::Band(w) => {
                let bricks = grid.dims.map(|n| n.div_ceil(BRICK));
                self.band_plan(grid, w, BrickBox::all(bricks))
            }
            Extent::Dense => Plan {
                grid,
                brick: DENSE_BRICK,
                bricks: grid.dims.map(|n| n.div_ceil(DENSE_BRICK)),
                flags: BrickBox::all(grid.dims.map(|n| n.div_ceil(DENSE_BRICK))),
                clamp: f32::INFINITY,
                near: None,
                regions: None,
            },
        };
        let (brick, bricks, clamp) = (plan.brick, plan.bricks, plan.clamp);
        let rows = bricks[1] * bricks[2];
        let done = AtomicUsize::new(0);
        let results: Vec<RowValues> = (0..rows)
            .into_par_iter()
            .map_init(row::Scratch::default, |scratch, r| {
                let mut out = self.sample_row(&plan, r, scratch, Vec::new());
                out.fill_uniform(nx, brick);
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                if n.is_multiple_of(64) || n == rows {
                    progress.update(n as f64 / rows as f64);
                }
                out
            })
            .collect();
        // Rows with the same `k` range fill one slab of the grid, x fastest: slabs in parallel.
        let mut values = vec![0.0f32; grid.len()];
        values
            .par_chunks_mut(nx * ny * brick)
            .zip(results.par_chunks(bricks[1]))
            .for_each(|(slab, rows)| {
                let layers = slab.len() / (nx * ny);
                for (bj, row) in rows.iter().enumerate() {
                    let (j0, j1) = (bj * brick, (bj * brick + brick).min(ny));
                    let mut lines = row.values.chunks_exact(nx);
                    for k in 0..layers {
                        for j in j0..j1 {
                            let at = nx * (j + ny * k);
                            slab[at..at + nx].copy_from_slice(lines.next().expect("row size"));
                        }
                    }
                }
            });
        let exact_nodes = results.iter().map(|row| row.exact).sum();
        Sampled {
            values,
            exact_nodes,
            clamp,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consistency::{sign_contradictions, sparse_sign_contradictions};
    use crate::{SdfError, SignMode};
    use glam::Vec3;
    use pgvol_mesh::shapes::octasphere as sphere;

    #[test]
    fn band_matches_dense_inside_the_band_and_clamps_outside() {
        let sdf = MeshSdf::new(&sphere(4), SignMode::Winding).unwrap();
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 40).unwrap();
        let dense = sdf.sample(&grid, Extent::Dense, &|_| {});
        let band = sdf.sample(&grid, Extent::Band(3.0), &|_| {});
        let clamp = 3.0 * grid.spacing;
        assert_eq!(band.clamp, clamp);
        assert!(band.exact_nodes > 0 && band.exact_nodes < grid.len() / 2);
        assert_eq!(dense.exact_nodes, grid.len());
        for (d, b) in dense.values.iter().zip(&band.values) {
            assert_eq!(d.signum(), b.signum());
            if d.abs() <= clamp {
                assert_eq!(d, b);
            } else {
                assert_eq!(b.abs(), clamp);
            }
        }
    }

    /// Grids much larger than their surface: whole rows and whole region tiles lie away from
    /// it, outside (a small sphere) or inside (a large one), and take one sign at once. The
    /// band's signs and values are the dense grid's.
    #[test]
    fn far_rows_and_tiles_have_the_dense_grids_signs() {
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 150).unwrap();
        for radius in [0.15f32, 0.9] {
            let mut mesh = sphere(3);
            mesh.positions.iter_mut().for_each(|p| *p *= radius);
            let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
            let dense = sdf.sample(&grid, Extent::Dense, &|_| {});
            let band = sdf.sample(&grid, Extent::Band(3.0), &|_| {});
            let sparse = sdf.sample_sparse(&grid, 3.0, &|_| {}).values.to_dense();
            let clamp = 3.0 * grid.spacing;
            let inside = dense.values.iter().filter(|d| **d < 0.0).count();
            assert!(
                inside > 0 && inside < grid.len(),
                "{radius}: {inside} inside"
            );
            for ((d, b), s) in dense.values.iter().zip(&band.values).zip(&sparse) {
                assert_eq!(d.signum(), b.signum(), "{radius}");
                assert_eq!(b.to_bits(), s.to_bits(), "{radius}");
                if d.abs() <= clamp {
                    assert_eq!(d, b);
                } else {
                    assert_eq!(b.abs(), clamp);
                }
            }
        }
    }

    #[test]
    fn sparse_band_holds_the_dense_band_values_and_stores_only_bricks_near_the_surface() {
        for (mesh, dims) in [
            (sphere(4), [40, 40, 40]),
            (overlapping_cubes(), [37, 21, 50]),
        ] {
            for sign in [SignMode::Winding, SignMode::Auto] {
                let sdf = MeshSdf::new(&mesh, sign).unwrap();
                let (lo, hi) = (Vec3::splat(-1.2), Vec3::splat(1.8));
                let spacing = (hi - lo).max_element() / (dims[2] - 1) as f32;
                let grid = Grid {
                    origin: lo,
                    spacing,
                    dims,
                    offset: Default::default(),
                };
                let dense = sdf.sample(&grid, Extent::Band(3.0), &|_| {});
                let sdf = MeshSdf::new(&mesh, sign).unwrap();
                let sparse = sdf.sample_sparse(&grid, 3.0, &|_| {});
                assert_eq!(sparse.clamp, dense.clamp);
                assert_eq!(sparse.exact_nodes, dense.exact_nodes);
                let back = sparse.values.to_dense();
                assert!(back
                    .iter()
                    .zip(&dense.values)
                    .all(|(a, b)| a.to_bits() == b.to_bits()));
                let all = sparse.values.brick_counts().iter().product::<usize>();
                let stored = sparse.values.stored_count();
                assert!(stored > 0 && stored < all, "{stored} of {all}");
                for (b, v) in sparse.values.stored() {
                    assert!(v.iter().any(|x| x.abs() < sparse.clamp) || b.iter().all(|&c| c < 99));
                }
            }
        }
    }

    #[test]
    fn sparse_contradictions_agree_with_dense_ones_on_whether_any_exist() {
        let sdf = MeshSdf::new(&sphere(3), SignMode::Winding).unwrap();
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 33).unwrap();
        let good = sdf.sample_sparse(&grid, 3.0, &|_| {});
        assert_eq!(sparse_sign_contradictions(&grid, &good.values), 0);
        // Flip the side of one far brick and the sign of one stored node far from zero.
        let mut far = good.values.clone();
        let absent = far.all_bricks().find(|&b| !far.is_stored(b)).unwrap();
        far.set_inside(absent, !far.is_inside(absent));
        assert!(sparse_sign_contradictions(&grid, &far) > 0);
        assert!(sign_contradictions(&grid, &far.to_dense()) > 0);
        let mut node = good.values.clone();
        let (b, v) = node
            .stored_mut()
            .find(|(_, v)| v.iter().any(|x| x.abs() > 2.5 * grid.spacing))
            .map(|(b, v)| (b, v.to_vec()))
            .unwrap();
        let at = v.iter().position(|x| x.abs() > 2.5 * grid.spacing).unwrap();
        node.brick_mut(b).unwrap()[at] *= -1.0;
        assert_eq!(
            sparse_sign_contradictions(&grid, &node) > 0,
            sign_contradictions(&grid, &node.to_dense()) > 0
        );
    }

    #[test]
    fn rows_sampled_alone_are_the_whole_grids_rows_bit_for_bit() {
        // 17 grid bricks (33 sampling bricks) per axis: three region tiles, the last of one brick,
        // and rows cut across them.
        for (mesh, sign) in [
            (sphere(4), SignMode::Auto),
            (overlapping_cubes(), SignMode::Winding),
        ] {
            let sdf = MeshSdf::new(&mesh, sign).unwrap();
            let grid = Grid::cube_res(Vec3::splat(-1.3), Vec3::splat(1.9), 130).unwrap();
            let whole = sdf.sample_sparse(&grid, 2.0, &|_| {}).values;
            for (ys, zs) in [(3..7, 0..17), (0..17, 9..10), (15..17, 5..13)] {
                let part = sdf.sample_sparse_rows(&grid, 2.0, ys.clone(), zs.clone(), &|_| {});
                let mut checked = 0;
                for b in whole.all_bricks() {
                    if !(ys.contains(&b[1]) && zs.contains(&b[2])) {
                        continue;
                    }
                    assert_eq!(whole.is_stored(b), part.values.is_stored(b), "{b:?}");
                    match (whole.brick(b), part.values.brick(b)) {
                        (Some(w), Some(p)) => {
                            let bits = |v: &BrickValues| v.map(f32::to_bits);
                            assert_eq!(bits(w), bits(p), "{b:?}");
                        }
                        _ => assert_eq!(whole.is_inside(b), part.values.is_inside(b), "{b:?}"),
                    }
                    checked += 1;
                }
                assert_eq!(checked, ys.len() * zs.len() * whole.brick_counts()[0]);
            }
        }
    }

    /// Two overlapping closed cubes: closed and consistently oriented, but they cross each other
    /// and do not bound one solid.
    fn overlapping_cubes() -> pgvol_mesh::Mesh {
        let mut a = pgvol_mesh::shapes::cuboid(Vec3::ZERO, Vec3::ONE);
        let b = pgvol_mesh::shapes::cuboid(Vec3::new(0.6, 0.2, 0.2), Vec3::new(1.6, 0.8, 0.8));
        let base = a.positions.len() as u32;
        a.positions.extend(&b.positions);
        a.triangles
            .extend(b.triangles.iter().map(|t| t.map(|i| i + base)));
        a
    }

    #[test]
    fn auto_takes_the_winding_number_where_pseudonormal_signs_contradict() {
        let mesh = overlapping_cubes();
        let grid = Grid::cube_res(Vec3::splat(-0.3), Vec3::splat(1.9), 32).unwrap();
        let pseudo = MeshSdf::new(&mesh, SignMode::Pseudonormal).unwrap();
        let wrong = pseudo.sample(&grid, Extent::Dense, &|_| {});
        assert!(sign_contradictions(&grid, &wrong.values) > 0);

        let winding = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        let auto = MeshSdf::new(&mesh, SignMode::Auto).unwrap();
        assert_eq!(auto.sign_mode(), SignMode::Winding);
        // Closed: the winding number is whole and carried, never evaluated.
        assert!(auto.winding_is_whole());
        for extent in [Extent::Dense, Extent::Band(3.0)] {
            let got = auto.sample(&grid, extent, &|_| {});
            assert_eq!(got.values, winding.sample(&grid, extent, &|_| {}).values);
            assert_eq!(sign_contradictions(&grid, &got.values), 0);
        }
        let sparse = auto.sample_sparse(&grid, 3.0, &|_| {});
        assert_eq!(sparse_sign_contradictions(&grid, &sparse.values), 0);
        // Inside the first cube, nearer the second one's face: inside the union.
        let p = Vec3::new(0.45, 0.5, 0.5);
        assert!(auto.signed_distance(p) < 0.0);
        assert!(
            pseudo.signed_distance(p) > 0.0,
            "the pseudonormal sign is wrong here"
        );
    }

    #[test]
    fn avx2_and_baseline_scans_give_identical_grids() {
        // Fine triangles (smaller than a grid spacing) and both signs that use closest points.
        let mesh = sphere(5);
        let grid = Grid::cube_res(Vec3::splat(-1.3), Vec3::splat(1.2), 37).unwrap();
        for mode in [SignMode::Winding, SignMode::Pseudonormal] {
            let avx2 = MeshSdf::new(&mesh, mode).unwrap();
            let mut baseline = MeshSdf::new(&mesh, mode).unwrap();
            baseline.use_baseline_scans();
            for extent in [Extent::Dense, Extent::Band(2.0)] {
                let a = avx2.sample(&grid, extent, &|_| {}).values;
                let b = baseline.sample(&grid, extent, &|_| {}).values;
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a), bits(&b), "{mode:?} {extent:?}");
            }
        }
    }

    #[test]
    fn skipping_leaves_by_oriented_boxes_changes_no_bit() {
        let grid = Grid::cube_res(Vec3::splat(-1.3), Vec3::splat(1.2), 37).unwrap();
        let mut cases = vec![(sphere(5), grid)];
        if let Some(dir) = std::env::var_os("PGVOL_SHARED_MESHES") {
            let bunny = pgvol_mesh::read(&std::path::Path::new(&dir).join("stanford-bunny.obj"))
                .expect("the shared bunny");
            let (lo, hi) = bunny.bounds().expect("not empty");
            let grid = Grid::cube_res(lo - (hi - lo) * 0.05, hi + (hi - lo) * 0.05, 40).unwrap();
            cases.push((bunny, grid));
        }
        for (mesh, grid) in cases {
            for mode in [SignMode::Winding, SignMode::Pseudonormal] {
                let oriented = MeshSdf::new(&mesh, mode).unwrap();
                let mut axis_aligned = MeshSdf::new(&mesh, mode).unwrap();
                axis_aligned.use_axis_aligned_boxes_only();
                for extent in [Extent::Dense, Extent::Band(2.0)] {
                    let a = oriented.sample(&grid, extent, &|_| {}).values;
                    let b = axis_aligned.sample(&grid, extent, &|_| {}).values;
                    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&a), bits(&b), "{mode:?} {extent:?}");
                }
            }
        }
    }

    /// The accepted sizes: at the largest and smallest scales the validation lets through, the
    /// grid is the unit mesh's grid scaled, and out of range the field is refused rather than
    /// wrong (a mesh of size 1e10 used to get distances 38 % off, one of size 1e-10 a panic).
    #[test]
    fn meshes_at_the_extremes_of_the_accepted_range_scale_exactly() {
        let unit = sphere(3);
        let grid = Grid::cube_res(Vec3::splat(-1.3), Vec3::splat(1.2), 21).unwrap();
        for scale in [2f32.powi(-19), 2f32.powi(26)] {
            let mut mesh = unit.clone();
            mesh.positions.iter_mut().for_each(|p| *p *= scale);
            let scaled_grid = Grid {
                origin: grid.origin * scale,
                spacing: grid.spacing * scale,
                dims: grid.dims,
                offset: Default::default(),
            };
            for mode in [SignMode::Winding, SignMode::Pseudonormal] {
                let want = MeshSdf::new(&unit, mode).unwrap();
                let got = MeshSdf::new(&mesh, mode).unwrap();
                for extent in [Extent::Dense, Extent::Band(2.0)] {
                    let want = want.sample(&grid, extent, &|_| {}).values;
                    let got = got.sample(&scaled_grid, extent, &|_| {}).values;
                    for (w, g) in want.iter().zip(&got) {
                        // Same sign, and the same distance up to rounding at the unit scale.
                        assert_eq!(*g < 0.0, *w < 0.0, "scale {scale} {mode:?} {extent:?}");
                        assert!(
                            (g / scale - w).abs() <= 1e-6,
                            "scale {scale} {mode:?} {extent:?}: {} against {w}",
                            g / scale
                        );
                    }
                }
            }
        }
        for scale in [1e9, 1e-7] {
            let mut mesh = unit.clone();
            mesh.positions.iter_mut().for_each(|p| *p *= scale);
            assert_eq!(
                MeshSdf::new(&mesh, SignMode::Winding).err(),
                Some(SdfError::OutOfRange)
            );
        }
    }

    #[test]
    fn sign_modes_agree_on_a_closed_mesh() {
        let mesh = sphere(3);
        let w = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        let p = MeshSdf::new(&mesh, SignMode::Pseudonormal).unwrap();
        let a = MeshSdf::new(&mesh, SignMode::Auto).unwrap();
        assert_eq!(a.sign_mode(), SignMode::Winding);
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 33).unwrap();
        let vw = w.sample_grid(&grid, &|_| {});
        let vp = p.sample_grid(&grid, &|_| {});
        assert_eq!(vw, vp);
    }

    /// The exact (f64) winding number of `mesh` at every node of `grid`, x fastest.
    fn exact_node_windings(mesh: &pgvol_mesh::Mesh, grid: &Grid) -> Vec<f64> {
        let tris: Vec<_> = (0..mesh.triangles.len())
            .map(|t| mesh.triangle(t))
            .collect();
        let [nx, ny, _] = grid.dims;
        (0..grid.len())
            .map(|n| {
                let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
                crate::winding::exact_winding(&tris, grid.point(i, j, k))
            })
            .collect()
    }

    /// Nodes whose sampled sign differs from the exact winding number's, among those at least
    /// `margin` from 1/2.
    fn sign_disagreements(exact: &[f64], values: &[f32], margin: f64) -> usize {
        exact
            .iter()
            .zip(values)
            .filter(|(w, v)| (**w > 0.5) != (**v < 0.0) && (**w - 0.5).abs() >= margin)
            .count()
    }

    #[test]
    fn carried_winding_signs_match_per_node_winding_on_an_open_mesh() {
        let mut mesh = sphere(4);
        // Open the sphere: drop the cap above z = 0.6 and one flank.
        mesh.triangles.retain(|t| {
            let c = t.iter().map(|&i| mesh.positions[i as usize]).sum::<Vec3>() / 3.0;
            c.z < 0.6 && !(c.x > 0.7 && c.y > 0.0)
        });
        let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 41).unwrap();
        let exact = exact_node_windings(&mesh, &grid);
        // Dense, and a band whose far bricks take their signs from carried values too.
        for extent in [Extent::Dense, Extent::Band(2.0)] {
            let values = sdf.sample(&grid, extent, &|_| {}).values;
            // Within 0.01 of 1/2 the sign is decided by rounding: not counted.
            let wrong = sign_disagreements(&exact, &values, 0.01);
            assert!(
                wrong <= 2,
                "{extent:?}: {wrong} sign disagreements out of {}",
                grid.len()
            );
        }
    }

    #[test]
    fn a_closed_mesh_carries_its_whole_winding_number_without_computing_it() {
        // Two overlapping spheres (winding number 2 where they overlap), and a many-sided
        // prism: rows of nodes pass through its vertical edges at every height alike.
        let mut overlapping = sphere(3);
        let second = sphere(3);
        let base = overlapping.positions.len() as u32;
        let shift = Vec3::new(0.7, 0.2, 0.1);
        overlapping
            .positions
            .extend(second.positions.iter().map(|p| *p + shift));
        overlapping
            .triangles
            .extend(second.triangles.iter().map(|t| t.map(|i| i + base)));
        for mesh in [overlapping, pgvol_mesh::shapes::prism(1000)] {
            let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
            assert!(sdf.winding_is_whole());
            let (lo, hi) = mesh.bounds().unwrap();
            let grid = Grid::cube_res(lo - 0.1, hi + 0.1, 29).unwrap();
            let exact = exact_node_windings(&mesh, &grid);
            for extent in [Extent::Dense, Extent::Band(2.0)] {
                let values = sdf.sample(&grid, extent, &|_| {}).values;
                let wrong = sign_disagreements(&exact, &values, 0.0);
                assert_eq!(wrong, 0, "{extent:?}");
            }
            let computed = sdf.sampler_windings.load(Ordering::Relaxed);
            assert_eq!(computed, 0, "winding numbers computed by the sampler");
        }
    }

    #[test]
    fn parity_agrees_with_the_winding_number_on_closed_meshes() {
        let mesh = sphere(3);
        let w = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        let p = MeshSdf::new(&mesh, SignMode::Parity).unwrap();
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 29).unwrap();
        let reference = w.sample_grid(&grid, &|_| {});
        // Signs only: separately built trees may break distance ties between triangles sharing
        // a vertex differently, which changes the last bit of a few distances.
        let differing = |values: Vec<f32>| {
            values
                .iter()
                .zip(&reference)
                .filter(|(a, b)| (**a < 0.0) != (**b < 0.0) || (*a - *b).abs() > 1e-6)
                .count()
        };
        assert_eq!(differing(p.sample_grid(&grid, &|_| {})), 0);
        // Flipped faces do not fool parity.
        let mut flipped = mesh.clone();
        for t in flipped.triangles.iter_mut().step_by(2) {
            t.swap(1, 2);
        }
        let pf = MeshSdf::new(&flipped, SignMode::Parity).unwrap();
        assert_eq!(differing(pf.sample_grid(&grid, &|_| {})), 0);
    }

    #[test]
    fn auto_picks_winding_for_open_meshes() {
        let mut mesh = sphere(2);
        mesh.triangles.pop();
        assert_eq!(
            MeshSdf::new(&mesh, SignMode::Auto).unwrap().sign_mode(),
            SignMode::Winding
        );
    }

    #[test]
    fn grid_values_do_not_depend_on_thread_count() {
        // Open, so that winding numbers are carried with drift bounds, dense and in a band.
        let mut mesh = sphere(3);
        mesh.triangles
            .retain(|t| t.iter().map(|&i| mesh.positions[i as usize].z).sum::<f32>() < 1.5);
        let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        assert!(!sdf.rims().is_empty());
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::ONE, 40).unwrap();
        for extent in [Extent::Dense, Extent::Band(2.0)] {
            let run = |threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| sdf.sample(&grid, extent, &|_: f64| {}).values)
            };
            let one = run(1);
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
            assert!(one.iter().any(|&d| d < 0.0) && one.iter().any(|&d| d > 0.0));
            assert_eq!(bits(&one), bits(&run(2)), "{extent:?}");
        }
    }
}
