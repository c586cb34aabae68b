//! Coefficient volumes stored sparsely: contouring must cost what the surface costs, whatever
//! the grid, and close surfaces that meet absent bricks or the grid's border.

use std::time::Instant;

use glam::Vec3;
use pgvol_contour::{contour_volume, resampled_grid, Method};
use pgvol_core::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};
use pgvol_field::{Basis, CoefficientVolume, Grid};

use crate::topology::check_closed_manifold;

const METHODS: [Method; 3] = [
    Method::MarchingCubes,
    Method::SurfaceNets,
    Method::DualContouring,
];

/// A cubic B-spline volume on a unit-spaced grid of `dims` nodes whose coefficients are the
/// distance to the sphere (`centre`, `r`) clamped to `±clamp`, stored only in the bricks whose
/// centre lies within `band` of the sphere; the others are absent on their side. Distances
/// stand in for the interpolating coefficients, which differ by far less than a spacing here.
fn sphere_volume(
    dims: [usize; 3],
    centre: Vec3,
    r: f32,
    clamp: f32,
    band: f32,
) -> CoefficientVolume {
    let grid = Grid {
        origin: Vec3::ZERO,
        spacing: 1.0,
        dims,
        offset: Default::default(),
    };
    let mut coeffs = SparseGrid::new(dims, Background::clamp(clamp));
    let half = (BRICK_EDGE - 1) as f32 / 2.0;
    let bricks: Vec<[usize; 3]> = coeffs.all_bricks().collect();
    for b in bricks {
        let (lo, n) = coeffs.brick_extent(b);
        let node = |i: usize, j: usize, k: usize| {
            Vec3::new((lo[0] + i) as f32, (lo[1] + j) as f32, (lo[2] + k) as f32)
        };
        let d = (node(0, 0, 0) + Vec3::splat(half) - centre).length() - r;
        if d.abs() > band {
            coeffs.set_inside(b, d < 0.0);
            continue;
        }
        let mut values = Box::new([clamp; BRICK_NODES]);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let d = (node(i, j, k) - centre).length() - r;
                    values[i + BRICK_EDGE * (j + BRICK_EDGE * k)] = d.clamp(-clamp, clamp);
                }
            }
        }
        coeffs.insert(b, values);
    }
    CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap()
}

/// Peak resident memory of this process so far, in MB.
fn peak_memory_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
    let kb: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kb / 1024.0
}

/// A dense 1024³ array of f32 would take 4 GB; a sphere of radius 40 needs a few thousand bricks.
#[test]
fn a_small_sphere_in_a_1024_grid_costs_what_its_surface_costs() {
    let r = 40.0;
    let v = sphere_volume([1024; 3], Vec3::new(500.3, 517.7, 509.1), r, 4.0, 12.0);
    let exact = 4.0 * std::f64::consts::PI * f64::from(r).powi(2);
    for method in METHODS {
        let start = Instant::now();
        let mesh = contour_volume(&v, &v.grid, 0.0, method, pgvol_core::progress::QUIET);
        let seconds = start.elapsed().as_secs_f64();
        let closed = check_closed_manifold(&mesh);
        let stats = mesh.stats();
        assert_eq!(closed.euler, 2, "{method:?}");
        assert_eq!(stats.components, 1, "{method:?}");
        assert!(
            (stats.area - exact).abs() < 0.02 * exact,
            "{method:?}: {stats:?}"
        );
        let memory = peak_memory_mb();
        eprintln!("{method:?}: {seconds:.3} s, peak memory {memory:.0} MB");
        assert!(memory < 500.0, "{method:?}: peak memory {memory:.0} MB");
        assert!(seconds < 20.0, "{method:?}: {seconds:.1} s");
    }
}

/// Thread count changes nothing, on the volume's grid and resampled.
#[test]
fn sparse_volumes_contour_identically_on_any_thread_count() {
    let v = sphere_volume([90, 80, 70], Vec3::new(10.0, 40.0, 35.0), 30.0, 4.0, 12.0);
    let in_pool = |threads: usize, f: &(dyn Fn() -> pgvol_core::Mesh + Sync)| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(f)
    };
    for grid in [v.grid, resampled_grid(&v, 37).unwrap()] {
        for method in METHODS {
            let run = || contour_volume(&v, &grid, 0.5, method, pgvol_core::progress::QUIET);
            let one = in_pool(1, &run);
            assert!(!one.triangles.is_empty());
            for threads in [2, 3] {
                assert_eq!(one, in_pool(threads, &run), "{method:?} {threads} threads");
            }
        }
    }
}

/// No brick stored at all: absent inside bricks against absent outside ones still bound a
/// region, and where it meets the border the padding closes it.
#[test]
fn absent_bricks_of_both_sides_bound_a_closed_region() {
    let dims = [40, 30, 50];
    let mut coeffs = SparseGrid::new(dims, Background::clamp(2.0));
    for b in coeffs.all_bricks().collect::<Vec<_>>() {
        coeffs.set_inside(b, b[2] < 3 && b[0] > 0);
    }
    let grid = Grid {
        origin: Vec3::ZERO,
        spacing: 1.0,
        dims,
        offset: Default::default(),
    };
    let v = CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap();
    for method in METHODS {
        let mesh = contour_volume(&v, &v.grid, 0.0, method, pgvol_core::progress::QUIET);
        let closed = check_closed_manifold(&mesh);
        assert_eq!(closed.euler, 2, "{method:?}");
        // Inside nodes span x 8..=39, y 0..=29, z 0..=23. The field crosses halfway to the
        // outside bricks, and two thirds of the way from -2 to the padding's +1; the dual
        // methods move their border vertices onto the field, which continues past the box.
        let pad = 2.0 / 3.0;
        let expected = (39.0 + pad - 7.5) * (29.0 + 2.0 * pad) * (23.5 + pad);
        let tolerance = if method == Method::MarchingCubes {
            0.02
        } else {
            0.08
        };
        assert!(
            (closed.volume - expected).abs() < tolerance * expected,
            "{method:?}: {}",
            closed.volume
        );
    }
}
