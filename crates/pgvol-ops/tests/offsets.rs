//! Offsets, shells and hollowing against exact volumes of the analytic solids they make.

use std::f64::consts::PI;

use glam::Vec3;
use pgvol_contour::{contour_volume, Method};
use pgvol_core::progress::QUIET;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_ops::{hollow, needs_wider_band, offset, shell, stored_band, Drain, ShellSide};
use rayon::prelude::*;

/// Resolution of the volume tests (nodes per axis of the field's grid).
const RES: usize = 128;

fn sample(grid: &Grid, f: impl Fn(Vec3) -> f32 + Sync) -> Vec<f32> {
    let [nx, ny, nz] = grid.dims;
    (0..nz)
        .into_par_iter()
        .flat_map_iter(|k| {
            let f = &f;
            (0..ny).flat_map(move |j| (0..nx).map(move |i| f(grid.point(i, j, k))))
        })
        .collect()
}

/// The field of `sdf` on a cube grid around `[-half, half]³`, cubic B-spline.
fn field(
    half: f32,
    res: usize,
    basis: Basis,
    sdf: impl Fn(Vec3) -> f32 + Sync,
) -> CoefficientVolume {
    let grid = Grid::cube_res(Vec3::splat(-half), Vec3::splat(half), res).unwrap();
    CoefficientVolume::interpolate(grid, basis, sample(&grid, sdf)).unwrap()
}

