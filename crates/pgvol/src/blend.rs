//! The slides' blends between primaries — Liming rounding, functional splines and I-patches —
//! re-fitted into one coefficient volume, renormalised near the surface.

use glam::Vec3;
use pgvol_field::Basis;
use pgvol_sdf::SignMode;

use crate::csg::{check_edit_memory, covering_grid, load_operands, operand_fields, ResultUse};
use crate::encode::ENCODE_BAND;
use crate::error::{Error, Result};
use crate::field_value::Field;
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
    /// `(1 − λ)·ΠPᵢ + λ·ΠBⱼ²` of two or more primaries with one or more bounds (the slides'
    /// n primaries and m bounds; the usual form has one bound per primary).
    Spline {
        /// The bounds, negative on the side of the edge to round.
        bounds: Vec<Operand>,
        /// λ in (0, 1).
        lambda: f32,
    },
    /// `Σ wᵢ Pᵢ Π_{j≠i} Bⱼᵉ + w·ΠBᵢᵉ`, one bound per primary, `e = n + 1` for Gⁿ continuity
    /// with the primaries along the boundary curves.
    IPatch {
        /// One bound per primary.
        bounds: Vec<Operand>,
        /// How the weights are set.
        weights: IPatchWeights,
        /// The order n of the continuity, G¹ (squared bounds) by default.
        continuity: pgvol_ops::Continuity,
    },
}

/// How an I-patch's weights are set.
#[derive(Clone, Debug)]
pub enum IPatchWeights {
    /// `w₁..wₙ` and `w` as given.
    Given(Vec<f32>, f32),
    /// Least squares of the patch at points on the wanted surface (world coordinates, as
    /// [`crate::read_points`] gives them), with `w₁ = 1`.
    Fitted(Vec<glam::DVec3>),
    /// `w₁..wₙ` as given and `w` from the one-point formula, so that the patch passes through
    /// the point (world coordinates).
    Through(Vec<f32>, glam::DVec3),
}

/// Grid and box of a blend's result.
#[derive(Clone, Copy, Debug)]
pub struct BlendOptions {
    /// Grid nodes per axis (default [`crate::csg::CSG_RES`]).
    pub res: usize,
    /// The box the result covers; by default that of the bounded primaries.
    pub bounds: Option<(Vec3, Vec3)>,
    /// How inside is told from outside in mesh primaries (default [`SignMode::Auto`]).
    pub sign: SignMode,
    /// What becomes of the result, for the memory estimate (default kept as a volume).
    pub result: ResultUse,
}

