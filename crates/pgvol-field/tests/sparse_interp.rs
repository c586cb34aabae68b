//! The local interpolation of sparse band samples against the global dense prefilter: same
//! coefficients to float precision where they matter, the background elsewhere, the same bits
//! on any number of threads.

use glam::Vec3;
use pgvol_core::sparse::brick_offset;
use pgvol_core::{Background, SparseGrid, BRICK_EDGE};
use pgvol_field::analytic::{Sphere, Torus};
use pgvol_field::fit::{interp_samples, interp_sparse};
use pgvol_field::{Basis, CoefficientVolume, FieldError, FitOptions, Grid, SignedDistance};

/// Band half-width in spacings, as the encoder samples by default.
const BAND: f32 = 4.0;

fn cube(n: usize) -> Grid {
    Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), n).unwrap()
}

fn box_grid(dims: [usize; 3]) -> Grid {
    Grid {
        origin: Vec3::splat(-1.0),
        spacing: 2.0 / (dims[0] - 1) as f32,
        dims,
        offset: Default::default(),
    }
}

fn sphere() -> Sphere {
    Sphere {
        centre: Vec3::new(0.03, -0.05, 0.07),
        radius: 0.6,
    }
}

fn torus() -> Torus {
    Torus {
        centre: Vec3::new(0.02, 0.04, -0.03),
        major: 0.55,
        minor: 0.22,
    }
}

/// `sdf` sampled as the encoder does, with the encoder's default band.
fn banded(grid: &Grid, sdf: &dyn SignedDistance) -> SparseGrid {
    pgvol_field::analytic::banded_samples(sdf, grid, BAND)
}

/// Bricks within one brick (26-neighbourhood) of a stored brick of `g`.
fn near_stored(g: &SparseGrid, b: [usize; 3]) -> bool {
    g.stored()
        .any(|(s, _)| (0..3).all(|a| s[a].abs_diff(b[a]) <= 1))
}

/// Largest coefficient difference between the sparse and the dense fit, over the nodes of the
/// bricks `within` selects.
fn max_coeff_diff(
    sparse: &CoefficientVolume,
    dense: &CoefficientVolume,
    within: impl Fn([usize; 3]) -> bool,
) -> f32 {
    let g = &sparse.coeffs;
    let mut worst = 0.0f32;
    for b in g.all_bricks().filter(|&b| within(b)) {
        let (lo, n) = g.brick_extent(b);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let node = [lo[0] + i, lo[1] + j, lo[2] + k];
                    worst = worst.max((g.get(node) - dense.coeffs.get(node)).abs());
                }
            }
        }
    }
    worst
}

/// Largest field difference at pseudo-random points of the box within the band, and how many
/// points were within it.
fn max_field_diff(
    sparse: &CoefficientVolume,
    dense: &CoefficientVolume,
    sdf: &dyn SignedDistance,
    clamp: f32,
) -> (f32, usize) {
    let grid = sparse.grid;
    let size = grid.max_corner() - grid.origin;
    let mut worst = 0.0f32;
    let mut tested = 0;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut unit = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..20_000 {
        let p = grid.origin + Vec3::new(unit(), unit(), unit()) * size;
        if sdf.distance(p).abs() >= clamp {
            continue;
        }
        tested += 1;
        worst = worst.max((sparse.value(p) - dense.value(p)).abs());
    }
    (worst, tested)
}

