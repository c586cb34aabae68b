//! The global fit of Turk and O'Brien: f(x) = Σ dⱼ |x − cⱼ|³ + a + b·x, the cubic being
//! conditionally positive definite, so the linear term and its side conditions Σ dⱼ = 0,
//! Σ dⱼ cⱼ = 0 make the system solvable. It is dense: the solve is O(n³) in time and O(n²)
//! in memory, which caps the centres at [`MAX_CUBIC_CENTRES`].

use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// The most centres the dense solve takes: a 4004² f64 matrix is 128 MB and its elimination
/// about 2·10¹⁰ operations, some seconds on two cores.
pub const MAX_CUBIC_CENTRES: usize = 4000;

/// A solved cubic interpolant.
pub struct CubicFit {
    centres: Vec<DVec3>,
    weights: Vec<f64>,
    /// a, b of the linear term.
    linear: [f64; 4],
}

/// Bytes the dense solve of `n` centres needs.
pub fn cubic_bytes(n: usize) -> u64 {
    ((n + 4) * (n + 4) * 8) as u64
}

/// Interpolates `values` at `centres`; `None` when the system is singular (repeated centres
/// or all centres on one plane).
pub fn fit(centres: &[Vec3], values: &[f32]) -> Option<CubicFit> {
    let n = centres.len();
    let m = n + 4;
    let c: Vec<DVec3> = centres.iter().map(|p| p.as_dvec3()).collect();
    let mut a = vec![0.0f64; m * m];
    a.par_chunks_mut(m).enumerate().for_each(|(i, row)| {
        if i < n {
            for j in 0..n {
                row[j] = c[i].distance(c[j]).powi(3);
            }
            row[n..].copy_from_slice(&[1.0, c[i].x, c[i].y, c[i].z]);
        } else {
            let k = i - n;
            for j in 0..n {
                row[j] = [1.0, c[j].x, c[j].y, c[j].z][k];
            }
        }
    });
    let mut b: Vec<f64> = values.iter().map(|&v| v as f64).collect();
    b.resize(m, 0.0);
    let x = solve_dense(&mut a, &mut b, m)?;
    Some(CubicFit {
        centres: c,
        weights: x[..n].to_vec(),
        linear: [x[n], x[n + 1], x[n + 2], x[n + 3]],
    })
}

/// Gaussian elimination with partial pivoting, the row updates in parallel.
fn solve_dense(a: &mut [f64], b: &mut [f64], m: usize) -> Option<Vec<f64>> {
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    for k in 0..m {
        let p = (k..m).max_by(|&i, &j| a[i * m + k].abs().total_cmp(&a[j * m + k].abs()))?;
        if a[p * m + k].abs() <= scale * 1e-14 {
            return None;
        }
        if p != k {
            for j in 0..m {
                a.swap(k * m + j, p * m + j);
            }
            b.swap(k, p);
        }
        let (top, rest) = a.split_at_mut((k + 1) * m);
        let pivot = &top[k * m..];
        let bk = b[k];
        let (_, b_rest) = b.split_at_mut(k + 1);
        rest.par_chunks_mut(m)
            .zip(b_rest.par_iter_mut())
            .for_each(|(row, bi)| {
                let f = row[k] / pivot[k];
                if f != 0.0 {
                    for j in k..m {
                        row[j] -= f * pivot[j];
                    }
                    *bi -= f * bk;
                }
            });
    }
    let mut x = vec![0.0; m];
    for k in (0..m).rev() {
        let s: f64 = (k + 1..m).map(|j| a[k * m + j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k * m + k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

impl CubicFit {
    /// The interpolant at `x`.
    pub fn value(&self, x: Vec3) -> f32 {
        let x = x.as_dvec3();
        let [a, bx, by, bz] = self.linear;
        let sum: f64 = self
            .centres
            .iter()
            .zip(&self.weights)
            .map(|(c, d)| d * c.distance(x).powi(3))
            .sum();
        (sum + a + bx * x.x + by * x.y + bz * x.z) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_linear_functions_and_interpolates() {
        let centres: Vec<Vec3> = (0..60)
            .map(|i| {
                let t = i as f32;
                Vec3::new((t * 0.37).fract(), (t * 0.61).fract(), (t * 0.113).fract())
            })
            .collect();
        let linear: Vec<f32> = centres.iter().map(|c| 1.0 + c.x - 2.0 * c.z).collect();
        let fit = fit(&centres, &linear).expect("solvable");
        let q = Vec3::new(0.3, 0.8, 0.4);
        assert!((fit.value(q) - (1.0 + 0.3 - 0.8)).abs() < 1e-4);
        let curved: Vec<f32> = centres.iter().map(|c| c.length_squared()).collect();
        let fit = super::fit(&centres, &curved).expect("solvable");
        for (c, v) in centres.iter().zip(&curved) {
            assert!((fit.value(*c) - v).abs() < 1e-4);
        }
        assert!(super::fit(&[Vec3::ZERO; 5], &[0.0; 5]).is_none());
    }
}