impl Default for BlendOptions {
    fn default() -> Self {
        BlendOptions {
            res: crate::csg::CSG_RES,
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
    pub field: Field,
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

impl Field {
    /// This field blended with `other` by `operator` on the grid `settings` gives; see
    /// [`blend`].
    pub fn blend(
        &self,
        other: &Field,
        operator: &BlendOperator,
        settings: &BlendOptions,
        progress: &dyn Progress,
    ) -> Result<Blended> {
        let operands = [Operand::from(self.clone()), Operand::from(other.clone())];
        blend(&operands, operator, settings, progress)
    }
}

/// The blend of `primaries` (two for Liming, two or more for functional splines and
/// I-patches), renormalised to a distance-like field near its surface and re-fitted in the
/// cubic B-spline brick by brick.
pub fn blend(
    primaries: &[Operand],
    operator: &BlendOperator,
    settings: &BlendOptions,
    progress: &dyn Progress,
) -> Result<Blended> {
    let extra = check_operands(primaries, operator)?;
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
            weights,
            continuity,
            ..
        } => {
            let terms = |p: glam::DVec3| {
                // Operands are near the origin (far ones are refused), so world is local.
                let p = p.as_vec3();
                let f64s = |f: &[OperandField]| -> Vec<f64> {
                    f.iter().map(|x| x.value(p) as f64).collect()
                };
                pgvol_ops::ipatch_terms(&f64s(prim), &f64s(rest), *continuity)
            };
            Some(ipatch_weights(weights, prim.len(), terms)?)
        }
        _ => None,
    };
    // Only I-patches read these.
    let (w, w0) = weights.clone().unwrap_or_default();
    progress.stage("blending");
    let step = 0.5 * grid.spacing;
    let raw = |p: Vec3| -> f32 {
        let (pv, bv) = (value(prim, p), value(rest, p));
        match operator {
            BlendOperator::Liming { lambda, .. } => pgvol_ops::liming(pv[0], pv[1], bv[0], *lambda),
            BlendOperator::Spline { lambda, .. } => pgvol_ops::functional_spline(&pv, &bv, *lambda),
            BlendOperator::IPatch { continuity, .. } => {
                pgvol_ops::ipatch(&pv, &bv, &w, w0, *continuity)
            }
        }
    };
    let clip = crate::csg::clip_box(&loaded[..primaries.len()], settings.bounds);
    let field = |p: Vec3| -> f32 {
        let blended = match operator {
            BlendOperator::IPatch { .. } => pgvol_ops::renormalised(&raw, p, step),
            _ => {
                let (pv, bv) = (value(prim, p), value(rest, p));
                let region = bv.iter().all(|&b| b < 0.0);
                pgvol_ops::edge_blend(&pv, region, || pgvol_ops::renormalised(&raw, p, step))
            }
        };
        crate::csg::clipped(blended, p, clip)
    };
    let band = ENCODE_BAND * grid.spacing;
    // Renormalised fields are distances only near their surface: a generous constant keeps
    // bricks the surface crosses from being skipped.
    let volume = pgvol_ops::sample_bricks(grid, Basis::Bspline3, band, 3.0, field)
        .map_err(crate::csg::ops_error)?;
    crate::progress::check(progress)?;
    let name = match operator {
        BlendOperator::Liming { .. } => "blend liming",
        BlendOperator::Spline { .. } => "blend spline",
        BlendOperator::IPatch { .. } => "blend ipatch",
    };
    let band = ENCODE_BAND * volume.grid.spacing;
    Ok(Blended {
        field: Field::edited(volume, name, band),
        weights,
    })
}

/// Refuses operands that do not fit the blend; returns its operands besides the primaries.
fn check_operands(primaries: &[Operand], operator: &BlendOperator) -> Result<Vec<Operand>> {
    match operator {
        BlendOperator::Liming { cut, lambda } => {
            check_lambda(*lambda)?;
            if primaries.len() != 2 {
                return Err(Error::parameter(format!(
                    "Liming rounding needs 2 primaries and one cutting surface, got {} primaries",
                    primaries.len()
                )));
            }
            Ok(vec![cut.clone()])
        }
        BlendOperator::Spline { bounds, lambda } => {
            check_lambda(*lambda)?;
            pgvol_ops::check_spline(primaries.len(), bounds.len())
                .map_err(crate::csg::ops_error)?;
            Ok(bounds.clone())
        }
        BlendOperator::IPatch {
            bounds, weights, ..
        } => {
            let given = match weights {
                IPatchWeights::Given(w, _) | IPatchWeights::Through(w, _) => Some(w.len()),
                IPatchWeights::Fitted(_) => None,
            };
            pgvol_ops::check_ipatch(primaries.len(), bounds.len(), given)
                .map_err(crate::csg::ops_error)?;
            Ok(bounds.clone())
        }
    }
}

/// The I-patch's `w₁..wₙ` and `w`; `terms` gives [`pgvol_ops::ipatch_terms`] at a point.
fn ipatch_weights(
    weights: &IPatchWeights,
    primaries: usize,
    terms: impl Fn(glam::DVec3) -> Vec<f64>,
) -> Result<(Vec<f32>, f32)> {
    let finite = |w: &[f32]| w.iter().all(|x| x.is_finite());
    match weights {
        IPatchWeights::Given(w, w0) => {
            if w.len() != primaries || !finite(w) || !w0.is_finite() {
                return Err(Error::parameter(format!(
                    "an I-patch of {primaries} primaries needs {primaries} finite weights and w, \
                     got {}",
                    w.len()
                )));
            }
            Ok((w.clone(), *w0))
        }
        IPatchWeights::Fitted(points) => {
            let terms: Vec<Vec<f64>> = points.iter().map(|&p| terms(p)).collect();
            pgvol_ops::fit_ipatch_weights(&terms).map_err(crate::csg::ops_error)
        }
        IPatchWeights::Through(w, point) => {
            let limit = f64::from(pgvol_mesh::MAX_COORDINATE);
            if !point.is_finite() || point.abs().max_element() >= limit {
                return Err(Error::parameter(format!(
                    "the point the patch passes through must be finite and within {limit:e} of \
                     the origin, got {point}"
                )));
            }
            let w0 = pgvol_ops::weight_through_point(&terms(*point), w)
                .map_err(crate::csg::ops_error)?;
            Ok((w.clone(), w0))
        }
    }
}
