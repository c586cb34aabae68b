//! Clearing the field's stray pieces: points of a check grid (with the mesh's exact signed
//! distance) where the field has the other sign get a spherical clearing bump, as the sign
//! points do in the loop. Contouring creates a piece only around nodes of the contouring grid,
//! so checking the nodes of that grid catches every stray piece it would contour whose nodes
//! lie far enough from the surface for a ball to fit.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::field::{Perturbation, PerturbationError, PerturbationField};
use crate::quadric::Quadric;

/// What [`clear_points`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Cleanup {
    /// Checked points on the wrong side of the field before the pass.
    pub wrong_before: usize,
    /// Clearing bumps added.
    pub bumps: usize,
    /// Checked points still on the wrong side after it.
    pub wrong_after: usize,
}

/// The clearing bump of the point `p` at signed distance `d` from the surface, where the field
/// is `v`: `f · Q³`, `Q = a (1 − |x − p|² / ρ²)`, `ρ = 0.9 |d|` (the ball holds no surface),
/// `a³ = |v| + |d|` (the point ends on its side by a margin of its distance).
pub(crate) fn clearing_bump(p: DVec3, d: f64, v: f64) -> Perturbation {
    let rho = 0.9 * d.abs();
    let a = (v.abs() + d.abs()).cbrt();
    Perturbation {
        quadric: Quadric {
            centre: p,
            scale: rho,
            q: [-a, -a, -a, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, a],
        },
        factor: if d > 0.0 { 1.0 } else { -1.0 },
    }
}

/// `field` with clearing bumps for the `checks` (points and their signed distance, negative
/// inside) on the wrong side, deepest first; a point put right by an earlier bump gets none.
pub fn clear_points(
    field: &PerturbationField,
    checks: &[(Vec3, f32)],
) -> Result<(PerturbationField, Cleanup), PerturbationError> {
    let wrong = |v: f64, d: f32| (v > 0.0) != (d > 0.0);
    let mut candidates: Vec<(DVec3, f64, f64)> = checks
        .par_iter()
        .filter(|(p, d)| *d != 0.0 && d.is_finite() && p.is_finite())
        .filter_map(|&(p, d)| {
            let p = p.as_dvec3();
            let v = field.value_f64(p);
            wrong(v, d).then_some((p, d as f64, v))
        })
        .collect();
    let wrong_before = candidates.len();
    candidates.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    let mut added: Vec<(Perturbation, (DVec3, DVec3))> = Vec::new();
    let extra = |added: &[(Perturbation, (DVec3, DVec3))], p: DVec3| -> f64 {
        added
            .iter()
            .filter(|(_, (lo, hi))| p.cmpge(*lo).all() && p.cmple(*hi).all())
            .filter_map(|(t, _)| t.shape(p).map(|(r, _)| t.factor * r))
            .sum()
    };
    for &(p, d, v) in &candidates {
        let v = v + extra(&added, p);
        if !wrong(v, d as f32) {
            continue;
        }
        let bump = clearing_bump(p, d, v);
        if let Some(b) = bump.quadric.positive_box() {
            added.push((bump, b));
        }
    }
    let wrong_after = candidates
        .iter()
        .filter(|&&(p, d, v)| wrong(v + extra(&added, p), d as f32))
        .count();
    let bumps = added.len();
    let mut terms = field.terms().to_vec();
    terms.extend(added.into_iter().map(|(t, _)| t));
    let field = PerturbationField::new(*field.base(), terms)?;
    Ok((
        field,
        Cleanup {
            wrong_before,
            bumps,
            wrong_after,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stray_piece_is_cleared_and_the_surface_kept() {
        // A unit sphere and a bump pulling a separate blob inside out at (2, 0, 0).
        let sphere = Quadric {
            centre: DVec3::ZERO,
            scale: 1.0,
            q: [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        };
        let blob = clearing_bump(DVec3::new(2.0, 0.0, 0.0), -0.3, 5.0);
        let field = PerturbationField::new(sphere, vec![blob]).unwrap();
        assert!(field.value_f64(DVec3::new(2.0, 0.0, 0.0)) < 0.0);
        // Checks on a grid of spacing 0.1, with the sphere's exact distance, away from it.
        let mut checks = Vec::new();
        for i in -30..=30 {
            for j in -30..=30 {
                for k in -30..=30 {
                    let p = Vec3::new(i as f32, j as f32, k as f32) * 0.1;
                    let d = p.length() - 1.0;
                    if d.abs() > 0.05 {
                        checks.push((p, d));
                    }
                }
            }
        }
        let (cleared, report) = clear_points(&field, &checks).unwrap();
        assert!(report.wrong_before > 0 && report.bumps > 0, "{report:?}");
        assert_eq!(report.wrong_after, 0);
        for &(p, d) in &checks {
            assert_eq!(cleared.value(p) > 0.0, d > 0.0, "{p} {d}");
        }
        // No clearing ball reaches the sphere: its points keep their value.
        for p in [DVec3::X, DVec3::Y, -DVec3::Z, DVec3::new(0.6, 0.8, 0.0)] {
            assert_eq!(cleared.value_f64(p), field.value_f64(p));
        }
    }
}
