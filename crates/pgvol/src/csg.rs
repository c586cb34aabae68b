//! Booleans of two or more operands, sharp or rounded, re-fitted into one coefficient volume on
//! a grid covering all of them.

use glam::Vec3;
use pgvol_core::Grid;
use pgvol_field::{Basis, CoefficientVolume};
use pgvol_ops::{Blend, BoolOp};
use pgvol_sdf::SignMode;

use crate::emptiness::{require_surface, IfEmpty, Sides};
use crate::encode::ENCODE_BAND;
use crate::error::{Error, Result};
use crate::field_value::Field;
use crate::operand::{LoadedOperand, Operand, OperandField};
use crate::progress::Progress;

/// An operation's refusal of a parameter as a facade error carrying the message once.
pub(crate) fn ops_error(e: pgvol_ops::OpsError) -> Error {
    match e {
        pgvol_ops::OpsError::BadParameter(message) => Error::parameter(message),
        other => other.into(),
    }
}

/// Grid nodes per axis of a Boolean's result, unless given.
pub const CSG_RES: usize = 128;

/// What the caller does with an edit's result, so that the memory estimate made before any
/// work counts it too.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ResultUse {
    /// Kept as the sparse coefficient volume returned.
    #[default]
    Volume,
    /// Written as a sparse file: the stored bricks around the surface, quantised and
    /// compressed, as [`crate::StorageOptions::default`] writes them.
    File,
    /// Written dense: every coefficient of the grid as f32.
    DenseFile,
    /// Contoured into a mesh on its own grid.
    Mesh,
}

/// Refuses an edit on `grid` whose estimated peak would exceed the memory limit, before any
/// operand is placed on the grid: the operands' fields, the brick-by-brick sampling of the
/// whole grid with the bricks near the surface (estimated from the operands' areas), and what
/// `result` adds.
pub(crate) fn check_edit_memory(
    job: &str,
    operands: &[LoadedOperand],
    grid: &Grid,
    reach: f32,
    result: ResultUse,
) -> Result<()> {
    let bricks = grid.dims.iter().fold(1u64, |n, &d| {
        n.saturating_mul(d.div_ceil(pgvol_core::BRICK_EDGE) as u64)
    });
    let area: f64 = operands.iter().map(|o| o.surface_area(grid)).sum();
    let near = crate::memory::band_bricks(area, grid.spacing, ENCODE_BAND).min(bricks);
    let fields = operands
        .iter()
        .fold(0u64, |n, o| n.saturating_add(o.field_bytes(grid, reach)));
    let sampling = bricks
        .saturating_mul(crate::memory::BYTES_PER_SAMPLED_BRICK)
        .saturating_add(near.saturating_mul(crate::memory::BYTES_PER_BAND_BRICK));
    let output = match result {
        ResultUse::Volume => 0,
        ResultUse::File => crate::memory::sparse_file_bytes(bricks, near),
        ResultUse::DenseFile => {
            crate::memory::grid_bytes(grid.len(), crate::memory::BYTES_PER_DENSE_FILE_NODE)
        }
        ResultUse::Mesh => near.saturating_mul(crate::memory::BYTES_PER_CONTOUR_BRICK),
    };
    let [nx, ny, nz] = grid.dims;
    crate::memory::check_memory(
        &format!("{job} on a {nx} x {ny} x {nz} grid"),
        fields.saturating_add(sampling).saturating_add(output),
        "lower the resolution",
    )
}

/// What to compute.
#[derive(Clone, Copy, Debug)]
pub struct CsgOptions {
    /// Union, intersection or difference (the first operand less the others).
    pub op: BoolOp,
    /// Sharp, or rounded with a radius in model units.
    pub blend: Blend,
    /// Grid nodes per axis of the result (default [`CSG_RES`]).
    pub res: usize,
    /// The box the result's grid covers (grown as [`Grid::cube_res`] grows it); by default the
    /// box of every bounded operand, grown by the blend radius. Needed when no operand is
    /// bounded (planes, cylinders).
    pub bounds: Option<(Vec3, Vec3)>,
    /// How inside is told from outside in mesh operands (default [`SignMode::Auto`]).
    pub sign: SignMode,
    /// What becomes of the result, for the memory estimate (default kept as a volume).
    pub result: ResultUse,
}

impl Default for CsgOptions {
    fn default() -> Self {
        CsgOptions {
            op: BoolOp::Union,
            blend: Blend::Sharp,
            res: CSG_RES,
            bounds: None,
            sign: SignMode::Auto,
            result: ResultUse::Volume,
        }
    }
}

