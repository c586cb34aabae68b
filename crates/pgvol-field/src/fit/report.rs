//! What a fit reports: its solver's outcome and where the time went.

use serde::{Deserialize, Serialize};

use super::solve;

/// What a fit did and how well its solver did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    pub method: String,
    /// `"prefilter"`, `"cg"`, `"cgls"` or `"none"`.
    pub solver: String,
    /// Iterations of the last solve (0 for the direct prefilter).
    pub iterations: usize,
    /// Relative residual `‖A c − b‖ / ‖b‖` of the (weighted) system at the end.
    pub residual: f64,
    pub converged: bool,
    pub seconds: f64,
    /// Nodes farther than one spacing from the surface where the field's sign disagrees with
    /// the SDF's: extra surface pieces.
    pub spurious_sign_changes: usize,
    /// The isosurface step used by `Iso`, in grid spacings.
    pub z_step: Option<f32>,
    /// Relative residual of the warm start, for iterative fits that have one (`Wls`): the solve
    /// took it to `residual`.
    #[serde(default)]
    pub initial_residual: Option<f64>,
    /// The normal-equation residual at the end relative to its start (least-squares solves).
    #[serde(default)]
    pub normal_residual: Option<f64>,
    /// Unknown coefficients and sample rows of the solve (0 for direct fits).
    #[serde(default)]
    pub unknowns: usize,
    #[serde(default)]
    pub rows: usize,
    /// Where the time went, in seconds.
    #[serde(default)]
    pub stages: FitStages,
}

/// Seconds per stage of a fit; stages a fit does not have stay 0.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FitStages {
    /// Interpolating the node samples (the fit itself for `Interp`, the warm start otherwise).
    pub warm_start: f64,
    /// Closest points and offset distances for the sample rows.
    pub projections: f64,
    /// Finding the unknowns and the preconditioner.
    pub setup: f64,
    pub solve: f64,
    /// Counting spurious sign changes.
    pub check: f64,
}

pub(crate) fn report(solver: &str, outcome: Option<solve::SolveOutcome>) -> FitReport {
    let o = outcome.unwrap_or(solve::SolveOutcome {
        iterations: 0,
        residual: 0.0,
        normal_residual: 0.0,
        converged: true,
    });
    FitReport {
        method: String::new(),
        solver: solver.to_string(),
        iterations: o.iterations,
        residual: o.residual,
        converged: o.converged,
        seconds: 0.0,
        spurious_sign_changes: 0,
        z_step: None,
        initial_residual: None,
        normal_residual: None,
        unknowns: 0,
        rows: 0,
        stages: FitStages::default(),
    }
}
