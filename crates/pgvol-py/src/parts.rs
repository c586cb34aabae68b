//! The library's jobs in parts (`pgvol::distributed`) for the Python module
//! `pgvol.distributed`, which runs them as Dask tasks or in the calling process. Bricks cross
//! as `bytes`, meshes as NumPy arrays, plans as lists of `(start, end)`.

use std::ops::Range;
use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

use pgvol::distributed as parts;

use crate::arrays;
use crate::errors;
use crate::field::{grid_spec, Field, Layer};
use crate::names;
use crate::progress::quiet;

/// The encode options of the keyword arguments every encode call takes.
fn encode_options(
    py: Python<'_>,
    res: Option<usize>,
    voxel: Option<f32>,
    band: f32,
    basis: &str,
    (sign, sharp, sharp_angle): (&str, &str, Option<f32>),
) -> PyResult<pgvol::EncodeOptions> {
    Ok(pgvol::EncodeOptions {
        grid: grid_spec(py, res, voxel)?,
        basis: names::basis(py, basis)?,
        fit: pgvol::FitMethod::Interp,
        band,
        sign: names::sign(py, sign)?,
        sharp: pgvol::sharp::SharpOptions {
            enabled: names::sharp(py, sharp)?,
            angle: sharp_angle.unwrap_or(pgvol::sharp::DEFAULT_SHARP_ANGLE),
        },
    })
}

/// A checked, cleaned mesh from arrays.
fn mesh(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
) -> PyResult<pgvol::Mesh> {
    let positions = arrays::world_points(vertices, "vertices")?;
    let triangles = arrays::faces(faces)?;
    quiet(py, || {
        Ok(pgvol::io::mesh_from_world(&positions, triangles)?.mesh)
    })
}

/// A part of an encode: groups `y0..y1`, `z0..z1` and the estimated peak bytes.
type PlannedPart = (usize, usize, usize, usize, u64);

fn pairs(ranges: Vec<Range<usize>>) -> Vec<(usize, usize)> {
    ranges.into_iter().map(|r| (r.start, r.end)).collect()
}

/// The parts of an encode as `(y0, y1, z0, z1, bytes)`: the fitting groups along y and z it
/// covers, and its estimated peak bytes.
#[pyfunction]
#[pyo3(signature = (vertices, faces, parts, *, res=None, voxel=None, band=4.0, basis="bspline3", sign="auto", sharp="off", sharp_angle=None))]
pub(crate) fn plan_encode(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    parts: usize,
    res: Option<usize>,
    voxel: Option<f32>,
    band: f32,
    basis: &str,
    sign: &str,
    sharp: &str,
    sharp_angle: Option<f32>,
) -> PyResult<Vec<PlannedPart>> {
    let options = encode_options(py, res, voxel, band, basis, (sign, sharp, sharp_angle))?;
    let mesh = mesh(py, vertices, faces)?;
    quiet(py, || {
        let plan = parts::plan_encode(&mesh, &options, parts)?;
        let bytes = parts::plan_encode_bytes(&mesh, &options, &plan)?;
        Ok(plan
            .parts
            .iter()
            .zip(bytes)
            .map(|(p, bytes)| (p.gy.start, p.gy.end, p.gz.start, p.gz.end, bytes))
            .collect())
    })
}

/// One part of an encode in parts: its coefficient bricks and the nodes it sampled exactly.
/// Pickles, so that it can travel from a worker process to the client.
#[pyclass(frozen, get_all, module = "pgvol._pgvol")]
pub(crate) struct EncodedPart {
    /// The coefficient bricks and sides of the part's box, as slab bytes.
    bricks: Py<PyBytes>,
    /// Nodes of the part's stored sample bricks within the band.
    exact_nodes: usize,
}

#[pymethods]
impl EncodedPart {
    #[new]
    fn new(bricks: Py<PyBytes>, exact_nodes: usize) -> Self {
        EncodedPart {
            bricks,
            exact_nodes,
        }
    }

    /// Rebuilt from its two fields when unpickled.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> (Bound<'py, PyAny>, (Py<PyBytes>, usize)) {
        let me = slf.get();
        let fields = (me.bricks.clone_ref(slf.py()), me.exact_nodes);
        (slf.get_type().into_any(), fields)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "EncodedPart(bricks=<{} bytes>, exact_nodes={})",
            self.bricks.bind(py).as_bytes().len(),
            self.exact_nodes
        )
    }
}

