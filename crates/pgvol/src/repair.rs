//! Mask restoration: protrusions replaced by a smooth cap, or noise smoothed, inside
//! axis-aligned masks, with the coefficients outside the masks' reach left bit-identical.

use pgvol_field::CoefficientVolume;
use pgvol_ops::{Mask, MaskReport, Restore};

use crate::emptiness::{require_surface, IfEmpty, Sides};
use crate::error::{Error, ErrorKind, Result};
use crate::field_value::Field;
use crate::progress::Progress;

/// Default normal derivative across the face a protrusion crosses: that of a distance, so the
/// cap continues the body's field (measured on a bumped sphere: 0.9 to 1 keeps the cap within
/// 1.3 % of the sphere's radius; see `docs/editing.md`).
pub const DEFAULT_ALPHA: f32 = 1.0;

/// Largest normal derivative accepted, in magnitude: a distance-like field's is near 1 (the
/// useful range measured is 0 to 2), and far beyond it the restored cap's values dwarf the
/// field's around it.
pub const MAX_ALPHA: f32 = 10.0;

/// Default coarse samples along a denoising mask's longest side.
pub const DEFAULT_COARSE: usize = 30;

/// How far from the surface a repair reads the field: the largest extent of its masks, so a
/// mesh is encoded with exact distances over them.
pub fn repair_reach(masks: &[Mask]) -> f32 {
    masks
        .iter()
        .map(|m| (m.hi - m.lo).max_element())
        .fold(0.0, f32::max)
}

/// A repaired field and a report per mask.
#[derive(Clone, Debug)]
pub struct Repaired {
    /// The field restored inside the masks.
    pub field: Field,
    /// What each mask's restoration did, in the masks' order.
    pub masks: Vec<MaskReport>,
}

impl Field {
    /// The field restored inside `masks` (see [`pgvol_ops::repair`]): a protrusion removed
    /// and the surface continued across, or noise smoothed away.
    pub fn repair(
        &self,
        masks: &[Mask],
        restore: Restore,
        progress: &dyn Progress,
    ) -> Result<Repaired> {
        crate::frame::require_near(self.file.volume.grid.offset, "repair")?;
        if let Restore::Protrusion { alpha, .. } = restore {
            if !(alpha.is_finite() && alpha.abs() <= MAX_ALPHA) {
                return Err(Error::parameter(format!(
                    "alpha must be a normal derivative from -{MAX_ALPHA} to {MAX_ALPHA} (that \
                     of a distance is 1), got {alpha}"
                )));
            }
        }
        // A mask over the whole shape leaves no field outside it to continue: the result is
        // empty, known before a solve over the whole mask.
        let (lo, hi) = self.bounds;
        if masks
            .iter()
            .any(|m| m.lo.cmple(lo).all() && m.hi.cmpge(hi).all())
        {
            return Err(Error::new(
                ErrorKind::EmptyResult,
                format!(
                    "the restored field would be empty: a mask takes in the whole shape ({lo} \
                     to {hi}), so nothing of it is kept; masks around only the parts to restore \
                     keep the rest"
                ),
            ));
        }
        check_repair_memory(&self.file.volume, masks, restore)?;
        progress.stage("restoring the masks");
        let (volume, reports) =
            pgvol_ops::repair(&self.file.volume, masks, restore).map_err(crate::csg::ops_error)?;
        crate::progress::check(progress)?;
        let why = IfEmpty {
            result: "the restored field",
            no_inside: "the masks take in every part of the shape, so nothing of it is kept; \
                        masks around only the parts to restore keep the rest",
            no_outside: "the masks take in every part of the shape's surface, so none of it is \
                         kept; masks around only the parts to restore keep the rest",
        };
        require_surface(Sides::of_volume(&volume), &why)?;
        let band = self.band.unwrap_or_else(|| pgvol_ops::stored_band(&volume));
        let operation = match restore {
            Restore::Denoise { coarse } => format!("denoise coarse {coarse}"),
            Restore::Protrusion { alpha, .. } => format!("repair alpha {alpha}"),
        };
        Ok(Repaired {
            field: Field::edited(volume, &operation, band),
            masks: reports,
        })
    }
}

impl Field {
    /// The field inside `masks` resampled with `coarse` samples along each mask's longest
    /// side and blended back: [`Field::repair`] with [`Restore::Denoise`].
    pub fn denoise(
        &self,
        masks: &[Mask],
        coarse: usize,
        progress: &dyn Progress,
    ) -> Result<Repaired> {
        self.repair(masks, Restore::Denoise { coarse }, progress)
    }
}

/// Bytes per mask node of a Laplace fill: the solver's f64 vectors and the system's indices.
const BYTES_PER_FILL_NODE: u64 = 64;

/// Refuses a repair whose largest mask would not fit in memory, before any work: the field's
/// copy, and the mask's solve or its coarse lattice (samples, coefficients and the prefilter's
/// copy, as in encoding). Masks and lattices over their node limit are refused by name.
fn check_repair_memory(volume: &CoefficientVolume, masks: &[Mask], restore: Restore) -> Result<()> {
    let mut largest = 0u64;
    for mask in masks {
        let nodes = pgvol_ops::mask_nodes(&volume.grid, mask).map_err(crate::csg::ops_error)?;
        let bytes = match restore {
            Restore::Protrusion { .. } => {
                (nodes.count() as u64).saturating_mul(BYTES_PER_FILL_NODE)
            }
            Restore::Denoise { coarse } => {
                let lattice = pgvol_ops::coarse_lattice(&volume.grid, mask, coarse)
                    .map_err(crate::csg::ops_error)?;
                crate::memory::grid_bytes(lattice.len(), crate::memory::BYTES_PER_NODE)
                    .saturating_add(nodes.count() as u64 * 4)
            }
        };
        largest = largest.max(bytes);
    }
    crate::memory::check_memory(
        &format!("restoring {} mask(s)", masks.len()),
        largest.saturating_add(volume.coeffs.memory_bytes() as u64),
        "use smaller masks or fewer coarse samples",
    )
}
