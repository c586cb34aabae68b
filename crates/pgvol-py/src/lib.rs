//! The `pgvol._pgvol` extension module: the pgvol library facade for Python, with NumPy arrays
//! in and out. Every call goes through the `pgvol` crate; this crate only converts arguments,
//! results and errors, releases the GIL around the work and forwards progress.
//!
//! The Python package `pgvol` (in `python/`) re-exports this module with its exception classes
//! and type stubs.

// Python signatures take their options as keyword arguments, one Rust parameter each.
#![allow(clippy::too_many_arguments)]

mod arrays;
mod edit;
mod errors;
mod field;
mod names;
mod parts;
mod perturb;
mod progress;
mod reports;
mod view;

use std::path::PathBuf;

use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::progress::{quiet, run};

/// Reads a mesh file (OBJ, glTF/GLB, STL, PLY or 3MF by extension; a 3MF build in millimetres),
/// with bit-identical vertices welded and degenerate or repeated triangles dropped: (vertices
/// (N, 3), faces (M, 3) int32).
/// Vertices are float32, or float64 for a mesh far from the origin (more than 64 times its
/// size away), whose positions single precision would round.
#[pyfunction]
fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyTuple>> {
    let mesh = quiet(py, || pgvol::io::read_mesh(&path))?.mesh;
    arrays::mesh_tuple(py, mesh, false)
}

/// Writes a mesh file (GLB, glTF, OBJ, STL or PLY by extension), atomically. The vertex normals
/// stored are `normals` (one per vertex, made unit length) where given, else weighted from the
/// faces.
#[pyfunction]
#[pyo3(signature = (path, vertices, faces, normals=None))]
fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let mut mesh = pgvol::Mesh::from_world(
        &arrays::world_points(vertices, "vertices")?,
        arrays::faces(faces)?,
    );
    if let Some(normals) = normals {
        mesh.normals = arrays::vertex_normals(normals, mesh.positions.len())?;
    }
    quiet(py, || pgvol::io::write_mesh(&path, &mesh))
}

/// Surface distances and statistics of mesh `a` against reference mesh `b`, from `samples`
/// area-uniform samples on each, reproducible from `seed`. Each mesh is a (vertices, faces)
/// pair or an object with `vertices` and `faces` (a `trimesh.Trimesh`).
#[pyfunction]
#[pyo3(signature = (a, b, *, samples=200_000, seed=0))]
fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    samples: usize,
    seed: u64,
) -> PyResult<reports::Comparison> {
    let (va, fa) = arrays::mesh_parts(a, "a")?;
    let (vb, fb) = arrays::mesh_parts(b, "b")?;
    let comparison = quiet(py, || {
        let a = pgvol::io::mesh_from_world(&va, fa)?.mesh;
        let b = pgvol::io::mesh_from_world(&vb, fb)?.mesh;
        pgvol::compare(&a, &b, samples, seed)
    })?;
    Ok(comparison.into())
}

// Python signatures show literal defaults only; this is the library's.
const _: () = assert!(pgvol::limits::COMPARE_SAMPLES == 200_000);

/// The signed distance of a mesh sampled on a grid: a cube of side 1.1 x the mesh's longest
/// extent with `res` nodes per axis (default 128) or spacing `voxel`. Exact distances
/// everywhere, or with `band` only within that many grid spacings of the surface (the sign and
/// a clamped magnitude elsewhere). Returns (values, grid): a float32 array of shape
/// (nx, ny, nz) indexed `[i, j, k]`, negative inside, and the Grid of the nodes.
#[pyfunction]
#[pyo3(signature = (vertices, faces, *, res=None, voxel=None, band=None, sign="auto", progress=None))]
fn signed_distance<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    res: Option<usize>,
    voxel: Option<f32>,
    band: Option<f32>,
    sign: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Bound<'py, PyArray3<f32>>, field::Grid)> {
    let positions = arrays::world_points(vertices, "vertices")?;
    let triangles = arrays::faces(faces)?;
    let options = pgvol::SdfOptions {
        grid: field::grid_spec(py, res, voxel)?,
        band,
        sign: names::sign(py, sign)?,
    };
    let sampled = run(py, progress, |p| {
        let mesh = pgvol::io::mesh_from_world(&positions, triangles)?.mesh;
        // The grid is returned in the mesh's local coordinates, exact only near the origin.
        pgvol::checks::require_near(mesh.offset, "signed_distance")?;
        pgvol::distances::signed_distance(&mesh, &options, p)
    })?;
    let grid = sampled.grid;
    Ok((
        arrays::grid_values(py, sampled.values, grid.dims),
        field::Grid { grid },
    ))
}

