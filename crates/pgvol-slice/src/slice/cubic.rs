//! The field along a segment of a layer's grid as polynomials in the fraction of the way: what
//! root finding on an edge evaluates, a few multiplications per step.

/// A field along a segment as one or two cubics in the fraction of the way, the second from
/// `split` on.
pub(crate) struct CubicPieces {
    pub(crate) split: f32,
    pub(crate) first: [f32; 4],
    pub(crate) second: [f32; 4],
}

impl CubicPieces {
    #[inline]
    pub(crate) fn at(&self, t: f32) -> f32 {
        let p = if t < self.split {
            &self.first
        } else {
            &self.second
        };
        ((p[3] * t + p[2]) * t + p[1]) * t + p[0]
    }
}

/// The cubic `p(x)` (coefficients by power) as a cubic in `t` for `x = x0 + s·t`.
pub(crate) fn shift_cubic(p: [f32; 4], x0: f32, s: f32) -> [f32; 4] {
    // Taylor coefficients of p at x0, each scaled by the matching power of s.
    let d0 = ((p[3] * x0 + p[2]) * x0 + p[1]) * x0 + p[0];
    let d1 = (3.0 * p[3] * x0 + 2.0 * p[2]) * x0 + p[1];
    let d2 = 3.0 * p[3] * x0 + p[2];
    let d3 = p[3];
    [d0, d1 * s, d2 * s * s, d3 * s * s * s]
}
