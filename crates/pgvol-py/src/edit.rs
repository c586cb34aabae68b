//! The arguments and results of repairs: masks from Python numbers, and a report per mask.

use pyo3::prelude::*;

use crate::errors;

/// A repair mask from six numbers `x0, y0, z0, x1, y1, z1` or from
/// `((x0, y0, z0), (x1, y1, z1))`; the library checks the box against the grid.
pub(crate) fn mask(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<pgvol::edit::Mask> {
    let numbers: Vec<f32> = match obj.extract::<Vec<f32>>() {
        Ok(v) => v,
        Err(_) => {
            let (lo, hi) = obj
                .extract::<((f32, f32, f32), (f32, f32, f32))>()
                .map_err(|_| {
                    errors::parameter(
                        py,
                        "a mask is (x0, y0, z0, x1, y1, z1) or ((x0, y0, z0), (x1, y1, z1))",
                    )
                })?;
            vec![lo.0, lo.1, lo.2, hi.0, hi.1, hi.2]
        }
    };
    if numbers.len() != 6 {
        return Err(errors::parameter(
            py,
            format!(
                "a mask: expected six numbers x0,y0,z0,x1,y1,z1, got {}",
                numbers.len()
            ),
        ));
    }
    Ok(pgvol::edit::Mask {
        lo: glam::Vec3::new(numbers[0], numbers[1], numbers[2]),
        hi: glam::Vec3::new(numbers[3], numbers[4], numbers[5]),
    })
}

/// What a repair did inside one mask.
#[pyclass(frozen, get_all, module = "pgvol")]
pub(crate) struct MaskReport {
    /// Grid nodes whose values were restored.
    pub(crate) nodes: usize,
    /// Iterations of the Laplace fill (0 when denoising).
    pub(crate) iterations: usize,
    /// Coefficients the local re-fit may have changed.
    pub(crate) coefficients: usize,
    /// The largest difference between the re-fitted field and the restored values at the
    /// mask's nodes.
    pub(crate) fit_error: f32,
}

impl From<pgvol::edit::MaskReport> for MaskReport {
    fn from(r: pgvol::edit::MaskReport) -> Self {
        MaskReport {
            nodes: r.nodes,
            iterations: r.iterations,
            coefficients: r.refit.coefficients,
            fit_error: r.refit.max_error,
        }
    }
}

#[pymethods]
impl MaskReport {
    fn __repr__(&self) -> String {
        format!(
            "MaskReport(nodes={}, iterations={}, coefficients={}, fit_error={})",
            self.nodes, self.iterations, self.coefficients, self.fit_error
        )
    }
}
