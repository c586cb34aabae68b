//! Predicting each quantised word from the words before it in its brick, as the format defines
//! it: the encoder codes the residual from this prediction, and the decoder's own loops
//! (`brick_decoder`) are tested against it.

use crate::sparse_params::Predictor;

/// The prediction of word `at` (x fastest in a brick of `n` nodes) from words before it.
pub(crate) fn predict(words: &[u32], n: [usize; 3], at: usize, pred: Predictor, mask: u32) -> u32 {
    let (i, j, k) = (at % n[0], (at / n[0]) % n[1], at / (n[0] * n[1]));
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
