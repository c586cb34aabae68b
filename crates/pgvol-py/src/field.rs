//! `pgvol.Field`: a coefficient volume with what is known of its shape, and every library call
//! on it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

use crate::arrays;
use crate::errors;
use crate::names;
use crate::progress::{quiet, run};

/// A grid of nodes: node `(i, j, k)` lies at `origin + spacing * (i, j, k)`.
#[pyclass(frozen, eq, module = "pgvol")]
#[derive(Clone, Copy, PartialEq)]
pub(crate) struct Grid {
    pub(crate) grid: pgvol::Grid,
}

#[pymethods]
impl Grid {
    #[new]
    fn new(origin: (f32, f32, f32), spacing: f32, dims: (usize, usize, usize)) -> Self {
        Self {
            grid: pgvol::Grid {
                origin: glam::Vec3::new(origin.0, origin.1, origin.2),
                spacing,
                dims: [dims.0, dims.1, dims.2],
                offset: Default::default(),
            },
        }
    }

    /// The position of node (0, 0, 0).
    #[getter]
    fn origin(&self) -> (f32, f32, f32) {
        self.grid.origin.into()
    }

    /// The distance between neighbouring nodes along every axis.
    #[getter]
    fn spacing(&self) -> f32 {
        self.grid.spacing
    }

    /// Nodes along x, y and z.
    #[getter]
    fn dims(&self) -> (usize, usize, usize) {
        let [nx, ny, nz] = self.grid.dims;
        (nx, ny, nz)
    }

    /// The position of the last node, `origin + spacing * (dims - 1)`.
    #[getter]
    fn max_corner(&self) -> (f32, f32, f32) {
        self.grid.max_corner().into()
    }

    fn __repr__(&self) -> String {
        let o = self.grid.origin;
        let [nx, ny, nz] = self.grid.dims;
        format!(
            "Grid(origin=({}, {}, {}), spacing={}, dims=({nx}, {ny}, {nz}))",
            o.x, o.y, o.z, self.grid.spacing
        )
    }
}

/// The closed contours of one layer plane.
#[pyclass(frozen, get_all, module = "pgvol")]
pub(crate) struct Layer {
    /// Position of the plane along the slicing axis.
    pub(crate) height: f32,
    /// One (M, 2) float32 array of layer coordinates per closed loop.
    pub(crate) loops: Vec<Py<PyArray2<f32>>>,
    /// Per loop: a hole (clockwise) rather than an outer boundary (counter-clockwise).
    pub(crate) holes: Vec<bool>,
}

impl Layer {
    /// The library's layer with its loops as NumPy arrays.
    pub(crate) fn from_layer(py: Python<'_>, layer: pgvol::Layer) -> Layer {
        let holes = layer.loops.iter().map(|l| l.hole).collect();
        let loops = layer
            .loops
            .into_iter()
            .map(|l| arrays::points2(py, l.points).unbind())
            .collect();
        Layer {
            height: layer.height,
            loops,
            holes,
        }
    }
}

impl Layer {
    /// The library's layer from this one's loops, each an (M, 2) array.
    pub(crate) fn to_layer(&self, py: Python<'_>) -> PyResult<pgvol::Layer> {
        let mut loops = Vec::with_capacity(self.loops.len());
        for (points, &hole) in self.loops.iter().zip(&self.holes) {
            let array = points.bind(py).readonly();
            let view = array.as_array();
            if view.ncols() != 2 {
                return Err(errors::parameter(py, "a loop must be an (M, 2) array"));
            }
            let points = view.rows().into_iter().map(|r| [r[0], r[1]]).collect();
            loops.push(pgvol::slicing::Loop { points, hole });
        }
        Ok(pgvol::Layer {
            height: self.height,
            loops,
        })
    }
}

#[pymethods]
impl Layer {
    /// A layer from its height, its loops ((M, 2) float32 arrays) and which loops are holes.
    #[new]
    fn new(height: f32, loops: Vec<Py<PyArray2<f32>>>, holes: Vec<bool>) -> PyResult<Layer> {
        if loops.len() != holes.len() {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "loops and holes must have the same length",
            ));
        }
        Ok(Layer {
            height,
            loops,
            holes,
        })
    }

    /// Pickles as its height, loops and holes.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let me = slf.borrow();
        let loops: Vec<&Py<PyArray2<f32>>> = me.loops.iter().collect();
        let args = (me.height, loops, me.holes.clone()).into_pyobject(py)?;
        PyTuple::new(py, [py.get_type::<Layer>().into_any(), args.into_any()])
    }

    fn __repr__(&self) -> String {
        format!("Layer(height={}, loops={})", self.height, self.loops.len())
    }
}

/// A smooth implicit field: coefficients of a compactly supported basis on a grid.
#[pyclass(frozen, module = "pgvol")]
pub(crate) struct Field {
    shape: pgvol::Field,
    header: pgvol::PgvHeader,
}

impl Field {
    pub(crate) fn from_file(file: pgvol::PgvFile) -> Self {
        Self::from_shape(pgvol::Field::from_file(file))
    }

    pub(crate) fn from_shape(shape: pgvol::Field) -> Self {
        Self {
            header: shape.header().clone(),
            shape,
        }
    }

    /// The field and what is known of its shape.
    pub(crate) fn shape(&self) -> &pgvol::Field {
        &self.shape
    }

    fn file(&self) -> pgvol::PgvFile {
        pgvol::PgvFile {
            header: self.header.clone(),
            volume: self.shape.volume().clone(),
        }
    }

    /// The Boolean `op` of this field and `other`, sharp or rounded with `radius`.
    fn boolean(
        &self,
        py: Python<'_>,
        op: pgvol::BoolOp,
        other: &Field,
        radius: Option<f32>,
    ) -> PyResult<Field> {
        let blend = radius.map_or(pgvol::Blend::Sharp, pgvol::Blend::Round);
        let shape = quiet(py, || self.shape.boolean(op, &other.shape, blend))?;
        Ok(Field::from_shape(shape))
    }

    fn storage(
        &self,
        py: Python<'_>,
        dense: Option<bool>,
        precision: Option<&str>,
    ) -> PyResult<pgvol::StorageOptions> {
        let mut storage = pgvol::StorageOptions::default();
        if let Some(dense) = dense {
            storage.dense = dense;
        }
        if let Some(p) = precision {
            storage.precision = Some(names::precision(py, p)?);
            if dense.is_none() {
                storage.dense = false;
            }
        }
        Ok(storage)
    }
}

