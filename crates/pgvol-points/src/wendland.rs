//! Compactly supported radial basis functions (Morse et al. 2001): f(x) = Σ dⱼ φ(|x − cⱼ| / R)
//! with Wendland's φ(r) = (1 − r)⁴(4r + 1), positive definite in 3D, so the interpolation
//! matrix is sparse, symmetric and positive definite and conjugate gradients solve it. Its
//! diagonal is φ(0) = 1, so Jacobi preconditioning would change nothing.

use glam::Vec3;
use rayon::prelude::*;

use crate::index::PointIndex;

/// Wendland's C² function on [0, 1], zero beyond.
#[inline]
pub fn wendland(r: f32) -> f32 {
    if r >= 1.0 {
        0.0
    } else {
        let s = 1.0 - r;
        let s2 = s * s;
        s2 * s2 * (4.0 * r + 1.0)
    }
}

/// Relative residual the conjugate gradients stop at: the correction is a small part of the
/// field, and 1e-4 of it is far below what the grid resolves.
pub const CG_TOLERANCE: f64 = 1e-4;

/// Iteration cap; well-spread centres converge in tens.
pub const CG_MAX_ITERATIONS: usize = 2000;

/// A solved Wendland interpolant.
pub struct WendlandFit<'a> {
    index: PointIndex<'a>,
    weights: Vec<f32>,
    radius: f32,
    /// Conjugate-gradient iterations.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Stored matrix entries.
    pub entries: usize,
}

impl WendlandFit<'_> {
    /// Whether the residual reached [`CG_TOLERANCE`] before the iteration cap.
    pub fn converged(&self) -> bool {
        self.residual <= CG_TOLERANCE
    }
}

/// Bytes of the stored matrix per entry (u32 column, f32 value).
pub const BYTES_PER_ENTRY: u64 = 8;

/// Interpolates `values` at `centres` with support radius `radius`.
pub fn fit<'a>(centres: &'a [Vec3], values: &[f32], radius: f32) -> WendlandFit<'a> {
    fit_index(PointIndex::new(centres, radius), values, radius)
}

/// As [`fit`], keeping the centres.
pub fn fit_owned(centres: Vec<Vec3>, values: &[f32], radius: f32) -> WendlandFit<'static> {
    fit_index(PointIndex::new(centres, radius), values, radius)
}

fn fit_index<'a>(index: PointIndex<'a>, values: &[f32], radius: f32) -> WendlandFit<'a> {
    let centres = index.points();
    let rows: Vec<Vec<(u32, f32)>> = centres
        .par_iter()
        .map(|&c| {
            let mut row = Vec::new();
            index.for_each_within(c, radius, |j, d2| {
                row.push((j as u32, wendland(d2.sqrt() / radius)));
            });
            row.sort_unstable_by_key(|e| e.0);
            row
        })
        .collect();
    let entries = rows.iter().map(Vec::len).sum();
    let matvec = |x: &[f64], y: &mut [f64]| {
        y.par_iter_mut().zip(&rows).for_each(|(yi, row)| {
            *yi = row.iter().map(|&(j, a)| a as f64 * x[j as usize]).sum();
        });
    };
    let b: Vec<f64> = values.iter().map(|&v| v as f64).collect();
    let (x, iterations, residual) = conjugate_gradients(matvec, &b);
    WendlandFit {
        index,
        weights: x.iter().map(|&v| v as f32).collect(),
        radius,
        iterations,
        residual,
        entries,
    }
}

/// Solves A x = b for a symmetric positive definite A given by its product.
fn conjugate_gradients(matvec: impl Fn(&[f64], &mut [f64]), b: &[f64]) -> (Vec<f64>, usize, f64) {
    let n = b.len();
    let norm_b = dot(b, b).sqrt().max(f64::MIN_POSITIVE);
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut p = r.clone();
    let mut ap = vec![0.0; n];
    let mut rr = dot(&r, &r);
    let mut iterations = 0;
    while iterations < CG_MAX_ITERATIONS && rr.sqrt() / norm_b > CG_TOLERANCE {
        matvec(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rr / pap;
        x.par_iter_mut()
            .zip(r.par_iter_mut())
            .zip(p.par_iter().zip(&ap))
            .for_each(|((xi, ri), (pi, api))| {
                *xi += alpha * pi;
                *ri -= alpha * api;
            });
        let rr_new = dot(&r, &r);
        let beta = rr_new / rr;
        p.par_iter_mut()
            .zip(&r)
            .for_each(|(pi, ri)| *pi = ri + beta * *pi);
        rr = rr_new;
        iterations += 1;
    }
    (x, iterations, rr.sqrt() / norm_b)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.par_iter().zip(b).map(|(x, y)| x * y).sum()
}

impl WendlandFit<'_> {
    /// Number of centres.
    pub fn centres(&self) -> usize {
        self.index.points().len()
    }

    /// The interpolant at `x`.
    pub fn value(&self, x: Vec3) -> f32 {
        let mut sum = 0.0;
        self.index.for_each_within(x, self.radius, |j, d2| {
            sum += self.weights[j] * wendland(d2.sqrt() / self.radius);
        });
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_its_centres() {
        let centres: Vec<Vec3> = (0..400)
            .map(|i| {
                let t = i as f32;
                Vec3::new((t * 0.37).fract(), (t * 0.61).fract(), (t * 0.113).fract())
            })
            .collect();
        let values: Vec<f32> = centres
            .iter()
            .map(|c| c.x - 2.0 * c.y + c.z * c.z)
            .collect();
        let fit = fit(&centres, &values, 0.3);
        assert!(fit.residual < 2e-4, "{}", fit.residual);
        for (c, v) in centres.iter().zip(&values) {
            assert!(
                (fit.value(*c) - v).abs() < 1e-3,
                "{c}: {} vs {v}",
                fit.value(*c)
            );
        }
        assert_eq!(wendland(1.0), 0.0);
        assert_eq!(wendland(0.0), 1.0);
    }
}
