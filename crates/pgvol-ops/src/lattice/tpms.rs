//! Triply periodic minimal surfaces as level-set approximations in phase coordinates: value and
//! gradient of the classical trigonometric forms, period 2π along every axis.

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

/// A triply periodic surface, the zero set of a trigonometric function of the phase
/// `u = 2π x / cell`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tpms {
    /// Schoen's gyroid: `sin x cos y + sin y cos z + sin z cos x`.
    Gyroid,
    /// Schwarz P (primitive): `cos x + cos y + cos z`.
    SchwarzP,
    /// Schwarz D (diamond): `sin x sin y sin z + sin x cos y cos z + cos x sin y cos z +
    /// cos x cos y sin z`.
    Diamond,
    /// Neovius: `3 (cos x + cos y + cos z) + 4 cos x cos y cos z`.
    Neovius,
}

/// Every surface with its names on the command line.
pub const TPMS_NAMES: [(Tpms, &str); 4] = [
    (Tpms::Gyroid, "gyroid"),
    (Tpms::SchwarzP, "schwarz-p"),
    (Tpms::Diamond, "diamond"),
    (Tpms::Neovius, "neovius"),
];

impl Tpms {
    /// The function and its gradient with respect to the phase at `u`.
    pub fn eval(self, u: Vec3) -> (f32, Vec3) {
        let (sx, cx) = u.x.sin_cos();
        let (sy, cy) = u.y.sin_cos();
        let (sz, cz) = u.z.sin_cos();
        match self {
            Tpms::Gyroid => (
                sx * cy + sy * cz + sz * cx,
                Vec3::new(cx * cy - sz * sx, cy * cz - sx * sy, cz * cx - sy * sz),
            ),
            Tpms::SchwarzP => (cx + cy + cz, Vec3::new(-sx, -sy, -sz)),
            Tpms::Diamond => (
                sx * sy * sz + sx * cy * cz + cx * sy * cz + cx * cy * sz,
                Vec3::new(
                    cx * sy * sz + cx * cy * cz - sx * sy * cz - sx * cy * sz,
                    sx * cy * sz - sx * sy * cz + cx * cy * cz - cx * sy * sz,
                    sx * sy * cz - sx * cy * sz - cx * sy * sz + cx * cy * cz,
                ),
            ),
            Tpms::Neovius => (
                3.0 * (cx + cy + cz) + 4.0 * cx * cy * cz,
                Vec3::new(
                    -3.0 * sx - 4.0 * sx * cy * cz,
                    -3.0 * sy - 4.0 * cx * sy * cz,
                    -3.0 * sz - 4.0 * cx * cy * sz,
                ),
            ),
        }
    }

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        TPMS_NAMES.iter().find(|(t, _)| *t == self).unwrap().1
    }
}

impl fmt::Display for Tpms {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Tpms {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim().to_ascii_lowercase();
        let alias = match s.as_str() {
            "primitive" | "schwarzp" | "p" => "schwarz-p",
            "d" | "schwarz-d" => "diamond",
            other => other,
        };
        TPMS_NAMES
            .iter()
            .find(|(_, n)| *n == alias)
            .map(|(t, _)| *t)
            .ok_or_else(|| {
                let names: Vec<&str> = TPMS_NAMES.iter().map(|(_, n)| *n).collect();
                format!(
                    "unknown surface '{s}'; expected one of {}",
                    names.join(", ")
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f32::consts::TAU;

    fn phase() -> impl Strategy<Value = Vec3> {
        (-10.0f32..10.0, -10.0f32..10.0, -10.0f32..10.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn gradient_matches_central_differences(u in phase()) {
            for (t, _) in TPMS_NAMES {
                let (_, g) = t.eval(u);
                let e = 1e-2f32;
                let fd = Vec3::new(
                    t.eval(u + Vec3::X * e).0 - t.eval(u - Vec3::X * e).0,
                    t.eval(u + Vec3::Y * e).0 - t.eval(u - Vec3::Y * e).0,
                    t.eval(u + Vec3::Z * e).0 - t.eval(u - Vec3::Z * e).0,
                ) / (2.0 * e);
                prop_assert!((g - fd).length() < 2e-3 * (1.0 + g.length()), "{t}: {g} vs {fd}");
            }
        }

        #[test]
        fn every_surface_is_periodic(u in phase()) {
            for (t, _) in TPMS_NAMES {
                for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                    let (a, b) = (t.eval(u).0, t.eval(u + axis * TAU).0);
                    prop_assert!((a - b).abs() < 1e-4, "{t}: {a} vs {b}");
                }
            }
        }

        // Each surface splits space into two congruent labyrinths: a translation by half a
        // period (P, Neovius) or the point reflection (gyroid, diamond) flips the sign.
        #[test]
        fn the_two_labyrinths_are_congruent(u in phase()) {
            let half = Vec3::splat(std::f32::consts::PI);
            for (t, other) in [
                (Tpms::Gyroid, -u),
                (Tpms::SchwarzP, u + half),
                (Tpms::Neovius, u + half),
                (Tpms::Diamond, -u),
            ] {
                let (a, b) = (t.eval(u).0, t.eval(other).0);
                prop_assert!((a + b).abs() < 1e-4, "{t}: {a} vs {b}");
            }
        }

        // On the surface the gradient never vanishes, so dividing by it is safe there.
        #[test]
        fn the_gradient_is_bounded_away_from_zero_on_the_surface(u in phase()) {
            for (t, _) in TPMS_NAMES {
                let (f, g) = t.eval(u);
                if f.abs() < 1e-2 {
                    prop_assert!(g.length() > 0.2, "{t}: |grad| {} at {u}", g.length());
                }
            }
        }
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_refused() {
        for (t, n) in TPMS_NAMES {
            assert_eq!(n.parse::<Tpms>().unwrap(), t);
        }
        assert_eq!("Primitive".parse::<Tpms>().unwrap(), Tpms::SchwarzP);
        let e = "lidinoid".parse::<Tpms>().unwrap_err();
        assert!(e.contains("gyroid") && e.contains("neovius"), "{e}");
    }
}
