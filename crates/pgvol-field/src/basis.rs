//! The bases a coefficient volume can use. Each is separable: its weights along one axis are a
//! function of the fractional position in a cell, so a point touches a fixed block of nodes.

use serde::{Deserialize, Serialize};

/// A basis, with its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Basis {
    /// Coefficients are the sampled values themselves, interpolated trilinearly: the baseline.
    Trilinear,
    /// Tensor-product cubic B-spline: C², reproduces polynomials up to degree 3.
    Bspline3,
}

impl Basis {
    pub fn name(self) -> &'static str {
        match self {
            Basis::Trilinear => "trilinear",
            Basis::Bspline3 => "bspline3",
        }
    }

    pub fn from_name(name: &str) -> Option<Basis> {
        match name {
            "trilinear" => Some(Basis::Trilinear),
            "bspline3" => Some(Basis::Bspline3),
            _ => None,
        }
    }

    /// Nodes per axis that one evaluation touches.
    pub fn width(self) -> usize {
        match self {
            Basis::Trilinear => 2,
            Basis::Bspline3 => 4,
        }
    }

    /// Index of the first node touched along an axis, for a point at grid coordinate `cell + t`.
    pub fn first_node(self, cell: i64) -> i64 {
        match self {
            Basis::Trilinear => cell,
            Basis::Bspline3 => cell - 1,
        }
    }

    /// Weights and their derivatives (per grid unit) along one axis at fraction `t` in `[0, 1]`.
    #[inline]
    pub fn weights(self, t: f32) -> ([f32; 4], [f32; 4]) {
        match self {
            Basis::Trilinear => ([1.0 - t, t, 0.0, 0.0], [-1.0, 1.0, 0.0, 0.0]),
            Basis::Bspline3 => {
                let s = 1.0 - t;
                let (t2, t3) = (t * t, t * t * t);
                (
                    [
                        s * s * s / 6.0,
                        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                        t3 / 6.0,
                    ],
                    [
                        -0.5 * s * s,
                        1.5 * t2 - 2.0 * t,
                        -1.5 * t2 + t + 0.5,
                        0.5 * t2,
                    ],
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const ALL: [Basis; 2] = [Basis::Trilinear, Basis::Bspline3];

    proptest! {
        /// Both bases form a partition of unity and reproduce linear functions.
        #[test]
        fn partition_of_unity_and_linear_reproduction(t in 0.0f32..=1.0) {
            for b in ALL {
                let (w, d) = b.weights(t);
                let first = b.first_node(0) as f32;
                let sum: f32 = w.iter().sum();
                let lin: f32 = w.iter().enumerate().map(|(n, w)| w * (first + n as f32)).sum();
                let dsum: f32 = d.iter().sum();
                let dlin: f32 = d.iter().enumerate().map(|(n, d)| d * (first + n as f32)).sum();
                prop_assert!((sum - 1.0).abs() < 1e-6);
                prop_assert!((lin - t).abs() < 1e-5);
                prop_assert!(dsum.abs() < 1e-6);
                prop_assert!((dlin - 1.0).abs() < 1e-5);
            }
        }

        /// The derivative weights are the derivatives of the weights (central differences).
        #[test]
        fn derivatives_match_finite_differences(t in 0.01f32..0.99) {
            for b in ALL {
                let e = 1e-3;
                let (lo, _) = b.weights(t - e);
                let (hi, _) = b.weights(t + e);
                let (_, d) = b.weights(t);
                for n in 0..4 {
                    prop_assert!(((hi[n] - lo[n]) / (2.0 * e) - d[n]).abs() < 2e-3);
                }
            }
        }
    }

    #[test]
    fn bspline_is_continuous_across_cells() {
        // At t = 1 the weights of nodes (first..first+4) must equal those at t = 0 shifted by one.
        let (w1, d1) = Basis::Bspline3.weights(1.0);
        let (w0, d0) = Basis::Bspline3.weights(0.0);
        for n in 0..3 {
            assert!((w1[n + 1] - w0[n]).abs() < 1e-6);
            assert!((d1[n + 1] - d0[n]).abs() < 1e-6);
        }
        assert!(w1[0].abs() < 1e-7 && w0[3].abs() < 1e-7);
    }

    #[test]
    fn names_round_trip() {
        for b in ALL {
            assert_eq!(Basis::from_name(b.name()), Some(b));
        }
        assert_eq!(Basis::from_name("gaussian"), None);
    }
}
