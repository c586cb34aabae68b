//! Times the brick-local fit of banded samples (`interp_sparse`) against the global one
//! (`interp_samples` on the densified samples), on a sphere's distance clamped to a band of 4
//! spacings: the stored and coefficient bricks, both times and the largest coefficient
//! difference in units of the clamp. Grids beyond the dense fit's reach get the sparse fit only.
//!
//! `cargo run --release -p pgvol-studies --bin sparse_fit [-- 128,192,256 [512,1024]]`
//! (the first list with both fits, the second sparse only; these are the defaults).

use std::time::Instant;

use glam::Vec3;
use pgvol_core::progress::QUIET;
use pgvol_core::sparse::brick_offset;
use pgvol_core::{Grid, SparseGrid};
use pgvol_field::analytic::Sphere;
use pgvol_field::fit::{interp_samples, interp_sparse, FitOptions};
use pgvol_field::Basis;

/// Half-width of the band, in grid spacings.
const BAND: f32 = 4.0;

/// A sphere's distance on an `n`³ grid over [−1, 1]³, banded as the encoder samples it.
fn banded_sphere(n: usize, band: f32) -> (Grid, SparseGrid) {
    let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), n).expect("a small grid");
    let ball = Sphere {
        centre: Vec3::new(0.03, -0.05, 0.07),
        radius: 0.6,
    };
    let samples = pgvol_field::analytic::banded_samples(&ball, &grid, band);
    (grid, samples)
}

/// Largest difference over the stored bricks of `a`, which `b` must store too.
fn max_diff(a: &SparseGrid, b: &SparseGrid) -> f32 {
    let mut worst = 0.0f32;
    for (at, x) in a.stored() {
        let y = b.brick(at).expect("the same bricks");
        let (_, n) = a.brick_extent(at);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let o = brick_offset([i, j, k]);
                    worst = worst.max((x[o] - y[o]).abs());
                }
            }
        }
    }
    worst
}

fn sizes(arg: Option<String>, default: &[usize]) -> Result<Vec<usize>, String> {
    match arg {
        None => Ok(default.to_vec()),
        Some(s) => s
            .split(',')
            .map(|n| n.trim().parse().map_err(|e| format!("{n}: {e}")))
            .collect(),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let both = sizes(args.next(), &[128, 192, 256])?;
    let sparse_only = sizes(args.next(), &[512, 1024])?;
    for n in both {
        let (grid, samples) = banded_sphere(n, BAND);
        let clamp = samples.background().outside;
        let t = Instant::now();
        let dense = samples.to_dense();
        let (dense_fit, _) = interp_samples(grid, Basis::Bspline3, &dense, &FitOptions::default())?;
        let dense_secs = t.elapsed().as_secs_f64();
        drop(dense);
        let t = Instant::now();
        let (sparse_fit, report) = interp_sparse(grid, Basis::Bspline3, &samples, QUIET)?;
        let sparse_secs = t.elapsed().as_secs_f64();
        let diff = max_diff(&sparse_fit.coeffs, &dense_fit.coeffs) / clamp;
        println!(
            "{n}³: {} of {} bricks stored, {} coefficient bricks; dense fit {dense_secs:.3} s, \
             sparse fit {sparse_secs:.3} s (sign check {:.3} s), max |Δc| {diff:.2e} · clamp",
            samples.stored_count(),
            samples.brick_counts().iter().product::<usize>(),
            sparse_fit.coeffs.stored_count(),
            report.stages.check,
        );
    }
    for n in sparse_only {
        let (grid, samples) = banded_sphere(n, BAND);
        let t = Instant::now();
        let (fit, _) = interp_sparse(grid, Basis::Bspline3, &samples, QUIET)?;
        println!(
            "{n}³: {} stored bricks, {} coefficient bricks; sparse fit {:.3} s",
            samples.stored_count(),
            fit.coeffs.stored_count(),
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
