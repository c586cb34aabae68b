//! NumPy arrays in and out. Points and vertices are (N, 3) float32 or float64, faces (M, 3)
//! int32, int64, uint32 or uint64, in C or Fortran order or any strides; anything array-like is
//! passed through `numpy.asarray` first. Arrays returned are handed to NumPy without a copy.

use glam::{DVec3, Vec3};
use numpy::ndarray::{Array1, Array2, Array3, ShapeBuilder};
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::errors;

/// `obj` as a NumPy array, converting lists and other array-likes.
fn ndarray<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let py = obj.py();
    let converted = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| errors::parameter(py, format!("cannot read an array from it: {e}")))?;
    converted
        .cast_into::<PyUntypedArray>()
        .map_err(|_| errors::parameter(py, "numpy.asarray did not give an array"))
}

/// The array `obj` as (N, 3), refusing any other shape; `name` labels errors.
fn n_by_3<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    let a = ndarray(obj)?;
    let shape = a.shape();
    if shape.len() != 2 || shape[1] != 3 {
        let shape: Vec<String> = shape.iter().map(usize::to_string).collect();
        return Err(errors::parameter(
            obj.py(),
            format!("{name} must have shape (N, 3), got ({})", shape.join(", ")),
        ));
    }
    Ok(a)
}

/// The rows of an (N, 3) array of `T`, mapped by `f`; `None` when the dtype is not `T`.
fn rows<T: Element + Copy, U>(
    a: &Bound<'_, PyUntypedArray>,
    mut f: impl FnMut([T; 3]) -> PyResult<U>,
) -> Option<PyResult<Vec<U>>> {
    let typed = a.cast::<PyArray2<T>>().ok()?;
    let read = match typed.try_readonly() {
        Ok(r) => r,
        Err(e) => {
            return Some(Err(errors::parameter(
                a.py(),
                format!("cannot read the array: {e}"),
            )))
        }
    };
    let view = read.as_array();
    let out = match view.as_slice() {
        Some(flat) => flat
            .chunks_exact(3)
            .map(|r| f([r[0], r[1], r[2]]))
            .collect(),
        None => view
            .rows()
            .into_iter()
            .map(|r| f([r[0], r[1], r[2]]))
            .collect(),
    };
    Some(out)
}

/// The dtype of `a` as NumPy names it.
fn dtype_name(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype().to_string()
}

/// World points (or vertices) from an (N, 3) float32 or float64 array-like, kept in f64 so
/// that positions far from the origin keep their precision; `name` labels errors.
pub(crate) fn world_points(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<DVec3>> {
    let a = n_by_3(obj, name)?;
    if let Some(p) = rows::<f32, _>(&a, |r| Ok(Vec3::from_array(r).as_dvec3())) {
        return p;
    }
    if let Some(p) = rows::<f64, _>(&a, |r| Ok(DVec3::from_array(r))) {
        return p;
    }
    Err(errors::parameter(
        obj.py(),
        format!("{name} must be float32 or float64, got {}", dtype_name(&a)),
    ))
}

/// One normal per vertex from an (N, 3) float32 or float64 array-like of `vertices` rows, every
/// value finite; a writer makes them unit length and gives zero ones a face's direction.
pub(crate) fn vertex_normals(obj: &Bound<'_, PyAny>, vertices: usize) -> PyResult<Vec<Vec3>> {
    let py = obj.py();
    let a = n_by_3(obj, "normals")?;
    let finite = |n: Vec3| {
        if n.is_finite() {
            Ok(n)
        } else {
            Err(errors::parameter(
                py,
                format!("normals must be finite, got {n}"),
            ))
        }
    };
    let normals = rows::<f32, _>(&a, |r| finite(Vec3::from_array(r)))
        .or_else(|| rows::<f64, _>(&a, |r| finite(DVec3::from_array(r).as_vec3())))
        .ok_or_else(|| {
            errors::parameter(
                py,
                format!("normals must be float32 or float64, got {}", dtype_name(&a)),
            )
        })??;
    if normals.len() != vertices {
        return Err(errors::parameter(
            py,
            format!(
                "normals has {} rows for {vertices} vertices; give one per vertex",
                normals.len()
            ),
        ));
    }
    Ok(normals)
}

/// The normals a file written from `mesh` stores, as an (N, 3) float32 array: the field's own
/// where the contour gave them, else weighted from the faces.
pub(crate) fn output_normals<'py>(
    py: Python<'py>,
    mesh: &pgvol::Mesh,
) -> Bound<'py, PyArray2<f32>> {
    vec3s(py, pgvol::io::output_normals(mesh).into_owned())
}

/// A mesh as `(vertices, faces)` ([`mesh_vertices`]: float32 near the origin; int32 faces), or
/// with `normals` `(vertices, faces, normals)` ([`output_normals`]).
pub(crate) fn mesh_tuple(
    py: Python<'_>,
    mut mesh: pgvol::Mesh,
    normals: bool,
) -> PyResult<Bound<'_, PyTuple>> {
    let n = mesh.positions.len();
    let normals = normals.then(|| output_normals(py, &mesh));
    let triangles = triangles(py, std::mem::take(&mut mesh.triangles), n)?;
    let vertices = mesh_vertices(py, mesh);
    match normals {
        Some(normals) => PyTuple::new(py, [vertices, triangles.into_any(), normals.into_any()]),
        None => PyTuple::new(py, [vertices, triangles.into_any()]),
    }
}

