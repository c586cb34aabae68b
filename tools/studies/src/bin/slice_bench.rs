//! Times slicing a mesh's field: `slice_bench MESH [RES] [LAYERS]` (defaults 256 and 500).
//! The field is encoded as `pgvol encode --res RES` encodes it and sliced as `pgvol slice` slices
//! its file: layers along z over the mesh's bounding box, the 2D grid spacing being the field's.
//!
//! `cargo run --release -p pgvol-studies --bin slice_bench -- MESH [RES] [LAYERS]`

use std::path::PathBuf;
use std::time::Instant;

use pgvol::{EncodeOptions, Field, GridSpec, Silent, SliceOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .ok_or("usage: slice_bench MESH [RES] [LAYERS]")?,
    );
    let res: usize = args.next().map_or(Ok(256), |s| s.parse())?;
    let layers: usize = args.next().map_or(Ok(500), |s| s.parse())?;

    let t = Instant::now();
    let mesh = pgvol::io::read_mesh(&path)?.mesh;
    let options = EncodeOptions {
        grid: GridSpec::Res(res),
        ..EncodeOptions::default()
    };
    let encoded = pgvol::encode(&mesh, &options, &Silent)?;
    let encode = t.elapsed();

    let shape = Field::from_file(encoded.file);
    let (lo, hi) = shape.bounds();
    let spacing = shape.volume().grid.spacing;
    let mut settings = SliceOptions::new((hi.z - lo.z) / layers as f32);
    let tolerance = spacing / 10.0;
    settings.tolerance = Some(tolerance);
    let t = Instant::now();
    let out = shape.slice(&settings, &Silent).map(|s| s.layers)?;
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
        spacing,
        encode.as_secs_f64()
    );
    println!(
        "sliced {} layers of {:.5} ({} loops, {} points, tolerance {:.5}) in {:.3} s on {} threads: {:.2} ms per layer",
        out.len(),
        settings.layer_height,
        loops,
        points,
        tolerance,
        slicing.as_secs_f64(),
        rayon::current_num_threads(),
        1e3 * slicing.as_secs_f64() / out.len().max(1) as f64
    );
    Ok(())
}
