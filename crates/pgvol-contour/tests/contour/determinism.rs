//! Output must not depend on the number of threads.

use glam::Vec3;
use pgvol_core::Mesh;

use crate::grids::{Rng, Samples};

fn in_pool(threads: usize, f: impl FnOnce() -> Mesh + Send) -> Mesh {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

fn assert_thread_independent(s: &Samples) {
    let one = in_pool(1, || s.contour(0.0));
    assert!(!one.triangles.is_empty());
    for threads in [2, 3, 4] {
        assert_eq!(
            one,
            in_pool(threads, || s.contour(0.0)),
            "{threads} threads"
        );
    }
}

#[test]
fn sphere_is_identical_for_any_thread_count() {
    let s = Samples::from_fn([56; 3], Vec3::splat(-1.0), 2.0 / 55.0, |p| p.length() - 0.6);
    assert_thread_independent(&s);
}

#[test]
fn noisy_field_is_identical_for_any_thread_count() {
    let mut rng = Rng::new(5);
    let s = Samples::padded([30, 24, 40], 1.0, |_| rng.range(-1.0, 1.0));
    assert_thread_independent(&s);
}

fn assert_methods_thread_independent(s: &Samples, field: &dyn pgvol_contour::Field) {
    let dc = in_pool(1, || s.dual(0.0, field));
    let sn = in_pool(1, || s.nets(0.0, field));
    assert!(!dc.triangles.is_empty() && !sn.triangles.is_empty());
    assert_eq!(dc, in_pool(2, || s.dual(0.0, field)), "dual contouring");
    assert_eq!(sn, in_pool(2, || s.nets(0.0, field)), "surface nets");
}

#[test]
fn dual_contouring_and_surface_nets_are_identical_for_any_thread_count() {
    let ball = crate::fields::sphere(0.6);
    let s = Samples::from_fn([70; 3], Vec3::splat(-1.0), 2.0 / 69.0, |p| p.length() - 0.6);
    assert_methods_thread_independent(&s, &ball);
    let mut rng = Rng::new(6);
    let s = Samples::padded([40, 36, 44], 1.0, |_| rng.range(-1.0, 1.0));
    assert_methods_thread_independent(&s, &crate::fields::trilinear(&s));
}
