//! Dual contouring geometry: vertices on the surface, sharp features, triangle quality.

use glam::{Mat3, Vec3};
use pgvol_contour::{marching_cubes_with, min_angle_histogram, DualContourOptions, Field};
use pgvol_core::Mesh;

use crate::fields::{cube_face_normal, rotated_cube, sphere, tilt, torus, trilinear};
use crate::grids::{Rng, Samples};
use crate::topology::{check_balanced, check_closed_manifold, check_surface};

pub fn sampled(n: usize, f: &dyn Field) -> Samples {
    Samples::from_fn([n; 3], Vec3::splat(-1.0), 2.0 / (n - 1) as f32, |p| {
        f.value(p)
    })
}

/// Marching cubes with its vertices found on the continuous field, as the pipeline runs it.
pub fn mc_on_field(s: &Samples, field: &dyn Field) -> Mesh {
    let refine = |a: Vec3, _va: f32, b: Vec3, _vb: f32| {
        let (mut lo, mut hi) = (a, b);
        let lo_inside = field.value(a) < 0.0;
        for _ in 0..30 {
            let m = (lo + hi) / 2.0;
            if (field.value(m) < 0.0) == lo_inside {
                lo = m;
            } else {
                hi = m;
            }
        }
        (lo + hi) / 2.0
    };
    marching_cubes_with(&s.values, s.dims, s.origin, s.spacing, 0.0, &refine)
}

/// Mean angle in degrees between the face normals of `mesh` at area-uniform random points and
/// the true normal of the rotated cube there.
pub fn mean_normal_deviation(mesh: &Mesh, rot: Mat3, samples: usize, seed: u64) -> f64 {
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0f64;
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        total += f64::from((b - a).cross(c - a).length()) / 2.0;
        cumulative.push(total);
    }
    let mut rng = Rng::new(seed);
    let mut sum = 0.0;
    for _ in 0..samples {
        let x = f64::from(rng.range(0.0, 1.0)) * total;
        let t = cumulative
            .partition_point(|&c| c < x)
            .min(mesh.triangles.len() - 1);
        let [a, b, c] = mesh.triangle(t);
        let (mut u, mut v) = (rng.range(0.0, 1.0), rng.range(0.0, 1.0));
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + (b - a) * u + (c - a) * v;
        let n = (b - a).cross(c - a).normalize();
        let cos = n.dot(cube_face_normal(rot, p)).clamp(-1.0, 1.0);
        sum += f64::from(cos.acos().to_degrees());
    }
    sum / samples as f64
}

#[test]
fn rotated_cube_edges_are_sharp() {
    let rot = tilt();
    let cube = rotated_cube(0.5, rot);
    // Side 1 over 19.5 cells.
    let s = sampled(40, &cube);
    let dc = s.dual(0.0, &cube);
    let mc = mc_on_field(&s, &cube);
    let dc_closed = check_surface(&dc);
    check_surface(&mc);
    assert_eq!(dc_closed.euler, 2);
    assert!(
        (dc_closed.volume - 1.0).abs() < 2e-3,
        "volume {}",
        dc_closed.volume
    );
    let dc_dev = mean_normal_deviation(&dc, rot, 20_000, 1);
    let mc_dev = mean_normal_deviation(&mc, rot, 20_000, 1);
    println!("mean normal deviation: dual contouring {dc_dev:.3}°, marching cubes {mc_dev:.3}°");
    assert!(
        mc_dev >= 3.0 * dc_dev,
        "dual contouring {dc_dev}° vs marching cubes {mc_dev}°"
    );
}

/// The cubic B-spline interpolant of the samples, as the pipeline decodes it: its gradients near
/// sharp features are smoothed, which is what the QEF threshold has to cope with.
fn bspline(s: &Samples) -> pgvol_field::CoefficientVolume {
    use pgvol_field::{Basis, CoefficientVolume, Grid};
    let grid = Grid {
        origin: s.origin,
        spacing: s.spacing,
        dims: s.dims,
        offset: Default::default(),
    };
    CoefficientVolume::interpolate(grid, Basis::Bspline3, s.values.clone()).unwrap()
}

#[test]
fn default_threshold_is_near_the_best_on_cube_and_sphere() {
    let rot = tilt();
    let cube = rotated_cube(0.5, rot);
    let ball = sphere(0.7);
    let (sc, ss) = (sampled(40, &cube), sampled(50, &ball));
    let (cube_b, ball_b) = (bspline(&sc), bspline(&ss));
    let measure = |t: f32| {
        let options = DualContourOptions {
            singular_threshold: t,
            ..Default::default()
        };
        let deviation =
            |f: &dyn Field| mean_normal_deviation(&sc.dual_with(0.0, f, &options), rot, 20_000, 2);
        let ball_error = |f: &dyn Field| {
            let m = ss.dual_with(0.0, f, &options);
            let sum: f64 = m
                .positions
                .iter()
                .map(|p| f64::from((p.length() - 0.7).abs()))
                .sum();
            sum / m.positions.len() as f64 / f64::from(ss.spacing)
        };
        [
            deviation(&cube),
            deviation(&cube_b),
            ball_error(&ball),
            ball_error(&ball_b),
        ]
    };
    let candidates = [0.01, 0.02, 0.05, 0.1, 0.2, 0.3];
    let results: Vec<[f64; 4]> = candidates.iter().map(|&t| measure(t)).collect();
    println!("| threshold | cube exact (°) | cube B-spline (°) | sphere exact (cells) | sphere B-spline (cells) |");
    for (t, r) in candidates.iter().zip(&results) {
        println!(
            "| {t} | {:.3} | {:.3} | {:.5} | {:.5} |",
            r[0], r[1], r[2], r[3]
        );
    }
    let default = measure(DualContourOptions::default().singular_threshold);
    for m in 0..4 {
        let best = results.iter().map(|r| r[m]).fold(f64::INFINITY, f64::min);
        assert!(
            default[m] <= 1.25 * best + 1e-3,
            "measure {m}: {} vs best {best}",
            default[m]
        );
    }
}

