//! Encoding the stored bricks: quantise, settle the free words, predict, zig-zag, shuffle the
//! bytes into planes and compress, each brick on its own. The decoder's side is
//! `brick_decoder`.

use pgvol_field::CoefficientVolume;
use rayon::prelude::*;

use super::bricks::Bricks;
use super::free_words::settle_free_words;
use super::predict::{delta_x_rows, for_each_node, predict_at};
use super::quantise::{dequantise, quantise};
use super::stored_band::{node_flags, KeptBrick};
use crate::sparse_params::{Compression, Precision, Predictor, SparseParams};

/// The zig-zag code of a residual of `bits` (16 or 32) bits read as two's complement: `2s`
/// for `s ≥ 0`, `−2s − 1` below. Branch-free: the residual is sign-extended by shifts.
#[inline]
fn zigzag(r: u32, bits: u32) -> u32 {
    let s = ((r << (32 - bits)) as i32) >> (32 - bits);
    ((s << 1) ^ (s >> 31)) as u32
}

/// Encodes one brick's values to its blob (before compression: q16 parameters, then residual
/// bytes, byte planes if shuffled).
pub(crate) fn brick_raw(params: &[u8], words: &[u32], n: [usize; 3], sp: &SparseParams) -> Vec<u8> {
    let w = sp.precision.width();
    let bits = 8 * w as u32;
    let mask = if w == 4 { u32::MAX } else { 0xffff };
    let mut residuals = Vec::with_capacity(words.len());
    if sp.predictor == Predictor::DeltaX {
        // The default predictor row by row: each word is predicted by the one before it.
        for (at, from) in delta_x_rows(n) {
            let mut p = from.map_or(0, |f| words[f]);
            for &w in &words[at..at + n[0]] {
                residuals.push(zigzag(w.wrapping_sub(p) & mask, bits));
                p = w;
            }
        }
    } else {
        for_each_node(n, |at, node| {
            let p = predict_at(words, n, at, node, sp.predictor, mask);
            residuals.push(zigzag(words[at].wrapping_sub(p) & mask, bits));
        });
    }
    let mut raw = params.to_vec();
    if sp.shuffle {
        for b in 0..w {
            raw.extend(residuals.iter().map(|r| (r >> (8 * b)) as u8));
        }
    } else {
        for r in &residuals {
            raw.extend_from_slice(&r.to_le_bytes()[..w]);
        }
    }
    raw
}

/// What the encoder stores: the `kept` bricks of `volume`, with the nodes the band needs, and
/// how many coarse `fixed` words the others may move.
pub(crate) struct StoredBricks<'a> {
    pub(crate) volume: &'a CoefficientVolume,
    pub(crate) bricks: &'a Bricks,
    pub(crate) kept: &'a [KeptBrick],
    pub(crate) tolerance_steps: i32,
}

/// The blobs of the stored bricks and their largest coefficient error.
pub(crate) type Encoded = (Vec<Vec<u8>>, f32);

/// Stored bricks under one precision: blobs and the largest error of a coefficient the band
/// needs, or `None` if the precision cannot hold the values.
pub(crate) fn encode_bricks(
    s: &StoredBricks,
    sp: &SparseParams,
    level: i32,
) -> Result<Option<Encoded>, String> {
    // Bricks are independent: encode them in parallel, collected in brick order so the file
    // does not depend on the thread count.
    let encoded: Vec<Option<(Vec<u8>, f32)>> = s
        .kept
        .par_iter()
        .map_init(Packer::default, |packer, k| {
            encode_brick(s, sp, level, k, packer)
        })
        .collect::<Result<_, String>>()?;
    let mut blobs = Vec::with_capacity(encoded.len());
    let mut worst = 0.0f32;
    for brick in encoded {
        let Some((blob, brick_worst)) = brick else {
            return Ok(None);
        };
        blobs.push(blob);
        worst = worst.max(brick_worst);
    }
    Ok(Some((blobs, worst)))
}

/// What each thread keeps between bricks: a compression context (making one per brick took a
/// few percent of a file's writing) and room for zstd's worst case.
#[derive(Default)]
pub(crate) struct Packer {
    compressor: Option<zstd::bulk::Compressor<'static>>,
    room: Vec<u8>,
}

/// One stored brick's compressed bytes and its largest error over needed coefficients; `None`
/// when `sp.precision` cannot represent its coefficients.
fn encode_brick(
    s: &StoredBricks,
    sp: &SparseParams,
    level: i32,
    kept: &KeptBrick,
    packer: &mut Packer,
) -> Result<Option<(Vec<u8>, f32)>, String> {
    let (lo, n) = s.bricks.extent(kept.index);
    let mut values = vec![0.0f32; n[0] * n[1] * n[2]];
    s.volume.coeffs.gather(lo, n, &mut values);
    let Some((params, mut words)) = quantise(&values, sp.precision, sp.fixed) else {
        return Ok(None);
    };
    let loose: Vec<bool> = node_flags(&kept.needed, n[0]).map(|x| !x).collect();
    if sp.precision == Precision::Fixed && s.tolerance_steps > 0 {
        settle_free_words(&mut words, &loose, n, sp.predictor, s.tolerance_steps);
    }
    let mut worst = 0.0f32;
    let mut take = |a: f32, d: f32| worst = worst.max((a - d).abs());
    match (sp.precision, sp.fixed) {
        // Word by word where a word decodes alone, and only the needed ones.
        (Precision::Fixed, Some(scale)) => {
            for ((&a, &w), l) in values.iter().zip(&words).zip(&loose) {
                if !l {
                    take(a, scale.value(w));
                }
            }
        }
        _ => {
            let decoded = dequantise(&params, &words, sp.precision, sp.fixed);
            for ((&a, d), l) in values.iter().zip(decoded).zip(&loose) {
                if !l {
                    take(a, d);
                }
            }
        }
    }
    let raw = brick_raw(&params, &words, n, sp);
    let blob = match sp.compression {
        Compression::None => raw,
        Compression::Zstd => {
            // Compressed into room for the worst case, then kept at its own length: a blob
            // is a tenth of that room, and every stored brick's blob is held until written.
            let scratch = &mut packer.room;
            scratch.resize(zstd::zstd_safe::compress_bound(raw.len()), 0);
            if packer.compressor.is_none() {
                packer.compressor = Some(
                    zstd::bulk::Compressor::new(level)
                        .map_err(|e| format!("zstd compression failed: {e}"))?,
                );
            }
            let compressor = packer.compressor.as_mut().expect("made above");
            let n = compressor
                .compress_to_buffer(&raw, &mut scratch[..])
                .map_err(|e| format!("zstd compression failed: {e}"))?;
            scratch[..n].to_vec()
        }
    };
    Ok(Some((blob, worst)))
}

#[cfg(test)]
mod tests {
    use super::zigzag;

    /// Every 16-bit residual and 32-bit ones at the edges of their range give the code of the
    /// signed value: 0, −1, 1, −2, … to 0, 1, 2, 3, ….
    #[test]
    fn zigzag_codes_the_signed_residual() {
        let code = |s: i64| (if s >= 0 { 2 * s } else { -2 * s - 1 }) as u32;
        for r in 0..=u16::MAX as u32 {
            assert_eq!(zigzag(r, 16), code(r as u16 as i16 as i64), "{r}");
        }
        for s in [
            0i64,
            1,
            -1,
            2,
            -2,
            i32::MAX as i64,
            i32::MIN as i64,
            12345,
            -54321,
        ] {
            assert_eq!(zigzag(s as i32 as u32, 32), code(s), "{s}");
        }
    }
}
