//! Decoding one stored brick's bytes, once decompressed, back to coefficients: gather the
//! residual words (undoing the byte shuffle), undo zig-zag and prediction, dequantise
//! (`docs/format.md`, "The sparse-bricks encoding"). Each step is one tight loop over the brick,
//! with buffers reused across bricks; the encoder's side is `brick_encoder::brick_raw`.

use half::f16;
use half::slice::HalfFloatSliceExt;

use super::quantise::{unorder16, unorder32, Q16_PARAMS};
use crate::fixed_step::{FastScale, FixedScale};
use crate::sparse_params::{Precision, Predictor, SparseParams};

/// Buffers reused from brick to brick, so that decoding a brick allocates nothing.
#[derive(Default)]
pub(crate) struct WordScratch {
    words: Vec<u32>,
    halves: Vec<f16>,
}

/// Decoding produced an infinite or NaN coefficient.
#[derive(Debug)]
pub(crate) struct NonFinite;

/// Bytes of a brick of `n` nodes before compression.
pub(crate) fn raw_len(n: [usize; 3], sp: &SparseParams) -> usize {
    params_len(sp.precision) + n[0] * n[1] * n[2] * sp.precision.width()
}

fn params_len(p: Precision) -> usize {
    if p == Precision::Q16 {
        Q16_PARAMS
    } else {
        0
    }
}

/// Decodes `raw` (exactly [`raw_len`] bytes) of a brick of `n` nodes into `out` (one value per
/// node, x fastest).
pub(crate) fn decode_values(
    raw: &[u8],
    n: [usize; 3],
    sp: &SparseParams,
    scratch: &mut WordScratch,
    out: &mut [f32],
) -> Result<(), NonFinite> {
    let count = n[0] * n[1] * n[2];
    debug_assert_eq!(raw.len(), raw_len(n, sp));
    debug_assert_eq!(out.len(), count);
    let (params, body) = raw.split_at(params_len(sp.precision));
    if let (Precision::Fixed, Predictor::DeltaX, true, Some(scale)) =
        (sp.precision, sp.predictor, sp.shuffle, sp.fixed)
    {
        return fixed_delta_x(body, n, &scale, &mut scratch.words, out);
    }
    let w = sp.precision.width();
    let words = &mut scratch.words;
    words.resize(count, 0);
    gather(body, w, sp.shuffle, words);
    let mask = if w == 4 { u32::MAX } else { 0xffff };
    unpredict(words, n, sp.predictor, mask);
    match sp.precision {
        Precision::Fixed => {
            // The reader checked that a fixed file has a scale.
            let Some(scale) = sp.fixed else {
                return Err(NonFinite);
            };
            let fast = scale.fast();
            for (o, &q) in out.iter_mut().zip(words.iter()) {
                *o = fast.value(q);
            }
        }
        Precision::F32 => {
            for (o, &m) in out.iter_mut().zip(words.iter()) {
                *o = f32::from_bits(unorder32(m));
            }
        }
        Precision::F16 => {
            // Slice conversion uses the CPU's half-float instructions where it has them.
            let halves = &mut scratch.halves;
            halves.clear();
            halves.extend(words.iter().map(|&m| f16::from_bits(unorder16(m as u16))));
            halves.convert_to_f32_slice(out);
        }
        Precision::Q16 => {
            let lo = f32::from_le_bytes(params[0..4].try_into().expect("4 bytes"));
            let step = f32::from_le_bytes(params[4..8].try_into().expect("4 bytes"));
            for (o, &q) in out.iter_mut().zip(words.iter()) {
                *o = lo + q as f32 * step;
            }
        }
    }
    if out.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(NonFinite)
    }
}

/// The default `fixed` encoding (byte planes, delta-x): the words ([`fixed_delta_x_words`]),
/// then their dequantisation, which vectorises when every word takes the f32 path. The same
/// values as the separate steps.
fn fixed_delta_x(
    body: &[u8],
    n: [usize; 3],
    scale: &FixedScale,
    words: &mut Vec<u32>,
    out: &mut [f32],
) -> Result<(), NonFinite> {
    let largest = fixed_delta_x_words(body, n, words);
    let fast = scale.fast();
    let exact = fast.all_exact(largest);
    if pgvol_core::cpu::run(Dequantise {
        fast,
        exact,
        words,
        out,
    }) {
        Ok(())
    } else {
        Err(NonFinite)
    }
}

