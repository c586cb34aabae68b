//! Predicting each quantised word from the words before it in its brick, as the format defines
//! it: the encoder codes the residual from this prediction, and the decoder's own loops
//! (`brick_decoder`) are tested against it.

use crate::sparse_params::Predictor;

/// The prediction of word `at` (x fastest in a brick of `n` nodes) from words before it: the
/// reference the decoder's loops are tested against.
#[cfg(test)]
pub(crate) fn predict(words: &[u32], n: [usize; 3], at: usize, pred: Predictor, mask: u32) -> u32 {
    let node = [at % n[0], (at / n[0]) % n[1], at / (n[0] * n[1])];
    predict_at(words, n, at, node, pred, mask)
}

/// Calls `visit` with each word's index and node `[i, j, k]` in coding order, for loops that
/// would otherwise divide the index back into the node for every word (most of the cost of a
/// prediction). Plain nested loops, which compile to tighter code than nested `flat_map`s.
#[inline]
pub(crate) fn for_each_node(n: [usize; 3], mut visit: impl FnMut(usize, [usize; 3])) {
    let mut at = 0;
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                visit(at, [i, j, k]);
                at += 1;
            }
        }
    }
}

/// The rows along x of a brick of `n` nodes in coding order, as the index of their first word
/// and of the word that predicts it under `delta-x` (the word above it in y, else the one
/// before it in z; none, a prediction of 0, for the first row). Every later word of a row is
/// predicted by the word before it.
#[inline]
pub(crate) fn delta_x_rows(n: [usize; 3]) -> impl Iterator<Item = (usize, Option<usize>)> {
    let (sy, sz) = (n[0], n[0] * n[1]);
    (0..n[2]).flat_map(move |k| {
        (0..n[1]).map(move |j| {
            let at = sy * j + sz * k;
            let from = if j > 0 {
                Some(at - sy)
            } else if k > 0 {
                Some(at - sz)
            } else {
                None
            };
            (at, from)
        })
    })
}

/// The prediction of word `at`, whose node `node` the caller knows.
#[inline]
pub(crate) fn predict_at(
    words: &[u32],
    n: [usize; 3],
    at: usize,
    node: [usize; 3],
    pred: Predictor,
    mask: u32,
) -> u32 {
    let [i, j, k] = node;
    let (sx, sy, sz) = (1, n[0], n[0] * n[1]);
    let get = |di: usize, dj: usize, dk: usize| -> u32 {
        if i < di || j < dj || k < dk {
            0
        } else {
            words[at - di * sx - dj * sy - dk * sz]
        }
    };
    let p = match pred {
        Predictor::None => 0,
        Predictor::DeltaX => {
            if i > 0 {
                get(1, 0, 0)
            } else if j > 0 {
                get(0, 1, 0)
            } else {
                get(0, 0, 1)
            }
        }
        Predictor::Lorenzo => get(1, 0, 0)
            .wrapping_add(get(0, 1, 0))
            .wrapping_add(get(0, 0, 1))
            .wrapping_sub(get(1, 1, 0))
            .wrapping_sub(get(1, 0, 1))
            .wrapping_sub(get(0, 1, 1))
            .wrapping_add(get(1, 1, 1)),
    };
    p & mask
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each row's first word gets the prediction `predict_at` gives it.
    #[test]
    fn delta_x_rows_start_with_the_words_prediction() {
        for n in [[1, 1, 1], [5, 1, 3], [1, 4, 2], [3, 2, 1], [16, 16, 16]] {
            let words: Vec<u32> = (0..n[0] * n[1] * n[2]).map(|w| w as u32 * 7 + 3).collect();
            let mut rows = 0;
            for (at, from) in delta_x_rows(n) {
                assert_eq!(at, rows * n[0]);
                let node = [0, (at / n[0]) % n[1], at / (n[0] * n[1])];
                let first = from.map_or(0, |f| words[f]);
                assert_eq!(
                    first,
                    predict_at(&words, n, at, node, Predictor::DeltaX, u32::MAX)
                );
                rows += 1;
            }
            assert_eq!(rows, n[1] * n[2]);
        }
    }

    /// The node-order walk numbers words as `predict` divides them, on bricks flat in each
    /// axis and a full one.
    #[test]
    fn nodes_in_coding_order_are_the_index_divided() {
        for n in [[1, 1, 1], [5, 1, 3], [1, 4, 2], [3, 2, 1], [16, 16, 16]] {
            let mut count = 0;
            for_each_node(n, |at, node| {
                assert_eq!(at, count);
                assert_eq!(node, [at % n[0], (at / n[0]) % n[1], at / (n[0] * n[1])]);
                count += 1;
            });
            assert_eq!(count, n[0] * n[1] * n[2]);
        }
    }
}
