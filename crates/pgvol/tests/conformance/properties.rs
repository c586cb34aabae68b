//! The properties every field is held to, written once over [`Evaluate`], which each trait's
//! suite implements through that trait's own methods.

use std::cell::Cell;

use pgvol::glam::Vec3;
use proptest::prelude::*;
use rayon::prelude::*;

use crate::subjects::Spec;
use crate::support::{bits, vec_bits, THREADS};
use crate::support::{check, fd_gradient, point_in, point_within, scattered, with_threads};

/// A scalar field with its gradient, as a trait under test exposes it.
pub trait Evaluate: Sync {
    fn value(&self, p: Vec3) -> f32;
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3);
}

/// A field and what it is held to.
pub struct Case<E> {
    pub field: E,
    pub spec: Spec,
}

/// The value alone and the value with the gradient come from the same field.
pub fn value_agrees_with_value_gradient<E: Evaluate>(case: &Case<E>) {
    let Case { field, spec } = case;
    check(256, point_in(spec.region), |p| {
        let v = field.value(p);
        let (w, _) = field.value_gradient(p);
        prop_assert!(
            (v - w).abs() <= spec.paths_agree_within,
            "value {} but value_gradient {} at {}",
            v,
            w,
            p
        );
        Ok(())
    });
}

/// Where the field is differentiable, its gradient is the limit of central differences.
pub fn gradient_matches_finite_differences<E: Evaluate>(case: &Case<E>) {
    let Case { field, spec } = case;
    let tested = Cell::new(0u32);
    check(256, point_in(spec.region), |p| {
        if !(spec.smooth)(p, spec.fd_step) {
            return Ok(());
        }
        tested.set(tested.get() + 1);
        let (_, g) = field.value_gradient(p);
        let fd = fd_gradient(|q| field.value(q), p, spec.fd_step);
        prop_assert!(
            (g - fd).length() <= spec.fd_tolerance,
            "gradient {} but differences {} at {}",
            g,
            fd,
            p
        );
        Ok(())
    });
    // A test that skipped most points would say little.
    assert!(tested.get() >= 64, "only {} smooth points", tested.get());
}

/// Negative inside, positive outside, wherever the shape's distance is clear of the field's
/// error; both sides must be sampled.
pub fn sign_is_negative_inside_positive_outside<E: Evaluate>(case: &Case<E>) {
    let Case { field, spec } = case;
    let (inside, outside) = (Cell::new(0u32), Cell::new(0u32));
    check(512, point_in(spec.region), |p| {
        let d = (spec.reference)(p);
        if d.abs() < spec.sign_margin {
            return Ok(());
        }
        let counter = if d < 0.0 { &inside } else { &outside };
        counter.set(counter.get() + 1);
        for v in [field.value(p), field.value_gradient(p).0] {
            prop_assert!(
                (v < 0.0) == (d < 0.0) && v != 0.0,
                "value {} where the distance is {} at {}",
                v,
                d,
                p
            );
        }
        Ok(())
    });
    assert!(
        inside.get() >= 16 && outside.get() >= 16,
        "{} inside and {} outside",
        inside.get(),
        outside.get()
    );
}

/// Near the surface the field is the shape's signed distance, to the implementor's accuracy.
pub fn value_is_the_distance_near_the_surface<E: Evaluate>(case: &Case<E>) {
    let Case { field, spec } = case;
    let tested = Cell::new(0u32);
    check(512, point_in(spec.region), |p| {
        let d = (spec.reference)(p);
        if d.abs() >= spec.near {
            return Ok(());
        }
        tested.set(tested.get() + 1);
        let v = field.value(p);
        prop_assert!(
            (v - d).abs() <= spec.accuracy,
            "value {} but distance {} at {}",
            v,
            d,
            p
        );
        Ok(())
    });
    assert!(
        tested.get() >= 32,
        "only {} points near the surface",
        tested.get()
    );
}

