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

    pub(super) fn set(&mut self, i: usize, sign: Option<bool>) {
        if let Some(inside) = sign {
            self.known.set(i);
            if inside {
                self.inside.set(i);
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
}
