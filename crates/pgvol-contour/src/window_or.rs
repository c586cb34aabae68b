//! Bitwise OR of a 3-D byte array over boxes that are products of one range per axis, in three
//! one-axis passes: each element costs the sum of its ranges' lengths, not their product.

use std::ops::Range;

use rayon::prelude::*;

/// `out[x + X * (y + Y * z)]` (`X`, `Y` the numbers of ranges along x and y): the OR of `src`
/// (x fastest over `dims`) over `ranges[0][x] × ranges[1][y] × ranges[2][z]`, each range within
/// its axis. Every axis needs at least one range.
pub(crate) fn or_over_boxes(src: &[u8], dims: [usize; 3], ranges: [&[Range<usize>]; 3]) -> Vec<u8> {
    let mut values = or_along(src, dims, 0, ranges[0]);
    let mut dims = dims;
    for axis in 0..3 {
        if axis > 0 {
            values = or_along(&values, dims, axis, ranges[axis]);
        }
        dims[axis] = ranges[axis].len();
    }
    values
}

/// `src` (x fastest over `dims`) with `axis` replaced by one OR per range.
fn or_along(src: &[u8], dims: [usize; 3], axis: usize, ranges: &[Range<usize>]) -> Vec<u8> {
    let [nx, ny, _] = dims;
    let mut out_dims = dims;
    out_dims[axis] = ranges.len();
    let [ox, oy, oz] = out_dims;
    let mut out = vec![0u8; ox * oy * oz];
    let or_into = |dst: &mut [u8], src: &[u8]| dst.iter_mut().zip(src).for_each(|(d, s)| *d |= s);
    match axis {
        0 => out.par_chunks_mut(ox).enumerate().for_each(|(row, dst)| {
            let row = &src[nx * row..nx * (row + 1)];
            for (d, r) in dst.iter_mut().zip(ranges) {
                *d = row[r.clone()].iter().fold(0, |a, &b| a | b);
            }
        }),
        1 => out
            .par_chunks_mut(ox * oy)
            .enumerate()
            .for_each(|(z, plane)| {
                for (dst, r) in plane.chunks_mut(ox).zip(ranges) {
                    for j in r.clone() {
                        let start = nx * (j + ny * z);
                        or_into(dst, &src[start..start + nx]);
                    }
                }
            }),
        _ => out
            .par_chunks_mut(ox * oy)
            .zip(ranges)
            .for_each(|(plane, r)| {
                for k in r.clone() {
                    or_into(plane, &src[nx * ny * k..nx * ny * (k + 1)]);
                }
            }),
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_or_over_each_box() {
        let dims = [5, 4, 3];
        let src: Vec<u8> = (0..60u32).map(|i| 1 << (i * 7 % 8)).collect();
        let xs = [0..2, 1..5, 4..5, 2..2];
        let ys = [0..4, 3..4];
        let zs = [1..3, 0..1];
        let out = or_over_boxes(&src, dims, [&xs, &ys, &zs]);
        assert_eq!(out.len(), 4 * 2 * 2);
        for (z, rz) in zs.iter().enumerate() {
            for (y, ry) in ys.iter().enumerate() {
                for (x, rx) in xs.iter().enumerate() {
                    let mut want = 0;
                    for k in rz.clone() {
                        for j in ry.clone() {
                            for i in rx.clone() {
                                want |= src[i + 5 * (j + 4 * k)];
                            }
                        }
                    }
                    assert_eq!(out[x + 4 * (y + 2 * z)], want, "{x} {y} {z}");
                }
            }
        }
    }
}
