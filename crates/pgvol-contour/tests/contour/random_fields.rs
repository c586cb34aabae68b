//! Random small fields, closed off by an outside border.

use proptest::prelude::*;

use crate::grids::Samples;
use crate::topology::check_surface;

fn value() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => -1.0f32..1.0,
        1 => Just(0.0f32),
        1 => Just(f32::NAN),
        1 => prop_oneof![Just(-1e-30f32), Just(1e-30f32), Just(-1e30f32)],
    ]
}

fn field() -> impl Strategy<Value = Samples> {
    (3usize..9, 3usize..9, 3usize..9).prop_flat_map(|(x, y, z)| {
        prop::collection::vec(value(), x * y * z).prop_map(move |v| {
            let mut it = v.into_iter();
            Samples::padded([x, y, z], 1.0, |_| it.next().unwrap())
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn random_fields_give_closed_oriented_manifolds(samples in field(), iso in -0.5f32..0.5) {
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