/// The operation's name as recorded in the result's file.
fn csg_name(settings: &CsgOptions) -> String {
    let op = match settings.op {
        BoolOp::Union => "union",
        BoolOp::Intersection => "intersection",
        BoolOp::Difference => "difference",
    };
    match settings.blend {
        Blend::Sharp => op.to_string(),
        Blend::Round(r) => format!("{op} radius {r}"),
    }
}

/// The grid every operand is placed on: a cube over `bounds`, or else over the bounded
/// operands, grown by `grow`.
pub(crate) fn covering_grid(
    operands: &[LoadedOperand],
    bounds: Option<(Vec3, Vec3)>,
    grow: f32,
    res: usize,
) -> Result<Grid> {
    let (lo, hi) = match bounds {
        Some(b) => b,
        None => operands
            .iter()
            .filter_map(LoadedOperand::bounds)
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
            .ok_or_else(|| {
                Error::parameter(
                    "no operand is bounded (planes and cylinders are infinite); give the box \
                     the result should cover",
                )
                .with_remedy(crate::error::Remedy::CoveringBox)
            })?,
    };
    if !(lo.is_finite() && hi.is_finite()) || (hi - lo).min_element() < 0.0 {
        return Err(Error::parameter(format!(
            "the box must be finite with its second corner above the first, got {lo} to {hi}"
        )));
    }
    Ok(Grid::cube_res(lo - grow, hi + grow, res)?)
}

/// Reads the operands: `.pgv` files and meshes by extension, primaries as given.
pub(crate) fn load_operands(operands: &[Operand]) -> Result<Vec<LoadedOperand>> {
    operands
        .iter()
        .map(|o| {
            LoadedOperand::load(o).map_err(|e| match (o, e.path()) {
                (Operand::File(path), None) => e.at(path),
                _ => e,
            })
        })
        .collect()
}

/// Places the operands on `grid` as fields with exact distances `reach` out.
pub(crate) fn operand_fields(
    operands: &[Operand],
    loaded: &[LoadedOperand],
    grid: Grid,
    reach: f32,
    sign: SignMode,
    progress: &dyn Progress,
) -> Result<Vec<OperandField>> {
    operands
        .iter()
        .zip(loaded)
        .map(|(o, l)| {
            l.field(grid, reach, sign, progress)
                .map_err(|e| match (o, e.path()) {
                    (Operand::File(path), None) => e.at(path),
                    _ => e,
                })
        })
        .collect()
}

impl Field {
    /// The Boolean of the operands (the first less the others for a difference), re-fitted in
    /// the cubic B-spline on one grid covering all, brick by brick. The result is a distance
    /// within [`ENCODE_BAND`] spacings of its surface where the operands are, bounded as
    /// [`pgvol_ops::union`] documents in the blends.
    pub fn csg(
        operands: &[Operand],
        options: &CsgOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        let volume = csg(operands, options, progress)?;
        let band = ENCODE_BAND * volume.grid.spacing;
        Ok(Field::edited(volume, &csg_name(options), band))
    }

    /// This shape joined with `other`, sharp or rounded by `blend`; see [`Field::boolean`].
    pub fn union(&self, other: &Field, blend: Blend) -> Result<Field> {
        self.boolean(BoolOp::Union, other, blend)
    }

    /// What this shape and `other` share, sharp or rounded by `blend`; see [`Field::boolean`].
    pub fn intersection(&self, other: &Field, blend: Blend) -> Result<Field> {
        self.boolean(BoolOp::Intersection, other, blend)
    }

    /// This shape less `other`, sharp or rounded by `blend`; see [`Field::boolean`].
    pub fn difference(&self, other: &Field, blend: Blend) -> Result<Field> {
        self.boolean(BoolOp::Difference, other, blend)
    }

    /// The Boolean `op` of this field and `other` on a grid covering both (grown by a rounding
    /// radius) as fine as the finer of their grids; see [`Field::csg`] to choose the grid.
    pub fn boolean(&self, op: BoolOp, other: &Field, blend: Blend) -> Result<Field> {
        let radius = match blend {
            Blend::Sharp => 0.0,
            Blend::Round(r) => r,
        };
        let (a, b) = (self.bounds, other.bounds);
        let (lo, hi) = (a.0.min(b.0) - radius, a.1.max(b.1) + radius);
        let spacing = self.grid().spacing.min(other.grid().spacing);
        // A cube grid of N nodes spans 1.1 × the longest side in N - 1 spacings.
        let nodes = (1.1 * (hi - lo).max_element() / spacing).ceil() as usize + 1;
        let options = CsgOptions {
            op,
            blend,
            res: nodes.clamp(crate::grid::MIN_RES as usize, crate::grid::MAX_RES as usize),
            bounds: Some((a.0.min(b.0), a.1.max(b.1))),
            ..CsgOptions::default()
        };
        let operands = [Operand::from(self.clone()), Operand::from(other.clone())];
        Field::csg(&operands, &options, &crate::progress::Silent)
    }
}

