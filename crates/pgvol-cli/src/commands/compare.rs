//! `pgvol compare`.

use anyhow::Result;
use clap::Args;

use super::args::{load_mesh, MeshInputArgs, OutputArgs, PathArg};
use crate::output::outln;
use crate::report::{self, Seconds};

#[derive(Args)]
#[command(
    after_help = "Vertex deviation: distance from each vertex of A to B (mean, max) and the angle \
between A's vertex normal and B's interpolated normal there. Depth buffers: both meshes rasterised \
orthographically at 256 x 256 from the 6 axis directions and the 8 cube corners, framed on the \
sphere around both boxes; mean absolute depth difference over the pixels either covers (a pixel \
one misses counts at the far side of the sphere).\n\nExample: pgvol compare remeshed.glb original.obj --samples 500000"
)]
pub struct CompareArgs {
    /// The mesh to measure.
    pub a: PathArg,
    /// The reference mesh (its bounding-box diagonal is the unit of the % figures).
    pub b: PathArg,
    #[command(flatten)]
    pub read: MeshInputArgs,
    /// Area-uniform samples drawn on each mesh.
    #[arg(long, default_value_t = pgvol::limits::COMPARE_SAMPLES as u64, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub samples: u64,
    /// Seed of the sampler (the same seed gives the same figures).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn run(a: CompareArgs) -> Result<()> {
    let start = std::time::Instant::now();
    let quiet = a.out.silent();
    let ma = load_mesh(&a.a, a.read, quiet)?;
    let mb = load_mesh(&a.b, a.read, quiet)?;
    let c = pgvol::compare(&ma, &mb, a.samples as usize, a.seed)?;
    if a.out.json {
        return report::print(&c, &Seconds::since(start));
    }
    outln!("A: {}\nB: {}", a.a.display(), a.b.display());
    outln!("samples per mesh      {}", c.samples);
    outln!("B diagonal            {}", fig(c.diagonal));
    outln!(
        "Hausdorff             {} ({:.4} %)",
        fig(c.hausdorff),
        c.hausdorff_pct
    );
    outln!(
        "Chamfer-L1            {} ({:.4} %)",
        fig(c.chamfer_l1),
        c.chamfer_l1_pct
    );
    outln!(
        "mean A->B, B->A       {}, {}",
        fig(c.mean_a_to_b),
        fig(c.mean_b_to_a)
    );
    outln!(
        "normal deviation      mean {:.3} deg, p95 {:.3} deg",
        c.normal_deviation_mean_deg,
        c.normal_deviation_p95_deg
    );
    let v = &c.vertex_deviation;
    outln!(
        "vertex deviation      mean {} ({:.4} %), max {} ({:.4} %) over {} vertices of A",
        fig(v.mean),
        c.vertex_deviation_mean_pct,
        fig(v.max),
        c.vertex_deviation_max_pct,
        v.vertices
    );
    outln!(
        "vertex normals        mean {:.3} deg, max {:.3} deg",
        v.normal_mean_deg,
        v.normal_max_deg
    );
    outln!(
        "depth buffers         mean |difference| {} ({:.4} %) over {} views at {}^2",
        fig(c.depth_buffer.mean_abs),
        c.depth_buffer_pct,
        c.depth_buffer.views.len(),
        c.depth_buffer.resolution
    );
    outln!("");
    outln!("{:<22}{:>18}{:>18}", "", "A", "B");
    let rows: [(&str, String, String); 10] = [
        (
            "triangles",
            c.a.triangles.to_string(),
            c.b.triangles.to_string(),
        ),
        (
            "vertices",
            c.a.vertices.to_string(),
            c.b.vertices.to_string(),
        ),
        (
            "boundary edges",
            c.a.boundary_edges.to_string(),
            c.b.boundary_edges.to_string(),
        ),
        (
            "non-manifold edges",
            c.a.non_manifold_edges.to_string(),
            c.b.non_manifold_edges.to_string(),
        ),
        (
            "watertight",
            c.a.watertight.to_string(),
            c.b.watertight.to_string(),
        ),
        (
            "winding consistent",
            c.a.winding_consistent.to_string(),
            c.b.winding_consistent.to_string(),
        ),
        (
            "Euler characteristic",
            c.a.euler_characteristic.to_string(),
            c.b.euler_characteristic.to_string(),
        ),
        (
            "components",
            c.a.components.to_string(),
            c.b.components.to_string(),
        ),
        (
            "volume",
            volume(c.a.volume, c.a.watertight),
            volume(c.b.volume, c.b.watertight),
        ),
        ("area", fig(c.a.area), fig(c.b.area)),
    ];
    for (name, x, y) in rows {
        outln!("{name:<22}{x:>18}{y:>18}");
    }
    Ok(())
}

/// A length, area or volume for reading: six decimals, or four significant digits in
/// scientific notation where six decimals would show only zeros (a part in metres).
fn fig(x: impl Into<f64>) -> String {
    let x = x.into();
    if x != 0.0 && x.abs() < 1e-3 {
        format!("{x:.4e}")
    } else {
        format!("{x:.6}")
    }
}

/// The enclosed volume, marked for an open mesh, whose volume depends on where the origin is.
fn volume(v: impl Into<f64>, watertight: bool) -> String {
    if watertight {
        fig(v)
    } else {
        format!("{} (open)", fig(v))
    }
}
