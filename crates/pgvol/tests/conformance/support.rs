//! Helpers shared by the suites: random points, property runs, finite differences and thread
//! pools.

use pgvol::glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};

/// Runs `test` on `cases` random values of `strategy`, panicking with the shrunk failure.
pub fn check<S: Strategy>(
    cases: u32,
    strategy: S,
    test: impl Fn(S::Value) -> Result<(), TestCaseError>,
) {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    if let Err(e) = TestRunner::new(config).run(&strategy, test) {
        panic!("{e}");
    }
}

/// Points uniformly in the box `(lo, hi)`.
pub fn point_in((lo, hi): (Vec3, Vec3)) -> impl Strategy<Value = Vec3> {
    (lo.x..=hi.x, lo.y..=hi.y, lo.z..=hi.z).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Points in the cube `[-s, s]³`.
pub fn point_within(s: f32) -> impl Strategy<Value = Vec3> {
    point_in((Vec3::splat(-s), Vec3::splat(s)))
}

/// Central differences of `f` at `p` with step `e`.
pub fn fd_gradient(f: impl Fn(Vec3) -> f32, p: Vec3, e: f32) -> Vec3 {
    Vec3::new(
        f(p + Vec3::X * e) - f(p - Vec3::X * e),
        f(p + Vec3::Y * e) - f(p - Vec3::Y * e),
        f(p + Vec3::Z * e) - f(p - Vec3::Z * e),
    ) / (2.0 * e)
}

/// Deterministic scattered points in a box, for checks that compare whole batches.
pub fn scattered((lo, hi): (Vec3, Vec3), n: usize) -> Vec<Vec3> {
    let frac = |x: f32| x - x.floor();
    (0..n)
        .map(|i| {
            let i = i as f32 + 0.5;
            // Weyl sequences with the generalised golden ratio's powers: low discrepancy.
            let t = Vec3::new(
                frac(i * 0.819_172_5),
                frac(i * 0.671_043_5),
                frac(i * 0.549_700_5),
            );
            lo + (hi - lo) * t
        })
        .collect()
}

/// Runs `work` inside a rayon pool of `threads` threads.
pub fn with_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(work)
}

/// Thread counts the batch calls are compared across.
pub const THREADS: [usize; 3] = [1, 2, 5];

/// Bit patterns, so that comparisons are exact and NaN-proof.
pub fn bits(v: f32) -> u32 {
    v.to_bits()
}

pub fn vec_bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}
