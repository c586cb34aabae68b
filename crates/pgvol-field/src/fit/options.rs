//! How a fit finds its coefficients and the settings of its solvers.

use serde::{Deserialize, Serialize};

/// How the coefficients are found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitMethod {
    /// The field equals the SDF at every node.
    Interp,
    /// The paper's choice: each node's collocation point moved to the nearest point of the
    /// isosurface `SDF = q · z_step` (q the nearest integer), `z_step` in grid spacings; `None`
    /// searches for the step with the smallest error near the surface.
    Iso { z_step: Option<f32> },
    /// Weighted least squares: band nodes projected onto the zero surface (weight
    /// `surface_weight`) and onto `±k/2` (`offset_weight`); only coefficients these samples
    /// reach are unknowns, each held to its `Interp` value with weight `node_weight`; the other
    /// coefficients keep their `Interp` values.
    Wls,
}

impl FitMethod {
    pub fn name(self) -> &'static str {
        match self {
            FitMethod::Interp => "interp",
            FitMethod::Iso { .. } => "iso",
            FitMethod::Wls => "wls",
        }
    }
}

/// Solver and sampling settings.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Relative residual at which an iterative solve stops.
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Half-width of the band of nodes that give surface samples to `Wls`, in grid spacings.
    pub band: f32,
    /// `Wls` weights: samples on the zero surface, samples k/2 off it, and the anchor holding
    /// each unknown coefficient to its `Interp` value.
    pub surface_weight: f32,
    pub offset_weight: f32,
    pub node_weight: f32,
    /// Tikhonov damping of the change from the warm start (`Wls`), relative to unit weights.
    pub damping: f64,
    /// `Wls` also stops once an iteration lowers its objective by at most this fraction of what
    /// the iterations so far did: its system is inconsistent, so the data residual never reaches
    /// `tolerance`, and the normal-equation residual left is in directions the fit barely sees.
    pub stall: f64,
    /// Fits tried by the `z_step` search of `Iso`.
    pub z_step_evaluations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            tolerance: 1e-5,
            max_iterations: 400,
            band: 1.5,
            surface_weight: 1.0,
            offset_weight: 0.5,
            // An anchor on each unknown, which damps alternating patterns that node rows would
            // leave free, so it is weaker than node rows were: at 128³ (Chamfer-L1, iterations)
            // 0.1 gave fandisk 0.0056 %, 5; 0.005 gave 0.0051 %, 9; 0.001 gave 0.0050 %, 11.
            node_weight: 0.005,
            damping: 1e-3,
            stall: 0.01,
            z_step_evaluations: 10,
        }
    }
}
