//! Exact B-spline interpolation by recursive filtering (Unser, Aldroubi & Eden 1991): the
//! coefficients whose spline passes through given samples, in O(N), with mirror boundaries.
//! Node-centred splines of degree 2 and 3 have sampled kernels `[1, 6, 1]/8` and `[1, 4, 1]/6`;
//! each inverse is one causal and one anti-causal pass with the pole `z` of `z + 1/z = −6` or `−4`.

use rayon::prelude::*;

/// The pole of the cubic B-spline's inverse filter, √3 − 2.
pub const CUBIC_POLE: f64 = -0.267_949_192_431_122_7;
/// The pole of the quadratic B-spline's inverse filter, 2√2 − 3.
pub const QUADRATIC_POLE: f64 = -0.171_572_875_253_809_9;

/// Turns samples along one line into cubic B-spline coefficients, in place, assuming the signal
/// continues by mirror symmetry about both end samples.
pub fn prefilter_line(line: &mut [f64]) {
    prefilter_line_with(line, CUBIC_POLE);
}

/// As [`prefilter_line`] for the symmetric 3-tap kernel whose inverse has pole `z`.
pub fn prefilter_line_with(line: &mut [f64], z: f64) {
    let n = line.len();
    if n < 2 {
        return;
    }
    // (1 − z)(1 − 1/z) is the kernel's normalisation: 6 for the cubic, 8 for the quadratic.
    let gain = (1.0 - z) * (1.0 - 1.0 / z);
    for v in line.iter_mut() {
        *v *= gain;
    }
    // Causal initial value: the infinite mirrored sum, truncated where z^k falls below 1e-12.
    let horizon = ((1e-12f64).ln() / z.abs().ln()).ceil() as usize;
    line[0] = if horizon < n {
        let mut zk = z;
        let mut sum = line[0];
        for v in &line[1..horizon] {
            sum += zk * v;
            zk *= z;
        }
        sum
    } else {
        let zn = z.powi(n as i32 - 1);
        let z2n = zn * zn;
        let iz = 1.0 / z;
        let mut zk = z;
        let mut zback = zn * iz; // z^(2n-3) / z^(n-1) bookkeeping: z^(n-2)
        let mut sum = line[0] + zn * line[n - 1];
        zback *= zn; // z^(2n-3)
        for v in &line[1..n - 1] {
            sum += (zk + zback) * v;
            zk *= z;
            zback *= iz;
        }
        sum / (1.0 - z2n)
    };
    for k in 1..n {
        line[k] += z * line[k - 1];
    }
    line[n - 1] = (z / (z * z - 1.0)) * (line[n - 1] + z * line[n - 2]);
    for k in (0..n - 1).rev() {
        line[k] = z * (line[k + 1] - line[k]);
    }
}

/// Prefilters a 3D array (x fastest) along all three axes for the cubic B-spline.
pub fn prefilter_volume(values: &mut [f32], dims: [usize; 3]) {
    prefilter_volume_with(values, dims, CUBIC_POLE);
}

