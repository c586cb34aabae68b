//! The slides' blends between primaries — Liming rounding, functional splines and I-patches —
//! re-fitted into one coefficient volume, renormalised near the surface.

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume};
use pgvol_sdf::SignMode;

use crate::csg::{check_edit_memory, covering_grid, load_operands, operand_fields, ResultUse};
use crate::encode::ENCODE_BAND;
use crate::error::{Error, Result};
use crate::operand::{Operand, OperandField};
use crate::progress::Progress;

/// Default blend parameter λ of Liming rounding and functional splines.
pub const DEFAULT_LAMBDA: f32 = 0.5;

/// Exact distances this many spacings from file and mesh operands, beyond the usual band: the
/// blends read their operands well away from the operands' own surfaces.
const BLEND_REACH: f32 = 8.0;

/// Which blend, with its own operands.
#[derive(Clone, Debug)]
pub enum BlendOperator {
    /// `(1 − λ)·P₁·P₂ + λ·C²` with the cutting surface `C` (negative on the edge's side).
    Liming {
        /// The cutting surface.
        cut: Operand,
        /// λ in (0, 1): larger moves the blend away from the edge.
        lambda: f32,
    },
    /// `(1 − λ)·P₁·P₂ + λ·B₁²·B₂²` with one bound per primary.
    Spline {
        /// One bound per primary.
        bounds: [Operand; 2],
        /// λ in (0, 1).
        lambda: f32,
    },
    /// `Σ wᵢ Pᵢ Π_{j≠i} Bⱼ² + w·ΠBᵢ²`, one bound per primary; the weights given, or fitted by
    /// least squares to `points` on the wanted surface (first weight 1).
    IPatch {
        /// One bound per primary.
        bounds: Vec<Operand>,
        /// `w₁..wₙ` and `w`, when given.
        weights: Option<(Vec<f32>, f32)>,
        /// Points on the wanted surface (world coordinates, as [`crate::read_points`] gives
        /// them), to fit the weights when not given.
        points: Vec<glam::DVec3>,
    },
}

/// Grid and box of a blend's result.
#[derive(Clone, Copy, Debug)]
pub struct BlendSettings {
    /// Grid nodes per axis (default [`crate::CSG_RES`]).
    pub res: usize,
    /// The box the result covers; by default that of the bounded primaries.
    pub bounds: Option<(Vec3, Vec3)>,
    /// How inside is told from outside in mesh primaries (default [`SignMode::Auto`]).
    pub sign: SignMode,
    /// What becomes of the result, for the memory estimate (default kept as a volume).
    pub result: ResultUse,
}

impl Default for BlendSettings {
    fn default() -> Self {
        BlendSettings {
            res: crate::CSG_RES,
            bounds: None,
            sign: SignMode::Auto,
            result: ResultUse::Volume,
        }
    }
}

/// The blend, and for I-patches the weights used (`w₁..wₙ`, `w`).
#[derive(Clone, Debug)]
pub struct Blended {
    /// The re-fitted field.
    pub volume: CoefficientVolume,
    /// The I-patch's weights.
    pub weights: Option<(Vec<f32>, f32)>,
}

fn check_lambda(lambda: f32) -> Result<()> {
    if !(lambda > 0.0 && lambda < 1.0) {
        return Err(Error::parameter(format!(
            "lambda must lie strictly between 0 and 1, got {lambda}"
        )));
    }
    Ok(())
}