/// The distance query of a mesh for encoding any of its parts; build one per process.
#[pyclass(frozen, module = "pgvol.distributed")]
pub(crate) struct EncodeJob {
    job: parts::EncodeJob,
}

#[pymethods]
impl EncodeJob {
    #[new]
    #[pyo3(signature = (vertices, faces, *, res=None, voxel=None, band=4.0, basis="bspline3", sign="auto", sharp="off", sharp_angle=None))]
    fn new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        res: Option<usize>,
        voxel: Option<f32>,
        band: f32,
        basis: &str,
        sign: &str,
        sharp: &str,
        sharp_angle: Option<f32>,
    ) -> PyResult<EncodeJob> {
        let options = encode_options(py, res, voxel, band, basis, (sign, sharp, sharp_angle))?;
        let mesh = mesh(py, vertices, faces)?;
        let job = quiet(py, || parts::EncodeJob::new(&mesh, &options))?;
        Ok(EncodeJob { job })
    }

    /// Samples and fits the fitting groups `y0..y1` along y and `z0..z1` along z.
    fn encode_part(
        &self,
        py: Python<'_>,
        y0: usize,
        y1: usize,
        z0: usize,
        z1: usize,
    ) -> PyResult<EncodedPart> {
        let part = parts::GroupBox {
            gy: y0..y1,
            gz: z0..z1,
        };
        let part = quiet(py, || self.job.encode_part(&part))?;
        Ok(EncodedPart {
            bricks: PyBytes::new(py, &part.bricks).unbind(),
            exact_nodes: part.exact_nodes,
        })
    }

    /// Estimated peak bytes of encoding the groups `y0..y1`, `z0..z1` in a fresh process.
    fn part_bytes(&self, y0: usize, y1: usize, z0: usize, z1: usize) -> u64 {
        self.job.part_bytes(&parts::GroupBox {
            gy: y0..y1,
            gz: z0..z1,
        })
    }
}

/// The field of a mesh from its parts' bricks, in plan order.
#[pyfunction]
#[pyo3(signature = (vertices, faces, bricks, *, res=None, voxel=None, band=4.0, basis="bspline3", sign="auto", sharp="off", sharp_angle=None))]
pub(crate) fn assemble_encode(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    bricks: Vec<Vec<u8>>,
    res: Option<usize>,
    voxel: Option<f32>,
    band: f32,
    basis: &str,
    sign: &str,
    sharp: &str,
    sharp_angle: Option<f32>,
) -> PyResult<Field> {
    let options = encode_options(py, res, voxel, band, basis, (sign, sharp, sharp_angle))?;
    let mesh = mesh(py, vertices, faces)?;
    let encoded = quiet(py, || {
        let slices: Vec<&[u8]> = bricks.iter().map(Vec::as_slice).collect();
        parts::assemble_encode(&mesh, &options, &slices)
    })?;
    Ok(Field::from_file(encoded.file))
}

/// Writes the file of an encode to `path` from its parts (an iterable of `EncodedPart` in plan
/// order), each taken as it comes: `("written", grid)`, or, with nothing written,
/// `("whole", grid)` when the automatic precision needs the parts assembled in memory. An exception raised by the
/// iterable stops the write and is raised again.
#[pyfunction]
#[pyo3(signature = (vertices, faces, parts, path, *, res=None, voxel=None, band=4.0, basis="bspline3", sign="auto", sharp="off", sharp_angle=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_encode_parts(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    parts: &Bound<'_, PyAny>,
    path: PathBuf,
    res: Option<usize>,
    voxel: Option<f32>,
    band: f32,
    basis: &str,
    sign: &str,
    sharp: &str,
    sharp_angle: Option<f32>,
) -> PyResult<(&'static str, crate::field::Grid)> {
    let options = encode_options(py, res, voxel, band, basis, (sign, sharp, sharp_angle))?;
    let mesh = mesh(py, vertices, faces)?;
    let grid = quiet(py, || options.grid.grid_for(&mesh))?;
    let source = parts.try_iter()?.unbind();
    // A Python exception from the iterable, kept to be raised again once the write stops.
    let raised: std::sync::Mutex<Option<PyErr>> = std::sync::Mutex::new(None);
    let outcome = quiet(py, || {
        let mut next = std::iter::from_fn(|| {
            Python::attach(|py| {
                let item = source.bind(py).clone().next()?;
                let part = item.and_then(|obj| {
                    let part = obj.cast::<EncodedPart>().map_err(PyErr::from)?.get();
                    Ok(parts::EncodedPart {
                        bricks: part.bricks.bind(py).as_bytes().to_vec(),
                        exact_nodes: part.exact_nodes,
                    })
                });
                Some(part.map_err(|e| {
                    let message = e.to_string();
                    *raised.lock().expect("not poisoned") = Some(e);
                    pgvol::Error::parameter(format!("the parts stopped: {message}"))
                }))
            })
        });
        parts::write_encode_parts(&path, &mesh, &options, &mut next)
    });
    if let Some(e) = raised.lock().expect("not poisoned").take() {
        return Err(e);
    }
    let name = match outcome? {
        parts::PartsWritten::Written(_) => "written",
        parts::PartsWritten::NeedsWholeVolume => "whole",
    };
    Ok((name, crate::field::Grid { grid }))
}

