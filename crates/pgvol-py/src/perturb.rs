//! `pgvol.perturb`: a mesh converted into a base quadric plus local bumps (the perturbation
//! method, `docs/perturbation.md`), returned resampled as a [`Field`] with the conversion's
//! report, and optionally its function list written as a `.pgv` file.

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::arrays;
use crate::field::Field;
use crate::progress::run;
use crate::reports::PerturbReport;

/// Converts the mesh (vertices, faces) by the perturbation method: a base quadric fitted to the
/// vertices, then up to `max_functions` local bumps until every vertex is within `tolerance` of
/// the bounding-box diagonal, each refined by up to `descent_steps` steps of descent on its
/// coefficients (the paper's optimisation step), checked on the cube grid of `res` nodes per axis so that the
/// field contoured there has the mesh's pieces and no stray ones. Returns the field resampled
/// on that grid (a cubic B-spline coefficient volume, metadata `source = perturbation`) and the
/// report: `perturbation` (the loop), `cleanup` and `strays` (the checks). With
/// `list_path`, the function list itself is also written there (a `.pgv` file, encoding
/// `perturbation-f64`, resampled on the same grid when read).
#[pyfunction]
#[pyo3(signature = (vertices, faces, *, max_functions=2000, tolerance=0.001, descent_steps=20, res=128, list_path=None, progress=None))]
pub(crate) fn perturb<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    max_functions: usize,
    tolerance: f64,
    descent_steps: usize,
    res: usize,
    list_path: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Field, PerturbReport)> {
    let positions = arrays::world_points(vertices, "vertices")?;
    let triangles = arrays::faces(faces)?;
    let options = pgvol::perturbation::PerturbOptions {
        max_functions,
        tolerance,
        descent_steps,
    };
    let spec = pgvol::GridSpec::Res(res);
    let (file, report) = run(py, progress, |p| {
        let mesh = pgvol::io::mesh_from_world(&positions, triangles)?.mesh;
        let built = pgvol::perturbation::perturb_on(&mesh, &options, spec, p)?;
        if let Some(path) = &list_path {
            let header = pgvol::perturbation::perturbation_header(&built.field, &mesh, spec)?;
            pgvol::perturbation::write_perturbation(path, &header, &built.field)?;
        }
        let file = pgvol::perturbation::resample(&built.field, &mesh, spec, p)?;
        let report = PerturbReport::new(built.report, built.cleanup, built.strays);
        Ok((file, report))
    })?;
    Ok((Field::from_file(file), report))
}

// Python signatures show literal defaults only; these are the library's.
const _: () = assert!(pgvol::limits::DEFAULT_RES == 128);
const _: () = assert!(pgvol::perturbation::DESCENT_STEPS == 20);
