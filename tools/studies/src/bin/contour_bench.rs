//! Times marching cubes, dual contouring and surface nets on a 256³ grid and prints a markdown
//! table. Run with `cargo run --release -p pgvol-studies --bin contour_bench [-- N]`.

use std::time::Instant;

use glam::Vec3;
use pgvol::Mesh;
use pgvol_contour::{
    dual_contour, marching_cubes, marching_cubes_with, min_angle_histogram, surface_nets,
    DualContourOptions, Field,
};
use rayon::prelude::*;

type AnalyticField = dyn Fn(Vec3) -> (f32, Vec3) + Sync;

fn sphere(p: Vec3) -> (f32, Vec3) {
    (p.length() - 0.7, p.normalize_or(Vec3::X))
}

/// A sphere with a smooth bumpy surface: sums of sines, with their exact gradient.
fn bumpy(p: Vec3) -> (f32, Vec3) {
    let mut v = p.length() - 0.6;
    let mut g = p.normalize_or(Vec3::X);
    for (k, w) in [(7.0f32, 0.05f32), (13.0, 0.025), (23.0, 0.012)] {
        let (s, c) = (
            Vec3::new((k * p.x).sin(), (k * p.y).sin(), (k * p.z).sin()),
            Vec3::new((k * p.x).cos(), (k * p.y).cos(), (k * p.z).cos()),
        );
        v += w * (s.x * c.y + s.y * c.z + s.z * c.x);
        g += w
            * k
            * Vec3::new(
                c.x * c.y - s.z * s.x,
                -s.x * s.y + c.y * c.z,
                -s.y * s.z + c.z * c.x,
            );
    }
    (v, g)
}

fn sample(n: usize, f: &dyn Field) -> Vec<f32> {
    let h = 2.0 / (n - 1) as f32;
    (0..n * n * n)
        .into_par_iter()
        .map(|idx| {
            let (i, j, k) = (idx % n, (idx / n) % n, idx / (n * n));
            f.value(Vec3::splat(-1.0) + h * Vec3::new(i as f32, j as f32, k as f32))
        })
        .collect()
}

fn time(f: impl Fn() -> Mesh) -> (Mesh, f64) {
    // Best of three, so the figure is not the cold first run.
    let mut best = f64::INFINITY;
    let mut mesh = Mesh::default();
    for _ in 0..3 {
        let t = Instant::now();
        mesh = f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (mesh, best)
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(256);
    let (dims, origin, h) = ([n; 3], Vec3::splat(-1.0), 2.0 / (n - 1) as f32);
    println!(
        "grid {n}³, {} threads, best of 3\n",
        rayon::current_num_threads()
    );
    println!("| field | method | time (ms) | vertices | triangles | min angle < 20° |");
    println!("|---|---|---|---|---|---|");
    let fields: [(&str, &AnalyticField); 2] =
        [("sphere", &sphere), ("noisy sphere (3 octaves)", &bumpy)];
    for (name, f) in fields {
        let field: &dyn Field = &f;
        let values = sample(n, field);
        let refine = |a: Vec3, va: f32, b: Vec3, vb: f32| {
            // The same regula falsi dual contouring uses, through the public callback.
            let (mut t0, mut f0, mut t1, mut f1) = (0.0f32, va, 1.0f32, vb);
            let mut t = t0 - f0 * (t1 - t0) / (f1 - f0);
            for _ in 0..8 {
                let v = field.value(a + (b - a) * t);
                if v == 0.0 || !v.is_finite() {
                    break;
                }
                if (v < 0.0) == (f0 < 0.0) {
                    (t0, f0) = (t, v);
                    f1 *= 0.5;
                } else {
                    (t1, f1) = (t, v);
                    f0 *= 0.5;
                }
                t = t0 - f0 * (t1 - t0) / (f1 - f0);
            }
            a + (b - a) * t
        };
        let methods: [(&str, &dyn Fn() -> Mesh); 4] = [
            ("marching cubes (linear)", &|| {
                marching_cubes(&values, dims, origin, h, 0.0)
            }),
            ("marching cubes (root finding)", &|| {
                marching_cubes_with(&values, dims, origin, h, 0.0, &refine)
            }),
            ("dual contouring", &|| {
                dual_contour(
                    &values,
                    dims,
                    origin,
                    h,
                    0.0,
                    field,
                    &DualContourOptions::default(),
                )
            }),
            ("surface nets", &|| {
                surface_nets(&values, dims, origin, h, 0.0, field)
            }),
        ];
        for (method, run) in methods {
            let (mesh, secs) = time(run);
            let hist = min_angle_histogram(&mesh);
            let slivers = (hist[0] + hist[1]) as f64 / mesh.triangles.len().max(1) as f64;
            println!(
                "| {name} | {method} | {:.0} | {} | {} | {:.1}% |",
                secs * 1e3,
                mesh.positions.len(),
                mesh.triangles.len(),
                100.0 * slivers
            );
        }
    }
}
