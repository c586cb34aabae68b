//! Crossings on the edges of a grid sampling a coefficient volume: on the volume's continuous
//! field where both ends lie in its box, linear in the padding outside it.

use glam::Vec3;
use pgvol_field::CoefficientVolume;

use crate::crossings::with_normal;
use crate::edge_cubic::{crossing_on_grid_edge, thirds_on_grid_edge};
use crate::place::onto_edge;
use crate::root::{cubic_edge_root, root_from_thirds};

/// Places the crossing of an edge on the continuous field of `volume` where both ends lie in
/// its box, and linearly elsewhere (where values are artificial padding).
pub(crate) fn volume_refine(
    volume: &CoefficientVolume,
    iso: f32,
) -> impl Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync + '_ {
    let in_box = in_box_of(volume);
    move |a: Vec3, va: f32, b: Vec3, vb: f32| -> Vec3 {
        if in_box(a) && in_box(b) {
            volume_edge_root(volume, a, va, b, vb, iso)
        } else {
            padding_crossing(a, va, b, vb, iso)
        }
    }
}

/// [`volume_refine`]'s crossing, put onto its edge along `axis`, with the unit gradient of the
/// field there; the normal is zero where the gradient vanishes and where the edge reaches into
/// the padding, whose values are artificial. The positions are [`volume_refine`]'s.
pub(crate) fn volume_place_with_normal(
    volume: &CoefficientVolume,
    iso: f32,
) -> impl Fn(Vec3, f32, Vec3, f32, usize) -> (Vec3, Vec3) + Sync + '_ {
    let in_box = in_box_of(volume);
    move |a: Vec3, va: f32, b: Vec3, vb: f32, axis: usize| -> (Vec3, Vec3) {
        if in_box(a) && in_box(b) {
            // The edge's stencil gives the root and the gradient from one read; where it
            // declines, `volume_edge_root` evaluates the field in general, and so does this.
            crossing_on_grid_edge(volume, a, va, b, vb, iso).unwrap_or_else(|| {
                let p = cubic_edge_root(volume, a, va, b, vb, iso);
                with_normal(a, b, axis, p, |p| volume.eval(p).1)
            })
        } else {
            (
                onto_edge(a, b, axis, padding_crossing(a, va, b, vb, iso)),
                Vec3::ZERO,
            )
        }
    }
}

/// Whether a point lies in `volume`'s box, where its field is continuous.
fn in_box_of(volume: &CoefficientVolume) -> impl Fn(Vec3) -> bool + Sync {
    let (lo, hi) = (volume.grid.origin, volume.grid.max_corner());
    move |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all()
}

/// The crossing of an edge reaching into the padding, linear in its end values since those of
/// the padding are artificial.
fn padding_crossing(a: Vec3, va: f32, b: Vec3, vb: f32, iso: f32) -> Vec3 {
    let t = ((iso - va) / (vb - va)).clamp(0.0, 1.0);
    a + (b - a) * t
}

/// The crossing on a grid edge of the continuous field of `volume`: from the coefficients
/// directly where the edge lies on the volume's own B-spline grid, else by two evaluations.
fn volume_edge_root(
    volume: &CoefficientVolume,
    a: Vec3,
    va: f32,
    b: Vec3,
    vb: f32,
    iso: f32,
) -> Vec3 {
    match thirds_on_grid_edge(volume, a, b) {
        Some(thirds) if va.is_finite() && vb.is_finite() => {
            root_from_thirds(a, va, b, vb, thirds, iso)
        }
        _ => cubic_edge_root(volume, a, va, b, vb, iso),
    }
}