/// Measured: coefficients differ by at most 4.7e-7 · clamp (cubic; 1.3e-7 quadratic) over the
/// stored sample bricks and over every stored coefficient brick, the field at random points of
/// the band by at most 3.2e-7 · clamp. The figures are the same with a halo covering the whole
/// grid: they are the float rounding of the dense filter, which stores f32 between its passes
/// (the halo's own error, below one ulp, is measured in the crate's unit tests).
#[test]
fn matches_the_global_prefilter_in_and_around_the_band() {
    let cases: [(Grid, &dyn SignedDistance, Basis); 6] = [
        (cube(40), &sphere(), Basis::Bspline3),
        (cube(100), &sphere(), Basis::Bspline3),
        (cube(64), &torus(), Basis::Bspline3),
        (cube(70), &sphere(), Basis::Bspline3),
        (box_grid([37, 50, 29]), &torus(), Basis::Bspline3),
        (box_grid([37, 50, 29]), &sphere(), Basis::Bspline2),
    ];
    for (grid, sdf, basis) in cases {
        let samples = banded(&grid, sdf);
        let clamp = samples.background().outside;
        let (sparse, report) =
            interp_sparse(grid, basis, &samples, pgvol_core::progress::QUIET).unwrap();
        let dense = CoefficientVolume::interpolate(grid, basis, samples.to_dense()).unwrap();
        let in_samples = max_coeff_diff(&sparse, &dense, |b| samples.is_stored(b)) / clamp;
        let in_coeffs = max_coeff_diff(&sparse, &dense, |b| sparse.coeffs.is_stored(b)) / clamp;
        let (field, tested) = max_field_diff(&sparse, &dense, sdf, clamp);
        let field = field / clamp;
        let name = format!("{basis} on {:?}", grid.dims);
        assert!(tested > 500, "{name}: {tested} points in the band");
        assert!(
            in_samples < 1e-6,
            "{name}: {in_samples:e} in the sample bricks"
        );
        assert!(
            in_coeffs < 1e-6,
            "{name}: {in_coeffs:e} in the coefficient bricks"
        );
        assert!(field < 1e-6, "{name}: field differs by {field:e}");
        // Unstored bricks begin 9 nodes from any sample brick: there the true coefficients
        // depart from the background by at most ≈ 1.4 · 0.268⁹ ≈ 1e-5 of its sample range.
        let everywhere = max_coeff_diff(&sparse, &dense, |_| true) / clamp;
        assert!(everywhere < 2e-5, "{name}: {everywhere:e} anywhere");
        assert_eq!(report.solver, "prefilter");
        assert_eq!(report.spurious_sign_changes, 0, "{name}");
    }
}

#[test]
fn far_bricks_are_the_background_of_their_side() {
    // Large enough for bricks inside that are not next to the band.
    let ball = Sphere {
        centre: Vec3::ZERO,
        radius: 0.8,
    };
    let grid = cube(96);
    let samples = banded(&grid, &ball);
    let (vol, _) =
        interp_sparse(grid, Basis::Bspline3, &samples, pgvol_core::progress::QUIET).unwrap();
    let c = &vol.coeffs;
    assert_eq!(c.background(), samples.background());
    let mut far = 0;
    let mut inside = 0;
    for b in c.all_bricks() {
        let near = near_stored(&samples, b);
        // Stored bricks are sample bricks or their neighbours; neighbours at the background
        // within the drop tolerance are left out.
        assert!(!c.is_stored(b) || near, "brick {b:?}");
        assert!(c.is_stored(b) || !samples.is_stored(b), "brick {b:?}");
        if !near {
            far += 1;
            inside += usize::from(samples.is_inside(b));
            assert_eq!(c.is_inside(b), samples.is_inside(b), "brick {b:?}");
            let bg = samples.background_of(b);
            assert!(c.brick_values(b).iter().all(|&v| v == bg), "brick {b:?}");
        }
    }
    assert!(far > 100 && inside > 0, "{far} far bricks, {inside} inside");
}

/// A lone stored brick holding the background all around it: every coefficient computed is
/// that constant to float rounding, as the prefilter maps constants to themselves.
#[test]
fn a_constant_brick_gives_constant_coefficients() {
    let grid = cube(40);
    let mut samples = SparseGrid::new(grid.dims, Background::clamp(0.25));
    let bricks: Vec<[usize; 3]> = samples.all_bricks().collect();
    for b in bricks {
        samples.set_inside(b, true);
    }
    samples.insert([2, 2, 2], Box::new([-0.25; 512]));
    let (vol, _) =
        interp_sparse(grid, Basis::Bspline3, &samples, pgvol_core::progress::QUIET).unwrap();
    // The sample brick; its neighbours sit at the background and are left to it.
    assert_eq!(vol.coeffs.stored_count(), 1);
    for (b, values) in vol.coeffs.stored() {
        let want = samples.background_of(b);
        assert!(values.iter().all(|v| (v - want).abs() < 1e-6), "{b:?}");
    }
}

/// No stored brick: nothing to compute, every brick keeps its side.
#[test]
fn samples_without_bricks_give_the_background() {
    let grid = box_grid([30, 20, 70]);
    let mut samples = SparseGrid::new(grid.dims, Background::clamp(0.5));
    samples.set_inside([1, 2, 8], true);
    let (vol, report) =
        interp_sparse(grid, Basis::Bspline3, &samples, pgvol_core::progress::QUIET).unwrap();
    assert_eq!(vol.coeffs.stored_count(), 0);
    assert_eq!(vol.coeffs, samples);
    assert_eq!(report.spurious_sign_changes, 0);
}

