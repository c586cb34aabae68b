//! Quadrics of ten coefficients in local coordinates, their least-squares and exact solves, and
//! the box of the region where a bounded quadric is positive.
//!
//! A quadric is stored around a centre `c` with a length `s`: `Q(x) = q · m((x − c) / s)` with
//! the monomials `m(u)` in the paper's order (x², y², z², xy, xz, yz, x, y, z, 1). Local
//! coordinates of order one keep the 10 × 10 systems well conditioned at any mesh scale.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Coefficients of a quadric.
pub const TERMS: usize = 10;

/// The monomials of `u` in the paper's order.
#[inline]
pub fn monomials(u: DVec3) -> [f64; TERMS] {
    [
        u.x * u.x,
        u.y * u.y,
        u.z * u.z,
        u.x * u.y,
        u.x * u.z,
        u.y * u.z,
        u.x,
        u.y,
        u.z,
        1.0,
    ]
}

/// `Q(x) = q · m((x − centre) / scale)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quadric {
    pub centre: DVec3,
    pub scale: f64,
    pub q: [f64; TERMS],
}

impl Quadric {
    /// Local coordinates of `p`.
    #[inline]
    pub fn local(&self, p: DVec3) -> DVec3 {
        (p - self.centre) / self.scale
    }

    #[inline]
    pub fn value(&self, p: DVec3) -> f64 {
        let m = monomials(self.local(p));
        self.q.iter().zip(m).map(|(a, b)| a * b).sum()
    }

    /// Value and gradient (in the units of `p`).
    #[inline]
    pub fn value_gradient(&self, p: DVec3) -> (f64, DVec3) {
        let u = self.local(p);
        let q = &self.q;
        let du = DVec3::new(
            2.0 * q[0] * u.x + q[3] * u.y + q[4] * u.z + q[6],
            2.0 * q[1] * u.y + q[3] * u.x + q[5] * u.z + q[7],
            2.0 * q[2] * u.z + q[4] * u.x + q[5] * u.y + q[8],
        );
        (self.value(p), du / self.scale)
    }

    /// The symmetric matrix `A` of the quadratic part in local coordinates (`uᵀAu`).
    fn quadratic_part(&self) -> [[f64; 3]; 3] {
        let q = &self.q;
        [
            [q[0], 0.5 * q[3], 0.5 * q[4]],
            [0.5 * q[3], q[1], 0.5 * q[5]],
            [0.5 * q[4], 0.5 * q[5], q[2]],
        ]
    }

    /// Whether the quadratic part is negative definite: the positive region is then an
    /// ellipsoid (or empty), so a perturbation built on it stays local.
    pub fn is_bounded_bump(&self) -> bool {
        let a = self.quadratic_part();
        let neg = a.map(|r| r.map(|x| -x));
        positive_definite(&neg)
    }

    /// Whether the quadratic part is positive definite: the negative region (inside) is an
    /// ellipsoid, and the zero set a single closed surface.
    pub fn is_ellipsoid(&self) -> bool {
        positive_definite(&self.quadratic_part())
    }

    /// The axis-aligned box (in the units of `p`) of the region `Q ≥ 0` of a bounded bump, or
    /// `None` when that region is empty or unbounded.
    pub fn positive_box(&self) -> Option<(DVec3, DVec3)> {
        if !self.is_bounded_bump() {
            return None;
        }
        let a = self.quadratic_part();
        let b = DVec3::new(self.q[6], self.q[7], self.q[8]);
        let inv = inverse3(&a)?;
        // Apex u0 = −A⁻¹b / 2, where Q(u) = (u − u0)ᵀA(u − u0) + Q(u0).
        let u0 = -0.5 * mul3(&inv, b);
        let peak = self.q[9] + 0.5 * b.dot(u0);
        if peak.is_nan() || peak <= 0.0 {
            return None;
        }
        // Extent of the ellipsoid (u − u0)ᵀ(−A)(u − u0) ≤ peak along axis i: √(peak · (−A)⁻¹ᵢᵢ).
        let half = DVec3::new(
            (peak * -inv[0][0]).sqrt(),
            (peak * -inv[1][1]).sqrt(),
            (peak * -inv[2][2]).sqrt(),
        );
        if !half.is_finite() {
            return None;
        }
        let lo = self.centre + (u0 - half) * self.scale;
        let hi = self.centre + (u0 + half) * self.scale;
        Some((lo, hi))
    }

    /// The largest value of a bounded bump (at its apex), or `None` when it is not one.
    pub fn peak(&self) -> Option<f64> {
        if !self.is_bounded_bump() {
            return None;
        }
        let a = self.quadratic_part();
        let b = DVec3::new(self.q[6], self.q[7], self.q[8]);
        let u0 = -0.5 * mul3(&inverse3(&a)?, b);
        Some(self.q[9] + 0.5 * b.dot(u0))
    }

    /// The largest half-width of [`positive_box`](Self::positive_box), in local units.
    pub fn positive_reach(&self) -> Option<f64> {
        self.positive_box()
            .map(|(lo, hi)| 0.5 * (hi - lo).max_element() / self.scale)
    }
}

fn positive_definite(a: &[[f64; 3]; 3]) -> bool {
    let m1 = a[0][0];
    let m2 = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    m1 > 0.0 && m2 > 0.0 && det3(a) > 0.0
}

fn det3(a: &[[f64; 3]; 3]) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

fn inverse3(a: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let d = det3(a);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
    };
    // The inverse is the transposed cofactor matrix over the determinant.
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = c(j, i) / d;
        }
    }
    Some(inv)
}

fn mul3(a: &[[f64; 3]; 3], v: DVec3) -> DVec3 {
    DVec3::new(
        a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
        a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
        a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z,
    )
}

