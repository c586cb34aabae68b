//! I-patches `I = Σ wᵢ Pᵢ Π_{j≠i} |Bⱼ|ᵉ + w·Π|Bᵢ|ᵉ` with the bounds raised to `e = n + 1` for
//! Gⁿ continuity with each primary along its boundary curve `Pᵢ = Bᵢ = 0`: every term but the
//! i-th holds `|Bᵢ|ᵉ`, so `I − wᵢ Pᵢ Π_{j≠i} |Bⱼ|ᵉ` vanishes to order n where `Bᵢ = 0`.
//!
//! The slides write `Bⱼⁿ⁺¹`; odd powers would flip the sign of every term holding a negative
//! bound, so the same weights would make different surfaces at odd and even orders. `|B|ⁿ⁺¹`
//! is n times differentiable with all n derivatives zero at `B = 0`, which is all the
//! continuity needs, and equals `B²` for G¹.

use crate::error::OpsError;

/// The highest continuity order offered. Each term is a product of bounds raised to `n + 1`,
/// so its magnitude grows as `|B|^((n+1)·m)`: past G⁴ a few bounds a few units large leave
/// the f32 range the field is sampled in, and the patch flattens onto its bounds so that the
/// renormalisation's central differences see little but rounding.
pub const MAX_CONTINUITY: u32 = 4;

/// The order n of an I-patch's Gⁿ continuity with its primaries, 1 to [`MAX_CONTINUITY`];
/// G¹ (squared bounds) by default.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Continuity(u32);

impl Continuity {
    /// G¹: the bounds squared, the slides' basic I-patch.
    pub const G1: Continuity = Continuity(1);

    /// Gⁿ, refused outside 1 to [`MAX_CONTINUITY`].
    pub fn new(order: u32) -> Result<Continuity, OpsError> {
        if (1..=MAX_CONTINUITY).contains(&order) {
            Ok(Continuity(order))
        } else {
            Err(OpsError::BadParameter(format!(
                "an I-patch's continuity order must be 1 to {MAX_CONTINUITY}, got {order}"
            )))
        }
    }

    /// The order n.
    pub fn order(self) -> u32 {
        self.0
    }

    /// The bounds' exponent, n + 1.
    pub fn exponent(self) -> u32 {
        self.0 + 1
    }
}

impl Default for Continuity {
    fn default() -> Self {
        Continuity::G1
    }
}

/// `x^e` by repeated multiplication: for `e = 2` exactly `x * x` (and `|x|·|x| = x·x` to the
/// bit), so G¹ patches keep the values they had when the bounds were squared directly.
fn power<T: Copy + std::ops::Mul<Output = T>>(x: T, e: u32) -> T {
    (1..e).fold(x, |acc, _| acc * x)
}

/// Refuses an I-patch whose bounds or weights do not pair one to one with its primaries:
/// [`ipatch`] and [`ipatch_terms`] take that as given.
pub fn check_ipatch(
    primaries: usize,
    bounds: usize,
    weights: Option<usize>,
) -> Result<(), OpsError> {
    if primaries < 2 || bounds != primaries {
        return Err(OpsError::BadParameter(format!(
            "an I-patch needs two or more primaries and one bound per primary, got {primaries} \
             primaries and {bounds} bounds"
        )));
    }
    match weights {
        Some(n) if n != primaries => Err(OpsError::BadParameter(format!(
            "an I-patch of {primaries} primaries needs {primaries} weights besides the bounds' \
             weight, got {n}"
        ))),
        _ => Ok(()),
    }
}

/// The I-patch of primaries `p` with bounds `b`, weights `w` and the bounds' weight `w0`, of
/// continuity `order`; one bound and one weight per primary (see [`check_ipatch`]).
pub fn ipatch(p: &[f32], b: &[f32], w: &[f32], w0: f32, order: Continuity) -> f32 {
    let powers: Vec<f32> = b
        .iter()
        .map(|&x| power(x.abs(), order.exponent()))
        .collect();
    let all: f32 = powers.iter().product();
    let mut sum = w0 * all;
    for i in 0..p.len() {
        let others: f32 = (0..p.len())
            .filter(|&j| j != i)
            .map(|j| powers[j])
            .product();
        sum += w[i] * p[i] * others;
    }
    sum
}

