//! Slicing: exact layer heights, exact cross-section areas, orientation, closure and simplicity.

use pgvol_core::progress::QUIET;
use std::f64::consts::PI;

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_slice::{layer_heights, slice, slice_volume, Axis, Layer, SliceOptions};
use proptest::prelude::*;

fn sample(grid: &Grid, f: impl Fn(Vec3) -> f32) -> Vec<f32> {
    let [nx, ny, nz] = grid.dims;
    let mut v = Vec::with_capacity(grid.len());
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                v.push(f(grid.point(i, j, k)));
            }
        }
    }
    v
}

fn field(half: f32, res: usize, sdf: impl Fn(Vec3) -> f32) -> CoefficientVolume {
    let grid = Grid::cube_res(Vec3::splat(-half), Vec3::splat(half), res).unwrap();
    CoefficientVolume::interpolate(grid, Basis::Bspline3, sample(&grid, sdf)).unwrap()
}

fn area(points: &[[f32; 2]]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            a[0] as f64 * b[1] as f64 - b[0] as f64 * a[1] as f64
        })
        .sum::<f64>()
        / 2.0
}

fn contains(poly: &[[f32; 2]], p: [f32; 2]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

fn cross(o: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f64 {
    (a[0] as f64 - o[0] as f64) * (b[1] as f64 - o[1] as f64)
        - (a[1] as f64 - o[1] as f64) * (b[0] as f64 - o[0] as f64)
}

/// Closed segments share a point (collinear overlaps included).
fn touch(p: [f32; 2], q: [f32; 2], r: [f32; 2], s: [f32; 2]) -> bool {
    let (d1, d2, d3, d4) = (
        cross(p, q, r),
        cross(p, q, s),
        cross(r, s, p),
        cross(r, s, q),
    );
    if d1 == 0.0 && d2 == 0.0 {
        let ov = |k: usize| p[k].min(q[k]) <= r[k].max(s[k]) && r[k].min(s[k]) <= p[k].max(q[k]);
        return ov(0) && ov(1);
    }
    d1.signum() * d2.signum() <= 0.0 && d3.signum() * d4.signum() <= 0.0
}

/// Every loop has at least 3 points, no segment of the layer touches another except a loop's
/// neighbouring segments at their shared end, and each loop is a hole exactly when an odd
/// number of other loops contain it, with orientation to match.
fn check_layer(layer: &Layer) {
    // (loop, index in loop, loop length, start, end)
    type Seg = (usize, usize, usize, [f32; 2], [f32; 2]);
    let segs: Vec<Seg> = layer
        .loops
        .iter()
        .enumerate()
        .flat_map(|(l, lp)| {
            let n = lp.points.len();
            (0..n).map(move |k| (l, k, n, lp.points[k], lp.points[(k + 1) % n]))
        })
        .collect();
    for lp in &layer.loops {
        assert!(lp.points.len() >= 3);
    }
    for (a, s) in segs.iter().enumerate() {
        for t in &segs[a + 1..] {
            if s.0 == t.0 && (t.1 == (s.1 + 1) % s.2 || s.1 == (t.1 + 1) % s.2) {
                // Neighbours: only the shared end, no fold-back.
                let (x, y, z) = if t.1 == (s.1 + 1) % s.2 {
                    (s.3, s.4, t.4)
                } else {
                    (t.3, t.4, s.4)
                };
                let back = (x[0] - y[0]) * (z[0] - y[0]) + (x[1] - y[1]) * (z[1] - y[1]);
                assert!(
                    !(cross(x, y, z) == 0.0 && back > 0.0),
                    "fold-back in loop {}",
                    s.0
                );
                continue;
            }
            assert!(
                !touch(s.3, s.4, t.3, t.4),
                "layer {}: loop {} segment {} touches loop {} segment {}",
                layer.height,
                s.0,
                s.1,
                t.0,
                t.1
            );
        }
    }
    for (l, lp) in layer.loops.iter().enumerate() {
        let depth = layer
            .loops
            .iter()
            .enumerate()
            .filter(|&(m, other)| m != l && contains(&other.points, lp.points[0]))
            .count();
        assert_eq!(lp.hole, depth % 2 == 1, "loop {l} at depth {depth}");
        assert_eq!(lp.hole, area(&lp.points) < 0.0, "loop {l} orientation");
    }
}

#[test]
fn layer_heights_are_exact() {
    let b = (Vec3::ZERO, Vec3::ONE);
    let mut o = SliceOptions::new(Axis::Z, 0.25, 0.01);
    o.first = Some(0.0);
    assert_eq!(
        layer_heights(b, &o).unwrap(),
        vec![0.0, 0.25, 0.5, 0.75, 1.0]
    );
    o.first = None;
    assert_eq!(
        layer_heights(b, &o).unwrap(),
        vec![0.125, 0.375, 0.625, 0.875]
    );
    let o = SliceOptions::new(Axis::Z, 0.1, 0.01);
    let h = layer_heights(b, &o).unwrap();
    assert_eq!(h.len(), 10);
    for (i, &z) in h.iter().enumerate() {
        assert_eq!(z, (0.05f32 as f64 + i as f64 * 0.1f32 as f64) as f32);
    }
    // The axis picks the coordinate of the bounds.
    let tall = (Vec3::new(0.0, -2.0, 0.0), Vec3::new(1.0, 2.0, 1.0));
    assert_eq!(
        layer_heights(tall, &SliceOptions::new(Axis::Y, 0.5, 0.1))
            .unwrap()
            .len(),
        8
    );
    // Above the top: nothing; bad steps: refused.
    let above = SliceOptions {
        first: Some(2.0),
        ..o
    };
    assert!(layer_heights(b, &above).unwrap().is_empty());
    assert!(layer_heights(b, &SliceOptions::new(Axis::Z, 0.0, 0.1)).is_err());
    assert!(layer_heights(b, &SliceOptions::new(Axis::Z, 1e-9, 0.1)).is_err());
}

#[test]
fn sphere_layers_are_discs() {
    let r = 0.5f64;
    let v = field(0.6, 64, |p| p.length() - r as f32);
    let bounds = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let mut o = SliceOptions::new(Axis::Z, 0.1, 0.01);
    o.tolerance = 2e-4;
    let layers = slice_volume(&v, bounds, &o, QUIET).unwrap();
    assert_eq!(layers.len(), 10);
    let mut worst = 0.0f64;
    for (i, layer) in layers.iter().enumerate() {
        let z = layer.height as f64;
        assert_eq!(
            layer.height,
            (-0.5 + 0.05f32 as f64 + i as f64 * 0.1f32 as f64) as f32
        );
        assert_eq!(layer.loops.len(), 1, "layer {z}");
        let lp = &layer.loops[0];
        assert!(!lp.hole);
        let exact = PI * (r * r - z * z);
        let e = (area(&lp.points) - exact).abs() / exact;
        worst = worst.max(e);
        assert!(e < 0.005, "layer {z}: area {} vs {exact}", area(&lp.points));
        check_layer(layer);
    }
    eprintln!("sphere layers: worst relative area error {worst:.2e}");
}

#[test]
fn every_axis_gives_counter_clockwise_discs() {
    // An off-centre ball: each axis sees the same disc at the same height.
    let c = Vec3::new(0.1, -0.05, 0.08);
    let v = field(0.6, 40, |p| (p - c).length() - 0.4);
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let mut o = SliceOptions::new(axis, 0.3, 0.01);
        o.first = Some(0.0);
        let layers = slice_volume(&v, (Vec3::splat(-0.5), Vec3::splat(0.5)), &o, QUIET).unwrap();
        let layer = &layers[0];
        assert_eq!(layer.loops.len(), 1, "{axis:?}");
        let h = match axis {
            Axis::X => c.x,
            Axis::Y => c.y,
            Axis::Z => c.z,
        } as f64;
        let exact = PI * (0.16 - h * h);
        let a = area(&layer.loops[0].points);
        assert!(
            (a - exact).abs() / exact < 0.005,
            "{axis:?}: {a} vs {exact}"
        );
    }
}

#[test]
fn torus_mid_layer_has_an_outer_loop_and_a_hole() {
    let (big, small) = (0.5f32, 0.2f32);
    let torus = move |p: Vec3| {
        let q = glam::Vec2::new(p.truncate().length() - big, p.z);
        q.length() - small
    };
    let v = field(0.75, 64, torus);
    let mut o = SliceOptions::new(Axis::Z, 1.0, 0.01);
    o.first = Some(0.0);
    o.tolerance = 2e-4;
    let layers = slice_volume(&v, (Vec3::splat(-0.75), Vec3::splat(0.75)), &o, QUIET).unwrap();
    assert_eq!(layers.len(), 1);
    let layer = &layers[0];
    assert_eq!(layer.loops.len(), 2);
    let outer = layer.loops.iter().find(|l| !l.hole).expect("outer loop");
    let hole = layer.loops.iter().find(|l| l.hole).expect("hole");
    let (ao, ah) = (area(&outer.points), area(&hole.points));
    assert!((ao - PI * 0.49).abs() / (PI * 0.49) < 0.005, "outer {ao}");
    assert!((ah + PI * 0.09).abs() / (PI * 0.09) < 0.005, "hole {ah}");
    assert!(contains(&outer.points, hole.points[0]));
    check_layer(layer);
}

/// A field full of saddles, islands and holes.
fn wavy(a: f32, b: f32, c: f32, bias: f32) -> impl Fn(Vec3) -> f32 + Sync {
    move |p: Vec3| {
        (a * p.x + 1.0).sin() * (b * p.y + 2.0).sin() + 0.4 * (c * p.z + p.x).sin() + bias
    }
}

#[test]
fn simplification_stays_within_tolerance_of_the_extracted_loops() {
    let f = wavy(9.0, 11.0, 5.0, 0.1);
    let bounds = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let mut exact = SliceOptions::new(Axis::Z, 0.25, 0.02);
    exact.tolerance = 0.0;
    let raw = slice(&f, bounds, &exact).unwrap();
    for tol in [0.002f32, 0.02, 0.1] {
        let simplified = slice(
            &f,
            bounds,
            &SliceOptions {
                tolerance: tol,
                ..exact
            },
        )
        .unwrap();
        let (mut before, mut after) = (0, 0);
        for (lr, ls) in raw.iter().zip(&simplified) {
            check_layer(ls);
            assert_eq!(lr.loops.len(), ls.loops.len());
            for (a, b) in lr.loops.iter().zip(&ls.loops) {
                assert_eq!(a.hole, b.hole);
                // A subsequence starting at the same vertex.
                let mut it = a.points.iter();
                for q in &b.points {
                    assert!(it.any(|p| p == q), "not a subsequence");
                }
                assert_eq!(a.points[0], b.points[0]);
                let n = b.points.len();
                for p in &a.points {
                    let d = (0..n)
                        .map(|k| seg_dist(*p, b.points[k], b.points[(k + 1) % n]))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        d <= tol as f64 * (1.0 + 1e-5),
                        "vertex {d} from the loop, tol {tol}"
                    );
                }
                before += a.points.len();
                after += n;
            }
        }
        assert!(
            after < before,
            "tolerance {tol}: {before} -> {after} vertices"
        );
        eprintln!("tolerance {tol}: {before} -> {after} vertices");
    }
    for layer in &raw {
        check_layer(layer);
    }
}