/// As [`prefilter_volume`] with the pole `z` of another spline degree.
pub fn prefilter_volume_with(values: &mut [f32], dims: [usize; 3], z: f64) {
    let [nx, ny, nz] = dims;
    // x lines are contiguous.
    values.par_chunks_mut(nx).for_each(|row| {
        let mut line: Vec<f64> = row.iter().map(|&v| v as f64).collect();
        prefilter_line_with(&mut line, z);
        for (d, s) in row.iter_mut().zip(&line) {
            *d = *s as f32;
        }
    });
    // y lines: within each z-plane.
    values.par_chunks_mut(nx * ny).for_each(|plane| {
        let mut line = vec![0.0f64; ny];
        for i in 0..nx {
            for (j, v) in line.iter_mut().enumerate() {
                *v = plane[i + nx * j] as f64;
            }
            prefilter_line_with(&mut line, z);
            for (j, v) in line.iter().enumerate() {
                plane[i + nx * j] = *v as f32;
            }
        }
    });
    // z lines: gather per (x, y) column in parallel over y, then scatter.
    let plane = nx * ny;
    let columns: Vec<Vec<f32>> = (0..plane)
        .into_par_iter()
        .map(|c| {
            let mut line: Vec<f64> = (0..nz).map(|k| values[c + plane * k] as f64).collect();
            prefilter_line_with(&mut line, z);
            line.into_iter().map(|v| v as f32).collect()
        })
        .collect();
    for (c, col) in columns.iter().enumerate() {
        for (k, v) in col.iter().enumerate() {
            values[c + plane * k] = *v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Evaluates the spline with mirrored coefficients at integer positions: must give the samples.
    fn reconstruct(coeffs: &[f64]) -> Vec<f64> {
        let n = coeffs.len() as i64;
        let at = |k: i64| {
            let m = if k < 0 {
                -k
            } else if k >= n {
                2 * (n - 1) - k
            } else {
                k
            };
            coeffs[m as usize]
        };
        (0..n)
            .map(|k| (at(k - 1) + 4.0 * at(k) + at(k + 1)) / 6.0)
            .collect()
    }

    #[test]
    fn interpolates_short_and_long_lines() {
        for n in [2usize, 3, 5, 17, 40, 200] {
            let samples: Vec<f64> = (0..n)
                .map(|k| ((k * 7919) % 13) as f64 - 6.0 + 0.1 * k as f64)
                .collect();
            let mut c = samples.clone();
            prefilter_line(&mut c);
            for (a, b) in reconstruct(&c).iter().zip(&samples) {
                assert!((a - b).abs() < 1e-9, "n = {n}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn quadratic_pole_inverts_its_kernel() {
        let z = QUADRATIC_POLE;
        assert!((z + 1.0 / z + 6.0).abs() < 1e-12);
        for n in [2usize, 3, 4, 9, 60] {
            let samples: Vec<f64> = (0..n)
                .map(|k| ((k * 31) % 7) as f64 - 0.3 * k as f64)
                .collect();
            let mut c = samples.clone();
            prefilter_line_with(&mut c, z);
            let at = |k: i64| c[super::super::stencil::mirror(k, n)];
            for (k, want) in samples.iter().enumerate() {
                let k = k as i64;
                let got = (at(k - 1) + 6.0 * at(k) + at(k + 1)) / 8.0;
                assert!(
                    (got - want).abs() < 1e-9,
                    "n = {n}, k = {k}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn volume_prefilter_interpolates() {
        let dims = [5, 6, 7];
        let f = |i: usize, j: usize, k: usize| ((i * 3 + j * 5 + k * 7) % 11) as f32;
        let mut v = Vec::new();
        for k in 0..7 {
            for j in 0..6 {
                for i in 0..5 {
                    v.push(f(i, j, k));
                }
            }
        }
        let samples = v.clone();
        prefilter_volume(&mut v, dims);
        // Reconstruct at nodes: separable [1 4 1]/6 stencil with mirroring.
        let at = |i: i64, j: i64, k: i64| {
            let m = |x: i64, n: i64| {
                if x < 0 {
                    -x
                } else if x >= n {
                    2 * (n - 1) - x
                } else {
                    x
                }
            };
            let (i, j, k) = (m(i, 5), m(j, 6), m(k, 7));
            v[(i + 5 * (j + 6 * k)) as usize] as f64
        };
        let w = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0];
        for k in 0..7i64 {
            for j in 0..6i64 {
                for i in 0..5i64 {
                    let mut s = 0.0;
                    for (a, wa) in w.iter().enumerate() {
                        for (b, wb) in w.iter().enumerate() {
                            for (c, wc) in w.iter().enumerate() {
                                s += wa
                                    * wb
                                    * wc
                                    * at(i + a as i64 - 1, j + b as i64 - 1, k + c as i64 - 1);
                            }
                        }
                    }
                    let want = samples[(i + 5 * (j + 6 * k)) as usize] as f64;
                    assert!((s - want).abs() < 1e-4, "{i} {j} {k}: {s} vs {want}");
                }
            }
        }
    }
}
