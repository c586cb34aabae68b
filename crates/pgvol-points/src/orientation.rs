//! Checks of given normals before a fit. The fit trusts each normal's side: neighbours on one
//! sheet pointing to opposite sides make the off-surface constraints contradict each other
//! (a surface breaks into pieces), and normals pointing into the solid turn it inside out (the
//! grid box minus the shape). Both are repaired here and reported, so the caller can say so.

use glam::Vec3;
use rayon::prelude::*;

use crate::normals::{nearest_neighbours, orient};

/// Share of neighbour pairs on one sheet with opposite normals above which the normals are
/// re-oriented. Consistent normals give none on smooth parts; a sharp edge of less than 90°
/// gives some along the edge only, a few per cent of a densely sampled part at most.
pub const MAX_DISAGREEING: f64 = 0.05;

/// Normals whose mean `(p − c)·n / |p − c|` over the cloud (c its centroid) is below minus this
/// point into the solid. By the divergence theorem the mean is positive for any closed
/// surface with outward normals (a sphere 1, a torus of radii 1 and 0.3 about 0.45); an open
/// sheet gives about 0 and is left alone.
pub const INWARD: f64 = 0.2;

/// What [`check_orientation`] found and changed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Orientation {
    /// Neighbour pairs on one sheet (the neighbour within 60° of the tangent plane).
    pub pairs: usize,
    /// Of those, the pairs whose normals pointed to opposite sides as given.
    pub disagreeing: usize,
    /// Whether the normals were re-oriented along a spanning tree of the neighbour graph.
    pub reoriented: bool,
    /// Whether all normals were flipped because they pointed into the solid.
    pub flipped: bool,
}

impl Orientation {
    /// The share of disagreeing pairs, 0 for none.
    pub fn disagreeing_share(&self) -> f64 {
        self.disagreeing as f64 / self.pairs.max(1) as f64
    }
}

/// Makes the given unit `normals` of `points` (mean spacing `spacing`) agree with their
/// neighbours and point outward, keeping each one's direction up to sign.
pub fn check_orientation(points: &[Vec3], normals: &mut [Vec3], spacing: f32) -> Orientation {
    let neighbours = nearest_neighbours(points, spacing);
    let (pairs, disagreeing) = neighbours
        .par_iter()
        .enumerate()
        .map(|(i, near)| {
            let (p, n) = (points[i], normals[i]);
            // A neighbour along the normal is likely on the other side of a thin wall, where
            // opposite normals are right.
            let on_sheet = near.iter().map(|&j| j as usize).filter(|&j| {
                let d = points[j] - p;
                j != i && n.dot(d).abs() < 0.5 * d.length()
            });
            on_sheet.fold((0usize, 0usize), |(all, bad), j| {
                (all + 1, bad + usize::from(n.dot(normals[j]) < 0.0))
            })
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let mut found = Orientation {
        pairs,
        disagreeing,
        ..Default::default()
    };
    if found.disagreeing_share() > MAX_DISAGREEING {
        orient(points, &neighbours, normals);
        found.reoriented = true;
    }
    if outwardness(points, normals) < -INWARD {
        normals.iter_mut().for_each(|n| *n = -*n);
        found.flipped = true;
    }
    found
}

/// The mean of `(p − c)·n / |p − c|` over the points, c their centroid.
fn outwardness(points: &[Vec3], normals: &[Vec3]) -> f64 {
    let c = points.iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>() / points.len().max(1) as f64;
    let sum: f64 = points
        .par_iter()
        .zip(normals)
        .map(|(p, n)| {
            let d = p.as_dvec3() - c;
            let len = d.length();
            if len > 0.0 {
                d.dot(n.as_dvec3()) / len
            } else {
                0.0
            }
        })
        .sum();
    sum / points.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere() -> (Vec<Vec3>, Vec<Vec3>) {
        let points = crate::test_points::sphere_points(3000, 1.0);
        let normals = points.iter().map(|p| p.normalize()).collect();
        (points, normals)
    }

    fn spacing(points: &[Vec3]) -> f32 {
        crate::index::mean_spacing(points)
    }

    #[test]
    fn consistent_outward_normals_are_left_alone() {
        let (points, mut normals) = sphere();
        let given = normals.clone();
        let found = check_orientation(&points, &mut normals, spacing(&points));
        assert!(found.pairs > 10 * points.len(), "{found:?}");
        assert_eq!(found.disagreeing, 0);
        assert!(!found.reoriented && !found.flipped);
        assert_eq!(normals, given);
    }

    #[test]
    fn alternating_normals_are_re_oriented_outward() {
        let (points, mut normals) = sphere();
        for n in normals.iter_mut().step_by(2) {
            *n = -*n;
        }
        let found = check_orientation(&points, &mut normals, spacing(&points));
        assert!(found.disagreeing_share() > 0.3, "{found:?}");
        assert!(found.reoriented && !found.flipped, "{found:?}");
        for (p, n) in points.iter().zip(&normals) {
            assert!(p.dot(*n) > 0.99, "{p} {n}");
        }
    }

    #[test]
    fn inward_normals_are_flipped_and_a_flat_sheet_is_not() {
        let (points, mut normals) = sphere();
        normals.iter_mut().for_each(|n| *n = -*n);
        let found = check_orientation(&points, &mut normals, spacing(&points));
        assert!(found.flipped && !found.reoriented, "{found:?}");
        assert!(points.iter().zip(&normals).all(|(p, n)| p.dot(*n) > 0.99));

        let sheet: Vec<Vec3> = (0..900)
            .map(|i| Vec3::new((i % 30) as f32, (i / 30) as f32, 0.0) * 0.1)
            .collect();
        let mut down = vec![-Vec3::Z; sheet.len()];
        let found = check_orientation(&sheet, &mut down, spacing(&sheet));
        assert!(!found.flipped && !found.reoriented, "{found:?}");
        assert!(down.iter().all(|n| *n == -Vec3::Z));
    }
}
