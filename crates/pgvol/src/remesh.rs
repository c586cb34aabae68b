//! Mesh → signed distance → mesh in one go: a clean, watertight remesh.

use std::time::Instant;

use pgvol_contour::Method;
use pgvol_core::{Grid, Mesh};
use pgvol_field::{Basis, FitMethod};
use pgvol_sdf::SignMode;

use crate::decode::{decode, DecodeOptions};
use crate::encode::{fit_volume, EncodeOptions, ENCODE_BAND};
use crate::error::{Error, ErrorKind, Result};
use crate::exact_distance::ExactDistance;
use crate::grid::GridSpec;
use crate::progress::Progress;
use crate::timings::Timings;

/// Which field places the vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RemeshField {
    /// The exact signed distance of the input mesh: sharp edges stay sharp with dual
    /// contouring (the default).
    Exact,
    /// The coefficient volume of this basis, as encode then decode would give.
    Decoded(Basis),
}

/// How to remesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RemeshOptions {
    /// The grid (default 128 nodes per axis).
    pub grid: GridSpec,
    /// Contouring method (default marching cubes).
    pub method: Method,
    /// The field the vertices lie on (default exact).
    pub field: RemeshField,
    /// Pieces enclosing less than this volume are removed; see
    /// [`DecodeOptions::min_component`] (default: specks under 2 grid cells).
    pub min_component: Option<f32>,
    /// How inside is told from outside (default [`SignMode::Auto`]).
    pub sign: SignMode,
}

impl Default for RemeshOptions {
    fn default() -> Self {
        Self {
            grid: GridSpec::default(),
            method: Method::MarchingCubes,
            field: RemeshField::Exact,
            min_component: None,
            sign: SignMode::Auto,
        }
    }
}

/// A remeshed surface and how it was made.
#[derive(Clone, Debug)]
pub struct Remeshed {
    /// The new surface: watertight and manifold.
    pub mesh: Mesh,
    /// The contouring grid.
    pub grid: Grid,
    /// Seconds per stage (`read` and `write` are the caller's).
    pub timings: Timings,
}

/// Remeshes `mesh` by `options`.
pub fn remesh(mesh: &Mesh, options: &RemeshOptions, progress: &dyn Progress) -> Result<Remeshed> {
    let grid = options.grid.grid_for(mesh)?;
    let mut timings = Timings::default();
    let out = match options.field {
        RemeshField::Exact => {
            crate::memory::check_grid("remeshing", &grid, crate::memory::BYTES_PER_NODE)?;
            let (method, sign) = (options.method, options.sign);
            let mut out = contour_exact(mesh, &grid, method, sign, &mut timings, progress)?;
            crate::decode::remove_specks(&mut out, options.min_component, grid.spacing, progress);
            out
        }
        RemeshField::Decoded(basis) => {
            let encode = EncodeOptions {
                grid: options.grid,
                basis,
                fit: FitMethod::Interp,
                band: ENCODE_BAND,
                sign: options.sign,
                sharp: crate::sharp::store::SharpOptions::default(),
            };
            encode.validate()?;
            crate::memory::check_sparse_encode("remeshing", mesh, &grid, ENCODE_BAND)?;
            let volume = fit_volume(mesh, grid, &encode, &mut timings, progress)?.volume;
            let start = Instant::now();
            let decode_options = DecodeOptions {
                method: options.method,
                min_component: options.min_component,
                ..DecodeOptions::default()
            };
            let out = decode(&volume, &decode_options, progress);
            timings.contour = start.elapsed().as_secs_f64();
            // An empty level set means the surface vanished; a cancellation stays one.
            out.map_err(|e| match e.kind() {
                ErrorKind::Cancelled => e,
                _ => vanished(),
            })?
        }
    };
    if out.triangles.is_empty() {
        return Err(vanished());
    }
    Ok(Remeshed {
        mesh: out,
        grid,
        timings,
    })
}

fn vanished() -> Error {
    Error::new(
        ErrorKind::BadParameter,
        "the surface vanished at this resolution (no inside region found); try a larger resolution",
    )
}

/// The surface of `mesh` contoured on `grid`, node signs from the banded sampler and every
/// vertex placed with the exact distance. Dual contouring keeps each crossing's own tangent
/// plane: exact normals need no offset away from a feature.
pub(crate) fn contour_exact(
    mesh: &Mesh,
    grid: &Grid,
    method: Method,
    sign: SignMode,
    timings: &mut Timings,
    progress: &dyn Progress,
) -> Result<Mesh> {
    let start = Instant::now();
    let exact = ExactDistance::new(mesh, sign)?;
    exact.contour(grid, method, timings, start, progress)
}
