//! A lattice as a distance-like field: a triply periodic surface scaled to a cell size,
//! normalised by its gradient so values are in model units, then made a sheet or a strut
//! solid, with the cell size and thickness optionally graded.

use std::f32::consts::TAU;

use glam::Vec3;

use super::tpms::Tpms;
use crate::error::OpsError;

/// Which side of the periodic surface is solid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LatticeStyle {
    /// A wall of the given thickness centred on the surface: `|d| ≤ t/2`.
    #[default]
    Sheet,
    /// One of the two labyrinths the surface bounds, its boundary moved to the level `t`:
    /// `d ≤ t` (0 gives half of each cell for the four surfaces; negative thins the struts).
    Strut,
}

/// Where a graded lattice reaches its far values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ramp {
    /// From the skin (the part's surface) to `depth` inside it, read from the part's field.
    Depth { depth: f32 },
    /// Along the segment from `from` to `to`, constant beyond its ends.
    Linear { from: Vec3, to: Vec3 },
}

/// Far values of a graded lattice: the lattice's own `cell` and `thickness` hold at the start of
/// the ramp (the skin, or `from`), these at its end, linearly in between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grade {
    pub ramp: Ramp,
    pub cell: f32,
    pub thickness: f32,
}

/// A triply periodic lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    pub surface: Tpms,
    pub style: LatticeStyle,
    /// The period along each axis, in model units.
    pub cell: f32,
    /// Sheet: the wall thickness (> 0). Strut: the level bounding the struts (any sign).
    pub thickness: f32,
    pub grade: Option<Grade>,
}

impl Lattice {
    /// An ungraded sheet lattice.
    pub fn sheet(surface: Tpms, cell: f32, thickness: f32) -> Lattice {
        Lattice {
            surface,
            style: LatticeStyle::Sheet,
            cell,
            thickness,
            grade: None,
        }
    }

    /// Refuses parameters that make no lattice: cells must be positive, a sheet's thickness
    /// positive and thinner than half a cell, a strut's level within a quarter cell, a depth
    /// ramp positive and a linear ramp of non-zero length; the cell is graded along a linear
    /// ramp only (grading it with depth would need the part's gradient, and bends the cells).
    pub fn check(&self) -> Result<(), OpsError> {
        let bad = |m: String| Err(OpsError::BadParameter(m));
        let pairs = [(self.cell, self.thickness, "")]
            .into_iter()
            .chain(self.grade.map(|g| (g.cell, g.thickness, "far ")));
        for (cell, thickness, far) in pairs {
            if !(cell.is_finite() && cell > 0.0) {
                return bad(format!(
                    "the {far}cell size must be a positive number, got {cell}"
                ));
            }
            match self.style {
                LatticeStyle::Sheet if !(thickness > 0.0 && thickness < 0.5 * cell) => {
                    return bad(format!(
                        "the {far}sheet thickness must be positive and under half the cell \
                         ({}), got {thickness}",
                        0.5 * cell
                    ));
                }
                LatticeStyle::Strut if !thickness.is_finite() || thickness.abs() >= 0.25 * cell => {
                    return bad(format!(
                        "the {far}strut level must lie within a quarter cell (±{}), got \
                         {thickness}",
                        0.25 * cell
                    ));
                }
                _ => {}
            }
        }
        match self.grade.map(|g| (g, g.ramp)) {
            Some((_, Ramp::Depth { depth })) if !(depth.is_finite() && depth > 0.0) => {
                bad(format!("the grading depth must be positive, got {depth}"))
            }
            Some((g, Ramp::Depth { .. })) if g.cell != self.cell => bad(
                "the cell size can be graded along a linear ramp only; keep the far cell equal \
                 to the cell with a depth ramp"
                    .into(),
            ),
            Some((_, Ramp::Linear { from, to }))
                if !(from.is_finite() && to.is_finite()) || (to - from).length() == 0.0 =>
            {
                bad("a linear ramp needs two distinct finite points".into())
            }
            _ => Ok(()),
        }
    }

