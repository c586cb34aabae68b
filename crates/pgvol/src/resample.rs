//! A field fitted again on another grid, and the analytic solids as fields.

use glam::Vec3;

use crate::csg::{combine_operands, CsgOptions, CSG_RES};
use crate::emptiness::{require_surface, IfEmpty, Sides};
use crate::encode::ENCODE_BAND;
use crate::error::{Error, Result};
use crate::field_value::Field;
use crate::operand::{Operand, Primary};
use crate::progress::Progress;

/// The grid a field is fitted on by [`Field::resample`] and [`Field::primitive`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResampleOptions {
    /// Grid nodes per axis (default [`CSG_RES`]).
    pub res: usize,
    /// The box the grid covers (grown as [`crate::Grid::cube_res`] grows it); by default the
    /// field's source box, or the primitive's. Needed for planes and cylinders.
    pub bounds: Option<(Vec3, Vec3)>,
    /// Grid spacings from the surface within which node values are sampled (default
    /// [`ENCODE_BAND`]), beyond which they are clamped: a wider band for operations that read
    /// the field farther out (offsets, blends). A resampled field is exact only as far as the
    /// field it reads.
    pub band: f32,
}

impl Default for ResampleOptions {
    fn default() -> Self {
        ResampleOptions {
            res: CSG_RES,
            bounds: None,
            band: ENCODE_BAND,
        }
    }
}

impl Field {
    /// The analytic solid `primary` as a field: its exact distance in a band around the
    /// surface, fitted in the cubic B-spline on the grid `options` gives.
    pub fn primitive(
        primary: Primary,
        options: &ResampleOptions,
        progress: &dyn Progress,
    ) -> Result<Field> {
        fitted(
            Operand::Primary(primary),
            options,
            f32::INFINITY,
            "primitive",
            progress,
        )
    }

    /// This field sampled on the grid `options` gives (by default over its own box) and
    /// fitted again there in the cubic B-spline: coarser to save bytes, finer to edit on.
    pub fn resample(&self, options: &ResampleOptions, progress: &dyn Progress) -> Result<Field> {
        crate::frame::require_near(self.file.volume.grid.offset, "resampling")?;
        let name = format!("resample {}", options.res);
        let exact = self.exact_band();
        fitted(Operand::from(self.clone()), options, exact, &name, progress)
    }
}

/// `operand` fitted on the grid of `options`, named `operation` in the header, which records
/// the band within which it is exact: the sampled band, or `exact` (the operand's own, in model
/// units) when that is narrower.
fn fitted(
    operand: Operand,
    options: &ResampleOptions,
    exact: f32,
    operation: &str,
    progress: &dyn Progress,
) -> Result<Field> {
    if !(options.band.is_finite() && options.band > 0.0) {
        return Err(Error::parameter(format!(
            "the band must be a positive number of grid spacings, got {}",
            options.band
        )));
    }
    let settings = CsgOptions {
        res: options.res,
        bounds: options.bounds,
        ..CsgOptions::default()
    };
    let volume = combine_operands("resampling", &[operand], &settings, options.band, progress)?;
    let why = IfEmpty {
        result: "the resampled field",
        no_inside: "the shape has no inside within the box; a box around the shape gives one",
        no_outside: "the shape fills the whole box; a box larger than the shape gives it a \
                     surface",
    };
    require_surface(Sides::of_volume(&volume), &why)?;
    let band = (options.band * volume.grid.spacing).min(exact);
    Ok(Field::edited(volume, operation, band))
}