/// The values of a brick's `fixed` words, as a kernel (every stored brick a decode reads goes
/// through it); whether all are finite.
struct Dequantise<'a> {
    fast: FastScale,
    /// Whether every word takes the f32 path.
    exact: bool,
    words: &'a [u32],
    out: &'a mut [f32],
}

impl pgvol_core::cpu::Kernel for Dequantise<'_> {
    type Output = bool;
    #[inline(always)]
    fn run(self) -> bool {
        let Dequantise {
            fast,
            exact,
            words,
            out,
        } = self;
        if exact {
            for (o, &w) in out.iter_mut().zip(words) {
                *o = fast.exact_value(w);
            }
        } else {
            for (o, &w) in out.iter_mut().zip(words) {
                *o = fast.value(w);
            }
        }
        out.iter().all(|v| v.is_finite())
    }
}

/// The words of the default `fixed` encoding (`n` nodes, x fastest) into `words`; returns the
/// largest magnitude among them.
fn fixed_delta_x_words(body: &[u8], n: [usize; 3], words: &mut Vec<u32>) -> u32 {
    words.resize(n[0] * n[1] * n[2], 0);
    if words.is_empty() {
        return 0;
    }
    pgvol_core::cpu::run(DeltaXWords {
        body,
        row: n[0],
        rows_per_slice: n[1],
        words,
    })
}

/// [`fixed_delta_x_words`] as a kernel: every stored brick a decode or a slicing reads goes
/// through it.
struct DeltaXWords<'a> {
    body: &'a [u8],
    /// Words per row (along x).
    row: usize,
    /// Rows per slice (along y).
    rows_per_slice: usize,
    words: &'a mut [u32],
}

impl pgvol_core::cpu::Kernel for DeltaXWords<'_> {
    type Output = u32;
    #[inline(always)]
    fn run(self) -> u32 {
        let DeltaXWords {
            body,
            row,
            rows_per_slice,
            words,
        } = self;
        let count = words.len();
        let (p0, rest) = body.split_at(count);
        let (p1, rest) = rest.split_at(count);
        let (p2, p3) = rest.split_at(count);
        // The residuals first: each word's own, so this loop vectorises.
        let planes = p0.iter().zip(p1).zip(p2.iter().zip(p3));
        for (w, ((&b0, &b1), (&b2, &b3))) in words.iter_mut().zip(planes) {
            *w = unzigzag(u32::from_le_bytes([b0, b1, b2, b3]), u32::MAX);
        }
        // Then the running sums along x, the only serial chain. A row's prediction starts from
        // the previous row's first word, a slice's first row from the previous slice's.
        let (mut row_first, mut slice_first) = (0u32, 0u32);
        for (r, run) in words.chunks_exact_mut(row).enumerate() {
            let mut prev = if r % rows_per_slice != 0 {
                row_first
            } else {
                slice_first
            };
            for w in run.iter_mut() {
                prev = w.wrapping_add(prev);
                *w = prev;
            }
            row_first = run[0];
            if r % rows_per_slice == 0 {
                slice_first = row_first;
            }
        }
        words
            .iter()
            .fold(0, |largest, &w| largest.max((w as i32).unsigned_abs()))
    }
}

/// Decodes `raw` as [`decode_values`] does, but into the `fixed` precision's words as 16-bit
/// integers (the value of a word `w` being `FixedScale::value(w as i32 as u32)`), for readers
/// that hold many bricks at once: half the memory of the values. `false` (and `out` unspecified)
/// where the file is not in the default `fixed` encoding or a word needs more than 16 bits;
/// [`decode_values`] serves those.
pub(crate) fn decode_words16(
    raw: &[u8],
    n: [usize; 3],
    sp: &SparseParams,
    scratch: &mut WordScratch,
    out: &mut [i16],
) -> bool {
    debug_assert_eq!(raw.len(), raw_len(n, sp));
    debug_assert_eq!(out.len(), n[0] * n[1] * n[2]);
    let (_, body) = raw.split_at(params_len(sp.precision));
    let default_fixed =
        (sp.precision, sp.predictor, sp.shuffle) == (Precision::Fixed, Predictor::DeltaX, true);
    if !default_fixed || sp.fixed.is_none() {
        return false;
    }
    let largest = fixed_delta_x_words(body, n, &mut scratch.words);
    if largest > i16::MAX as u32 {
        return false;
    }
    for (o, &w) in out.iter_mut().zip(scratch.words.iter()) {
        *o = w as i32 as i16;
    }
    true
}

