//! Times slicing a mesh's field: `slice_bench MESH [RES] [LAYERS]` (defaults 256 and 500).
//! The field is built as `pgvol encode` builds it: banded signed distance, cubic B-spline
//! interpolation. Layers are cut along z over the mesh's bounding box, the 2D grid spacing being
//! the field's.
//!
//! `cargo run --release -p pgvol-studies --bin slice_bench -- MESH [RES] [LAYERS]`

use std::path::PathBuf;
use std::time::Instant;

use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_ops::{slice_volume, Axis, SliceOptions};
use pgvol_sdf::{sampling::Extent, MeshSdf, SignMode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .ok_or("usage: slice_bench MESH [RES] [LAYERS]")?,
    );
    let res: usize = args.next().map_or(Ok(256), |s| s.parse())?;
    let layers: usize = args.next().map_or(Ok(500), |s| s.parse())?;

    let t = Instant::now();
    let (mesh, _) = pgvol_mesh::read_clean(&path)?;
    let (lo, hi) = mesh.bounds().ok_or("empty mesh")?;
    let grid = Grid::cube_res(lo, hi, res)?;
    let sdf = MeshSdf::new(&mesh, SignMode::Auto)?;
    let samples = sdf.sample(&grid, Extent::Band(4.0), &|_| {}).values;
    let volume = CoefficientVolume::interpolate(grid, Basis::Bspline3, samples)?;
    let encode = t.elapsed();

    let height = hi.z - lo.z;
    let options = SliceOptions::new(Axis::Z, height / layers as f32, grid.spacing);
    let t = Instant::now();
    let out = slice_volume(&volume, (lo, hi), &options)?;
    let slicing = t.elapsed();

    let loops: usize = out.iter().map(|l| l.loops.len()).sum();
    let points: usize = out
        .iter()
        .flat_map(|l| &l.loops)
        .map(|l| l.points.len())
        .sum();
    println!(
        "{}: {} triangles, field {}^3 (spacing {:.5}) in {:.2} s",
        path.display(),
        mesh.triangles.len(),
        res,
        grid.spacing,
        encode.as_secs_f64()
    );
    println!(
        "sliced {} layers of {:.5} ({} loops, {} points, tolerance {:.5}) in {:.3} s on {} threads: {:.2} ms per layer",
        out.len(),
        options.layer_height,
        loops,
        points,
        options.tolerance,
        slicing.as_secs_f64(),
        rayon::current_num_threads(),
        1e3 * slicing.as_secs_f64() / out.len().max(1) as f64
    );
    Ok(())
}
