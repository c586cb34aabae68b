//! Times the contouring of a grid of samples read from a `.npy` file (float32, C order, shape
//! `(nz, ny, nx)`, as `pgvol sdf --format npy` writes), for comparison with other contourers
//! working on the same array:
//!
//! * marching cubes on the samples, vertices by linear interpolation ("grid only");
//! * marching cubes on the samples of the cubic B-spline interpolating them, vertices by root
//!   finding on that continuous field (as `pgvol decode` does);
//! * dual contouring and surface nets on the same field.
//!
//! `cargo run --release -p pgvol-studies --bin contour_grid -- GRID.npy [--reps R] [--json]`
//! prints the best of R runs (default 5) of each, as a markdown table or one JSON object;
//! `--only NAME` runs just one of them (names as printed).

mod npy;

use std::time::Instant;

use glam::Vec3;
use pgvol::Mesh;
use pgvol_contour::{contour_sampled, marching_cubes, marching_cubes_on_field, Method};
use pgvol_field::{Basis, CoefficientVolume, Grid};

/// Best time in seconds of `reps` runs, and the last result.
fn best_of(reps: usize, f: impl Fn() -> Mesh) -> (Mesh, f64) {
    let mut best = f64::INFINITY;
    let mut mesh = Mesh::default();
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        mesh = f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (mesh, best)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: contour_grid GRID.npy [--reps R] [--json] [--only NAME]");
        std::process::exit(2);
    };
    let reps = args
        .iter()
        .position(|a| a == "--reps")
        .and_then(|i| args.get(i + 1))
        .and_then(|r| r.parse().ok())
        .unwrap_or(5);
    let json = args.iter().any(|a| a == "--json");
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1));
    let (values, shape) = npy::read(path).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1);
    });
    let dims = [shape[2], shape[1], shape[0]];
    // Timing does not depend on where the grid is; unit spacing keeps the numbers readable.
    let grid = Grid {
        origin: Vec3::ZERO,
        spacing: 1.0,
        dims,
        offset: Default::default(),
    };
    let (origin, h) = (grid.origin, grid.spacing);
    // The continuous field is built only when a run needs it, so `--only mc_grid` profiles
    // marching cubes alone.
    let field = std::sync::OnceLock::new();
    let field = || {
        field.get_or_init(|| {
            let volume = CoefficientVolume::interpolate(grid, Basis::Bspline3, values.clone())
                .unwrap_or_else(|e| {
                    eprintln!("{path}: {e}");
                    std::process::exit(1);
                });
            let decoded = volume.sample(&grid);
            (volume, decoded)
        })
    };
    let runs: [(&str, &dyn Fn() -> Mesh); 5] = [
        ("mc_grid", &|| marching_cubes(&values, dims, origin, h, 0.0)),
        ("mc_root_finding", &|| {
            let (volume, decoded) = field();
            contour_sampled(volume, &grid, decoded, 0.0, Method::MarchingCubes)
        }),
        ("mc_two_evaluations", &|| {
            let (volume, decoded) = field();
            marching_cubes_on_field(decoded, dims, origin, h, 0.0, volume)
        }),
        ("dc", &|| {
            let (volume, decoded) = field();
            contour_sampled(volume, &grid, decoded, 0.0, Method::DualContouring)
        }),
        ("sn", &|| {
            let (volume, decoded) = field();
            contour_sampled(volume, &grid, decoded, 0.0, Method::SurfaceNets)
        }),
    ];
    let mut rows = Vec::new();
    for (name, run) in runs {
        if only.is_some_and(|o| o != name) {
            continue;
        }
        let (mesh, secs) = best_of(reps, run);
        let stats = mesh.stats();
        rows.push((name, secs, mesh.triangles.len(), stats.watertight));
    }
    let threads = rayon::current_num_threads();
    if json {
        let fields: Vec<String> = rows
            .iter()
            .map(|(name, secs, tris, closed)| {
                format!(
                    "\"{name}\": {{\"seconds\": {secs:.6}, \"triangles\": {tris}, \
                     \"watertight\": {closed}}}"
                )
            })
            .collect();
        println!(
            "{{\"dims\": {dims:?}, \"threads\": {threads}, \"reps\": {reps}, {}}}",
            fields.join(", ")
        );
    } else {
        println!("grid {dims:?}, {threads} threads, best of {reps}\n");
        println!("| run | ms | triangles | watertight |\n|---|---|---|---|");
        for (name, secs, tris, closed) in rows {
            println!("| {name} | {:.1} | {tris} | {closed} |", secs * 1e3);
        }
    }
}