/// The zig-zag coded residual words, `w` bytes each, little-endian; with `shuffle` the bytes
/// come as planes (byte 0 of every word, then byte 1, ...).
fn gather(body: &[u8], w: usize, shuffle: bool, words: &mut [u32]) {
    let count = words.len();
    if shuffle && w == 2 {
        // The common case (f16, q16) in one pass.
        let (low, high) = body.split_at(count);
        for ((z, &lo), &hi) in words.iter_mut().zip(low).zip(high) {
            *z = lo as u32 | (hi as u32) << 8;
        }
    } else if shuffle && w == 4 {
        // f32 and fixed, also in one pass.
        let (p0, rest) = body.split_at(count);
        let (p1, rest) = rest.split_at(count);
        let (p2, p3) = rest.split_at(count);
        let planes = p0.iter().zip(p1).zip(p2.iter().zip(p3));
        for (z, ((&b0, &b1), (&b2, &b3))) in words.iter_mut().zip(planes) {
            *z = u32::from_le_bytes([b0, b1, b2, b3]);
        }
    } else if shuffle {
        words.fill(0);
        for (b, plane) in body.chunks_exact(count).take(w).enumerate() {
            for (z, &byte) in words.iter_mut().zip(plane) {
                *z |= (byte as u32) << (8 * b);
            }
        }
    } else {
        for (z, bytes) in words.iter_mut().zip(body.chunks_exact(w)) {
            *z = bytes
                .iter()
                .rev()
                .fold(0u32, |acc, &byte| acc << 8 | byte as u32);
        }
    }
}

/// Zig-zag decoding modulo `mask + 1`: even `z` → `z / 2`, odd → `−(z + 1) / 2`.
#[inline(always)]
fn unzigzag(z: u32, mask: u32) -> u32 {
    ((z >> 1) ^ 0u32.wrapping_sub(z & 1)) & mask
}

