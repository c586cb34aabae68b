//! Mask restoration: protrusions replaced by a smooth cap, or noise smoothed, inside
//! axis-aligned masks, with the coefficients outside the masks' reach left bit-identical.

use glam::Vec3;
use pgvol_field::CoefficientVolume;
use pgvol_ops::{Face, Mask, MaskReport, Restore};

use crate::emptiness::{require_surface, IfEmpty, Sides};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::shape::Shape;

/// Default normal derivative across the face a protrusion crosses: that of a distance, so the
/// cap continues the body's field (measured on a bumped sphere: 0.9 to 1 keeps the cap within
/// 1.3 % of the sphere's radius; see `docs/editing.md`).
pub const DEFAULT_ALPHA: f32 = 1.0;

/// Default coarse samples along a denoising mask's longest side.
pub const DEFAULT_COARSE: usize = 30;

/// A mask from `x0,y0,z0,x1,y1,z1`.
pub fn parse_mask(text: &str) -> Result<Mask> {
    let v: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| {
            Error::parameter(format!(
                "mask: '{text}' is not six numbers x0,y0,z0,x1,y1,z1"
            ))
        })?;
    if v.len() != 6 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::parameter(format!(
            "mask: expected six finite numbers x0,y0,z0,x1,y1,z1, got '{text}'"
        )));
    }
    let (lo, hi) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
    if hi.cmple(lo).any() {
        return Err(Error::parameter(format!(
            "mask: the second corner must lie above the first on every axis, got '{text}'"
        )));
    }
    Ok(Mask { lo, hi })
}

/// A face from `+x`, `-x`, `+y`, `-y`, `+z` or `-z`.
pub fn parse_face(text: &str) -> Result<Face> {
    let t = text.trim();
    let (sign, axis) = t.split_at(t.len().min(1));
    let axis = match axis {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => usize::MAX,
    };
    if axis == usize::MAX || !(sign == "+" || sign == "-") {
        return Err(Error::parameter(format!(
            "face: expected one of +x, -x, +y, -y, +z, -z, got '{text}'"
        )));
    }
    Ok(Face {
        axis,
        upper: sign == "+",
    })
}

/// How far from the surface a repair reads the field: the largest extent of its masks, so a
/// mesh is encoded with exact distances over them.
pub fn repair_reach(masks: &[Mask]) -> f32 {
    masks
        .iter()
        .map(|m| (m.hi - m.lo).max_element())
        .fold(0.0, f32::max)
}

/// The shape's field restored inside `masks` (see [`pgvol_ops::repair`]), with a report per
/// mask.
pub fn repair(
    shape: &Shape,
    masks: &[Mask],
    restore: Restore,
    progress: &dyn Progress,
) -> Result<(CoefficientVolume, Vec<MaskReport>)> {
    crate::frame::require_near(shape.volume.grid.offset, "repair")?;
    if let Restore::Protrusion { alpha, .. } = restore {
        if !alpha.is_finite() {
            return Err(Error::parameter(format!(
                "alpha must be finite, got {alpha}"
            )));
        }
    }
    check_repair_memory(&shape.volume, masks, restore)?;
    progress.stage("restoring the masks");
    let repaired =
        pgvol_ops::repair(&shape.volume, masks, restore).map_err(crate::csg::ops_error)?;
    crate::progress::check(progress)?;
    let why = IfEmpty {
        result: "the restored field",
        no_inside: "the masks take in every part of the shape, so nothing of it is kept; masks \
                    around only the parts to restore keep the rest",
        no_outside: "the masks take in every part of the shape's surface, so none of it is \
                     kept; masks around only the parts to restore keep the rest",
    };
    require_surface(Sides::of_volume(&repaired.0), &why)?;
    Ok(repaired)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_and_faces_parse_and_bad_ones_are_refused() {
        let m = parse_mask("0,0,0,1,2,3").unwrap();
        assert_eq!(m.hi, Vec3::new(1.0, 2.0, 3.0));
        assert!(parse_mask("0,0,0,1,2").is_err());
        assert!(parse_mask("0,0,0,1,-2,3").is_err());
        assert_eq!(
            parse_face("-z").unwrap(),
            Face {
                axis: 2,
                upper: false
            }
        );
        assert_eq!(
            parse_face("+x").unwrap(),
            Face {
                axis: 0,
                upper: true
            }
        );
        assert!(parse_face("z").is_err());
        assert!(parse_face("+w").is_err());
    }
}
