//! The `fixed` precision: coefficients as integer words on a piecewise-linear scale, a fine step
//! up to a knee and a coarser one beyond (the surface depends on the small coefficients near
//! it; the far ones only need the band's accuracy); and the encoder's defaults for it.

use pgvol_core::WordScale;
use serde::{Deserialize, Serialize};

/// Default fine step of `fixed`, in grid spacings (`docs/format.md`, "How the encoder chooses").
pub const FIXED_STEP: f32 = 1.0 / 512.0;
/// Default knee of `fixed`, in grid spacings: the fine step holds for |c| up to this.
pub const FIXED_KNEE: f32 = 1.0;
/// Default ratio of the coarse step to the fine one.
pub const FIXED_RATIO: u32 = 8;

/// The header's `sparse.fixed` object: how a word maps to a coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedScale {
    /// The fine step, in field units.
    pub step: f32,
    /// Words of magnitude up to `knee` are multiples of `step`.
    pub knee: u32,
    /// Beyond the knee, each word counts `ratio` steps.
    pub ratio: u32,
}

/// [`FixedScale::value`], bit for bit, faster: while `n < 2²⁴` every step of the computation
/// is exact in f32, so only larger words take the 64-bit path.
pub(crate) struct FastScale {
    scale: FixedScale,
    words: WordScale,
}

impl FastScale {
    #[inline]
    pub(crate) fn value(&self, w: u32) -> f32 {
        if self.all_exact((w as i32).unsigned_abs()) {
            self.exact_value(w)
        } else {
            self.scale.value(w)
        }
    }

    /// Whether words of magnitude up to `largest` all take the f32 path.
    #[inline]
    pub(crate) fn all_exact(&self, largest: u32) -> bool {
        self.words.exact_up_to(largest)
    }

    /// The value of a word whose magnitude passes [`FastScale::all_exact`]; branch-free.
    #[inline]
    pub(crate) fn exact_value(&self, w: u32) -> f32 {
        self.words.value(w as i32)
    }
}

/// The largest `ratio` a reader accepts.
pub const MAX_RATIO: u32 = 1 << 16;

/// [`FixedScale::words_of`] as a kernel: every stored coefficient of a file goes through it.
struct WordsOf<'a>(&'a FixedScale, &'a [f32]);

impl pgvol_core::cpu::Kernel for WordsOf<'_> {
    type Output = Option<Vec<u32>>;
    #[inline(always)]
    fn run(self) -> Self::Output {
        self.0.words_of_here(self.1)
    }
}

impl FixedScale {
    /// Whether a reader accepts these parameters.
    pub fn is_valid(&self) -> bool {
        self.step.is_finite()
            && self.step > 0.0
            && self.knee <= i32::MAX as u32
            && (1..=MAX_RATIO).contains(&self.ratio)
    }

    /// The coefficient of a word: the word as a two's-complement integer `q`, its magnitude
    /// `a` counted in steps `n = a` up to the knee, `n = knee + (a − knee) · ratio` beyond, and
    /// the value `sign(q) · (n as f32) · step` in f32.
    #[inline]
    pub fn value(&self, word: u32) -> f32 {
        // Branch-free (words near the knee would defeat branch prediction):
        // `a + max(a − K, 0) · (R − 1)` equals both cases of `n`; the value is ≥ 0, so the
        // word's sign bit is its sign.
        let a = (word as i32).unsigned_abs() as i64;
        let n = a + (a - self.knee as i64).max(0) * (self.ratio as i64 - 1);
        let v = n as f32 * self.step;
        f32::from_bits(v.to_bits() | (word & 0x8000_0000))
    }

    /// Constants for decoding many words quickly.
    pub(crate) fn fast(&self) -> FastScale {
        FastScale {
            scale: *self,
            words: self.words(),
        }
    }

    /// The f32 computation of [`FixedScale::value`], exact for the words it says.
    pub fn words(&self) -> WordScale {
        WordScale::new(self.step, self.knee, self.ratio)
    }

    /// [`FixedScale::word`] of each of `values`, `None` if any has none. Quantising a file
    /// asks this of every stored coefficient, so values within 2²² steps of zero take a
    /// loop without branches or calls, which computes what `word` does there: the same
    /// quotient and roundings, no neighbour to try, and a finite value for every word when the
    /// step is below `f32::MAX / 2²⁴` (a word's value is at most 2²³ steps there). Any other
    /// value sends the whole slice through `word`.
    pub fn words_of(&self, values: &[f32]) -> Option<Vec<u32>> {
        pgvol_core::cpu::run(WordsOf(self, values))
    }