/// The z cells of each part of contouring `field`.
#[pyfunction]
pub(crate) fn plan_decode(
    py: Python<'_>,
    field: &Field,
    parts: usize,
) -> PyResult<Vec<(usize, usize)>> {
    parts::plan_decode(field.shape().volume(), parts)
        .map(pairs)
        .map_err(|e| errors::to_py(py, e))
}

/// The coefficient bricks around the z cells `start..end` of `field`.
#[pyfunction]
pub(crate) fn decode_part_bricks<'py>(
    py: Python<'py>,
    field: &Field,
    start: usize,
    end: usize,
) -> Bound<'py, PyBytes> {
    let bytes = py.detach(|| parts::decode_part_bricks(field.shape().volume(), start..end));
    PyBytes::new(py, &bytes)
}

/// The triangles of the z cells `start..end`: (vertices, faces), with `normals` (vertices,
/// faces, normals).
#[pyfunction]
#[pyo3(signature = (bricks, start, end, *, iso=0.0, normals=true))]
pub(crate) fn decode_part<'py>(
    py: Python<'py>,
    bricks: Vec<u8>,
    start: usize,
    end: usize,
    iso: f32,
    normals: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let options = part_options(iso);
    let mesh = quiet(py, || parts::decode_part(&bricks, start..end, &options))?;
    arrays::mesh_tuple(py, mesh, normals)
}

/// The options of a part contoured at level `iso`.
fn part_options(iso: f32) -> pgvol::DecodeOptions {
    pgvol::DecodeOptions {
        iso,
        ..Default::default()
    }
}

/// The z cells of each part of contouring the `.pgv` file at `path` and its grid spacing, from
/// its header; `None` for a file not read slab by slab, whose parts come from the loaded field.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub(crate) fn plan_decode_file(
    py: Python<'_>,
    path: PathBuf,
    parts: usize,
) -> PyResult<Option<(Vec<(usize, usize)>, f32)>> {
    let plan = quiet(py, || parts::plan_decode_file(&path, parts))?;
    Ok(plan.map(|(ranges, spacing)| (pairs(ranges), spacing)))
}

/// What contouring the z cells `start..end` of the file at `path` reads: a `.pgv` file of the
/// file's own bricks in the slabs the part reaches, for `decode_file_part`.
#[pyfunction]
pub(crate) fn decode_file_part_bricks<'py>(
    py: Python<'py>,
    path: PathBuf,
    start: usize,
    end: usize,
) -> PyResult<Bound<'py, PyBytes>> {
    let bytes = quiet(py, || parts::decode_file_part_bricks(&path, start..end))?;
    Ok(PyBytes::new(py, &bytes))
}

/// The triangles of the z cells `start..end` from the bytes `decode_file_part_bricks` gave:
/// as [`decode_part`] returns them.
#[pyfunction]
#[pyo3(signature = (part, start, end, *, iso=0.0, normals=true))]
pub(crate) fn decode_file_part<'py>(
    py: Python<'py>,
    part: Vec<u8>,
    start: usize,
    end: usize,
    iso: f32,
    normals: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let options = part_options(iso);
    let mesh = quiet(py, || parts::decode_file_part(&part, start..end, &options))?;
    arrays::mesh_tuple(py, mesh, normals)
}

