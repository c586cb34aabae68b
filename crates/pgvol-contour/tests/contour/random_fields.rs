//! Random small fields, closed off by an outside border.

use proptest::prelude::*;

use crate::grids::{random_field, Samples};
use crate::topology::check_surface;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn random_fields_give_closed_oriented_manifolds(samples in random_field(), iso in -0.5f32..0.5) {
        let mesh = samples.contour(iso);
        check_surface(&mesh);
    }

    #[test]
    fn six_cubed_fields(values in prop::collection::vec(-1.0f32..1.0, 64)) {
        let mut it = values.into_iter();
        let samples = Samples::padded([6, 6, 6], 1.0, |_| it.next().unwrap());
        check_surface(&samples.contour(0.0));
    }
}