/// A mesh's vertices in world coordinates: (N, 3) float32 as held for a mesh near the origin,
/// float64 (the frame offset added) for a mesh far from it.
pub(crate) fn mesh_vertices<'py>(py: Python<'py>, mesh: pgvol::Mesh) -> Bound<'py, PyAny> {
    if mesh.offset == DVec3::ZERO {
        return vec3s(py, mesh.positions).into_any();
    }
    let n = mesh.positions.len();
    let flat: Vec<f64> = (0..n).flat_map(|i| mesh.world(i).to_array()).collect();
    Array2::from_shape_vec((n, 3), flat)
        .expect("three coordinates per vertex")
        .into_pyarray(py)
        .into_any()
}

/// One vertex index, refused when negative or beyond u32.
fn index<T: TryInto<u32> + Copy + std::fmt::Display>(py: Python<'_>, i: T) -> PyResult<u32> {
    i.try_into().map_err(|_| {
        errors::parameter(
            py,
            format!("faces: vertex index {i} is out of range (0 to 4294967295)"),
        )
    })
}

/// Triangles from an (M, 3) integer array-like (int32, int64, uint32 or uint64).
pub(crate) fn faces(obj: &Bound<'_, PyAny>) -> PyResult<Vec<[u32; 3]>> {
    let py = obj.py();
    let a = n_by_3(obj, "faces")?;
    macro_rules! try_dtype {
        ($t:ty) => {
            if let Some(f) = rows::<$t, _>(&a, |r| {
                Ok([index(py, r[0])?, index(py, r[1])?, index(py, r[2])?])
            }) {
                return f;
            }
        };
    }
    try_dtype!(i32);
    try_dtype!(i64);
    try_dtype!(u32);
    try_dtype!(u64);
    Err(errors::parameter(
        py,
        format!(
            "faces must be int32, int64, uint32 or uint64, got {}",
            dtype_name(&a)
        ),
    ))
}

/// A mesh from `(vertices, faces)` or any object with `vertices` and `faces` attributes (a
/// `trimesh.Trimesh`); `name` labels errors.
pub(crate) fn mesh_parts(
    obj: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(Vec<DVec3>, Vec<[u32; 3]>)> {
    let py = obj.py();
    let (v, f) = if obj.hasattr("vertices")? && obj.hasattr("faces")? {
        (obj.getattr("vertices")?, obj.getattr("faces")?)
    } else {
        obj.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>()
            .map_err(|_| {
                errors::parameter(
                    py,
                    format!("{name} must be a (vertices, faces) pair or have .vertices and .faces"),
                )
            })?
    };
    Ok((world_points(&v, "vertices")?, faces(&f)?))
}

/// Floats as a 1-D array.
pub(crate) fn vector(py: Python<'_>, values: Vec<f32>) -> Bound<'_, PyArray1<f32>> {
    Array1::from_vec(values).into_pyarray(py)
}

/// Vectors as an (N, 3) float32 array.
pub(crate) fn vec3s(py: Python<'_>, values: Vec<Vec3>) -> Bound<'_, PyArray2<f32>> {
    let n = values.len();
    let flat: Vec<f32> = match bytemuck::allocation::try_cast_vec::<Vec3, [f32; 3]>(values) {
        Ok(arrays) => arrays.into_flattened(),
        Err((_, values)) => values.iter().flat_map(|v| v.to_array()).collect(),
    };
    Array2::from_shape_vec((n, 3), flat)
        .expect("three floats per vector")
        .into_pyarray(py)
}

/// Triangles as an (M, 3) int32 array.
pub(crate) fn triangles(
    py: Python<'_>,
    triangles: Vec<[u32; 3]>,
    vertices: usize,
) -> PyResult<Bound<'_, PyArray2<i32>>> {
    if vertices > i32::MAX as usize {
        return Err(errors::parameter(
            py,
            format!("{vertices} vertices are more than int32 faces can index"),
        ));
    }
    let n = triangles.len();
    let flat: Vec<u32> = triangles.into_flattened();
    let flat: Vec<i32> = match bytemuck::allocation::try_cast_vec::<u32, i32>(flat) {
        Ok(v) => v,
        Err((_, v)) => v.iter().map(|&i| i as i32).collect(),
    };
    Ok(Array2::from_shape_vec((n, 3), flat)
        .expect("three indices per triangle")
        .into_pyarray(py))
}

/// Values at the nodes of a grid, x fastest, as an array of shape (nx, ny, nz) indexed
/// `[i, j, k]` (Fortran order: the same memory, no copy).
pub(crate) fn grid_values(
    py: Python<'_>,
    values: Vec<f32>,
    dims: [usize; 3],
) -> Bound<'_, PyArray3<f32>> {
    Array3::from_shape_vec((dims[0], dims[1], dims[2]).f(), values)
        .expect("one value per node")
        .into_pyarray(py)
}

/// 2-D points as an (N, 2) float32 array.
pub(crate) fn points2(py: Python<'_>, points: Vec<[f32; 2]>) -> Bound<'_, PyArray2<f32>> {
    let n = points.len();
    Array2::from_shape_vec((n, 2), points.into_flattened())
        .expect("two floats per point")
        .into_pyarray(py)
}
