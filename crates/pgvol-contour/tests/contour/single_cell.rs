//! Every corner configuration of one cell, closed off by outside values all around.

use crate::grids::{single_cell, Rng, Samples};
use crate::topology::check_surface;

fn check_case(case: usize, samples: &Samples) {
    let mesh = samples.contour(0.0);
    if case == 0 {
        assert!(mesh.triangles.is_empty());
        return;
    }
    assert!(!mesh.triangles.is_empty(), "case {case}: no surface");
    let closed = check_surface(&mesh);
    // No component can be a cavity here: the outside region reaches the border from every
    // outside corner, so each piece of surface must enclose inside volume.
    for v in &closed.component_volumes {
        assert!(*v > 0.0, "case {case}: component with volume {v}");
    }
}

#[test]
fn all_cases_with_unit_magnitudes() {
    // Equal magnitudes put every ambiguous face's saddle exactly at iso.
    for case in 0..256 {
        check_case(case, &single_cell(case, |_| 1.0));
    }
}

#[test]
fn all_cases_with_random_magnitudes() {
    let mut rng = Rng::new(1);
    for case in 0..256 {
        for _ in 0..60 {
            let samples = single_cell(case, |_| rng.range(0.01, 2.0));
            check_case(case, &samples);
        }
    }
}

#[test]
fn all_cases_with_outside_corners_exactly_at_iso() {
    // Values equal to iso are outside; vertices then sit at the clamped end of their edges.
    let mut rng = Rng::new(2);
    for case in 0..256 {
        for _ in 0..10 {
            let samples = single_cell(case, |c| {
                if (case >> c) & 1 == 1 || rng.next_u64() & 1 == 0 {
                    rng.range(0.01, 2.0)
                } else {
                    0.0
                }
            });
            check_case(case, &samples);
        }
    }
}

#[test]
fn asymptotic_decider_sets_connectivity_across_a_face() {
    // Corners 0 and 3 are diagonal on the face z = 0. Deep inside values and shallow outside
    // ones put the saddle inside (one joined piece); the reverse separates them.
    let case = 0b1001;
    for (inside, outside, pieces) in [(1.0, 0.1, 1), (0.1, 1.0, 2)] {
        let samples = single_cell(case, |c| {
            if (case >> c) & 1 == 1 {
                inside
            } else {
                outside
            }
        });
        let closed = check_surface(&samples.contour(0.0));
        assert_eq!(
            closed.component_volumes.len(),
            pieces,
            "inside {inside} outside {outside}"
        );
    }
}
