//! Golden-section search, the one-dimensional minimiser behind the `iso` fit's `z_step` choice.

/// The minimiser of `cost` on `[a, b]` found with `evaluations` calls (at least 3), assuming the
/// cost is unimodal there; otherwise some local minimum.
pub fn golden_section(
    cost: impl Fn(f64) -> f64,
    mut a: f64,
    mut b: f64,
    evaluations: usize,
) -> f64 {
    let phi = 0.618_033_988_749_895;
    let mut x1 = b - phi * (b - a);
    let mut x2 = a + phi * (b - a);
    let (mut f1, mut f2) = (cost(x1), cost(x2));
    for _ in 2..evaluations.max(3) {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - phi * (b - a);
            f1 = cost(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + phi * (b - a);
            f2 = cost(x2);
        }
    }
    if f1 <= f2 {
        x1
    } else {
        x2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn finds_the_minimum_of_a_parabola_with_the_calls_it_was_given() {
        let calls = Cell::new(0);
        let cost = |x: f64| {
            calls.set(calls.get() + 1);
            (x - 0.3).powi(2)
        };
        let x = golden_section(cost, 0.0, 1.0, 30);
        assert!((x - 0.3).abs() < 1e-5, "{x}");
        assert_eq!(calls.get(), 30);
    }

    #[test]
    fn a_minimum_at_the_end_of_the_interval_is_approached() {
        let x = golden_section(|x| x, 0.05, 1.0, 20);
        assert!(x < 0.06, "{x}");
    }
}
