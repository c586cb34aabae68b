//! From a field given at points to node samples in a `SparseGrid`: only the bricks within the
//! band of some input point are stored, and the side of every other brick comes from a flood
//! fill of the brick grid from its border, so cost follows the surface, not the volume.

use std::collections::VecDeque;

use glam::Vec3;
use pgvol_core::sparse::{brick_offset, Background, BRICK_EDGE, BRICK_NODES};
use pgvol_core::{Grid, SparseGrid};
use rayon::prelude::*;

use crate::tangent::TangentField;

/// Node samples on `grid` of `field(x, t)`, `t` being the tangent-plane field at `x`, at the
/// nodes within `band` (mesh units) of a point, clamped to ±`band`, in the bricks holding such
/// nodes. The other nodes of those bricks get ±`band` by the side of their neighbours: two
/// adjacent nodes both a band (≥ 2 spacings) from every point cannot lie on opposite sides.
pub fn sample_band(
    grid: &Grid,
    points: &[Vec3],
    tangent: &TangentField,
    band: f32,
    field: &(dyn Fn(Vec3, f32) -> f32 + Sync),
) -> SparseGrid {
    let mut values = SparseGrid::new(grid.dims, Background::clamp(band));
    let bricks = band_bricks(grid, points, band);
    let filled: Vec<([usize; 3], Box<[f32; BRICK_NODES]>)> = bricks
        .par_iter()
        .map_init(Vec::new, |scratch, &b| {
            let mut brick = Box::new([f32::NAN; BRICK_NODES]);
            let lo = b.map(|c| c * BRICK_EDGE);
            for k in 0..BRICK_EDGE {
                for j in 0..BRICK_EDGE {
                    for i in 0..BRICK_EDGE {
                        let n = [lo[0] + i, lo[1] + j, lo[2] + k];
                        let at = brick_offset([i, j, k]);
                        if n.iter().zip(&grid.dims).any(|(a, d)| a >= d) {
                            brick[at] = band;
                            continue;
                        }
                        let x = grid.point(n[0], n[1], n[2]);
                        if let Some(t) = tangent.value(x, scratch) {
                            brick[at] = field(x, t).clamp(-band, band);
                        }
                    }
                }
            }
            spread_sides(&mut brick, band, |at| {
                let (i, j, k) = (
                    at % BRICK_EDGE,
                    at / BRICK_EDGE % BRICK_EDGE,
                    at / (BRICK_EDGE * BRICK_EDGE),
                );
                let n = [lo[0] + i, lo[1] + j, lo[2] + k];
                tangent.far_side(grid.point(n[0], n[1], n[2]))
            });
            (b, brick)
        })
        .collect();
    for (b, brick) in filled {
        values.insert(b, brick);
    }
    mark_inside(&mut values);
    values
}

/// `samples` (from [`sample_band`]) with `field(x)`, clamped to ±`band`, at every node of
/// their stored bricks: a refined field defined over those bricks replaces the first, without
/// repeating its neighbour queries. The unstored bricks keep their side.
pub fn resample(
    grid: &Grid,
    samples: &SparseGrid,
    band: f32,
    field: &(dyn Fn(Vec3) -> f32 + Sync),
) -> SparseGrid {
    let bricks: Vec<([usize; 3], Box<[f32; BRICK_NODES]>)> =
        samples.stored().map(|(b, v)| (b, Box::new(*v))).collect();
    let bricks: Vec<([usize; 3], Box<[f32; BRICK_NODES]>)> = bricks
        .into_par_iter()
        .map(|(b, mut brick)| {
            let (lo, n) = samples.brick_extent(b);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let x = grid.point(lo[0] + i, lo[1] + j, lo[2] + k);
                        brick[brick_offset([i, j, k])] = field(x).clamp(-band, band);
                    }
                }
            }
            (b, brick)
        })
        .collect();
    let mut out = samples.clone();
    for (b, brick) in bricks {
        out.insert(b, brick);
    }
    out
}