#[test]
fn sphere_and_torus_vertices_lie_on_the_surface() {
    let ball = sphere(0.7);
    let s = sampled(48, &ball);
    let mesh = s.dual(0.0, &ball);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
    let worst = mesh
        .positions
        .iter()
        .map(|p| (p.length() - 0.7).abs())
        .fold(0.0, f32::max);
    // Tangent planes of a curved surface meet slightly outside it: about h²/(8 r) for planes
    // from crossings half a cell apart.
    assert!(
        worst < 0.05 * s.spacing,
        "vertex {worst} from the sphere (h = {})",
        s.spacing
    );
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.7f64.powi(3);
    assert!(
        (closed.volume - exact).abs() / exact < 3e-3,
        "volume {}",
        closed.volume
    );

    let ring = torus(0.55, 0.25);
    let t = sampled(64, &ring);
    let closed = check_surface(&t.dual(0.0, &ring));
    assert_eq!(closed.euler, 0);
    assert_eq!(closed.component_volumes.len(), 1);
}

#[test]
fn clamped_vertices_give_no_degenerate_triangles() {
    let cube = rotated_cube(0.5, tilt());
    let mut rng = Rng::new(21);
    let noisy = Samples::padded([24, 24, 24], 1.0, |_| rng.range(-1.0, 1.0));
    let inputs: [(Samples, Mesh); 3] = [
        {
            let s = sampled(33, &cube);
            let m = s.dual(0.0, &cube);
            (s, m)
        },
        {
            let m = noisy.dual_trilinear(0.0);
            (noisy.clone(), m)
        },
        {
            // The field disagrees with the samples here: vertices must still stay in their cells.
            let s = sampled(33, &cube);
            let m = s.dual(0.0, &sphere(0.3));
            (s, m)
        },
    ];
    for (s, mesh) in &inputs {
        assert!(!mesh.triangles.is_empty());
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.triangle(t);
            let area = (b - a).cross(c - a).length() / 2.0;
            assert!(area > 0.0, "triangle {t} has zero area");
        }
        let hist = min_angle_histogram(mesh);
        assert_eq!(hist.iter().sum::<usize>(), mesh.triangles.len());
        println!(
            "min angle histogram (10° bins): {hist:?}, spacing {}",
            s.spacing
        );
        check_surface(mesh);
    }
}

#[test]
fn dual_contouring_has_better_shaped_triangles_than_marching_cubes_on_a_sphere() {
    let ball = sphere(0.7);
    let s = sampled(48, &ball);
    let share_below_20 = |m: &Mesh| {
        let h = min_angle_histogram(m);
        (h[0] + h[1]) as f64 / m.triangles.len() as f64
    };
    let (dc, mc) = (
        share_below_20(&s.dual(0.0, &ball)),
        share_below_20(&mc_on_field(&s, &ball)),
    );
    println!("triangles with an angle under 20°: dual contouring {dc:.3}, marching cubes {mc:.3}");
    assert!(dc < mc, "dual contouring {dc} vs marching cubes {mc}");
}

#[test]
fn unclamped_vertices_keep_the_topology() {
    let mut rng = Rng::new(22);
    let s = Samples::padded([16, 16, 16], 1.0, |_| rng.range(-1.0, 1.0));
    let options = DualContourOptions {
        clamp_to_cell: false,
        ..Default::default()
    };
    let field = trilinear(&s);
    let free = s.dual_with(0.0, &field, &options);
    let clamped = s.dual(0.0, &field);
    // Geometry is not guaranteed without clamping (and diagonals are chosen by shape), so only
    // the combinatorics are compared.
    assert_eq!(free.positions.len(), clamped.positions.len());
    assert_eq!(free.triangles.len(), clamped.triangles.len());
    let moved = free
        .positions
        .iter()
        .zip(&clamped.positions)
        .filter(|(a, b)| a != b)
        .count();
    assert!(moved > 0, "clamping changed nothing on a noisy field");
    let edges = check_balanced(&free);
    assert_eq!(edges.max_uses, 2);
    assert_eq!(edges.non_manifold_vertices, 0);
    check_closed_manifold(&clamped);
}

#[test]
fn coefficient_volumes_are_fields() {
    use pgvol_field::{Basis, CoefficientVolume, Grid};
    let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 40).unwrap();
    let mut values = Vec::with_capacity(grid.len());
    for k in 0..grid.dims[2] {
        for j in 0..grid.dims[1] {
            for i in 0..grid.dims[0] {
                values.push(grid.point(i, j, k).length() - 0.6);
            }
        }
    }
    let volume = CoefficientVolume::interpolate(grid, Basis::Bspline3, values).unwrap();
    let samples = volume.sample(&grid);
    let mesh = pgvol_contour::dual_contour(
        &samples,
        grid.dims,
        grid.origin,
        grid.spacing,
        0.0,
        &volume,
        &DualContourOptions::default(),
    );
    assert_eq!(check_surface(&mesh).euler, 2);
    for p in &mesh.positions {
        assert!(
            volume.value(*p).abs() < 0.05 * grid.spacing,
            "{}",
            volume.value(*p)
        );
    }
}
