//! Signed distance of a mesh: the grids of `pgvol sdf` and the distance the fits query.

use std::borrow::Cow;
use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use pgvol_core::{Grid, Mesh};
use pgvol_field::fit::SignedDistance;
use pgvol_sdf::sampling::Extent;
use pgvol_sdf::{MeshSdf, SignMode};
use serde::Serialize;

use crate::error::{Error, FileResult, Result};
use crate::grid::GridSpec;
use crate::progress::{self, Progress};

/// The mesh distance as the fits see it: value and the unit direction away from the closest
/// surface point, signed like the distance.
pub struct MeshDistance<'a>(pub &'a MeshSdf);

impl SignedDistance for MeshDistance<'_> {
    fn distance(&self, p: Vec3) -> f32 {
        self.0.signed_distance(p)
    }

    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let sdf = self.0;
        let (d, slot) = sdf.signed_distance_with_hint(p, None);
        let Some(slot) = slot else {
            return (d, Vec3::ZERO);
        };
        let c = sdf.bvh().closest_on_slot(p, slot);
        let v = p - c.point;
        let l = v.length();
        if l > 1e-6 * (1.0 + p.abs().max_element()) {
            return (d, v / l * d.signum());
        }
        // On the surface the direction is undefined: central differences at a tiny step.
        let e = 1e-4 * (1.0 + p.abs().max_element());
        let g = Vec3::new(
            sdf.signed_distance(p + Vec3::X * e) - sdf.signed_distance(p - Vec3::X * e),
            sdf.signed_distance(p + Vec3::Y * e) - sdf.signed_distance(p - Vec3::Y * e),
            sdf.signed_distance(p + Vec3::Z * e) - sdf.signed_distance(p - Vec3::Z * e),
        );
        (d, g.normalize_or_zero())
    }
}

/// Options of [`signed_distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfOptions {
    /// The grid (default 128 nodes per axis).
    pub grid: GridSpec,
    /// Exact distances only within this many grid spacings of the surface, the sign and the
    /// clamped magnitude elsewhere; `None` (the default) for exact distances everywhere.
    pub band: Option<f32>,
    /// How inside is told from outside (default: automatic).
    pub sign: SignMode,
}

impl Default for SdfOptions {
    fn default() -> Self {
        Self {
            grid: GridSpec::default(),
            band: None,
            sign: SignMode::Auto,
        }
    }
}

/// A sampled signed-distance grid and how it was made.
#[derive(Clone, Debug, Serialize)]
pub struct SdfGrid {
    /// The grid the values sit on.
    pub grid: Grid,
    /// One value per node, x fastest; negative inside.
    #[serde(skip)]
    pub values: Vec<f32>,
    /// The sign mode that was used (`auto` resolved).
    pub sign: &'static str,
    /// Nodes whose distance is exact.
    pub exact_nodes: usize,
    /// Seconds spent sampling.
    pub seconds: f64,
}

/// The prepared distance query of `mesh`, refusing meshes it cannot measure. With the
/// automatic sign the faces are first oriented consistently and outward
/// ([`Mesh::orient_outward`]), so reversed or partly reversed faces give the same inside.
pub fn mesh_sdf(mesh: &Mesh, sign: SignMode) -> Result<MeshSdf> {
    Ok(MeshSdf::new(&oriented(mesh, sign), sign)?)
}

/// `mesh` as the distance stages see it: oriented outward under the automatic sign, as given
/// under an explicit one.
pub(crate) fn oriented(mesh: &Mesh, sign: SignMode) -> Cow<'_, Mesh> {
    if sign != SignMode::Auto {
        return Cow::Borrowed(mesh);
    }
    let mut turned = mesh.clone();
    match turned.orient_outward() {
        0 => Cow::Borrowed(mesh),
        _ => Cow::Owned(turned),
    }
}

/// Samples `sdf` on `grid` as the stage "distance" of `progress`.
pub(crate) fn sample(
    sdf: &MeshSdf,
    grid: &Grid,
    extent: Extent,
    progress: &dyn Progress,
) -> Result<pgvol_sdf::sampling::Sampled> {
    progress::stage(progress, "distance", |update| {
        sdf.sample(grid, extent, update)
    })
}

/// Samples `sdf` within `width` spacings of the surface on `grid`, sparse, as the stage
/// "distance" of `progress`.
pub(crate) fn sample_sparse(
    sdf: &MeshSdf,
    grid: &Grid,
    width: f32,
    progress: &dyn Progress,
) -> Result<pgvol_sdf::sampling::SparseSampled> {
    progress::stage(progress, "distance", |update| {
        sdf.sample_sparse(grid, width, update)
    })
}

/// The signed distance of `mesh` on the grid of `options`.
pub fn signed_distance(
    mesh: &Mesh,
    options: &SdfOptions,
    progress: &dyn Progress,
) -> Result<SdfGrid> {
    if let Some(w) = options.band {
        if !(w.is_finite() && w > 0.0) {
            return Err(Error::parameter(format!(
                "the band must be a positive number of grid spacings, got {w}"
            )));
        }
    }
    let grid = options.grid.grid_for(mesh)?;
    crate::memory::check_grid("sampling", &grid, crate::memory::BYTES_PER_SDF_NODE)?;
    let start = Instant::now();
    let sdf = mesh_sdf(mesh, options.sign)?;
    let extent = options.band.map_or(Extent::Dense, Extent::Band);
    let sampled = sample(&sdf, &grid, extent, progress)?;
    Ok(SdfGrid {
        grid,
        values: sampled.values,
        sign: sdf.sign_mode().name(),
        exact_nodes: sampled.exact_nodes,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// File formats of a sampled grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridFormat {
    /// NRRD, raw float32 with the grid's origin and spacing in the header.
    Nrrd,
    /// NumPy `.npy`, float32 of shape (nz, ny, nx).
    Npy,
}

impl GridFormat {
    /// The format named by `path`'s extension (`.nrrd` or `.npy`).
    pub fn from_path(path: impl AsRef<Path>) -> Result<GridFormat> {
        let path = path.as_ref();
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
        {
            Some(e) if e == "npy" => Ok(GridFormat::Npy),
            Some(e) if e == "nrrd" => Ok(GridFormat::Nrrd),
            _ => Err(Error::new(
                crate::error::ErrorKind::OutputFile,
                "unknown grid file extension (expected .nrrd or .npy)",
            )
            .at(path)),
        }
    }
}

/// Writes a sampled grid to `path` atomically.
pub fn write_grid(
    path: impl AsRef<Path>,
    grid: &Grid,
    values: &[f32],
    format: GridFormat,
) -> Result<()> {
    let path = path.as_ref();
    match format {
        GridFormat::Nrrd => pgvol_format::grid_files::write_nrrd(path, grid, values, &[]),
        GridFormat::Npy => pgvol_format::grid_files::write_npy(path, grid, values),
    }
    .writing()
}
