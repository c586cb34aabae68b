//! The `fixed` precision's map from integer words to coefficients, computed in f32: a fine step
//! up to a knee and a coarser one beyond. Shared by the file reader, which dequantises with it,
//! and by slicing, which keeps bricks as 16-bit words and maps them as it reads them.

/// A word's value while its count of fine steps stays below 2²⁴, where every step of the f32
/// computation is exact (so the value is the format's, bit for bit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WordScale {
    step: f32,
    knee: f32,
    ratio_less_one: f32,
    /// Words of smaller magnitude count fewer than 2²⁴ fine steps.
    exact_below: u32,
}

impl WordScale {
    /// The scale of fine step `step`, `knee` words of it, then `ratio` steps per word (≥ 1).
    pub fn new(step: f32, knee: u32, ratio: u32) -> Self {
        WordScale {
            step,
            knee: knee as f32,
            ratio_less_one: ratio.saturating_sub(1) as f32,
            exact_below: (1u32 << 24) / ratio.max(1),
        }
    }

    /// Whether words of magnitude up to `largest` all have exact values here.
    #[inline]
    pub fn exact_up_to(&self, largest: u32) -> bool {
        largest < self.exact_below
    }

    /// The value of word `w` (two's complement), whose magnitude passes
    /// [`WordScale::exact_up_to`]; branch-free, so loops of it vectorise.
    #[inline(always)]
    pub fn value(&self, w: i32) -> f32 {
        let a = w.unsigned_abs() as f32;
        let v = (a + (a - self.knee).max(0.0) * self.ratio_less_one) * self.step;
        f32::from_bits(v.to_bits() | (w as u32 & 0x8000_0000))
    }

    /// Adds `weight` times the value of each of `words` to `out`; every word must pass
    /// [`WordScale::exact_up_to`].
    #[inline(always)]
    pub fn add_words(&self, words: &[i16], weight: f32, out: &mut [f32]) {
        for (o, &w) in out.iter_mut().zip(words) {
            *o += weight * self.value(w as i32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_follow_the_knee() {
        let s = WordScale::new(0.5, 4, 8);
        assert_eq!(s.value(0).to_bits(), 0.0f32.to_bits());
        assert_eq!(s.value(3), 1.5);
        assert_eq!(s.value(-4), -2.0);
        // Beyond the knee a word counts 8 steps: 4 + 2 · 8 = 20 steps.
        assert_eq!(s.value(6), 10.0);
        assert_eq!(s.value(-6), -10.0);
        assert!(s.exact_up_to((1 << 21) - 1) && !s.exact_up_to(1 << 21));
        let mut out = [1.0f32; 3];
        s.add_words(&[2, -2, 6], 2.0, &mut out);
        assert_eq!(out, [3.0, -1.0, 21.0]);
    }
}
