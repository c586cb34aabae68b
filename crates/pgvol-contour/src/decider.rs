//! Asymptotic decider for faces whose diagonal corners share a sign.

/// Whether the inside corners of an ambiguous face are connected across the face.
///
/// `g` holds the face's corner values minus iso in cyclic order, and `first_inside` says whether
/// corners 0 and 2 (rather than 1 and 3) are the inside pair. The bilinear interpolant has its
/// saddle at `(g0 g2 - g1 g3) / (g0 + g2 - g1 - g3)`; the denominator is (inside pair sum) minus
/// (outside pair sum), which is strictly negative, so the saddle lies inside exactly when the
/// inside pair's product exceeds the outside pair's. Comparing products avoids the division and
/// its rounding: products commute exactly, so both cells sharing the face reach the same answer
/// whatever corner they start from. A saddle exactly at iso counts as outside, like any value
/// `>= iso`; NaN makes the comparison false, which also separates.
#[inline]
pub(crate) fn joins_inside(g: [f32; 4], first_inside: bool) -> bool {
    let (inside, outside) = if first_inside {
        (g[0] * g[2], g[1] * g[3])
    } else {
        (g[1] * g[3], g[0] * g[2])
    };
    inside > outside
}

#[cfg(test)]
mod tests {
    use super::*;

    fn saddle(g: [f32; 4]) -> f64 {
        let g = g.map(f64::from);
        (g[0] * g[2] - g[1] * g[3]) / (g[0] + g[2] - g[1] - g[3])
    }

    #[test]
    fn matches_the_saddle_value() {
        let cases = [
            [-1.0, 0.5, -1.0, 0.5],
            [-0.2, 0.5, -0.3, 0.9],
            [-2.0, 1.0, -0.1, 3.0],
            [0.4, -0.7, 0.1, -0.9],
        ];
        for g in cases {
            let first_inside = g[0] < 0.0;
            assert_eq!(joins_inside(g, first_inside), saddle(g) < 0.0, "{g:?}");
        }
    }

    #[test]
    fn same_answer_from_every_starting_corner_and_direction() {
        let g = [-0.3f32, 0.7, -0.9, 0.25];
        let expect = joins_inside(g, true);
        for shift in 0..4 {
            let rot: [f32; 4] = std::array::from_fn(|i| g[(i + shift) % 4]);
            let rev: [f32; 4] = std::array::from_fn(|i| rot[(4 - i) % 4]);
            assert_eq!(joins_inside(rot, rot[0] < 0.0), expect);
            assert_eq!(joins_inside(rev, rev[0] < 0.0), expect);
        }
    }

    #[test]
    fn a_tie_separates() {
        assert!(!joins_inside([-1.0, 1.0, -1.0, 1.0], true));
    }
}
