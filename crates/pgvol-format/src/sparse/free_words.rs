//! The encoder's choice of the values of stored coefficients the surface band does not need
//! (`fixed` only): moved towards their prediction, so that their residuals are zero.

use super::options::EncodeOptions;
use super::predict::{delta_x_rows, for_each_node, predict_at};
use crate::sparse_params::Predictor;

/// How many coarse `fixed` words a coefficient the band does not need may move: the tolerance
/// of `opts` in coarse words for a basis whose weights sum to at most `weight`, so that no value
/// moves further than the tolerance.
pub(crate) fn tolerance_steps(opts: &EncodeOptions, weight: f32) -> i32 {
    (opts.free_tolerance / (opts.fixed_step / weight * opts.fixed_ratio as f32)).clamp(0.0, 1e9)
        as i32
}

/// Replaces each free word (`free[at]`, in coding order) by the word closest to its prediction
/// from the words before it (already settled) among those between it and `tolerance` words
/// nearer to zero, so that its residual is usually zero. Only towards zero: magnitudes never
/// grow, so the field's largest node value (which `pgvol offset` reads as the stored band) does
/// not either, and the sign stays. Words are two's-complement integers.
pub(crate) fn settle_free_words(
    words: &mut [u32],
    free: &[bool],
    n: [usize; 3],
    pred: Predictor,
    tolerance: i32,
) {
    if pred == Predictor::DeltaX {
        // The default predictor row by row: each word is predicted by the one before it.
        for (at, from) in delta_x_rows(n) {
            let mut p = from.map_or(0, |f| words[f]);
            for (word, &free) in words[at..at + n[0]].iter_mut().zip(&free[at..]) {
                if free {
                    *word = settled(*word, p, tolerance);
                }
                p = *word;
            }
        }
    } else {
        settle_node_by_node(words, free, n, pred, tolerance);
    }
}

/// [`settle_free_words`] for any predictor, a node at a time.
fn settle_node_by_node(
    words: &mut [u32],
    free: &[bool],
    n: [usize; 3],
    pred: Predictor,
    tolerance: i32,
) {
    for_each_node(n, |at, node| {
        if free[at] {
            let p = predict_at(words, n, at, node, pred, u32::MAX);
            words[at] = settled(words[at], p, tolerance);
        }
    });
}

/// The word between `word` and `tolerance` words nearer to zero that is closest to the
/// prediction `p`.
fn settled(word: u32, p: u32, tolerance: i32) -> u32 {
    let (p, q) = (p as i32, word as i32);
    let (lo, hi) = if q >= 0 {
        (q.saturating_sub(tolerance).max(0), q)
    } else {
        (q, q.saturating_add(tolerance).min(0))
    };
    p.clamp(lo, hi) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The row-by-row `delta-x` path settles the words as the node-by-node one does.
        #[test]
        fn delta_x_rows_settle_as_nodes_do(
            n in proptest::array::uniform3(1usize..12),
            seed in any::<u64>(),
            tolerance in 0i32..40,
        ) {
            let mut s = seed | 1;
            let mut next = || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                s
            };
            let len = n[0] * n[1] * n[2];
            let words: Vec<u32> = (0..len).map(|_| ((next() % 201) as i32 - 100) as u32).collect();
            let free: Vec<bool> = (0..len).map(|_| next() % 3 != 0).collect();
            let mut rows = words.clone();
            settle_free_words(&mut rows, &free, n, Predictor::DeltaX, tolerance);
            let mut nodes = words;
            settle_node_by_node(&mut nodes, &free, n, Predictor::DeltaX, tolerance);
            prop_assert_eq!(rows, nodes);
        }
    }

    #[test]
    fn free_words_follow_the_prediction_within_the_tolerance() {
        // A ramp along x with the middle words free: they become the ramp where it is within
        // reach, and stop at the tolerance where it is not.
        let mut words: Vec<u32> = [0i32, 10, 20, 999, 40, -999, 60]
            .iter()
            .map(|&v| v as u32)
            .collect();
        let free = [false, false, false, true, false, true, false];
        settle_free_words(&mut words, &free, [7, 1, 1], Predictor::DeltaX, 5);
        let got: Vec<i32> = words.iter().map(|&w| w as i32).collect();
        // delta-x predicts the previous word.
        assert_eq!(got, [0, 10, 20, 994, 40, -994, 60]);
        let mut words: Vec<u32> = vec![3, 7, 12];
        settle_free_words(
            &mut words,
            &[false, true, false],
            [3, 1, 1],
            Predictor::DeltaX,
            5,
        );
        assert_eq!(words, [3, 3, 12]);
        // Never away from zero, nor across it.
        let mut words: Vec<u32> = [9i32, 5, -9, -5, 2, -3].iter().map(|&v| v as u32).collect();
        let free = [false, true, false, true, false, true];
        settle_free_words(&mut words, &free, [6, 1, 1], Predictor::DeltaX, 5);
        let got: Vec<i32> = words.iter().map(|&w| w as i32).collect();
        assert_eq!(got, [9, 5, -9, -5, 2, 0]);
    }
}
