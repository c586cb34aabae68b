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

/// Per-brick q16 parameters: offset and step.
fn q16_params(values: &[f32]) -> Option<(f32, f32)> {
    let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let scale = ((hi as f64 - lo as f64) / 65535.0) as f32;
    (lo.is_finite() && scale.is_finite()).then_some((lo, scale))
}

fn q16_decode(q: u16, lo: f32, scale: f32) -> f32 {
    lo + q as f32 * scale
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
            let words: Option<Vec<u32>> = values.iter().map(|&v| scale.word(v)).collect();
            Some((Vec::new(), words?))
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
            let words = values
                .iter()
                .map(|&v| {
                    if scale > 0.0 {
                        ((v - lo) / scale).round().clamp(0.0, 65535.0) as u32
                    } else {
                        0
                    }
                })
                .collect();
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