// Python signatures show literal defaults only; these are the library's.
const _: () = assert!(pgvol::limits::ENCODE_BAND == 4.0);
const _: () = assert!(pgvol::limits::DEFAULT_ALPHA == 1.0);
const _: () = assert!(pgvol::limits::DEFAULT_COARSE == 30);
const _: () = assert!(pgvol::limits::CSG_RES == 128);
const _: () = assert!(same_str(pgvol::limits::THREEMF_UNIT, "millimeter"));

/// Whether two strings are equal, in a constant.
const fn same_str(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The grid choice of `res` and `voxel`.
pub(crate) fn grid_spec(
    py: Python<'_>,
    res: Option<usize>,
    voxel: Option<f32>,
) -> PyResult<pgvol::GridSpec> {
    match (res, voxel) {
        (Some(_), Some(_)) => Err(errors::parameter(py, "give res or voxel, not both")),
        (None, Some(h)) if !(h.is_finite() && h > 0.0) => Err(errors::parameter(
            py,
            format!("voxel must be a positive number, got {h}"),
        )),
        (None, Some(h)) => Ok(pgvol::GridSpec::Voxel(h)),
        (res, None) => {
            let n = res.unwrap_or(pgvol::limits::DEFAULT_RES);
            let (lo, hi) = (
                pgvol::limits::MIN_RES as usize,
                pgvol::limits::MAX_RES as usize,
            );
            if !(lo..=hi).contains(&n) {
                return Err(errors::parameter(
                    py,
                    format!("res must be from {lo} to {hi}, got {n}"),
                ));
            }
            Ok(pgvol::GridSpec::Res(n))
        }
    }
}

/// A drain hole from seven numbers `x, y, z, dx, dy, dz, diameter` or from
/// `((x, y, z), (dx, dy, dz), diameter)`, checked by the library.
/// A segment ((x0, y0, z0), (x1, y1, z1)).
type Segment = ((f32, f32, f32), (f32, f32, f32));

/// A lattice from the keyword arguments of `lattice` and `infill`: the grading is
/// (depth, linear segment, far cell, far thickness).
fn make_lattice(
    py: Python<'_>,
    surface: &str,
    style: &str,
    cell: f32,
    thickness: f32,
    (depth, linear, cell_far, thickness_far): (
        Option<f32>,
        Option<Segment>,
        Option<f32>,
        Option<f32>,
    ),
) -> PyResult<pgvol::Lattice> {
    let ramp = match (depth, linear) {
        (Some(_), Some(_)) => {
            return Err(errors::parameter(
                py,
                "give grade_depth or grade_linear, not both",
            ))
        }
        (Some(depth), None) => Some(pgvol::lattices::Ramp::Depth { depth }),
        (None, Some((a, b))) => Some(pgvol::lattices::Ramp::Linear {
            from: glam::Vec3::new(a.0, a.1, a.2),
            to: glam::Vec3::new(b.0, b.1, b.2),
        }),
        (None, None) => None,
    };
    pgvol::lattices::make_lattice(
        names::tpms(py, surface)?,
        names::lattice_style(py, style)?,
        cell,
        thickness,
        ramp,
        cell_far,
        thickness_far,
    )
    .map_err(|e| errors::to_py(py, e))
}

/// Two corners of a box, lowest then highest.
type Corners = ((f32, f32, f32), (f32, f32, f32));

/// The grid of `resample` and `primitive`.
fn resample_options(res: usize, bounds: Option<Corners>, band: f32) -> pgvol::ResampleOptions {
    let corner = |c: (f32, f32, f32)| glam::Vec3::new(c.0, c.1, c.2);
    pgvol::ResampleOptions {
        res,
        bounds: bounds.map(|(lo, hi)| (corner(lo), corner(hi))),
        band,
    }
}

/// An operand of `Field.csg`: a Field, a primary's text or a file's path.
fn operand(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<pgvol::Operand> {
    if let Ok(field) = obj.cast::<Field>() {
        return Ok(pgvol::Operand::from(field.get().shape.clone()));
    }
    if let Ok(text) = obj.extract::<String>() {
        return pgvol::Operand::parse(&text).map_err(|e| errors::to_py(py, e));
    }
    match obj.extract::<PathBuf>() {
        Ok(path) => Ok(pgvol::Operand::File(path)),
        Err(_) => Err(errors::parameter(
            py,
            "an operand is a Field, a primary such as \"sphere:0,0,0,1\", or a file's path",
        )),
    }
}

/// The drains given as a list (none when absent), each read by [`drain`].
fn drain_list(
    py: Python<'_>,
    drains: Option<Vec<Bound<'_, PyAny>>>,
) -> PyResult<Vec<pgvol::edit::Drain>> {
    drains
        .unwrap_or_default()
        .iter()
        .map(|d| drain(py, d))
        .collect()
}

fn drain(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<pgvol::edit::Drain> {
    let numbers: Vec<f32> = match obj.extract::<Vec<f32>>() {
        Ok(v) => v,
        Err(_) => {
            let (p, d, diameter) = obj
                .extract::<((f32, f32, f32), (f32, f32, f32), f32)>()
                .map_err(|_| {
                    errors::parameter(
                        py,
                        "a drain is (x, y, z, dx, dy, dz, diameter) or ((x, y, z), (dx, dy, dz), diameter)",
                    )
                })?;
            vec![p.0, p.1, p.2, d.0, d.1, d.2, diameter]
        }
    };
    if numbers.len() != 7 || numbers.iter().any(|x| !x.is_finite()) {
        return Err(errors::parameter(
            py,
            "a drain: expected seven finite numbers x,y,z,dx,dy,dz,diameter",
        ));
    }
    let direction = glam::Vec3::new(numbers[3], numbers[4], numbers[5]);
    if direction.length() == 0.0 || numbers[6] <= 0.0 {
        return Err(errors::parameter(
            py,
            "a drain's direction must be non-zero and its diameter positive",
        ));
    }
    Ok(pgvol::edit::Drain {
        point: glam::Vec3::new(numbers[0], numbers[1], numbers[2]),
        direction: direction.normalize(),
        diameter: numbers[6],
    })
}

#[pymethods]
impl Field {
    /// Encodes a triangle mesh: signed distance on a cube grid around it, fitted with a basis.
    #[staticmethod]
    #[pyo3(signature = (vertices, faces, *, res=None, voxel=None, band=4.0, basis="bspline3", fit="interp", sign="auto", z_step=None, sharp="off", sharp_angle=None, progress=None))]
    fn from_mesh(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        res: Option<usize>,
        voxel: Option<f32>,
        band: f32,
        basis: &str,
        fit: &str,
        sign: &str,
        z_step: Option<f32>,
        sharp: &str,
        sharp_angle: Option<f32>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let positions = arrays::world_points(vertices, "vertices")?;
        let triangles = arrays::faces(faces)?;
        let options = pgvol::EncodeOptions {
            grid: grid_spec(py, res, voxel)?,
            basis: names::basis(py, basis)?,
            fit: names::fit(py, fit, z_step)?,
            band,
            sign: names::sign(py, sign)?,
            sharp: pgvol::sharp::SharpOptions {
                enabled: names::sharp(py, sharp)?,
                angle: sharp_angle.unwrap_or(pgvol::sharp::DEFAULT_SHARP_ANGLE),
            },
        };
        let encoded = run(py, progress, |p| {
            let mesh = pgvol::io::mesh_from_world(&positions, triangles)?.mesh;
            pgvol::encode(&mesh, &options, p)
        })?;
        Ok(Field::from_file(encoded.file))
    }

    /// A smooth closed surface through a point cloud (normals estimated when not given), and
    /// with `sections=(axis, heights)` its cross-sections cut from the method's own field.
    #[staticmethod]
    #[pyo3(signature = (points, normals=None, *, res=None, voxel=None, method="spline", band=pgvol::limits::ENCODE_BAND, support=None, sections=None, section_resolution=None, progress=None))]
    fn from_points(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        normals: Option<&Bound<'_, PyAny>>,
        res: Option<usize>,
        voxel: Option<f32>,
        method: &str,
        band: f32,
        support: Option<f32>,
        sections: Option<&Bound<'_, PyAny>>,
        section_resolution: Option<f32>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        let single = |v: Vec<glam::DVec3>| -> Vec<glam::Vec3> {
            v.into_iter().map(|p| p.as_vec3()).collect()
        };
        let cloud = pgvol::reconstruct::PointCloud {
            points: single(arrays::world_points(points, "points")?),
            normals: normals
                .map(|n| arrays::world_points(n, "normals"))
                .transpose()?
                .map(single),
        };
        if cloud.points.is_empty() {
            return Err(errors::parameter(
                py,
                "points: the array holds no points; a surface needs a cloud of points on it",
            ));
        }
        if let Some(n) = &cloud.normals {
            if n.len() != cloud.points.len() {
                return Err(errors::parameter(
                    py,
                    format!(
                        "{} normals for {} points: give one normal per point, or none",
                        n.len(),
                        cloud.points.len()
                    ),
                ));
            }
        }
        let options = pgvol::PointsOptions {
            grid: grid_spec(py, res, voxel)?,
            method: names::points_method(py, method)?,
            band,
            support,
        };
        let Some(sections) = sections else {
            if section_resolution.is_some() {
                return Err(errors::parameter(
                    py,
                    "section_resolution applies only with sections",
                ));
            }
            let fitted = run(py, progress, |p| {
                pgvol::reconstruct::points(&cloud, &options, p)
            })?;
            return Ok(Py::new(py, Field::from_file(fitted.file))?.into_any());
        };
        let (axis, heights) = sections.extract::<(String, Vec<f32>)>().map_err(|_| {
            errors::parameter(
                py,
                "sections must be (axis, heights), e.g. (\"z\", [0.0, 0.5])",
            )
        })?;
        let settings = pgvol::reconstruct::SectionOptions {
            axis: names::axis(py, &axis)?,
            heights,
            resolution: section_resolution,
        };
        let (fitted, cut) = run(py, progress, |p| {
            pgvol::reconstruct::points_with_sections(&cloud, &options, &settings, p)
        })?;
        let field = Py::new(py, Field::from_file(fitted.file))?;
        let layers: Vec<Layer> = cut
            .layers
            .into_iter()
            .map(|l| Layer::from_layer(py, l))
            .collect();
        Ok((field, layers).into_pyobject(py)?.into_any().unbind())
    }

    /// A closed solid through a stack of planar contours along `axis`: a list of Layers (as
    /// `slice` returns them) or a layer file (.json, .cli or .svg, as `write_layers` and
    /// `pgvol slice` write them). `method` "spline" interpolates each plane's 2D signed
    /// distance across the planes; the RBF methods fit points along the loops. The solid is
    /// closed half a layer beyond the outermost planes.
    #[staticmethod]
    #[pyo3(signature = (layers, *, axis="z", res=None, voxel=None, method="spline", progress=None))]
    fn from_contours(
        py: Python<'_>,
        layers: &Bound<'_, PyAny>,
        axis: &str,
        res: Option<usize>,
        voxel: Option<f32>,
        method: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let source = match layers.extract::<Vec<PyRef<'_, Layer>>>() {
            Ok(list) => Ok(list
                .iter()
                .map(|l| l.to_layer(py))
                .collect::<PyResult<Vec<_>>>()?),
            Err(_) => Err(layers.extract::<PathBuf>().map_err(|_| {
                errors::parameter(py, "layers must be a list of Layer or a layer file's path")
            })?),
        };
        let options = pgvol::PointsOptions {
            grid: grid_spec(py, res, voxel)?,
            method: names::points_method(py, method)?,
            ..Default::default()
        };
        let axis = names::axis(py, axis)?;
        let fitted = run(py, progress, |p| {
            let layers = match source {
                Ok(layers) => layers,
                Err(path) => pgvol::io::read_layers(&path)?,
            };
            pgvol::reconstruct::contours(&layers, axis, &options, p)
        })?;
        Ok(Field::from_file(fitted.file))
    }

    /// Encodes a `trimesh.Trimesh` (or anything with `vertices` and `faces`); the keywords are
    /// those of `from_mesh`.
    #[staticmethod]
    #[pyo3(signature = (mesh, **kwargs))]
    fn from_trimesh(
        py: Python<'_>,
        mesh: &Bound<'_, PyAny>,
        kwargs: Option<&Bound<'_, pyo3::types::PyDict>>,
    ) -> PyResult<Py<PyAny>> {
        let args = PyTuple::new(py, [mesh.getattr("vertices")?, mesh.getattr("faces")?])?;
        let cls = py.get_type::<Field>();
        Ok(cls.getattr("from_mesh")?.call(args, kwargs)?.unbind())
    }

    /// Reads a `.pgv` file, or an OpenVDB `.vdb` level set (its first float level set, as
    /// `from_vdb` reads it).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Field> {
        if pgvol::io::is_vdb(&path) {
            return Field::from_vdb(py, path, None);
        }
        let file = quiet(py, || pgvol::io::read_pgv(&path))?;
        Ok(Field::from_file(file))
    }

    /// Fits an OpenVDB level set (a float grid of class "level set" in a `.vdb` file, by
    /// default the first) on its own voxel grid, a node at each voxel centre, within its band.
    #[staticmethod]
    #[pyo3(signature = (path, grid=None))]
    fn from_vdb(py: Python<'_>, path: PathBuf, grid: Option<String>) -> PyResult<Field> {
        let options = pgvol::io::VdbEncodeOptions {
            grid_name: grid,
            ..Default::default()
        };
        let encoded = quiet(py, || {
            pgvol::io::encode_vdb(&path, &options, &pgvol::Silent)
        })?;
        Ok(Field::from_file(encoded.file))
    }

    /// Decodes the bytes of a `.pgv` file.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Field> {
        // There is no file: bytes that do not decode are a bad value, not a missing file.
        let file = quiet(py, || {
            pgvol::io::read_pgv_bytes(data, Path::new("<bytes>")).map_err(|e| match e.kind() {
                pgvol::ErrorKind::InputFile => pgvol::Error::parameter(format!(
                    "the bytes are not a readable .pgv file: {}",
                    e.message()
                )),
                _ => e,
            })
        })?;
        Ok(Field::from_file(file))
    }

    /// Writes the field to a `.pgv` file, atomically: sparse compressed bricks at the automatic
    /// precision unless `dense` or `precision` say otherwise. A field loaded from a file and
    /// saved with the same options gives the same bytes.
    #[pyo3(signature = (path, *, dense=None, precision=None))]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        dense: Option<bool>,
        precision: Option<&str>,
    ) -> PyResult<()> {
        let storage = self.storage(py, dense, precision)?;
        quiet(py, || {
            pgvol::io::check_pgv_name(&path)?;
            pgvol::io::write_pgv(&path, &self.file(), &storage).map(|_| ())
        })
    }

    /// The bytes of the field's `.pgv` file.
    #[pyo3(signature = (*, dense=None, precision=None))]
    fn to_bytes<'py>(
        &self,
        py: Python<'py>,
        dense: Option<bool>,
        precision: Option<&str>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let storage = self.storage(py, dense, precision)?;
        let bytes = quiet(py, || pgvol::io::pgv_bytes(&self.file(), &storage))?.bytes;
        Ok(PyBytes::new(py, &bytes))
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let bytes = self.to_bytes(py, Some(true), None)?;
        Ok((py.get_type::<Field>().getattr("from_bytes")?, (bytes,)))
    }

    /// The field's values at (N, 3) points: an (N,) float32 array, negative inside.
    fn __call__<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let points = self.shape.to_local(&query_points(points)?);
        let values = py.detach(|| self.shape.volume().values_many(&points));
        Ok(arrays::vector(py, values))
    }

    /// Values (N,) and analytic gradients (N, 3) at (N, 3) points.
    #[allow(clippy::type_complexity)]
    fn eval_with_gradient<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, Bound<'py, PyArray2<f32>>)> {
        let points = self.shape.to_local(&query_points(points)?);
        let (values, gradients): (Vec<f32>, Vec<glam::Vec3>) =
            py.detach(|| self.shape.volume().eval_many(&points).into_iter().unzip());
        Ok((arrays::vector(py, values), arrays::vec3s(py, gradients)))
    }

    /// Whether the value at each of (N, 3) points is an exact distance: inside the grid's box
    /// and within `exact_band` of the surface. A bool array (N,).
    fn is_exact<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let points = query_points(points)?;
        let exact: Vec<bool> = py.detach(|| {
            self.shape
                .eval(&points)
                .into_iter()
                .map(|e| e.exact)
                .collect()
        });
        Ok(PyArray1::from_vec(py, exact))
    }

    /// The field sampled at every node of `grid` (default: its own grid), as a float32 array
    /// of shape (nx, ny, nz) indexed `[i, j, k]`.
    #[pyo3(signature = (grid=None))]
    fn sample_grid<'py>(
        &self,
        py: Python<'py>,
        grid: Option<&Bound<'py, Grid>>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let grid = grid.map_or(self.shape.volume().grid, |g| g.get().grid);
        let values = quiet(py, || self.shape.sample_grid(&grid))?;
        Ok(arrays::grid_values(py, values, grid.dims))
    }

    /// The field sampled at every node of its own grid; see `sample_grid`.
    fn to_dense<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        self.sample_grid(py, None)
    }

    /// Contours the level set `iso` into a mesh: (vertices (N, 3), faces (M, 3) int32), the
    /// vertices float32, or float64 world positions for a field far from the origin; with
    /// `normals`, also the unit normals (N, 3) float32 that `write_mesh` stores.
    #[pyo3(signature = (*, method="mc", iso=0.0, res=None, min_component=None, normals=false, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn to_mesh<'py>(
        &self,
        py: Python<'py>,
        method: &str,
        iso: f32,
        res: Option<usize>,
        min_component: Option<f32>,
        normals: bool,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        if min_component.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "min_component must be a finite volume of at least 0",
            ));
        }
        let options = pgvol::DecodeOptions {
            iso,
            method: names::method(py, method)?,
            res,
            min_component,
        };
        let mesh = run(py, progress, |p| self.shape.to_mesh(&options, p))?;
        arrays::mesh_tuple(py, mesh, normals)
    }

    /// The contoured mesh as a `trimesh.Trimesh` carrying `to_mesh`'s normals; the keywords
    /// are those of `to_mesh`.
    #[pyo3(signature = (**kwargs))]
    fn to_trimesh(
        slf: &Bound<'_, Self>,
        kwargs: Option<&Bound<'_, pyo3::types::PyDict>>,
    ) -> PyResult<Py<PyAny>> {
        let py = slf.py();
        let trimesh = py.import("trimesh")?;
        let kwargs = match kwargs {
            Some(k) => k.copy()?,
            None => pyo3::types::PyDict::new(py),
        };
        kwargs.set_item("normals", true)?;
        let (v, f, n): (Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyAny>) =
            slf.getattr("to_mesh")?.call((), Some(&kwargs))?.extract()?;
        let kw = pyo3::types::PyDict::new(py);
        kw.set_item("vertices", v)?;
        kw.set_item("faces", f)?;
        kw.set_item("vertex_normals", n)?;
        kw.set_item("process", false)?;
        Ok(trimesh.getattr("Trimesh")?.call((), Some(&kw))?.unbind())
    }

    /// The shape grown (distance > 0) or shrunk (distance < 0) by `distance`.
    fn offset(&self, py: Python<'_>, distance: f32) -> PyResult<Field> {
        let shape = quiet(py, || self.shape.offset(distance))?;
        Ok(Field::from_shape(shape))
    }

    /// This field sampled on a cube grid of `res` nodes per axis over its box (or over
    /// `bounds`, two corners) and fitted again: coarser to save bytes, finer to edit on. Node
    /// values within `band` grid spacings of the surface are kept, clamped beyond.
    #[pyo3(signature = (res=128, *, bounds=None, band=4.0, progress=None))]
    fn resample(
        &self,
        py: Python<'_>,
        res: usize,
        bounds: Option<Corners>,
        band: f32,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let options = resample_options(res, bounds, band);
        let shape = run(py, progress, |p| self.shape.resample(&options, p))?;
        Ok(Field::from_shape(shape))
    }

    /// An analytic solid as a field, given as text as `csg` takes it ("sphere:x,y,z,r",
    /// "box:x0,y0,z0,x1,y1,z1", "plane:nx,ny,nz,d", "cylinder:...": see `docs/editing.md`),
    /// fitted on a cube grid of `res` nodes per axis over its box (`bounds` for planes and
    /// cylinders), exact within `band` grid spacings of the surface.
    #[staticmethod]
    #[pyo3(signature = (solid, *, res=128, bounds=None, band=4.0, progress=None))]
    fn primitive(
        py: Python<'_>,
        solid: &str,
        res: usize,
        bounds: Option<Corners>,
        band: f32,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let primary = match pgvol::Operand::parse(solid).map_err(|e| errors::to_py(py, e))? {
            pgvol::Operand::Primary(primary) => primary,
            _ => {
                return Err(errors::parameter(
                    py,
                    format!("{solid:?} is not an analytic solid such as \"sphere:0,0,0,1\""),
                ))
            }
        };
        let options = resample_options(res, bounds, band);
        let shape = run(py, progress, |p| {
            pgvol::Field::primitive(primary, &options, p)
        })?;
        Ok(Field::from_shape(shape))
    }

    /// The field inside `masks` (as `repair` takes them) resampled with `coarse` samples along
    /// each mask's longest side and blended back: `repair(masks, denoise=True)`.
    #[pyo3(signature = (masks, *, coarse=30, progress=None))]
    fn denoise(
        &self,
        py: Python<'_>,
        masks: Vec<Bound<'_, PyAny>>,
        coarse: usize,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let masks = masks
            .iter()
            .map(|m| crate::edit::mask(py, m))
            .collect::<PyResult<Vec<_>>>()?;
        let repaired = run(py, progress, |p| self.shape.denoise(&masks, coarse, p))?;
        Ok(Field::from_shape(repaired.field))
    }

    /// A wall of `thickness` around the surface (`side` "inner", "outer" or "centred"), or with
    /// `hollow=True` the shape with a cavity `thickness` inside its surface and optional drain
    /// holes.
    #[pyo3(signature = (thickness, *, side="inner", hollow=false, drains=None, progress=None))]
    fn shell(
        &self,
        py: Python<'_>,
        thickness: f32,
        side: &str,
        hollow: bool,
        drains: Option<Vec<Bound<'_, PyAny>>>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let kind = if hollow {
            pgvol::ShellKind::Hollow
        } else {
            pgvol::ShellKind::Wall(names::side(py, side)?)
        };
        let drains = drain_list(py, drains)?;
        let options = pgvol::ShellOptions {
            thickness,
            kind,
            drains,
        };
        let shape = run(py, progress, |p| self.shape.shell(&options, p))?;
        Ok(Field::from_shape(shape))
    }

    /// The part cut by a triply periodic lattice: `surface` "gyroid", "schwarz-p", "diamond" or
    /// "neovius" with period `cell`; `style` "sheet" (a wall of `thickness`) or "strut" (a
    /// labyrinth bounded at the level `thickness`). Grading: `grade_depth` (the thickness from
    /// the skin to that depth) or `grade_linear` ((x0, y0, z0), (x1, y1, z1)), towards
    /// `cell_far` and `thickness_far`. See docs/lattices.md.
    #[pyo3(signature = (surface, cell, thickness, *, style="sheet", grade_depth=None, grade_linear=None, cell_far=None, thickness_far=None, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn lattice(
        &self,
        py: Python<'_>,
        surface: &str,
        cell: f32,
        thickness: f32,
        style: &str,
        grade_depth: Option<f32>,
        grade_linear: Option<Segment>,
        cell_far: Option<f32>,
        thickness_far: Option<f32>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let grading = (grade_depth, grade_linear, cell_far, thickness_far);
        let lattice = make_lattice(py, surface, style, cell, thickness, grading)?;
        let solid = run(py, progress, |p| self.shape.lattice(&lattice, p))?;
        Ok(Field::from_shape(solid.field))
    }

    /// The shape hollowed to walls of `wall` thickness with the cavity filled by a lattice (the
    /// parameters of `lattice`), and `drains` (as for `shell`) cut through wall and lattice.
    #[pyo3(signature = (wall, surface, cell, thickness, *, style="sheet", drains=None, grade_depth=None, grade_linear=None, cell_far=None, thickness_far=None, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn infill(
        &self,
        py: Python<'_>,
        wall: f32,
        surface: &str,
        cell: f32,
        thickness: f32,
        style: &str,
        drains: Option<Vec<Bound<'_, PyAny>>>,
        grade_depth: Option<f32>,
        grade_linear: Option<Segment>,
        cell_far: Option<f32>,
        thickness_far: Option<f32>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let grading = (grade_depth, grade_linear, cell_far, thickness_far);
        let lattice = make_lattice(py, surface, style, cell, thickness, grading)?;
        let drains = drain_list(py, drains)?;
        let solid = run(py, progress, |p| {
            self.shape.infill(wall, &lattice, &drains, p)
        })?;
        Ok(Field::from_shape(solid.field))
    }

    /// Writes the lattice (the parameters of `lattice`) cut to this part, or with `wall` the
    /// infill of the part hollowed to that wall with `drains`, as a 3MF package naming `unit`:
    /// the part as the level set's image stack, the lattice as an implicit function of it (see
    /// docs/interop.md). Returns the image stack's grid.
    #[pyo3(signature = (path, surface, cell, thickness, *, style="sheet", wall=None, drains=None, grade_depth=None, grade_linear=None, cell_far=None, thickness_far=None, unit="millimeter"))]
    #[allow(clippy::too_many_arguments)]
    fn lattice_3mf(
        &self,
        py: Python<'_>,
        path: PathBuf,
        surface: &str,
        cell: f32,
        thickness: f32,
        style: &str,
        wall: Option<f32>,
        drains: Option<Vec<Bound<'_, PyAny>>>,
        grade_depth: Option<f32>,
        grade_linear: Option<Segment>,
        cell_far: Option<f32>,
        thickness_far: Option<f32>,
        unit: &str,
    ) -> PyResult<Grid> {
        let grading = (grade_depth, grade_linear, cell_far, thickness_far);
        let lattice = make_lattice(py, surface, style, cell, thickness, grading)?;
        let drains = drain_list(py, drains)?;
        let cut = match wall {
            Some(wall) => pgvol::lattices::LatticeCut::Infill { wall },
            None if drains.is_empty() => pgvol::lattices::LatticeCut::Part,
            None => {
                let e =
                    pgvol::Error::parameter("drains need a wall: they open the infill's cavity");
                return Err(errors::to_py(py, e));
            }
        };
        let written = quiet(py, || {
            self.shape
                .write_lattice_3mf(&path, &lattice, cut, &drains, unit)
        })?;
        Ok(Grid { grid: written.grid })
    }

    /// This shape joined with `other`: sharp, or rounded with `radius` (model units). The
    /// result is re-fitted on a grid covering both shapes (grown by the radius) as fine as the
    /// finer of their grids, a distance within 4 spacings of its surface.
    #[pyo3(signature = (other, *, radius=None))]
    fn union(
        &self,
        py: Python<'_>,
        other: &Bound<'_, Field>,
        radius: Option<f32>,
    ) -> PyResult<Field> {
        self.boolean(py, pgvol::BoolOp::Union, other.get(), radius)
    }

    /// What this shape and `other` share, sharp or rounded with `radius`; see `union`.
    #[pyo3(signature = (other, *, radius=None))]
    fn intersection(
        &self,
        py: Python<'_>,
        other: &Bound<'_, Field>,
        radius: Option<f32>,
    ) -> PyResult<Field> {
        self.boolean(py, pgvol::BoolOp::Intersection, other.get(), radius)
    }

    /// This shape less `other`, sharp or rounded with `radius`; see `union`.
    #[pyo3(signature = (other, *, radius=None))]
    fn difference(
        &self,
        py: Python<'_>,
        other: &Bound<'_, Field>,
        radius: Option<f32>,
    ) -> PyResult<Field> {
        self.boolean(py, pgvol::BoolOp::Difference, other.get(), radius)
    }

    /// The Boolean `op` ("union", "intersection", or "difference": the first less the others)
    /// of two or more `operands`, each a Field, an analytic solid ("sphere:cx,cy,cz,r",
    /// "box:cx,cy,cz,hx,hy,hz", "plane:nx,ny,nz,d", "cylinder:px,py,pz,ax,ay,az,r") or the path
    /// of a `.pgv` or mesh file; sharp, or rounded with `radius`. The result is re-fitted on a
    /// cube grid of `res` nodes per axis over `bounds` ((x0, y0, z0), (x1, y1, z1)), by default
    /// the box of every bounded operand grown by the radius; `sign` tells inside from outside
    /// in mesh files.
    #[staticmethod]
    #[pyo3(signature = (operands, op="union", *, radius=None, res=128, bounds=None, sign="auto", progress=None))]
    fn csg(
        py: Python<'_>,
        operands: Vec<Bound<'_, PyAny>>,
        op: &str,
        radius: Option<f32>,
        res: usize,
        bounds: Option<Segment>,
        sign: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let operands = operands
            .iter()
            .map(|o| operand(py, o))
            .collect::<PyResult<Vec<_>>>()?;
        let pgvol::GridSpec::Res(res) = grid_spec(py, Some(res), None)? else {
            unreachable!("a resolution gives a resolution");
        };
        let options = pgvol::CsgOptions {
            op: names::bool_op(py, op)?,
            blend: radius.map_or(pgvol::Blend::Sharp, pgvol::Blend::Round),
            res,
            bounds: bounds.map(|(a, b)| {
                (
                    glam::Vec3::new(a.0, a.1, a.2),
                    glam::Vec3::new(b.0, b.1, b.2),
                )
            }),
            sign: names::sign(py, sign)?,
            ..Default::default()
        };
        let shape = run(py, progress, |p| pgvol::Field::csg(&operands, &options, p))?;
        Ok(Field::from_shape(shape))
    }

    /// An algebraic blend of `primaries` (each as for `csg`: a Field, an analytic solid by
    /// text, or a file): `kind` "liming" (two primaries rounded where they meet, by the cutting
    /// surface `cut`: `(1 − lam)·P₁·P₂ + lam·C²`), "spline" (a functional spline of the
    /// primaries with one or more `bound` surfaces) or "ipatch" (one `bound` per primary; the
    /// weights `weights` (w₁..wₙ then w), or w₁..wₙ with w set so the patch passes `through` a
    /// point, or fitted to points `fit_points`; `continuity` the order of contact, 1 or more).
    /// Bounds are negative on the side of the edge to round. Re-fitted on a cube grid of `res`
    /// nodes per axis over `bounds` ((x0, y0, z0), (x1, y1, z1)), by default the box of the
    /// bounded primaries (needed when none is bounded). See docs/editing.md.
    #[staticmethod]
    #[pyo3(signature = (kind, primaries, *, cut=None, bound=None, lam=0.5, weights=None, through=None, fit_points=None, continuity=1, res=128, bounds=None, sign="auto", progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn blend(
        py: Python<'_>,
        kind: &str,
        primaries: Vec<Bound<'_, PyAny>>,
        cut: Option<Bound<'_, PyAny>>,
        bound: Option<Vec<Bound<'_, PyAny>>>,
        lam: f32,
        weights: Option<Vec<f32>>,
        through: Option<(f64, f64, f64)>,
        fit_points: Option<Vec<(f64, f64, f64)>>,
        continuity: u32,
        res: usize,
        bounds: Option<Segment>,
        sign: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Field> {
        let operands = |list: &[Bound<'_, PyAny>]| {
            list.iter()
                .map(|o| operand(py, o))
                .collect::<PyResult<Vec<_>>>()
        };
        let primaries = operands(&primaries)?;
        let bound = operands(&bound.unwrap_or_default())?;
        let operator = match kind {
            "liming" => pgvol::edit::BlendOperator::Liming {
                cut: match cut {
                    Some(c) => operand(py, &c)?,
                    None => {
                        return Err(errors::parameter(
                            py,
                            "liming needs cut, the cutting surface",
                        ))
                    }
                },
                lambda: lam,
            },
            "spline" => pgvol::edit::BlendOperator::Spline {
                bounds: bound,
                lambda: lam,
            },
            "ipatch" => {
                let point = |p: (f64, f64, f64)| glam::DVec3::new(p.0, p.1, p.2);
                let weights = match (weights, through, fit_points) {
                    (Some(mut w), None, None) if w.len() >= 2 => {
                        let last = w.pop().unwrap_or_default();
                        pgvol::edit::IPatchWeights::Given(w, last)
                    }
                    (Some(w), Some(p), None) => pgvol::edit::IPatchWeights::Through(w, point(p)),
                    (None, None, Some(points)) => {
                        pgvol::edit::IPatchWeights::Fitted(points.into_iter().map(point).collect())
                    }
                    _ => {
                        return Err(errors::parameter(
                            py,
                            "ipatch needs weights (w1..wn, w), weights (w1..wn) with through, \
                             or fit_points",
                        ))
                    }
                };
                pgvol::edit::BlendOperator::IPatch {
                    bounds: bound,
                    weights,
                    continuity: pgvol::edit::Continuity::new(continuity)
                        .map_err(|e| errors::parameter(py, e.to_string()))?,
                }
            }
            other => {
                return Err(errors::parameter(
                    py,
                    format!("unknown blend '{other}' (liming, spline or ipatch)"),
                ))
            }
        };
        let pgvol::GridSpec::Res(res) = grid_spec(py, Some(res), None)? else {
            unreachable!("a resolution gives a resolution");
        };
        let options = pgvol::edit::BlendOptions {
            res,
            bounds: bounds.map(|(a, b)| {
                (
                    glam::Vec3::new(a.0, a.1, a.2),
                    glam::Vec3::new(b.0, b.1, b.2),
                )
            }),
            sign: names::sign(py, sign)?,
            ..Default::default()
        };
        let blended = run(py, progress, |p| {
            pgvol::edit::blend(&primaries, &operator, &options, p)
        })?;
        Ok(Field::from_shape(blended.field))
    }

    /// `a | b`: the sharp union.
    fn __or__(&self, py: Python<'_>, other: &Bound<'_, Field>) -> PyResult<Field> {
        self.boolean(py, pgvol::BoolOp::Union, other.get(), None)
    }

    /// `a & b`: the sharp intersection.
    fn __and__(&self, py: Python<'_>, other: &Bound<'_, Field>) -> PyResult<Field> {
        self.boolean(py, pgvol::BoolOp::Intersection, other.get(), None)
    }

    /// `a - b`: the sharp difference.
    fn __sub__(&self, py: Python<'_>, other: &Bound<'_, Field>) -> PyResult<Field> {
        self.boolean(py, pgvol::BoolOp::Difference, other.get(), None)
    }

    /// The field restored inside `masks` (each six numbers x0, y0, z0, x1, y1, z1, or two
    /// corners): with `face` ("+x", "-x", "+y", "-y", "+z", "-z") a protrusion whose base
    /// crosses that face of the mask is replaced by a smooth cap continuing the body (`alpha`:
    /// the field's normal derivative across the face); with `denoise=True` the field is
    /// resampled with `coarse` samples along the mask's longest side. Coefficients whose support
    /// misses every mask stay bit-identical. With `reports=True`, returns (field, reports), one
    /// MaskReport per mask.
    #[pyo3(signature = (masks, *, face=None, alpha=1.0, denoise=false, coarse=30, reports=false, progress=None))]
    fn repair(
        &self,
        py: Python<'_>,
        masks: Vec<Bound<'_, PyAny>>,
        face: Option<&str>,
        alpha: f32,
        denoise: bool,
        coarse: usize,
        reports: bool,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        let masks = masks
            .iter()
            .map(|m| crate::edit::mask(py, m))
            .collect::<PyResult<Vec<_>>>()?;
        if masks.is_empty() {
            return Err(errors::parameter(py, "give at least one mask"));
        }
        let restore = match (face, denoise) {
            (Some(_), true) => {
                return Err(errors::parameter(
                    py,
                    "give face (protrusion removal) or denoise=True, not both",
                ))
            }
            (Some(face), false) => pgvol::edit::Restore::Protrusion {
                face: names::face(py, face)?,
                alpha,
            },
            (None, true) => pgvol::edit::Restore::Denoise { coarse },
            (None, false) => {
                return Err(errors::parameter(
                    py,
                    "give the face the protrusion's base crosses (e.g. face=\"-z\"), or \
                     denoise=True",
                ))
            }
        };
        let repaired = run(py, progress, |p| self.shape.repair(&masks, restore, p))?;
        let field = Py::new(py, Field::from_shape(repaired.field))?;
        if !reports {
            return Ok(field.into_any());
        }
        let reports = repaired
            .masks
            .into_iter()
            .map(|r| Py::new(py, crate::edit::MaskReport::from(r)))
            .collect::<PyResult<Vec<_>>>()?;
        Ok((field, reports).into_pyobject(py)?.into_any().unbind())
    }

    /// Writes the field for other tools, by the extension of `path`: ".nrrd" or ".npy" the
    /// field sampled on a grid (the stored grid, or `res` nodes along the box's longest side),
    /// ".3mf" a 3MF volumetric level set naming `unit`, ".vdb" an OpenVDB level set (nodes
    /// within `band` voxels of the surface active, as half floats with `half=True`, value
    /// chunks zlib-compressed or raw by `vdb_compression`); with `coefficients=True`, ".nrrd"
    /// holds the coefficients with the basis in its key/value fields. Returns the grid written.
    /// (`band`'s default is `pgvol::limits::VDB_BAND`, spelled out for the signature.)
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (path, *, res=None, coefficients=false, unit="millimeter", band=3.0, half=false, vdb_compression="zip"))]
    fn export(
        &self,
        py: Python<'_>,
        path: PathBuf,
        res: Option<usize>,
        coefficients: bool,
        unit: &str,
        band: f32,
        half: bool,
        vdb_compression: &str,
    ) -> PyResult<Grid> {
        let compression = names::vdb_compression(py, vdb_compression)?;
        let grid = quiet(py, || {
            let options = pgvol::ExportOptions {
                kind: Some(pgvol::ExportKind::from_path(&path, coefficients)?),
                res,
                unit,
                band,
                half,
                compression,
            };
            self.shape.export(&path, &options)
        })?;
        Ok(Grid { grid })
    }

    /// Layers of closed contours `layer_height` apart along `axis`. To slice a `.pgv` file
    /// without loading it whole, `slice_file` gives the same layers.
    #[pyo3(signature = (layer_height, *, axis="z", first=None, resolution=None, tolerance=None, progress=None))]
    fn slice(
        &self,
        py: Python<'_>,
        layer_height: f32,
        axis: &str,
        first: Option<f32>,
        resolution: Option<f32>,
        tolerance: Option<f32>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Vec<Layer>> {
        // Layers are returned in the field's local coordinates, exact only near the origin.
        pgvol::checks::require_near(self.shape.volume().grid.offset, "slicing into arrays")
            .map_err(|e| errors::to_py(py, e))?;
        let settings = names::slice_settings(py, layer_height, axis, first, resolution, tolerance)?;
        let sliced = run(py, progress, |p| self.shape.slice(&settings, p))?;
        Ok(sliced
            .layers
            .into_iter()
            .map(|l| Layer::from_layer(py, l))
            .collect())
    }

    /// Writes the viewer page to `path` (.html), atomically: the surface, lit and turnable, and
    /// an axis-aligned section computed in the browser from the field, in one file that opens
    /// from disk. `section` is (axis, height) in the model's coordinates; `colours` maps
    /// "surface", "section" and "background" to "#rrggbb"; above `max_res` nodes per axis the
    /// page holds the surface and the field resampled onto a coarser grid.
    // max_res: pgvol::view::VIEW_RES, written out so the signature shows it (tests/test_view.py
    // checks it against the command line's default).
    #[pyo3(signature = (path, *, section=None, iso=0.0, colours=None, max_res=256, title=None, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn view(
        &self,
        py: Python<'_>,
        path: PathBuf,
        section: Option<(String, f64)>,
        iso: f32,
        colours: Option<std::collections::HashMap<String, String>>,
        max_res: usize,
        title: Option<String>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<()> {
        let options = crate::view::options(py, section, iso, colours, max_res, title)?;
        run(py, progress, |p| self.shape.write_view(&path, &options, p))
    }

    /// The viewer page in an iframe, as a notebook shows the field.
    fn _repr_html_(&self, py: Python<'_>) -> PyResult<String> {
        let options = pgvol::view::ViewOptions::default();
        let page = quiet(py, || self.shape.view_html(&options, &pgvol::Silent))?;
        Ok(crate::view::iframe(&page))
    }

    /// The grid of the coefficients.
    #[getter]
    fn grid(&self) -> Grid {
        Grid {
            grid: self.shape.volume().grid,
        }
    }

    /// The basis: "bspline3", "bspline2", "trilinear" or "pg-n<N>-r<R>".
    #[getter]
    fn basis(&self) -> String {
        self.shape.volume().basis.to_string()
    }

    /// How the coefficients were fitted ("interp", "iso", "wls").
    #[getter]
    fn fit(&self) -> String {
        self.header.fit.clone()
    }

    /// The recorded distance from the surface within which the stored samples were exact
    /// distances, in mesh units; None when the file records none.
    #[getter]
    fn band(&self) -> Option<f32> {
        self.shape.band()
    }

    /// The distance from the surface within which values are exact distances: the band less
    /// the reach of the basis. Offsets, shells and levels must stay within it.
    #[getter]
    fn exact_band(&self) -> f32 {
        self.shape.exact_band()
    }

    /// The box of the source shape: ((x, y, z) min, (x, y, z) max).
    #[getter]
    #[allow(clippy::type_complexity)]
    fn bounds(&self) -> ((f32, f32, f32), (f32, f32, f32)) {
        let (lo, hi) = self.shape.bounds();
        (lo.into(), hi.into())
    }

    /// The header's key/value metadata.
    #[getter]
    fn metadata(&self) -> BTreeMap<String, String> {
        self.header.metadata.clone()
    }

    fn __repr__(&self) -> String {
        let g = self.shape.volume().grid;
        let [nx, ny, nz] = g.dims;
        let band = match self.shape.band() {
            Some(b) => format!("{b}"),
            None => "None".into(),
        };
        format!(
            "Field(basis={}, dims=({nx}, {ny}, {nz}), spacing={}, band={band})",
            self.shape.volume().basis,
            g.spacing
        )
    }
}

/// (N, 3) query points in world coordinates, refused where not finite or beyond the coordinate
/// range, as the `eval` command refuses them.
fn query_points(points: &Bound<'_, PyAny>) -> PyResult<Vec<glam::DVec3>> {
    let world = arrays::world_points(points, "points")?;
    pgvol::Field::check_query_points(&world).map_err(|e| errors::to_py(points.py(), e))?;
    Ok(world)
}
