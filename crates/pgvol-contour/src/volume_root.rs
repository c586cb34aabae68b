//! Crossings on the edges of a grid sampling a coefficient volume: on the volume's continuous
//! field where both ends lie in its box, linear in the padding outside it.

use glam::Vec3;
use pgvol_field::CoefficientVolume;

use crate::edge_cubic::thirds_on_grid_edge;
use crate::root::{cubic_edge_root, root_from_thirds};

/// Places the crossing of an edge on the continuous field of `volume` where both ends lie in
/// its box, and linearly elsewhere (where values are artificial padding).
pub(crate) fn volume_refine(
    volume: &CoefficientVolume,
    iso: f32,
) -> impl Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync + '_ {
    let (lo, hi) = (volume.grid.origin, volume.grid.max_corner());
    let in_box = move |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
    move |a: Vec3, va: f32, b: Vec3, vb: f32| -> Vec3 {
        if in_box(a) && in_box(b) {
            volume_edge_root(volume, a, va, b, vb, iso)
        } else {
            let t = ((iso - va) / (vb - va)).clamp(0.0, 1.0);
            a + (b - a) * t
        }
    }
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
