//! The perturbation field sampled onto a sparse grid band, brick by brick, for a coefficient
//! fit: the cost follows the surface, and the field's box tree keeps each node to the terms
//! that reach it.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, Grid, SparseGrid, BRICK_EDGE, BRICK_NODES};
use rayon::prelude::*;

use crate::field::PerturbationField;

/// The first-order distance estimate `M / |∇M|` of `field` at the nodes of `grid`, clamped to
/// `band` spacings. A grid brick is sampled when its corners and centre disagree in sign or
/// one of them estimates the surface within the brick's half-diagonal plus the band; every
/// other brick takes the side of its centre.
pub fn sample_band(
    field: &PerturbationField,
    grid: &Grid,
    band: f32,
    update: &dyn pgvol_core::progress::Interrupt,
) -> SparseGrid {
    let h = grid.spacing;
    let clamp = band * h;
    let mut values = SparseGrid::new(grid.dims, Background::clamp(clamp));
    let bricks: Vec<[usize; 3]> = values.all_bricks().collect();
    let edge = (BRICK_EDGE - 1) as f32 * h;
    let reach = 0.5 * edge * 3f32.sqrt() + clamp;
    let node = |n: [usize; 3]| grid.origin + Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32) * h;
    let done = AtomicUsize::new(0);
    let total = bricks.len().max(1);
    let results: Vec<([usize; 3], Option<Box<BrickValues>>, bool)> = bricks
        .par_iter()
        .map(|&b| {
            let lo = node(b.map(|i| i * BRICK_EDGE));
            let probes = (0..8)
                .map(|c| {
                    lo + Vec3::new((c & 1) as f32, ((c >> 1) & 1) as f32, (c >> 2) as f32) * edge
                })
                .chain(std::iter::once(lo + Vec3::splat(0.5 * edge)));
            let estimates: Vec<f32> = probes.map(|p| field.distance_estimate(p).0).collect();
            let centre = estimates[8];
            let mixed = estimates.iter().any(|&d| d < 0.0) && estimates.iter().any(|&d| d >= 0.0);
            let near = estimates.iter().any(|d| d.abs() <= reach);
            let n = done.fetch_add(1, Ordering::Relaxed);
            if n.is_multiple_of(256) {
                update.update(n as f64 / total as f64);
            }
            if !(mixed || near) {
                return (b, None, centre < 0.0);
            }
            let mut brick = Box::new([clamp; BRICK_NODES]);
            for (k, v) in brick.iter_mut().enumerate() {
                let local = [
                    k % BRICK_EDGE,
                    (k / BRICK_EDGE) % BRICK_EDGE,
                    k / (BRICK_EDGE * BRICK_EDGE),
                ];
                let n = [0, 1, 2].map(|a| b[a] * BRICK_EDGE + local[a]);
                if n.iter().zip(grid.dims).any(|(&i, d)| i >= d) {
                    continue;
                }
                *v = field.distance_estimate(node(n)).0.clamp(-clamp, clamp);
            }
            (b, Some(brick), centre < 0.0)
        })
        .collect();
    for (b, brick, inside) in results {
        match brick {
            Some(v) => values.insert(b, v),
            None => values.set_inside(b, inside),
        }
    }
    values
}