    /// How far outside a lattice solid its field is still distance-like: `d` is clamped to
    /// half the largest cell, so a value this large says only "outside".
    pub fn clamp(&self) -> f32 {
        0.5 * self.grade.map_or(self.cell, |g| g.cell.max(self.cell))
    }

    /// The largest value [`Lattice::value`] takes anywhere: the clamp less the thinnest
    /// sheet's half thickness, or less the lowest strut level. A part's field above it wins
    /// every max with the lattice.
    pub fn max_value(&self) -> f32 {
        let thinnest = self
            .grade
            .map_or(self.thickness, |g| g.thickness.min(self.thickness));
        match self.style {
            LatticeStyle::Sheet => self.clamp() - 0.5 * thinnest,
            LatticeStyle::Strut => self.clamp() - thinnest,
        }
    }

    /// Position along the ramp, 0 at its start and 1 at its end, and its gradient; `part` is
    /// the part's field at `p` (negative inside).
    fn ramp(&self, p: Vec3, part: f32) -> (f32, Vec3) {
        match self.grade.map(|g| g.ramp) {
            None => (0.0, Vec3::ZERO),
            Some(Ramp::Depth { depth }) => ((-part / depth).clamp(0.0, 1.0), Vec3::ZERO),
            Some(Ramp::Linear { from, to }) => {
                let axis = (to - from) / (to - from).length_squared();
                let s = (p - from).dot(axis);
                if (0.0..=1.0).contains(&s) {
                    (s, axis)
                } else {
                    (s.clamp(0.0, 1.0), Vec3::ZERO)
                }
            }
        }
    }

    /// The distance-like value of the periodic surface at `p`: the function divided by the
    /// norm of its gradient in model units, clamped to ±[`Lattice::clamp`]. A graded cell
    /// scales the phase about the ramp's start, and the gradient carries that variation.
    pub fn surface_distance(&self, p: Vec3, part: f32) -> f32 {
        let (s, ds) = self.ramp(p, part);
        let (cell, anchor) = match self.grade {
            Some(g) => (
                self.cell + (g.cell - self.cell) * s,
                match g.ramp {
                    Ramp::Linear { from, .. } => from,
                    Ramp::Depth { .. } => Vec3::ZERO,
                },
            ),
            None => (self.cell, Vec3::ZERO),
        };
        let q = p - anchor;
        let (f, g) = self.surface.eval(q * (TAU / cell));
        // u = 2π q / L(p): ∇ₚf = 2π/L (g − ∇L (q·g) / L).
        let dcell = ds * self.grade.map_or(0.0, |gr| gr.cell - self.cell);
        let world = (g - dcell * (q.dot(g) / cell)) * (TAU / cell);
        let clamp = self.clamp();
        let norm = world.length();
        if norm * clamp <= f.abs() {
            return clamp.copysign(f);
        }
        f / norm
    }