/// Replaces each zig-zag residual by its word: residual plus the prediction from the words
/// already decoded (neighbours outside the brick count as 0), modulo `mask + 1`.
fn unpredict(words: &mut [u32], n: [usize; 3], pred: Predictor, mask: u32) {
    let (sy, sz) = (n[0], n[0] * n[1]);
    match pred {
        Predictor::None => {
            for z in words.iter_mut() {
                *z = unzigzag(*z, mask);
            }
        }
        Predictor::DeltaX => {
            let mut at = 0;
            for k in 0..n[2] {
                for j in 0..n[1] {
                    // A row starts from the row before, a slice from the slice before.
                    let mut prev = if j > 0 {
                        words[at - sy]
                    } else if k > 0 {
                        words[at - sz]
                    } else {
                        0
                    };
                    for z in &mut words[at..at + n[0]] {
                        prev = unzigzag(*z, mask).wrapping_add(prev) & mask;
                        *z = prev;
                    }
                    at += n[0];
                }
            }
        }
        Predictor::Lorenzo => {
            let mut at = 0;
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let get = |di: usize, dj: usize, dk: usize| -> u32 {
                            if i < di || j < dj || k < dk {
                                0
                            } else {
                                words[at - di - dj * sy - dk * sz]
                            }
                        };
                        let p = get(1, 0, 0)
                            .wrapping_add(get(0, 1, 0))
                            .wrapping_add(get(0, 0, 1))
                            .wrapping_sub(get(1, 1, 0))
                            .wrapping_sub(get(1, 0, 1))
                            .wrapping_sub(get(0, 1, 1))
                            .wrapping_add(get(1, 1, 1));
                        words[at] = unzigzag(words[at], mask).wrapping_add(p) & mask;
                        at += 1;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::brick_encoder::brick_raw;
    use crate::sparse::predict::predict;
    use crate::sparse::quantise::{dequantise, quantise};
    use crate::sparse_params::Compression;
    use proptest::prelude::*;

    fn unzigzag(z: u32, bits: u32) -> u32 {
        let s = if z & 1 == 0 {
            (z >> 1) as i64
        } else {
            -((z >> 1) as i64) - 1
        };
        (s.rem_euclid(1i64 << bits)) as u32
    }

    /// Inverse of [`brick_raw`], step by step as `docs/format.md` states it: the reference the
    /// fast decoder is tested against. `raw` has exactly the expected length.
    fn brick_values(raw: &[u8], n: [usize; 3], sp: &SparseParams) -> Vec<f32> {
        let w = sp.precision.width();
        let bits = 8 * w as u32;
        let mask = if w == 4 { u32::MAX } else { 0xffff };
        let count = n[0] * n[1] * n[2];
        let pl = if sp.precision == Precision::Q16 {
            Q16_PARAMS
        } else {
            0
        };
        let (params, body) = raw.split_at(pl);
        let mut words = vec![0u32; count];
        for at in 0..count {
            let mut z = 0u32;
            for b in 0..w {
                let byte = if sp.shuffle {
                    body[b * count + at]
                } else {
                    body[at * w + b]
                };
                z |= (byte as u32) << (8 * b);
            }
            let r = unzigzag(z, bits);
            words[at] = r.wrapping_add(predict(&words, n, at, sp.predictor, mask)) & mask;
        }
        dequantise(params, &words, sp.precision, sp.fixed)
    }

    fn params(precision: Precision, predictor: Predictor, shuffle: bool) -> SparseParams {
        SparseParams {
            brick: 8,
            bricks: [1, 1, 1],
            stored: 1,
            precision,
            predictor,
            shuffle,
            compression: Compression::None,
            clamp: 1.0,
            band: 3.0,
            fixed: (precision == Precision::Fixed).then_some(FixedScale {
                step: 1.0 / 1024.0,
                knee: 700,
                ratio: 8,
            }),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Random words (any bit pattern, so also non-finite floats) in bricks of any shape.
        #[test]
        fn fast_decoder_matches_the_reference_bit_for_bit(
            n in proptest::array::uniform3(1usize..10),
            seed in any::<u64>(),
            which in 0usize..4,
            predictor in 0usize..3,
            shuffle in any::<bool>(),
            q16 in (any::<f32>(), any::<f32>()),
        ) {
            let precision = Precision::ALL[which];
            let predictor = [Predictor::None, Predictor::DeltaX, Predictor::Lorenzo][predictor];
            let sp = params(precision, predictor, shuffle);
            let mask = if precision.width() == 4 { u32::MAX } else { 0xffff };
            let mut s = seed | 1;
            let words: Vec<u32> = (0..n[0] * n[1] * n[2])
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    s as u32 & mask
                })
                .collect();
            let mut head = Vec::new();
            if precision == Precision::Q16 {
                head.extend_from_slice(&q16.0.to_le_bytes());
                head.extend_from_slice(&q16.1.to_le_bytes());
            }
            let raw = brick_raw(&head, &words, n, &sp);
            prop_assert_eq!(raw.len(), raw_len(n, &sp));
            let want = brick_values(&raw, n, &sp);
            let mut got = vec![0.0f32; want.len()];
            let finite = decode_values(&raw, n, &sp, &mut WordScratch::default(), &mut got);
            prop_assert_eq!(finite.is_ok(), want.iter().all(|v| v.is_finite()));
            for (g, w) in got.iter().zip(&want) {
                prop_assert_eq!(g.to_bits(), w.to_bits());
            }
        }

        /// Quantised real values decode to what the encoder's own dequantisation gives.
        #[test]
        fn quantised_values_decode_as_the_encoder_expects(
            n in proptest::array::uniform3(1usize..10),
            seed in any::<u64>(),
            which in 0usize..4,
            scale in 1e-3f32..1e3,
        ) {
            let precision = Precision::ALL[which];
            let sp = params(precision, Predictor::DeltaX, true);
            let mut s = seed | 1;
            let values: Vec<f32> = (0..n[0] * n[1] * n[2])
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    ((s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32 * scale
                })
                .collect();
            let (head, words) = quantise(&values, precision, sp.fixed).unwrap();
            let raw = brick_raw(&head, &words, n, &sp);
            let mut got = vec![0.0f32; values.len()];
            decode_values(&raw, n, &sp, &mut WordScratch::default(), &mut got).unwrap();
            let want = dequantise(&head, &words, precision, sp.fixed);
            for (g, w) in got.iter().zip(&want) {
                prop_assert_eq!(g.to_bits(), w.to_bits());
            }
        }
    }
}