/// Solves the square system `a · x = b` by Gaussian elimination with partial pivoting;
/// `None` when it is singular to working precision.
pub fn solve_square(mut a: [[f64; TERMS]; TERMS], mut b: [f64; TERMS]) -> Option<[f64; TERMS]> {
    let scale = a
        .iter()
        .flatten()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    for col in 0..TERMS {
        let pivot = (col..TERMS).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= 1e-13 * scale {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..TERMS {
            let f = a[row][col] / a[col][col];
            if f != 0.0 {
                let pivot_row = a[col];
                for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                    *x -= f * p;
                }
                b[row] -= f * b[col];
            }
        }
    }
    let mut x = [0.0; TERMS];
    for row in (0..TERMS).rev() {
        let s: f64 = (row + 1..TERMS).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The coefficients through exactly ten points (the paper's system): `Q(uᵢ) = tᵢ`.
pub fn interpolate(rows: &[[f64; TERMS]; TERMS], targets: &[f64; TERMS]) -> Option<[f64; TERMS]> {
    solve_square(*rows, *targets)
}

/// Least squares with a pull toward `prior`: minimises `Σ (rowᵢ · q − tᵢ)² + λ |q − prior|²`
/// through its 10 × 10 normal equations. With λ = 0 and ten independent rows this is the
/// exact interpolation; λ > 0 picks, among the near-solutions of a degenerate set (points on a
/// plane leave the normal direction free), the one closest to the prior.
pub fn least_squares(
    rows: &[[f64; TERMS]],
    targets: &[f64],
    prior: &[f64; TERMS],
    lambda: f64,
) -> Option<[f64; TERMS]> {
    let mut n = [[0.0; TERMS]; TERMS];
    let mut rhs = [0.0; TERMS];
    for (row, &t) in rows.iter().zip(targets) {
        for i in 0..TERMS {
            rhs[i] += row[i] * t;
            for j in 0..TERMS {
                n[i][j] += row[i] * row[j];
            }
        }
    }
    for i in 0..TERMS {
        n[i][i] += lambda;
        rhs[i] += lambda * prior[i];
    }
    solve_square(n, rhs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    #[test]
    fn ten_points_recover_a_known_quadric() {
        let truth = [0.7, -1.2, 0.4, 0.3, -0.8, 0.5, 0.1, -0.6, 0.9, -0.25];
        let mut s = 42;
        for _ in 0..20 {
            let mut rows = [[0.0; TERMS]; TERMS];
            let mut t = [0.0; TERMS];
            for i in 0..TERMS {
                let u = DVec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s));
                rows[i] = monomials(u);
                t[i] = rows[i].iter().zip(truth).map(|(a, b)| a * b).sum();
            }
            let q = interpolate(&rows, &t).expect("random points are independent");
            for (a, b) in q.iter().zip(truth) {
                assert!((a - b).abs() < 1e-8, "{q:?}");
            }
            let ls = least_squares(&rows, &t, &[0.0; TERMS], 0.0).unwrap();
            for (a, b) in ls.iter().zip(truth) {
                assert!((a - b).abs() < 1e-5, "{ls:?}");
            }
        }
    }

    #[test]
    fn coplanar_points_are_singular_and_the_prior_decides() {
        // Ten points on z = 0: z², xz, yz and z are free.
        let mut s = 7;
        let mut rows = [[0.0; TERMS]; TERMS];
        for row in &mut rows {
            *row = monomials(DVec3::new(lcg(&mut s), lcg(&mut s), 0.0));
        }
        assert!(interpolate(&rows, &[1.0; TERMS]).is_none());
        let prior = [-1.0, -1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let q = least_squares(&rows, &[0.5; TERMS], &prior, 1e-6).unwrap();
        // The free z² coefficient stays at the prior's; the plane's data is met.
        assert!((q[2] + 1.0).abs() < 1e-6, "{q:?}");
        for row in &rows {
            let v: f64 = row.iter().zip(q).map(|(a, b)| a * b).sum();
            assert!((v - 0.5).abs() < 1e-3);
        }
    }

    #[test]
    fn gradient_matches_differences() {
        let quad = Quadric {
            centre: DVec3::new(0.3, -0.2, 1.0),
            scale: 0.5,
            q: [0.7, -1.2, 0.4, 0.3, -0.8, 0.5, 0.1, -0.6, 0.9, -0.25],
        };
        let p = DVec3::new(0.1, 0.2, 0.7);
        let (_, g) = quad.value_gradient(p);
        let h = 1e-6;
        let fd = DVec3::new(
            quad.value(p + DVec3::X * h) - quad.value(p - DVec3::X * h),
            quad.value(p + DVec3::Y * h) - quad.value(p - DVec3::Y * h),
            quad.value(p + DVec3::Z * h) - quad.value(p - DVec3::Z * h),
        ) / (2.0 * h);
        assert!((g - fd).length() < 1e-6, "{g} vs {fd}");
    }

    #[test]
    fn bump_box_is_the_ellipsoid_box() {
        // Q = 1 − (x/2)² − y² − (z/3)² around (1, 2, 3): half-widths 2, 1, 3.
        let quad = Quadric {
            centre: DVec3::new(1.0, 2.0, 3.0),
            scale: 1.0,
            q: [-0.25, -1.0, -1.0 / 9.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        };
        let (lo, hi) = quad.positive_box().unwrap();
        assert!((lo - DVec3::new(-1.0, 1.0, 0.0)).length() < 1e-12, "{lo}");
        assert!((hi - DVec3::new(3.0, 3.0, 6.0)).length() < 1e-12, "{hi}");
        let saddle = Quadric {
            q: [-1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            ..quad
        };
        assert!(saddle.positive_box().is_none());
    }
}
