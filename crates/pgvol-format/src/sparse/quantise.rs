//! Quantising a brick's coefficients to words under each precision, and the values the words
//! stand for.

use crate::fixed_step::FixedScale;
use crate::sparse_params::Precision;

/// Bytes of the q16 parameters (offset f32, scale f32) in front of a brick's values.
pub(crate) const Q16_PARAMS: usize = 8;

/// Maps float bits to integers in the same order as the floats, so that neighbouring values
/// have nearby integers and prediction residuals stay small across zero.
fn order16(b: u16) -> u16 {
    if b & 0x8000 != 0 {
        !b
    } else {
        b | 0x8000
    }
}

pub(crate) fn unorder16(m: u16) -> u16 {
    if m & 0x8000 != 0 {
        m & 0x7fff
    } else {
        !m
    }
}

fn order32(b: u32) -> u32 {
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

pub(crate) fn unorder32(m: u32) -> u32 {
    if m & 0x8000_0000 != 0 {
        m & 0x7fff_ffff
    } else {
        !m
    }
}

/// Per-brick q16 parameters: offset and step. The offset is the brick's minimum `lo`. The top
/// word decodes to `top(step) = lo + 65535 · step` (f32 arithmetic), which is monotone in the
/// step: the step is taken among those whose top is the least value at or above the maximum
/// `hi`, the one nearest `(top − lo) / 65535` rounded to f32 — usually that rounding of
/// `(hi − lo) / 65535` itself. Decoded values have the same minimum, and their maximum is that
/// top, which gives the same step: a decoded brick gets its parameters back.
fn q16_params(values: &[f32]) -> Option<(f32, f32)> {
    let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let step_for = |top: f32| ((top as f64 - lo as f64) / 65535.0) as f32;
    let guess = step_for(hi);
    if !(lo.is_finite() && guess.is_finite()) {
        return None;
    }
    if hi == lo {
        return Some((lo, 0.0));
    }
    let top = |step: f32| q16_decode(u16::MAX, lo, step);
    // The steps whose top is the least one reaching `hi`: from the first reaching it to the
    // last before the first reaching past it.
    let first = least_step_reaching(hi, guess, &top)?;
    let reached = top(first);
    let last = match least_step_reaching(next_up(reached), first, &top) {
        Some(past) => f32::from_bits(past.to_bits() - 1),
        None => f32::MAX,
    };
    Some((lo, step_for(reached).clamp(first, last)))
}

/// The next f32 above the finite `v`.
fn next_up(v: f32) -> f32 {
    if v == 0.0 {
        f32::from_bits(1)
    } else if v > 0.0 {
        f32::from_bits(v.to_bits() + 1)
    } else {
        f32::from_bits(v.to_bits() - 1)
    }
}

/// The least step `s ≥ 0` with `top(s) ≥ target`, for a non-decreasing `top` with
/// `top(0) < target`, searched from `guess` > 0; `None` when no finite step reaches it.
fn least_step_reaching(target: f32, guess: f32, top: &impl Fn(f32) -> f32) -> Option<f32> {
    let reaches = |step: f32| top(step) >= target;
    // Bracket it by growing distances from the guess: `below` does not reach the target,
    // `above` does (positive f32 bits order as the values do).
    let first = (guess * f32::EPSILON).max(f32::from_bits(1));
    let (mut below, mut above) = (guess, guess);
    let mut reach = first;
    while !reaches(above) {
        above = guess + reach;
        reach *= 2.0;
        if !above.is_finite() {
            return None;
        }
    }
    let mut reach = first;
    while below > 0.0 && reaches(below) {
        below = (guess - reach).max(0.0);
        reach *= 2.0;
    }
    let (mut b, mut a) = (below.to_bits(), above.to_bits());
    while a - b > 1 {
        let mid = b + (a - b) / 2;
        if reaches(f32::from_bits(mid)) {
            a = mid;
        } else {
            b = mid;
        }
    }
    Some(f32::from_bits(a))
}

fn q16_decode(q: u16, lo: f32, scale: f32) -> f32 {
    lo + q as f32 * scale
}

/// The word a value some q16 word decodes to exactly gets back: the top word for the top value,
/// else the estimate or a neighbour of it (the estimate may miss by one where f32 does not tell
/// neighbouring words apart).
fn q16_exact(v: f32, lo: f32, scale: f32) -> Option<u32> {
    if v == q16_decode(u16::MAX, lo, scale) {
        return Some(u16::MAX as u32);
    }
    let q = q16_nearest(v, lo, scale);
    [q, q.wrapping_sub(1), q + 1]
        .into_iter()
        .find(|&r| r <= 65535 && q16_decode(r as u16, lo, scale) == v)
}

fn q16_nearest(v: f32, lo: f32, scale: f32) -> u32 {
    ((v - lo) / scale).round().clamp(0.0, 65535.0) as u32
}

/// The q16 word of `v` in a brick of offset `lo`, step `scale` and maximum `hi`: the maximum
/// takes the top word, a value a word decodes to takes it ([`q16_exact`]), any other the
/// nearest word, as [`q16_exact`] names its value. Decoded values thus quantise to their words.
fn q16_word(v: f32, lo: f32, scale: f32, hi: f32) -> u32 {
    if scale <= 0.0 {
        return 0;
    }
    if v == hi {
        return u16::MAX as u32;
    }
    q16_exact(v, lo, scale).unwrap_or_else(|| {
        let q = q16_nearest(v, lo, scale);
        q16_exact(q16_decode(q as u16, lo, scale), lo, scale).unwrap_or(q)
    })
}

/// Quantises `values` to words (and the bytes that precede them). `None` if the precision
/// cannot represent them (f16 overflow, q16 range overflow, fixed without a step or beyond
/// 32 bits).
pub(crate) fn quantise(
    values: &[f32],
    p: Precision,
    fixed: Option<FixedScale>,
) -> Option<(Vec<u8>, Vec<u32>)> {
    match p {
        Precision::Fixed => {
            let scale = fixed.filter(FixedScale::is_valid)?;
            Some((Vec::new(), scale.words_of(values)?))
        }
        Precision::F32 => Some((
            Vec::new(),
            values.iter().map(|v| order32(v.to_bits())).collect(),
        )),
        Precision::F16 => {
            let words: Option<Vec<u32>> = values
                .iter()
                .map(|&v| {
                    let h = half::f16::from_f32(v);
                    h.is_finite().then_some(order16(h.to_bits()) as u32)
                })
                .collect();
            Some((Vec::new(), words?))
        }
        Precision::Q16 => {
            let (lo, scale) = q16_params(values)?;
            let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            let words = values.iter().map(|&v| q16_word(v, lo, scale, hi)).collect();
            let mut params = lo.to_le_bytes().to_vec();
            params.extend_from_slice(&scale.to_le_bytes());
            Some((params, words))
        }
    }
}

/// The values that `words` decode to.
pub(crate) fn dequantise(
    params: &[u8],
    words: &[u32],
    p: Precision,
    fixed: Option<FixedScale>,
) -> Vec<f32> {
    match p {
        Precision::Fixed => match fixed {
            Some(scale) => words.iter().map(|&w| scale.value(w)).collect(),
            None => vec![f32::NAN; words.len()],
        },
        Precision::F32 => words
            .iter()
            .map(|&w| f32::from_bits(unorder32(w)))
            .collect(),
        Precision::F16 => words
            .iter()
            .map(|&w| half::f16::from_bits(unorder16(w as u16)).to_f32())
            .collect(),
        Precision::Q16 => {
            let lo = f32::from_le_bytes(params[0..4].try_into().expect("4 bytes"));
            let scale = f32::from_le_bytes(params[4..8].try_into().expect("4 bytes"));
            words
                .iter()
                .map(|&w| q16_decode(w as u16, lo, scale))
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed_step::{FIXED_KNEE, FIXED_RATIO, FIXED_STEP};
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Quantisation is a projection: the values words decode to quantise to the same bytes,
        /// over ranges from far finer than f32 resolves at the offset to wider than it.
        #[test]
        fn quantising_decoded_values_gives_their_words_again(
            len in 1usize..200,
            seed in any::<u64>(),
            which in 0usize..4,
            mantissa in 1f32..2.0,
            exponent in -30i32..12,
            offset in -1e3f32..1e3,
        ) {
            let precision = Precision::ALL[which];
            let fixed = Some(FixedScale {
                step: FIXED_STEP * 0.1,
                knee: (FIXED_KNEE / FIXED_STEP) as u32,
                ratio: FIXED_RATIO,
            });
            let mut s = seed | 1;
            let values: Vec<f32> = (0..len)
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    let unit = (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                    unit as f32 * mantissa * 2f32.powi(exponent) + offset
                })
                .collect();
            let Some((params, words)) = quantise(&values, precision, fixed) else {
                return Ok(());
            };
            let decoded = dequantise(&params, &words, precision, fixed);
            let (params2, words2) = quantise(&decoded, precision, fixed).unwrap();
            prop_assert_eq!(&params2, &params);
            prop_assert_eq!(&words2, &words);
        }
    }
}