/// The mesh of the parts' pieces ((vertices, faces, normals) triples, or (vertices, faces)
/// pairs): seams welded, small pieces removed; (vertices, faces), with `normals` (vertices,
/// faces, normals), the pieces' normals where every piece has them, else weighted from the
/// faces.
#[pyfunction]
#[pyo3(signature = (pieces, spacing, *, iso=0.0, min_component=None, normals=true))]
pub(crate) fn weld_parts<'py>(
    py: Python<'py>,
    pieces: Vec<Bound<'py, PyAny>>,
    spacing: f32,
    iso: f32,
    min_component: Option<f32>,
    normals: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let meshes = pieces
        .iter()
        .map(|p| {
            type Triple<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>);
            if let Ok((v, f, n)) = p.extract::<Triple>() {
                let v = arrays::world_points(&v, "vertices")?;
                let mut mesh = pgvol::Mesh::from_world(&v, arrays::faces(&f)?);
                if normals {
                    mesh.normals = arrays::vertex_normals(&n, mesh.positions.len())?;
                }
                return Ok(mesh);
            }
            let (v, f) = arrays::mesh_parts(p, "piece")?;
            Ok(pgvol::Mesh::from_world(&v, f))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let options = pgvol::DecodeOptions {
        min_component,
        ..part_options(iso)
    };
    let mesh = quiet(py, || {
        parts::weld_parts(meshes, spacing, &options, &pgvol::Silent)
    })?;
    arrays::mesh_tuple(py, mesh, normals)
}

/// The layer numbers of each part of slicing `field`.
#[pyfunction]
#[pyo3(signature = (field, parts, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
pub(crate) fn plan_slice(
    py: Python<'_>,
    field: &Field,
    parts: usize,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Vec<(usize, usize)>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    quiet(py, || parts::plan_slice(field.shape(), &settings, parts)).map(pairs)
}

/// The coefficient bricks the layers `start..end` read.
#[pyfunction]
#[pyo3(signature = (field, start, end, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
pub(crate) fn slice_part_bricks<'py>(
    py: Python<'py>,
    field: &Field,
    start: usize,
    end: usize,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Bound<'py, PyBytes>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let bytes = quiet(py, || {
        parts::slice_part_bricks(field.shape(), &settings, start..end)
    })?;
    Ok(PyBytes::new(py, &bytes))
}

/// The layers `start..end` from their bricks; `bounds` is the field's.
#[pyfunction]
#[pyo3(signature = (bricks, bounds, start, end, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
pub(crate) fn slice_part(
    py: Python<'_>,
    bricks: Vec<u8>,
    bounds: ((f32, f32, f32), (f32, f32, f32)),
    start: usize,
    end: usize,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Vec<Layer>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let bounds = (glam::Vec3::from(bounds.0), glam::Vec3::from(bounds.1));
    let layers = quiet(py, || {
        parts::slice_part(&bricks, bounds, &settings, start..end)
    })?;
    Ok(layers
        .into_iter()
        .map(|l| Layer::from_layer(py, l))
        .collect())
}

/// The parts' layers of slicing `field` (concatenated in plan order) with the corners of the
/// field's sharp section put back, as `Field.slice` gives them.
#[pyfunction]
#[pyo3(signature = (field, layers, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sharpen_layers(
    py: Python<'_>,
    field: &Field,
    layers: Vec<PyRef<'_, Layer>>,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Vec<Layer>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let shape = field.shape();
    sharpened(py, layers, |out| {
        parts::sharpen_layers(shape, &settings, out)
    })
}

/// `layers` with the corners `sharpen` puts back.
fn sharpened(
    py: Python<'_>,
    layers: Vec<PyRef<'_, Layer>>,
    sharpen: impl FnOnce(&mut [pgvol::Layer]) -> pgvol::Result<()> + Send,
) -> PyResult<Vec<Layer>> {
    let mut out = layers
        .iter()
        .map(|l| l.to_layer(py))
        .collect::<PyResult<Vec<_>>>()?;
    drop(layers);
    quiet(py, || sharpen(&mut out))?;
    Ok(out.into_iter().map(|l| Layer::from_layer(py, l)).collect())
}

/// The layer numbers of each part of slicing the `.pgv` file at `path`, from its header; `None`
/// for a file not read slab by slab, whose parts come from the loaded field.
#[pyfunction]
#[pyo3(signature = (path, parts, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
pub(crate) fn plan_slice_file(
    py: Python<'_>,
    path: PathBuf,
    parts: usize,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Option<Vec<(usize, usize)>>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let plan = quiet(py, || parts::plan_slice_file(&path, &settings, parts))?;
    Ok(plan.map(pairs))
}