/// See [`Field::csg`].
fn csg(
    operands: &[Operand],
    settings: &CsgOptions,
    progress: &dyn Progress,
) -> Result<CoefficientVolume> {
    if operands.len() < 2 {
        return Err(Error::parameter(format!(
            "a Boolean needs two or more operands, got {}",
            operands.len()
        )));
    }
    let volume = combine_operands("a Boolean", operands, settings, ENCODE_BAND, progress)?;
    let (result, no_inside) = match settings.op {
        BoolOp::Union => (
            "the union",
            "no operand has an inside within the box the result covers",
        ),
        BoolOp::Intersection => (
            "the intersection",
            "the operands do not overlap, or overlap by less than the grid spacing; operands \
             that share a volume, or a finer grid for a thin overlap, give a non-empty one",
        ),
        BoolOp::Difference => (
            "the difference",
            "the other operands cover all of the first, or all but slivers thinner than the \
             grid spacing; subtract less, or use a finer grid for thin slivers",
        ),
    };
    let why = IfEmpty {
        result,
        no_inside,
        no_outside: "it fills the whole box it covers; a box larger than the result gives it \
                     a surface",
    };
    require_surface(Sides::of_volume(&volume), &why)?;
    Ok(volume)
}

/// The box unbounded operands are cut at: the given `bounds` when some operand (a plane, a
/// cylinder) has no bounds of its own, so the result ends at the box asked for rather than at
/// the grid's wider cube. Bounded operands lie within their box already and are not cut.
pub(crate) fn clip_box(
    operands: &[LoadedOperand],
    bounds: Option<(Vec3, Vec3)>,
) -> Option<(Vec3, Vec3)> {
    bounds.filter(|_| operands.iter().any(|o| o.bounds().is_none()))
}

/// `value` cut at the box `clip`, when there is one: the larger of it and the box's distance.
pub(crate) fn clipped(value: f32, p: Vec3, clip: Option<(Vec3, Vec3)>) -> f32 {
    let Some((lo, hi)) = clip else {
        return value;
    };
    let q = (p - 0.5 * (lo + hi)).abs() - 0.5 * (hi - lo);
    let box_distance = q.max(Vec3::ZERO).length() + q.max_element().min(0.0);
    value.max(box_distance)
}

/// The operands placed on one grid covering them (as `settings` asks), combined by
/// `settings.op` node by node within `band` grid spacings of the surface and fitted again; one
/// operand is resampled. `job` names the work in a refusal for memory.
pub(crate) fn combine_operands(
    job: &str,
    operands: &[Operand],
    settings: &CsgOptions,
    band: f32,
    progress: &dyn Progress,
) -> Result<CoefficientVolume> {
    pgvol_ops::check_blend(settings.blend).map_err(ops_error)?;
    let radius = match settings.blend {
        Blend::Sharp => 0.0,
        Blend::Round(r) => r,
    };
    let loaded = load_operands(operands)?;
    let grid = covering_grid(&loaded, settings.bounds, radius, settings.res)?;
    check_edit_memory(job, &loaded, &grid, radius, settings.result)?;
    let fields = operand_fields(operands, &loaded, grid, radius, settings.sign, progress)?;
    progress.stage("combining the fields");
    let band = band * grid.spacing;
    let (op, blend) = (settings.op, settings.blend);
    let clip = clip_box(&loaded, settings.bounds);
    let volume = pgvol_ops::sample_bricks(grid, Basis::Bspline3, band, blend.lipschitz(), |p| {
        let mut values = [0.0f32; 16];
        let combined = if fields.len() <= values.len() {
            for (v, f) in values.iter_mut().zip(&fields) {
                *v = f.value(p);
            }
            pgvol_ops::combine(op, blend, &values[..fields.len()])
        } else {
            let values: Vec<f32> = fields.iter().map(|f| f.value(p)).collect();
            pgvol_ops::combine(op, blend, &values)
        };
        clipped(combined, p, clip)
    })
    .map_err(ops_error)?;
    crate::progress::check(progress)?;
    Ok(volume)
}