fn seg_dist(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f64 {
    let (px, py, ax, ay) = (p[0] as f64, p[1] as f64, a[0] as f64, a[1] as f64);
    let (dx, dy) = (b[0] as f64 - ax, b[1] as f64 - ay);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((px - ax) * dx + (py - ay) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (px - ax - t * dx).hypot(py - ay - t * dy)
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let f = wavy(7.0, 8.0, 6.0, -0.05);
    let bounds = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let o = SliceOptions::new(Axis::Y, 0.1, 0.03);
    let many = slice(&f, bounds, &o).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let one = pool.install(|| slice(&f, bounds, &o).unwrap());
    assert_eq!(many, one);
}

#[test]
fn solids_reaching_the_bounds_are_closed_along_them() {
    // The whole plane is inside: one loop just outside the bounds (the ring of outside nodes
    // one spacing out closes it, cutting the corners).
    let layers = slice(
        &|_| -1.0,
        (Vec3::ZERO, Vec3::ONE),
        &SliceOptions::new(Axis::Z, 0.5, 0.1),
    )
    .unwrap();
    assert_eq!(layers.len(), 2);
    for layer in &layers {
        assert_eq!(layer.loops.len(), 1);
        let lp = &layer.loops[0];
        assert!(!lp.hole);
        for p in &lp.points {
            assert!(p.iter().all(|&x| (-0.1..=1.1).contains(&x)), "{p:?}");
            assert!(p.iter().any(|&x| !(0.0..=1.0).contains(&x)), "{p:?}");
        }
        let a = area(&lp.points);
        assert!(a > 1.0 && a < 1.2 * 1.2, "{a}");
        check_layer(layer);
    }
    // Non-finite values count as outside.
    let layers = slice(
        &|_| f32::NAN,
        (Vec3::ZERO, Vec3::ONE),
        &SliceOptions::new(Axis::Z, 0.5, 0.1),
    )
    .unwrap();
    assert!(layers.iter().all(|l| l.loops.is_empty()));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn random_fields_give_valid_layers(
        a in 2.0f32..14.0, b in 2.0f32..14.0, c in 1.0f32..8.0, bias in -0.6f32..0.6,
        res in 0.02f32..0.08, tol_frac in 0.0f32..2.0,
    ) {
        let f = wavy(a, b, c, bias);
        let mut o = SliceOptions::new(Axis::Z, 0.3, res);
        o.tolerance = res * tol_frac;
        let layers = slice(&f, (Vec3::splat(-0.7), Vec3::splat(0.7)), &o).unwrap();
        prop_assert_eq!(layers.len(), 5);
        for layer in &layers {
            check_layer(layer);
        }
    }
}