#[test]
fn bits_do_not_depend_on_the_thread_count() {
    let grid = box_grid([70, 61, 53]);
    let samples = banded(&grid, &torus());
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            interp_sparse(grid, Basis::Bspline3, &samples, pgvol_core::progress::QUIET)
                .unwrap()
                .0
        })
    };
    let (one, two) = (run(1), run(2));
    let bricks = |v: &CoefficientVolume| -> Vec<([usize; 3], Vec<u32>)> {
        v.coeffs
            .stored()
            .map(|(b, x)| (b, x.iter().map(|f| f.to_bits()).collect()))
            .collect()
    };
    assert!(one.coeffs.stored_count() > 100);
    assert_eq!(bricks(&one), bricks(&two));
    assert_eq!(one, two);
}

/// Axes of 9, 17 and 11 nodes end in bricks of 1, 1 and 3 nodes, and the windows cover whole
/// axes: the local filter is then the global one, up to its float rounding.
#[test]
fn grids_not_a_multiple_of_the_brick() {
    for dims in [[9, 17, 11], [2, 3, 2], [37, 50, 29]] {
        let grid = Grid {
            origin: Vec3::splat(-0.6),
            spacing: 1.2 / (dims[1] - 1) as f32,
            dims,
            offset: Default::default(),
        };
        let samples = banded(&grid, &sphere());
        let clamp = samples.background().outside;
        let (sparse, _) =
            interp_sparse(grid, Basis::Bspline3, &samples, pgvol_core::progress::QUIET).unwrap();
        let dense =
            CoefficientVolume::interpolate(grid, Basis::Bspline3, samples.to_dense()).unwrap();
        let diff = max_coeff_diff(&sparse, &dense, |_| true) / clamp;
        assert!(diff < 2e-5, "{dims:?}: {diff:e}");
        let in_coeffs = max_coeff_diff(&sparse, &dense, |b| sparse.coeffs.is_stored(b)) / clamp;
        assert!(in_coeffs < 1e-6, "{dims:?}: {in_coeffs:e}");
        // Nodes of the last bricks past the grid are not nodes: every node compares equal.
        for n in [[dims[0] - 1, dims[1] - 1, dims[2] - 1], [dims[0] - 1, 0, 0]] {
            let (s, d) = (sparse.coeffs.get(n), dense.coeffs.get(n));
            assert!(
                (s - d).abs() < 1e-6 * clamp,
                "{dims:?} at {n:?}: {s} vs {d}"
            );
        }
        assert!(dims.iter().any(|&n| n % BRICK_EDGE != 0));
    }
}

#[test]
fn trilinear_keeps_the_samples_and_pseudo_gaussians_fit_densely() {
    let grid = cube(20);
    let samples = banded(&grid, &sphere());
    let (tri, report) = interp_sparse(
        grid,
        Basis::Trilinear,
        &samples,
        pgvol_core::progress::QUIET,
    )
    .unwrap();
    assert_eq!(tri.coeffs, samples);
    assert_eq!(report.solver, "none");
    let pg = Basis::Pg { n: 3, r: 1.5 };
    let (sparse, _) = interp_sparse(grid, pg, &samples, pgvol_core::progress::QUIET).unwrap();
    let opts = FitOptions::default();
    let (dense, _) = interp_samples(grid, pg, &samples.to_dense(), &opts).unwrap();
    assert_eq!(sparse, dense);
}

#[test]
fn bad_samples_are_refused() {
    let grid = cube(20);
    let other = SparseGrid::new([20, 20, 19], Background::clamp(1.0));
    assert_eq!(
        interp_sparse(grid, Basis::Bspline3, &other, pgvol_core::progress::QUIET).err(),
        Some(FieldError::DimsMismatch {
            got: [20, 20, 19],
            want: [20, 20, 20]
        })
    );
    let mut bad = SparseGrid::new(grid.dims, Background::clamp(1.0));
    let mut values = Box::new([0.5; 512]);
    values[brick_offset([3, 1, 2])] = f32::NAN;
    bad.insert([1, 0, 0], values);
    assert_eq!(
        interp_sparse(grid, Basis::Bspline3, &bad, pgvol_core::progress::QUIET).err(),
        Some(FieldError::NonFinite {
            index: grid.index(11, 1, 2)
        })
    );
}