/// The I-patch's terms at a point: `Pᵢ Π_{j≠i} |Bⱼ|ᵉ` for each i, then `Π|Bᵢ|ᵉ`, so that the patch
/// is `Σ wᵢ·termᵢ + w·term_last`; one bound per primary (see [`check_ipatch`]).
pub fn ipatch_terms(p: &[f64], b: &[f64], order: Continuity) -> Vec<f64> {
    let e = order.exponent();
    let mut terms: Vec<f64> = (0..p.len())
        .map(|i| {
            let mut t = p[i];
            for (j, &bj) in b.iter().enumerate() {
                if j != i {
                    t *= power(bj.abs(), e);
                }
            }
            t
        })
        .collect();
    terms.push(b.iter().map(|&x| power(x.abs(), e)).product());
    terms
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The k-th one-sided derivative of `f` at `t` (`side` ±1) by the k-th forward difference
    /// of step `h` on that side; the patch is only n times differentiable across its bound,
    /// but a polynomial on either side.
    fn difference(f: &impl Fn(f64) -> f64, t: f64, k: u32, h: f64, side: f64) -> f64 {
        let mut sum = 0.0;
        let mut binomial = 1.0;
        for j in 0..=k {
            let sign = (-1.0f64).powi((k - j) as i32);
            sum += sign * binomial * f(t + side * j as f64 * h);
            binomial = binomial * (k - j) as f64 / (j + 1) as f64;
        }
        sum / (side * h).powi(k as i32)
    }

    /// [`difference`] at h, h/2, …, h/16 extrapolated (Richardson; the error is a series in
    /// h): accurate to about 1e-6 up to the fifth derivative with steps coarse enough to keep
    /// rounding small.
    fn derivative(f: &impl Fn(f64) -> f64, t: f64, k: u32, h: f64, side: f64) -> f64 {
        let mut table: Vec<f64> = (0..5)
            .map(|i| difference(f, t, k, h / f64::from(1u32 << i), side))
            .collect();
        for level in 1..5 {
            let factor = f64::from(1u32 << level);
            for i in (level..5).rev() {
                table[i] = (factor * table[i] - table[i - 1]) / (factor - 1.0);
            }
        }
        table[4]
    }

    #[test]
    fn an_ipatch_of_order_n_matches_its_primary_to_n_derivatives_across_the_bound() {
        // Curved primaries and a curved first bound; the second bound is constant along the
        // test line, so there `I / (w₁·B₂ᵉ)` and P₁ differ by `O(B₁ᵉ)` only.
        let p1 = |x: f64, y: f64, z: f64| x * x + 0.5 * y * y + 0.3 * z - 0.4;
        let p2 = |x: f64, y: f64, z: f64| (x - 0.2).powi(2) + y * z - 0.9;
        let b1 = |x: f64, y: f64, z: f64| x + 0.3 * y * y - 0.2 * z - 0.5;
        let b2 = |_x: f64, y: f64, _z: f64| 1.5 - y;
        let (w, w0) = ([0.8, 1.7], -0.6);
        // Along x = t, y = 0.3, z = 0.1 the first bound vanishes at t₀ = 0.5 − 0.027 + 0.02.
        let (y, z) = (0.3, 0.1);
        let t0 = 0.5 - 0.3 * y * y + 0.2 * z;
        assert!(b1(t0, y, z).abs() < 1e-12);
        for n in 1..=MAX_CONTINUITY {
            let order = Continuity::new(n).unwrap();
            let q = w[0] * power(b2(0.0, y, 0.0), order.exponent());
            let patch = |t: f64| {
                let terms = ipatch_terms(
                    &[p1(t, y, z), p2(t, y, z)],
                    &[b1(t, y, z), b2(t, y, z)],
                    order,
                );
                (w[0] * terms[0] + w[1] * terms[1] + w0 * terms[2]) / q
            };
            let primary = |t: f64| p1(t, y, z);
            let h = 0.04;
            for side in [1.0, -1.0] {
                for k in 0..=n {
                    let a = derivative(&patch, t0, k, h, side);
                    let b = derivative(&primary, t0, k, h, side);
                    assert!(
                        (a - b).abs() < 1e-4 * (1.0 + b.abs()),
                        "order {n}, side {side}, derivative {k}: {a} vs {b}"
                    );
                }
            }
            // And no further: the difference grows as the (n+1)-th power of the distance to
            // the bound, on both sides.
            for d in [0.01, -0.01] {
                let lead = |d: f64| (patch(t0 + d) - primary(t0 + d)) / d.abs().powi(n as i32 + 1);
                let (a, b) = (lead(d), lead(d / 2.0));
                assert!(
                    a.abs() > 0.5 && (a - b).abs() < 0.05 * a.abs(),
                    "order {n}: {a}, {b}"
                );
            }
        }
    }

    #[test]
    fn g1_ipatches_keep_the_squared_bounds_values() {
        // The G¹ patch is the basic one: the same f32 arithmetic with squares.
        let (p, b, w, w0) = (
            [0.3f32, -1.2, 0.7],
            [0.9f32, -0.4, 1.3],
            [1.0f32, 2.0, -0.5],
            -0.7,
        );
        let sq: Vec<f32> = b.iter().map(|x| x * x).collect();
        let mut want = w0 * sq.iter().product::<f32>();
        for i in 0..3 {
            let others: f32 = (0..3).filter(|&j| j != i).map(|j| sq[j]).product();
            want += w[i] * p[i] * others;
        }
        assert_eq!(
            ipatch(&p, &b, &w, w0, Continuity::G1).to_bits(),
            want.to_bits()
        );
        assert_eq!(Continuity::default(), Continuity::G1);
        // Cubed bounds' magnitudes for G².
        let g2 = ipatch(&p[..2], &b[..2], &w[..2], w0, Continuity::new(2).unwrap());
        let (c0, c1) = (b[0].abs().powi(3), b[1].abs().powi(3));
        let want2 = w[0] * p[0] * c1 + w[1] * p[1] * c0 + w0 * c0 * c1;
        assert!((g2 - want2).abs() < 1e-6, "{g2} vs {want2}");
    }

    #[test]
    fn continuity_orders_out_of_range_are_refused() {
        for n in [0, MAX_CONTINUITY + 1, u32::MAX] {
            let e = Continuity::new(n).unwrap_err().to_string();
            assert!(e.contains("1 to 4") && !e.contains("--"), "{e}");
        }
        assert_eq!(Continuity::new(3).unwrap().exponent(), 4);
    }

    #[test]
    fn ipatches_without_a_bound_per_primary_are_refused() {
        assert!(check_ipatch(2, 2, None).is_ok() && check_ipatch(3, 3, Some(3)).is_ok());
        let e = check_ipatch(2, 1, None).unwrap_err().to_string();
        assert!(e.contains("2 primaries and 1 bounds"), "{e}");
        assert!(check_ipatch(1, 1, None).is_err());
        assert!(check_ipatch(2, 3, None).is_err());
        let e = check_ipatch(2, 2, Some(1)).unwrap_err().to_string();
        assert!(e.contains("needs 2 weights"), "{e}");
    }
}