fn unit_cube(p: Vec3) -> f32 {
    let q = p.abs() - Vec3::splat(0.5);
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

fn ball(r: f32) -> impl Fn(Vec3) -> f32 + Sync {
    move |p: Vec3| p.length() - r
}

fn contoured_volume(v: &CoefficientVolume) -> f64 {
    let mesh = contour_volume(v, &v.grid, 0.0, Method::MarchingCubes, QUIET);
    let s = mesh.stats();
    assert!(s.watertight && s.winding_consistent, "{s:?}");
    s.volume
}

fn assert_close(got: f64, want: f64, rel: f64, what: &str) {
    let e = (got - want).abs() / want;
    eprintln!("{what}: relative volume error {e:.2e}");
    assert!(
        e < rel,
        "{what}: volume {got}, exact {want}, relative error {e}"
    );
}

#[test]
fn outward_offset_of_a_cube_is_the_rounded_cube() {
    let v = field(0.72, RES, Basis::Bspline3, unit_cube);
    let d = 0.15f64;
    let out = offset(&v, d as f32).unwrap();
    let exact = 1.0 + 6.0 * d + 3.0 * PI * d * d + 4.0 / 3.0 * PI * d * d * d;
    assert_close(contoured_volume(&out), exact, 0.005, "cube + 0.15");
}

#[test]
fn inward_offset_of_a_cube_is_a_smaller_cube() {
    let v = field(0.72, RES, Basis::Bspline3, unit_cube);
    let d = 0.15f64;
    let inner = offset(&v, -d as f32).unwrap();
    assert_close(
        contoured_volume(&inner),
        (1.0 - 2.0 * d).powi(3),
        0.005,
        "cube - 0.15",
    );
}

#[test]
fn offsets_of_a_ball_are_balls() {
    let v = field(0.7, RES, Basis::Bspline3, ball(0.5));
    for d in [-0.2f64, 0.1] {
        let moved = offset(&v, d as f32).unwrap();
        let exact = 4.0 / 3.0 * PI * (0.5 + d).powi(3);
        assert_close(
            contoured_volume(&moved),
            exact,
            0.005,
            &format!("ball {d:+}"),
        );
    }
}

#[test]
fn separable_offsets_subtract_the_constant_everywhere() {
    let wavy = |p: Vec3| (3.0 * p.x).sin() + p.y * p.z - 0.2;
    for basis in Basis::SEPARABLE {
        let v = field(1.0, 12, basis, wavy);
        let moved = offset(&v, 0.37).unwrap();
        // Inside, at the border and outside the box, where the field is extended.
        for p in [
            Vec3::new(0.1, -0.3, 0.25),
            Vec3::new(1.1, 0.0, -1.1),
            Vec3::splat(-1.1),
            Vec3::new(3.0, 0.2, 0.1),
        ] {
            let (a, b) = (v.value(p), moved.value(p));
            assert!(
                (a - 0.37 - b).abs() < 1e-5,
                "{basis:?} at {p}: {a} - 0.37 vs {b}"
            );
        }
    }
}

#[test]
fn pseudo_gaussian_offsets_are_refitted() {
    let basis = Basis::Pg { n: 3, r: 1.5 };
    let v = field(0.7, 16, basis, ball(0.5));
    let moved = offset(&v, 0.1).unwrap();
    assert_eq!(moved.basis, basis);
    // The refit interpolates the shifted node values (to the iterative solver's tolerance).
    let g = v.grid;
    for (i, j, k) in [(3, 4, 5), (8, 8, 8), (0, 15, 7), (12, 2, 9)] {
        let p = g.point(i, j, k);
        let (a, b) = (v.value(p), moved.value(p));
        assert!(
            (a - 0.1 - b).abs() < 2e-3,
            "node {i},{j},{k}: {a} - 0.1 vs {b}"
        );
    }
}

#[test]
fn hollowed_ball_is_the_difference_of_two_balls() {
    let v = field(0.6, RES, Basis::Bspline3, ball(0.5));
    let h = hollow(&v, 0.1, &[], QUIET).unwrap();
    let mesh = contour_volume(&h, &h.grid, 0.0, Method::MarchingCubes, QUIET);
    let s = mesh.stats();
    // Two spheres: the outside and the cavity's wall.
    assert_eq!((s.components, s.euler_characteristic), (2, 4), "{s:?}");
    let exact = 4.0 / 3.0 * PI * (0.5f64.powi(3) - 0.4f64.powi(3));
    assert_close(s.volume, exact, 0.005, "hollow ball");
}

#[test]
fn a_drain_joins_the_cavity_to_the_outside() {
    let v = field(0.6, 64, Basis::Bspline3, ball(0.5));
    let drain = Drain {
        point: Vec3::ZERO,
        direction: Vec3::new(0.0, 0.0, 2.0),
        diameter: 0.12,
    };
    let h = hollow(&v, 0.1, &[drain], QUIET).unwrap();
    let mesh = contour_volume(&h, &h.grid, 0.0, Method::MarchingCubes, QUIET);
    let s = mesh.stats();
    // One surface of genus 0: the cavity's wall continues through the tube to the outside.
    assert_eq!((s.components, s.euler_characteristic), (1, 2), "{s:?}");
    assert!(
        h.value(Vec3::new(0.0, 0.0, 0.45)) > 0.0,
        "the wall is open on the axis"
    );
    assert!(
        h.value(Vec3::new(0.0, 0.0, -0.45)) < 0.0,
        "the opposite wall is intact"
    );
}

#[test]
fn shells_have_the_volume_of_their_wall() {
    let v = field(0.7, RES, Basis::Bspline3, ball(0.5));
    let t = 0.1f64;
    let ball_volume = |r: f64| 4.0 / 3.0 * PI * r.powi(3);
    for (side, outer, inner) in [
        (ShellSide::Centred, 0.5 + t / 2.0, 0.5 - t / 2.0),
        (ShellSide::Inner, 0.5, 0.5 - t),
        (ShellSide::Outer, 0.5 + t, 0.5),
    ] {
        let s = shell(&v, t as f32, side, QUIET).unwrap();
        let exact = ball_volume(outer) - ball_volume(inner);
        assert_close(contoured_volume(&s), exact, 0.005, &format!("{side:?}"));
    }
}

#[test]
fn band_checks_follow_the_clamp() {
    let grid = Grid::cube_res(Vec3::splat(-0.6), Vec3::splat(0.6), 32).unwrap();
    let clamp = 4.0 * grid.spacing;
    let samples = sample(&grid, |p| (p.length() - 0.5).clamp(-clamp, clamp));
    let v = CoefficientVolume::interpolate(grid, Basis::Bspline3, samples).unwrap();
    assert!((stored_band(&v) - clamp).abs() < 1e-4 * clamp);
    assert!(!needs_wider_band(&v, grid.spacing));
    assert!(!needs_wider_band(&v, -1.9 * grid.spacing));
    assert!(needs_wider_band(&v, 2.1 * grid.spacing));
    assert!(needs_wider_band(&v, -3.0 * grid.spacing));
}

#[test]
fn bad_parameters_are_refused() {
    let v = field(0.6, 8, Basis::Bspline3, ball(0.5));
    assert!(offset(&v, f32::NAN).is_err());
    assert!(shell(&v, 0.0, ShellSide::Inner, QUIET).is_err());
    assert!(hollow(&v, -0.1, &[], QUIET).is_err());
    let bad = Drain {
        point: Vec3::ZERO,
        direction: Vec3::ZERO,
        diameter: 0.1,
    };
    assert!(hollow(&v, 0.1, &[bad], QUIET).is_err());
}