/// What the layers `start..end` of slicing the file at `path` read: a `.pgv` file of the file's
/// own compressed bricks in the slabs they reach, for `slice_file_part`.
#[pyfunction]
#[pyo3(signature = (path, start, end, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
pub(crate) fn slice_file_part_bricks<'py>(
    py: Python<'py>,
    path: PathBuf,
    start: usize,
    end: usize,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Bound<'py, PyBytes>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let bytes = quiet(py, || {
        parts::slice_file_part_bricks(&path, &settings, start..end)
    })?;
    Ok(PyBytes::new(py, &bytes))
}

/// The layers `start..end` of slicing, from the bytes `slice_file_part_bricks` gave for them.
#[pyfunction]
#[pyo3(signature = (part, start, end, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
pub(crate) fn slice_file_part(
    py: Python<'_>,
    part: Vec<u8>,
    start: usize,
    end: usize,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Vec<Layer>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    let layers = quiet(py, || parts::slice_file_part(&part, &settings, start..end))?;
    Ok(layers
        .into_iter()
        .map(|l| Layer::from_layer(py, l))
        .collect())
}

/// `sharpen_layers` for the file at `path`, from its header.
#[pyfunction]
#[pyo3(signature = (path, layers, layer_height, *, axis="z", first=None, resolution=None, tolerance=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sharpen_file_layers(
    py: Python<'_>,
    path: PathBuf,
    layers: Vec<PyRef<'_, Layer>>,
    layer_height: f32,
    axis: &str,
    first: Option<f32>,
    resolution: Option<f32>,
    tolerance: Option<f32>,
) -> PyResult<Vec<Layer>> {
    let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
    sharpened(py, layers, |out| {
        parts::sharpen_file_layers(&path, &settings, out)
    })
}

/// Writes layers to an SVG, Common Layer Interface (`binary` for its binary form) or JSON
/// file by extension, atomically; `units_mm` is millimetres per model unit (CLI headers).
#[pyfunction]
#[pyo3(signature = (path, layers, *, binary=false, units_mm=1.0))]
pub(crate) fn write_layers(
    py: Python<'_>,
    path: PathBuf,
    layers: Vec<PyRef<'_, Layer>>,
    binary: bool,
    units_mm: f32,
) -> PyResult<()> {
    let out = layers
        .iter()
        .map(|l| l.to_layer(py))
        .collect::<PyResult<Vec<_>>>()?;
    quiet(py, || {
        let format = pgvol::io::LayerFormat::from_path(&path, binary)?;
        // Layers from Python are world coordinates as given.
        pgvol::io::write_layers(
            &path,
            &out,
            format,
            units_mm,
            &pgvol::reconstruct::LayerFrame::default(),
        )
    })
}

/// Registers the classes and functions of this module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<EncodeJob>()?;
    m.add_class::<EncodedPart>()?;
    m.add_function(wrap_pyfunction!(plan_encode, m)?)?;
    m.add_function(wrap_pyfunction!(assemble_encode, m)?)?;
    m.add_function(wrap_pyfunction!(write_encode_parts, m)?)?;
    m.add_function(wrap_pyfunction!(plan_decode, m)?)?;
    m.add_function(wrap_pyfunction!(decode_part_bricks, m)?)?;
    m.add_function(wrap_pyfunction!(decode_part, m)?)?;
    m.add_function(wrap_pyfunction!(plan_decode_file, m)?)?;
    m.add_function(wrap_pyfunction!(decode_file_part_bricks, m)?)?;
    m.add_function(wrap_pyfunction!(decode_file_part, m)?)?;
    m.add_function(wrap_pyfunction!(weld_parts, m)?)?;
    m.add_function(wrap_pyfunction!(plan_slice, m)?)?;
    m.add_function(wrap_pyfunction!(slice_part_bricks, m)?)?;
    m.add_function(wrap_pyfunction!(slice_part, m)?)?;
    m.add_function(wrap_pyfunction!(sharpen_layers, m)?)?;
    m.add_function(wrap_pyfunction!(plan_slice_file, m)?)?;
    m.add_function(wrap_pyfunction!(slice_file_part_bricks, m)?)?;
    m.add_function(wrap_pyfunction!(slice_file_part, m)?)?;
    m.add_function(wrap_pyfunction!(sharpen_file_layers, m)?)?;
    m.add_function(wrap_pyfunction!(write_layers, m)?)?;
    Ok(())
}
