//! The stages wired together: mesh → signed distance → coefficient volume → mesh.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;
use pgvol_field::{Basis, ClosestFn, CoefficientVolume, FitMethod, FitOptions, FitReport, Grid};
use pgvol_mesh::Mesh;
use pgvol_sdf::sampling::{Extent, Sampled};
use pgvol_sdf::{MeshSdf, SignMode};
use serde::Serialize;

use crate::commands::MethodArg;
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

/// The coefficient volume of `mesh` on `grid`, the fit's report and the seconds spent on
/// signed distances. `interp` interpolates band-limited node distances (fast); `wls` adds the
/// mesh's closest points to the same band samples; `iso` queries the mesh's distance at every
/// node. `band` is the band of exact distances in spacings.
pub fn encode_with(
    mesh: &Mesh,
    grid: Grid,
    basis: Basis,
    method: FitMethod,
    band: f32,
    quiet: bool,
) -> Result<(CoefficientVolume, FitReport, f64)> {
    let options = FitOptions::default();
    match method {
        FitMethod::Interp => return encode_banded(mesh, grid, basis, band, quiet),
        FitMethod::Wls => return encode_banded_wls(mesh, grid, basis, band, &options, quiet),
        FitMethod::Iso { .. } => {}
    }
    let t = Instant::now();
    let sdf = MeshSdf::new(mesh, SignMode::Auto).context("cannot build the distance field")?;
    let sdf_time = t.elapsed().as_secs_f64();
    if !quiet {
        eprintln!(
            "fitting {} coefficients ({} fit, {} basis)...",
            grid.len(),
            method.name(),
            basis
        );
    }
    let (volume, report) = pgvol_field::fit(grid, basis, method, &sdf, &options)
        .context("cannot fit the coefficients")?;
    Ok((volume, report, sdf_time))
}

/// The `interp` fit on distances exact within `band` grid spacings of the surface.
pub fn encode_banded(
    mesh: &Mesh,
    grid: Grid,
    basis: Basis,
    band: f32,
    quiet: bool,
) -> Result<(CoefficientVolume, FitReport, f64)> {
    let t = Instant::now();
    let (sampled, _) =
        signed_distance_grid(mesh, &grid, Extent::Band(band), SignMode::Auto, quiet)?;
    let sdf_time = t.elapsed().as_secs_f64();
    let (volume, report) =
        pgvol_field::fit::interp_samples(grid, basis, &sampled.values, &FitOptions::default())
            .context("cannot fit the coefficients")?;
    Ok((volume, report, sdf_time))
}

/// The `wls` fit on distances exact within `band` grid spacings (at least the fit's own band,
/// whose nodes give its surface samples), with the mesh's closest points for those samples.
fn encode_banded_wls(
    mesh: &Mesh,
    grid: Grid,
    basis: Basis,
    band: f32,
    options: &FitOptions,
    quiet: bool,
) -> Result<(CoefficientVolume, FitReport, f64)> {
    let t = Instant::now();
    let sdf = MeshSdf::new(mesh, SignMode::Auto).context("cannot build the distance field")?;
    let pb = progress::bar(1000, "distance", quiet);
    let extent = Extent::Band(band.max(options.band));
    let sampled = sdf.sample(&grid, extent, &|done| {
        pb.set_position((done * 1000.0) as u64)
    });
    pb.finish_and_clear();
    let sdf_time = t.elapsed().as_secs_f64();
    // Closest points need no sign, so they skip the winding number.
    let surface =
        ClosestFn(|p: Vec3, reach: f32| sdf.bvh().closest(p, reach * reach).map(|c| c.point));
    let (volume, report) = pgvol_field::wls_band(grid, basis, &sampled.values, &surface, options)
        .context("cannot fit the coefficients")?;
    Ok((volume, report, sdf_time))
}

/// [`encode_with`] with the `interp` fit, returning the seconds spent on distances and the fit.
pub fn encode(
    mesh: &Mesh,
    grid: Grid,
    basis: Basis,
    quiet: bool,
) -> Result<(CoefficientVolume, f64, f64)> {
    let (volume, report, sdf_time) =
        encode_with(mesh, grid, basis, FitMethod::Interp, ENCODE_BAND, quiet)?;
    Ok((volume, sdf_time, report.seconds))
}

/// Contours the `iso` level set of `volume` with `method`, on the volume's own grid or on a grid
/// of `res` nodes along its longest side spanning the same box.
pub fn decode(
    volume: &CoefficientVolume,
    iso: f32,
    method: MethodArg,
    res: Option<usize>,
) -> Result<Mesh> {
    let grid = match res {
        None => volume.grid,
        Some(n) => pgvol_contour::resampled_grid(volume, n)
            .with_context(|| format!("--res {n} gives a grid larger than the limit"))?,
    };
    let method = match method {
        MethodArg::Mc => pgvol_contour::Method::MarchingCubes,
        MethodArg::Sn => pgvol_contour::Method::SurfaceNets,
        MethodArg::Dc => pgvol_contour::Method::DualContouring,
    };
    Ok(pgvol_contour::contour_volume(volume, &grid, iso, method))
}