    /// [`FixedScale::words_of`], inlined into both builds of its kernel.
    #[inline(always)]
    fn words_of_here(&self, values: &[f32]) -> Option<Vec<u32>> {
        const FINITE_STEP: f32 = f32::MAX / (1u32 << 24) as f32;
        if self.step < FINITE_STEP {
            let (step, knee, ratio) = (self.step as f64, self.knee as f64, self.ratio as f64);
            let mut words = vec![0u32; values.len()];
            let mut outside = 0u32;
            for (w, &v) in words.iter_mut().zip(values) {
                let a = (v as f64 / step).abs();
                let near = a < NEIGHBOURS_FROM;
                outside |= u32::from(!near);
                // Out-of-range lanes compute from 0 and are discarded below.
                let a = if near { a } else { 0.0 };
                let r = round_small(a);
                let m = if r <= knee {
                    r
                } else {
                    knee + round_small((a - knee) / ratio)
                };
                // `m` is a whole number below 2²³, so it is the low bits of `m + 2⁵²`.
                let q = (m + WHOLE).to_bits() as u32;
                *w = if v < 0.0 { q.wrapping_neg() } else { q };
            }
            if outside == 0 {
                return Some(words);
            }
        }
        values.iter().map(|&v| self.word(v)).collect()
    }

    /// The word nearest to `v` on this scale, or `None` if there is none (beyond 31 bits, or a
    /// non-finite value either way). A value some word decodes to gets that word back, so
    /// quantising decoded values gives their words again (far beyond 2²³ fine steps, where the
    /// estimate in f64 may miss by one, the neighbours are tried).
    pub fn word(&self, v: f32) -> Option<u32> {
        let a = (v as f64 / self.step as f64).abs();
        let k = self.knee as f64;
        let m = if a.round() <= k {
            a.round()
        } else {
            k + ((a - k) / self.ratio as f64).round()
        };
        if m.is_nan() || m >= i32::MAX as f64 {
            return None;
        }
        let q = if v < 0.0 { -(m as i32) } else { m as i32 };
        let value = self.value(q as u32);
        if !value.is_finite() {
            return None;
        }
        // Below 2²² steps the rounded estimate of a decoded value is its own word (its relative
        // error of 2⁻²⁴ is under half a step), so only larger ones need the neighbours.
        if value != v && a >= NEIGHBOURS_FROM {
            for r in [q.checked_sub(1), q.checked_add(1)].into_iter().flatten() {
                if r != i32::MIN && self.value(r as u32) == v {
                    return Some(r as u32);
                }
            }
        }
        Some(q as u32)
    }
}

/// 2⁵²: adding it to a double below it rounds away the fraction, since its unit is 1.
const WHOLE: f64 = (1u64 << 52) as f64;

/// `x.round()` (halves away from zero) for `0 ≤ x < 2⁵¹`, in a form that vectorises (on the
/// baseline x86-64 target `f64::round` is a library call, and casts to integers check their
/// range). `t` is the integer part and `x − t` is exact (`x` and `t` are within a factor of two,
/// or `t` is 0), so comparing it with ½ decides as rounding does. Other `x` give a value that
/// is not used.
#[inline]
fn round_small(x: f64) -> f64 {
    let nearest = (x + WHOLE) - WHOLE;
    let t = if nearest > x { nearest - 1.0 } else { nearest };
    if x - t >= 0.5 {
        t + 1.0
    } else {
        t
    }
}

/// Steps from zero beyond which [`FixedScale::word`] checks the neighbouring words.
const NEIGHBOURS_FROM: f64 = (1u64 << 22) as f64;