    /// The lattice solid's field at `p` (negative inside), before any part is applied.
    pub fn value(&self, p: Vec3, part: f32) -> f32 {
        let d = self.surface_distance(p, part);
        let thickness = match self.grade {
            Some(g) => self.thickness + (g.thickness - self.thickness) * self.ramp(p, part).0,
            None => self.thickness,
        };
        match self.style {
            LatticeStyle::Sheet => d.abs() - 0.5 * thickness,
            LatticeStyle::Strut => d - thickness,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schwarz_p_distance_is_exact_on_the_axes() {
        // Along x through the phase (·, 0, π), cos y + cos z = 0 and sin y = sin z = 0:
        // f = cos x, ∇f = (−sin x, 0, 0)·2π/L. Near x = π/2 the normalised value is the
        // distance to the plane x = L/4 up to a relative (πo/L)²/3.
        let lattice = Lattice::sheet(Tpms::SchwarzP, 4.0, 0.4);
        for offset in [-0.05f32, 0.02, 0.1] {
            let p = Vec3::new(1.0 + offset, 0.0, 2.0);
            let d = lattice.surface_distance(p, -1.0);
            assert!((d + offset).abs() < 2e-3, "{offset}: {d}");
            assert!((lattice.value(p, -1.0) - (offset.abs() - 0.2)).abs() < 2e-3);
        }
    }

    #[test]
    fn no_value_exceeds_the_bound() {
        for style in [LatticeStyle::Sheet, LatticeStyle::Strut] {
            let lattice = Lattice {
                style,
                ..Lattice::sheet(Tpms::Neovius, 1.5, 0.2)
            };
            let bound = lattice.max_value();
            for i in 0..4000 {
                let p = Vec3::new(i as f32 * 0.013, i as f32 * 0.0071, i as f32 * 0.0037);
                assert!(lattice.value(p, -1.0) <= bound + 1e-6);
            }
        }
    }

    #[test]
    fn values_are_clamped_where_the_gradient_vanishes() {
        // The P function's maximum 3 sits at the origin, where its gradient is zero.
        let lattice = Lattice::sheet(Tpms::SchwarzP, 2.0, 0.2);
        assert_eq!(lattice.surface_distance(Vec3::ZERO, -1.0), 1.0);
    }

    #[test]
    fn a_linear_grade_changes_the_period_and_the_thickness() {
        let mut lattice = Lattice::sheet(Tpms::SchwarzP, 2.0, 0.2);
        lattice.grade = Some(Grade {
            ramp: Ramp::Linear {
                from: Vec3::ZERO,
                to: Vec3::X * 10.0,
            },
            cell: 4.0,
            thickness: 0.6,
        });
        lattice.check().unwrap();
        // Beyond the ramp's end the cell is 4 about the start: the planes x ≡ 1 (mod 2)
        // in y = z = 1 lie at x = 4·(k + 1/4); x = 13 is one of them, and the wall is 0.6 thick.
        let p = Vec3::new(13.0, 1.0, 1.0);
        assert!(lattice.surface_distance(p, 0.0).abs() < 1e-4);
        assert!((lattice.value(p, 0.0) + 0.3).abs() < 1e-4);
        // Before its start, cell 2 and thickness 0.2.
        let q = Vec3::new(-1.5, 0.5, 0.5);
        assert!(lattice.surface_distance(q, 0.0).abs() < 1e-4);
        assert!((lattice.value(q, 0.0) + 0.1).abs() < 1e-4);
    }

    #[test]
    fn a_depth_grade_follows_the_part_field() {
        let mut lattice = Lattice::sheet(Tpms::Gyroid, 5.0, 1.0);
        lattice.grade = Some(Grade {
            ramp: Ramp::Depth { depth: 2.0 },
            cell: 5.0,
            thickness: 0.5,
        });
        lattice.check().unwrap();
        let p = Vec3::new(0.3, 0.7, 1.1);
        let d = lattice.surface_distance(p, 0.0).abs();
        for (part, t) in [(0.0, 1.0), (-1.0, 0.75), (-2.0, 0.5), (-7.0, 0.5)] {
            assert!((lattice.value(p, part) - (d - 0.5 * t)).abs() < 1e-5);
        }
    }

    #[test]
    fn impossible_parameters_are_refused_with_the_reason() {
        let bad = [
            (Lattice::sheet(Tpms::Gyroid, 0.0, 0.1), "cell size"),
            (
                Lattice::sheet(Tpms::Gyroid, 1.0, 0.6),
                "under half the cell",
            ),
            (Lattice::sheet(Tpms::Gyroid, f32::NAN, 0.1), "cell size"),
            (
                Lattice {
                    style: LatticeStyle::Strut,
                    ..Lattice::sheet(Tpms::Diamond, 1.0, -0.3)
                },
                "quarter cell",
            ),
            (
                Lattice {
                    grade: Some(Grade {
                        ramp: Ramp::Depth { depth: 1.0 },
                        cell: 2.0,
                        thickness: 0.1,
                    }),
                    ..Lattice::sheet(Tpms::Gyroid, 1.0, 0.1)
                },
                "linear ramp only",
            ),
        ];
        for (lattice, want) in bad {
            let e = lattice.check().unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
    }
}