/// Fills the unset (NaN) nodes of a brick with ±`band` from the side of a set 6-neighbour,
/// sweep after sweep; a brick with no set node asks `side` for its first node.
fn spread_sides(brick: &mut [f32; BRICK_NODES], band: f32, side: impl Fn(usize) -> f32) {
    if brick.iter().all(|v| v.is_nan()) {
        brick[0] = band.copysign(side(0));
    }
    let e = BRICK_EDGE;
    loop {
        let mut unset = false;
        for at in 0..BRICK_NODES {
            if !brick[at].is_nan() {
                continue;
            }
            let (i, j, k) = (at % e, at / e % e, at / (e * e));
            let mut neighbours = [None; 6];
            if i > 0 {
                neighbours[0] = Some(at - 1);
            }
            if i + 1 < e {
                neighbours[1] = Some(at + 1);
            }
            if j > 0 {
                neighbours[2] = Some(at - e);
            }
            if j + 1 < e {
                neighbours[3] = Some(at + e);
            }
            if k > 0 {
                neighbours[4] = Some(at - e * e);
            }
            if k + 1 < e {
                neighbours[5] = Some(at + e * e);
            }
            match neighbours
                .iter()
                .flatten()
                .map(|&m| brick[m])
                .find(|v| !v.is_nan())
            {
                Some(v) => brick[at] = band.copysign(v),
                None => unset = true,
            }
        }
        if !unset {
            break;
        }
    }
}

/// The bricks of `grid` with a node within `band` of a point (by the box around it), z slowest.
/// One flag per brick of the grid rather than a list per point: the flags take a byte per
/// 512 nodes, the lists 24 bytes for each of the up to 27 bricks of every point.
pub fn band_bricks(grid: &Grid, points: &[Vec3], band: f32) -> Vec<[usize; 3]> {
    let counts = grid.dims.map(|d| d.div_ceil(BRICK_EDGE));
    let to_brick = |x: Vec3| {
        let g = grid.to_grid(x).to_array();
        std::array::from_fn::<usize, 3, _>(|a| {
            ((g[a].max(0.0) as usize) / BRICK_EDGE).min(counts[a].max(1) - 1)
        })
    };
    let mut flags = vec![false; counts.iter().product()];
    for &p in points {
        let lo = to_brick(p - band);
        let hi = to_brick(p + band + grid.spacing);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let row = counts[0] * (y + counts[1] * z);
                flags[row + lo[0]..=row + hi[0]].fill(true);
            }
        }
    }
    flags
        .iter()
        .enumerate()
        .filter(|(_, &f)| f)
        .map(|(i, _)| {
            [
                i % counts[0],
                i / counts[0] % counts[1],
                i / (counts[0] * counts[1]),
            ]
        })
        .collect()
}

/// Marks every absent brick not reachable from the grid's border through absent bricks as
/// inside: the stored band separates the inside from the border when the cloud is closed.
fn mark_inside(values: &mut SparseGrid) {
    let counts = values.brick_counts();
    let flat = |b: [usize; 3]| b[0] + counts[0] * (b[1] + counts[1] * b[2]);
    let mut outside = vec![false; counts.iter().product()];
    let mut queue = VecDeque::new();
    for b in values.all_bricks() {
        let border = (0..3).any(|a| b[a] == 0 || b[a] + 1 == counts[a]);
        if border && !values.is_stored(b) {
            outside[flat(b)] = true;
            queue.push_back(b);
        }
    }
    while let Some(b) = queue.pop_front() {
        for a in 0..3 {
            for step in [-1isize, 1] {
                let c = b[a] as isize + step;
                if c < 0 || c as usize >= counts[a] {
                    continue;
                }
                let mut n = b;
                n[a] = c as usize;
                if !outside[flat(n)] && !values.is_stored(n) {
                    outside[flat(n)] = true;
                    queue.push_back(n);
                }
            }
        }
    }
    let inside: Vec<[usize; 3]> = values
        .all_bricks()
        .filter(|&b| !outside[flat(b)] && !values.is_stored(b))
        .collect();
    for b in inside {
        values.set_inside(b, true);
    }
}
