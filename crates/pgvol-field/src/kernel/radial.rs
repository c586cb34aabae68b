//! The pseudo-Gaussian radial basis `pg_n(d) = (1 − d²/r²)^(n+1)` for `d < r`, zero beyond: its
//! first n derivatives vanish at `d = r`, so sums of shifted copies are C^n.

use glam::{Mat3, Vec3};

use super::jet::{Jet, Kernel};

/// `n` is the continuity order, `r` the support radius in grid spacings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PseudoGaussian {
    pub n: u8,
    pub r: f32,
}

impl PseudoGaussian {
    /// Value only: the hot path of matrix-free fitting.
    #[inline]
    pub fn value_sq(&self, d2: f32) -> f32 {
        let s = d2 / (self.r * self.r);
        if s >= 1.0 {
            0.0
        } else {
            (1.0 - s).powi(self.n as i32 + 1)
        }
    }
}

impl Kernel for PseudoGaussian {
    fn support(&self) -> f32 {
        self.r
    }

    #[inline]
    fn jet(&self, d: Vec3) -> Jet {
        let r2 = self.r * self.r;
        let s = d.length_squared() / r2;
        if s >= 1.0 {
            return Jet::ZERO;
        }
        let n = self.n as i32;
        let m = 1.0 - s;
        let mn1 = if n >= 1 { m.powi(n - 1) } else { 0.0 };
        let mn = mn1 * m;
        // Chain rule through s = |d|²/r²: ∇s = 2d/r², ∇∇s = 2I/r².
        let f1 = -(n as f32 + 1.0) * mn;
        let f2 = (n as f32 + 1.0) * n as f32 * mn1;
        let gradient = d * (2.0 * f1 / r2);
        let hessian =
            Mat3::from_diagonal(Vec3::splat(2.0 * f1 / r2)) + outer(d, d) * (4.0 * f2 / (r2 * r2));
        Jet {
            value: mn * m,
            gradient,
            hessian,
        }
    }

    fn partition_of_unity(&self) -> bool {
        // Only the degenerate r ≤ 1 case, where each node sees only itself, sums to one at nodes;
        // between nodes no pseudo-Gaussian lattice sum is constant.
        false
    }
}

#[inline]
fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}