/// A clean, watertight remesh (`pgvol remesh`): the mesh's field contoured on a cube grid of
/// `res` nodes per axis (or spacing `voxel`) by `method` ("mc", "sn" or "dc"). `field` "exact"
/// places the vertices on the mesh's exact signed distance (sharp edges stay sharp with "dc");
/// a basis name ("bspline3", ...) on the coefficient volume an encode would give. Pieces
/// enclosing less than `min_component` go (default: specks under 2 grid cells). Returns
/// (vertices, faces).
#[pyfunction]
#[pyo3(signature = (vertices, faces, *, res=None, voxel=None, method="mc", field="exact", min_component=None, sign="auto", progress=None))]
#[allow(clippy::too_many_arguments)]
fn remesh<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    res: Option<usize>,
    voxel: Option<f32>,
    method: &str,
    field: &str,
    min_component: Option<f32>,
    sign: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let positions = arrays::world_points(vertices, "vertices")?;
    let triangles = arrays::faces(faces)?;
    let options = pgvol::RemeshOptions {
        grid: field::grid_spec(py, res, voxel)?,
        method: names::method(py, method)?,
        field: match field {
            "exact" => pgvol::RemeshField::Exact,
            basis => pgvol::RemeshField::Decoded(names::basis(py, basis)?),
        },
        min_component,
        sign: names::sign(py, sign)?,
    };
    let remeshed = run(py, progress, |p| {
        let mesh = pgvol::io::mesh_from_world(&positions, triangles)?.mesh;
        pgvol::remesh(&mesh, &options, p)
    })?;
    arrays::mesh_tuple(py, remeshed.mesh, false)
}

/// The layers of the `.pgv` file at `path`, as `Field.load(path).slice(...)` gives them, read
/// slab by slab as `pgvol slice` reads it: memory is a window of the volume rather than all of
/// it, and no decoding of the whole file comes first.
#[pyfunction]
#[pyo3(signature = (path, layer_height, *, axis="z", first=None, resolution=None, tolerance=None, progress=None))]
fn slice_file(
    py: Python<'_>,
    path: PathBuf,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Vec<field::Layer>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let sliced = run(py, progress, |p| {
        let sliced = pgvol::stream::slice_file(&path, &settings, p)?;
        // Layers are returned in the field's local coordinates, as `Field.slice` returns them:
        // exact only near the origin.
        if !sliced.frame.is_zero() {
            let [a, u, v] = settings.axis.indices();
            let mut offset = glam::DVec3::ZERO;
            (offset[a], offset[u], offset[v]) =
                (sliced.frame.height, sliced.frame.u, sliced.frame.v);
            pgvol::checks::require_near(offset, "slicing into arrays")?;
        }
        Ok(sliced)
    })?;
    Ok(sliced
        .layers
        .into_iter()
        .map(|l| field::Layer::from_layer(py, l))
        .collect())
}

/// Sets the largest estimated peak memory, in bytes, a call may start with; None returns to
/// the default, the memory the machine has available when the call starts.
#[pyfunction]
#[pyo3(signature = (limit))]
fn set_memory_limit(limit: Option<u64>) {
    pgvol::limits::set_memory_limit(limit);
}

/// The memory limit in force, in bytes (None where the platform does not tell).
#[pyfunction]
fn memory_limit() -> Option<u64> {
    pgvol::limits::memory_limit()
}

#[pymodule]
fn _pgvol(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<field::Field>()?;
    m.add_class::<field::Grid>()?;
    m.add_class::<field::Layer>()?;
    m.add_class::<edit::MaskReport>()?;
    m.add_class::<reports::Comparison>()?;
    m.add_class::<reports::MeshStats>()?;
    m.add_class::<reports::VertexDeviation>()?;
    m.add_class::<reports::DepthDifference>()?;
    m.add_class::<reports::ViewDifference>()?;
    m.add_class::<reports::PerturbReport>()?;
    m.add_class::<reports::PerturbLoop>()?;
    m.add_class::<reports::Refusals>()?;
    m.add_class::<reports::Cleanup>()?;
    m.add_class::<reports::Strays>()?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(signed_distance, m)?)?;
    m.add_function(wrap_pyfunction!(remesh, m)?)?;
    m.add_function(wrap_pyfunction!(slice_file, m)?)?;
    m.add_function(wrap_pyfunction!(perturb::perturb, m)?)?;
    m.add_function(wrap_pyfunction!(set_memory_limit, m)?)?;
    m.add_function(wrap_pyfunction!(memory_limit, m)?)?;
    parts::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("DEFAULT_RES", pgvol::limits::DEFAULT_RES)?;
    m.add("MIN_RES", pgvol::limits::MIN_RES)?;
    m.add("MAX_RES", pgvol::limits::MAX_RES)?;
    m.add("ENCODE_BAND", pgvol::limits::ENCODE_BAND)?;
    m.add("COMPARE_SAMPLES", pgvol::limits::COMPARE_SAMPLES)?;
    Ok(())
}
