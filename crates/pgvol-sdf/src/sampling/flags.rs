//! One bit per sampling brick: the band's plan holds a few flags for every brick of the grid
//! (134 million bricks of 4³ at 2048³), so they are packed rather than a byte each.

/// A fixed-length set of bits.
#[derive(Clone, Debug)]
pub(super) struct Bits(Vec<u64>);

impl Bits {
    pub(super) fn new(len: usize) -> Self {
        Bits(vec![0; len.div_ceil(64)])
    }

    #[inline]
    pub(super) fn get(&self, i: usize) -> bool {
        self.0[i >> 6] >> (i & 63) & 1 == 1
    }

    #[inline]
    pub(super) fn set(&mut self, i: usize) {
        self.0[i >> 6] |= 1 << (i & 63);
    }

    /// Sets bits `range` (a run of bricks along x).
    pub(super) fn set_range(&mut self, range: std::ops::RangeInclusive<usize>) {
        for i in range {
            self.set(i);
        }
    }

    /// Sets every bit of `range`, a word at a time.
    pub(super) fn set_run(&mut self, range: std::ops::Range<usize>) {
        let (start, end) = (range.start, range.end);
        if start >= end {
            return;
        }
        for w in start >> 6..((end - 1) >> 6) + 1 {
            let lo = start.max(w << 6) - (w << 6);
            let hi = end.min((w + 1) << 6) - (w << 6);
            self.0[w] |= mask(lo, hi);
        }
    }

    /// Whether some bit of `range` is set, a word at a time.
    pub(super) fn any_in(&self, range: std::ops::Range<usize>) -> bool {
        self.words_in(range).any(|(word, mask)| word & mask != 0)
    }

    /// Whether every bit of `range` is set, a word at a time.
    pub(super) fn all_in(&self, range: std::ops::Range<usize>) -> bool {
        self.words_in(range).all(|(word, mask)| word & mask == mask)
    }

    /// The words holding `range`, each with the mask of the range's bits in it.
    fn words_in(&self, range: std::ops::Range<usize>) -> impl Iterator<Item = (u64, u64)> + '_ {
        let (start, end) = (range.start, range.end);
        let words = if start < end {
            start >> 6..((end - 1) >> 6) + 1
        } else {
            0..0
        };
        words.map(move |w| {
            let lo = start.max(w << 6) - (w << 6);
            let hi = end.min((w + 1) << 6) - (w << 6);
            (self.0[w], mask(lo, hi))
        })
    }
}

/// The bits `lo..hi` of a word (`hi` ≤ 64).
fn mask(lo: usize, hi: usize) -> u64 {
    if hi - lo == 64 {
        u64::MAX
    } else {
        ((1u64 << (hi - lo)) - 1) << lo
    }
}

/// Per brick: its sign when known (the region's winding number decided it), else unknown.
#[derive(Clone, Debug)]
pub(super) struct RegionSigns {
    known: Bits,
    inside: Bits,
}

impl RegionSigns {
    pub(super) fn new(len: usize) -> Self {
        Self {
            known: Bits::new(len),
            inside: Bits::new(len),
        }
    }

    #[inline]
    pub(super) fn get(&self, i: usize) -> Option<bool> {
        self.known.get(i).then(|| self.inside.get(i))
    }

    /// The sign every brick of `range` has, when each has one and they agree.
    pub(super) fn same_in(&self, range: std::ops::Range<usize>) -> Option<bool> {
        if !self.known.all_in(range.clone()) {
            return None;
        }
        if self.inside.all_in(range.clone()) {
            Some(true)
        } else if !self.inside.any_in(range) {
            Some(false)
        } else {
            None
        }
    }

    pub(super) fn set(&mut self, i: usize, sign: Option<bool>) {
        if let Some(inside) = sign {
            self.known.set(i);
            if inside {
                self.inside.set(i);
            }
        }
    }

    /// [`RegionSigns::set`] of every brick of `range` to `sign`, a word at a time.
    pub(super) fn set_run(&mut self, range: std::ops::Range<usize>, sign: Option<bool>) {
        if let Some(inside) = sign {
            self.known.set_run(range.clone());
            if inside {
                self.inside.set_run(range);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_and_signs_read_back_what_was_set() {
        let mut b = Bits::new(200);
        b.set_range(60..=70);
        b.set(199);
        assert!((0..200).all(|i| b.get(i) == ((60..=70).contains(&i) || i == 199)));
        let mut s = RegionSigns::new(130);
        s.set(3, Some(true));
        s.set(64, Some(false));
        s.set(65, None);
        assert_eq!(
            (s.get(3), s.get(64), s.get(65), s.get(0)),
            (Some(true), Some(false), None, None)
        );
    }

    /// The word-at-a-time range tests agree with testing bit by bit, across word borders.
    #[test]
    fn ranges_test_as_their_bits_do() {
        let mut b = Bits::new(300);
        b.set_range(60..=140);
        b.set(250);
        for start in [0, 1, 59, 60, 63, 64, 100, 127, 128, 141, 249, 251] {
            for end in [start, start + 1, 64, 65, 128, 141, 142, 192, 251, 300] {
                if end < start {
                    continue;
                }
                let bits: Vec<bool> = (start..end).map(|i| b.get(i)).collect();
                assert_eq!(
                    b.any_in(start..end),
                    bits.iter().any(|&x| x),
                    "{start}..{end}"
                );
                assert_eq!(
                    b.all_in(start..end),
                    bits.iter().all(|&x| x),
                    "{start}..{end}"
                );
            }
        }
        let mut s = RegionSigns::new(200);
        for i in 10..150 {
            s.set(i, Some(i >= 100));
        }
        assert_eq!(s.same_in(10..100), Some(false));
        assert_eq!(s.same_in(100..150), Some(true));
        assert_eq!(s.same_in(90..110), None);
        assert_eq!(s.same_in(140..151), None);
        let mut runs = RegionSigns::new(300);
        let mut each = RegionSigns::new(300);
        for (range, sign) in [
            (3..70, Some(true)),
            (70..200, Some(false)),
            (200..260, None),
        ] {
            runs.set_run(range.clone(), sign);
            range.for_each(|i| each.set(i, sign));
        }
        assert!((0..300).all(|i| runs.get(i) == each.get(i)));
    }
}
