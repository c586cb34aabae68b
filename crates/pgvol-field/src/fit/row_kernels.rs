//! The transposed product's loop over precomputed windows, compiled twice: for the baseline
//! target and with AVX2, chosen at run time. Each window line is a 4-wide update, one AVX2
//! instruction instead of two; AVX2 without FMA does the same IEEE operations in the same
//! order, so both give the same bits.

use std::ops::Range;

use super::row_window::Window;

/// Adds `value(i) · w` (`w²` when `SQUARED`) over the part of window i in the z-layers
/// `layers`, for the rows `rows`, into `slab`, which starts at flat index `lo`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn accumulate<const SQUARED: bool>(
    windows: &[Window],
    rows: Range<usize>,
    layers: &Range<usize>,
    value: &impl Fn(usize) -> f64,
    slab: &mut [f64],
    lo: usize,
    nx: usize,
    plane: usize,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        return unsafe {
            accumulate_avx2::<SQUARED>(windows, rows, layers, value, slab, lo, nx, plane)
        };
    }
    accumulate_plain::<SQUARED>(windows, rows, layers, value, slab, lo, nx, plane)
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn accumulate_plain<const SQUARED: bool>(
    windows: &[Window],
    rows: Range<usize>,
    layers: &Range<usize>,
    value: &impl Fn(usize) -> f64,
    slab: &mut [f64],
    lo: usize,
    nx: usize,
    plane: usize,
) {
    for i in rows {
        let win = &windows[i];
        let within = win.layers_within(layers, plane);
        if !within.is_empty() {
            win.add::<SQUARED>(slab, lo, value(i), within, nx, plane);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn accumulate_avx2<const SQUARED: bool>(
    windows: &[Window],
    rows: Range<usize>,
    layers: &Range<usize>,
    value: &impl Fn(usize) -> f64,
    slab: &mut [f64],
    lo: usize,
    nx: usize,
    plane: usize,
) {
    accumulate_plain::<SQUARED>(windows, rows, layers, value, slab, lo, nx, plane)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::Basis;
    use crate::fit::row_window::windows;
    use glam::Vec3;

    /// The run-time choice gives the bits of the baseline loop, plain and squared, whole
    /// windows and clipped ones.
    #[test]
    fn every_build_gives_the_same_bits() {
        let dims = [12, 10, 9];
        let (nx, plane) = (dims[0], dims[0] * dims[1]);
        let points: Vec<Vec3> = (0..500)
            .map(|i| {
                let t = i as f32;
                Vec3::new(
                    5.5 + 5.4 * (t * 0.37).sin(),
                    4.5 + 4.4 * (t * 0.71).cos(),
                    4.0 + 3.9 * (t * 0.13).sin(),
                )
            })
            .collect();
        let windows = windows(Basis::Bspline3, dims, &points).unwrap();
        let value = |i: usize| (i as f64 * 0.29).sin();
        for layers in [0..9, 3..6] {
            let lo = layers.start * plane;
            let len = layers.len() * plane;
            let run = |squared: bool, plain: bool| {
                let mut slab = vec![0.0f64; len];
                let rows = 0..points.len();
                let args = (&windows[..], rows, &layers, &value);
                match (squared, plain) {
                    (false, false) => accumulate::<false>(
                        args.0, args.1, args.2, args.3, &mut slab, lo, nx, plane,
                    ),
                    (false, true) => accumulate_plain::<false>(
                        args.0, args.1, args.2, args.3, &mut slab, lo, nx, plane,
                    ),
                    (true, false) => {
                        accumulate::<true>(args.0, args.1, args.2, args.3, &mut slab, lo, nx, plane)
                    }
                    (true, true) => accumulate_plain::<true>(
                        args.0, args.1, args.2, args.3, &mut slab, lo, nx, plane,
                    ),
                }
                slab.iter().map(|v| v.to_bits()).collect::<Vec<u64>>()
            };
            for squared in [false, true] {
                let plain = run(squared, true);
                assert!(plain.iter().any(|&b| b != 0));
                assert_eq!(run(squared, false), plain, "{layers:?} {squared}");
            }
        }
    }
}
