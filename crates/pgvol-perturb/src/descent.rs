//! The paper's optimisation step: once a perturbation is chosen, its quadric's coefficients are
//! moved down the gradient of the functional (the sum of `|M|` over the vertices), in small
//! steps that grow while they succeed and shrink when they fail, so that the move stays near
//! the minimum it started in (the paper's "smooth" movement along the gradient instead of plain
//! gradient descent). Every step must keep the term a local bump within the loop's bounds and
//! must not put more probes on the wrong side.

use crate::field::Perturbation;
use crate::quadric::{monomials, TERMS};
use crate::trial::{evaluate, State, Trial};

/// First step, as a fraction of the length of the coefficient vector.
const FIRST_STEP: f64 = 0.05;

/// The descent ends once a step this small (of the coefficients' length) fails.
const SMALLEST_STEP: f64 = 1e-3;

/// The gradient of the functional with respect to the quadric's coefficients at `trial`:
/// `Σ sign(M) f 3Q² m(u)` over the vertices where the bump is positive (elsewhere its value and
/// its derivative are zero).
fn gradient(state: &State, trial: &Trial) -> [f64; TERMS] {
    let quadric = &trial.term.quadric;
    let mut g = [0.0; TERMS];
    for &(i, v, _) in &trial.vertices {
        let p = state.points[i as usize];
        let q = quadric.value(p);
        if q <= 0.0 || v == 0.0 {
            continue;
        }
        let w = v.signum() * trial.term.factor * 3.0 * q * q;
        for (gk, mk) in g.iter_mut().zip(monomials(quadric.local(p))) {
            *gk += w * mk;
        }
    }
    g
}

/// `trial` improved by at most `steps` descent steps on its coefficients, keeping its reach
/// within `reach_limit` local units and its peak within `peak_limit`; returns it and the steps
/// taken.
pub(crate) fn refine(
    state: &State,
    mut trial: Trial,
    reach_limit: f64,
    peak_limit: f64,
    steps: usize,
) -> (Trial, usize) {
    let mut step = FIRST_STEP;
    let mut taken = 0;
    for _ in 0..steps {
        let g = gradient(state, &trial);
        let g_len = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        let q_len = trial
            .term
            .quadric
            .q
            .iter()
            .map(|x| x * x)
            .sum::<f64>()
            .sqrt();
        if g_len == 0.0 || !g_len.is_finite() {
            break;
        }
        let mut improved = false;
        while step >= SMALLEST_STEP {
            let mut quadric = trial.term.quadric;
            for (qk, gk) in quadric.q.iter_mut().zip(g) {
                *qk -= step * q_len * gk / g_len;
            }
            let local = quadric.positive_reach().is_some_and(|r| r <= reach_limit)
                && quadric.peak().is_some_and(|p| p <= peak_limit);
            let candidate = Perturbation {
                quadric,
                factor: trial.term.factor,
            };
            match local.then(|| evaluate(state, candidate).ok()).flatten() {
                Some(better) if better.gain > trial.gain => {
                    trial = better;
                    step *= 1.5;
                    improved = true;
                    break;
                }
                _ => step *= 0.5,
            }
        }
        if !improved {
            break;
        }
        taken += 1;
    }
    (trial, taken)
}