/// The blend of `primaries` (two for Liming and functional splines, two or more for
/// I-patches), renormalised to a distance-like field near its surface and re-fitted in the
/// cubic B-spline brick by brick.
pub fn blend(
    primaries: &[Operand],
    operator: &BlendOperator,
    settings: &BlendSettings,
    progress: &dyn Progress,
) -> Result<Blended> {
    let extra: Vec<Operand> = match operator {
        BlendOperator::Liming { cut, lambda } => {
            check_lambda(*lambda)?;
            vec![cut.clone()]
        }
        BlendOperator::Spline { bounds, lambda } => {
            check_lambda(*lambda)?;
            bounds.to_vec()
        }
        BlendOperator::IPatch {
            bounds, weights, ..
        } => {
            pgvol_ops::check_ipatch(
                primaries.len(),
                bounds.len(),
                weights.as_ref().map(|w| w.0.len()),
            )
            .map_err(crate::csg::ops_error)?;
            bounds.clone()
        }
    };
    let needed = match operator {
        BlendOperator::IPatch { .. } => primaries.len().max(2),
        _ => 2,
    };
    // Liming has its one cutting surface; the others one bound per primary.
    let wanted_extra = match operator {
        BlendOperator::Liming { .. } => 1,
        _ => needed,
    };
    if primaries.len() != needed || extra.len() != wanted_extra {
        return Err(Error::parameter(format!(
            "this blend needs {needed} primaries{}, got {} primaries and {} bounds",
            match operator {
                BlendOperator::Liming { .. } => " and one cutting surface".to_string(),
                _ => format!(" and {needed} bounds"),
            },
            primaries.len(),
            extra.len()
        )));
    }
    let all: Vec<Operand> = primaries.iter().chain(&extra).cloned().collect();
    let loaded = load_operands(&all)?;
    let grid = covering_grid(
        &loaded[..primaries.len()],
        settings.bounds,
        0.0,
        settings.res,
    )?;
    let reach = BLEND_REACH * grid.spacing;
    check_edit_memory("a blend", &loaded, &grid, reach, settings.result)?;
    let fields = operand_fields(&all, &loaded, grid, reach, settings.sign, progress)?;
    let (prim, rest) = fields.split_at(primaries.len());
    let value =
        |f: &[OperandField], p: Vec3| -> Vec<f32> { f.iter().map(|x| x.value(p)).collect() };
    let weights = match operator {
        BlendOperator::IPatch {
            weights: Some(w), ..
        } => {
            if w.0.len() != prim.len() || w.0.iter().chain([&w.1]).any(|x| !x.is_finite()) {
                return Err(Error::parameter(format!(
                    "an I-patch of {} primaries needs {} finite weights and w, got {}",
                    prim.len(),
                    prim.len(),
                    w.0.len()
                )));
            }
            Some(w.clone())
        }
        BlendOperator::IPatch { points, .. } => {
            let terms: Vec<Vec<f64>> = points
                .iter()
                // Operands are near the origin (far ones are refused), so world is local.
                .map(|&p| p.as_vec3())
                .map(|p| pgvol_ops::ipatch_terms(&value(prim, p), &value(rest, p)))
                .collect();
            Some(pgvol_ops::fit_ipatch_weights(&terms).map_err(crate::csg::ops_error)?)
        }
        _ => None,
    };
    progress.stage("blending");
    let step = 0.5 * grid.spacing;
    let raw = |p: Vec3| -> f32 {
        let (pv, bv) = (value(prim, p), value(rest, p));
        match operator {
            BlendOperator::Liming { lambda, .. } => pgvol_ops::liming(pv[0], pv[1], bv[0], *lambda),
            BlendOperator::Spline { lambda, .. } => {
                pgvol_ops::functional_spline([pv[0], pv[1]], [bv[0], bv[1]], *lambda)
            }
            BlendOperator::IPatch { .. } => {
                let (w, w0) = weights.as_ref().expect("weights set above");
                pgvol_ops::ipatch(&pv, &bv, w, *w0)
            }
        }
    };
    let field = |p: Vec3| -> f32 {
        match operator {
            BlendOperator::IPatch { .. } => pgvol_ops::renormalised(&raw, p, step),
            _ => {
                let (pv, bv) = (value(prim, p), value(rest, p));
                let region = bv.iter().all(|&b| b < 0.0);
                pgvol_ops::edge_blend(pv[0], pv[1], region, || {
                    pgvol_ops::renormalised(&raw, p, step)
                })
            }
        }
    };
    let band = ENCODE_BAND * grid.spacing;
    // Renormalised fields are distances only near their surface: a generous constant keeps
    // bricks the surface crosses from being skipped.
    let volume = pgvol_ops::sample_bricks(grid, Basis::Bspline3, band, 3.0, field)
        .map_err(crate::csg::ops_error)?;
    crate::progress::check(progress)?;
    Ok(Blended { volume, weights })
}
