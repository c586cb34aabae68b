//! The stages wired together: mesh → signed distance → coefficient volume → mesh.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_mesh::Mesh;
use pgvol_sdf::sampling::{Extent, Sampled};
use pgvol_sdf::{MeshSdf, SignMode};
use serde::Serialize;

use crate::progress;

/// How the user asked for the grid.
#[derive(Clone, Copy, Debug)]
pub enum GridSpec {
    Res(usize),
    Voxel(f32),
}

impl GridSpec {
    pub fn from_args(res: Option<usize>, voxel: Option<f32>, default_res: usize) -> GridSpec {
        match (res, voxel) {
            (_, Some(h)) => GridSpec::Voxel(h),
            (Some(n), None) => GridSpec::Res(n),
            (None, None) => GridSpec::Res(default_res),
        }
    }

    /// The grid around `mesh` by the project convention.
    pub fn grid_for(self, mesh: &Mesh) -> Result<Grid> {
        let (lo, hi) = mesh.bounds().context("the mesh has no triangles")?;
        let grid = match self {
            GridSpec::Res(n) => Grid::cube_res(lo, hi, n),
            GridSpec::Voxel(h) => Grid::cube_voxel(lo, hi, h),
        };
        grid.context("cannot make the sampling grid")
    }
}

/// Seconds spent per stage.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    pub read: f64,
    pub sdf: f64,
    pub fit: f64,
    pub contour: f64,
    pub write: f64,
}

/// Reads a mesh, merges bit-identical vertices and drops degenerate triangles, saying so on
/// standard error unless `quiet`.
pub fn load_mesh(path: &Path, quiet: bool) -> Result<Mesh> {
    let (mesh, report) = pgvol_mesh::read_clean(path)?;
    if !quiet && (report.vertices_merged > 0 || report.degenerate_dropped > 0) {
        eprintln!(
            "{}: merged {} duplicate vertices, dropped {} degenerate triangles",
            path.display(),
            report.vertices_merged,
            report.degenerate_dropped
        );
    }
    Ok(mesh)
}

/// Signed distance of `mesh` on `grid`, and the sign mode that was used.
pub fn signed_distance_grid(
    mesh: &Mesh,
    grid: &Grid,
    extent: Extent,
    sign: SignMode,
    quiet: bool,
) -> Result<(Sampled, SignMode)> {
    let sdf = MeshSdf::new(mesh, sign).context("cannot build the distance field")?;
    let pb = progress::bar(1000, "distance", quiet);
    let sampled = sdf.sample(grid, extent, &|done| {
        pb.set_position((done * 1000.0) as u64)
    });
    pb.finish_and_clear();
    Ok((sampled, sdf.sign_mode()))
}

/// Exact distances within this many grid spacings of the surface when encoding: the cubic
/// B-spline near the surface depends on samples up to 2 nodes away directly and on farther ones
/// through the prefilter, whose influence falls by 0.268 per node.
pub const ENCODE_BAND: f32 = 4.0;

/// The coefficient volume of `mesh` on `grid`, and the seconds spent on distances and the fit.
pub fn encode(
    mesh: &Mesh,
    grid: Grid,
    basis: Basis,
    quiet: bool,
) -> Result<(CoefficientVolume, f64, f64)> {
    let t = Instant::now();
    let (sampled, _) = signed_distance_grid(
        mesh,
        &grid,
        Extent::Band(ENCODE_BAND),
        SignMode::Auto,
        quiet,
    )?;
    let samples = sampled.values;
    let sdf_time = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let volume = CoefficientVolume::interpolate(grid, basis, samples)
        .context("cannot fit the coefficients")?;
    Ok((volume, sdf_time, t.elapsed().as_secs_f64()))
}

/// Contours the `iso` level set of `volume` with marching cubes on its own grid, vertices placed
/// on the continuous field. The grid is padded with one layer of outside values so the surface
/// is closed even where it reaches the border.
pub fn decode(volume: &CoefficientVolume, iso: f32) -> Mesh {
    let g = volume.grid;
    let inner = volume.sample(&g);
    let [nx, ny, nz] = g.dims;
    let dims = [nx + 2, ny + 2, nz + 2];
    let outside = iso + g.spacing;
    let mut values = vec![outside; dims[0] * dims[1] * dims[2]];
    for k in 0..nz {
        for j in 0..ny {
            let src = nx * (j + ny * k);
            let dst = 1 + dims[0] * ((j + 1) + dims[1] * (k + 1));
            values[dst..dst + nx].copy_from_slice(&inner[src..src + nx]);
        }
    }
    let origin = g.origin - Vec3::splat(g.spacing);
    let refine = |a: Vec3, va: f32, b: Vec3, vb: f32| -> Vec3 {
        let lo = g.origin;
        let hi = g.max_corner();
        let inside_box = |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
        if inside_box(a) && inside_box(b) {
            volume.root_on_segment(a, va, b, vb, iso)
        } else {
            // An edge into the padding: the padding value is artificial, interpolate linearly.
            let t = ((iso - va) / (vb - va)).clamp(0.0, 1.0);
            a + (b - a) * t
        }
    };
    pgvol_contour::marching_cubes_with(&values, dims, origin, g.spacing, iso, &refine)
}
