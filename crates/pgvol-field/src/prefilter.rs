//! Exact B-spline interpolation by recursive filtering (Unser, Aldroubi & Eden 1991): the
//! coefficients whose spline passes through given samples, in O(N), with mirror boundaries.
//! Node-centred splines of degree 2 and 3 have sampled kernels `[1, 6, 1]/8` and `[1, 4, 1]/6`;
//! each inverse is one causal and one anti-causal pass with the pole `z` of `z + 1/z = −6` or `−4`.

use rayon::prelude::*;

/// The pole of the cubic B-spline's inverse filter, √3 − 2.
pub const CUBIC_POLE: f64 = -0.267_949_192_431_122_7;
/// The pole of the quadratic B-spline's inverse filter, 2√2 − 3.
pub const QUADRATIC_POLE: f64 = -0.171_572_875_253_809_9;

/// y values per batch of the z pass.
const Z_BATCH: usize = 16;

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
    // x and y lines, a z-plane at a time, all lines of the plane at once: the plane held with
    // the filtered axis slowest (transposed for x), so each step runs along contiguous lanes.
    values.par_chunks_mut(nx * ny).for_each(|plane| {
        let mut lanes = vec![0.0f64; nx * ny];
        for (j, row) in plane.chunks(nx).enumerate() {
            for (i, &v) in row.iter().enumerate() {
                lanes[j + ny * i] = v as f64;
            }
        }
        prefilter_lanes(&mut lanes, ny, nx, z);
        for (j, row) in plane.chunks_mut(nx).enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                *v = lanes[j + ny * i] as f32;
            }
        }
        for (lane, &v) in lanes.iter_mut().zip(plane.iter()) {
            *lane = v as f64;
        }
        prefilter_lanes(&mut lanes, nx, ny, z);
        for (v, &lane) in plane.iter_mut().zip(&lanes) {
            *v = lane as f32;
        }
    });
    // z lines: per y, every x at once (rows along x are contiguous at each z), in parallel over
    // y; each lane does exactly the operations of `prefilter_line_with` on its column. A batch
    // of y at a time, so the filtered slabs waiting to be copied back stay few and their memory
    // is reused rather than freshly mapped.
    let plane = nx * ny;
    for batch in (0..ny).collect::<Vec<_>>().chunks(Z_BATCH) {
        let slabs: Vec<Vec<f32>> = batch
            .par_iter()
            .map(|&j| {
                let mut slab: Vec<f64> = (0..nz)
                    .flat_map(|k| values[nx * j + plane * k..][..nx].iter().map(|&v| v as f64))
                    .collect();
                prefilter_lanes(&mut slab, nx, nz, z);
                slab.into_iter().map(|v| v as f32).collect()
            })
            .collect();
        for (&j, slab) in batch.iter().zip(&slabs) {
            for k in 0..nz {
                values[nx * j + plane * k..][..nx].copy_from_slice(&slab[nx * k..][..nx]);
            }
        }
    }
}

/// [`prefilter_line_with`] on `lanes` interleaved lines of length `n` (`data[lane + lanes · k]`
/// is sample k of line `lane`), with the same operations in the same order per line.
pub(crate) fn prefilter_lanes(data: &mut [f64], lanes: usize, n: usize, z: f64) {
    pgvol_core::cpu::run(PrefilterLanes { data, lanes, n, z })
}

/// [`prefilter_lanes`] as a kernel: the fit spends most of its time here.
struct PrefilterLanes<'a> {
    data: &'a mut [f64],
    lanes: usize,
    n: usize,
    z: f64,
}

impl pgvol_core::cpu::Kernel for PrefilterLanes<'_> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        prefilter_lanes_here(self.data, self.lanes, self.n, self.z)
    }
}

/// [`prefilter_lanes`], inlined into both builds of its kernel.
#[inline(always)]
fn prefilter_lanes_here(data: &mut [f64], lanes: usize, n: usize, z: f64) {
    if n < 2 {
        return;
    }
    let gain = (1.0 - z) * (1.0 - 1.0 / z);
    for v in data.iter_mut() {
        *v *= gain;
    }
    let horizon = ((1e-12f64).ln() / z.abs().ln()).ceil() as usize;
    let mut first = vec![0.0f64; lanes];
    if horizon < n {
        first.copy_from_slice(&data[..lanes]);
        let mut zk = z;
        for k in 1..horizon {
            for (s, v) in first.iter_mut().zip(&data[lanes * k..][..lanes]) {
                *s += zk * v;
            }
            zk *= z;
        }
    } else {
        let zn = z.powi(n as i32 - 1);
        let z2n = zn * zn;
        let iz = 1.0 / z;
        let last = &data[lanes * (n - 1)..][..lanes];
        for ((s, a), b) in first.iter_mut().zip(&data[..lanes]).zip(last) {
            *s = a + zn * b;
        }
        let mut zk = z;
        let mut zback = zn * iz;
        zback *= zn;
        for k in 1..n - 1 {
            for (s, v) in first.iter_mut().zip(&data[lanes * k..][..lanes]) {
                *s += (zk + zback) * v;
            }
            zk *= z;
            zback *= iz;
        }
        for s in first.iter_mut() {
            *s /= 1.0 - z2n;
        }
    }
    data[..lanes].copy_from_slice(&first);
    for k in 1..n {
        let (done, rest) = data.split_at_mut(lanes * k);
        for (v, p) in rest[..lanes].iter_mut().zip(&done[lanes * (k - 1)..]) {
            *v += z * p;
        }
    }
    let scale = z / (z * z - 1.0);
    {
        let (head, last) = data.split_at_mut(lanes * (n - 1));
        for (v, p) in last.iter_mut().zip(&head[lanes * (n - 2)..]) {
            *v = scale * (*v + z * p);
        }
    }
    for k in (0..n - 1).rev() {
        let (head, tail) = data.split_at_mut(lanes * (k + 1));
        for (v, next) in head[lanes * k..].iter_mut().zip(&tail[..lanes]) {
            *v = z * (next - *v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The volume filter equals filtering every line on its own, bit for bit, on all three axes
    /// (short z to take the exact-sum start, long z to take the truncated one).
    #[test]
    fn volume_filter_is_the_line_filter_on_every_axis() {
        for dims in [[5usize, 4, 3], [3, 2, 40]] {
            let [nx, ny, nz] = dims;
            let len = nx * ny * nz;
            let data: Vec<f32> = (0..len)
                .map(|i| ((i * 7919) % 103) as f32 / 17.0 - 3.0)
                .collect();
            let mut want = data.clone();
            let index = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
            let filter = |idx: &mut dyn FnMut(usize) -> usize, n: usize, v: &mut [f32]| {
                let mut line: Vec<f64> = (0..n).map(|t| v[idx(t)] as f64).collect();
                prefilter_line(&mut line);
                for (t, x) in line.into_iter().enumerate() {
                    v[idx(t)] = x as f32;
                }
            };
            for k in 0..nz {
                for j in 0..ny {
                    filter(&mut |t| index(t, j, k), nx, &mut want);
                }
            }
            for k in 0..nz {
                for i in 0..nx {
                    filter(&mut |t| index(i, t, k), ny, &mut want);
                }
            }
            for j in 0..ny {
                for i in 0..nx {
                    filter(&mut |t| index(i, j, t), nz, &mut want);
                }
            }
            let mut got = data;
            prefilter_volume(&mut got, dims);
            assert_eq!(got, want, "dims {dims:?}");
        }
    }

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
