//! Contours the cubic B-spline interpolating a grid of signed distances read from a `.npy` file
//! (as `pgvol sdf --format npy` writes) and writes the mesh, with the dual contouring settings
//! exposed, for studying how they change sharp features:
//!
//! `cargo run --release -p pgvol-studies --bin contour_npy -- GRID.npy OUT.obj
//!  --origin X,Y,Z --spacing H [--method mc|dc] [--threshold T] [--offset CELLS]`
//!
//! `--origin` and `--spacing` place node (0, 0, 0) and the node spacing in mesh units, so the
//! output can be compared with the input mesh (`pgvol compare`).

#[path = "contour_grid/npy.rs"]
mod npy;

use glam::Vec3;
use pgvol_contour::{dual_contour, marching_cubes_with, DualContourOptions};
use pgvol_field::{Basis, CoefficientVolume, Grid};

fn arg<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

fn fail(message: String) -> ! {
    eprintln!("{message}");
    std::process::exit(1)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(input), Some(output)) = (args.first(), args.get(1)) else {
        fail(format!(
            "usage: contour_npy GRID.npy OUT.obj --origin X,Y,Z --spacing H {}",
            "[--method mc|dc] [--threshold T] [--offset CELLS]"
        ));
    };
    let origin: Vec<f32> = arg(&args, "--origin")
        .unwrap_or("0,0,0")
        .split(',')
        .map(|s| {
            s.trim()
                .parse()
                .unwrap_or_else(|_| fail(format!("bad --origin {s}")))
        })
        .collect();
    if origin.len() != 3 {
        fail("--origin needs three numbers".into());
    }
    let spacing: f32 = arg(&args, "--spacing")
        .unwrap_or("1")
        .parse()
        .unwrap_or_else(|_| fail("bad --spacing".into()));
    let method = arg(&args, "--method").unwrap_or("dc");
    let mut options = DualContourOptions::default();
    if let Some(t) = arg(&args, "--threshold") {
        options.singular_threshold = t.parse().unwrap_or_else(|_| fail("bad --threshold".into()));
    }
    if let Some(t) = arg(&args, "--offset") {
        options.feature_offset = t.parse().unwrap_or_else(|_| fail("bad --offset".into()));
    }
    let (values, shape) = npy::read(input).unwrap_or_else(|e| fail(e));
    let grid = Grid {
        origin: Vec3::from_slice(&origin),
        spacing,
        dims: [shape[2], shape[1], shape[0]],
        offset: Default::default(),
    };
    let volume = CoefficientVolume::interpolate(grid, Basis::Bspline3, values)
        .unwrap_or_else(|e| fail(format!("{input}: {e}")));
    let samples = volume.sample(&grid);
    let mesh = match method {
        "mc" => {
            let root = |a, va, b, vb| volume.root_on_segment(a, va, b, vb, 0.0);
            marching_cubes_with(&samples, grid.dims, grid.origin, spacing, 0.0, &root)
        }
        "dc" => dual_contour(
            &samples,
            grid.dims,
            grid.origin,
            spacing,
            0.0,
            &volume,
            &options,
        ),
        other => fail(format!("unknown --method {other}")),
    };
    pgvol::io::write_mesh(std::path::Path::new(output), &mesh)
        .unwrap_or_else(|e| fail(e.to_string()));
}
