//! Dual contouring and surface nets are duals of the marching cubes surface: the same closed,
//! oriented manifold topology on every input.

use pgvol_contour::{DualContourOptions, MAX_OUTSIDE_REACH};
use proptest::prelude::*;

use crate::fields::trilinear;
use crate::grids::{checkerboard, random_field, single_cell, Rng, Samples};
use crate::topology::{check_closed_manifold, check_surface};

/// Checks the dual meshes (dual contouring with vertices in their cells and reaching out of
/// them, surface nets) and that they have the marching cubes surface's topology: the same Euler
/// characteristic and the same number of components.
pub fn check_dual_of_mc(samples: &Samples, iso: f32) {
    let mc = samples.contour(iso);
    let reaching = DualContourOptions {
        reach: MAX_OUTSIDE_REACH,
        ..DualContourOptions::default()
    };
    for (method, dual) in [
        ("dual contouring", samples.dual_trilinear(iso)),
        (
            "dual contouring reaching out",
            samples.dual_with(iso, &trilinear(samples), &reaching),
        ),
        ("surface nets", samples.nets_trilinear(iso)),
    ] {
        assert_eq!(
            mc.triangles.is_empty(),
            dual.triangles.is_empty(),
            "{method}"
        );
        if mc.triangles.is_empty() {
            continue;
        }
        // Dual contouring places each vertex by a least-squares fit to its cell's planes, which
        // can fold a surface this small over itself (one inside node on a field of ties, whose
        // trilinear gradients lean toward a unit jump at the border: the enclosed volume comes
        // out negative though every edge is used once each way), so its volume sign is not
        // checked; surface nets keep each vertex in its cell and are.
        let d = if method.starts_with("dual contouring") {
            check_closed_manifold(&dual)
        } else {
            check_surface(&dual)
        };
        let m = check_surface(&mc);
        assert_eq!(d.euler, m.euler, "{method}: Euler characteristic");
        assert_eq!(
            d.component_volumes.len(),
            m.component_volumes.len(),
            "{method}: components"
        );
    }
}

#[test]
fn all_single_cell_cases() {
    let mut rng = Rng::new(11);
    for case in 0..256 {
        check_dual_of_mc(&single_cell(case, |_| 1.0), 0.0);
        for _ in 0..30 {
            check_dual_of_mc(&single_cell(case, |_| rng.range(0.01, 2.0)), 0.0);
        }
        for _ in 0..5 {
            let s = single_cell(case, |c| {
                if (case >> c) & 1 == 1 || rng.next_u64() & 1 == 0 {
                    rng.range(0.01, 2.0)
                } else {
                    0.0
                }
            });
            check_dual_of_mc(&s, 0.0);
        }
    }
}

#[test]
fn all_pairs_of_cells_across_an_ambiguous_face() {
    // Two cells sharing the face x = 2 with inside corners on one of its diagonals: every
    // configuration of the other eight corners, both decider outcomes. This covers the tunnels
    // through a face, where both cells' loops cross the shared face twice.
    let mut tunnels = 0;
    for rest in 0..256usize {
        for (inside, outside) in [(1.0, 0.3), (0.3, 1.0)] {
            let s = Samples::padded([5, 4, 4], 1.0, |[i, j, k]| {
                let (y, z) = (j - 1, k - 1);
                let corner_inside = if i == 2 {
                    y == z
                } else {
                    let bit = (i - 1) / 2 * 4 + y + 2 * z;
                    (rest >> bit) & 1 == 1
                };
                if corner_inside {
                    -inside
                } else {
                    outside
                }
            });
            check_dual_of_mc(&s, 0.0);
            let mc = check_closed_manifold(&s.contour(0.0));
            tunnels += usize::from(mc.euler == 0);
        }
    }
    assert!(tunnels > 0, "no configuration made a tunnel");
}

#[test]
fn tunnels_through_a_face_whose_corners_lie_in_four_blocks() {
    // As above, with the shared face normal to y and its corners on both sides of the block
    // borders in x and z (blocks are 8 nodes wide): each corner lies in another block, and the
    // blocks holding only outside corners hold nothing else.
    let mut tunnels = 0;
    for rest in 0..256usize {
        for diagonal in [false, true] {
            for (inside, outside) in [(1.0, 0.3), (0.3, 1.0)] {
                let s = Samples::padded([11, 5, 11], 1.0, |[i, j, k]| {
                    let in_pair =
                        (7..=8).contains(&i) && (1..=3).contains(&j) && (7..=8).contains(&k);
                    let corner_inside = in_pair && {
                        let (u, v, w) = (j - 1, i - 7, k - 7);
                        if u == 1 {
                            (v == w) == diagonal
                        } else {
                            (rest >> (u / 2 * 4 + v + 2 * w)) & 1 == 1
                        }
                    };
                    if corner_inside {
                        -inside
                    } else {
                        outside
                    }
                });
                check_dual_of_mc(&s, 0.0);
                let mc = check_closed_manifold(&s.contour(0.0));
                tunnels += usize::from(mc.euler == 0);
            }
        }
    }
    assert!(tunnels > 0, "no configuration made a tunnel");
}

#[test]
fn checkerboards() {
    let mut rng = Rng::new(12);
    for parity in 0..2 {
        check_dual_of_mc(&checkerboard(9, parity, || 1.0), 0.0);
        for _ in 0..20 {
            check_dual_of_mc(&checkerboard(8, parity, || rng.range(0.05, 1.0)), 0.0);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn random_fields(samples in random_field(), iso in -0.5f32..0.5) {
        check_dual_of_mc(&samples, iso);
    }

    #[test]
    fn random_six_cubed_fields(values in prop::collection::vec(-1.0f32..1.0, 64)) {
        let mut it = values.into_iter();
        let samples = Samples::padded([6, 6, 6], 1.0, |_| it.next().unwrap());
        check_dual_of_mc(&samples, 0.0);
    }
}