/// Default bound on how far a coefficient the band does not need may move, in grid spacings.
pub const FREE_TOLERANCE: f32 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_is_fine_up_to_the_knee_and_coarse_beyond() {
        let s = FixedScale {
            step: 0.5,
            knee: 4,
            ratio: 3,
        };
        assert!(s.is_valid());
        let values: Vec<f32> = [0i32, 1, 4, 5, 6, -5, i32::MIN + 1]
            .iter()
            .map(|&q| s.value(q as u32))
            .collect();
        assert_eq!(values[..6], [0.0, 0.5, 2.0, 3.5, 5.0, -3.5]);
        assert!(values[6] < -1e9);
        // Nearest words: fine steps below the knee, coarse above, the sign kept.
        assert_eq!(s.word(1.2), Some(2));
        assert_eq!(s.word(-1.2), Some(-2i32 as u32));
        assert_eq!(s.word(3.4), Some(5));
        assert_eq!(s.word(4.4), Some(6));
        assert_eq!(s.word(f32::NAN), None);
        assert_eq!(s.word(1e30), None);
        for bad in [
            FixedScale { step: 0.0, ..s },
            FixedScale {
                step: f32::INFINITY,
                ..s
            },
            FixedScale { ratio: 0, ..s },
            FixedScale {
                ratio: MAX_RATIO + 1,
                ..s
            },
            FixedScale {
                knee: u32::MAX,
                ..s
            },
        ] {
            assert!(!bad.is_valid(), "{bad:?}");
        }
    }

    /// The batch gives `word` of each value: words' own values and the halves between them on
    /// both sides of the knee, random values, values past the fast range and non-finite ones
    /// (which send the batch through `word`, `None` included).
    #[test]
    fn batch_words_are_single_words() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for (step, knee, ratio) in [(1.0f32 / 512.0, 512u32, 8u32), (0.37, 5, 3), (1e-3, 0, 1)] {
            let scale = FixedScale { step, knee, ratio };
            let mut values = Vec::new();
            for w in (0..2000u32).chain(knee.saturating_sub(50)..knee + 50) {
                let v = scale.value(w);
                let half = step * if w >= knee { ratio as f32 } else { 1.0 } * 0.5;
                for x in [v, v + half, v - half, v + half * 0.999, v + half * 1.001] {
                    values.extend([x, -x]);
                }
            }
            for _ in 0..20_000 {
                let bits = next();
                let x = (bits >> 40) as f32 / (1u64 << 24) as f32 * 4.0 * step * knee as f32;
                values.push(if bits & 1 == 0 { x } else { -x });
            }
            let single: Vec<Option<u32>> = values.iter().map(|&v| scale.word(v)).collect();
            let batch = scale.words_of(&values).expect("all in range");
            for ((v, s), b) in values.iter().zip(&single).zip(&batch) {
                assert_eq!(Some(*b), *s, "{scale:?} {v:e}");
            }
            let far = step * (1u32 << 23) as f32 * ratio as f32;
            let mut beyond = values[..100].to_vec();
            beyond.push(far);
            let want: Option<Vec<u32>> = beyond.iter().map(|&v| scale.word(v)).collect();
            assert_eq!(scale.words_of(&beyond), want);
            assert!(want.is_some());
            for bad in [f32::NAN, f32::INFINITY, -1e38] {
                beyond.push(bad);
                assert_eq!(scale.words_of(&beyond), None, "{bad}");
                beyond.pop();
            }
            // A scale no reader accepts still gives `word`'s answers.
            let invalid = FixedScale {
                knee: u32::MAX,
                ..scale
            };
            let want: Option<Vec<u32>> = values.iter().map(|&v| invalid.word(v)).collect();
            assert_eq!(invalid.words_of(&values), want);
        }
    }

    #[test]
    fn the_fast_path_gives_the_same_bits() {
        for (step, knee, ratio) in [(0.37f32, 512u32, 8u32), (1e-3, 0, 1), (3.1, 5, 65536)] {
            let scale = FixedScale { step, knee, ratio };
            let fast = scale.fast();
            let exact = (1u32 << 24) / ratio;
            let mut words = Vec::new();
            for centre in [0, knee, exact, 1 << 24, i32::MAX as u32] {
                for d in 0..=40u32 {
                    for q in [
                        centre.wrapping_add(d).wrapping_sub(20),
                        centre.wrapping_add(d),
                    ] {
                        words.extend([q, (q as i32).wrapping_neg() as u32]);
                    }
                }
            }
            for w in words {
                assert_eq!(
                    fast.value(w).to_bits(),
                    scale.value(w).to_bits(),
                    "{scale:?} {w}"
                );
            }
            // Every 16-bit word the f32 scale calls exact, as slicing maps them.
            let words = scale.words();
            for w in i16::MIN..=i16::MAX {
                let w = w as i32;
                if words.exact_up_to(w.unsigned_abs()) {
                    assert_eq!(words.value(w).to_bits(), scale.value(w as u32).to_bits());
                }
            }
        }
    }
}
