//! The perturbation method's result as a [`Field`]: the function list resampled on a grid.
//! Apart from `perturb.rs`, which the `.pgv` reader uses to resample perturbation files.

use pgvol_core::Mesh;

use crate::error::Result;
use crate::field_value::Field;
use crate::grid::GridSpec;
use crate::perturb::{perturb_on, resample};
use crate::perturbation::PerturbOptions;
use crate::progress::Progress;

impl Field {
    /// `mesh` converted by the perturbation method and checked on the grid `grid` gives for
    /// it ([`perturb_on`]), then resampled there ([`resample`]). The function list and the
    /// conversion's report come from those two.
    pub fn perturb(
        mesh: &Mesh,
        options: &PerturbOptions,
        grid: GridSpec,
        progress: &dyn Progress,
    ) -> Result<Field> {
        let built = perturb_on(mesh, options, grid, progress)?;
        Ok(Field::from_file(resample(
            &built.field,
            mesh,
            grid,
            progress,
        )?))
    }
}
