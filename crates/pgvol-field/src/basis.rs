//! The bases a coefficient volume can use, with their parameters, names and validity rules.

use serde::{Deserialize, Serialize};
use std::fmt;

/// Largest pseudo-Gaussian support radius accepted, in grid spacings: evaluation cost grows as
/// (r/k)³ and the study found nothing to gain beyond it.
pub const MAX_PG_RADIUS: f32 = 4.0;

/// A basis, with its parameters. Serialised as `"trilinear"`, `"bspline2"`, `"bspline3"` or
/// `{"pg":{"n":3,"r":1.5}}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Basis {
    /// Coefficients are the sampled values themselves, interpolated trilinearly: the baseline.
    Trilinear,
    /// Tensor-product quadratic B-spline centred on the nodes: C¹, support ±1.5 spacings.
    Bspline2,
    /// Tensor-product cubic B-spline: C², reproduces polynomials up to degree 3.
    Bspline3,
    /// Radial pseudo-Gaussian `(1 − d²/r²)^(n+1)` for `d < r`: C^n, `r` in grid spacings.
    Pg { n: u8, r: f32 },
}

impl Basis {
    /// The separable bases.
    pub const SEPARABLE: [Basis; 3] = [Basis::Trilinear, Basis::Bspline2, Basis::Bspline3];

    /// Short family name (`"pg"` for every pseudo-Gaussian); [`fmt::Display`] gives parameters too.
    pub fn name(self) -> &'static str {
        match self {
            Basis::Trilinear => "trilinear",
            Basis::Bspline2 => "bspline2",
            Basis::Bspline3 => "bspline3",
            Basis::Pg { .. } => "pg",
        }
    }

    /// Parses a family name, or `pg-n<N>-r<R>` (e.g. `pg-n3-r1.5`) as [`fmt::Display`] writes it.
    pub fn from_name(name: &str) -> Option<Basis> {
        match name {
            "trilinear" => Some(Basis::Trilinear),
            "bspline2" => Some(Basis::Bspline2),
            "bspline3" => Some(Basis::Bspline3),
            _ => {
                let rest = name.strip_prefix("pg-n")?;
                let (n, r) = rest.split_once("-r")?;
                let b = Basis::Pg {
                    n: n.parse().ok()?,
                    r: r.parse().ok()?,
                };
                b.validate().ok().map(|_| b)
            }
        }
    }

    /// Checks the parameters: `n` in 1..=4, `r` finite in (0, [`MAX_PG_RADIUS`]].
    pub fn validate(self) -> Result<(), String> {
        if let Basis::Pg { n, r } = self {
            if !(1..=4).contains(&n) {
                return Err(format!("pseudo-Gaussian order n must be 1..=4, got {n}"));
            }
            if !(r.is_finite() && r > 0.0 && r <= MAX_PG_RADIUS) {
                return Err(format!(
                    "pseudo-Gaussian radius r must be in (0, {MAX_PG_RADIUS}] spacings, got {r}"
                ));
            }
        }
        Ok(())
    }

    /// Support radius in grid spacings: per axis for separable bases, Euclidean for radial ones.
    pub fn support(self) -> f32 {
        match self {
            Basis::Trilinear => 1.0,
            Basis::Bspline2 => 1.5,
            Basis::Bspline3 => 2.0,
            Basis::Pg { r, .. } => r,
        }
    }

    /// Nodes per axis that one evaluation may touch.
    pub fn width(self) -> usize {
        match self {
            Basis::Trilinear => 2,
            Basis::Bspline2 => 3,
            Basis::Bspline3 => 4,
            // Nodes strictly within r of a point span at most 2⌈r⌉ positions per axis.
            Basis::Pg { r, .. } => 2 * r.ceil() as usize,
        }
    }

    pub fn is_separable(self) -> bool {
        !matches!(self, Basis::Pg { .. })
    }

    /// Whether the coefficients outside the grid are mirror images of those inside (the
    /// B-spline prefilter's boundary condition) rather than zero.
    pub fn mirrors_boundary(self) -> bool {
        self.is_separable()
    }
}

impl fmt::Display for Basis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Basis::Pg { n, r } => write!(f, "pg-n{n}-r{r}"),
            b => f.write_str(b.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for b in [
            Basis::Trilinear,
            Basis::Bspline2,
            Basis::Bspline3,
            Basis::Pg { n: 3, r: 1.5 },
            Basis::Pg { n: 1, r: 2.0 },
        ] {
            assert_eq!(Basis::from_name(&b.to_string()), Some(b));
        }
        assert_eq!(Basis::from_name("gaussian"), None);
        assert_eq!(Basis::from_name("pg-n7-r1.5"), None);
        assert_eq!(Basis::from_name("pg-n3-r9"), None);
    }

    #[test]
    fn serialised_names_are_stable() {
        let j = |b: Basis| serde_json::to_string(&b).unwrap();
        assert_eq!(j(Basis::Trilinear), "\"trilinear\"");
        assert_eq!(j(Basis::Bspline3), "\"bspline3\"");
        assert_eq!(j(Basis::Bspline2), "\"bspline2\"");
        assert_eq!(j(Basis::Pg { n: 3, r: 1.5 }), r#"{"pg":{"n":3,"r":1.5}}"#);
        let back: Basis = serde_json::from_str(r#"{"pg":{"n":4,"r":2.0}}"#).unwrap();
        assert_eq!(back, Basis::Pg { n: 4, r: 2.0 });
        let back: Basis = serde_json::from_str("\"bspline3\"").unwrap();
        assert_eq!(back, Basis::Bspline3);
    }

    #[test]
    fn invalid_parameters_are_refused() {
        assert!(Basis::Pg { n: 0, r: 1.5 }.validate().is_err());
        assert!(Basis::Pg { n: 3, r: f32::NAN }.validate().is_err());
        assert!(Basis::Pg { n: 3, r: -1.0 }.validate().is_err());
        assert!(Basis::Pg { n: 4, r: 4.0 }.validate().is_ok());
    }
}