/// `|f(a) − f(b)| <= L |a − b|`. Half the pairs step along the gradient, where a distance
/// field changes fastest, so a field steeper than claimed is caught.
pub fn lipschitz_bound_holds<E: Evaluate>(case: &Case<E>) {
    let Case { field, spec } = case;
    let (lo, hi) = spec.region;
    let tested = Cell::new(0u32);
    let pairs = (point_in(spec.region), point_within(1.0), any::<bool>());
    check(512, pairs, |(a, u, along_gradient)| {
        let b = if along_gradient {
            let g = field.value_gradient(a).1.normalize_or_zero();
            a + g * u.x * spec.lipschitz_reach.min((hi - lo).max_element())
        } else if spec.lipschitz_reach.is_finite() {
            a + u * spec.lipschitz_reach
        } else {
            lo + (hi - lo) * (u * 0.5 + 0.5)
        };
        if !((spec.lipschitz_where)(a) && (spec.lipschitz_where)(b)) || a == b {
            return Ok(());
        }
        tested.set(tested.get() + 1);
        let (fa, fb) = (field.value(a), field.value(b));
        // An absolute 1e-6 absorbs the rounding of values near 1.
        prop_assert!(
            (fa - fb).abs() <= spec.lipschitz * a.distance(b) + 1e-6,
            "|{} − {}| over {} from {} to {}",
            fa,
            fb,
            a.distance(b),
            a,
            b
        );
        Ok(())
    });
    assert!(
        tested.get() >= 64,
        "only {} pairs in the region",
        tested.get()
    );
}

/// The same point gives the same bits whenever and from whichever thread it is asked: in
/// another order (no state carried from one query to the next), on several threads at once,
/// and in rayon pools of several sizes.
pub fn evaluation_is_deterministic_across_calls_and_threads<E: Evaluate>(case: &Case<E>) {
    let Case { field, spec } = case;
    let points = scattered(spec.region, 1000);
    let eval = |p: &Vec3| {
        let (v, g) = field.value_gradient(*p);
        (bits(field.value(*p)), bits(v), vec_bits(g))
    };
    let first: Vec<_> = points.iter().map(eval).collect();
    let mut reversed: Vec<_> = points.iter().rev().map(eval).collect();
    reversed.reverse();
    assert!(reversed == first, "the reverse order gave other bits");
    let (points, eval) = (&points, &eval);
    std::thread::scope(|scope| {
        let runs: Vec<_> = (0..3)
            .map(|t| {
                scope.spawn(move || {
                    points
                        .iter()
                        .skip(t)
                        .step_by(3)
                        .map(eval)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for (t, run) in runs.into_iter().enumerate() {
            let expected: Vec<_> = first.iter().skip(t).step_by(3).cloned().collect();
            assert!(
                run.join().unwrap() == expected,
                "thread {t} gave other bits"
            );
        }
    });
    for threads in THREADS {
        let parallel: Vec<_> = with_threads(threads, || {
            points.par_iter().with_max_len(8).map(eval).collect()
        });
        assert!(
            parallel == first,
            "a pool of {threads} threads gave other bits"
        );
    }
}

/// One `#[test]` per property for each `name => case` given, in a module of that name; the
/// case's field implements [`Evaluate`] through the trait under test. Functions of the calling
/// module listed after `also` become tests too, for properties of one trait only.
macro_rules! property_tests {
    ($($name:ident => $case:expr $(, also $($extra:ident),+)?;)*) => {
        $(
            mod $name {
                use super::*;
                use crate::properties as p;

                #[test]
                fn value_agrees_with_value_gradient() {
                    p::value_agrees_with_value_gradient(&$case);
                }

                #[test]
                fn gradient_matches_finite_differences() {
                    p::gradient_matches_finite_differences(&$case);
                }

                #[test]
                fn sign_is_negative_inside_positive_outside() {
                    p::sign_is_negative_inside_positive_outside(&$case);
                }

                #[test]
                fn value_is_the_distance_near_the_surface() {
                    p::value_is_the_distance_near_the_surface(&$case);
                }

                #[test]
                fn lipschitz_bound_holds() {
                    p::lipschitz_bound_holds(&$case);
                }

                #[test]
                fn evaluation_is_deterministic_across_calls_and_threads() {
                    p::evaluation_is_deterministic_across_calls_and_threads(&$case);
                }

                $($(
                    #[test]
                    fn $extra() {
                        super::$extra(&$case);
                    }
                )+)?
            }
        )*
    };
}
pub(crate) use property_tests;
